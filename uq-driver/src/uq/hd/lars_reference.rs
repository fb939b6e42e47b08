//! The LARS path as it was before the design was prepared once for every response
//!: standardisation, transposes and Gram entries recomputed for each response.
//! Kept for the tests, which pin the prepared path to it bit for bit; likewise the nested
//! leave-one-out errors as they were before the Gram-Schmidt steps were fused and kept in
//! flat buffers.

use nalgebra::{DMatrix, DVector};

use super::standardize;

/// Active columns of LARS with their entry signs and the Cholesky factor of the Gram
/// matrix of the signed columns `s_j x_j`, extended by one row per added column
/// (without the lasso modification the active correlations keep their signs).
#[derive(Default)]
struct ActiveSet {
    cols: Vec<usize>,
    signs: Vec<f64>,
    /// Lower-triangular rows.
    chol: Vec<Vec<f64>>,
}

impl ActiveSet {
    /// Adds column `j` of `x` with `sign`; false if it is (numerically) dependent.
    fn add(&mut self, x: &DMatrix<f64>, j: usize, sign: f64) -> bool {
        let xj = x.column(j);
        let g: Vec<f64> = self
            .cols
            .iter()
            .zip(&self.signs)
            .map(|(&k, &sk)| sk * sign * x.column(k).dot(&xj))
            .collect();
        let mut l = vec![0.0; g.len()];
        for i in 0..g.len() {
            let s: f64 = (0..i).map(|k| self.chol[i][k] * l[k]).sum();
            l[i] = (g[i] - s) / self.chol[i][i];
        }
        let d2 = xj.norm_squared() - l.iter().map(|v| v * v).sum::<f64>();
        if d2 <= 1e-12 {
            return false;
        }
        l.push(d2.sqrt());
        self.chol.push(l);
        self.cols.push(j);
        self.signs.push(sign);
        true
    }

    /// `G^-1 1` by two triangular solves.
    fn gram_solve_ones(&self) -> Vec<f64> {
        let k = self.cols.len();
        let l = &self.chol;
        let mut z = vec![0.0; k];
        for i in 0..k {
            let s: f64 = (0..i).map(|j| l[i][j] * z[j]).sum();
            z[i] = (1.0 - s) / l[i][i];
        }
        let mut w = vec![0.0; k];
        for i in (0..k).rev() {
            let s: f64 = (i + 1..k).map(|j| l[j][i] * w[j]).sum();
            w[i] = (z[i] - s) / l[i][i];
        }
        w
    }
}

/// The LARS sequence of active sets (design column indices, constant excluded).
pub fn lars_path_reference(
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
    let mut in_active = vec![false; m];
    let mut path: Vec<Vec<usize>> = Vec::new();
    let mut c = x.transpose() * &r;
    let first = (0..m).max_by(|&a, &b| c[a].abs().total_cmp(&c[b].abs()));
    let Some(first) = first else {
        return path;
    };
    if c[first].abs() <= 1e-14 * r.norm().max(f64::MIN_POSITIVE) {
        return path;
    }
    let mut act = ActiveSet::default();
    if !act.add(&x, first, c[first].signum()) {
        return path;
    }
    in_active[first] = true;
    while act.cols.len() <= limit {
        path.push(act.cols.iter().map(|&k| idx[k]).collect());
        if act.cols.len() == limit {
            break;
        }
        let big_c = act.cols.iter().map(|&k| c[k].abs()).fold(0.0, f64::max);
        if big_c <= 1e-13 * r.norm().max(1e-300) {
            break;
        }
        let gi1 = act.gram_solve_ones();
        let aa = 1.0 / gi1.iter().sum::<f64>().sqrt();
        let mut u = DVector::<f64>::zeros(n);
        for (i, &j) in act.cols.iter().enumerate() {
            u.axpy(aa * gi1[i] * act.signs[i], &x.column(j), 1.0);
        }
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
            Some(j) if act.add(&x, j, c[j].signum()) => {
                in_active[j] = true;
            }
            _ => break,
        }
    }
    path
}

/// The corrected relative LOO errors of the nested fits on the prefixes of `order`, one
/// vector per orthonormal column.
pub fn nested_loo_errors_reference(psi: &DMatrix<f64>, y: &[f64], order: &[usize]) -> Vec<f64> {
    let n = psi.nrows();
    let var = crate::uq::hd::regression::sample_variance(y);
    let negligible = crate::uq::hd::regression::negligible_variance(y);
    let mut qs: Vec<DVector<f64>> = Vec::new();
    let mut rinv: Vec<Vec<f64>> = Vec::new(); // columns of R^-1 (upper triangular)
    let mut rcols: Vec<Vec<f64>> = Vec::new(); // columns of R
    let mut tr = 0.0;
    let mut res = DVector::from_column_slice(y);
    let mut lev = vec![0.0; n];
    let yv = DVector::from_column_slice(y);
    let mut out = Vec::with_capacity(order.len());
    for (k, &col) in order.iter().enumerate() {
        let mut v = psi.column(col).into_owned();
        let norm0 = v.norm();
        let mut r = vec![0.0; k + 1];
        for _ in 0..2 {
            for (j, q) in qs.iter().enumerate() {
                let d = q.dot(&v);
                r[j] += d;
                v.axpy(-d, q, 1.0);
            }
        }
        let rkk = v.norm();
        if rkk.is_nan() || rkk <= 1e-10 * norm0.max(f64::MIN_POSITIVE) {
            out.resize(order.len(), f64::INFINITY);
            return out;
        }
        r[k] = rkk;
        let q = v / rkk;
        // New column of R^-1: t_i = -(sum_j Rinv[i][j] r_j) / rkk, t_k = 1 / rkk.
        let mut t = vec![0.0; k + 1];
        for (i, ti) in t.iter_mut().enumerate().take(k) {
            let s: f64 = (i..k).map(|j| rinv[j][i] * r[j]).sum();
            *ti = -s / rkk;
        }
        t[k] = 1.0 / rkk;
        tr += t.iter().map(|x| x * x).sum::<f64>();
        rinv.push(t);
        rcols.push(r);
        let qy = q.dot(&yv);
        res.axpy(-qy, &q, 1.0);
        for (h, qi) in lev.iter_mut().zip(q.iter()) {
            *h += qi * qi;
        }
        qs.push(q);
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
            crate::uq::hd::regression::relative(t * loo, var, negligible)
        } else {
            f64::INFINITY
        };
        out.push(err);
    }
    out
}
