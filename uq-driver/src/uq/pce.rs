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

use nalgebra::DMatrix;
use rayon::prelude::*;

use crate::uq::rng;

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

/// Probabilists' Hermite polynomial `He_n(x)` by the three-term recurrence.
pub fn hermite_he(n: usize, x: f64) -> f64 {
    let (mut prev, mut cur) = (0.0, 1.0);
    for k in 0..n {
        let next = x * cur - k as f64 * prev;
        prev = cur;
        cur = next;
    }
    cur
}

/// All `He_0(x), ..., He_{n_max}(x)` into `out[0..=n_max]` (only the first
/// `out.len()` values if `out` is shorter).
pub fn hermite_all(n_max: usize, x: f64, out: &mut [f64]) {
    let m = out.len().min(n_max.saturating_add(1));
    if m == 0 {
        return;
    }
    out[0] = 1.0;
    if m > 1 {
        out[1] = x;
    }
    for k in 1..m.saturating_sub(1) {
        out[k + 1] = x * out[k] - k as f64 * out[k - 1];
    }
}

/// `n!` as an integer while it fits in a `u128` (n <= 34).
fn factorial_u128(n: usize) -> Option<u128> {
    (1..=n as u128).try_fold(1u128, |acc, k| acc.checked_mul(k))
}

/// `n!` as `f64`: exact integer arithmetic up to 34!, then floating products
/// (infinite beyond 170!).
fn factorial_f64(n: usize) -> f64 {
    const EXACT: usize = 34;
    if n <= EXACT {
        return factorial_u128(n).map_or(f64::INFINITY, |v| v as f64);
    }
    let mut f = factorial_u128(EXACT).map_or(f64::INFINITY, |v| v as f64);
    for k in EXACT + 1..=n {
        f *= k as f64;
    }
    f
}

/// `E[He_n(Z)^2] = n!` for `Z ~ N(0, 1)` (exact up to 34!, correctly rounded
/// from the integer; then rounded products).
pub fn hermite_norm_sq(n: usize) -> f64 {
    factorial_f64(n)
}

/// Exact integer `i! j! k! / ((s-i)! (s-j)! (s-k)!)` as `u128`, if it fits.
fn triple_u128(i: usize, j: usize, a: usize, b: usize, k: usize) -> Option<u128> {
    // = C(i, b) * j! / a! * k!  with i = b + c, j = a + c, k = a + b.
    let mut binom: u128 = 1;
    for m in 0..b as u128 {
        // C(i, m+1) = C(i, m) (i - m) / (m + 1), exact at every step.
        binom = binom.checked_mul(i as u128 - m)? / (m + 1);
    }
    let mut falling: u128 = 1;
    for m in a + 1..=j {
        falling = falling.checked_mul(m as u128)?;
    }
    binom.checked_mul(falling)?.checked_mul(factorial_u128(k)?)
}

/// Galerkin triple product `E[He_i He_j He_k]`:
/// `i! j! k! / ((s-i)! (s-j)! (s-k)!)` when `i + j + k = 2s` is even and
/// `s >= i, j, k`, else 0. Computed in exact integer arithmetic when the value
/// fits in a `u128` (then correctly rounded to `f64`), else in floating point.
pub fn hermite_triple(i: usize, j: usize, k: usize) -> f64 {
    let total = i + j + k;
    if total % 2 == 1 {
        return 0.0;
    }
    let s = total / 2;
    if s < i || s < j || s < k {
        return 0.0;
    }
    let (a, b) = (s - i, s - j);
    if let Some(v) = triple_u128(i, j, a, b, k) {
        return v as f64;
    }
    let mut binom = 1.0;
    for m in 0..b {
        binom *= (i - m) as f64 / (m + 1) as f64;
    }
    let mut falling = 1.0;
    for m in a + 1..=j {
        falling *= m as f64;
    }
    binom * falling * factorial_f64(k)
}

/// A set of multi-indices `k = (k_1, ..., k_d)` defining the chaos basis
/// `Psi_k(z) = prod_i He_{k_i}(z_i)`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MultiIndexSet {
    /// Number of germ dimensions `d`.
    pub dim: usize,
    /// Largest total degree.
    pub order: usize,
    /// The multi-indices, each of length `dim`, all distinct.
    pub indices: Vec<Vec<usize>>,
}

fn push_total_degree(dim: usize, deg: usize, prefix: &mut Vec<usize>, out: &mut Vec<Vec<usize>>) {
    if dim == 1 {
        prefix.push(deg);
        out.push(prefix.clone());
        prefix.pop();
        return;
    }
    for first in (0..=deg).rev() {
        prefix.push(first);
        push_total_degree(dim - 1, deg - first, prefix, out);
        prefix.pop();
    }
}

impl MultiIndexSet {
    /// Total-order set `{k : |k| <= order}` with `C(order + dim, dim)`
    /// members, in graded lexicographic order: degree 0 first; within a
    /// degree, descending in the first variable, then the second, ...
    /// (for `dim = 2`, `order = 2`: `[0,0] [1,0] [0,1] [2,0] [1,1] [0,2]`).
    /// The constant term is always index 0. `dim = 0` gives the constant only.
    pub fn total_order(dim: usize, order: usize) -> Self {
        let mut indices = Vec::new();
        if dim == 0 {
            indices.push(Vec::new());
        } else {
            let mut prefix = Vec::with_capacity(dim);
            for deg in 0..=order {
                push_total_degree(dim, deg, &mut prefix, &mut indices);
            }
        }
        MultiIndexSet {
            dim,
            order: if dim == 0 { 0 } else { order },
            indices,
        }
    }

    /// Number of germ dimensions (same as the `dim` field).
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// Largest total degree (same as the `order` field).
    pub fn order(&self) -> usize {
        self.order
    }

    /// The multi-indices (same as the `indices` field).
    pub fn indices(&self) -> &[Vec<usize>] {
        &self.indices
    }

    /// Position of the multi-index `k` in the set, if present.
    pub fn position(&self, k: &[usize]) -> Option<usize> {
        self.indices.iter().position(|m| m.as_slice() == k)
    }

    /// Number of basis terms.
    pub fn len(&self) -> usize {
        self.indices.len()
    }

    /// Whether the set has no term.
    pub fn is_empty(&self) -> bool {
        self.indices.is_empty()
    }

    /// `||Psi_k||^2 = E[Psi_k^2] = prod_i k_i!` (exact) for term `k`.
    ///
    /// # Panics
    /// If `k >= self.len()`.
    pub fn norm_sq(&self, k: usize) -> f64 {
        self.indices[k]
            .iter()
            .map(|&n| hermite_norm_sq(n))
            .product()
    }

    /// Position of the constant term (all-zero multi-index), if present.
    pub fn constant_term(&self) -> Option<usize> {
        self.indices.iter().position(|k| k.iter().all(|&n| n == 0))
    }

    /// Largest degree of each dimension over the set.
    pub fn max_degree_per_dim(&self) -> Vec<usize> {
        let mut m = vec![0; self.dim];
        for k in &self.indices {
            for (mi, &ki) in m.iter_mut().zip(k) {
                *mi = (*mi).max(ki);
            }
        }
        m
    }

    /// Checks that every multi-index has `dim` entries, that they are distinct
    /// and that their total degree does not exceed `order`.
    pub fn validate(&self) -> Result<(), PceError> {
        let mut seen = std::collections::HashSet::new();
        for (t, k) in self.indices.iter().enumerate() {
            if k.len() != self.dim {
                return Err(PceError::InvalidBasis(format!(
                    "term {t} has {} entries, expected {}",
                    k.len(),
                    self.dim
                )));
            }
            if k.iter().sum::<usize>() > self.order {
                return Err(PceError::InvalidBasis(format!(
                    "term {t} has total degree above the order {}",
                    self.order
                )));
            }
            if !seen.insert(k) {
                return Err(PceError::InvalidBasis(format!("term {t} is repeated")));
            }
        }
        Ok(())
    }

    /// Values of all basis polynomials at `z` into `out` (`out[t] = Psi_t(z)`).
    ///
    /// # Panics
    /// If `z.len() != self.dim` or `out.len() != self.len()`.
    pub fn eval(&self, z: &[f64], out: &mut [f64]) {
        let mut scratch = Vec::new();
        self.eval_with(z, out, &mut scratch);
    }

    /// [`eval`](Self::eval) reusing a scratch buffer (for loops over points).
    fn eval_with(&self, z: &[f64], out: &mut [f64], scratch: &mut Vec<f64>) {
        assert_eq!(z.len(), self.dim, "point dimension differs from the basis");
        assert_eq!(
            out.len(),
            self.len(),
            "output length differs from the basis"
        );
        let stride = self.max_degree_per_dim().into_iter().max().unwrap_or(0) + 1;
        scratch.clear();
        scratch.resize(stride * self.dim, 0.0);
        for (i, &zi) in z.iter().enumerate() {
            hermite_all(stride - 1, zi, &mut scratch[i * stride..(i + 1) * stride]);
        }
        for (o, k) in out.iter_mut().zip(&self.indices) {
            *o = k
                .iter()
                .enumerate()
                .map(|(i, &ki)| scratch[i * stride + ki])
                .product();
        }
    }
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

    /// `n` draws of output `col` of the surrogate: draw `i` evaluates it at
    /// `d` standard normals from `rng::stream(seed, i)`
    /// ([`rng::standard_normal`]), so the result is independent of the
    /// thread count.
    ///
    /// # Panics
    /// If `col >= self.outputs()`.
    pub fn sample_column(&self, col: usize, n: usize, seed: u64) -> Vec<f64> {
        assert!(col < self.outputs(), "column {col} out of range");
        let d = self.basis.dim;
        (0..n as u64)
            .into_par_iter()
            .map_init(
                || (vec![0.0; d], vec![0.0; self.basis.len()], Vec::new()),
                |(z, psi, scratch), i| {
                    let mut r = rng::stream(seed, i);
                    for zj in z.iter_mut() {
                        *zj = rng::standard_normal(&mut r);
                    }
                    self.basis.eval_with(z, psi, scratch);
                    dot_column(&self.coeffs, col, psi)
                },
            )
            .collect()
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::uq::quadrature::{gauss_hermite, tensor_grid};

    fn factorial_exact(n: u32) -> u128 {
        (1..=u128::from(n)).product()
    }

    #[test]
    fn hermite_polynomials_match_explicit_forms() {
        for &x in &[-2.5f64, -1.0, 0.0, 0.3, 2.0, 7.0] {
            let explicit = [
                1.0,
                x,
                x * x - 1.0,
                x * x * x - 3.0 * x,
                x.powi(4) - 6.0 * x * x + 3.0,
                x.powi(5) - 10.0 * x.powi(3) + 15.0 * x,
            ];
            let mut all = [0.0; 6];
            hermite_all(5, x, &mut all);
            for (n, &e) in explicit.iter().enumerate() {
                let tol = 1e-13 * e.abs().max(1.0);
                assert!((hermite_he(n, x) - e).abs() <= tol, "He_{n}({x})");
                assert!((all[n] - e).abs() <= tol);
            }
        }
        // Short buffers are filled as far as they go.
        let mut short = [9.0; 2];
        hermite_all(5, 2.0, &mut short);
        assert_eq!(short, [1.0, 2.0]);
        let mut none: [f64; 0] = [];
        hermite_all(3, 1.0, &mut none);
    }

    #[test]
    fn norms_are_exact_factorials_and_match_quadrature() {
        assert_eq!(hermite_norm_sq(0), 1.0);
        assert_eq!(hermite_norm_sq(20), 2_432_902_008_176_640_000.0);
        assert_eq!(hermite_norm_sq(30), factorial_exact(30) as f64);
        assert_eq!(hermite_norm_sq(34), factorial_exact(34) as f64);
        assert!((hermite_norm_sq(40) / 8.159_152_832_478_977e47 - 1.0).abs() < 1e-14);
        let (x, w) = gauss_hermite(20).unwrap();
        for m in 0..12 {
            for n in 0..12 {
                let q: f64 = x
                    .iter()
                    .zip(&w)
                    .map(|(&x, &w)| w * hermite_he(m, x) * hermite_he(n, x))
                    .sum();
                let want = if m == n { hermite_norm_sq(n) } else { 0.0 };
                assert!(
                    (q - want).abs() < 1e-12 * hermite_norm_sq(m.max(n)),
                    "{m} {n}"
                );
            }
        }
    }

    #[test]
    fn triple_products_exact_values() {
        assert_eq!(hermite_triple(0, 0, 0), 1.0);
        assert_eq!(hermite_triple(1, 1, 2), 2.0);
        assert_eq!(hermite_triple(2, 2, 2), 8.0);
        assert_eq!(hermite_triple(0, 3, 3), 6.0);
        assert_eq!(hermite_triple(1, 2, 2), 0.0); // odd sum
        assert_eq!(hermite_triple(1, 1, 4), 0.0); // s = 3 < 4
        assert_eq!(hermite_triple(3, 4, 5), 1440.0); // 3!4!5!/(3!2!1!)
                                                     // 10!^3 / 5!^3 = 30240^3, exact in f64.
        assert_eq!(hermite_triple(10, 10, 10), 27_653_197_824_000.0);
        // Symmetric in its arguments.
        for (i, j, k) in [(2, 5, 7), (6, 6, 4), (12, 9, 5)] {
            let v = hermite_triple(i, j, k);
            for p in [(i, k, j), (j, i, k), (j, k, i), (k, i, j), (k, j, i)] {
                assert_eq!(hermite_triple(p.0, p.1, p.2), v);
            }
        }
        // Beyond u128: (40!/20!)^3, floating-point path.
        let r: f64 = (21..=40).map(f64::from).product();
        let v = hermite_triple(40, 40, 40);
        assert!((v / r.powi(3) - 1.0).abs() < 1e-13);
        // Galerkin identity He_1 He_n = He_{n+1} + n He_{n-1}.
        for n in 1..20 {
            assert_eq!(hermite_triple(1, n, n + 1), hermite_norm_sq(n + 1));
            assert_eq!(
                hermite_triple(1, n, n - 1),
                n as f64 * hermite_norm_sq(n - 1)
            );
        }
    }

    #[test]
    fn triple_products_match_quadrature() {
        let (x, w) = gauss_hermite(20).unwrap(); // exact to degree 39
        for i in 0..=9 {
            for j in 0..=9 {
                for k in 0..=9 {
                    let q: f64 = x
                        .iter()
                        .zip(&w)
                        .map(|(&x, &w)| w * hermite_he(i, x) * hermite_he(j, x) * hermite_he(k, x))
                        .sum();
                    let want = hermite_triple(i, j, k);
                    let scale = (hermite_norm_sq(i) * hermite_norm_sq(j) * hermite_norm_sq(k))
                        .sqrt()
                        .max(1.0);
                    assert!(
                        (q - want).abs() < 1e-12 * scale,
                        "{i} {j} {k}: {q} vs {want}"
                    );
                }
            }
        }
    }

    #[test]
    fn total_order_sets() {
        let s = MultiIndexSet::total_order(2, 2);
        let expect: Vec<Vec<usize>> = vec![
            vec![0, 0],
            vec![1, 0],
            vec![0, 1],
            vec![2, 0],
            vec![1, 1],
            vec![0, 2],
        ];
        assert_eq!(s.indices, expect);
        assert_eq!(MultiIndexSet::total_order(2, 6).len(), 28);
        assert_eq!(MultiIndexSet::total_order(3, 4).len(), 35);
        assert_eq!(MultiIndexSet::total_order(5, 3).len(), 56);
        assert_eq!(MultiIndexSet::total_order(1, 7).len(), 8);
        let s3 = MultiIndexSet::total_order(3, 2);
        assert_eq!(
            s3.indices[4..10],
            [
                vec![2, 0, 0],
                vec![1, 1, 0],
                vec![1, 0, 1],
                vec![0, 2, 0],
                vec![0, 1, 1],
                vec![0, 0, 2]
            ]
        );
        assert!(s3.validate().is_ok());
        assert_eq!(s3.position(&[1, 0, 1]), Some(6));
        assert_eq!(s3.position(&[3, 0, 0]), None);
        assert_eq!((s3.dim(), s3.order(), s3.indices().len()), (3, 2, 10));
        let zero = MultiIndexSet::total_order(0, 3);
        assert_eq!(zero.len(), 1);
        assert_eq!(zero.constant_term(), Some(0));
        let s = MultiIndexSet::total_order(3, 3);
        assert_eq!(
            s.norm_sq(s.indices.iter().position(|k| k == &[2, 0, 1]).unwrap()),
            2.0
        );
        assert_eq!(s.max_degree_per_dim(), vec![3, 3, 3]);
    }

    #[test]
    fn invalid_sets_are_rejected() {
        let mut s = MultiIndexSet::total_order(2, 2);
        s.indices.push(vec![1, 1]);
        assert!(matches!(s.validate(), Err(PceError::InvalidBasis(_))));
        let mut s = MultiIndexSet::total_order(2, 2);
        s.indices[3] = vec![2];
        assert!(matches!(s.validate(), Err(PceError::InvalidBasis(_))));
    }

    #[test]
    fn basis_eval_is_the_product_of_hermites() {
        let s = MultiIndexSet::total_order(3, 4);
        let z = [0.3, -1.2, 2.1];
        let mut out = vec![0.0; s.len()];
        s.eval(&z, &mut out);
        for (t, k) in s.indices.iter().enumerate() {
            let want: f64 = k.iter().zip(&z).map(|(&n, &x)| hermite_he(n, x)).product();
            assert!((out[t] - want).abs() < 1e-13 * want.abs().max(1.0));
        }
    }

    type Fun<'a> = &'a dyn Fn(&[f64]) -> f64;

    /// Values of `f` at the points of a tensor grid, one output column per function.
    fn grid_values(points: &[Vec<f64>], fs: &[Fun]) -> DMatrix<f64> {
        DMatrix::from_fn(points.len(), fs.len(), |q, c| fs[c](&points[q]))
    }

    #[test]
    fn projection_of_a_polynomial_is_exact() {
        // f = 1 + 2 He1(z1) + 3 He1(z1) He2(z2) + 0.5 He3(z2)
        let f = |z: &[f64]| {
            1.0 + 2.0 * hermite_he(1, z[0])
                + 3.0 * hermite_he(1, z[0]) * hermite_he(2, z[1])
                + 0.5 * hermite_he(3, z[1])
        };
        let g = |z: &[f64]| z[0] * z[0]; // = He2 + 1
        let npd = [4, 4];
        let grid = tensor_grid(&npd).unwrap();
        let vals = grid_values(&grid.points, &[&f, &g]);
        let basis = MultiIndexSet::total_order(2, 3);
        let pce = Pce::project(basis.clone(), &grid.points, &grid.weights, &vals, &npd).unwrap();
        let pos = |k: [usize; 2]| basis.indices.iter().position(|b| b == &k).unwrap();
        for t in 0..basis.len() {
            let want = match basis.indices[t].as_slice() {
                [0, 0] => 1.0,
                [1, 0] => 2.0,
                [1, 2] => 3.0,
                [0, 3] => 0.5,
                _ => 0.0,
            };
            assert!(
                (pce.coeffs[(t, 0)] - want).abs() < 1e-13,
                "term {:?}",
                basis.indices[t]
            );
        }
        assert!((pce.coeffs[(pos([2, 0]), 1)] - 1.0).abs() < 1e-13);
        assert!((pce.mean()[0] - 1.0).abs() < 1e-13);
        assert!((pce.mean()[1] - 1.0).abs() < 1e-13);
        // Var f = 4 * 1 + 9 * 1! 2! + 0.25 * 3! = 23.5; Var z1^2 = 2.
        let var = pce.variance();
        assert!((var[0] - 23.5).abs() < 1e-12);
        assert!((var[1] - 2.0).abs() < 1e-12);
        assert!((pce.std()[1] - 2f64.sqrt()).abs() < 1e-12);
        // The surrogate reproduces f anywhere.
        let z = [0.7, -1.9];
        assert!((pce.eval(&z)[0] - f(&z)).abs() < 1e-12);
        assert!((pce.eval_column(1, &z) - g(&z)).abs() < 1e-12);
    }

    #[test]
    fn lognormal_fixture_mean_and_variance() {
        // f = exp(a z): mean exp(a^2/2), variance exp(2a^2) - exp(a^2);
        // exact coefficients exp(a^2/2) a^n / n!.
        let a: f64 = 0.5;
        let (order, nodes) = (10, 11);
        let grid = tensor_grid(&[nodes]).unwrap();
        let vals = grid_values(&grid.points, &[&|z: &[f64]| (a * z[0]).exp()]);
        let pce = Pce::project(
            MultiIndexSet::total_order(1, order),
            &grid.points,
            &grid.weights,
            &vals,
            &[nodes],
        )
        .unwrap();
        let m = (0.5 * a * a).exp();
        assert!((pce.mean()[0] - m).abs() < 1e-14);
        let exact_var = (2.0 * a * a).exp() - (a * a).exp();
        // Truncation: sum_{n > 10} exp(a^2) a^(2n) / n! ~ 3e-14.
        assert!((pce.variance()[0] - exact_var).abs() < 1e-12);
        // Exact up to the aliasing of the neglected degrees (largest for n = order).
        for n in 0..=order {
            let c = m * a.powi(n as i32) / hermite_norm_sq(n);
            assert!((pce.coeffs[(n, 0)] - c).abs() < 1e-11 * m, "n={n}");
        }
        // Sampling the surrogate reproduces the moments.
        let s = pce.sample_column(0, 40_000, 5);
        let mean = s.iter().sum::<f64>() / s.len() as f64;
        let sd = exact_var.sqrt();
        assert!((mean - m).abs() < 5.0 * sd / 200.0);
        assert_eq!(s, pce.sample_column(0, 40_000, 5));
        assert_eq!(s[..100], pce.sample_column(0, 100, 5)[..]);
    }

    #[test]
    fn sobol_indices_of_additive_and_interacting_functions() {
        let npd = [3, 3];
        let grid = tensor_grid(&npd).unwrap();
        let vals = grid_values(
            &grid.points,
            &[
                &|z: &[f64]| z[0] + 2.0 * z[1],
                &|z: &[f64]| z[0] * z[1] + z[0],
                &|_: &[f64]| 3.0,
            ],
        );
        let pce = Pce::project(
            MultiIndexSet::total_order(2, 2),
            &grid.points,
            &grid.weights,
            &vals,
            &npd,
        )
        .unwrap();
        let close = |a: &[f64], b: &[f64]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-13);
        assert!(close(&pce.sobol_first(0), &[0.2, 0.8]));
        assert!(close(&pce.sobol_total(0), &[0.2, 0.8]));
        // z1 z2 + z1: Var = 2; S = (1/2, 0), T = (1, 1/2).
        assert!(close(&pce.sobol_first(1), &[0.5, 0.0]));
        assert!(close(&pce.sobol_total(1), &[1.0, 0.5]));
        // Constant output: zero variance gives zero indices.
        assert_eq!(pce.sobol_first(2), vec![0.0, 0.0]);
        assert!(pce.variance()[2] < 1e-28);
    }

    #[test]
    fn order_not_below_nodes_is_refused() {
        // The trap: 6 nodes, order 6. He_6 vanishes at all 6 nodes, so its
        // quadrature norm is ~1e-14 and dividing by it would explode.
        let npd = [6];
        let grid = tensor_grid(&npd).unwrap();
        let quad_norm: f64 = grid
            .points
            .iter()
            .zip(&grid.weights)
            .map(|(p, w)| w * hermite_he(6, p[0]).powi(2))
            .sum();
        assert!(quad_norm < 1e-10, "{quad_norm}");
        let vals = grid_values(&grid.points, &[&|z: &[f64]| hermite_he(6, z[0]) + z[0]]);
        let err = Pce::project(
            MultiIndexSet::total_order(1, 6),
            &grid.points,
            &grid.weights,
            &vals,
            &npd,
        )
        .unwrap_err();
        assert_eq!(
            err,
            PceError::OrderNotBelowNodes {
                dim: 0,
                degree: 6,
                nodes: 6
            }
        );
        assert!(err
            .to_string()
            .contains("order must be below the nodes per dimension"));
        // Lenient: a warning, aliased (zero) top coefficient, no explosion.
        let (pce, warnings) = Pce::project_lenient(
            MultiIndexSet::total_order(1, 6),
            &grid.points,
            &grid.weights,
            &vals,
            &npd,
        )
        .unwrap();
        assert_eq!(warnings.len(), 1);
        assert!(pce.coeffs[(6, 0)].abs() < 1e-12);
        assert!((pce.std()[0] - 1.0).abs() < 1e-12);
        // Order 5 with 6 nodes is fine.
        assert!(Pce::project(
            MultiIndexSet::total_order(1, 5),
            &grid.points,
            &grid.weights,
            &vals,
            &npd
        )
        .is_ok());
    }

    #[test]
    fn bad_shapes_and_values_are_errors() {
        let npd = [2, 2];
        let grid = tensor_grid(&npd).unwrap();
        let basis = MultiIndexSet::total_order(2, 1);
        let vals = DMatrix::from_element(4, 3, 1.0);
        let ok = Pce::project(basis.clone(), &grid.points, &grid.weights, &vals, &npd);
        assert!(ok.is_ok());
        let r = Pce::project(basis.clone(), &grid.points, &grid.weights[..3], &vals, &npd);
        assert!(matches!(r, Err(PceError::Shape(_))));
        let r = Pce::project(basis.clone(), &grid.points, &grid.weights, &vals, &[2]);
        assert!(matches!(r, Err(PceError::Shape(_))));
        let mut bad = vals.clone();
        bad[(2, 1)] = f64::NAN;
        let r = Pce::project(basis, &grid.points, &grid.weights, &bad, &npd);
        assert_eq!(
            r,
            Err(PceError::NotFinite {
                what: "value",
                point: 2
            })
        );
    }
}
