//! Intrusive stochastic Galerkin method (SGM) for linear second-order systems
//!
//! ```text
//! M(ξ) q'' + C(ξ) q' + K(ξ) q = f(t),   q(0) = q0(ξ),  q'(0) = v0(ξ)
//! A(ξ) = A_0 + Σ_l ξ_l A_l            (A = M, C, K, q0, v0; ξ_l independent standard normals)
//! ```
//!
//! The solution is expanded on a total-order probabilists' Hermite basis Ψ_k (C(N+d, d) terms),
//! q(t, ξ) ≈ Σ_k q_k(t) Ψ_k(ξ). Galerkin projection (test with each Ψ_k) gives one coupled
//! deterministic system of size n·P:
//!
//! ```text
//! 𝕄 = G_0 ⊗ M_0 + Σ_l G_l ⊗ M_l,   G_0[k,i] = E[Ψ_k Ψ_i] = δ_ki ‖Ψ_k‖²,  G_l[k,i] = E[ξ_l Ψ_k Ψ_i]
//! ```
//!
//! (likewise ℂ and 𝕂); the right-hand side is f(t) on the k = 0 block only. E[ξ_l Ψ_k Ψ_i] is a
//! product of one-dimensional triple products E[He_a He_b He_c] (exact integers). The coupled
//! system is integrated by RK4 with equal substeps no longer than `h`.
//!
//! The Galerkin operator of a Gaussian stiffness is not positive definite for every order:
//! [`GalerkinSystem::check_definiteness`] reports the smallest eigenvalues of 𝕄 and 𝕂.

use nalgebra::{DMatrix, DVector};

use super::pce::{hermite_triple, MultiIndexSet, Pce};

pub mod system;

/// A matrix (or vector, as an n×1 matrix) depending affinely on standard Gaussian germs.
#[derive(Clone, Debug, PartialEq)]
pub struct Affine {
    /// The mean part A_0.
    pub mean: DMatrix<f64>,
    /// (germ index l, A_l).
    pub terms: Vec<(usize, DMatrix<f64>)>,
}

impl Affine {
    /// A deterministic matrix.
    pub fn constant(mean: DMatrix<f64>) -> Self {
        Affine {
            mean,
            terms: Vec::new(),
        }
    }

    /// Evaluates A(ξ). Serves the tests (their realisation-by-realisation reference
    /// solve).
    #[cfg(test)]
    pub(crate) fn at(&self, xi: &[f64]) -> DMatrix<f64> {
        let mut a = self.mean.clone();
        for (l, m) in &self.terms {
            a += m * xi[*l];
        }
        a
    }
}

/// A deterministic load term: amplitude vector times a waveform.
#[derive(Clone, Debug, PartialEq)]
pub enum Waveform {
    /// 1.
    Constant,
    /// sin(ω t + φ), ω in rad/s. Only the tests build one (a time-dependent load for the
    /// solver); the models solved here have constant loads.
    #[cfg(test)]
    Sine {
        /// Angular frequency (rad/s).
        omega: f64,
        /// Phase (rad).
        phase: f64,
    },
}

impl Waveform {
    /// The value at time `t` (read by the tests' sine only: a constant load has none).
    fn at(&self, #[cfg_attr(not(test), allow(unused_variables))] t: f64) -> f64 {
        match self {
            Waveform::Constant => 1.0,
            #[cfg(test)]
            Waveform::Sine { omega, phase } => (omega * t + phase).sin(),
        }
    }
}

/// The stochastic linear system.
#[derive(Clone, Debug)]
pub struct LinearSystem {
    /// Number of germs d.
    pub n_germs: usize,
    /// Mass matrix.
    pub m: Affine,
    /// Damping matrix.
    pub c: Affine,
    /// Stiffness matrix.
    pub k: Affine,
    /// Load: Σ amplitude · waveform(t).
    pub force: Vec<(DVector<f64>, Waveform)>,
    /// Initial displacement (n×1).
    pub q0: Affine,
    /// Initial velocity (n×1).
    pub v0: Affine,
}

/// SGM failures.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GalerkinError {
    /// Inconsistent dimensions or indices.
    #[error("{0}")]
    Shape(String),
    /// The Galerkin mass matrix is singular.
    #[error("the Galerkin mass operator is singular or not positive definite (smallest eigenvalue {0:e})")]
    SingularMass(f64),
    /// Bad step or time grid.
    #[error("{0}")]
    Time(String),
    /// The solution blew up.
    #[error("the Galerkin solution became non-finite at t = {0} s")]
    NonFinite(f64),
}

/// The assembled Galerkin system.
#[derive(Clone, Debug)]
pub struct GalerkinSystem {
    /// The chaos basis.
    pub basis: MultiIndexSet,
    /// Number of physical DOFs n.
    pub n: usize,
    /// 𝕄, ℂ, 𝕂 of size nP × nP.
    pub mm: DMatrix<f64>,
    /// ℂ.
    pub cc: DMatrix<f64>,
    /// 𝕂.
    pub kk: DMatrix<f64>,
    /// Initial coefficients of q and v (nP; block k holds the coefficients of Ψ_k).
    pub y0: (DVector<f64>, DVector<f64>),
    force: Vec<(DVector<f64>, Waveform)>,
    minv: DMatrix<f64>,
}

/// Definiteness report of the Galerkin operators.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Definiteness {
    /// Smallest eigenvalue of the (symmetric) Galerkin mass operator.
    pub min_eig_mass: f64,
    /// Smallest eigenvalue of the Galerkin stiffness operator.
    pub min_eig_stiffness: f64,
    /// Smallest eigenvalue of the Galerkin damping operator.
    pub min_eig_damping: f64,
    /// Human-readable warnings (empty if all operators are positive (semi-)definite as expected).
    pub warnings: Vec<String>,
}

/// Chaos coefficients of one DOF over time: (displacement, velocity), each terms × times.
pub type Trajectory = (DMatrix<f64>, DMatrix<f64>);

/// G_l[k, i] = E[ξ_l Ψ_k Ψ_i] (l = None: E[Ψ_k Ψ_i]).
pub fn germ_matrix(basis: &MultiIndexSet, l: Option<usize>) -> DMatrix<f64> {
    let p = basis.len();
    let idx = basis.indices();
    DMatrix::from_fn(p, p, |k, i| {
        let mut v = 1.0;
        for (d, (&a, &b)) in idx[k].iter().zip(&idx[i]).enumerate() {
            v *= hermite_triple(a, b, usize::from(l == Some(d)));
            if v == 0.0 {
                break;
            }
        }
        v
    })
}

fn kron_add(out: &mut DMatrix<f64>, g: &DMatrix<f64>, a: &DMatrix<f64>) {
    let n = a.nrows();
    for k in 0..g.nrows() {
        for i in 0..g.ncols() {
            let gv = g[(k, i)];
            if gv != 0.0 {
                let mut blk = out.view_mut((k * n, i * n), (n, n));
                blk += a * gv;
            }
        }
    }
}

fn check_affine(
    name: &str,
    a: &Affine,
    rows: usize,
    cols: usize,
    n_germs: usize,
) -> Result<(), GalerkinError> {
    let bad = |m: &DMatrix<f64>| m.nrows() != rows || m.ncols() != cols;
    if bad(&a.mean) || a.terms.iter().any(|(_, m)| bad(m)) {
        return Err(GalerkinError::Shape(format!(
            "{name} must be {rows}×{cols} in every term"
        )));
    }
    if let Some((l, _)) = a.terms.iter().find(|(l, _)| *l >= n_germs) {
        return Err(GalerkinError::Shape(format!(
            "{name} refers to germ {l}, but there are {n_germs}"
        )));
    }
    if a.mean
        .iter()
        .chain(a.terms.iter().flat_map(|(_, m)| m.iter()))
        .any(|v| !v.is_finite())
    {
        return Err(GalerkinError::Shape(format!(
            "{name} has a non-finite entry"
        )));
    }
    Ok(())
}

impl GalerkinSystem {
    /// Assembles the Galerkin system of total order `order`.
    pub fn assemble(sys: &LinearSystem, order: usize) -> Result<GalerkinSystem, GalerkinError> {
        let n = sys.m.mean.nrows();
        if n == 0 {
            return Err(GalerkinError::Shape(
                "the system has no degrees of freedom".into(),
            ));
        }
        check_affine("M", &sys.m, n, n, sys.n_germs)?;
        check_affine("C", &sys.c, n, n, sys.n_germs)?;
        check_affine("K", &sys.k, n, n, sys.n_germs)?;
        check_affine("q0", &sys.q0, n, 1, sys.n_germs)?;
        check_affine("v0", &sys.v0, n, 1, sys.n_germs)?;
        if sys.force.iter().any(|(f, _)| f.len() != n) {
            return Err(GalerkinError::Shape(format!(
                "force vectors must have {n} entries"
            )));
        }
        let basis = MultiIndexSet::total_degree(sys.n_germs, order)
            .map_err(|e| GalerkinError::Shape(e.to_string()))?;
        let p = basis.len();
        let g0 = germ_matrix(&basis, None);
        let gl: Vec<DMatrix<f64>> = (0..sys.n_germs)
            .map(|l| germ_matrix(&basis, Some(l)))
            .collect();
        let build = |a: &Affine| {
            let mut out = DMatrix::zeros(n * p, n * p);
            kron_add(&mut out, &g0, &a.mean);
            for (l, m) in &a.terms {
                kron_add(&mut out, &gl[*l], m);
            }
            out
        };
        let mm = build(&sys.m);
        let cc = build(&sys.c);
        let kk = build(&sys.k);
        // Initial coefficients: q0(ξ) = q0_0 + Σ ξ_l q0_l, and ξ_l = Ψ_{e_l}.
        let init = |a: &Affine| {
            let mut y = DVector::zeros(n * p);
            y.rows_mut(0, n).copy_from(&a.mean.column(0));
            for (l, m) in &a.terms {
                let mut e = vec![0; sys.n_germs];
                e[*l] = 1;
                let k = basis
                    .position(&e)
                    .expect("order >= 1 contains every first-degree term");
                let mut blk = y.rows_mut(k * n, n);
                blk += m.column(0);
            }
            y
        };
        if order == 0 && (!sys.q0.terms.is_empty() || !sys.v0.terms.is_empty()) {
            return Err(GalerkinError::Shape(
                "order 0 cannot represent random initial conditions".into(),
            ));
        }
        let y0 = (init(&sys.q0), init(&sys.v0));
        let minv = mm
            .clone()
            .cholesky()
            .ok_or_else(|| {
                let e = mm.clone().symmetric_eigenvalues().min();
                GalerkinError::SingularMass(e)
            })?
            .inverse();
        Ok(GalerkinSystem {
            basis,
            n,
            mm,
            cc,
            kk,
            y0,
            force: sys.force.clone(),
            minv,
        })
    }

    /// Smallest eigenvalues of the Galerkin operators, with warnings when the stiffness or
    /// damping operator is not positive definite (order too high for the input's spread).
    pub fn check_definiteness(&self) -> Definiteness {
        let min_eig = |a: &DMatrix<f64>| a.clone().symmetric_eigenvalues().min();
        let (m, k, c) = (min_eig(&self.mm), min_eig(&self.kk), min_eig(&self.cc));
        let mut warnings = Vec::new();
        if k <= 0.0 {
            warnings.push(format!(
                "the Galerkin stiffness operator is not positive definite (smallest eigenvalue {k:.3e}): \
                 at order {} the chaos reaches values where the Gaussian stiffness is negative; lower the order \
                 or use a bounded input",
                self.basis.order()
            ));
        }
        if c < -1e-12 * self.cc.amax().max(1.0) {
            warnings.push(format!(
                "the Galerkin damping operator has a negative eigenvalue ({c:.3e})"
            ));
        }
        Definiteness {
            min_eig_mass: m,
            min_eig_stiffness: k,
            min_eig_damping: c,
            warnings,
        }
    }

    fn accel(
        &self,
        t: f64,
        q: &DVector<f64>,
        v: &DVector<f64>,
        rhs: &mut DVector<f64>,
    ) -> DVector<f64> {
        rhs.fill(0.0);
        for (f, w) in &self.force {
            let s = w.at(t);
            let mut blk = rhs.rows_mut(0, self.n);
            blk += f * s;
        }
        *rhs -= &self.cc * v;
        *rhs -= &self.kk * q;
        &self.minv * &*rhs
    }

    /// Integrates over `times` (increasing) with RK4 substeps no longer than `h`. Returns the
    /// displacement coefficients of DOF `dof` as a P × times matrix (and likewise velocity).
    pub fn solve(
        &self,
        times: &[f64],
        h: f64,
        dofs: &[usize],
    ) -> Result<Vec<Trajectory>, GalerkinError> {
        if !(h.is_finite() && h > 0.0) {
            return Err(GalerkinError::Time(format!("step {h} must be > 0")));
        }
        if times.is_empty() || times.windows(2).any(|w| w[1] <= w[0]) {
            return Err(GalerkinError::Time("times must be increasing".into()));
        }
        if let Some(&d) = dofs.iter().find(|&&d| d >= self.n) {
            return Err(GalerkinError::Shape(format!(
                "DOF {d} does not exist ({} DOFs)",
                self.n
            )));
        }
        let p = self.basis.len();
        let n = self.n;
        let mut out: Vec<(DMatrix<f64>, DMatrix<f64>)> = dofs
            .iter()
            .map(|_| {
                (
                    DMatrix::zeros(p, times.len()),
                    DMatrix::zeros(p, times.len()),
                )
            })
            .collect();
        let (mut q, mut v) = self.y0.clone();
        let mut rhs = DVector::zeros(n * p);
        let record = |out: &mut Vec<(DMatrix<f64>, DMatrix<f64>)>,
                      col: usize,
                      q: &DVector<f64>,
                      v: &DVector<f64>| {
            for (o, &d) in dofs.iter().enumerate() {
                for k in 0..p {
                    out[o].0[(k, col)] = q[k * n + d];
                    out[o].1[(k, col)] = v[k * n + d];
                }
            }
        };
        record(&mut out, 0, &q, &v);
        for col in 1..times.len() {
            let t0 = times[col - 1];
            let span = times[col] - t0;
            let ns = (span / h - 1e-9 * (span / h).max(1.0)).ceil().max(1.0) as usize;
            let dt = span / ns as f64;
            for s in 0..ns {
                let t = t0 + s as f64 * dt;
                let a1 = self.accel(t, &q, &v, &mut rhs);
                let (q2, v2) = (&q + &v * (dt / 2.0), &v + &a1 * (dt / 2.0));
                let a2 = self.accel(t + dt / 2.0, &q2, &v2, &mut rhs);
                let (q3, v3) = (&q + &v2 * (dt / 2.0), &v + &a2 * (dt / 2.0));
                let a3 = self.accel(t + dt / 2.0, &q3, &v3, &mut rhs);
                let (q4, v4) = (&q + &v3 * dt, &v + &a3 * dt);
                let a4 = self.accel(t + dt, &q4, &v4, &mut rhs);
                q += (&v + &v2 * 2.0 + &v3 * 2.0 + &v4) * (dt / 6.0);
                v += (&a1 + &a2 * 2.0 + &a3 * 2.0 + &a4) * (dt / 6.0);
            }
            if q.iter().chain(v.iter()).any(|x| !x.is_finite()) {
                return Err(GalerkinError::NonFinite(times[col]));
            }
            record(&mut out, col, &q, &v);
        }
        Ok(out)
    }

    /// The chaos of one DOF's displacement over time, from [`GalerkinSystem::solve`] output
    /// (coefficients in the unnormalized basis `prod He_k`, rescaled by the exact norms to
    /// the orthonormal Hermite chaos).
    pub fn pce(&self, coeffs: DMatrix<f64>) -> Pce {
        Pce::from_hermite_he(self.basis.clone(), coeffs)
            .expect("a Hermite basis of the set's own dimension, one row per term")
    }
}

#[cfg(test)]
mod tests;
