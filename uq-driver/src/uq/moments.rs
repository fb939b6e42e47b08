//! Moments, quantiles and exceedance probabilities of ensembles.
//!
//! An ensemble is a `DMatrix<f64>` with one row per point/sample and one
//! column per time step (or output); nalgebra stores it column-major, so each
//! time step is contiguous. Per-column results are returned in column order.

use nalgebra::DMatrix;

/// Mean and unbiased (`M - 1`) standard deviation of `xs` by the corrected
/// two-pass algorithm. `(NaN, NaN)` when empty; std NaN for one sample.
fn mean_std(xs: &[f64]) -> (f64, f64) {
    let m = xs.len();
    if m == 0 {
        return (f64::NAN, f64::NAN);
    }
    let mean = xs.iter().sum::<f64>() / m as f64;
    if m < 2 {
        return (mean, f64::NAN);
    }
    let (mut s1, mut s2) = (0.0, 0.0);
    for &x in xs {
        let d = x - mean;
        s1 += d;
        s2 += d * d;
    }
    // The s1 term corrects the rounding error of the mean (of the mean itself, too: equal
    // values give exactly that value).
    let var = (s2 - s1 * s1 / m as f64) / (m - 1) as f64;
    (mean + s1 / m as f64, var.max(0.0).sqrt())
}

/// Per-column sample mean and unbiased (`M - 1`) standard deviation of an
/// ensemble with `M` rows (numerically stable two-pass algorithm).
/// With no rows both are NaN; with one row the std is NaN.
pub fn sample_mean_std(values: &DMatrix<f64>) -> (Vec<f64>, Vec<f64>) {
    values.column_iter().map(|c| mean_std(c.as_slice())).unzip()
}

/// Per-column weighted mean `mu = sum w f` and standard deviation
/// `sqrt(sum w (f - mu)^2)` with quadrature weights (one per row, meant to
/// sum to 1; they are divided by their sum, which is harmless when it is 1).
/// Negative weights (e.g. sparse grids) are allowed: a slightly negative
/// variance from rounding is clamped to 0.
///
/// # Panics
/// If `weights.len() != values.nrows()`.
pub fn weighted_mean_std(values: &DMatrix<f64>, weights: &[f64]) -> (Vec<f64>, Vec<f64>) {
    assert_eq!(weights.len(), values.nrows(), "one weight per row");
    let total: f64 = weights.iter().sum();
    values
        .column_iter()
        .map(|c| {
            let mean = c.iter().zip(weights).map(|(f, w)| w * f).sum::<f64>() / total;
            let (mut s1, mut s2) = (0.0, 0.0);
            for (f, w) in c.iter().zip(weights) {
                let d = f - mean;
                s1 += w * d;
                s2 += w * d * d;
            }
            // The s1 term corrects the rounding error of the mean.
            let var = (s2 - s1 * s1 / total) / total;
            (mean, var.max(0.0).sqrt())
        })
        .unzip()
}

/// Quantile of already sorted (ascending) data by linear interpolation
/// between order statistics (Hyndman–Fan type 7, the default of R and
/// NumPy): `h = (n - 1) p`, `x[floor h] + (h - floor h) (x[floor h + 1] - x[floor h])`.
/// NaN for empty data or `p` outside `[0, 1]`.
pub fn quantile(sorted: &[f64], p: f64) -> f64 {
    let n = sorted.len();
    if n == 0 || !(0.0..=1.0).contains(&p) {
        return f64::NAN;
    }
    let h = (n - 1) as f64 * p;
    let lo = (h.floor() as usize).min(n - 1);
    let hi = (lo + 1).min(n - 1);
    let frac = h - lo as f64;
    if frac == 0.0 {
        sorted[lo]
    } else {
        sorted[lo] + frac * (sorted[hi] - sorted[lo])
    }
}

/// Fraction of samples strictly above `limit` and its binomial standard
/// error `sqrt(p (1 - p) / n)`. `(NaN, NaN)` for no samples. Note that the
/// standard error is 0 when no sample exceeds: then `p < 3/n` at 95 %
/// confidence (rule of three) is the useful statement.
pub fn exceedance_probability(samples: &[f64], limit: f64) -> (f64, f64) {
    let n = samples.len();
    if n == 0 {
        return (f64::NAN, f64::NAN);
    }
    let k = samples.iter().filter(|&&x| x > limit).count();
    let p = k as f64 / n as f64;
    (p, (p * (1.0 - p) / n as f64).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mean_of_equal_values_is_that_value_exactly() {
        // 0.1 + 0.2 + ... in floating point rounds; the corrected mean does not.
        for x in [0.1, 1.0 / 3.0, 2.000_000_000_000_001_3, -7.7e-3] {
            for m in [3, 10, 50, 1001] {
                let (mean, std) = mean_std(&vec![x; m]);
                assert_eq!(mean, x, "{m} copies of {x}");
                assert_eq!(std, 0.0);
            }
        }
    }
    use crate::uq::quadrature::gauss_hermite;

    #[test]
    fn sample_mean_std_per_column() {
        // Columns: 1..=5, constant 7, and 2 x.
        let m = DMatrix::from_fn(5, 3, |r, c| {
            let x = (r + 1) as f64;
            [x, 7.0, 2.0 * x][c]
        });
        let (mean, std) = sample_mean_std(&m);
        assert_eq!(mean, vec![3.0, 7.0, 6.0]);
        assert!((std[0] - 2.5f64.sqrt()).abs() < 1e-15);
        assert_eq!(std[1], 0.0);
        assert!((std[2] - 2.0 * 2.5f64.sqrt()).abs() < 1e-15);
    }

    #[test]
    fn sample_std_is_stable_with_a_large_offset() {
        // Naive sum-of-squares loses everything here.
        let m = DMatrix::from_fn(4, 1, |r, _| 1e9 + [4.0, 7.0, 13.0, 16.0][r]);
        let (mean, std) = sample_mean_std(&m);
        assert_eq!(mean[0], 1e9 + 10.0);
        assert!((std[0] - 30f64.sqrt()).abs() < 1e-6);
    }

    #[test]
    fn degenerate_ensembles() {
        let (mean, std) = sample_mean_std(&DMatrix::from_element(1, 2, 3.0));
        assert_eq!(mean, vec![3.0, 3.0]);
        assert!(std.iter().all(|s| s.is_nan()));
        let (mean, _) = sample_mean_std(&DMatrix::zeros(0, 2));
        assert!(mean.iter().all(|m| m.is_nan()));
    }

    #[test]
    fn weighted_moments_with_gauss_hermite_weights() {
        // f = 3 + 2 z and f = z^2 on 5 Gauss-Hermite nodes: exact moments.
        let (x, w) = gauss_hermite(5).unwrap();
        let m = DMatrix::from_fn(5, 2, |r, c| [3.0 + 2.0 * x[r], x[r] * x[r]][c]);
        let (mean, std) = weighted_mean_std(&m, &w);
        assert!((mean[0] - 3.0).abs() < 1e-14);
        assert!((std[0] - 2.0).abs() < 1e-14);
        assert!((mean[1] - 1.0).abs() < 1e-14);
        assert!((std[1] - 2f64.sqrt()).abs() < 1e-14);
        // Constant column: zero to rounding, never NaN from a negative variance.
        let c = DMatrix::from_element(5, 1, 0.1);
        let (_, std) = weighted_mean_std(&c, &w);
        assert!(std[0] >= 0.0 && std[0] < 1e-16);
    }

    #[test]
    fn type7_quantiles() {
        let s = [1.0, 2.0, 3.0, 4.0, 5.0];
        assert_eq!(quantile(&s, 0.0), 1.0);
        assert_eq!(quantile(&s, 1.0), 5.0);
        assert_eq!(quantile(&s, 0.5), 3.0);
        assert!((quantile(&s, 0.1) - 1.4).abs() < 1e-15);
        assert!((quantile(&[10.0, 20.0], 0.25) - 12.5).abs() < 1e-15);
        assert_eq!(quantile(&[4.0], 0.3), 4.0);
        assert!(quantile(&[], 0.5).is_nan());
        assert!(quantile(&s, 1.5).is_nan());
        assert!(quantile(&s, f64::NAN).is_nan());
    }

    #[test]
    fn exceedance() {
        let xs: Vec<f64> = (0..1000).map(f64::from).collect();
        let (p, se) = exceedance_probability(&xs, 899.0);
        assert_eq!(p, 0.1);
        assert!((se - (0.09f64 / 1000.0).sqrt()).abs() < 1e-15);
        assert_eq!(exceedance_probability(&xs, 999.0), (0.0, 0.0));
        let (p, se) = exceedance_probability(&[], 0.0);
        assert!(p.is_nan() && se.is_nan());
    }
}
