//! One column of draws (a time step of an output, or a scalar quantity) summarised in a few
//! linear passes: range, mean, Std, exact type-7 quantiles by selection, Silverman's
//! bandwidth.

use std::borrow::Cow;

use multiversion::multiversion;

use crate::qoi::kde;
use crate::uq::moments;

/// One column of draws (a time step, or a scalar quantity) summarised in one pass.
#[derive(Clone, Debug)]
pub(super) struct Column {
    /// Type-7 quantiles at the requested levels.
    pub quantiles: Vec<f64>,
    pub min: f64,
    pub max: f64,
    /// Mean of the finite values.
    pub mean: f64,
    /// Their standard deviation (n − 1).
    pub std: f64,
    /// Silverman's bandwidth.
    pub bandwidth: f64,
}

/// Quantiles, range and bandwidth of the finite values of `col`, in a few linear passes over
/// it (range and sum; squared deviations; bin counts; the members of the bins that hold the
/// order statistics needed).
pub(super) fn column(col: &[f64], ps: &[f64]) -> Column {
    let mut levels = ps.to_vec();
    levels.extend([0.25, 0.75]);
    let (n, sum, lo, hi) = count_sum_range(col);
    let n: usize = n.iter().sum();
    let (min, max) = (
        lo.iter().copied().fold(f64::INFINITY, f64::min),
        hi.iter().copied().fold(f64::NEG_INFINITY, f64::max),
    );
    let mean = sum.iter().sum::<f64>() / n.max(1) as f64;
    // The finite values (the column itself when all are).
    let finite: Cow<[f64]> = if n == col.len() {
        Cow::Borrowed(col)
    } else {
        Cow::Owned(col.iter().copied().filter(|x| x.is_finite()).collect())
    };
    let (q, ss) = select_quantiles(&finite, &levels, min, max, mean);
    let std = if n > 1 {
        (ss / (n - 1) as f64).sqrt()
    } else {
        0.0
    };
    let iqr = q[ps.len() + 1] - q[ps.len()];
    Column {
        quantiles: q[..ps.len()].to_vec(),
        min,
        max,
        mean,
        std,
        bandwidth: kde::silverman_from(n, mean, std, iqr),
    }
}

/// Per lane of four (value `i` in lane `i % 4`, the remainder in lane 0): the count, sum,
/// least and greatest of the finite values. Four independent accumulators each, so that
/// the loop is not one dependency chain; compiled for the baseline and for wider vector
/// units, chosen at run time (the same sums in every version).
#[multiversion(targets("x86_64+avx512f+avx512vl+avx2+avx+sse4.2", "x86_64+avx2+avx+sse4.2"))]
#[allow(clippy::type_complexity)]
fn count_sum_range(col: &[f64]) -> ([usize; 4], [f64; 4], [f64; 4], [f64; 4]) {
    let (mut n, mut sum) = ([0usize; 4], [0.0f64; 4]);
    let (mut lo, mut hi) = ([f64::INFINITY; 4], [f64::NEG_INFINITY; 4]);
    let mut chunks = col.chunks_exact(4);
    for c in &mut chunks {
        for i in 0..4 {
            let x = c[i];
            let ok = x.is_finite();
            n[i] += usize::from(ok);
            sum[i] += if ok { x } else { 0.0 };
            lo[i] = if ok && x < lo[i] { x } else { lo[i] };
            hi[i] = if ok && x > hi[i] { x } else { hi[i] };
        }
    }
    for &x in chunks.remainder().iter().filter(|x| x.is_finite()) {
        n[0] += 1;
        sum[0] += x;
        lo[0] = lo[0].min(x);
        hi[0] = hi[0].max(x);
    }
    (n, sum, lo, hi)
}

/// The sum of `(x - mean)²` over `values`, in four lanes (value `i` in lane `i % 4`, the
/// remainder in lanes `0..`), compiled for the baseline and for wider vector units.
#[multiversion(targets("x86_64+avx512f+avx512vl+avx2+avx+sse4.2", "x86_64+avx2+avx+sse4.2"))]
fn squared_deviations(values: &[f64], mean: f64) -> f64 {
    let mut ss = [0.0; 4];
    let mut chunks = values.chunks_exact(4);
    for c in &mut chunks {
        for i in 0..4 {
            ss[i] += (c[i] - mean) * (c[i] - mean);
        }
    }
    for (i, x) in chunks.remainder().iter().enumerate() {
        ss[i] += (x - mean) * (x - mean);
    }
    ss.iter().sum()
}

/// Type-7 quantiles (as [`moments::quantile`] of the sorted values) of the finite `values`
/// (within `[min, max]`) at the levels `ps`, without sorting them all, and the sum of squared
/// deviations from `mean`. NaN for no value or a level outside [0, 1].
fn select_quantiles(values: &[f64], ps: &[f64], min: f64, max: f64, mean: f64) -> (Vec<f64>, f64) {
    let n = values.len();
    if n == 0 || max == min || !(max - min).is_finite() {
        let mut sorted = values.to_vec();
        sorted.sort_by(f64::total_cmp);
        let ss = values.iter().map(|x| (x - mean) * (x - mean)).sum();
        return (
            ps.iter().map(|&p| moments::quantile(&sorted, p)).collect(),
            ss,
        );
    }
    let ss = squared_deviations(values, mean);
    let rank_pairs = |p: f64| {
        let h = (n - 1) as f64 * p;
        let r = h.floor() as usize;
        (r, (r + 1).min(n - 1), h - r as f64)
    };
    let valid = |p: &f64| (0.0..=1.0).contains(p);
    let mut ranks: Vec<usize> = ps
        .iter()
        .filter(|p| valid(p))
        .flat_map(|&p| {
            let (r0, r1, _) = rank_pairs(p);
            [r0, r1]
        })
        .collect();
    ranks.sort_unstable();
    ranks.dedup();
    let at = select_ranks(values, min, max, &ranks, 0);
    let order_statistic = |r: usize| at[ranks.binary_search(&r).expect("rank selected")];
    let q = ps
        .iter()
        .map(|&p| {
            if !valid(&p) {
                return f64::NAN;
            }
            let (r0, r1, frac) = rank_pairs(p);
            let a = order_statistic(r0);
            if frac == 0.0 {
                a
            } else {
                a + frac * (order_statistic(r1) - a)
            }
        })
        .collect();
    (q, ss)
}

/// Below this many values, [`select_ranks`] sorts.
const SORT_BELOW: usize = 64;
/// Levels of rebinning before [`select_ranks`] sorts a bin whatever its size.
const MAX_DEPTH: usize = 4;

/// The bin of each value in `[min, max]`: `y = ((x - min) * scale).min(top)` rounded to the
/// nearest integer (`0..=top`, `top < 2^16`). Rounding is monotone, which is all the
/// selection needs; it is taken as the low bits of `y + 1.5 · 2^52` (exact: the sum's unit
/// in the last place is 1), which vectorises, unlike a saturating conversion. Compiled for
/// the baseline and for wider vector units, chosen at run time (the same bins in every
/// version).
#[multiversion(targets("x86_64+avx512f+avx512vl+avx2+avx+sse4.2", "x86_64+avx2+avx+sse4.2"))]
fn bin_indices(values: &[f64], min: f64, scale: f64, top: f64) -> Vec<u16> {
    const MAGIC: f64 = 6_755_399_441_055_744.0;
    values
        .iter()
        .map(|&x| (((x - min) * scale).min(top) + MAGIC).to_bits() as u16)
        .collect()
}

/// The order statistics of (0-based, ascending, distinct) `ranks` of the finite `values`,
/// whose range is `[min, max]`, as a sorted copy would give them (by `f64::total_cmp`).
///
/// The values are counted into `n / 8` equal-width bins; only the bins holding a rank are
/// gathered, and each is solved the same way on its own range (so heavy tails, which crowd
/// most values into a few bins, cost a few more linear passes, not a sort), or sorted when
/// small, constant or [`MAX_DEPTH`] levels down. `O(n)` in all but pathological cases.
fn select_ranks(values: &[f64], min: f64, max: f64, ranks: &[usize], depth: usize) -> Vec<f64> {
    let n = values.len();
    if n <= SORT_BELOW || depth >= MAX_DEPTH || max == min || !(max - min).is_finite() {
        let mut sorted = values.to_vec();
        sorted.sort_unstable_by(f64::total_cmp);
        return ranks.iter().map(|&r| sorted[r]).collect();
    }
    let bins = (n / 8).clamp(16, 1 << 14);
    let scale = bins as f64 / (max - min);
    // Bin of each value (u16: at most 2^14 bins), and the counts in four interleaved
    // histograms, so that equal neighbours do not wait on one counter.
    let top = (bins - 1) as f64;
    let index = bin_indices(values, min, scale, top);
    let mut counts = vec![0u32; 4 * bins];
    let mut quads = index.chunks_exact(4);
    for q in &mut quads {
        for (lane, &b) in q.iter().enumerate() {
            counts[4 * b as usize + lane] += 1;
        }
    }
    for &b in quads.remainder() {
        counts[4 * b as usize] += 1;
    }
    // start[b]: the rank of the first value of bin b.
    let mut start = vec![0usize; bins + 1];
    for b in 0..bins {
        let c = &counts[4 * b..4 * b + 4];
        start[b + 1] = start[b] + (c[0] + c[1] + c[2] + c[3]) as usize;
    }
    let bin_of_rank = |r: usize| start.partition_point(|&s| s <= r) - 1;
    // The bins needed, in ascending order, each with the ranks it holds.
    const NONE: u32 = u32::MAX;
    let mut slot = vec![NONE; bins];
    let mut needed: Vec<(usize, Vec<usize>)> = Vec::new();
    for &r in ranks {
        let b = bin_of_rank(r);
        if slot[b] == NONE {
            slot[b] = needed.len() as u32;
            needed.push((b, Vec::new()));
        }
        needed[slot[b] as usize].1.push(r - start[b]);
    }
    let mut members: Vec<Vec<f64>> = needed
        .iter()
        .map(|&(b, _)| Vec::with_capacity(start[b + 1] - start[b]))
        .collect();
    for (&x, &b) in values.iter().zip(&index) {
        let s = slot[b as usize];
        if s != NONE {
            members[s as usize].push(x);
        }
    }
    let mut out = Vec::with_capacity(ranks.len());
    for ((_, local), m) in needed.iter().zip(&members) {
        let (lo, hi) = m
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                (a.min(x), b.max(x))
            });
        out.extend(select_ranks(m, lo, hi, local, depth + 1));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::uq::rng;

    /// Quantiles by sorting everything, the definition.
    fn sorted_quantiles(xs: &[f64], ps: &[f64]) -> Vec<f64> {
        let mut v: Vec<f64> = xs.iter().copied().filter(|x| x.is_finite()).collect();
        v.sort_by(f64::total_cmp);
        ps.iter().map(|&p| moments::quantile(&v, p)).collect()
    }

    #[test]
    fn selection_gives_the_sorted_quantiles_exactly() {
        let ps = [0.0, 0.01, 0.25, 0.333, 0.5, 0.75, 0.99, 1.0];
        let normal: Vec<f64> = (0..20_000u64)
            .map(|i| rng::standard_normal(&mut rng::stream(3, i)))
            .collect();
        let heavy: Vec<f64> = normal.iter().map(|z| z.powi(5)).collect();
        let ties: Vec<f64> = normal.iter().map(|z| (z * 2.0).round()).collect();
        let mut clustered = vec![1.0; 5000];
        clustered.extend([-1e9, 2.0, 1e12]);
        // Crowded into ever smaller bins (rebinning several levels down, then sorting).
        let cubed: Vec<f64> = normal.iter().map(|z| z.powi(3)).collect();
        let geometric: Vec<f64> = (0..3000).map(|i| 0.8f64.powi(i)).collect();
        let signed_zeros: Vec<f64> = (0..3000)
            .map(|i| match i % 3 {
                0 => -0.0,
                1 => 0.0,
                _ => f64::from(i % 7) * 1e-300,
            })
            .collect();
        let with_nan = [f64::NAN, 3.0, 1.0, f64::INFINITY, 2.0];
        for xs in [
            &normal[..],
            &heavy,
            &ties,
            &clustered,
            &cubed,
            &geometric,
            &signed_zeros,
            &normal[..7],
            &[5.0][..],
            &with_nan,
        ] {
            let c = column(xs, &ps);
            assert_eq!(
                c.quantiles,
                sorted_quantiles(xs, &ps),
                "{:?}",
                &xs[..xs.len().min(5)]
            );
        }
        assert!(column(&[], &[0.5]).quantiles[0].is_nan());
        assert!(column(&[1.0, 2.0], &[1.5]).quantiles[0].is_nan());
    }

    /// The cost of summarising a chaos study's draws (501 columns of 4 000):
    /// `cargo test --release -p uq-driver --lib -- --ignored column_timing --nocapture`.
    #[test]
    #[ignore = "prints timings"]
    fn column_timing() {
        let normal: Vec<f64> = (0..501 * 4_000u64)
            .map(|i| rng::standard_normal(&mut rng::stream(5, i)))
            .collect();
        let cubed: Vec<f64> = normal.iter().map(|z| z.powi(3)).collect();
        for (what, draws) in [("normal", normal), ("cubed normal", cubed)] {
            let t = std::time::Instant::now();
            let mut sink = 0.0;
            for _ in 0..20 {
                for col in draws.chunks_exact(4_000) {
                    sink += column(col, &[0.01, 0.5, 0.99]).bandwidth;
                }
            }
            eprintln!(
                "{what}: 501 columns of 4000: {:?} ({sink})",
                t.elapsed() / 20
            );
        }
    }

    #[test]
    fn bins_are_monotone_and_within_range() {
        // Sorted values, with the ends and neighbours of rounding ties.
        let (min, max, bins) = (-3.0, 5.0, 500usize);
        let scale = bins as f64 / (max - min);
        let mut xs: Vec<f64> = (0..=80_000)
            .map(|i| min + (max - min) * i as f64 / 8e4)
            .collect();
        xs.extend((0..bins).map(|b| min + (b as f64 + 0.5) / scale));
        xs.push(max);
        xs.sort_by(f64::total_cmp);
        let index = bin_indices(&xs, min, scale, (bins - 1) as f64);
        assert!(index.windows(2).all(|w| w[0] <= w[1]));
        assert_eq!((index[0], *index.last().unwrap()), (0, (bins - 1) as u16));
        // Rounded to the nearest bin.
        assert_eq!(
            bin_indices(&[min + 2.4 / scale, min + 2.6 / scale], min, scale, 499.0),
            [2, 3]
        );
    }

    #[test]
    fn column_range_and_bandwidth() {
        let xs: Vec<f64> = (1..=9).map(f64::from).collect();
        let c = column(&xs, &[0.5]);
        assert_eq!((c.min, c.max), (1.0, 9.0));
        assert!((c.bandwidth - kde::silverman_bandwidth(&xs)).abs() < 1e-15);
        let c = column(&[2.0; 10], &[0.5]);
        assert_eq!((c.min, c.max, c.quantiles[0]), (2.0, 2.0, 2.0));
        assert!(c.bandwidth > 0.0);
    }
}
