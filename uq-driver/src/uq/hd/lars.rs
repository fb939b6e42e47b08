//! Sparse regression: least-angle regression (Efron, Hastie, Johnstone & Tibshirani,
//! Ann. Stat. 32, 2004) and orthogonal matching pursuit, with the basis chosen by the
//! corrected leave-one-out error ("hybrid LARS", Blatman & Sudret, J. Comput. Phys. 230,
//! 2011).
//!
//! The path algorithms return the nested sequence of active sets `A_1 ⊂ A_2 ⊂ ...` (column
//! indices of the design). [`select_by_loo`] refits each by ordinary least squares
//! (see [`super::regression`]) — with the constant column always included when one is
//! given — and keeps the set of smallest corrected relative LOO error.
//!
//! The paths work on the non-constant columns, centred and scaled to unit norm, and on
//! the centred response (the constant plays the intercept). They stop when every column
//! is active, when `N - 2` columns are active (the refit needs `N > P`), when the
//! remaining correlation vanishes, or when the active Gram matrix becomes singular.

use nalgebra::{DMatrix, DVector};

use super::regression::{columns, least_squares, LeastSquaresFit, RegressionError};

/// Path algorithm.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PathKind {
    /// Least-angle regression.
    Lars,
    /// Orthogonal matching pursuit.
    Omp,
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
    /// Coefficients scattered to a full vector of `ncols` entries (zeros elsewhere).
    pub fn full_coefficients(&self, ncols: usize) -> Vec<f64> {
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

/// The LARS sequence of active sets (design column indices, constant excluded).
pub fn lars_path(
    psi: &DMatrix<f64>,
    y: &[f64],
    constant: Option<usize>,
    max_active: usize,
) -> Vec<Vec<usize>> {
    let (x, idx) = standardize(psi, constant);
    let (n, m) = x.shape();
    let ym = if constant.is_some() {
        y.iter().sum::<f64>() / n as f64
    } else {
        0.0
    };
    let mut r = DVector::from_iterator(n, y.iter().map(|v| v - ym));
    let limit = max_active.min(m).min(n.saturating_sub(2));
    let mut active: Vec<usize> = Vec::new();
    let mut in_active = vec![false; m];
    let mut path = Vec::new();
    let mut c = x.transpose() * &r;
    let first = (0..m).max_by(|&a, &b| c[a].abs().total_cmp(&c[b].abs()));
    let Some(first) = first else {
        return path;
    };
    if c[first].abs() <= 1e-14 * r.norm().max(f64::MIN_POSITIVE) {
        return path;
    }
    active.push(first);
    in_active[first] = true;
    while active.len() <= limit {
        path.push(active.iter().map(|&k| idx[k]).collect());
        if active.len() == limit {
            break;
        }
        let big_c = active.iter().map(|&k| c[k].abs()).fold(0.0, f64::max);
        if big_c <= 1e-13 * r.norm().max(1e-300) {
            break;
        }
        let s: Vec<f64> = active.iter().map(|&k| c[k].signum()).collect();
        let xa = DMatrix::from_fn(n, active.len(), |i, j| x[(i, active[j])] * s[j]);
        let g = xa.transpose() * &xa;
        let Some(chol) = g.cholesky() else {
            break;
        };
        let ones = DVector::from_element(active.len(), 1.0);
        let gi1 = chol.solve(&ones);
        let aa = 1.0 / ones.dot(&gi1).sqrt();
        let w = gi1 * aa;
        let u = &xa * &w;
        let a = x.transpose() * &u;
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
        r -= &u * gamma;
        c = x.transpose() * &r;
        match next {
            Some(j) => {
                active.push(j);
                in_active[j] = true;
            }
            None => break,
        }
    }
    path
}

/// The orthogonal matching pursuit sequence of active sets (constant excluded).
pub fn omp_path(
    psi: &DMatrix<f64>,
    y: &[f64],
    constant: Option<usize>,
    max_active: usize,
) -> Vec<Vec<usize>> {
    let (x, idx) = standardize(psi, constant);
    let (n, m) = x.shape();
    let ym = if constant.is_some() {
        y.iter().sum::<f64>() / n as f64
    } else {
        0.0
    };
    let yc = DVector::from_iterator(n, y.iter().map(|v| v - ym));
    let limit = max_active.min(m).min(n.saturating_sub(2));
    let mut r = yc.clone();
    let mut active: Vec<usize> = Vec::new();
    let mut in_active = vec![false; m];
    let mut path = Vec::new();
    while active.len() < limit {
        let c = x.transpose() * &r;
        let best = (0..m)
            .filter(|&j| !in_active[j])
            .max_by(|&a, &b| c[a].abs().total_cmp(&c[b].abs()));
        let Some(j) = best else { break };
        if c[j].abs() <= 1e-13 * yc.norm().max(1e-300) {
            break;
        }
        active.push(j);
        in_active[j] = true;
        let xa = DMatrix::from_fn(n, active.len(), |i, k| x[(i, active[k])]);
        let qr = xa.clone().qr();
        let rr = qr.r();
        if (0..active.len()).any(|k| rr[(k, k)].abs() < 1e-12) {
            break;
        }
        let coef = rr
            .solve_upper_triangular(&(qr.q().transpose() * &yc))
            .expect("checked diagonal");
        r = &yc - &xa * coef;
        path.push(active.iter().map(|&k| idx[k]).collect());
    }
    path
}

/// Refits each active set of `path` (plus the constant column, if any) by least squares
/// and keeps the smallest corrected relative LOO error. The empty model (constant only)
/// is a candidate when a constant is given.
pub fn select_by_loo(
    psi: &DMatrix<f64>,
    y: &[f64],
    constant: Option<usize>,
    path: &[Vec<usize>],
) -> Result<SparseFit, RegressionError> {
    let mut candidates: Vec<Vec<usize>> = Vec::new();
    if let Some(c0) = constant {
        candidates.push(vec![c0]);
    }
    for set in path {
        let mut cols: Vec<usize> = constant.into_iter().collect();
        let mut rest = set.clone();
        rest.sort_unstable();
        cols.extend(rest);
        candidates.push(cols);
    }
    let mut best: Option<SparseFit> = None;
    let mut errors = Vec::with_capacity(candidates.len());
    for cols in candidates {
        let fit = match least_squares(&columns(psi, &cols), y) {
            Ok(f) => f,
            Err(RegressionError::RankDeficient { .. }) => {
                errors.push(f64::INFINITY);
                continue;
            }
            Err(e) => return Err(e),
        };
        let e = fit.corrected_relative_loo();
        errors.push(e);
        let better = match &best {
            None => true,
            Some(b) => e < b.fit.corrected_relative_loo(),
        };
        if better {
            best = Some(SparseFit {
                columns: cols,
                fit,
                path_errors: vec![],
            });
        }
    }
    let mut best = best.ok_or(RegressionError::Underdetermined {
        samples: psi.nrows(),
        terms: psi.ncols(),
    })?;
    best.path_errors = errors;
    Ok(best)
}

/// Hybrid sparse regression: the `kind` path, then selection by corrected LOO.
pub fn sparse_regression(
    psi: &DMatrix<f64>,
    y: &[f64],
    constant: Option<usize>,
    kind: PathKind,
) -> Result<SparseFit, RegressionError> {
    if y.len() != psi.nrows() {
        return Err(RegressionError::Shape {
            rows: psi.nrows(),
            responses: y.len(),
        });
    }
    let path = match kind {
        PathKind::Lars => lars_path(psi, y, constant, usize::MAX),
        PathKind::Omp => omp_path(psi, y, constant, usize::MAX),
    };
    select_by_loo(psi, y, constant, &path)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::uq::hd::askey::Family;
    use crate::uq::hd::basis::{Basis, MultiIndexSet};
    use crate::uq::rng::{standard_normal, stream, uniform_open01};

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
        for kind in [PathKind::Lars, PathKind::Omp] {
            let fit = sparse_regression(&psi, &y, Some(0), kind).unwrap();
            let mut want: Vec<usize> = truth.iter().map(|t| t.0).collect();
            want.sort_unstable();
            assert_eq!(fit.columns, want, "{kind:?}");
            let full = fit.full_coefficients(psi.ncols());
            for &(k, c) in &truth {
                assert!(
                    (full[k] - c).abs() < 1e-10,
                    "{kind:?}: term {k}: {}",
                    full[k]
                );
            }
            assert!(fit.fit.corrected_relative_loo() < 1e-20);
        }
        // The full fit is refused: 80 samples for 286 terms.
        assert!(matches!(
            least_squares(&psi, &y),
            Err(RegressionError::Underdetermined { .. })
        ));
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
