//! Gaussian copula (Nataf transformation) for correlated inputs.
//!
//! Inputs `X_i = g_i(Z_i)` with `g_i = F_i^-1 o Phi` and `Z ~ N(0, R_z)`. The user gives
//! the Pearson correlation `R_x` of the physical inputs; for non-normal marginals the
//! normal-space correlation `R_z` differs and is solved pair by pair:
//! `rho_x(rho_z) = (E[g_i(Z_1) g_j(Z_2)] - mu_i mu_j) / (sigma_i sigma_j)` with
//! `corr(Z_1, Z_2) = rho_z`. The expectation is the Gauss–Hermite quadrature of the
//! product in Mehler's form: with `a_k = E[g_i(Z) h_k(Z)]`, `b_k = E[g_j(Z) h_k(Z)]`
//! (`h_k` orthonormal Hermite, one 1-D Gauss–Hermite rule of 160 nodes per marginal),
//! `E[g_i(Z_1) g_j(Z_2)] = sum_k a_k b_k rho_z^k` — a polynomial in `rho_z`, increasing,
//! solved by bisection. Both matrices must be positive definite (Cholesky); the error
//! names the offending matrix.
//!
//! Designs and chaos are built in the *independent* standard space `U ~ N(0, I)`: the map
//! `u -> z = L u -> x`, with `R_z = L L^T`, is that of
//! [`RandomInputs::to_physical`](crate::uq::RandomInputs::to_physical).

use nalgebra::{Cholesky, DMatrix};

use crate::uq::distributions::Distribution;
use crate::uq::pce::askey::Family;

/// Number of Gauss–Hermite nodes for the Mehler coefficients.
const GH_NODES: usize = 160;
/// Number of Mehler terms.
const MEHLER_TERMS: usize = 100;

/// A marginal known through its isoprobabilistic map from the standard normal.
pub trait NormalMapped: Send + Sync {
    /// `x = F^-1(Phi(z))`: the physical value of standard-normal `z`.
    fn physical(&self, z: f64) -> f64;
}

impl NormalMapped for Distribution {
    fn physical(&self, z: f64) -> f64 {
        Distribution::from_standard_normal(self, z)
    }
}

/// Errors of the copula.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CopulaError {
    /// Matrix of the wrong shape, not symmetric, or without a unit diagonal.
    #[error("the correlation matrix must be a symmetric {dim}x{dim} matrix with unit diagonal and entries in [-1, 1]: {matrix}")]
    NotACorrelation {
        /// Expected dimension.
        dim: usize,
        /// The matrix, printed.
        matrix: String,
    },
    /// A matrix is not positive definite.
    #[error("the {which} correlation matrix is not positive definite: {matrix}")]
    NotPositiveDefinite {
        /// "requested" or "normal-space".
        which: &'static str,
        /// The matrix, printed.
        matrix: String,
    },
    /// A requested correlation is outside the range the two marginals can reach.
    #[error("correlation {rho} between inputs {i} and {j} is not attainable with their marginals (range {lo:.4} to {hi:.4})")]
    NotAttainable {
        /// First input.
        i: usize,
        /// Second input.
        j: usize,
        /// Requested value.
        rho: f64,
        /// Lowest attainable.
        lo: f64,
        /// Highest attainable.
        hi: f64,
    },
    /// A marginal has no finite variance on the quadrature.
    #[error("input {0} has no finite, positive variance under the normal map")]
    Degenerate(usize),
}

/// Mehler coefficients of one marginal: `c[k] = E[g(Z) h_k(Z)]`, `c[0]` the mean, and
/// the standard deviation from the quadrature.
#[derive(Clone, Debug)]
struct Mehler {
    c: Vec<f64>,
    sd: f64,
}

fn mehler(g: &dyn NormalMapped, nodes: &(Vec<f64>, Vec<f64>)) -> Mehler {
    let mut c = vec![0.0; MEHLER_TERMS + 1];
    let mut h = vec![0.0; MEHLER_TERMS + 1];
    let mut m2 = 0.0;
    for (&z, &w) in nodes.0.iter().zip(&nodes.1) {
        let x = g.physical(z);
        Family::Hermite.eval_all(z, &mut h);
        for (ck, hk) in c.iter_mut().zip(&h) {
            *ck += w * x * hk;
        }
        m2 += w * x * x;
    }
    let var = m2 - c[0] * c[0];
    Mehler {
        c,
        sd: var.max(0.0).sqrt(),
    }
}

/// `rho_x` as a function of `rho_z` for two Mehler expansions.
fn rho_x(a: &Mehler, b: &Mehler, rz: f64) -> f64 {
    let mut s = 0.0;
    let mut p = 1.0;
    for k in 1..=MEHLER_TERMS {
        p *= rz;
        s += a.c[k] * b.c[k] * p;
    }
    s / (a.sd * b.sd)
}

/// The range of Pearson correlations reachable by a Gaussian copula of two marginals
/// (at `rho_z = -1` and `+1`; [`GaussianCopula::new`] refuses a correlation outside it).
/// Serves the tests.
#[cfg(test)]
pub(crate) fn attainable_range(a: &dyn NormalMapped, b: &dyn NormalMapped) -> (f64, f64) {
    let nodes = Family::Hermite.gauss(GH_NODES).expect("fixed node count");
    let (ma, mb) = (mehler(a, &nodes), mehler(b, &nodes));
    (rho_x(&ma, &mb, -1.0), rho_x(&ma, &mb, 1.0))
}

fn solve_pair(a: &Mehler, b: &Mehler, target: f64, i: usize, j: usize) -> Result<f64, CopulaError> {
    if target == 0.0 {
        return Ok(0.0);
    }
    let (lo, hi) = (rho_x(a, b, -1.0), rho_x(a, b, 1.0));
    if target < lo - 1e-12 || target > hi + 1e-12 {
        return Err(CopulaError::NotAttainable {
            i,
            j,
            rho: target,
            lo,
            hi,
        });
    }
    let (mut l, mut h) = (-1.0f64, 1.0f64);
    for _ in 0..200 {
        let m = 0.5 * (l + h);
        if m <= l || m >= h {
            break;
        }
        if rho_x(a, b, m) < target {
            l = m;
        } else {
            h = m;
        }
    }
    Ok(0.5 * (l + h))
}

/// The normal-space correlation giving Pearson correlation `rho` between two marginals: what
/// [`GaussianCopula::new`] solves for each pair. Serves the tests, which check the solve on
/// pairs with closed forms.
#[cfg(test)]
pub(crate) fn nataf_normal_correlation(
    a: &dyn NormalMapped,
    b: &dyn NormalMapped,
    rho: f64,
) -> Result<f64, CopulaError> {
    let nodes = Family::Hermite.gauss(GH_NODES).expect("fixed node count");
    let (ma, mb) = (mehler(a, &nodes), mehler(b, &nodes));
    if !(ma.sd > 0.0 && ma.sd.is_finite()) {
        return Err(CopulaError::Degenerate(0));
    }
    if !(mb.sd > 0.0 && mb.sd.is_finite()) {
        return Err(CopulaError::Degenerate(1));
    }
    solve_pair(&ma, &mb, rho, 0, 1)
}

fn print_matrix(m: &DMatrix<f64>) -> String {
    let rows: Vec<String> = m
        .row_iter()
        .map(|r| {
            let v: Vec<String> = r.iter().map(|x| format!("{x:.6}")).collect();
            format!("[{}]", v.join(", "))
        })
        .collect();
    format!("[{}]", rows.join(", "))
}

/// A Gaussian copula over given marginals.
#[derive(Clone, Debug, PartialEq)]
pub struct GaussianCopula {
    marginals: Vec<Distribution>,
    normal_corr: DMatrix<f64>,
    chol: DMatrix<f64>,
}

impl GaussianCopula {
    /// The copula of `marginals` with requested Pearson correlation matrix `target`.
    pub fn new(marginals: Vec<Distribution>, target: &DMatrix<f64>) -> Result<Self, CopulaError> {
        let d = marginals.len();
        let bad = || CopulaError::NotACorrelation {
            dim: d,
            matrix: print_matrix(target),
        };
        if target.nrows() != d || target.ncols() != d {
            return Err(bad());
        }
        for i in 0..d {
            if (target[(i, i)] - 1.0).abs() > 1e-12 {
                return Err(bad());
            }
            for j in 0..d {
                let v = target[(i, j)];
                if !v.is_finite() || v.abs() > 1.0 || (v - target[(j, i)]).abs() > 1e-12 {
                    return Err(bad());
                }
            }
        }
        if Cholesky::new(target.clone()).is_none() {
            return Err(CopulaError::NotPositiveDefinite {
                which: "requested",
                matrix: print_matrix(target),
            });
        }
        let nodes = Family::Hermite.gauss(GH_NODES).expect("fixed node count");
        let mut me: Vec<Option<Mehler>> = vec![None; d];
        let mut rz = DMatrix::<f64>::identity(d, d);
        for i in 0..d {
            for j in 0..i {
                let t = target[(i, j)];
                if t == 0.0 {
                    continue;
                }
                for k in [i, j] {
                    if me[k].is_none() {
                        let m = mehler(&marginals[k], &nodes);
                        if !(m.sd > 0.0 && m.sd.is_finite()) {
                            return Err(CopulaError::Degenerate(k));
                        }
                        me[k] = Some(m);
                    }
                }
                let (a, b) = (me[i].as_ref().unwrap(), me[j].as_ref().unwrap());
                let r = solve_pair(a, b, t, i, j)?;
                rz[(i, j)] = r;
                rz[(j, i)] = r;
            }
        }
        let chol = Cholesky::new(rz.clone())
            .ok_or_else(|| CopulaError::NotPositiveDefinite {
                which: "normal-space",
                matrix: print_matrix(&rz),
            })?
            .l();
        Ok(GaussianCopula {
            marginals,
            normal_corr: rz,
            chol,
        })
    }

    /// The solved normal-space correlation `R_z`.
    pub fn normal_correlation(&self) -> &DMatrix<f64> {
        &self.normal_corr
    }

    /// Lower Cholesky factor `L` of `R_z`.
    pub fn cholesky(&self) -> &DMatrix<f64> {
        &self.chol
    }

    /// Physical values of independent standard normals `u`: `x_i = g_i((L u)_i)`. Serves
    /// the tests (the studies map through
    /// [`RandomInputs::to_physical`](crate::uq::RandomInputs::to_physical)).
    #[cfg(test)]
    pub(crate) fn to_physical(&self, u: &[f64]) -> Vec<f64> {
        let z = &self.chol * nalgebra::DVector::from_column_slice(u);
        z.iter()
            .zip(&self.marginals)
            .map(|(&zi, m)| m.physical(zi))
            .collect()
    }

    /// Independent standard normals of physical values `x` (inverse of `to_physical`).
    /// Serves the tests.
    #[cfg(test)]
    pub(crate) fn to_independent(&self, x: &[f64]) -> Vec<f64> {
        use crate::uq::distributions::Germ;
        let z = nalgebra::DVector::from_iterator(
            x.len(),
            x.iter()
                .zip(&self.marginals)
                .map(|(&xi, m)| m.to_germ(Germ::Normal, xi)),
        );
        let u = self
            .chol
            .solve_lower_triangular(&z)
            .expect("Cholesky factor has a positive diagonal");
        u.iter().copied().collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::uq::distributions::Distribution as Marginal;
    use crate::uq::quadrature::gauss_hermite;
    use crate::uq::rng::{standard_normal, stream};

    /// Lognormal exp(mu + s z), written here.
    struct LogN(f64, f64);
    impl NormalMapped for LogN {
        fn physical(&self, z: f64) -> f64 {
            (self.0 + self.1 * z).exp()
        }
    }

    /// rho_x(rho_z) by a direct 2-D Gauss–Hermite product rule (independent of Mehler).
    fn direct_rho(a: &dyn NormalMapped, b: &dyn NormalMapped, rz: f64) -> f64 {
        let (x, w) = gauss_hermite(120).unwrap();
        let s = (1.0 - rz * rz).sqrt();
        let (mut ea, mut eb, mut ea2, mut eb2, mut eab) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for (&u, &wu) in x.iter().zip(&w) {
            let ga = a.physical(u);
            let gb = b.physical(u);
            ea += wu * ga;
            eb += wu * gb;
            ea2 += wu * ga * ga;
            eb2 += wu * gb * gb;
            for (&v, &wv) in x.iter().zip(&w) {
                eab += wu * wv * ga * b.physical(rz * u + s * v);
            }
        }
        (eab - ea * eb) / ((ea2 - ea * ea) * (eb2 - eb * eb)).sqrt()
    }

    #[test]
    fn normal_marginals_keep_the_requested_correlation() {
        let n = Distribution::normal(3.0, 2.0).unwrap();
        let m = Distribution::normal(-1.0, 0.1).unwrap();
        for rho in [-0.9, -0.3, 0.2, 0.75, 0.99] {
            let r = nataf_normal_correlation(&n, &m, rho).unwrap();
            assert!((r - rho).abs() < 1e-12, "{rho}: {r}");
        }
    }

    #[test]
    fn lognormal_pair_matches_the_closed_form() {
        // rho_x = (exp(rz s1 s2) - 1) / sqrt((exp(s1^2) - 1)(exp(s2^2) - 1)).
        let (s1, s2) = (0.3, 0.5);
        let a = LogN(0.1, s1);
        let b = LogN(-0.4, s2);
        for rho in [-0.5, 0.1, 0.6, 0.9] {
            let r = nataf_normal_correlation(&a, &b, rho).unwrap();
            let want =
                (1.0 + rho * ((s1 * s1).exp_m1() * (s2 * s2).exp_m1()).sqrt()).ln() / (s1 * s2);
            assert!((r - want).abs() < 1e-10, "{rho}: {r} vs {want}");
        }
    }

    #[test]
    fn solved_correlation_agrees_with_direct_two_dimensional_quadrature() {
        let a = Marginal::gamma(2.0, 1.5).unwrap();
        let b = Marginal::beta(2.0, 5.0, 0.0, 1.0).unwrap();
        let c = Marginal::weibull(1.3, 2.0).unwrap();
        for (p, q, rho) in [
            (&a as &dyn NormalMapped, &b as &dyn NormalMapped, 0.6),
            (&a, &c, -0.5),
            (&b, &c, 0.3),
        ] {
            let r = nataf_normal_correlation(p, q, rho).unwrap();
            assert!(
                (r.abs() - rho.abs()).abs() > 1e-4,
                "non-normal: r differs from rho"
            );
            let back = direct_rho(p, q, r);
            assert!(
                (back - rho).abs() < 1e-8,
                "{rho}: r = {r}, direct rho_x = {back}"
            );
        }
    }

    #[test]
    fn exponential_pair_lower_bound_is_one_minus_pi_squared_over_six() {
        let e = Marginal::gamma(1.0, 1.0).unwrap();
        let (lo, hi) = attainable_range(&e, &e);
        assert!(
            (lo - (1.0 - std::f64::consts::PI.powi(2) / 6.0)).abs() < 2e-3,
            "{lo}"
        );
        assert!((hi - 1.0).abs() < 2e-3, "{hi}");
        let err = nataf_normal_correlation(&e, &e, -0.8).unwrap_err();
        assert!(matches!(err, CopulaError::NotAttainable { .. }), "{err}");
    }

    #[test]
    fn draws_reproduce_the_target_correlation_within_its_standard_error() {
        let margs = vec![
            Marginal::gamma(2.0, 1.5).unwrap(),
            Marginal::beta(2.0, 5.0, 1.0, 2.0).unwrap(),
            Marginal::weibull(1.3, 2.0).unwrap(),
        ];
        let target =
            DMatrix::from_row_slice(3, 3, &[1.0, 0.5, -0.3, 0.5, 1.0, 0.2, -0.3, 0.2, 1.0]);
        let cop = GaussianCopula::new(margs, &target).unwrap();
        let n = 100_000;
        let mut rng = stream(11, 0);
        let xs: Vec<Vec<f64>> = (0..n)
            .map(|_| {
                let u: Vec<f64> = (0..3).map(|_| standard_normal(&mut rng)).collect();
                let x = cop.to_physical(&u);
                // Round trip back to the independent space.
                let back = cop.to_independent(&x);
                for (a, b) in u.iter().zip(&back) {
                    assert!((a - b).abs() < 1e-7, "{u:?} -> {back:?}");
                }
                x
            })
            .collect();
        for (i, j) in [(0, 1), (0, 2), (1, 2)] {
            let mi = xs.iter().map(|x| x[i]).sum::<f64>() / n as f64;
            let mj = xs.iter().map(|x| x[j]).sum::<f64>() / n as f64;
            let cov = xs.iter().map(|x| (x[i] - mi) * (x[j] - mj)).sum::<f64>();
            let vi = xs.iter().map(|x| (x[i] - mi).powi(2)).sum::<f64>();
            let vj = xs.iter().map(|x| (x[j] - mj).powi(2)).sum::<f64>();
            let r = cov / (vi * vj).sqrt();
            let t = target[(i, j)];
            // SE of a sample correlation ~ (1 - rho^2) / sqrt(n), inflated 2x for the
            // non-normal marginals; 4 SE.
            let se = 2.0 * (1.0 - t * t) / (n as f64).sqrt();
            assert!((r - t).abs() < 4.0 * se, "({i},{j}): {r} vs {t}");
        }
    }

    #[test]
    fn bad_matrices_are_refused_with_the_matrix_named() {
        let margs = || vec![Distribution::normal(0.0, 1.0).unwrap(); 3];
        let not_pd =
            DMatrix::from_row_slice(3, 3, &[1.0, 0.9, -0.9, 0.9, 1.0, 0.9, -0.9, 0.9, 1.0]);
        let err = GaussianCopula::new(margs(), &not_pd).unwrap_err();
        assert!(matches!(
            err,
            CopulaError::NotPositiveDefinite {
                which: "requested",
                ..
            }
        ));
        assert!(
            err.to_string().contains("[1.000000, 0.900000, -0.900000]"),
            "{err}"
        );
        let asym = DMatrix::from_row_slice(3, 3, &[1.0, 0.2, 0.0, 0.1, 1.0, 0.0, 0.0, 0.0, 1.0]);
        assert!(matches!(
            GaussianCopula::new(margs(), &asym),
            Err(CopulaError::NotACorrelation { .. })
        ));
        let wrong = DMatrix::<f64>::identity(2, 2);
        assert!(GaussianCopula::new(margs(), &wrong).is_err());
    }
}
