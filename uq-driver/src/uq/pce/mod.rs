//! Probabilists' Hermite polynomial chaos in independent standard-normal
//! germs `z = (z_1, ..., z_d)`.
//!
//! Basis: `Psi_k(z) = prod_i He_{k_i}(z_i)` with the probabilists' Hermite
//! polynomials `He_{n+1}(x) = x He_n(x) - n He_{n-1}(x)`, orthogonal with
//! `E[He_m He_n] = n! delta_mn`, so `||Psi_k||^2 = prod_i k_i!`.
//!
//! The coefficients are computed by pseudo-spectral projection on a
//! Gauss–Hermite tensor grid, always dividing by these EXACT norms. Dividing
//! by norms computed with the same quadrature is a known trap: with `n` nodes
//! a degree-`n` polynomial vanishes at every node, its quadrature norm is
//! rounding noise (~1e-14) and the coefficient explodes. [`Pce::project`]
//! therefore refuses bases whose degree in some dimension is not below the
//! number of nodes in that dimension.

mod hermite;
mod multi_index;
#[cfg(test)]
mod tests;

use nalgebra::DMatrix;

pub use hermite::{hermite_all, hermite_he, hermite_norm_sq, hermite_triple};
pub use multi_index::MultiIndexSet;

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
    /// The basis is not a valid set of distinct multi-indices.
    #[error("invalid multi-index set: {0}")]
    InvalidBasis(String),
    /// An ensemble value or weight is NaN or infinite.
    #[error("non-finite {what} at point {point}")]
    NotFinite {
        /// "value" or "weight" or "point".
        what: &'static str,
        /// Row (point index).
        point: usize,
    },
}

/// A polynomial-chaos expansion of several outputs (e.g. the time steps of a
/// response) on a common basis.
#[derive(Clone, Debug, PartialEq)]
pub struct Pce {
    /// The basis.
    pub basis: MultiIndexSet,
    /// Coefficients: one row per basis term, one column per output.
    pub coeffs: DMatrix<f64>,
}

impl Pce {
    /// Pseudo-spectral projection
    /// `c_k = sum_q w_q f(z_q) Psi_k(z_q) / ||Psi_k||^2` with the exact norms.
    ///
    /// `points` and `weights`: a quadrature rule in standard-normal space
    /// (e.g. [`tensor_grid`](crate::uq::quadrature::tensor_grid)), `values`:
    /// one row per point, one column per output; `nodes_per_dim`: the number
    /// of Gauss–Hermite nodes of the rule in each dimension.
    ///
    /// Errors: sizes inconsistent, non-finite data, invalid basis, or a basis
    /// degree not below the number of nodes in some dimension
    /// ([`PceError::OrderNotBelowNodes`]; see [`Pce::project_lenient`]).
    pub fn project(
        basis: MultiIndexSet,
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

    /// Like [`Pce::project`] but accepts a basis degree that reaches the
    /// number of nodes, returning one warning per offending dimension. The
    /// highest-degree coefficients are then aliased (wrong, typically
    /// zero); the exact norms keep them from exploding.
    pub fn project_lenient(
        basis: MultiIndexSet,
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

    /// Number of outputs (columns).
    pub fn outputs(&self) -> usize {
        self.coeffs.ncols()
    }

    /// Mean of every output: the coefficient of the constant term.
    pub fn mean(&self) -> Vec<f64> {
        match self.basis.constant_term() {
            Some(t) => self.coeffs.row(t).iter().copied().collect(),
            None => vec![0.0; self.outputs()],
        }
    }

    /// Variance of every output: `sum_{k != 0} c_k^2 ||Psi_k||^2`.
    pub fn variance(&self) -> Vec<f64> {
        let c0 = self.basis.constant_term();
        (0..self.outputs())
            .map(|col| {
                (0..self.basis.len())
                    .filter(|&t| Some(t) != c0)
                    .map(|t| self.coeffs[(t, col)].powi(2) * self.basis.norm_sq(t))
                    .sum()
            })
            .collect()
    }

    /// Standard deviation of every output.
    pub fn std(&self) -> Vec<f64> {
        self.variance().into_iter().map(f64::sqrt).collect()
    }

    /// The surrogate of every output at the germ point `z`.
    ///
    /// # Panics
    /// If `z.len() != self.basis.dim`.
    pub fn eval(&self, z: &[f64]) -> Vec<f64> {
        let mut psi = vec![0.0; self.basis.len()];
        self.basis.eval(z, &mut psi);
        (0..self.outputs())
            .map(|col| dot_column(&self.coeffs, col, &psi))
            .collect()
    }

    /// The surrogate of output `col` at the germ point `z`.
    ///
    /// # Panics
    /// If `col >= self.outputs()` or `z.len() != self.basis.dim`.
    pub fn eval_column(&self, col: usize, z: &[f64]) -> f64 {
        assert!(col < self.outputs(), "column {col} out of range");
        let mut psi = vec![0.0; self.basis.len()];
        self.basis.eval(z, &mut psi);
        dot_column(&self.coeffs, col, &psi)
    }

    /// `n` draws of every output of the surrogate, one row per draw: row `i` is the chaos at
    /// the standard normals of [`MultiIndexSet::draws`] (a function of `(seed, i)` only).
    pub fn sample(&self, n: usize, seed: u64) -> DMatrix<f64> {
        self.basis.draws(n, seed) * &self.coeffs
    }

    /// First-order Sobol' indices of output `col`, one per germ dimension:
    /// the variance share of the terms depending on that dimension only.
    /// All zeros when the variance vanishes (or is at the rounding level of
    /// the mean, as for a constant output).
    ///
    /// # Panics
    /// If `col >= self.outputs()`.
    pub fn sobol_first(&self, col: usize) -> Vec<f64> {
        self.sobol(col, |k, i| {
            k[i] > 0 && k.iter().enumerate().all(|(j, &kj)| j == i || kj == 0)
        })
    }

    /// Total Sobol' indices of output `col`, one per germ dimension: the
    /// variance share of all terms involving that dimension.
    /// All zeros when the variance vanishes.
    ///
    /// # Panics
    /// If `col >= self.outputs()`.
    pub fn sobol_total(&self, col: usize) -> Vec<f64> {
        self.sobol(col, |k, i| k[i] > 0)
    }

    fn sobol(&self, col: usize, selects: impl Fn(&[usize], usize) -> bool) -> Vec<f64> {
        assert!(col < self.outputs(), "column {col} out of range");
        let parts: Vec<f64> = (0..self.basis.len())
            .map(|t| self.coeffs[(t, col)].powi(2) * self.basis.norm_sq(t))
            .collect();
        let c0 = self.basis.constant_term();
        let var: f64 = parts
            .iter()
            .enumerate()
            .filter(|&(t, _)| Some(t) != c0)
            .map(|(_, v)| v)
            .sum();
        // Variance at rounding level of the mean (a constant output) counts as zero.
        let c0_abs = c0.map_or(0.0, |t| self.coeffs[(t, col)].abs());
        let negligible = (64.0 * f64::EPSILON * c0_abs).powi(2);
        (0..self.basis.dim)
            .map(|i| {
                if var.is_nan() || var <= negligible {
                    return 0.0;
                }
                let s: f64 = self
                    .basis
                    .indices
                    .iter()
                    .zip(&parts)
                    .filter(|(k, _)| selects(k, i))
                    .map(|(_, v)| v)
                    .sum();
                s / var
            })
            .collect()
    }
}

fn dot_column(c: &DMatrix<f64>, col: usize, psi: &[f64]) -> f64 {
    c.column(col).iter().zip(psi).map(|(a, b)| a * b).sum()
}

fn check_inputs(
    basis: &MultiIndexSet,
    points: &[Vec<f64>],
    weights: &[f64],
    values: &DMatrix<f64>,
    nodes_per_dim: &[usize],
) -> Result<(), PceError> {
    basis.validate()?;
    if points.len() != weights.len() || points.len() != values.nrows() {
        return Err(PceError::Shape(format!(
            "{} points, {} weights, {} value rows",
            points.len(),
            weights.len(),
            values.nrows()
        )));
    }
    if nodes_per_dim.len() != basis.dim {
        return Err(PceError::Shape(format!(
            "nodes given for {} dimensions, basis has {}",
            nodes_per_dim.len(),
            basis.dim
        )));
    }
    for (q, p) in points.iter().enumerate() {
        if p.len() != basis.dim {
            return Err(PceError::Shape(format!(
                "point {q} has {} coordinates, basis has {} dimensions",
                p.len(),
                basis.dim
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
fn aliasing(basis: &MultiIndexSet, nodes_per_dim: &[usize]) -> Vec<PceError> {
    basis
        .max_degree_per_dim()
        .into_iter()
        .zip(nodes_per_dim)
        .enumerate()
        .filter(|&(_, (degree, &nodes))| degree >= nodes)
        .map(|(dim, (degree, &nodes))| PceError::OrderNotBelowNodes { dim, degree, nodes })
        .collect()
}

fn project_unchecked(
    basis: MultiIndexSet,
    points: &[Vec<f64>],
    weights: &[f64],
    values: &DMatrix<f64>,
) -> Pce {
    let p = basis.len();
    // a[(t, q)] = w_q Psi_t(z_q) / ||Psi_t||^2
    let mut a = DMatrix::<f64>::zeros(p, points.len());
    let inv_norms: Vec<f64> = (0..p).map(|t| 1.0 / basis.norm_sq(t)).collect();
    let mut psi = vec![0.0; p];
    let mut scratch = Vec::new();
    for (q, (z, &w)) in points.iter().zip(weights).enumerate() {
        basis.eval_with(z, &mut psi, &mut scratch);
        for t in 0..p {
            a[(t, q)] = w * psi[t] * inv_norms[t];
        }
    }
    let coeffs = a * values;
    Pce { basis, coeffs }
}
