//! Probability distributions of uncertain inputs and their isoprobabilistic
//! maps from the unit interval (sampling) and from the standard normal
//! (collocation).
//!
//! Tails are handled with complementary probabilities: for an upper-tail
//! point, `1 - u` is carried explicitly instead of being recomputed from `u`,
//! so that Gauss–Hermite nodes at 10 sigma still map to distinct,
//! correctly ordered physical values.

#[cfg(test)]
mod tests;
mod truncated;

use serde::{Deserialize, Serialize};

use crate::uq::special::{norm_cdf, norm_isf, norm_pdf, norm_ppf, norm_sf};
use truncated::Trunc;

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

impl Distribution {
    /// Normal distribution; `std` must be finite and positive, `mean` finite.
    pub fn normal(mean: f64, std: f64) -> Result<Self, DistributionError> {
        Distribution::Normal { mean, std }.checked()
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
        Distribution::LogNormal { mu, sigma }.checked()
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
        Distribution::Uniform { low, high }.checked()
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
        Distribution::TruncatedNormal {
            mean,
            std,
            low,
            high,
        }
        .checked()
    }

    /// `self` if its parameters are valid.
    fn checked(self) -> Result<Self, DistributionError> {
        self.validate()?;
        Ok(self)
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

    /// The value of this input at the germ coordinate `x` of a design built in the
    /// standard space `germ` (the isoprobabilistic map `F^{-1}(G(x))`, `G` the germ's CDF).
    pub fn from_germ(&self, germ: Germ, x: f64) -> f64 {
        match germ {
            Germ::Normal => self.from_standard_normal(x),
            Germ::Uniform => self.inverse_cdf(x),
        }
    }

    /// The germ coordinate of `value` in the standard space `germ`, the inverse of
    /// [`Distribution::from_germ`] (`G^{-1}(F(value))`); tails keep their relative precision.
    pub fn to_germ(&self, germ: Germ, value: f64) -> f64 {
        match (germ, self) {
            (Germ::Uniform, _) => self.cdf(value),
            (Germ::Normal, &Distribution::Normal { mean, std }) => (value - mean) / std,
            (Germ::Normal, &Distribution::LogNormal { mu, sigma }) => (value.ln() - mu) / sigma,
            (Germ::Normal, _) => {
                let u = self.cdf(value);
                if u <= 0.5 {
                    norm_ppf(u)
                } else {
                    norm_isf(self.sf(value))
                }
            }
        }
    }
}

/// A standard space in which designs are built: independent germs, each mapped to its
/// input by [`Distribution::from_germ`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Germ {
    /// Standard normal N(0, 1) (Gauss–Hermite rules, Hermite chaos).
    Normal,
    /// Uniform on (0, 1) (Monte Carlo and Latin hypercube designs).
    Uniform,
}

/// A named random input of a study (an FMU parameter).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RandomParameter {
    /// FMU variable name.
    pub name: String,
    /// Its distribution.
    pub distribution: Distribution,
}
