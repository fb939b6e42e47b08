//! Support, moments, density, CDF, survival function and quantile of every family.

use super::shapes::Shape;
use super::truncated::{clamp_to, Trunc};
use super::Distribution;
use crate::uq::special::{norm_cdf, norm_isf, norm_pdf, norm_ppf, norm_sf};

impl Distribution {
    /// The standard shape of a Beta, Gamma or Weibull input and the affine map
    /// `x = offset + scale · s` from it.
    fn shape(&self) -> Option<(Shape, f64, f64)> {
        match *self {
            Distribution::Beta {
                alpha,
                beta,
                low,
                high,
            } => Some((Shape::Beta(alpha, beta), low, high - low)),
            Distribution::Gamma { shape, scale } => Some((Shape::Gamma(shape), 0.0, scale)),
            Distribution::Weibull { shape, scale } => Some((Shape::Weibull(shape), 0.0, scale)),
            _ => None,
        }
    }

    /// Number of values of an integer uniform input (no overflow for any `low`, `high`).
    pub(super) fn count(low: i64, high: i64) -> f64 {
        (i128::from(high) - i128::from(low)) as f64 + 1.0
    }

    /// Support `(lower, upper)` (possibly infinite; for the integer uniform its smallest and
    /// largest values).
    pub fn support(&self) -> (f64, f64) {
        match *self {
            Distribution::Normal { .. } => (f64::NEG_INFINITY, f64::INFINITY),
            Distribution::LogNormal { .. } => (0.0, f64::INFINITY),
            Distribution::Uniform { low, high }
            | Distribution::TruncatedNormal { low, high, .. }
            | Distribution::Beta { low, high, .. } => (low, high),
            Distribution::Gamma { .. } | Distribution::Weibull { .. } => (0.0, f64::INFINITY),
            Distribution::IntegerUniform { low, high } => (low as f64, high as f64),
        }
    }

    /// Mean of the distribution.
    pub fn mean(&self) -> f64 {
        if let Some((s, offset, scale)) = self.shape() {
            return offset + scale * s.moments().0;
        }
        match *self {
            Distribution::Normal { mean, .. } => mean,
            Distribution::LogNormal { mu, sigma } => (mu + 0.5 * sigma * sigma).exp(),
            Distribution::Uniform { low, high } => 0.5 * (low + high),
            Distribution::TruncatedNormal {
                mean,
                std,
                low,
                high,
            } => mean + std * Trunc::new(mean, std, low, high).moments().0,
            Distribution::IntegerUniform { low, high } => 0.5 * (low as f64 + high as f64),
            Distribution::Beta { .. }
            | Distribution::Gamma { .. }
            | Distribution::Weibull { .. } => {
                unreachable!("shapes handled above")
            }
        }
    }

    /// Standard deviation of the distribution.
    pub fn std(&self) -> f64 {
        if let Some((s, _, scale)) = self.shape() {
            return scale * s.moments().1.max(0.0).sqrt();
        }
        match *self {
            Distribution::Normal { std, .. } => std,
            Distribution::LogNormal { mu, sigma } => {
                let s2 = sigma * sigma;
                s2.exp_m1().sqrt() * (mu + 0.5 * s2).exp()
            }
            Distribution::Uniform { low, high } => (high - low) / 12f64.sqrt(),
            Distribution::TruncatedNormal {
                mean,
                std,
                low,
                high,
            } => std * Trunc::new(mean, std, low, high).moments().1,
            Distribution::IntegerUniform { low, high } => {
                let n = Self::count(low, high);
                ((n * n - 1.0) / 12.0).sqrt()
            }
            Distribution::Beta { .. }
            | Distribution::Gamma { .. }
            | Distribution::Weibull { .. } => {
                unreachable!("shapes handled above")
            }
        }
    }

    /// Probability density at `x` (for the integer uniform: the probability mass at an
    /// integer of the support, else 0).
    pub fn pdf(&self, x: f64) -> f64 {
        if x.is_nan() {
            return f64::NAN;
        }
        if let Some((s, offset, scale)) = self.shape() {
            return s.pdf((x - offset) / scale) / scale;
        }
        match *self {
            Distribution::Normal { mean, std } => norm_pdf((x - mean) / std) / std,
            Distribution::LogNormal { mu, sigma } => {
                if x <= 0.0 || x.is_infinite() {
                    0.0
                } else {
                    norm_pdf((x.ln() - mu) / sigma) / (sigma * x)
                }
            }
            Distribution::Uniform { low, high } => {
                if (low..=high).contains(&x) {
                    1.0 / (high - low)
                } else {
                    0.0
                }
            }
            Distribution::TruncatedNormal {
                mean,
                std,
                low,
                high,
            } => {
                if (low..=high).contains(&x) {
                    let t = Trunc::new(mean, std, low, high);
                    norm_pdf((x - mean) / std) / (std * t.mass)
                } else {
                    0.0
                }
            }
            Distribution::IntegerUniform { low, high } => {
                if x.fract() == 0.0 && x >= low as f64 && x <= high as f64 {
                    1.0 / Self::count(low, high)
                } else {
                    0.0
                }
            }
            Distribution::Beta { .. }
            | Distribution::Gamma { .. }
            | Distribution::Weibull { .. } => {
                unreachable!("shapes handled above")
            }
        }
    }

    /// Cumulative distribution function `P(X <= x)`, accurate in relative
    /// terms in the lower tail.
    pub fn cdf(&self, x: f64) -> f64 {
        self.tail(x, false)
    }

    /// Survival function `P(X > x)`, accurate in relative terms in the upper
    /// tail (use it for small exceedance probabilities).
    pub fn sf(&self, x: f64) -> f64 {
        self.tail(x, true)
    }

    /// `P(X > x)` if `upper`, else `P(X <= x)`, each computed directly (not as one minus
    /// the other).
    fn tail(&self, x: f64, upper: bool) -> f64 {
        if x.is_nan() {
            return f64::NAN;
        }
        if let Some((s, offset, scale)) = self.shape() {
            let y = (x - offset) / scale;
            return if upper { s.sf(y) } else { s.cdf(y) };
        }
        let phi = if upper { norm_sf } else { norm_cdf };
        match *self {
            Distribution::Normal { mean, std } => phi((x - mean) / std),
            Distribution::LogNormal { mu, sigma } => {
                if x <= 0.0 {
                    f64::from(u8::from(upper))
                } else {
                    phi((x.ln() - mu) / sigma)
                }
            }
            Distribution::Uniform { low, high } => {
                let inside = if upper { high - x } else { x - low };
                (inside / (high - low)).clamp(0.0, 1.0)
            }
            Distribution::TruncatedNormal {
                mean,
                std,
                low,
                high,
            } => {
                let t = Trunc::new(mean, std, low, high);
                let z = (x - mean) / std;
                if upper {
                    t.sf(z)
                } else {
                    t.cdf(z)
                }
            }
            Distribution::IntegerUniform { low, high } => {
                // Values <= x: floor(x) - low + 1, clamped to the support.
                let n = Self::count(low, high);
                let below = clamp_to(x.floor() - low as f64 + 1.0, 0.0, n);
                if upper {
                    (n - below) / n
                } else {
                    below / n
                }
            }
            Distribution::Beta { .. }
            | Distribution::Gamma { .. }
            | Distribution::Weibull { .. } => {
                unreachable!("shapes handled above")
            }
        }
    }

    /// Quantile (inverse CDF) at probability `u` in `[0, 1]` (NaN outside).
    /// `u = 0` and `u = 1` give the ends of the support. For the integer uniform, the
    /// smallest value `k` with `P(X <= k) >= u`.
    pub fn inverse_cdf(&self, u: f64) -> f64 {
        if u.is_nan() || !(0.0..=1.0).contains(&u) {
            return f64::NAN;
        }
        // 1 - u is exact for u >= 1/2, where it is used.
        self.quantile(u, 1.0 - u)
    }

    /// Quantile from `u` and `v = 1 - u`, using whichever is accurate.
    pub(super) fn quantile(&self, u: f64, v: f64) -> f64 {
        if u == 0.0 {
            return self.support().0;
        }
        if v == 0.0 {
            return self.support().1;
        }
        if let Some((s, offset, scale)) = self.shape() {
            let x = offset + scale * s.quantile(u, v, u <= 0.5);
            let (lo, hi) = self.support();
            return clamp_to(x, lo, hi);
        }
        let z_of = |u: f64, v: f64| if u <= 0.5 { norm_ppf(u) } else { norm_isf(v) };
        match *self {
            Distribution::Normal { mean, std } => mean + std * z_of(u, v),
            Distribution::LogNormal { mu, sigma } => (mu + sigma * z_of(u, v)).exp(),
            Distribution::Uniform { low, high } => {
                let x = if u <= 0.5 {
                    low + u * (high - low)
                } else {
                    high - v * (high - low)
                };
                clamp_to(x, low, high)
            }
            Distribution::TruncatedNormal {
                mean,
                std,
                low,
                high,
            } => {
                let z = Trunc::new(mean, std, low, high).quantile(u, v);
                clamp_to(mean + std * z, low, high)
            }
            Distribution::IntegerUniform { low, high } => {
                let n = Self::count(low, high);
                // The k-th value (from 0) covers u in ((k)/n, (k+1)/n].
                let k = if u <= 0.5 {
                    (u * n).ceil() - 1.0
                } else {
                    n - 1.0 - (v * n).floor()
                };
                clamp_to(
                    low as f64 + clamp_to(k, 0.0, n - 1.0),
                    low as f64,
                    high as f64,
                )
            }
            Distribution::Beta { .. }
            | Distribution::Gamma { .. }
            | Distribution::Weibull { .. } => {
                unreachable!("shapes handled above")
            }
        }
    }
}
