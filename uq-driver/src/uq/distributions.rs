//! Probability distributions of uncertain inputs and their isoprobabilistic
//! maps from the unit interval (sampling) and from the standard normal
//! (collocation).
//!
//! Tails are handled with complementary probabilities: for an upper-tail
//! point, `1 - u` is carried explicitly instead of being recomputed from `u`,
//! so that Gauss–Hermite nodes at 10 sigma still map to distinct,
//! correctly ordered physical values.

use std::sync::OnceLock;

use serde::{Deserialize, Serialize};

use crate::uq::quadrature::gauss_legendre;
use crate::uq::special::{norm_cdf, norm_isf, norm_pdf, norm_ppf, norm_sf};

/// Errors of the distribution constructors and of [`Distribution::validate`].
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum DistributionError {
    /// A parameter is NaN or infinite.
    #[error("`{name}` must be finite (got {value})")]
    NotFinite {
        /// Parameter name.
        name: &'static str,
        /// Offending value.
        value: f64,
    },
    /// A parameter that must be strictly positive is not.
    #[error("`{name}` must be positive (got {value})")]
    NotPositive {
        /// Parameter name.
        name: &'static str,
        /// Offending value.
        value: f64,
    },
    /// A coefficient of variation was given for a zero mean.
    #[error("a coefficient of variation needs a nonzero mean")]
    ZeroMeanCov,
    /// The bounds do not satisfy `low < high` (or one is NaN).
    #[error("`low` must be below `high` (got low = {low}, high = {high})")]
    EmptyInterval {
        /// Lower bound.
        low: f64,
        /// Upper bound.
        high: f64,
    },
    /// The truncation interval has (numerically) zero probability.
    #[error(
        "the interval [{low}, {high}] has negligible probability under a normal \
         with mean {mean} and std {std}"
    )]
    NegligibleMass {
        /// Mean of the parent normal.
        mean: f64,
        /// Standard deviation of the parent normal.
        std: f64,
        /// Lower bound.
        low: f64,
        /// Upper bound.
        high: f64,
    },
    /// The mean or standard deviation of the distribution overflows.
    #[error("the mean or standard deviation of the distribution is not finite")]
    MomentsNotFinite,
}

/// A one-dimensional input distribution.
///
/// Serialized with a `kind` tag, e.g. `{"kind": "normal", "mean": 1.0, "std": 0.1}`;
/// the log-normal kind is `log_normal` (`lognormal` is accepted on input).
/// Deserialization does not validate: call [`Distribution::validate`] on
/// deserialized values (the constructors validate).
/// Infinite truncation bounds are allowed but cannot be written as JSON
/// (they become `null`); TOML (`inf`) handles them.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Distribution {
    /// Normal with the given mean and standard deviation (same units as the input).
    Normal {
        /// Mean.
        mean: f64,
        /// Standard deviation (> 0).
        std: f64,
    },
    /// Log-normal: `exp(mu + sigma Z)` with `Z ~ N(0, 1)`.
    #[serde(alias = "lognormal")]
    LogNormal {
        /// Mean of the underlying normal (of `ln X`).
        mu: f64,
        /// Standard deviation of the underlying normal (> 0).
        sigma: f64,
    },
    /// Uniform on `[low, high]`.
    Uniform {
        /// Lower bound.
        low: f64,
        /// Upper bound (> low).
        high: f64,
    },
    /// Normal with parameters `mean`, `std`, conditioned on `[low, high]`
    /// (bounds may be infinite for one-sided truncation). `mean` and `std`
    /// are those of the parent normal, not of the truncated distribution.
    TruncatedNormal {
        /// Mean of the parent normal.
        mean: f64,
        /// Standard deviation of the parent normal (> 0).
        std: f64,
        /// Lower bound (may be `-inf`).
        low: f64,
        /// Upper bound (may be `+inf`, > low).
        high: f64,
    },
}

fn finite(name: &'static str, value: f64) -> Result<f64, DistributionError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(DistributionError::NotFinite { name, value })
    }
}

fn positive(name: &'static str, value: f64) -> Result<f64, DistributionError> {
    finite(name, value)?;
    if value > 0.0 {
        Ok(value)
    } else {
        Err(DistributionError::NotPositive { name, value })
    }
}

/// Standardised truncation interval of a truncated normal.
struct Trunc {
    alpha: f64,
    beta: f64,
    /// `Phi(alpha)`: mass below the interval.
    cdf_alpha: f64,
    /// `Q(beta)`: mass above the interval.
    sf_beta: f64,
    /// `Phi(beta) - Phi(alpha)`, computed without cancellation of large terms.
    mass: f64,
}

impl Trunc {
    fn new(mean: f64, std: f64, low: f64, high: f64) -> Self {
        let alpha = (low - mean) / std;
        let beta = (high - mean) / std;
        let cdf_alpha = norm_cdf(alpha);
        let sf_beta = norm_sf(beta);
        let mass = if alpha.is_finite() && is_short(alpha, beta - alpha) {
            // Narrow interval: integrate instead of subtracting close numbers.
            norm_pdf(alpha) * increment_integral(alpha, beta - alpha)
        } else if alpha >= 0.0 {
            norm_sf(alpha) - sf_beta
        } else if beta <= 0.0 {
            norm_cdf(beta) - cdf_alpha
        } else {
            1.0 - cdf_alpha - sf_beta
        };
        Trunc {
            alpha,
            beta,
            cdf_alpha,
            sf_beta,
            mass,
        }
    }

    /// Standardised quantile for probability `u` with `v = 1 - u` given
    /// separately (both accurate).
    fn quantile(&self, u: f64, v: f64) -> f64 {
        // Near a finite bound, solve for the (small) distance to it directly,
        // so that points near the bound keep their relative resolution.
        if u <= 0.5 && self.alpha.is_finite() {
            if let Some(d) = increment_for(self.alpha, u * self.mass / norm_pdf(self.alpha)) {
                return (self.alpha + d).clamp(self.alpha, self.beta);
            }
        }
        if v <= 0.5 && self.beta.is_finite() {
            if let Some(d) = increment_for(-self.beta, v * self.mass / norm_pdf(self.beta)) {
                return (self.beta - d).clamp(self.alpha, self.beta);
            }
        }
        let z = if self.alpha >= 0.0 {
            // Q(z) = Q(beta) + v Z: a sum of positive terms.
            norm_isf(self.sf_beta + v * self.mass)
        } else if self.beta <= 0.0 {
            norm_ppf(self.cdf_alpha + u * self.mass)
        } else {
            let t = self.cdf_alpha + u * self.mass;
            if t <= 0.5 {
                norm_ppf(t)
            } else {
                norm_isf(self.sf_beta + v * self.mass)
            }
        };
        z.clamp(self.alpha, self.beta)
    }

    /// `P(alpha < Z <= z) / mass`.
    fn cdf(&self, z: f64) -> f64 {
        if z <= self.alpha {
            0.0
        } else if z >= self.beta {
            1.0
        } else if is_short(self.alpha, z - self.alpha) {
            (norm_pdf(self.alpha) * increment_integral(self.alpha, z - self.alpha) / self.mass)
                .clamp(0.0, 1.0)
        } else if self.alpha >= 0.0 {
            ((norm_sf(self.alpha) - norm_sf(z)) / self.mass).clamp(0.0, 1.0)
        } else {
            ((norm_cdf(z) - self.cdf_alpha) / self.mass).clamp(0.0, 1.0)
        }
    }

    /// `P(Z > z) / mass` for `alpha < z < beta`.
    fn sf(&self, z: f64) -> f64 {
        if z <= self.alpha {
            1.0
        } else if z >= self.beta {
            0.0
        } else if is_short(-self.beta, self.beta - z) {
            (norm_pdf(self.beta) * increment_integral(-self.beta, self.beta - z) / self.mass)
                .clamp(0.0, 1.0)
        } else if self.beta <= 0.0 {
            ((norm_cdf(self.beta) - norm_cdf(z)) / self.mass).clamp(0.0, 1.0)
        } else {
            ((norm_sf(z) - self.sf_beta) / self.mass).clamp(0.0, 1.0)
        }
    }

    /// Mean and standard deviation of the standardised truncated variable.
    fn moments(&self) -> (f64, f64) {
        let (a, b) = (self.alpha, self.beta);
        if b - a <= 2.0 {
            // Narrow interval: the closed form cancels; integrate instead.
            // Density relative to phi(c): exp(-(c h u + h^2 u^2 / 2)).
            let (nodes, weights) = legendre_24();
            let c = 0.5 * (a + b);
            let h = 0.5 * (b - a);
            let f: Vec<f64> = nodes
                .iter()
                .zip(weights)
                .map(|(&u, &w)| w * (-(c * h * u + 0.5 * h * h * u * u)).exp())
                .collect();
            let s: f64 = f.iter().sum();
            let mu: f64 = f.iter().zip(nodes).map(|(f, u)| f * u).sum::<f64>() / s;
            let var: f64 = f
                .iter()
                .zip(nodes)
                .map(|(f, u)| f * (u - mu) * (u - mu))
                .sum::<f64>()
                / s;
            return (c + h * mu, h * var.max(0.0).sqrt());
        }
        let xphi = |x: f64| if x.is_finite() { x * norm_pdf(x) } else { 0.0 };
        let lambda = (norm_pdf(a) - norm_pdf(b)) / self.mass;
        let var = 1.0 + (xphi(a) - xphi(b)) / self.mass - lambda * lambda;
        (lambda, var.max(0.0).sqrt())
    }
}

/// Whether `[a, a + d]` is short enough for [`increment_integral`] to be
/// exact to rounding (the integrand varies by at most a factor e^4 or so).
fn is_short(a: f64, d: f64) -> bool {
    d.is_finite() && d * a.abs().max((a + d).abs()).max(1.0) <= 4.0
}

/// `int_0^d exp(-a t - t^2 / 2) dt = (Phi(a + d) - Phi(a)) / phi(a)`, by
/// 24-point Gauss–Legendre (accurate to rounding when [`is_short`]).
fn increment_integral(a: f64, d: f64) -> f64 {
    let (nodes, weights) = legendre_24();
    let half = 0.5 * d;
    let s: f64 = nodes
        .iter()
        .zip(weights)
        .map(|(&x, &w)| {
            let t = half * (1.0 + x);
            w * (-(a * t + 0.5 * t * t)).exp()
        })
        .sum();
    half * s
}

/// The `d >= 0` with `increment_integral(a, d) = target`, when it is small
/// (`target * max(|a|, 1) <= 0.5`); `None` otherwise.
fn increment_for(a: f64, target: f64) -> Option<f64> {
    if target.is_nan() || target < 0.0 || target * a.abs().max(1.0) > 0.5 {
        return None;
    }
    let mut d = target;
    for _ in 0..30 {
        let slope = (-(a * d + 0.5 * d * d)).exp();
        let step = (increment_integral(a, d) - target) / slope;
        d = (d - step).max(0.0);
        if step.abs() <= 1e-16 * d {
            break;
        }
    }
    Some(d)
}

/// The 24-point Gauss–Legendre rule, computed once.
fn legendre_24() -> (&'static [f64], &'static [f64]) {
    static RULE: OnceLock<(Vec<f64>, Vec<f64>)> = OnceLock::new();
    let rule = RULE.get_or_init(|| gauss_legendre(24).unwrap_or_default());
    (&rule.0, &rule.1)
}

impl Distribution {
    /// Normal distribution; `std` must be finite and positive, `mean` finite.
    pub fn normal(mean: f64, std: f64) -> Result<Self, DistributionError> {
        let d = Distribution::Normal { mean, std };
        d.validate()?;
        Ok(d)
    }

    /// Normal distribution from its mean and coefficient of variation
    /// (`std = |mean| * cov`); `mean` must be nonzero, `cov` positive.
    pub fn normal_cov(mean: f64, cov: f64) -> Result<Self, DistributionError> {
        finite("mean", mean)?;
        positive("cov", cov)?;
        if mean == 0.0 {
            return Err(DistributionError::ZeroMeanCov);
        }
        Self::normal(mean, mean.abs() * cov)
    }

    /// Log-normal distribution from the parameters of the underlying normal.
    pub fn lognormal(mu: f64, sigma: f64) -> Result<Self, DistributionError> {
        let d = Distribution::LogNormal { mu, sigma };
        d.validate()?;
        Ok(d)
    }

    /// Log-normal distribution with the given mean and standard deviation
    /// (of the variable itself; both positive):
    /// `sigma^2 = ln(1 + (std/mean)^2)`, `mu = ln(mean) - sigma^2 / 2`.
    pub fn lognormal_from_mean_std(mean: f64, std: f64) -> Result<Self, DistributionError> {
        positive("mean", mean)?;
        positive("std", std)?;
        let cov = std / mean;
        let s2 = (cov * cov).ln_1p();
        Self::lognormal(mean.ln() - 0.5 * s2, s2.sqrt())
    }

    /// Uniform distribution on `[low, high]` (finite, `low < high`).
    pub fn uniform(low: f64, high: f64) -> Result<Self, DistributionError> {
        let d = Distribution::Uniform { low, high };
        d.validate()?;
        Ok(d)
    }

    /// Normal `N(mean, std^2)` truncated to `[low, high]`; the bounds may be
    /// infinite (one-sided truncation) but the interval must carry a
    /// probability of at least `f64::MIN_POSITIVE` under the parent normal.
    pub fn truncated_normal(
        mean: f64,
        std: f64,
        low: f64,
        high: f64,
    ) -> Result<Self, DistributionError> {
        let d = Distribution::TruncatedNormal {
            mean,
            std,
            low,
            high,
        };
        d.validate()?;
        Ok(d)
    }

    /// Checks the parameters (used by the constructors; call it on
    /// deserialized values).
    pub fn validate(&self) -> Result<(), DistributionError> {
        match *self {
            Distribution::Normal { mean, std } => {
                finite("mean", mean)?;
                positive("std", std)?;
            }
            Distribution::LogNormal { mu, sigma } => {
                finite("mu", mu)?;
                positive("sigma", sigma)?;
            }
            Distribution::Uniform { low, high } => {
                finite("low", low)?;
                finite("high", high)?;
                if low >= high || !(high - low).is_finite() {
                    return Err(DistributionError::EmptyInterval { low, high });
                }
            }
            Distribution::TruncatedNormal {
                mean,
                std,
                low,
                high,
            } => {
                finite("mean", mean)?;
                positive("std", std)?;
                if low.is_nan() || high.is_nan() || low >= high {
                    return Err(DistributionError::EmptyInterval { low, high });
                }
                let t = Trunc::new(mean, std, low, high);
                if t.mass.is_nan() || t.mass < f64::MIN_POSITIVE {
                    return Err(DistributionError::NegligibleMass {
                        mean,
                        std,
                        low,
                        high,
                    });
                }
            }
        }
        if !self.mean().is_finite() || !self.std().is_finite() {
            return Err(DistributionError::MomentsNotFinite);
        }
        Ok(())
    }

    /// Whether this is a (non-truncated) normal distribution, i.e. a linear
    /// map of the standard-normal germ.
    pub fn is_gaussian(&self) -> bool {
        matches!(self, Distribution::Normal { .. })
    }

    /// Support `(lower, upper)` (possibly infinite).
    pub fn support(&self) -> (f64, f64) {
        match *self {
            Distribution::Normal { .. } => (f64::NEG_INFINITY, f64::INFINITY),
            Distribution::LogNormal { .. } => (0.0, f64::INFINITY),
            Distribution::Uniform { low, high }
            | Distribution::TruncatedNormal { low, high, .. } => (low, high),
        }
    }

    /// Mean of the distribution.
    pub fn mean(&self) -> f64 {
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
        }
    }

    /// Standard deviation of the distribution.
    pub fn std(&self) -> f64 {
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
        }
    }

    /// Probability density at `x`.
    pub fn pdf(&self, x: f64) -> f64 {
        if x.is_nan() {
            return f64::NAN;
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
        }
    }

    /// Cumulative distribution function `P(X <= x)`, accurate in relative
    /// terms in the lower tail.
    pub fn cdf(&self, x: f64) -> f64 {
        if x.is_nan() {
            return f64::NAN;
        }
        match *self {
            Distribution::Normal { mean, std } => norm_cdf((x - mean) / std),
            Distribution::LogNormal { mu, sigma } => {
                if x <= 0.0 {
                    0.0
                } else {
                    norm_cdf((x.ln() - mu) / sigma)
                }
            }
            Distribution::Uniform { low, high } => ((x - low) / (high - low)).clamp(0.0, 1.0),
            Distribution::TruncatedNormal {
                mean,
                std,
                low,
                high,
            } => Trunc::new(mean, std, low, high).cdf((x - mean) / std),
        }
    }

    /// Survival function `P(X > x)`, accurate in relative terms in the upper
    /// tail (use it for small exceedance probabilities).
    pub fn sf(&self, x: f64) -> f64 {
        if x.is_nan() {
            return f64::NAN;
        }
        match *self {
            Distribution::Normal { mean, std } => norm_sf((x - mean) / std),
            Distribution::LogNormal { mu, sigma } => {
                if x <= 0.0 {
                    1.0
                } else {
                    norm_sf((x.ln() - mu) / sigma)
                }
            }
            Distribution::Uniform { low, high } => ((high - x) / (high - low)).clamp(0.0, 1.0),
            Distribution::TruncatedNormal {
                mean,
                std,
                low,
                high,
            } => Trunc::new(mean, std, low, high).sf((x - mean) / std),
        }
    }

    /// Quantile (inverse CDF) at probability `u` in `[0, 1]` (NaN outside).
    /// `u = 0` and `u = 1` give the ends of the support.
    pub fn inverse_cdf(&self, u: f64) -> f64 {
        if u.is_nan() || !(0.0..=1.0).contains(&u) {
            return f64::NAN;
        }
        // 1 - u is exact for u >= 1/2, where it is used.
        self.quantile(u, 1.0 - u)
    }

    /// Quantile from `u` and `v = 1 - u`, using whichever is accurate.
    fn quantile(&self, u: f64, v: f64) -> f64 {
        if u == 0.0 {
            return self.support().0;
        }
        if v == 0.0 {
            return self.support().1;
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
                x.clamp(low, high)
            }
            Distribution::TruncatedNormal {
                mean,
                std,
                low,
                high,
            } => {
                let z = Trunc::new(mean, std, low, high).quantile(u, v);
                (mean + std * z).clamp(low, high)
            }
        }
    }

    /// Isoprobabilistic map from the standard-normal germ `z` to this
    /// distribution, `F^{-1}(Phi(z))`, as used by stochastic collocation.
    ///
    /// Normal: `mean + std z`; log-normal: `exp(mu + sigma z)` (both exact);
    /// others through the quantile with `Phi(z)` and `1 - Phi(z) = Phi(-z)`
    /// both computed in relative precision, so nodes far in either tail map
    /// to distinct points inside the support.
    pub fn from_standard_normal(&self, z: f64) -> f64 {
        if z.is_nan() {
            return f64::NAN;
        }
        match *self {
            Distribution::Normal { mean, std } => mean + std * z,
            Distribution::LogNormal { mu, sigma } => (mu + sigma * z).exp(),
            _ => self.quantile(norm_cdf(z), norm_sf(z)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol * b.abs().max(1e-300)
    }

    fn all() -> Vec<Distribution> {
        vec![
            Distribution::normal(3.0, 0.5).unwrap(),
            Distribution::lognormal_from_mean_std(2.0e7, 3.0e6).unwrap(),
            Distribution::uniform(-1.0, 4.0).unwrap(),
            Distribution::truncated_normal(1.0, 2.0, 0.0, 3.0).unwrap(),
            Distribution::truncated_normal(0.0, 1.0, 0.0, f64::INFINITY).unwrap(),
            Distribution::truncated_normal(0.0, 1.0, f64::NEG_INFINITY, -4.0).unwrap(),
            Distribution::truncated_normal(10.0, 1.0, 9.7, 9.9).unwrap(),
        ]
    }

    #[test]
    fn constructors_reject_bad_parameters() {
        use DistributionError as E;
        assert!(matches!(
            Distribution::normal(0.0, 0.0),
            Err(E::NotPositive { name: "std", .. })
        ));
        assert!(matches!(
            Distribution::normal(f64::NAN, 1.0),
            Err(E::NotFinite { name: "mean", .. })
        ));
        assert!(matches!(
            Distribution::normal(0.0, f64::INFINITY),
            Err(E::NotFinite { name: "std", .. })
        ));
        assert!(matches!(
            Distribution::normal(1.0, -1.0),
            Err(E::NotPositive { .. })
        ));
        assert_eq!(Distribution::normal_cov(0.0, 0.1), Err(E::ZeroMeanCov));
        assert!(matches!(
            Distribution::normal_cov(1.0, 0.0),
            Err(E::NotPositive { name: "cov", .. })
        ));
        assert!(matches!(
            Distribution::lognormal_from_mean_std(-1.0, 1.0),
            Err(E::NotPositive { name: "mean", .. })
        ));
        assert!(matches!(
            Distribution::lognormal(0.0, 0.0),
            Err(E::NotPositive { name: "sigma", .. })
        ));
        assert!(matches!(
            Distribution::lognormal(710.0, 1.0),
            Err(E::MomentsNotFinite)
        ));
        assert!(matches!(
            Distribution::uniform(1.0, 1.0),
            Err(E::EmptyInterval { .. })
        ));
        assert!(matches!(
            Distribution::uniform(0.0, f64::INFINITY),
            Err(E::NotFinite { .. })
        ));
        assert!(matches!(
            Distribution::uniform(-1e308, 1e308),
            Err(E::EmptyInterval { .. })
        ));
        assert!(matches!(
            Distribution::truncated_normal(0.0, 1.0, 2.0, 1.0),
            Err(E::EmptyInterval { .. })
        ));
        assert!(matches!(
            Distribution::truncated_normal(0.0, 1.0, f64::NAN, 1.0),
            Err(E::EmptyInterval { .. })
        ));
        assert!(matches!(
            Distribution::truncated_normal(0.0, 1.0, 50.0, 60.0),
            Err(E::NegligibleMass { .. })
        ));
        assert!(Distribution::truncated_normal(0.0, 1.0, 30.0, f64::INFINITY).is_ok());
        let bad = Distribution::Normal {
            mean: 0.0,
            std: -1.0,
        };
        assert!(bad.validate().is_err());
    }

    #[test]
    fn normal_cov_sets_std() {
        let d = Distribution::normal_cov(-4.0, 0.25).unwrap();
        assert_eq!(d, Distribution::normal(-4.0, 1.0).unwrap());
        assert!(d.is_gaussian());
        assert!(!Distribution::lognormal(0.0, 1.0).unwrap().is_gaussian());
    }

    #[test]
    fn serde_uses_a_kind_tag() {
        let d = Distribution::normal(1.0, 2.0).unwrap();
        let s = serde_json::to_string(&d).unwrap();
        assert_eq!(s, r#"{"kind":"normal","mean":1.0,"std":2.0}"#);
        let t: Distribution = serde_json::from_str(
            r#"{"kind":"truncated_normal","mean":0,"std":1,"low":-1,"high":2}"#,
        )
        .unwrap();
        assert_eq!(
            t,
            Distribution::truncated_normal(0.0, 1.0, -1.0, 2.0).unwrap()
        );
        let l: Distribution =
            serde_json::from_str(r#"{"kind":"lognormal","mu":0,"sigma":0.5}"#).unwrap();
        assert_eq!(l, Distribution::lognormal(0.0, 0.5).unwrap());
        for d in all().into_iter().filter(|d| {
            let (a, b) = d.support();
            a.is_finite() && b.is_finite()
        }) {
            let back: Distribution =
                serde_json::from_str(&serde_json::to_string(&d).unwrap()).unwrap();
            assert_eq!(back, d);
        }
    }

    #[test]
    fn closed_form_moments() {
        let l = Distribution::lognormal_from_mean_std(10.0, 2.0).unwrap();
        assert!(close(l.mean(), 10.0, 1e-14));
        assert!(close(l.std(), 2.0, 1e-14));
        let u = Distribution::uniform(1.0, 4.0).unwrap();
        assert_eq!(u.mean(), 2.5);
        assert!(close(u.std(), 3.0 / 12f64.sqrt(), 1e-15));
        // Half-normal: mean sqrt(2/pi), variance 1 - 2/pi.
        let h = Distribution::truncated_normal(0.0, 1.0, 0.0, f64::INFINITY).unwrap();
        assert!(close(h.mean(), (2.0 / std::f64::consts::PI).sqrt(), 1e-14));
        assert!(close(
            h.std(),
            (1.0 - 2.0 / std::f64::consts::PI).sqrt(),
            1e-14
        ));
        // Symmetric [-1, 1] (quadrature branch) and [-1.5, 1.5] (closed form).
        for c in [1.0, 1.5f64] {
            let t = Distribution::truncated_normal(5.0, 2.0, 5.0 - 2.0 * c, 5.0 + 2.0 * c).unwrap();
            let z = 2.0 * norm_cdf(c) - 1.0;
            let var = 1.0 - 2.0 * c * norm_pdf(c) / z;
            assert!(close(t.mean(), 5.0, 1e-15));
            assert!(close(t.std(), 2.0 * var.sqrt(), 1e-13), "c={c}");
        }
    }

    #[test]
    fn truncated_moments_continuous_across_the_quadrature_switch() {
        let a = Distribution::truncated_normal(0.0, 1.0, 0.3, 2.3 - 1e-9).unwrap();
        let b = Distribution::truncated_normal(0.0, 1.0, 0.3, 2.3 + 1e-9).unwrap();
        assert!(close(a.mean(), b.mean(), 1e-8));
        assert!(close(a.std(), b.std(), 1e-8));
        // A very narrow interval is nearly uniform.
        let n = Distribution::truncated_normal(0.0, 1.0, 3.0, 3.0 + 1e-6).unwrap();
        assert!(close(n.std(), 1e-6 / 12f64.sqrt(), 1e-6));
        assert!(n.mean() > 3.0 && n.mean() < 3.0 + 0.5e-6);
    }

    #[test]
    fn moments_match_the_quantile_function() {
        // Midpoint rule in u of x(u) and x(u)^2 (checks inverse_cdf against mean/std).
        let m = 20_000;
        for d in all() {
            let (mut s1, mut s2) = (0.0, 0.0);
            for i in 0..m {
                let x = d.inverse_cdf((i as f64 + 0.5) / m as f64) - d.mean();
                s1 += x;
                s2 += x * x;
            }
            let mean = d.mean() + s1 / m as f64;
            let std = (s2 / m as f64 - (s1 / m as f64).powi(2)).sqrt();
            assert!(
                (mean - d.mean()).abs() < 1e-4 * d.std(),
                "{d:?}: {mean} vs {}",
                d.mean()
            );
            assert!(close(std, d.std(), 2e-3), "{d:?}: {std} vs {}", d.std());
        }
    }

    #[test]
    fn cdf_and_inverse_cdf_round_trip() {
        for d in all() {
            for i in 1..100 {
                let u = f64::from(i) / 100.0;
                let x = d.inverse_cdf(u);
                assert!(close(d.cdf(x), u, 1e-12), "{d:?} u={u}");
                assert!(close(d.sf(x), 1.0 - u, 1e-11), "{d:?} u={u}");
            }
            let (lo, hi) = d.support();
            assert_eq!(d.inverse_cdf(0.0), lo);
            assert_eq!(d.inverse_cdf(1.0), hi);
            assert!(d.inverse_cdf(-0.1).is_nan());
            assert!(d.inverse_cdf(f64::NAN).is_nan());
            assert_eq!(d.cdf(f64::INFINITY), 1.0);
            assert_eq!(d.cdf(f64::NEG_INFINITY), 0.0);
        }
    }

    #[test]
    fn pdf_integrates_to_one() {
        for d in all() {
            let m = 20_000;
            let (a, b) = (d.inverse_cdf(1e-12), d.inverse_cdf(1.0 - 1e-12));
            let h = (b - a) / m as f64;
            let s: f64 = (0..m).map(|i| d.pdf(a + (i as f64 + 0.5) * h)).sum::<f64>() * h;
            assert!((s - 1.0).abs() < 1e-4, "{d:?}: {s}");
        }
    }

    #[test]
    fn from_standard_normal_is_exact_for_gaussian_and_lognormal() {
        let n = Distribution::normal(3.0, 0.5).unwrap();
        assert_eq!(n.from_standard_normal(2.0), 4.0);
        let l = Distribution::lognormal(1.0, 0.5).unwrap();
        assert_eq!(l.from_standard_normal(-2.0), 0.0f64.exp());
        assert!(l.from_standard_normal(-40.0) > 0.0);
    }

    #[test]
    fn from_standard_normal_matches_inverse_cdf_of_phi() {
        for d in all() {
            for i in -30..=30 {
                let z = f64::from(i) * 0.1;
                let a = d.from_standard_normal(z);
                let b = d.inverse_cdf(norm_cdf(z));
                assert!((a - b).abs() <= 1e-12 * (a.abs() + d.std()), "{d:?} z={z}");
            }
        }
    }

    #[test]
    fn far_tail_nodes_map_inside_the_support_and_stay_ordered() {
        // Gauss-Hermite nodes reach beyond 10 sigma for ~40 nodes.
        let zs = [-13.0, -11.0, -9.0, -7.0, 7.0, 9.0, 11.0, 13.0];
        let h = Distribution::truncated_normal(0.0, 1.0, 0.0, f64::INFINITY).unwrap();
        let xs: Vec<f64> = zs.iter().map(|&z| h.from_standard_normal(z)).collect();
        assert!(xs.iter().all(|&x| x >= 0.0 && x.is_finite()));
        assert!(xs.windows(2).all(|w| w[0] < w[1]), "{xs:?}");
        // Upper tail of a half-normal: Q(x) = Q(z) / 2.
        for &z in &[7.0, 9.0, 11.0, 13.0] {
            let x = h.from_standard_normal(z);
            assert!(close(norm_sf(x), 0.5 * norm_sf(z), 1e-12));
        }
        // Left-truncated far below the mean, mapped in its own tail.
        let t = Distribution::truncated_normal(0.0, 1.0, f64::NEG_INFINITY, -4.0).unwrap();
        let xs: Vec<f64> = zs.iter().map(|&z| t.from_standard_normal(z)).collect();
        assert!(xs.iter().all(|&x| x <= -4.0));
        // Near the bound -4 the f64 resolution (9e-16) merges the upper nodes.
        assert!(xs.windows(2).all(|w| w[0] <= w[1]), "{xs:?}");
        assert!(xs[..5].windows(2).all(|w| w[0] < w[1]), "{xs:?}");
        let target = norm_sf(3.0) * norm_sf(4.0) / norm_pdf(4.0);
        assert!(close(-4.0 - t.from_standard_normal(3.0), target, 2e-3));
        // Relative accuracy next to a bound: half-normal CDF ~ 2 phi(0) x.
        assert!(close(h.cdf(1e-20), 2.0 * norm_pdf(0.0) * 1e-20, 1e-14));
        assert!(close(
            h.inverse_cdf(1e-20),
            1e-20 / (2.0 * norm_pdf(0.0)),
            1e-14
        ));
        let eps = 2f64.powi(-30); // exact distance to the bound
        assert!(close(
            t.sf(-4.0 - eps),
            eps * norm_pdf(4.0) / norm_sf(4.0),
            1e-8
        ));
        let u = Distribution::uniform(0.0, 1.0).unwrap();
        let xs: Vec<f64> = zs.iter().map(|&z| u.from_standard_normal(z)).collect();
        assert!(xs.iter().all(|&x| (0.0..=1.0).contains(&x)));
        assert!(xs[0] > 0.0 && xs[0] < 1e-38);
        assert!(u.from_standard_normal(7.0) < 1.0);
    }
}
