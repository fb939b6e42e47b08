//! Functional outputs: a chaos method fits a series on the principal components
//! (Karhunen–Loève modes) of its centred runs instead of column by column (a design without
//! quadrature weights: a regression chaos).
//!
//! The runs `Y` (n runs × T columns) are centred column by column, `Yc = Y − 1 μᵀ`, and each
//! column is scaled to unit variance (`W`; a column whose Std is at most 1e-3 of the largest
//! as if at that level), so that a column of small variance, such as the start of a
//! response, is represented as well as the large ones. The scaled runs are decomposed
//! `Yc W = Σ_k z_k φ_kᵀ`: scores `z_k` over the runs (`‖z_k‖² = λ_k`), orthonormal modes
//! `φ_k` over time. Enough leading modes are kept to hold the share `retained_variance` of
//! the scaled variance `Σ_k λ_k`, and at least `1 − max(1 − retained_variance, 1e-3)` of
//! every resolved column's own ([`COLUMN_DISCARD`]). The method fits one chaos per score
//! column, and column t's chaos is `μ_t + Σ_k w_t⁻¹ φ_k(t) z_k(ξ)`: the coefficients on the
//! union of the modes' bases, so the mean, Std, Sobol' indices and draws of every column
//! come from the per-column code. Column t's truncation-error estimate is the share of its
//! variance the modes miss, added to the modes' own estimates weighted by their variance in
//! the column.
//!
//! The decomposition takes the smaller of two symmetric matrices: the Gram matrix
//! `Yc W² Ycᵀ` (n × n) when n ≤ T, accumulated over the analysis's blocks of columns, or
//! the covariance `W Ycᵀ Yc W` (T × T) when the series is one block. Sums over columns run
//! over chunks of [`BLOCK_ALIGN`] columns in order, on one thread: the numbers depend
//! neither on the thread count nor on the block width.
//!
//! The column-by-column fit fits identical columns (bit for bit over the runs) once
//! ([`estimate_distinct`]).

use std::collections::HashMap;
use std::hash::{Hash, Hasher};

use nalgebra::{DMatrix, SymmetricEigen};

use super::blocks::{self, BLOCK_ALIGN};
use super::runs::Runs;
use super::{output_error, AnalysisError};
use crate::results::FunctionalFit;
use crate::uq::method::{
    ChaosError, Design, Estimate, InvalidSettings, MethodError, Sampling, Sobol, SobolIntervals,
};
use crate::uq::pce::Pce;

/// The principal components of a series' centred runs kept by a truncation.
#[derive(Debug)]
pub(super) struct Modes {
    /// Column means (T).
    pub mean: Vec<f64>,
    /// Scores over the runs (n × m): column k is `z_k`, `‖z_k‖² = λ_k`.
    pub scores: DMatrix<f64>,
    /// The modes over the columns in the series' units (T × m): `Yc ≈ scores modesᵀ`
    /// (orthonormal modes of the scaled columns, each row times its column's scale).
    pub modes: DMatrix<f64>,
    /// `λ_k = ‖z_k‖²` of the kept modes, descending.
    pub eigenvalues: Vec<f64>,
    /// Per column, the sum of its squared centred values (`(n − 1)` times its variance).
    pub sq: Vec<f64>,
    /// Distinct columns (bit for bit).
    pub distinct: usize,
    /// A hash of every column's values (as [`column_hash`]).
    pub hashes: Vec<u64>,
}

impl Modes {
    /// Per column, the part of [`Modes::sq`] the kept modes miss: `‖Yc_t‖² − Σ_k λ_k φ_k(t)²`
    /// (at least 0).
    pub fn discarded(&self) -> Vec<f64> {
        (0..self.sq.len())
            .map(|t| {
                let kept: f64 = (0..self.eigenvalues.len())
                    .map(|k| self.eigenvalues[k] * self.modes[(t, k)].powi(2))
                    .sum();
                (self.sq[t] - kept).max(0.0)
            })
            .collect()
    }

    /// The share of the total variance the kept modes miss.
    pub fn discarded_share(&self) -> f64 {
        let total: f64 = self.sq.iter().sum();
        if total > 0.0 {
            (self.discarded().iter().sum::<f64>() / total).clamp(0.0, 1.0)
        } else {
            0.0
        }
    }
}

/// A hash of a column's values, bit for bit (equal columns, equal hashes).
pub(super) fn column_hash(values: &[f64]) -> u64 {
    // SipHash with fixed keys: the same value on every run of the program.
    #[allow(deprecated)]
    let mut h = std::hash::SipHasher::new();
    for v in values {
        v.to_bits().hash(&mut h);
    }
    h.finish()
}

/// The block centred column by column, with the column means, the sums of squares of the
/// centred values and the hashes of the (uncentred) columns.
fn centre(mut b: DMatrix<f64>) -> (DMatrix<f64>, Vec<f64>, Vec<f64>, Vec<u64>) {
    let n = b.nrows();
    let (mut mean, mut sq, mut hashes) = (Vec::new(), Vec::new(), Vec::new());
    for mut c in b.column_iter_mut() {
        hashes.push(column_hash(c.as_slice()));
        let m = c.iter().sum::<f64>() / n.max(1) as f64;
        c.add_scalar_mut(-m);
        mean.push(m);
        sq.push(c.norm_squared());
    }
    (b, mean, sq, hashes)
}

/// How many of the eigenvalues `lambda` (descending) keep the share `retained` of `total`
/// (the sum of all): the fewest whose sum reaches it, never one at the rounding level of
/// the largest (so `retained = 1` keeps the numerical rank). 0 when `total` is 0.
pub(super) fn kept_modes(lambda: &[f64], total: f64, retained: f64) -> usize {
    let largest = lambda.first().copied().unwrap_or(0.0);
    if !(total > 0.0 && largest > 0.0) {
        return 0;
    }
    let floor = largest * lambda.len() as f64 * f64::EPSILON * 16.0;
    let mut sum = 0.0;
    for (k, &l) in lambda.iter().enumerate() {
        if l <= floor {
            return k;
        }
        sum += l;
        if sum >= retained * total {
            return k + 1;
        }
    }
    lambda.len()
}

/// The eigenvalues (descending, ties by index) and eigenvectors of a symmetric matrix.
fn eigen_descending(g: DMatrix<f64>) -> (Vec<f64>, DMatrix<f64>) {
    let e = SymmetricEigen::new(g);
    let mut order: Vec<usize> = (0..e.eigenvalues.len()).collect();
    order.sort_by(|&a, &b| {
        e.eigenvalues[b]
            .total_cmp(&e.eigenvalues[a])
            .then(a.cmp(&b))
    });
    let values = order.iter().map(|&k| e.eigenvalues[k]).collect();
    (values, e.eigenvectors.select_columns(&order))
}

/// The largest share of a column's own variance the kept modes may miss, whatever
/// `retained_variance` allows (where that allows less, its own share): a column of small
/// variance beside large ones (the start of a response) keeps its Std within 0.05 %.
pub(super) const COLUMN_DISCARD: f64 = 1e-3;

/// A column whose Std is at most this fraction of the largest is not held to
/// [`COLUMN_DISCARD`] (as the truncation-error warnings leave such columns out), and is
/// scaled as if its Std were at this level.
const RESOLVED_STD: f64 = 1e-3;

/// The sum of squares of a scaled column above which it is held to [`COLUMN_DISCARD`]: the
/// resolved columns have 1 (to rounding), the others less.
const RESOLVED_SQ: f64 = 1.0 - 1e-9;

/// The fewest leading modes that keep the share `1 − cap` of the variance of every column of
/// `q` (rows: columns of the series; `q[(t, k)]² = λ_k φ_k(t)²`) whose sum of squares
/// `sq[t]` is above `floor`.
fn column_modes(q: &DMatrix<f64>, sq: &[f64], floor: f64, cap: f64) -> usize {
    let mut need = 0;
    for (t, &s) in sq.iter().enumerate() {
        if s <= floor {
            continue;
        }
        let mut left = s;
        let mut k = 0;
        while k < q.ncols() && left > cap * s {
            left -= q[(t, k)].powi(2);
            k += 1;
        }
        need = need.max(k);
    }
    need
}

/// The principal components of a series of `nt` columns over `n` runs, read in blocks of
/// `width` columns by `read(j0, w)`, truncated to keep the share `retained` of its variance
/// and of each column's (at least `1 − COLUMN_DISCARD` of a column's: [`COLUMN_DISCARD`]);
/// `None` when nothing is to be kept (no variance) or the covariance route would need more
/// than one block (more runs than columns, and the series does not fit one block).
pub(super) fn decompose<E>(
    n: usize,
    nt: usize,
    width: usize,
    retained: f64,
    read: &mut dyn FnMut(usize, usize) -> Result<DMatrix<f64>, E>,
) -> Result<Option<Modes>, E> {
    let width = width.max(1);
    let single = width >= nt;
    let gram = n <= nt;
    if !gram && !single {
        return Ok(None);
    }
    // The column means, sums of squares and hashes; the series kept if it is one block.
    let (mut mean, mut sq, mut hashes) = (Vec::new(), Vec::new(), Vec::new());
    let mut kept_block = None;
    for (j0, w) in blocks::blocks(nt, width) {
        let (bc, m, s, h) = centre(read(j0, w)?);
        mean.extend(m);
        sq.extend(s);
        hashes.extend(h);
        if single {
            kept_block = Some(bc);
        }
    }
    // Every column scaled to unit variance, those at or below RESOLVED_STD of the largest
    // Std as if at that level.
    let largest = sq.iter().copied().fold(0.0, f64::max);
    let floor = RESOLVED_STD * RESOLVED_STD * largest;
    let scale: Vec<f64> = sq.iter().map(|&s| s.max(floor).sqrt()).collect();
    let wsq: Vec<f64> = sq
        .iter()
        .zip(&scale)
        .map(|(&s, &c)| if c > 0.0 { s / (c * c) } else { 0.0 })
        .collect();
    let mut block_of = |j0: usize, w: usize| -> Result<DMatrix<f64>, E> {
        let mut b = match &kept_block {
            Some(b) => b.columns(j0, w).into_owned(),
            None => centre(read(j0, w)?).0,
        };
        for (k, mut c) in b.column_iter_mut().enumerate() {
            let f = scale[j0 + k];
            c.scale_mut(if f > 0.0 { f.recip() } else { 0.0 });
        }
        Ok(b)
    };
    let (lambda, vectors) = if gram {
        let mut g = DMatrix::<f64>::zeros(n, n);
        for (j0, w) in blocks::blocks(nt, width) {
            let b = block_of(j0, w)?;
            for (c0, cw) in blocks::blocks(w, BLOCK_ALIGN) {
                let chunk = b.columns(c0, cw);
                g.gemm(1.0, &chunk, &chunk.transpose(), 1.0);
            }
        }
        eigen_descending(g)
    } else {
        let b = block_of(0, nt)?;
        eigen_descending(b.tr_mul(&b))
    };
    let total: f64 = wsq.iter().sum();
    let m0 = kept_modes(&lambda, total, 1.0);
    let mut m = kept_modes(&lambda, total, retained);
    if m == 0 {
        return Ok(None);
    }
    let cap = (1.0 - retained).max(COLUMN_DISCARD);
    let scale_by = |q: &mut DMatrix<f64>, f: &dyn Fn(f64) -> f64| {
        for (k, &l) in lambda.iter().take(q.ncols()).enumerate() {
            q.column_mut(k).scale_mut(f(l));
        }
    };
    // Yc W = U S Vᵀ (Gram: U, the eigenvectors) or W Ycᵀ Yc W = V Λ Vᵀ (covariance: V).
    if gram {
        // q = W Ycᵀ U, q_tk = s_k φ_k(t), over the modes above the rounding level.
        let u = vectors.columns(0, m0);
        for (j0, w) in blocks::blocks(nt, width) {
            let q = block_of(j0, w)?.tr_mul(&u);
            m = m.max(column_modes(&q, &wsq[j0..j0 + w], RESOLVED_SQ, cap));
        }
    } else {
        let mut q = vectors.columns(0, m0).into_owned();
        scale_by(&mut q, &|l| l.max(0.0).sqrt());
        m = m.max(column_modes(&q, &wsq, RESOLVED_SQ, cap));
    }
    let v = vectors.columns(0, m).into_owned();
    let (scores, mut modes) = if gram {
        // Scores U S, modes W Ycᵀ U S⁻¹, a block of columns at a time.
        let mut scores = v.clone();
        scale_by(&mut scores, &|l| l.sqrt());
        let mut modes = DMatrix::<f64>::zeros(nt, m);
        for (j0, w) in blocks::blocks(nt, width) {
            let mut part = block_of(j0, w)?.tr_mul(&v);
            scale_by(&mut part, &|l| l.sqrt().recip());
            modes.rows_mut(j0, w).copy_from(&part);
        }
        (scores, modes)
    } else {
        // Modes V, scores Yc W V.
        let b = block_of(0, nt)?;
        (&b * &v, v)
    };
    // In the series' own units: Yc_t ≈ Σ_k scale_t φ_k(t) z_k.
    for (t, mut row) in modes.row_iter_mut().enumerate() {
        row.scale_mut(scale[t]);
    }
    let distinct = {
        let mut h = hashes.clone();
        h.sort_unstable();
        h.dedup();
        h.len()
    };
    Ok(Some(Modes {
        mean,
        scores,
        modes,
        eigenvalues: lambda[..m].to_vec(),
        sq,
        distinct,
        hashes,
    }))
}

/// The estimate of every column from the estimate of the modes' scores: each column's chaos
/// `μ_t + Σ_k φ_k(t) z_k`, its moments and Sobol' indices, and its truncation error (where
/// the method estimates the modes'): `(Σ_k φ_k(t)² e_k λ_k + d_t) / ‖Yc_t‖²`, the modes'
/// relative errors `e_k` weighted by their variance in the column, plus the part `d_t` the
/// modes miss.
pub(super) fn combine(of_modes: Estimate, modes: &Modes) -> Result<Estimate, MethodError> {
    let no_chaos = || MethodError::Invalid(InvalidSettings("the modes' fit has no chaos".into()));
    let pce = with_constant(of_modes.chaos.ok_or_else(no_chaos)?)?;
    let dim = pce.dim();
    let c0 = pce.set().position(&vec![0; dim]).ok_or_else(no_chaos)?;
    let mut coeffs = &pce.coeffs * modes.modes.transpose();
    for (t, m) in modes.mean.iter().enumerate() {
        coeffs[(c0, t)] += m;
    }
    let mut estimate = Estimate::from_chaos(Pce::new(pce.basis, coeffs)?);
    let discarded = modes.discarded();
    // Each column's error: its modes' errors weighted by their share of it, plus the variance
    // the kept modes miss, relative to the column's variance.
    let per_column = |of_mode: &[f64]| -> Vec<f64> {
        (0..modes.sq.len())
            .map(|t| {
                if modes.sq[t] <= 0.0 {
                    return 0.0;
                }
                let fitted: f64 = (0..modes.eigenvalues.len())
                    .map(|k| modes.modes[(t, k)].powi(2) * of_mode[k] * modes.eigenvalues[k])
                    .sum();
                (fitted + discarded[t]) / modes.sq[t]
            })
            .collect()
    };
    estimate.chaos_error = of_modes.chaos_error.map(|e| ChaosError {
        kind: e.kind,
        values: per_column(&e.values),
        check: e.check.as_deref().map(per_column),
    });
    Ok(estimate)
}

/// `pce` on a basis that holds the constant term (added with zero coefficients if missing).
fn with_constant(pce: Pce) -> Result<Pce, MethodError> {
    let zero = vec![0; pce.dim()];
    if pce.set().position(&zero).is_some() {
        return Ok(pce);
    }
    let indices = pce.set().indices().to_vec();
    let mut columns: Vec<(Vec<Vec<usize>>, Vec<f64>)> = pce
        .coeffs
        .column_iter()
        .map(|c| (indices.clone(), c.iter().copied().collect()))
        .collect();
    let m = columns.len();
    columns.push((vec![zero], vec![0.0]));
    let joined = Pce::from_columns(pce.basis.families().to_vec(), &columns)?;
    Ok(Pce::new(
        joined.basis,
        joined.coeffs.columns(0, m).into_owned(),
    )?)
}

/// The estimate of an output fitted on its principal components (see the module
/// documentation), with what summary.json says of the fit and the hash of every column;
/// `None` where a column-by-column fit is to be used instead: nothing to decompose (see
/// [`decompose`]), or as many modes as distinct columns (fitting those costs no more).
pub(super) fn pca_estimate(
    method: &dyn Sampling,
    design: &Design,
    runs: &Runs,
    (o, name, nt): (usize, &str, usize),
    retained: f64,
) -> Result<Option<(Estimate, FunctionalFit, Vec<u64>)>, AnalysisError> {
    let n = runs.rows.len();
    let width = blocks::block_width(nt, n);
    // A quadrature (a sparse grid) projects every column at the cost of a matrix product,
    // and its weights, some of them negative, bound neither what a discarded component takes
    // from its moments nor how the components' errors add up: its columns are fitted as
    // they are.
    if design.weights.is_some() {
        return Ok(None);
    }
    let read = &mut |j0, w| runs.block(o, nt, j0, w);
    let Some(modes) = decompose(n, nt, width, retained, read)? else {
        return Ok(None);
    };
    let m = modes.eigenvalues.len();
    if m >= modes.distinct {
        return Ok(None);
    }
    let fail = output_error(name);
    let of_modes = method
        .estimate(design, &runs.rows, &modes.scores)
        .map_err(fail)?;
    let estimate = combine(of_modes, &modes).map_err(fail)?;
    let discarded = modes.discarded();
    let largest = modes.sq.iter().copied().fold(0.0, f64::max);
    // The worst column among those whose Std is above 1e-3 of the largest (below, the
    // share of a rounding-level variance says nothing).
    let worst = (0..nt)
        .filter(|&t| modes.sq[t] > 1e-6 * largest)
        .map(|t| discarded[t] / modes.sq[t])
        .fold(0.0, f64::max);
    let fit = FunctionalFit {
        method: "pca".into(),
        modes: Some(m),
        fits: m,
        retained_variance: Some(retained),
        discarded_variance: Some(modes.discarded_share()),
        discarded_max: Some(worst.min(1.0)),
    };
    Ok(Some((estimate, fit, modes.hashes)))
}

/// For every column of `data`, the index of the first column equal to it bit for bit
/// (itself when it is the first), with the hash of every column.
pub(super) fn first_equal(data: &DMatrix<f64>) -> (Vec<usize>, Vec<u64>) {
    let hashes: Vec<u64> = data
        .column_iter()
        .map(|c| column_hash(c.as_slice()))
        .collect();
    let mut seen: HashMap<u64, Vec<usize>> = HashMap::new();
    let mut first = Vec::with_capacity(hashes.len());
    for (k, &h) in hashes.iter().enumerate() {
        let same = |&j: &usize| {
            data.column(j)
                .iter()
                .zip(data.column(k).iter())
                .all(|(a, b)| a.to_bits() == b.to_bits())
        };
        let found = seen.get(&h).and_then(|c| c.iter().copied().find(same));
        match found {
            Some(j) => first.push(j),
            None => {
                seen.entry(h).or_default().push(k);
                first.push(k);
            }
        }
    }
    (first, hashes)
}

/// The method's estimate of every column of `data`, identical columns fitted once; with the
/// number of columns fitted and the hash of every column.
pub(super) fn estimate_distinct(
    method: &dyn Sampling,
    design: &Design,
    rows: &[usize],
    data: &DMatrix<f64>,
) -> Result<(Estimate, usize, Vec<u64>), MethodError> {
    let (first, hashes) = first_equal(data);
    let distinct: Vec<usize> = (0..first.len()).filter(|&k| first[k] == k).collect();
    if distinct.len() == data.ncols() {
        return Ok((method.estimate(design, rows, data)?, distinct.len(), hashes));
    }
    let estimate = method.estimate(design, rows, &data.select_columns(&distinct))?;
    // Column k is the fitted column at the place of its first equal.
    let mut place = vec![0; first.len()];
    for (i, &k) in distinct.iter().enumerate() {
        place[k] = i;
    }
    let of: Vec<usize> = first.iter().map(|&j| place[j]).collect();
    Ok((select(&estimate, &of), distinct.len(), hashes))
}

/// The estimate of the columns `of` of `e` (in that order, repeats allowed).
pub(super) fn select(e: &Estimate, of: &[usize]) -> Estimate {
    fn pick<T: Clone>(v: &[T], of: &[usize]) -> Vec<T> {
        of.iter().map(|&k| v[k].clone()).collect()
    }
    Estimate {
        mean: pick(&e.mean, of),
        std: pick(&e.std, of),
        std_error_mean: e.std_error_mean.as_ref().map(|v| pick(v, of)),
        std_chaos: e.std_chaos.as_ref().map(|v| pick(v, of)),
        chaos: e.chaos.as_ref().map(|p| Pce {
            basis: p.basis.clone(),
            coeffs: p.coeffs.select_columns(of),
        }),
        sobol: e.sobol.as_ref().map(|s| Sobol {
            first: pick(&s.first, of),
            total: pick(&s.total, of),
            intervals: s.intervals.as_ref().map(|i| SobolIntervals {
                level: i.level,
                first: pick(&i.first, of),
                total: pick(&i.total, of),
            }),
            given_data: s.given_data,
        }),
        draws: e.draws,
        chaos_error: e.chaos_error.as_ref().map(|c| ChaosError {
            kind: c.kind,
            values: pick(&c.values, of),
            check: c.check.as_ref().map(|v| pick(v, of)),
        }),
    }
}

#[cfg(test)]
mod tests {
    use std::sync::atomic::{AtomicUsize, Ordering};

    use super::*;
    use crate::uq::method::pce_regression::PceRegression;
    use crate::uq::method::{Evaluation, Method, MethodSummary, Problem, RunResults};
    use crate::uq::random_inputs::RandomInputs;
    use crate::uq::{Distribution, RandomParameter};

    /// A series of `n` runs × `nt` columns of rank 3 (three fixed shapes over time times
    /// functions of the runs), plus a column mean; `x` gives the runs' inputs.
    fn rank_three(x: &[Vec<f64>], nt: usize) -> DMatrix<f64> {
        DMatrix::from_fn(x.len(), nt, |i, t| {
            let s = t as f64 / nt as f64;
            let (a, b) = (x[i][0], x[i][1]);
            10.0 + s
                + (a + 0.5 * b) * (6.0 * s).sin()
                + a * b * (1.0 + s * s)
                + (b * b - 1.0) * (3.0 * s).cos() * 0.3
        })
    }

    fn points(n: usize) -> Vec<Vec<f64>> {
        (0..n)
            .map(|i| {
                let u = (i as f64 + 0.5) / n as f64;
                vec![
                    2.0 * u - 1.0,
                    ((i * 7919) % n) as f64 / n as f64 * 2.0 - 1.0,
                ]
            })
            .collect()
    }

    fn decomposed(y: &DMatrix<f64>, width: usize, retained: f64) -> Modes {
        let (n, nt) = y.shape();
        decompose::<()>(n, nt, width, retained, &mut |j0, w| {
            Ok(y.columns(j0, w).into_owned())
        })
        .unwrap()
        .unwrap()
    }

    #[test]
    fn kept_modes_reach_the_retained_share_and_stop_at_rounding() {
        let l = [4.0, 2.0, 1.0, 1e-20];
        assert_eq!(kept_modes(&l, 7.0, 1.0), 3);
        assert_eq!(kept_modes(&l, 7.0, 0.8), 2);
        assert_eq!(kept_modes(&l, 7.0, 0.5), 1);
        assert_eq!(kept_modes(&[0.0, 0.0], 0.0, 1.0), 0);
    }

    /// A series of rank 3 keeps 3 modes, discards nothing, and its scores times its modes
    /// give back the centred runs; the same numbers bit for bit in blocks of 32 columns.
    #[test]
    fn pca_of_a_rank_three_series_keeps_three_modes_and_discards_nothing() {
        // More columns than runs (the Gram route), then more runs than columns (covariance).
        for (n, nt) in [(40, 301), (150, 60)] {
            let y = rank_three(&points(n), nt);
            let m = decomposed(&y, nt, 1.0 - 1e-6);
            assert_eq!(m.eigenvalues.len(), 3, "{n} × {nt}");
            assert!(m.discarded_share() < 1e-12, "{}", m.discarded_share());
            let mut centred = y.clone();
            for (t, mut c) in centred.column_iter_mut().enumerate() {
                c.add_scalar_mut(-m.mean[t]);
            }
            let back = &m.scores * m.modes.transpose();
            let err = (&back - &centred).abs().max();
            assert!(err < 1e-10 * centred.abs().max(), "{n} × {nt}: {err}");
            assert_eq!(m.distinct, nt);
            if n <= nt {
                let blocked = decomposed(&y, 32, 1.0 - 1e-6);
                assert_eq!(blocked.scores, m.scores);
                assert_eq!(blocked.modes, m.modes);
            }
        }
    }

    /// A method that counts the columns it fits (least squares of order 2 underneath).
    #[derive(Debug)]
    struct Counting {
        inner: PceRegression,
        columns: AtomicUsize,
    }

    impl Method for Counting {
        fn kind(&self) -> &'static str {
            "pce_regression"
        }
        fn label(&self, dim: usize) -> String {
            self.inner.label(dim)
        }
        fn validate(&self, problem: &Problem) -> Result<(), InvalidSettings> {
            self.inner.validate(problem)
        }
        fn summary(&self, dim: usize) -> MethodSummary {
            self.inner.summary(dim)
        }
        fn evaluation(&self) -> Evaluation<'_> {
            Evaluation::Sampling(self)
        }
    }

    impl Sampling for Counting {
        fn make_design(&self, inputs: &RandomInputs, seed: u64) -> Result<Design, MethodError> {
            self.inner.make_design(inputs, seed)
        }
        fn make_estimate(&self, results: RunResults) -> Result<Estimate, MethodError> {
            self.columns
                .fetch_add(results.data.ncols(), Ordering::Relaxed);
            self.inner.make_estimate(results)
        }
        fn chaos_per_column(&self) -> bool {
            true
        }
    }

    fn counting(text: &str) -> (Counting, Design) {
        let inner: PceRegression = toml::from_str(text).unwrap();
        let inputs = RandomInputs::independent(
            ["a", "b"]
                .iter()
                .map(|n| RandomParameter {
                    name: (*n).into(),
                    distribution: Distribution::uniform(-1.0, 1.0).unwrap(),
                })
                .collect(),
        );
        let design = inner.design(&inputs, 5).unwrap();
        let m = Counting {
            inner,
            columns: AtomicUsize::new(0),
        };
        (m, design)
    }

    #[test]
    fn identical_columns_are_fitted_once() {
        let (m, design) = counting("samples = 30\norder = 2");
        let x = &design.values;
        let rows: Vec<usize> = (0..x.len()).collect();
        let f = |k: usize| -> Vec<f64> {
            x.iter()
                .map(|v| v[0] * v[1] + k as f64 * v[0] * v[0])
                .collect()
        };
        // Columns a, b, a, a, b, c.
        let cols = [f(0), f(1), f(0), f(0), f(1), f(2)];
        let data = DMatrix::from_fn(x.len(), cols.len(), |i, t| cols[t][i]);
        let (e, fits, hashes) = estimate_distinct(&m, &design, &rows, &data).unwrap();
        assert_eq!(fits, 3);
        assert_eq!(m.columns.load(Ordering::Relaxed), 3);
        assert_eq!(hashes[0], hashes[2]);
        assert_ne!(hashes[0], hashes[1]);
        // Every column as its own fit gives.
        m.columns.store(0, Ordering::Relaxed);
        let all = m.estimate(&design, &rows, &data).unwrap();
        assert_eq!(m.columns.load(Ordering::Relaxed), 6);
        assert_eq!(e.mean, all.mean);
        assert_eq!(e.std, all.std);
        assert_eq!(e.chaos_error, all.chaos_error);
        assert_eq!(e.sobol, all.sobol);
    }

    /// Least squares is linear in the data: the chaos of the principal components of a rank-3
    /// series, combined over time, is the chaos of every column (to rounding), from 3 fits.
    #[test]
    fn pca_chaos_of_a_low_rank_series_matches_the_column_fit() {
        let (m, design) = counting("samples = 40\norder = 3");
        let rows: Vec<usize> = (0..design.len()).collect();
        let y = rank_three(&design.values, 200);
        let modes = decomposed(&y, 200, 1.0 - 1e-6);
        assert_eq!(modes.eigenvalues.len(), 3);
        let of_modes = m.estimate(&design, &rows, &modes.scores).unwrap();
        assert_eq!(m.columns.load(Ordering::Relaxed), 3);
        let pca = combine(of_modes, &modes).unwrap();
        let columns = m.estimate(&design, &rows, &y).unwrap();
        let smax = columns.std.iter().copied().fold(0.0, f64::max);
        for t in 0..200 {
            assert!((pca.mean[t] - columns.mean[t]).abs() < 1e-10, "mean at {t}");
            assert!(
                (pca.std[t] - columns.std[t]).abs() < 1e-10 * smax,
                "std at {t}"
            );
            let (s, c) = (
                &pca.sobol.as_ref().unwrap().first[t],
                &columns.sobol.as_ref().unwrap().first[t],
            );
            for (a, b) in s.iter().zip(c) {
                assert!((a - b).abs() < 1e-8, "S1 at {t}: {a} {b}");
            }
            // A polynomial of order 3 in the inputs: no truncation error, no discarded part.
            assert!(pca.chaos_error.as_ref().unwrap().values[t] < 1e-12);
        }
    }
}
