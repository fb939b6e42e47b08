//! Draws of a chaos surrogate for quantiles and densities, computed once per study and in
//! parallel: the basis at the random germ points (the same points as
//! [`germ_draws`], row `i` from the stream `(seed, i)`) is shared by every output
//! and quantity whose chaos has that basis, and each chaos is one matrix product with it,
//! split over blocks of columns. The draws are those of [`Pce::sample`], whatever the
//! thread count.

use std::sync::{Arc, Mutex};

use nalgebra::{DMatrix, DMatrixViewMut};
use rayon::prelude::*;

use crate::uq::pce::{basis_at_germ_draws, Basis, Pce};

/// Rows of germ points evaluated per parallel task.
const ROWS_PER_TASK: usize = 512;
/// Columns of the product per parallel task.
pub(super) const COLUMNS_PER_TASK: usize = 32;

/// The basis at the germ points, per basis, grown on demand.
pub(crate) struct Surrogates {
    seed: u64,
    /// Rows computed at least, whatever is asked first: a study that will ask for the
    /// scalar quantities' `surrogate_samples` draws after the series' fewer ones computes
    /// the basis at the germ points once.
    min_rows: usize,
    cache: Mutex<Vec<(Basis, Arc<DMatrix<f64>>)>>,
}

impl Surrogates {
    /// Draws under `seed`.
    pub fn new(seed: u64) -> Surrogates {
        Surrogates {
            seed,
            min_rows: 0,
            cache: Mutex::new(Vec::new()),
        }
    }

    /// The same, computing at least `rows` germ points whenever it computes any.
    pub fn with_min_rows(self, rows: usize) -> Surrogates {
        Surrogates {
            min_rows: rows,
            ..self
        }
    }

    /// The first `n` draws of `pce` (one row per draw, one column per output of the chaos):
    /// equal to `pce.sample(n, seed)`.
    pub fn draws(&self, pce: &Pce, n: usize) -> DMatrix<f64> {
        let cols = pce.coeffs.ncols();
        let mut out = DMatrix::<f64>::zeros(n, cols);
        self.draws_into(pce, n, 0, out.as_mut_slice());
        out
    }

    /// The columns `j0..j0 + w` of [`Surrogates::draws`] written into `out` (`n` rows, `w`
    /// columns, column-major; `w = out.len() / n`). With `j0` a multiple of 32 the values are
    /// those of `draws` bit for bit (the product is split into the same 32-column tasks).
    pub fn draws_into(&self, pce: &Pce, n: usize, j0: usize, out: &mut [f64]) {
        let psi = self.basis_at_germs(&pce.basis, n);
        out.par_chunks_mut(n.max(1) * COLUMNS_PER_TASK)
            .enumerate()
            .for_each(|(b, block)| product(&psi, pce, n, j0 + b * COLUMNS_PER_TASK, block));
    }

    /// One task of [`Surrogates::draws_into`], on the calling thread: the columns
    /// `j..j + w` of the draws into `out` (`n` rows, `w = out.len() / n` columns). With `j`
    /// a multiple of 32 and `w` at most 32 the values are those of `draws` bit for bit.
    pub fn draws_task(&self, pce: &Pce, n: usize, j: usize, out: &mut [f64]) {
        product(&self.basis_at_germs(&pce.basis, n), pce, n, j, out);
    }

    /// The basis at the first `n` germ points (rows), computed at most once per size.
    fn basis_at_germs(&self, basis: &Basis, n: usize) -> Arc<DMatrix<f64>> {
        let mut cache = self.cache.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((_, psi)) = cache.iter().find(|(b, psi)| b == basis && psi.nrows() >= n) {
            return Arc::clone(psi);
        }
        let psi = Arc::new(basis_at_germs(basis, n.max(self.min_rows), self.seed));
        cache.retain(|(b, _)| b != basis);
        cache.push((basis.clone(), Arc::clone(&psi)));
        psi
    }
}

/// The columns `j..j + w` of the draws, the first `n` rows of `psi` times the coefficients,
/// written straight into `out` (`n` rows, `w = out.len() / n` columns, column-major).
fn product(psi: &DMatrix<f64>, pce: &Pce, n: usize, j: usize, out: &mut [f64]) {
    let w = out.len() / n.max(1);
    let mut part = DMatrixViewMut::from_slice(out, n, w);
    part.gemm(1.0, &psi.rows(0, n), &pce.coeffs.columns(j, w), 0.0);
}

/// `basis.design_matrix(&germ_draws(basis.families(), n, seed))`, rows computed in parallel.
fn basis_at_germs(basis: &Basis, n: usize, seed: u64) -> DMatrix<f64> {
    let terms = basis.len();
    // Row-major per task, then transposed into the column-major matrix.
    let rows: Vec<Vec<f64>> = (0..n.div_ceil(ROWS_PER_TASK))
        .into_par_iter()
        .map(|task| {
            let (i0, i1) = (task * ROWS_PER_TASK, ((task + 1) * ROWS_PER_TASK).min(n));
            let mut block = vec![0.0; (i1 - i0) * terms];
            basis_at_germ_draws(basis, seed, i0..i1, |i, psi| {
                block[(i - i0) * terms..][..terms].copy_from_slice(psi)
            });
            block
        })
        .collect();
    let mut psi = DMatrix::<f64>::zeros(n, terms);
    for (task, block) in rows.iter().enumerate() {
        let i0 = task * ROWS_PER_TASK;
        for (r, row) in block.chunks_exact(terms.max(1)).enumerate() {
            for (t, v) in row.iter().enumerate() {
                psi[(i0 + r, t)] = *v;
            }
        }
    }
    psi
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shared_parallel_draws_are_those_of_pce_sample() {
        use crate::uq::pce::{Family, MultiIndexSet};
        let set = MultiIndexSet::total_degree(3, 3).unwrap();
        let families = vec![Family::Hermite, Family::Legendre, Family::Hermite];
        let basis = Basis::new(families.clone(), set).unwrap();
        let coeffs = DMatrix::from_fn(basis.len(), 70, |t, k| {
            (t as f64 + 1.0).recip() * (1.0 + 0.1 * k as f64).cos()
        });
        let pce = Pce { basis, coeffs };
        let s = Surrogates::new(11);
        for n in [1, 700, 1500, 300] {
            let fast = s.draws(&pce, n);
            let slow = pce.sample(n, 11);
            assert_eq!(fast.shape(), slow.shape());
            let err = (&fast - &slow).abs().max();
            assert!(err <= 1e-14 * slow.abs().max(), "n = {n}: {err}");
        }
        // Another basis is drawn on its own, at the same germ points.
        let small = Pce {
            basis: Basis::new(families, MultiIndexSet::total_degree(3, 1).unwrap()).unwrap(),
            coeffs: DMatrix::from_element(4, 1, 1.0),
        };
        assert_eq!(s.draws(&small, 5), small.sample(5, 11));
        // Blocks of columns starting at multiples of 32 are the same draws bit for bit.
        let all = s.draws(&pce, 700);
        let mut buf = vec![f64::NAN; 700 * 64];
        for j0 in [0, 32] {
            let w = 64.min(70 - j0);
            s.draws_into(&pce, 700, j0, &mut buf[..700 * w]);
            assert_eq!(&buf[..700 * w], all.columns(j0, w).into_owned().as_slice());
        }
        // One task on the calling thread: the same draws bit for bit.
        let mut task = vec![f64::NAN; 700 * 6];
        s.draws_task(&pce, 700, 64, &mut task);
        assert_eq!(&task[..], all.columns(64, 6).into_owned().as_slice());
        // Computing more rows up front changes no draw.
        let ahead = Surrogates::new(11).with_min_rows(2_000);
        assert_eq!(ahead.draws(&pce, 300), s.draws(&pce, 300));
    }
}
