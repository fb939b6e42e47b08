//! Multi-index sets: the terms `Psi_k(z) = prod_i He_{k_i}(z_i)` of a chaos basis.

use nalgebra::DMatrix;

use super::hermite::{hermite_all, hermite_norm_sq};
use super::PceError;
use crate::uq::rng;

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
    pub(crate) fn eval_with(&self, z: &[f64], out: &mut [f64], scratch: &mut Vec<f64>) {
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

    /// The basis at `n` random germ points, one row per point (`n × len`): point `i` has the
    /// `dim` standard normals of `rng::stream(seed, i)` ([`rng::standard_normal`]), so the
    /// draws do not depend on `n` beyond their number, nor on the thread count.
    pub fn draws(&self, n: usize, seed: u64) -> DMatrix<f64> {
        let mut psi = DMatrix::<f64>::zeros(n, self.len());
        let mut z = vec![0.0; self.dim];
        let mut row = vec![0.0; self.len()];
        let mut scratch = Vec::new();
        for i in 0..n {
            let mut r = rng::stream(seed, i as u64);
            for zj in z.iter_mut() {
                *zj = rng::standard_normal(&mut r);
            }
            self.eval_with(&z, &mut row, &mut scratch);
            for (j, v) in row.iter().enumerate() {
                psi[(i, j)] = *v;
            }
        }
        psi
    }
}
