//! One column of draws (a time step of an output, or a scalar quantity) summarised in a few
//! linear passes: range, mean, Std, exact type-7 quantiles by selection, Silverman's
//! bandwidth.

use crate::qoi::kde;
use crate::uq::moments;

/// One column of draws (a time step, or a scalar quantity) summarised in one pass.
#[derive(Clone, Debug)]
pub(super) struct Column {
    /// Type-7 quantiles at the requested levels.
    pub quantiles: Vec<f64>,
    pub min: f64,
    pub max: f64,
    /// Silverman's bandwidth.
    pub bandwidth: f64,
}

/// Quantiles, range and bandwidth of the finite values of `col`, in three passes over it
/// (range and sum; squared deviations and bin counts; the members of the bins that hold
/// the order statistics needed).
pub(super) fn column(col: &[f64], ps: &[f64]) -> Column {
    let mut levels = ps.to_vec();
    levels.extend([0.25, 0.75]);
    // Four independent accumulators each, so that the loop is not one dependency chain.
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
    let n: usize = n.iter().sum();
    let (min, max) = (
        lo.iter().copied().fold(f64::INFINITY, f64::min),
        hi.iter().copied().fold(f64::NEG_INFINITY, f64::max),
    );
    let mean = sum.iter().sum::<f64>() / n.max(1) as f64;
    let (q, ss) = select_quantiles(col, &levels, n, min, max, mean);
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
        bandwidth: kde::silverman_from(n, mean, std, iqr),
    }
}

/// Type-7 quantiles (as [`moments::quantile`] of the sorted finite values) of `values` at
/// the levels `ps`, without sorting, and the sum of squared deviations from `mean`: one
/// pass counts the `n` finite values (within `[min, max]`) into equal-width bins, and only
/// the bins holding the order statistics needed are sorted. `O(n)` unless most values fall
/// into one bin (then it costs a sort of those). NaN for no finite value or a level outside
/// [0, 1].
fn select_quantiles(
    values: &[f64],
    ps: &[f64],
    n: usize,
    min: f64,
    max: f64,
    mean: f64,
) -> (Vec<f64>, f64) {
    let finite = || values.iter().copied().filter(|x| x.is_finite());
    if n == 0 || max == min || !(max - min).is_finite() {
        let mut sorted: Vec<f64> = finite().collect();
        sorted.sort_by(f64::total_cmp);
        let ss = finite().map(|x| (x - mean) * (x - mean)).sum();
        return (
            ps.iter().map(|&p| moments::quantile(&sorted, p)).collect(),
            ss,
        );
    }
    let bins = (n / 8).clamp(16, 1 << 14);
    let scale = bins as f64 / (max - min);
    let bin = |x: f64| (((x - min) * scale) as usize).min(bins - 1);
    let mut start = vec![0usize; bins + 1];
    let mut ss = [0.0; 4];
    for (i, x) in finite().enumerate() {
        ss[i % 4] += (x - mean) * (x - mean);
        start[bin(x) + 1] += 1;
    }
    let ss: f64 = ss.iter().sum();
    for b in 0..bins {
        start[b + 1] += start[b];
    }
    // The bin holding the order statistic of (0-based) rank r.
    let bin_of_rank = |r: usize| start.partition_point(|&s| s <= r) - 1;
    let rank_pairs = |p: f64| {
        let h = (n - 1) as f64 * p;
        let r = h.floor() as usize;
        (r, (r + 1).min(n - 1), h - r as f64)
    };
    // slot[b]: where the members of a needed bin b are gathered.
    const NONE: u32 = u32::MAX;
    let mut slot = vec![NONE; bins];
    let mut members: Vec<Vec<f64>> = Vec::new();
    for &p in ps.iter().filter(|p| (0.0..=1.0).contains(*p)) {
        let (r0, r1, _) = rank_pairs(p);
        for b in [bin_of_rank(r0), bin_of_rank(r1)] {
            if slot[b] == NONE {
                slot[b] = members.len() as u32;
                members.push(Vec::with_capacity(start[b + 1] - start[b]));
            }
        }
    }
    for x in finite() {
        let s = slot[bin(x)];
        if s != NONE {
            members[s as usize].push(x);
        }
    }
    for m in &mut members {
        m.sort_by(f64::total_cmp);
    }
    let order_statistic = |r: usize| {
        let b = bin_of_rank(r);
        members[slot[b] as usize][r - start[b]]
    };
    let q = ps
        .iter()
        .map(|&p| {
            if !(0.0..=1.0).contains(&p) {
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
        let with_nan = [f64::NAN, 3.0, 1.0, f64::INFINITY, 2.0];
        for xs in [
            &normal[..],
            &heavy,
            &ties,
            &clustered,
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
