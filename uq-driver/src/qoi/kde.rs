//! Gaussian kernel density estimation of sampled quantities of interest.

use crate::uq::special::norm_pdf;

/// Kernel contributions beyond this many bandwidths are skipped
/// (relative mass left out: `2 Q(8) = 1.2e-15`).
const CUTOFF: f64 = 8.0;

/// Scale used when the samples have no spread: a thousandth of the value
/// (or 1e-3 around 0).
fn degenerate_scale(x: f64) -> f64 {
    if x != 0.0 && x.is_finite() {
        x.abs() * 1e-3
    } else {
        1e-3
    }
}

/// Finite samples, sorted.
fn finite_sorted(samples: &[f64]) -> Vec<f64> {
    let mut v: Vec<f64> = samples.iter().copied().filter(|x| x.is_finite()).collect();
    v.sort_by(f64::total_cmp);
    v
}

/// Silverman's rule of thumb `0.9 min(std, IQR / 1.34) n^(-1/5)` over the
/// finite samples. Falls back to the other spread measure when one is zero,
/// and to a thousandth of the (common) value when all samples are equal, so
/// the result is always positive and finite (1e-3 for no samples).
pub fn silverman_bandwidth(samples: &[f64]) -> f64 {
    let s = finite_sorted(samples);
    let n = s.len();
    if n == 0 {
        return 1e-3;
    }
    let mean = s.iter().sum::<f64>() / n as f64;
    let std = if n > 1 {
        let var = s.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1) as f64;
        var.sqrt()
    } else {
        0.0
    };
    let iqr =
        (crate::uq::moments::quantile(&s, 0.75) - crate::uq::moments::quantile(&s, 0.25)) / 1.34;
    let spread = match (std > 0.0, iqr > 0.0) {
        (true, true) => std.min(iqr),
        (true, false) => std,
        (false, true) => iqr,
        (false, false) => degenerate_scale(mean),
    };
    0.9 * spread * (n as f64).powf(-0.2)
}

/// Gaussian kernel density estimate at the `grid` points:
/// `sum_i w_i phi((x - x_i) / h) / h` with weights normalised to sum 1
/// (equal weights when `weights` is `None`). Non-finite samples are ignored;
/// a non-positive or non-finite `bandwidth` is replaced by
/// [`silverman_bandwidth`]. Zeros when there is no sample; NaN when the
/// weights do not have a positive finite sum.
///
/// Cost `O((n + grid) log n + grid * k)` with `k` the samples within
/// 8 bandwidths of a grid point.
///
/// # Panics
/// If `weights` is given with a length different from `samples`.
pub fn gaussian_kde(
    samples: &[f64],
    weights: Option<&[f64]>,
    grid: &[f64],
    bandwidth: f64,
) -> Vec<f64> {
    if let Some(w) = weights {
        assert_eq!(w.len(), samples.len(), "one weight per sample");
    }
    let mut pairs: Vec<(f64, f64)> = samples
        .iter()
        .enumerate()
        .filter(|(_, x)| x.is_finite())
        .map(|(i, &x)| (x, weights.map_or(1.0, |w| w[i])))
        .collect();
    if pairs.is_empty() {
        return vec![0.0; grid.len()];
    }
    let total: f64 = pairs.iter().map(|p| p.1).sum();
    if !(total > 0.0 && total.is_finite()) {
        return vec![f64::NAN; grid.len()];
    }
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    let h = if bandwidth > 0.0 && bandwidth.is_finite() {
        bandwidth
    } else {
        let xs: Vec<f64> = pairs.iter().map(|p| p.0).collect();
        silverman_bandwidth(&xs)
    };
    let scale = 1.0 / (total * h);
    grid.iter()
        .map(|&g| {
            let lo = pairs.partition_point(|p| p.0 < g - CUTOFF * h);
            let hi = pairs.partition_point(|p| p.0 <= g + CUTOFF * h);
            let s: f64 = pairs[lo..hi.max(lo)]
                .iter()
                .map(|&(x, w)| w * norm_pdf((g - x) / h))
                .sum();
            s * scale
        })
        .collect()
}

/// `n` equally spaced points from `min` to `max` (both included; swapped if
/// given in the wrong order). When `min == max` the range is widened to
/// `value +- 5e-3 |value|` (or `+- 5e-3` around 0), matching the fallback
/// bandwidth of [`silverman_bandwidth`]. Empty for `n = 0` or non-finite
/// bounds; the midpoint for `n = 1`.
pub fn auto_grid(min: f64, max: f64, n: usize) -> Vec<f64> {
    if n == 0 || !min.is_finite() || !max.is_finite() {
        return Vec::new();
    }
    let (mut a, mut b) = if min <= max { (min, max) } else { (max, min) };
    if a == b {
        let d = 5.0 * degenerate_scale(a);
        a -= d;
        b += d;
    }
    if n == 1 {
        return vec![0.5 * (a + b)];
    }
    let step = (b - a) / (n - 1) as f64;
    (0..n)
        .map(|i| if i == n - 1 { b } else { a + step * i as f64 })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::uq::rng;

    fn trapezoid(x: &[f64], y: &[f64]) -> f64 {
        x.windows(2)
            .zip(y.windows(2))
            .map(|(x, y)| 0.5 * (x[1] - x[0]) * (y[0] + y[1]))
            .sum()
    }

    fn normal_samples(n: usize, seed: u64) -> Vec<f64> {
        (0..n as u64)
            .map(|i| rng::standard_normal(&mut rng::stream(seed, i)))
            .collect()
    }

    #[test]
    fn integrates_to_one() {
        let xs = [0.0, 0.1, 0.5, 2.0, 2.2, 7.0];
        let h = silverman_bandwidth(&xs);
        let grid = auto_grid(-10.0, 20.0, 3001);
        let f = gaussian_kde(&xs, None, &grid, h);
        assert!((trapezoid(&grid, &f) - 1.0).abs() < 1e-9);
        let w = [1.0, 2.0, 3.0, 0.5, 0.5, 3.0];
        let f = gaussian_kde(&xs, Some(&w), &grid, 0.7);
        assert!((trapezoid(&grid, &f) - 1.0).abs() < 1e-9);
    }

    #[test]
    fn recovers_a_standard_normal_density() {
        let xs = normal_samples(20_000, 17);
        let h = silverman_bandwidth(&xs);
        assert!(h > 0.1 && h < 0.2, "{h}");
        let grid = auto_grid(-4.0, 4.0, 81);
        let f = gaussian_kde(&xs, None, &grid, h);
        for (g, v) in grid.iter().zip(&f) {
            assert!((v - norm_pdf(*g)).abs() < 0.015, "x={g}: {v}");
        }
    }

    #[test]
    fn cutoff_matches_the_full_sum() {
        let xs = normal_samples(500, 3);
        let grid = auto_grid(-5.0, 5.0, 41);
        let h = 0.3;
        let f = gaussian_kde(&xs, None, &grid, h);
        for (g, v) in grid.iter().zip(&f) {
            let full: f64 = xs.iter().map(|x| norm_pdf((g - x) / h)).sum::<f64>() / (500.0 * h);
            // Each skipped kernel is below phi(8) / phi(0) = 1.3e-14 of a peak.
            assert!((v - full).abs() <= 1e-14 * full + 1e-14 / h);
        }
    }

    #[test]
    fn degenerate_input_gives_finite_values() {
        let xs = [2.5; 100];
        let h = silverman_bandwidth(&xs);
        assert!(h > 0.0 && h.is_finite());
        let grid = auto_grid(2.5, 2.5, 51);
        assert_eq!(grid.len(), 51);
        assert!(grid[0] < 2.5 && grid[50] > 2.5);
        let f = gaussian_kde(&xs, None, &grid, h);
        assert!(f.iter().all(|v| v.is_finite()));
        assert!((trapezoid(&grid, &f) - 1.0).abs() < 1e-6);
        let zeros = [0.0; 10];
        let h0 = silverman_bandwidth(&zeros);
        assert!(h0 > 0.0);
        let f = gaussian_kde(&zeros, None, &auto_grid(0.0, 0.0, 11), h0);
        assert!(f.iter().all(|v| v.is_finite()) && f[5] > 0.0);
        // One sample, no sample, NaN samples, bad bandwidth.
        assert!(silverman_bandwidth(&[1.0]) > 0.0);
        assert!(silverman_bandwidth(&[]) > 0.0);
        assert_eq!(gaussian_kde(&[], None, &[0.0, 1.0], 1.0), vec![0.0, 0.0]);
        let f = gaussian_kde(&[f64::NAN, 1.0, 2.0], None, &[1.5], f64::NAN);
        assert!(f[0].is_finite() && f[0] > 0.0);
        assert!(gaussian_kde(&[1.0], Some(&[0.0]), &[1.0], 1.0)[0].is_nan());
    }

    #[test]
    fn silverman_uses_the_smaller_spread() {
        // IQR of 1..=9 is 4 (type 7): 4/1.34 = 2.99 < std = 2.74? No: std smaller.
        let xs: Vec<f64> = (1..=9).map(f64::from).collect();
        let std = 7.5f64.sqrt();
        let want = 0.9 * std.min(4.0 / 1.34) * 9f64.powf(-0.2);
        assert!((silverman_bandwidth(&xs) - want).abs() < 1e-15);
        // Heavy outlier: the IQR wins.
        let mut ys = xs.clone();
        ys.push(1e6);
        let h = silverman_bandwidth(&ys);
        assert!(h < 5.0, "{h}");
    }

    #[test]
    fn grids() {
        assert_eq!(auto_grid(0.0, 1.0, 5), vec![0.0, 0.25, 0.5, 0.75, 1.0]);
        assert_eq!(auto_grid(1.0, 0.0, 3), vec![0.0, 0.5, 1.0]);
        assert_eq!(auto_grid(0.0, 1.0, 1), vec![0.5]);
        assert!(auto_grid(0.0, 1.0, 0).is_empty());
        assert!(auto_grid(f64::NAN, 1.0, 10).is_empty());
        let g = auto_grid(-3.0, -3.0, 3);
        assert_eq!(g, vec![-3.015, -3.0, -2.985]);
    }
}
