//! Sobol' indices by pick-freeze sampling, bootstrap intervals, and replicated-design
//! estimators.
//!
//! Design: two independent base samples `A` and `B` (N points each, in any germ space,
//! e.g. the two halves of a 2d-dimensional scrambled Sobol' or LHS design) and, for each
//! input `i`, `AB_i` = `A` with column `i` taken from `B`: `N (d + 2)` model runs, laid out
//! by [`pick_freeze_design`] as `A`, `B`, `AB_1`, ..., `AB_d`.
//!
//! Estimators (Saltelli et al., Comput. Phys. Commun. 181, 2010, table 2):
//! - first order `V_i = (1/N) sum_j f(B)_j (f(AB_i)_j - f(A)_j)` (Saltelli 2010);
//! - total `VT_i = (1/2N) sum_j (f(A)_j - f(AB_i)_j)^2` (Jansen 1999);
//! - `V` the variance of the `2N` values of `f(A)` and `f(B)`; `S_i = V_i / V`,
//!   `ST_i = VT_i / V`.
//!
//! Bootstrap: `B` resamples of the row indices `j` with replacement (the same rows of
//! `A`, `B` and every `AB_i`), resample `k` drawn from `rng::stream(seed, k)`;
//! percentile intervals. [`pick_freeze_bootstrap_columns`] bootstraps many outputs on the
//! same rows (e.g. every time column): each resample is drawn once for all of them and the
//! outputs are evaluated a few at a time in lock step (one SIMD lane each), every sum in the
//! same order as for a single output, so the numbers are those of [`pick_freeze_bootstrap`]
//! bit for bit.
//!
//! Replicates: [`pick_freeze_replicates`] takes the rows as consecutive groups, each an
//! independent replicate of the design (e.g. independently scrambled Sobol' nets, whose rows
//! are not independent within a net, so that the bootstrap over rows does not apply), and
//! gives Student's t intervals from the spread of the replicate estimates around the
//! estimate on all rows.

use rayon::prelude::*;

use crate::uq::rng::{stream, uniform_below};
use lanes::{Lanes, LANES};

mod lanes;

/// Errors of the estimators.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum SensitivityError {
    /// The value vector does not have `N (d + 2)` entries.
    #[error("pick-freeze needs N (d + 2) = {expected} model values, got {got}")]
    Count {
        /// Expected count.
        expected: usize,
        /// Given count.
        got: usize,
    },
    /// Too few base samples.
    #[error("pick-freeze needs at least 2 base samples (got {0})")]
    TooFew(usize),
    /// Base samples of different sizes or dimensions.
    #[error("the base samples A and B must have the same number of points and dimension")]
    Mismatch,
}

/// The `N (d + 2)` points `A`, `B`, `AB_1`, ..., `AB_d` (each block in row order).
pub fn pick_freeze_design(
    a: &[Vec<f64>],
    b: &[Vec<f64>],
) -> Result<Vec<Vec<f64>>, SensitivityError> {
    let n = a.len();
    let d = a.first().map_or(0, Vec::len);
    if b.len() != n || a.iter().chain(b).any(|p| p.len() != d) {
        return Err(SensitivityError::Mismatch);
    }
    let mut out = Vec::with_capacity(n * (d + 2));
    out.extend(a.iter().cloned());
    out.extend(b.iter().cloned());
    for i in 0..d {
        for (pa, pb) in a.iter().zip(b) {
            let mut p = pa.clone();
            p[i] = pb[i];
            out.push(p);
        }
    }
    Ok(out)
}

/// Point estimates of the indices.
#[derive(Clone, Debug, PartialEq)]
pub struct SobolIndices {
    /// First-order indices.
    pub first: Vec<f64>,
    /// Total indices.
    pub total: Vec<f64>,
    /// Output variance `V`.
    pub variance: f64,
}

/// Indices with bootstrap percentile intervals.
#[derive(Clone, Debug, PartialEq)]
pub struct SobolWithCi {
    /// Point estimates.
    pub estimate: SobolIndices,
    /// Interval `(low, high)` per first-order index.
    pub first_ci: Vec<(f64, f64)>,
    /// Interval `(low, high)` per total index.
    pub total_ci: Vec<(f64, f64)>,
}

fn check(values: &[f64], n: usize, d: usize) -> Result<(), SensitivityError> {
    if n < 2 {
        return Err(SensitivityError::TooFew(n));
    }
    if values.len() != n * (d + 2) {
        return Err(SensitivityError::Count {
            expected: n * (d + 2),
            got: values.len(),
        });
    }
    Ok(())
}

/// Estimates over the rows `rows` (with repetition for the bootstrap).
fn estimate_rows(values: &[f64], n: usize, d: usize, rows: &[usize]) -> SobolIndices {
    let fa = &values[..n];
    let fb = &values[n..2 * n];
    let m = rows.len() as f64;
    let mean = rows.iter().map(|&j| fa[j] + fb[j]).sum::<f64>() / (2.0 * m);
    let variance = rows
        .iter()
        .map(|&j| (fa[j] - mean).powi(2) + (fb[j] - mean).powi(2))
        .sum::<f64>()
        / (2.0 * m - 1.0);
    let mut first = vec![0.0; d];
    let mut total = vec![0.0; d];
    for i in 0..d {
        let fab = &values[(2 + i) * n..(3 + i) * n];
        let (mut v, mut vt) = (0.0, 0.0);
        for &j in rows {
            v += fb[j] * (fab[j] - fa[j]);
            vt += (fa[j] - fab[j]).powi(2);
        }
        first[i] = v / m / variance;
        total[i] = vt / (2.0 * m) / variance;
    }
    SobolIndices {
        first,
        total,
        variance,
    }
}

/// First-order (Saltelli 2010) and total (Jansen) indices from the `N (d + 2)` values in
/// the order of [`pick_freeze_design`].
pub fn pick_freeze(values: &[f64], n: usize, d: usize) -> Result<SobolIndices, SensitivityError> {
    check(values, n, d)?;
    let rows: Vec<usize> = (0..n).collect();
    Ok(estimate_rows(values, n, d, &rows))
}

/// `pick_freeze` with bootstrap percentile intervals at `level` (e.g. 0.95) from
/// `resamples` resamples seeded by `seed`.
pub fn pick_freeze_bootstrap(
    values: &[f64],
    n: usize,
    d: usize,
    resamples: usize,
    level: f64,
    seed: u64,
) -> Result<SobolWithCi, SensitivityError> {
    let mut all = pick_freeze_bootstrap_columns(&[values], n, d, resamples, level, seed)?;
    Ok(all.remove(0))
}

/// [`pick_freeze_bootstrap`] of every column of `columns` (each `N (d + 2)` values in the
/// order of [`pick_freeze_design`]) on the same resampled rows: the same results as one call
/// per column, bit for bit, at a fraction of the cost (one draw of each resample, the columns
/// evaluated a few at a time in lock step, in parallel).
pub fn pick_freeze_bootstrap_columns<V: AsRef<[f64]> + Sync>(
    columns: &[V],
    n: usize,
    d: usize,
    resamples: usize,
    level: f64,
    seed: u64,
) -> Result<Vec<SobolWithCi>, SensitivityError> {
    let limits = (GROUP_VALUES, BATCH_ROWS);
    bootstrap_columns(columns, n, d, resamples, level, seed, limits)
}

/// [`pick_freeze_bootstrap_columns`] keeping at most `limits.0` replicate estimates and
/// `limits.1` resampled rows at once.
fn bootstrap_columns<V: AsRef<[f64]> + Sync>(
    columns: &[V],
    n: usize,
    d: usize,
    resamples: usize,
    level: f64,
    seed: u64,
    (group_values, batch_rows): (usize, usize),
) -> Result<Vec<SobolWithCi>, SensitivityError> {
    let estimates = columns
        .par_iter()
        .map(|v| pick_freeze(v.as_ref(), n, d))
        .collect::<Result<Vec<_>, _>>()?;
    let stats = 2 * d;
    // Column groups and resample batches bound the memory: the replicate estimates of a group
    // (`stats x resamples` per column) and the rows of a batch.
    let group = ((group_values / (stats * resamples).max(1)) / LANES).max(1) * LANES;
    let batch = (batch_rows / n).clamp(1, resamples.max(1));
    let single_batch = batch >= resamples;
    let cached = single_batch.then(|| resample_rows(n, 0..resamples, seed));
    let mut out = Vec::with_capacity(columns.len());
    for (g, cols) in columns.chunks(group).enumerate() {
        // Per column: the replicate estimates, statistic-major (`k + resamples * s`).
        let mut reps = vec![vec![0.0; stats * resamples]; cols.len()];
        for start in (0..resamples).step_by(batch) {
            let ks = start..(start + batch).min(resamples);
            let drawn;
            let rows = match &cached {
                Some(r) => r,
                None => {
                    drawn = resample_rows(n, ks.clone(), seed);
                    &drawn
                }
            };
            cols.par_chunks(LANES)
                .zip(reps.par_chunks_mut(LANES))
                .for_each(|(chunk, reps)| {
                    Lanes::new(chunk, n, d).replicates(rows, ks.clone(), resamples, reps);
                });
        }
        let base = g * group;
        let intervals: Vec<SobolWithCi> = reps
            .par_iter_mut()
            .enumerate()
            .map(|(c, r)| {
                let mut ci = |s: usize| {
                    percentile_interval(&mut r[s * resamples..(s + 1) * resamples], level)
                };
                SobolWithCi {
                    estimate: estimates[base + c].clone(),
                    first_ci: (0..d).map(&mut ci).collect(),
                    total_ci: (d..stats).map(&mut ci).collect(),
                }
            })
            .collect();
        out.extend(intervals);
    }
    Ok(out)
}

/// Most replicate estimates kept at once (a group of columns).
const GROUP_VALUES: usize = 1 << 22;

/// Most resampled rows drawn at once (a batch of resamples).
const BATCH_ROWS: usize = 1 << 21;

/// The rows of resamples `ks` (resample `k` from `stream(seed, k)`), resample after
/// resample.
fn resample_rows(n: usize, ks: std::ops::Range<usize>, seed: u64) -> Vec<usize> {
    let mut rows = vec![0usize; n * ks.len()];
    rows.par_chunks_mut(n.max(1)).zip(ks).for_each(|(rows, k)| {
        let mut rng = stream(seed, k as u64);
        for r in rows.iter_mut() {
            *r = uniform_below(&mut rng, n as u64) as usize;
        }
    });
    rows
}

/// Percentile interval at `level` of the finite values (NaN when there are none); `values`
/// is reordered. The order statistics are found by selection: the same values as from the
/// sorted data (equal under `total_cmp` means the same bits).
fn percentile_interval(values: &mut [f64], level: f64) -> (f64, f64) {
    let mut finite = 0;
    for i in 0..values.len() {
        if values[i].is_finite() {
            values.swap(finite, i);
            finite += 1;
        }
    }
    let v = &mut values[..finite];
    if v.is_empty() {
        return (f64::NAN, f64::NAN);
    }
    let alpha = 0.5 * (1.0 - level);
    (
        selected_percentile(v, alpha),
        selected_percentile(v, 1.0 - alpha),
    )
}

/// [`percentile`] of `values` as if sorted, by selection (`values` is reordered).
fn selected_percentile(values: &mut [f64], q: f64) -> f64 {
    let pos = q * (values.len() - 1) as f64;
    let (lo, hi) = (pos.floor() as usize, pos.ceil() as usize);
    let (_, &mut low, above) = values.select_nth_unstable_by(lo, f64::total_cmp);
    // The next order statistic is the least of those above.
    let high = if hi == lo {
        low
    } else {
        above.iter().copied().min_by(f64::total_cmp).unwrap_or(low)
    };
    low + (pos - lo as f64) * (high - low)
}

/// [`pick_freeze`] on all `n` rows with intervals from independent replicates of the design:
/// the rows are grouped replicate after replicate, `sizes[r]` rows in replicate `r` (the rows
/// of an independently scrambled Sobol' net, say, whose rows are not independent of each
/// other, so that a bootstrap over them does not see the error). Each replicate with at least
/// 2 rows gives its own estimates; the interval of an index is the estimate on all rows
/// `± t_{R-1, (1 + level)/2} sd_R / sqrt(R)`, with `sd_R` the standard deviation of the `R`
/// replicate estimates (Student's t). Fewer than 2 such replicates, or a replicate estimate
/// that is not finite (a replicate without variance), give NaN intervals.
pub fn pick_freeze_replicates(
    values: &[f64],
    n: usize,
    d: usize,
    sizes: &[usize],
    level: f64,
) -> Result<SobolWithCi, SensitivityError> {
    let estimate = pick_freeze(values, n, d)?;
    if sizes.iter().sum::<usize>() != n {
        return Err(SensitivityError::Mismatch);
    }
    let mut start = 0;
    let mut replicates = Vec::with_capacity(sizes.len());
    for &size in sizes {
        let rows: Vec<usize> = (start..start + size).collect();
        start += size;
        if size >= 2 {
            replicates.push(estimate_rows(values, n, d, &rows));
        }
    }
    let half = |spread: Vec<f64>| {
        let r = spread.len();
        if r < 2 || spread.iter().any(|v| !v.is_finite()) {
            return f64::NAN;
        }
        student_t_quantile(0.5 * (1.0 + level), (r - 1) as f64)
            * replicate_summary(&spread).std_error
    };
    let interval = |at: f64, h: f64| {
        if h.is_nan() {
            (f64::NAN, f64::NAN)
        } else {
            (at - h, at + h)
        }
    };
    let first_ci = (0..d)
        .map(|i| {
            let h = half(replicates.iter().map(|e| e.first[i]).collect());
            interval(estimate.first[i], h)
        })
        .collect();
    let total_ci = (0..d)
        .map(|i| {
            let h = half(replicates.iter().map(|e| e.total[i]).collect());
            interval(estimate.total[i], h)
        })
        .collect();
    Ok(SobolWithCi {
        estimate,
        first_ci,
        total_ci,
    })
}

/// The `p` quantile of Student's t distribution with `freedom` degrees of freedom.
pub fn student_t_quantile(p: f64, freedom: f64) -> f64 {
    use statrs::distribution::{ContinuousCDF, StudentsT};
    match StudentsT::new(0.0, 1.0, freedom) {
        Ok(t) if (0.0..=1.0).contains(&p) => t.inverse_cdf(p),
        _ => f64::NAN,
    }
}

/// Summary of `R` independent replicate estimates of one statistic (replicated LHS,
/// independently scrambled QMC): their mean and its standard error
/// `sd(estimates) / sqrt(R)` (an honest error, unlike the plain MC formula for LHS).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReplicateSummary {
    /// Mean of the replicate estimates.
    pub mean: f64,
    /// Standard error of that mean (NaN for fewer than 2 replicates).
    pub std_error: f64,
    /// Number of replicates.
    pub replicates: usize,
}

/// Combines per-replicate estimates.
pub fn replicate_summary(estimates: &[f64]) -> ReplicateSummary {
    let r = estimates.len();
    let mean = estimates.iter().sum::<f64>() / r as f64;
    let std_error = if r < 2 {
        f64::NAN
    } else {
        (estimates.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (r - 1) as f64 / r as f64)
            .sqrt()
    };
    ReplicateSummary {
        mean,
        std_error,
        replicates: r,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::uq::hd::sobol_seq::Sobol;
    use std::f64::consts::PI;

    fn ishigami(x: &[f64]) -> f64 {
        let (a, b) = (7.0, 0.1);
        x[0].sin() + a * x[1].sin().powi(2) + b * x[2].powi(4) * x[0].sin()
    }

    /// Closed forms (Ishigami & Homma 1990; Sobol' & Levitan 1999), a = 7, b = 0.1.
    fn ishigami_exact() -> ([f64; 3], [f64; 3]) {
        let (a, b) = (7.0f64, 0.1f64);
        let pi4 = PI.powi(4);
        let pi8 = PI.powi(8);
        let v1 = 0.5 * (1.0 + b * pi4 / 5.0).powi(2);
        let v2 = a * a / 8.0;
        let v13 = b * b * pi8 * (1.0 / 18.0 - 1.0 / 50.0);
        let v = a * a / 8.0 + b * pi4 / 5.0 + b * b * pi8 / 18.0 + 0.5;
        ([v1 / v, v2 / v, 0.0], [(v1 + v13) / v, v2 / v, v13 / v])
    }

    fn ishigami_values(n: usize, seed: u64) -> Vec<f64> {
        let pts = Sobol::scrambled(6, seed, 0).unwrap().points(0, n).unwrap();
        let map = |u: f64| -PI + 2.0 * PI * u;
        let a: Vec<Vec<f64>> = pts
            .iter()
            .map(|p| p[..3].iter().map(|&u| map(u)).collect())
            .collect();
        let b: Vec<Vec<f64>> = pts
            .iter()
            .map(|p| p[3..].iter().map(|&u| map(u)).collect())
            .collect();
        pick_freeze_design(&a, &b)
            .unwrap()
            .iter()
            .map(|x| ishigami(x))
            .collect()
    }

    #[test]
    fn ishigami_closed_form_values() {
        let (s, st) = ishigami_exact();
        assert!((s[0] - 0.3139).abs() < 1e-4);
        assert!((s[1] - 0.4424).abs() < 1e-4);
        assert!((st[2] - 0.2437).abs() < 1e-4);
    }

    #[test]
    fn pick_freeze_estimates_ishigami_indices_with_covering_intervals() {
        let (s, st) = ishigami_exact();
        let n = 1 << 13;
        let values = ishigami_values(n, 17);
        let est = pick_freeze_bootstrap(&values, n, 3, 300, 0.99, 5).unwrap();
        let mut covered = 0;
        for i in 0..3 {
            assert!(
                (est.estimate.first[i] - s[i]).abs() < 0.02,
                "S{i}: {}",
                est.estimate.first[i]
            );
            assert!(
                (est.estimate.total[i] - st[i]).abs() < 0.02,
                "ST{i}: {}",
                est.estimate.total[i]
            );
            let (lo, hi) = est.first_ci[i];
            covered += usize::from(lo <= s[i] && s[i] <= hi);
            let (lo, hi) = est.total_ci[i];
            covered += usize::from(lo <= st[i] && st[i] <= hi);
            assert!(est.first_ci[i].1 - est.first_ci[i].0 < 0.1);
        }
        assert!(
            covered >= 5,
            "{covered} of 6 intervals cover the exact values"
        );
        // Reproducible for the seed.
        let again = pick_freeze_bootstrap(&values, n, 3, 300, 0.99, 5).unwrap();
        assert_eq!(est, again);
    }

    /// The bootstrap as it was before the resamples were shared between columns: one column
    /// at a time, one resample at a time, the straightforward sums of `estimate_rows`.
    fn bootstrap_one_column_at_a_time(
        values: &[f64],
        n: usize,
        d: usize,
        resamples: usize,
        level: f64,
        seed: u64,
    ) -> SobolWithCi {
        let estimate = pick_freeze(values, n, d).unwrap();
        let mut firsts = vec![Vec::new(); d];
        let mut totals = vec![Vec::new(); d];
        for k in 0..resamples {
            let mut rng = stream(seed, k as u64);
            let rows: Vec<usize> = (0..n)
                .map(|_| uniform_below(&mut rng, n as u64) as usize)
                .collect();
            let e = estimate_rows(values, n, d, &rows);
            for i in 0..d {
                firsts[i].push(e.first[i]);
                totals[i].push(e.total[i]);
            }
        }
        let ci = |mut v: Vec<f64>| {
            v.retain(|x| x.is_finite());
            if v.is_empty() {
                return (f64::NAN, f64::NAN);
            }
            v.sort_by(f64::total_cmp);
            let alpha = 0.5 * (1.0 - level);
            (percentile(&v, alpha), percentile(&v, 1.0 - alpha))
        };
        SobolWithCi {
            estimate,
            first_ci: firsts.into_iter().map(ci).collect(),
            total_ci: totals.into_iter().map(ci).collect(),
        }
    }

    /// Linear-interpolation percentile of sorted data, `q` in [0, 1].
    fn percentile(sorted: &[f64], q: f64) -> f64 {
        let pos = q * (sorted.len() - 1) as f64;
        let lo = pos.floor() as usize;
        let hi = pos.ceil() as usize;
        sorted[lo] + (pos - lo as f64) * (sorted[hi] - sorted[lo])
    }

    /// Bit patterns, so that NaN equals NaN and 0.0 differs from -0.0.
    fn bits(e: &SobolWithCi) -> Vec<u64> {
        let pairs = e
            .first_ci
            .iter()
            .chain(&e.total_ci)
            .flat_map(|&(a, b)| [a, b]);
        e.estimate
            .first
            .iter()
            .chain(&e.estimate.total)
            .copied()
            .chain([e.estimate.variance])
            .chain(pairs)
            .map(f64::to_bits)
            .collect()
    }

    #[test]
    fn shared_bootstrap_resamples_give_the_per_column_numbers_bit_for_bit() {
        // Regression: the bootstrap of a time-resolved study drew every resample again for each
        // column and summed one column at a time. The shared draw and the lock-step sums must
        // not change a bit: 11 columns (not a multiple of the lanes), an odd base sample,
        // d = 3, a column with a large mean, a constant column (0/0 estimates), and the
        // batched and grouped paths (tiny limits).
        let (n, d) = (301, 3);
        let base = ishigami_values(n, 9);
        let mut columns: Vec<Vec<f64>> = (0..10)
            .map(|c| {
                let t = c as f64;
                base.iter()
                    .enumerate()
                    .map(|(k, v)| (1.0 + 0.1 * t) * v + t * (k as f64).sin() * 1e-3)
                    .collect()
            })
            .collect();
        columns[3].iter_mut().for_each(|v| *v += 1e6);
        columns.push(vec![0.25; base.len()]);
        let (resamples, level, seed) = (37, 0.9, 123);
        let want: Vec<Vec<u64>> = columns
            .iter()
            .map(|v| {
                bits(&bootstrap_one_column_at_a_time(
                    v, n, d, resamples, level, seed,
                ))
            })
            .collect();
        for limits in [
            (GROUP_VALUES, BATCH_ROWS),
            (1, 1),
            (300, 5 * n),
            (1000, 2 * n + 1),
        ] {
            let got = bootstrap_columns(&columns, n, d, resamples, level, seed, limits).unwrap();
            let got: Vec<Vec<u64>> = got.iter().map(bits).collect();
            assert_eq!(got, want, "limits {limits:?}");
        }
        let one = pick_freeze_bootstrap(&columns[0], n, d, resamples, level, seed).unwrap();
        assert_eq!(bits(&one), want[0]);
        // No resamples: NaN intervals, as before.
        let none = pick_freeze_bootstrap(&columns[0], n, d, 0, level, seed).unwrap();
        assert_eq!(
            bits(&none),
            bits(&bootstrap_one_column_at_a_time(
                &columns[0],
                n,
                d,
                0,
                level,
                seed
            ))
        );
    }

    #[test]
    fn percentile_intervals_by_selection_equal_those_of_the_sorted_values() {
        // Regression: the intervals take their order statistics by selection, not by sorting.
        // Ties, signed zeros, infinities and NaN (left out), odd and even counts, levels
        // that fall on an order statistic and between two.
        let mut s = 7u64;
        let mut next = || {
            s = s
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1442695040888963407);
            (s >> 40) as f64 / (1u64 << 24) as f64
        };
        for len in [1, 2, 3, 10, 37, 200] {
            let mut values: Vec<f64> = (0..len)
                .map(|i| match i % 9 {
                    0 => 0.0,
                    1 => -0.0,
                    2 => 0.25,
                    3 if len > 3 => f64::NAN,
                    4 if len > 3 => f64::INFINITY,
                    _ => next() - 0.5,
                })
                .collect();
            for level in [0.0, 0.5, 0.9, 0.95, 1.0] {
                let mut sorted: Vec<f64> =
                    values.iter().copied().filter(|x| x.is_finite()).collect();
                sorted.sort_by(f64::total_cmp);
                let alpha = 0.5 * (1.0 - level);
                let (lo, hi) = percentile_interval(&mut values, level);
                assert_eq!(
                    (lo.to_bits(), hi.to_bits()),
                    (
                        percentile(&sorted, alpha).to_bits(),
                        percentile(&sorted, 1.0 - alpha).to_bits()
                    ),
                    "{len} values at level {level}"
                );
            }
        }
        let (lo, hi) = percentile_interval(&mut [f64::NAN, f64::NEG_INFINITY], 0.9);
        assert!(lo.is_nan() && hi.is_nan());
    }

    #[test]
    fn intervals_shrink_with_the_base_sample() {
        let w = |n: usize| {
            let v = ishigami_values(n, 3);
            let e = pick_freeze_bootstrap(&v, n, 3, 200, 0.95, 1).unwrap();
            e.total_ci[0].1 - e.total_ci[0].0
        };
        let (w1, w2) = (w(512), w(8192));
        // 16x the samples: about 4x narrower (at least 2.5x).
        assert!(w1 / w2 > 2.5, "{w1} vs {w2}");
    }

    #[test]
    fn design_layout_and_errors() {
        let a = vec![vec![1.0, 2.0], vec![3.0, 4.0]];
        let b = vec![vec![5.0, 6.0], vec![7.0, 8.0]];
        let d = pick_freeze_design(&a, &b).unwrap();
        assert_eq!(d.len(), 8);
        assert_eq!(d[4], vec![5.0, 2.0]); // AB_1, row 0
        assert_eq!(d[7], vec![3.0, 8.0]); // AB_2, row 1
        assert!(matches!(
            pick_freeze(&[0.0; 7], 2, 2),
            Err(SensitivityError::Count {
                expected: 8,
                got: 7
            })
        ));
        assert!(pick_freeze_design(&a, &b[..1]).is_err());
    }

    #[test]
    fn replicated_lhs_gives_an_honest_error_where_the_mc_formula_overstates_it() {
        use crate::uq::sampling::latin_hypercube;
        use rand::RngCore;
        // Nearly additive f on U(0,1)^4: LHS removes the additive variance, so the plain
        // MC formula sigma / sqrt(n) overstates the error of the LHS mean.
        let f = |x: &[f64]| -> f64 {
            x.iter().map(|v| (3.0 * v).sin()).sum::<f64>() + 0.1 * x[0] * x[1]
        };
        let n = 50;
        let lhs_mean = |r: u64| -> (f64, f64) {
            let seed = stream(99, r).next_u64();
            let y: Vec<f64> = latin_hypercube(n, 4, seed).iter().map(|x| f(x)).collect();
            let m = y.iter().sum::<f64>() / n as f64;
            let sd = (y.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt();
            (m, sd / (n as f64).sqrt())
        };
        // R = 10 replicates: the replicated standard error of one replicate's mean is
        // se * sqrt(R).
        let reps: Vec<(f64, f64)> = (0..10).map(lhs_mean).collect();
        let summary = replicate_summary(&reps.iter().map(|r| r.0).collect::<Vec<_>>());
        let per_replicate = summary.std_error * (summary.replicates as f64).sqrt();
        // The true spread of one LHS mean, from 300 further replicates.
        let many: Vec<f64> = (100..400).map(|r| lhs_mean(r).0).collect();
        let truth = replicate_summary(&many).std_error * (many.len() as f64).sqrt();
        let mc_formula = reps[0].1;
        assert!(
            mc_formula > 5.0 * truth,
            "MC formula {mc_formula} vs true {truth}"
        );
        assert!(
            per_replicate > 0.4 * truth && per_replicate < 2.0 * truth,
            "replicated {per_replicate} vs true {truth}"
        );
    }

    #[test]
    fn replicate_summary_is_the_standard_error_of_the_mean() {
        let s = replicate_summary(&[1.0, 2.0, 3.0, 4.0]);
        assert_eq!(s.mean, 2.5);
        // sd = sqrt(5/3), se = sd / 2.
        assert!((s.std_error - (5.0f64 / 3.0).sqrt() / 2.0).abs() < 1e-15);
    }
}
