//! Polynomial chaos in independent germs, one orthonormal family of the Askey scheme per
//! dimension: the chaos type of every method (SCM, SGM, sparse grids, regression).
//!
//! - [`askey`]: the families (Hermite, Legendre, Laguerre, Jacobi) by three-term
//!   recurrences, their Gauss rules and the family of each input distribution;
//! - [`basis`]: multi-index sets (total degree, hyperbolic) and the multivariate basis
//!   `Psi_k(t) = prod_i p^(i)_{k_i}(t_i)` over them, orthonormal for the product germ law;
//! - `hermite`: probabilists' Hermite polynomials `He_n` with their exact norms `n!` and
//!   triple products (the stochastic Galerkin method assembles in that basis and hands its
//!   chaos over through [`Pce::from_hermite_he`]).
//!
//! A [`Pce`] holds one basis and one column of coefficients per output (e.g. per time
//! step). The basis is orthonormal, so the mean is the constant coefficient, the variance
//! the sum of the other squared coefficients and the Sobol' indices sums of squares over
//! index subsets. The norms are exact by construction (the recurrences have exact
//! coefficients): the projection never divides by norms computed with the quadrature it
//! projects with — a known trap, since with `n` nodes a degree-`n` polynomial vanishes at
//! every node and its quadrature norm is rounding noise. [`Pce::project`] refuses bases
//! whose degree in some dimension is not below the number of nodes there.

pub mod askey;
pub mod basis;
mod hermite;
#[cfg(test)]
mod tests;

use nalgebra::DMatrix;

pub use askey::Family;
pub use basis::{Basis, BasisError, ChaosStats, MultiIndexSet};
#[cfg(test)]
pub(crate) use hermite::hermite_he;
pub use hermite::{hermite_norm_sq, hermite_triple};

use crate::uq::rng;
use crate::uq::Distribution;

/// Errors of the polynomial-chaos construction.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum PceError {
    /// The basis degree in a dimension is not below its number of nodes.
    #[error(
        "the order must be below the nodes per dimension for an exact projection of \
         the basis: degree {degree} in dimension {dim} with {nodes} nodes \
         (use at least {} nodes or order at most {})",
        degree + 1,
        nodes.saturating_sub(1)
    )]
    OrderNotBelowNodes {
        /// Dimension (0-based).
        dim: usize,
        /// Largest basis degree in that dimension.
        degree: usize,
        /// Quadrature nodes in that dimension.
        nodes: usize,
    },
    /// Inconsistent sizes of points, weights, values or basis.
    #[error("shape mismatch: {0}")]
    Shape(String),
    /// The basis is not valid.
    #[error("invalid chaos basis: {0}")]
    InvalidBasis(#[from] BasisError),
    /// An ensemble value or weight is NaN or infinite.
    #[error("non-finite {what} at point {point}")]
    NotFinite {
        /// "value" or "weight" or "point".
        what: &'static str,
        /// Row (point index).
        point: usize,
    },
}

/// A polynomial-chaos expansion of several outputs (e.g. the time steps of a response) on a
/// common orthonormal basis.
#[derive(Clone, Debug, PartialEq)]
pub struct Pce {
    /// The basis: one family per germ dimension, the multi-indices.
    pub basis: Basis,
    /// Coefficients: one row per basis term, one column per output.
    pub coeffs: DMatrix<f64>,
}

impl Pce {
    /// A chaos from coefficients in the orthonormal basis `basis`.
    pub fn new(basis: Basis, coeffs: DMatrix<f64>) -> Result<Pce, PceError> {
        if coeffs.nrows() != basis.len() {
            return Err(PceError::Shape(format!(
                "{} coefficient rows for {} basis terms",
                coeffs.nrows(),
                basis.len()
            )));
        }
        Ok(Pce { basis, coeffs })
    }

    /// The Hermite chaos (standard-normal germs) of coefficients `he` given in the
    /// *unnormalized* basis `prod_i He_{k_i}(z_i)`: each row is scaled by the exact norm
    /// `sqrt(prod_i k_i!)`.
    pub fn from_hermite_he(set: MultiIndexSet, he: DMatrix<f64>) -> Result<Pce, PceError> {
        let mut coeffs = he;
        for (t, k) in set.indices().iter().enumerate() {
            let norm: f64 = k
                .iter()
                .map(|&n| hermite_norm_sq(n))
                .product::<f64>()
                .sqrt();
            coeffs.row_mut(t).scale_mut(norm);
        }
        let basis = Basis::new(vec![Family::Hermite; set.dim()], set)?;
        Pce::new(basis, coeffs)
    }

    /// One chaos over the union of per-column multi-index sets (each column's coefficients
    /// placed at its own indices, zeros elsewhere), as regression fits of separate outputs
    /// give; the union is in graded order (total degree, then lexicographically
    /// decreasing).
    pub fn from_columns(
        families: Vec<Family>,
        columns: &[(Vec<Vec<usize>>, Vec<f64>)],
    ) -> Result<Pce, PceError> {
        let mut union: Vec<Vec<usize>> = columns.iter().flat_map(|c| c.0.clone()).collect();
        union.sort_by(|a, b| {
            let (sa, sb): (usize, usize) = (a.iter().sum(), b.iter().sum());
            sa.cmp(&sb).then_with(|| b.cmp(a))
        });
        union.dedup();
        let set = MultiIndexSet::from_indices(families.len(), union)?;
        let mut coeffs = DMatrix::<f64>::zeros(set.len(), columns.len());
        for (col, (indices, c)) in columns.iter().enumerate() {
            for (k, v) in indices.iter().zip(c) {
                let row = set.position(k).expect("in the union");
                coeffs[(row, col)] = *v;
            }
        }
        Pce::new(Basis::new(families, set)?, coeffs)
    }

    /// Pseudo-spectral projection `c_k = sum_q w_q f(t_q) Psi_k(t_q)` of `values` (one
    /// row per point, one column per output) with a tensor quadrature rule of the germ law
    /// (`points`, `weights` summing to 1; `nodes_per_dim` nodes of a Gauss rule in each
    /// dimension). The basis is orthonormal with exact norms: nothing is divided by a
    /// quadrature norm.
    ///
    /// Errors: sizes inconsistent, non-finite data, or a basis degree not below the number
    /// of nodes in some dimension ([`PceError::OrderNotBelowNodes`]; see
    /// [`Pce::project_lenient`]).
    pub fn project(
        basis: Basis,
        points: &[Vec<f64>],
        weights: &[f64],
        values: &DMatrix<f64>,
        nodes_per_dim: &[usize],
    ) -> Result<Pce, PceError> {
        check_inputs(&basis, points, weights, values, nodes_per_dim)?;
        if let Some(e) = aliasing(&basis, nodes_per_dim).into_iter().next() {
            return Err(e);
        }
        Ok(project_unchecked(basis, points, weights, values))
    }

    /// Like [`Pce::project`] but accepts a basis degree that reaches the number of nodes,
    /// returning one warning per offending dimension. The highest-degree coefficients are
    /// then aliased (wrong, typically zero); the exact norms keep them from exploding.
    pub fn project_lenient(
        basis: Basis,
        points: &[Vec<f64>],
        weights: &[f64],
        values: &DMatrix<f64>,
        nodes_per_dim: &[usize],
    ) -> Result<(Pce, Vec<String>), PceError> {
        check_inputs(&basis, points, weights, values, nodes_per_dim)?;
        let warnings = aliasing(&basis, nodes_per_dim)
            .into_iter()
            .map(|e| format!("{e}; the highest-degree coefficients are aliased"))
            .collect();
        Ok((project_unchecked(basis, points, weights, values), warnings))
    }

    /// Number of germ dimensions.
    pub fn dim(&self) -> usize {
        self.basis.set().dim()
    }

    /// Number of outputs (columns).
    pub fn outputs(&self) -> usize {
        self.coeffs.ncols()
    }

    /// The multi-index set.
    pub fn set(&self) -> &MultiIndexSet {
        self.basis.set()
    }

    /// Position of the constant term, if present.
    fn constant_term(&self) -> Option<usize> {
        self.set().position(&vec![0; self.dim()])
    }

    /// Mean of every output: the coefficient of the constant term.
    pub fn mean(&self) -> Vec<f64> {
        match self.constant_term() {
            Some(t) => self.coeffs.row(t).iter().copied().collect(),
            None => vec![0.0; self.outputs()],
        }
    }

    /// Variance of every output: `sum_{k != 0} c_k^2`.
    pub fn variance(&self) -> Vec<f64> {
        let c0 = self.constant_term();
        (0..self.outputs())
            .map(|col| {
                (0..self.basis.len())
                    .filter(|&t| Some(t) != c0)
                    .map(|t| self.coeffs[(t, col)].powi(2))
                    .sum()
            })
            .collect()
    }

    /// Standard deviation of every output.
    pub fn std(&self) -> Vec<f64> {
        self.variance().into_iter().map(f64::sqrt).collect()
    }

    /// Mean, variance and Sobol' indices of output `col` (NaN indices for zero variance).
    pub fn stats(&self, col: usize) -> ChaosStats {
        ChaosStats::new(self.set(), self.coeffs.column(col).as_slice())
    }

    /// The surrogate of every output at the germ point `t`.
    ///
    /// # Panics
    /// If `t.len() != self.dim()`.
    pub fn eval(&self, t: &[f64]) -> Vec<f64> {
        let psi = self.basis_at(t);
        (0..self.outputs())
            .map(|col| dot_column(&self.coeffs, col, &psi))
            .collect()
    }

    /// The surrogate of output `col` at the germ point `t`.
    ///
    /// # Panics
    /// If `col >= self.outputs()` or `t.len() != self.dim()`.
    pub fn eval_column(&self, col: usize, t: &[f64]) -> f64 {
        assert!(col < self.outputs(), "column {col} out of range");
        dot_column(&self.coeffs, col, &self.basis_at(t))
    }

    /// The basis functions at the germ point `t`.
    ///
    /// # Panics
    /// If `t.len() != self.dim()`.
    fn basis_at(&self, t: &[f64]) -> Vec<f64> {
        assert_eq!(
            t.len(),
            self.dim(),
            "point dimension differs from the basis"
        );
        let mut psi = vec![0.0; self.basis.len()];
        self.basis.eval(t, &mut psi);
        psi
    }

    /// `n` draws of every output of the surrogate, one row per draw: row `i` is the chaos at
    /// point `i` of [`germ_draws`] (a function of `(seed, i)` only).
    pub fn sample(&self, n: usize, seed: u64) -> DMatrix<f64> {
        let mut m = DMatrix::<f64>::zeros(n, self.basis.len());
        basis_at_germ_draws(&self.basis, seed, 0..n, |i, psi| {
            m.row_mut(i).copy_from_slice(psi)
        });
        m * &self.coeffs
    }

    /// First-order Sobol' indices of output `col`, one per germ dimension: the variance
    /// share of the terms depending on that dimension only. All zeros when the variance
    /// vanishes (or is at the rounding level of the mean, as for a constant output).
    ///
    /// # Panics
    /// If `col >= self.outputs()`.
    pub fn sobol_first(&self, col: usize) -> Vec<f64> {
        self.sobol(col, |k, i| {
            k[i] > 0 && k.iter().enumerate().all(|(j, &kj)| j == i || kj == 0)
        })
    }

    /// Total Sobol' indices of output `col`, one per germ dimension: the variance share of
    /// all terms involving that dimension. All zeros when the variance vanishes.
    ///
    /// # Panics
    /// If `col >= self.outputs()`.
    pub fn sobol_total(&self, col: usize) -> Vec<f64> {
        self.sobol(col, |k, i| k[i] > 0)
    }

    fn sobol(&self, col: usize, selects: impl Fn(&[usize], usize) -> bool) -> Vec<f64> {
        assert!(col < self.outputs(), "column {col} out of range");
        let parts: Vec<f64> = (0..self.basis.len())
            .map(|t| self.coeffs[(t, col)].powi(2))
            .collect();
        let c0 = self.constant_term();
        let var: f64 = parts
            .iter()
            .enumerate()
            .filter(|&(t, _)| Some(t) != c0)
            .map(|(_, v)| v)
            .sum();
        // Variance at rounding level of the mean (a constant output) counts as zero.
        let c0_abs = c0.map_or(0.0, |t| self.coeffs[(t, col)].abs());
        let negligible = (64.0 * f64::EPSILON * c0_abs).powi(2);
        (0..self.dim())
            .map(|i| {
                if var.is_nan() || var <= negligible {
                    return 0.0;
                }
                let s: f64 = self
                    .set()
                    .indices()
                    .iter()
                    .zip(&parts)
                    .filter(|(k, _)| selects(k, i))
                    .map(|(_, v)| v)
                    .sum();
                // + 0.0: an empty sum is -0.0.
                s / var + 0.0
            })
            .collect()
    }
}

/// `n` random points of the germs of `families`: point `i` takes one uniform per dimension
/// from `rng::stream(seed, i)` and maps it through the germ law's quantile (a Hermite germ is
/// [`rng::standard_normal`]), so the points depend on `(seed, i)` only.
pub fn germ_draws(families: &[Family], n: usize, seed: u64) -> Vec<Vec<f64>> {
    let laws: Vec<_> = families.iter().map(Family::law).collect();
    (0..n)
        .map(|i| {
            let mut z = vec![0.0; families.len()];
            germ_draw(families, &laws, seed, i, &mut z);
            z
        })
        .collect()
}

/// Point `i` of [`germ_draws`] into `out` (`laws[j]` is `families[j].law()`): a function
/// of `(seed, i)` only.
pub fn germ_draw(families: &[Family], laws: &[Distribution], seed: u64, i: usize, out: &mut [f64]) {
    let mut r = rng::stream(seed, i as u64);
    for ((o, f), law) in out.iter_mut().zip(families).zip(laws) {
        *o = match f {
            Family::Hermite => rng::standard_normal(&mut r),
            _ => law.inverse_cdf(rng::uniform_open01(&mut r)),
        };
    }
}

/// The basis at points `rows` of [`germ_draws`]: `put(i, psi)` for each point `i`, `psi` the
/// basis there (one buffer reused from point to point, no vector per point).
pub(crate) fn basis_at_germ_draws(
    basis: &Basis,
    seed: u64,
    rows: std::ops::Range<usize>,
    mut put: impl FnMut(usize, &[f64]),
) {
    let families = basis.families();
    let laws: Vec<_> = families.iter().map(Family::law).collect();
    let mut z = vec![0.0; families.len()];
    let mut psi = vec![0.0; basis.len()];
    for i in rows {
        germ_draw(families, &laws, seed, i, &mut z);
        basis.eval(&z, &mut psi);
        put(i, &psi);
    }
}

fn dot_column(c: &DMatrix<f64>, col: usize, psi: &[f64]) -> f64 {
    c.column(col).iter().zip(psi).map(|(a, b)| a * b).sum()
}

fn check_inputs(
    basis: &Basis,
    points: &[Vec<f64>],
    weights: &[f64],
    values: &DMatrix<f64>,
    nodes_per_dim: &[usize],
) -> Result<(), PceError> {
    let dim = basis.set().dim();
    if points.len() != weights.len() || points.len() != values.nrows() {
        return Err(PceError::Shape(format!(
            "{} points, {} weights, {} value rows",
            points.len(),
            weights.len(),
            values.nrows()
        )));
    }
    if nodes_per_dim.len() != dim {
        return Err(PceError::Shape(format!(
            "nodes given for {} dimensions, basis has {dim}",
            nodes_per_dim.len(),
        )));
    }
    for (q, p) in points.iter().enumerate() {
        if p.len() != dim {
            return Err(PceError::Shape(format!(
                "point {q} has {} coordinates, basis has {dim} dimensions",
                p.len(),
            )));
        }
        if p.iter().any(|x| !x.is_finite()) {
            return Err(PceError::NotFinite {
                what: "point",
                point: q,
            });
        }
        if !weights[q].is_finite() {
            return Err(PceError::NotFinite {
                what: "weight",
                point: q,
            });
        }
        if values.row(q).iter().any(|v| !v.is_finite()) {
            return Err(PceError::NotFinite {
                what: "value",
                point: q,
            });
        }
    }
    Ok(())
}

/// One error per dimension whose basis degree is not below its node count.
fn aliasing(basis: &Basis, nodes_per_dim: &[usize]) -> Vec<PceError> {
    basis
        .set()
        .max_per_dim()
        .into_iter()
        .zip(nodes_per_dim)
        .enumerate()
        .filter(|&(_, (degree, &nodes))| degree >= nodes)
        .map(|(dim, (degree, &nodes))| PceError::OrderNotBelowNodes { dim, degree, nodes })
        .collect()
}

fn project_unchecked(
    basis: Basis,
    points: &[Vec<f64>],
    weights: &[f64],
    values: &DMatrix<f64>,
) -> Pce {
    // a[(t, q)] = w_q Psi_t(t_q)
    let mut a = basis.design_matrix(points).transpose();
    for (q, &w) in weights.iter().enumerate() {
        a.column_mut(q).scale_mut(w);
    }
    let coeffs = a * values;
    Pce { basis, coeffs }
}
