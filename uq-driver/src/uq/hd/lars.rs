//! Sparse regression: least-angle regression (Efron, Hastie, Johnstone & Tibshirani,
//! Ann. Stat. 32, 2004), with the basis chosen by the corrected leave-one-out error
//! ("hybrid LARS", Blatman & Sudret, J. Comput. Phys. 230, 2011).
//!
//! The path algorithm returns the nested sequence of active sets `A_1 ⊂ A_2 ⊂ ...` (column
//! indices of the design). Each is refitted by ordinary least squares (see
//! [`super::regression`]) — with the constant column always included when one is given —
//! and the set of smallest corrected relative LOO error is kept.
//!
//! The path works on the non-constant columns, centred and scaled to unit norm, and on
//! the centred response (the constant plays the intercept). They stop when every column
//! is active, when `N - 2` columns are active (the refit needs `N > P`), when the
//! remaining correlation vanishes, or when the active Gram matrix becomes singular.

use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

use nalgebra::DMatrix;

use super::regression::{columns, LeastSquares, LeastSquaresFit, RegressionError};

/// Path algorithm.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PathKind {
    /// Least-angle regression.
    Lars,
}

/// The selected sparse model.
#[derive(Clone, Debug, PartialEq)]
pub struct SparseFit {
    /// Selected columns (the constant first when given), ascending after it.
    pub columns: Vec<usize>,
    /// The OLS refit on those columns (coefficients in `columns` order).
    pub fit: LeastSquaresFit,
    /// Corrected relative LOO error of every candidate set along the path (by size).
    pub path_errors: Vec<f64>,
}

impl SparseFit {
    /// Coefficients scattered to a full vector of `ncols` entries (zeros elsewhere). Serves
    /// the tests.
    #[cfg(test)]
    pub(crate) fn full_coefficients(&self, ncols: usize) -> Vec<f64> {
        let mut c = vec![0.0; ncols];
        for (&j, &v) in self.columns.iter().zip(&self.fit.coeffs) {
            c[j] = v;
        }
        c
    }
}

/// Centred, unit-norm copies of the non-constant columns, and the map back.
fn standardize(psi: &DMatrix<f64>, constant: Option<usize>) -> (DMatrix<f64>, Vec<usize>) {
    let n = psi.nrows();
    let idx: Vec<usize> = (0..psi.ncols()).filter(|&j| Some(j) != constant).collect();
    let mut x = DMatrix::<f64>::zeros(n, idx.len());
    for (k, &j) in idx.iter().enumerate() {
        let col = psi.column(j);
        let m = if constant.is_some() { col.mean() } else { 0.0 };
        let mut c = col.add_scalar(-m);
        let nrm = c.norm();
        if nrm > 0.0 {
            c /= nrm;
        }
        x.set_column(k, &c);
    }
    (x, idx)
}

/// What the paths need of a design, whatever the response: the standardised columns, their
/// transpose, their Gram matrix and squared norms. Computed once for any number of responses
/// on the same design (the path is then that of the design prepared per response, bit for
/// bit: the same operations on the same numbers). A row of the Gram matrix is computed the
/// first time its column enters a path: a path reads only the rows of its active columns.
#[derive(Clone, Debug)]
pub struct PathDesign {
    constant: Option<usize>,
    x: DMatrix<f64>,
    xt: DMatrix<f64>,
    idx: Vec<usize>,
    /// Row `j`: `x_k . x_j` at `k`, filled on first use.
    gram: Vec<OnceLock<Vec<f64>>>,
    norms2: Vec<f64>,
}

impl PathDesign {
    /// The design `psi` with its constant column (the intercept), if any.
    pub fn new(psi: &DMatrix<f64>, constant: Option<usize>) -> PathDesign {
        let (x, idx) = standardize(psi, constant);
        let m = x.ncols();
        let norms2 = (0..m).map(|j| x.column(j).norm_squared()).collect();
        PathDesign {
            constant,
            xt: x.transpose(),
            x,
            idx,
            gram: (0..m).map(|_| OnceLock::new()).collect(),
            norms2,
        }
    }

    /// `x_k . x_j` for every `k` (summed as nalgebra's `dot`, in the vector units chosen at
    /// run time: the same bits).
    fn gram_row(&self, j: usize) -> &[f64] {
        self.gram[j].get_or_init(|| {
            let n = self.x.nrows();
            let xs = self.x.as_slice();
            let xj = &xs[j * n..(j + 1) * n];
            if n == 0 {
                return vec![0.0; self.x.ncols()];
            }
            xs.chunks_exact(n).map(|xk| kernels::dot(xk, xj)).collect()
        })
    }
}

/// Active columns of LARS with their entry signs and the Cholesky factor `L` of the Gram
/// matrix of the signed columns `s_j x_j`, extended by one row per added column
/// (without the lasso modification the active correlations keep their signs).
/// `L` is kept by rows and by columns (each solve reads it contiguously), and with it
/// `z = L^-1 1`, which only grows by one entry per added column.
struct ActiveSet {
    cols: Vec<usize>,
    signs: Vec<f64>,
    /// Most columns.
    cap: usize,
    /// `L[i][j]` at `i * cap + j`.
    rows: Vec<f64>,
    /// `L[i][j]` at `j * cap + i`.
    by_col: Vec<f64>,
    z: Vec<f64>,
}

impl ActiveSet {
    /// An empty set for up to `cap` columns.
    fn new(cap: usize) -> ActiveSet {
        ActiveSet {
            cols: Vec::with_capacity(cap),
            signs: Vec::with_capacity(cap),
            cap,
            rows: vec![0.0; cap * cap],
            by_col: vec![0.0; cap * cap],
            z: Vec::with_capacity(cap),
        }
    }

    /// Adds column `j` of the design with `sign`; false if it is (numerically) dependent
    /// or the set is full.
    fn add(&mut self, design: &PathDesign, j: usize, sign: f64) -> bool {
        let (k, cap) = (self.cols.len(), self.cap);
        if k == cap {
            return false;
        }
        let gram_j = design.gram_row(j);
        // The new row l solves L l = g (the signed Gram entries), written in place.
        let (done, row) = self.rows.split_at_mut(k * cap);
        let l = &mut row[..k + 1];
        for (i, (&c, &sc)) in self.cols.iter().zip(&self.signs).enumerate() {
            let g = sc * sign * gram_j[c];
            let li = &done[i * cap..i * cap + i + 1];
            let s: f64 = li[..i].iter().zip(&l[..i]).map(|(a, b)| a * b).sum();
            l[i] = (g - s) / li[i];
        }
        let d2 = design.norms2[j] - l[..k].iter().map(|v| v * v).sum::<f64>();
        if d2 <= 1e-12 {
            return false;
        }
        l[k] = d2.sqrt();
        for (i, &v) in l.iter().enumerate() {
            self.by_col[i * cap + k] = v;
        }
        let s: f64 = l[..k].iter().zip(&self.z).map(|(a, b)| a * b).sum();
        self.z.push((1.0 - s) / l[k]);
        self.cols.push(j);
        self.signs.push(sign);
        true
    }

    /// `G^-1 1 = L^-T z`.
    fn gram_solve_ones(&self) -> Vec<f64> {
        let (k, cap) = (self.cols.len(), self.cap);
        let mut w = vec![0.0; k];
        for i in (0..k).rev() {
            let col = &self.by_col[i * cap..i * cap + k];
            let s: f64 = col[i + 1..]
                .iter()
                .zip(&w[i + 1..])
                .map(|(a, b)| a * b)
                .sum();
            w[i] = (self.z[i] - s) / col[i];
        }
        w
    }
}

/// The LARS sequence of active sets (design column indices, constant excluded). Serves the
/// tests ([`lars_path_on`] with the design prepared for this response alone).
#[cfg(test)]
pub(crate) fn lars_path(
    psi: &DMatrix<f64>,
    y: &[f64],
    constant: Option<usize>,
    max_active: usize,
) -> Vec<Vec<usize>> {
    lars_path_on(&PathDesign::new(psi, constant), y, max_active)
}

/// The LARS sequence of active sets (design column indices, constant excluded) on a prepared
/// design.
pub fn lars_path_on(design: &PathDesign, y: &[f64], max_active: usize) -> Vec<Vec<usize>> {
    use kernels::{combine_columns, mat_vec};
    let (x, xt, idx, constant) = (&design.x, &design.xt, &design.idx, design.constant);
    let (n, m) = x.shape();
    let ym = if constant.is_some() {
        y.iter().sum::<f64>() / n as f64
    } else {
        0.0
    };
    let mut r: Vec<f64> = y.iter().map(|v| v - ym).collect();
    let norm = |r: &[f64]| nalgebra::DVectorView::from_slice(r, r.len()).norm();
    let limit = max_active.min(m).min(n.saturating_sub(2));
    let mut in_active = vec![false; m];
    let mut path: Vec<Vec<usize>> = Vec::new();
    let mut c = vec![0.0; m];
    mat_vec(xt, &r, &mut c);
    let first = (0..m).max_by(|&a, &b| c[a].abs().total_cmp(&c[b].abs()));
    let Some(first) = first else {
        return path;
    };
    if c[first].abs() <= 1e-14 * norm(&r).max(f64::MIN_POSITIVE) {
        return path;
    }
    let mut act = ActiveSet::new(limit.max(1));
    if !act.add(design, first, c[first].signum()) {
        return path;
    }
    in_active[first] = true;
    let (mut u, mut a) = (vec![0.0; n], vec![0.0; m]);
    let mut coef = Vec::with_capacity(limit);
    while act.cols.len() <= limit {
        path.push(act.cols.iter().map(|&k| idx[k]).collect());
        if act.cols.len() == limit {
            break;
        }
        let big_c = act.cols.iter().map(|&k| c[k].abs()).fold(0.0, f64::max);
        if big_c <= 1e-13 * norm(&r).max(1e-300) {
            break;
        }
        let gi1 = act.gram_solve_ones();
        let aa = 1.0 / gi1.iter().sum::<f64>().sqrt();
        coef.clear();
        coef.extend(gi1.iter().zip(&act.signs).map(|(&g, &s)| aa * g * s));
        combine_columns(x.as_slice(), &act.cols, &coef, &mut u);
        mat_vec(xt, &u, &mut a);
        let mut gamma = big_c / aa;
        let mut next = None;
        for j in 0..m {
            if in_active[j] {
                continue;
            }
            for cand in [(big_c - c[j]) / (aa - a[j]), (big_c + c[j]) / (aa + a[j])] {
                if cand > 1e-15 * gamma && cand < gamma {
                    gamma = cand;
                    next = Some(j);
                }
            }
        }
        for (ri, &ui) in r.iter_mut().zip(&u) {
            *ri -= ui * gamma;
        }
        mat_vec(xt, &r, &mut c);
        match next {
            Some(j) if act.add(design, j, c[j].signum()) => {
                in_active[j] = true;
            }
            _ => break,
        }
    }
    path
}

/// Corrected relative LOO errors of the nested least-squares fits on the column
/// prefixes `order[..1]`, `order[..2]`, ...: one incremental Gram–Schmidt QR (with
/// re-orthogonalisation), leverages, residuals and `|R^-1|_F^2` updated per column
/// (`O(N P)` per step instead of a refit). Infinite from the first dependent column on.
pub fn nested_loo_errors(psi: &DMatrix<f64>, y: &[f64], order: &[usize]) -> Vec<f64> {
    fn view(v: &[f64]) -> nalgebra::DVectorView<'_, f64> {
        nalgebra::DVectorView::from_slice(v, v.len())
    }
    let (n, cap) = (psi.nrows(), order.len());
    let var = super::regression::sample_variance(y);
    let negligible = super::regression::negligible_variance(y);
    // q_j at j * n; column j of R^-1 (upper triangular) at j * cap.
    let mut qs = vec![0.0; n * cap];
    let mut rinv = vec![0.0; cap * cap];
    let (mut r, mut s) = (vec![0.0; cap], vec![0.0; cap]);
    let mut tr = 0.0;
    let mut res = y.to_vec();
    let mut lev = vec![0.0; n];
    let mut out = Vec::with_capacity(order.len());
    for (k, &col) in order.iter().enumerate() {
        let (done, rest) = qs.split_at_mut(k * n);
        let v = &mut rest[..n];
        v.copy_from_slice(psi.column(col).as_slice());
        let norm0 = view(v).norm();
        r[..=k].fill(0.0);
        // Modified Gram-Schmidt twice: d = q_j . v, v -= d q_j for each j in turn, each
        // update fused with the next product.
        if k > 0 {
            let q = |j: usize| &done[(j % k) * n..(j % k + 1) * n];
            let mut d = kernels::dot(q(0), v);
            for step in 0..2 * k {
                r[step % k] += d;
                if step + 1 < 2 * k {
                    d = kernels::axpy_dot(v, -d, q(step), q(step + 1));
                } else {
                    for (vi, &qi) in v.iter_mut().zip(q(step)) {
                        *vi += -d * qi;
                    }
                }
            }
        }
        let rkk = view(v).norm();
        if rkk.is_nan() || rkk <= 1e-10 * norm0.max(f64::MIN_POSITIVE) {
            out.resize(order.len(), f64::INFINITY);
            return out;
        }
        r[k] = rkk;
        v.iter_mut().for_each(|vi| *vi /= rkk);
        let q = &*v;
        // New column of R^-1: t_i = -(sum_{j >= i} Rinv[i][j] r_j) / rkk, t_k = 1 / rkk;
        // the sums over j in order, all i at once.
        s[..k].fill(-0.0);
        for j in 0..k {
            let rj = r[j];
            for (si, &ri) in s[..=j].iter_mut().zip(&rinv[j * cap..j * cap + j + 1]) {
                *si += ri * rj;
            }
        }
        let t = &mut rinv[k * cap..k * cap + k + 1];
        for (ti, &si) in t.iter_mut().zip(&s[..k]) {
            *ti = -si / rkk;
        }
        t[k] = 1.0 / rkk;
        tr += t.iter().map(|x| x * x).sum::<f64>();
        let qy = view(q).dot(&view(y));
        for ((ri, h), &qi) in res.iter_mut().zip(lev.iter_mut()).zip(q) {
            *ri += -qy * qi;
            *h += qi * qi;
        }
        let p = k + 1;
        let err = if n > p {
            let loo = (0..n)
                .map(|i| {
                    let d = 1.0 - lev[i];
                    if d <= 1e-12 {
                        if res[i] == 0.0 {
                            0.0
                        } else {
                            f64::INFINITY
                        }
                    } else {
                        (res[i] / d).powi(2)
                    }
                })
                .sum::<f64>()
                / n as f64;
            let t = n as f64 / (n - p) as f64 * (1.0 + tr);
            super::regression::relative(t * loo, var, negligible)
        } else {
            f64::INFINITY
        };
        out.push(err);
    }
    out
}

/// Refits each active set of `path` (plus the constant column, if any) by least squares
/// and keeps the smallest corrected relative LOO error. The empty model (constant only)
/// is a candidate when a constant is given. The path's sets must be nested, each adding
/// one column (as LARS produces); the errors come from [`nested_loo_errors`] and
/// the chosen set is refitted once. Serves the tests (the fit without a cache).
#[cfg(test)]
pub(crate) fn select_by_loo(
    psi: &DMatrix<f64>,
    y: &[f64],
    constant: Option<usize>,
    path: &[Vec<usize>],
) -> Result<SparseFit, RegressionError> {
    select_by_loo_cached(psi, y, constant, path, None)
}

/// Refits each active set of `path` (plus the constant column, if any) by least squares
/// and keeps the smallest corrected relative LOO error. The empty model (constant only)
/// is a candidate when a constant is given. The path's sets must be nested, each adding
/// one column (as LARS produces); the errors come from [`nested_loo_errors`] and
/// the chosen set is refitted once, its factorisation taken from `cache` when another
/// response chose the same columns (the same numbers: the factorisation depends on the
/// columns only).
fn select_by_loo_cached(
    psi: &DMatrix<f64>,
    y: &[f64],
    constant: Option<usize>,
    path: &[Vec<usize>],
    cache: Option<&SupportCache>,
) -> Result<SparseFit, RegressionError> {
    // Column order: the constant, then each set's new column.
    let mut order: Vec<usize> = constant.into_iter().collect();
    for set in path {
        let new: Vec<usize> = set.iter().copied().filter(|j| !order.contains(j)).collect();
        if new.len() != 1 || set.len() + usize::from(constant.is_some()) != order.len() + 1 {
            return Err(RegressionError::Shape {
                rows: set.len(),
                responses: order.len(),
            });
        }
        order.push(new[0]);
    }
    if order.is_empty() {
        return Err(RegressionError::Underdetermined {
            samples: psi.nrows(),
            terms: psi.ncols(),
        });
    }
    let errors = nested_loo_errors(psi, y, &order);
    let best = (0..errors.len())
        .filter(|&k| errors[k].is_finite())
        .min_by(|&a, &b| errors[a].total_cmp(&errors[b]))
        .ok_or(RegressionError::Underdetermined {
            samples: psi.nrows(),
            terms: order.len(),
        })?;
    let mut cols: Vec<usize> = constant.into_iter().collect();
    let mut rest: Vec<usize> = order[usize::from(constant.is_some())..=best].to_vec();
    rest.sort_unstable();
    cols.extend(rest);
    let fit = match cache {
        Some(cache) => cache.factor(psi, &cols)?.fit(y)?,
        None => LeastSquares::new(&columns(psi, &cols))?.fit(y)?,
    };
    Ok(SparseFit {
        columns: cols,
        fit,
        path_errors: errors,
    })
}

/// Least-squares factorisations of column subsets of one design, shared by the responses
/// fitted on it (a time-resolved output chooses the same few supports again and again).
/// Holds at most [`SupportCache::BUDGET`] numbers; past that it factors without keeping.
#[derive(Debug, Default)]
pub struct SupportCache {
    map: Mutex<(usize, Factors)>,
}

/// Factorisations by column set.
type Factors = HashMap<Vec<usize>, Arc<LeastSquares>>;

impl SupportCache {
    /// Most numbers kept (matrices of the factorisations), 64 MB.
    pub const BUDGET: usize = 1 << 23;

    /// The factorisation of the columns `cols` of `psi` (`psi` must be the cache's design).
    fn factor(
        &self,
        psi: &DMatrix<f64>,
        cols: &[usize],
    ) -> Result<Arc<LeastSquares>, RegressionError> {
        let lock = || self.map.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(ls) = lock().1.get(cols) {
            return Ok(Arc::clone(ls));
        }
        let ls = Arc::new(LeastSquares::new(&columns(psi, cols))?);
        let size = psi.nrows() * (2 * cols.len() + 1) + cols.len() * cols.len();
        let mut guard = lock();
        if guard.0 + size <= Self::BUDGET {
            guard.0 += size;
            guard.1.insert(cols.to_vec(), Arc::clone(&ls));
        }
        Ok(ls)
    }
}

/// Hybrid sparse regression: the `kind` path, then selection by corrected LOO. Serves the
/// tests ([`sparse_regression_on`] with the design prepared for this response alone).
#[cfg(test)]
pub(crate) fn sparse_regression(
    psi: &DMatrix<f64>,
    y: &[f64],
    constant: Option<usize>,
    kind: PathKind,
) -> Result<SparseFit, RegressionError> {
    let design = PathDesign::new(psi, constant);
    sparse_regression_on(&design, psi, y, kind, None)
}

/// Hybrid sparse regression on a prepared design (`design` must be that of `psi`): the
/// `kind` path, then selection by corrected LOO, with the refits shared through `cache` if
/// given: the same fit, bit for bit, for any number of responses on one design.
pub fn sparse_regression_on(
    design: &PathDesign,
    psi: &DMatrix<f64>,
    y: &[f64],
    kind: PathKind,
    cache: Option<&SupportCache>,
) -> Result<SparseFit, RegressionError> {
    if y.len() != psi.nrows() {
        return Err(RegressionError::Shape {
            rows: psi.nrows(),
            responses: y.len(),
        });
    }
    let path = match kind {
        PathKind::Lars => lars_path_on(design, y, usize::MAX),
    };
    select_by_loo_cached(psi, y, design.constant, &path, cache)
}

#[path = "lars_kernels.rs"]
mod kernels;

#[cfg(test)]
#[path = "lars_reference.rs"]
mod reference;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::uq::hd::regression::least_squares;
    use crate::uq::pce::askey::Family;
    use crate::uq::pce::basis::{Basis, MultiIndexSet};
    use crate::uq::rng::{standard_normal, stream, uniform_open01};
    use nalgebra::DVector;

    #[test]
    fn lars_on_an_orthonormal_design_enters_by_decreasing_correlation() {
        // For X^T X = I the LARS path is the soft-thresholding path: variables enter in
        // decreasing order of |X^T y|.
        let (n, m) = (40, 8);
        let mut r = stream(3, 0);
        let raw = DMatrix::from_fn(n, m, |_, _| standard_normal(&mut r));
        let q = raw.qr().q();
        let y: Vec<f64> = (0..n).map(|_| standard_normal(&mut r)).collect();
        let path = lars_path(&q, &y, None, usize::MAX);
        let c = q.transpose() * DVector::from_column_slice(&y);
        let mut order: Vec<usize> = (0..m).collect();
        order.sort_by(|&a, &b| c[b].abs().total_cmp(&c[a].abs()));
        assert_eq!(path.len(), m);
        for (k, set) in path.iter().enumerate() {
            let mut got = set.clone();
            got.sort_unstable();
            let mut want = order[..=k].to_vec();
            want.sort_unstable();
            assert_eq!(got, want, "step {k}");
        }
    }

    /// A sparse Legendre chaos in 10 dimensions, total degree 3 (286 terms), 5 active
    /// terms including the constant; N samples on scrambled Sobol' points.
    fn sparse_problem(n: usize) -> (DMatrix<f64>, Vec<f64>, Vec<(usize, f64)>) {
        let set = MultiIndexSet::total_degree(10, 3).unwrap();
        assert_eq!(set.len(), 286);
        let basis = Basis::new(vec![Family::Legendre; 10], set.clone()).unwrap();
        let pts = crate::uq::hd::sobol_seq::Sobol::scrambled(10, 5, 0)
            .unwrap()
            .points(0, n)
            .unwrap();
        let germ: Vec<Vec<f64>> = pts
            .iter()
            .map(|p| p.iter().map(|u| 2.0 * u - 1.0).collect())
            .collect();
        let psi = basis.design_matrix(&germ);
        let pos = |a: &[usize]| set.position(a).unwrap();
        let truth = vec![
            (0, 1.5),
            (pos(&[1, 0, 0, 0, 0, 0, 0, 0, 0, 0]), 2.0),
            (pos(&[0, 0, 2, 0, 0, 0, 0, 0, 0, 0]), -0.7),
            (pos(&[0, 1, 0, 0, 0, 0, 1, 0, 0, 0]), 1.3),
            (pos(&[0, 0, 0, 0, 1, 0, 0, 0, 0, 2]), 0.4),
        ];
        let y: Vec<f64> = (0..n)
            .map(|i| truth.iter().map(|&(k, c)| c * psi[(i, k)]).sum())
            .collect();
        (psi, y, truth)
    }

    #[test]
    fn hybrid_lars_recovers_an_exactly_sparse_chaos_from_fewer_samples_than_terms() {
        let (psi, y, truth) = sparse_problem(80);
        let fit = sparse_regression(&psi, &y, Some(0), PathKind::Lars).unwrap();
        let mut want: Vec<usize> = truth.iter().map(|t| t.0).collect();
        want.sort_unstable();
        assert_eq!(fit.columns, want);
        let full = fit.full_coefficients(psi.ncols());
        for &(k, c) in &truth {
            assert!((full[k] - c).abs() < 1e-10, "term {k}: {}", full[k]);
        }
        assert!(fit.fit.corrected_relative_loo() < 1e-20);
        // The full fit is refused: 80 samples for 286 terms.
        assert!(matches!(
            least_squares(&psi, &y),
            Err(RegressionError::Underdetermined { .. })
        ));
    }

    #[test]
    fn incremental_loo_errors_equal_full_refits() {
        let (psi, mut y, _) = sparse_problem(60);
        let mut r = stream(2, 2);
        for v in y.iter_mut() {
            *v += 0.1 * standard_normal(&mut r);
        }
        let order = [0, 5, 17, 3, 40, 100, 7, 250, 12];
        let inc = nested_loo_errors(&psi, &y, &order);
        for k in 1..=order.len() {
            let full = least_squares(&columns(&psi, &order[..k]), &y).unwrap();
            let want = full.corrected_relative_loo();
            assert!(
                (inc[k - 1] / want - 1.0).abs() < 1e-9,
                "{k}: {} vs {want}",
                inc[k - 1]
            );
        }
    }

    #[test]
    fn fused_gram_schmidt_loo_errors_equal_the_reference_bit_for_bit() {
        // Regression: the nested LOO errors decide the chosen model, so fusing the
        // Gram-Schmidt steps and keeping them in flat buffers must not change a bit, also
        // past a dependent column (a repeated one) and with more columns than samples.
        let (psi, mut y, _) = sparse_problem(60);
        let mut r = stream(4, 1);
        for v in y.iter_mut() {
            *v += 0.1 * standard_normal(&mut r);
        }
        let orders: [&[usize]; 4] = [
            &[0, 5, 17, 3, 40, 100, 7, 250, 12],
            &[0, 5, 17, 5, 40],
            &[3],
            &(0..70).map(|k| (k * 37) % 286).collect::<Vec<_>>(),
        ];
        for order in orders {
            let got = nested_loo_errors(&psi, &y, order);
            let want = reference::nested_loo_errors_reference(&psi, &y, order);
            let bits = |v: &[f64]| v.iter().map(|e| e.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&got), bits(&want), "{order:?}");
        }
    }

    #[test]
    fn a_design_prepared_once_gives_every_response_the_per_response_fit_bit_for_bit() {
        // Regression: a time-resolved sparse chaos re-standardised the design, transposed it
        // twice per step and refactored the chosen columns for every time column. The
        // prepared design and the shared refits must not change a bit: the paths equal those
        // of the per-response LARS kept in `reference`, and the fits those refitted alone.
        use crate::uq::hd::sobol_seq::Sobol;
        use crate::uq::special::norm_ppf;
        let pts: Vec<Vec<f64>> = Sobol::scrambled(2, 42, 0)
            .unwrap()
            .points(0, 60)
            .unwrap()
            .into_iter()
            .map(|p| p.iter().map(|&u| norm_ppf(u)).collect())
            .collect();
        // A damped oscillator's displacement over time (stiffness and damping from the
        // points): smooth early, oscillating late; plus an exact polynomial and a constant.
        let mut responses: Vec<Vec<f64>> = (0..40)
            .map(|i| {
                let t = 0.1 * i as f64;
                pts.iter()
                    .map(|p| {
                        let (k, c) = (100.0 + 10.0 * p[0], 20.0 + 2.0 * p[1]);
                        let w = (k / 10.0 - (c / 20.0).powi(2)).sqrt();
                        (-c * t / 20.0).exp() * (w * t).cos()
                    })
                    .collect()
            })
            .collect();
        responses.push(
            pts.iter()
                .map(|p| p[0] * p[1] - 0.5 * p[1].powi(3))
                .collect(),
        );
        responses.push(vec![1.5; pts.len()]);
        for degree in [3, 6, 9] {
            let set = MultiIndexSet::total_degree(2, degree).unwrap();
            let psi = Basis::new(vec![Family::Hermite; 2], set)
                .unwrap()
                .design_matrix(&pts);
            let design = PathDesign::new(&psi, Some(0));
            let cache = SupportCache::default();
            // Twice over: the second pass takes every refit from the cache.
            for pass in 0..2 {
                for (i, y) in responses.iter().enumerate() {
                    let want = reference::lars_path_reference(&psi, y, Some(0), usize::MAX);
                    assert_eq!(lars_path_on(&design, y, usize::MAX), want, "{degree} {i}");
                    if let Some(last) = want.last() {
                        let mut order = vec![0];
                        for set in &want {
                            let new: Vec<usize> =
                                set.iter().copied().filter(|j| !order.contains(j)).collect();
                            order.extend(new);
                        }
                        assert_eq!(order.len(), last.len() + 1);
                        let got = nested_loo_errors(&psi, y, &order);
                        let old = reference::nested_loo_errors_reference(&psi, y, &order);
                        let bits = |v: &[f64]| v.iter().map(|e| e.to_bits()).collect::<Vec<_>>();
                        assert_eq!(bits(&got), bits(&old), "degree {degree}, response {i}");
                    }
                    let alone = select_by_loo(&psi, y, Some(0), &want);
                    let shared =
                        sparse_regression_on(&design, &psi, y, PathKind::Lars, Some(&cache));
                    assert_eq!(shared, alone, "degree {degree}, response {i}, pass {pass}");
                }
            }
        }
    }

    #[test]
    fn gram_rows_in_vector_units_equal_nalgebra_dot_products_bit_for_bit() {
        // Regression: the Gram rows of a 20-input order-10 design (3 240 columns) were a
        // quarter of the analysis, summed by nalgebra one column at a time. The kernel must
        // give the same bits, with rows not a multiple of the block too.
        for n in [7, 60, 61, 203] {
            let (psi, _, _) = sparse_problem(n);
            let design = PathDesign::new(&psi, Some(0));
            for j in [0, 1, 17, 284] {
                let want: Vec<u64> = (0..design.x.ncols())
                    .map(|k| design.x.column(k).dot(&design.x.column(j)).to_bits())
                    .collect();
                let got: Vec<u64> = design.gram_row(j).iter().map(|v| v.to_bits()).collect();
                assert_eq!(got, want, "n = {n}, column {j}");
            }
        }
    }

    #[test]
    fn noisy_data_selects_a_small_model_with_honest_loo() {
        let (psi, mut y, _) = sparse_problem(120);
        let mut r = stream(8, 8);
        for v in y.iter_mut() {
            *v += 0.05 * (uniform_open01(&mut r) - 0.5);
        }
        let fit = sparse_regression(&psi, &y, Some(0), PathKind::Lars).unwrap();
        assert!(fit.columns.len() < 30, "{} terms", fit.columns.len());
        // Noise variance 0.05^2/12 ~ 2.1e-4 against Var(y) ~ 7: relative error ~ 3e-5.
        let e = fit.fit.corrected_relative_loo();
        assert!(e > 1e-6 && e < 1e-3, "{e}");
    }
}
