//! Probability distributions of uncertain inputs and their isoprobabilistic
//! maps from the unit interval (sampling), from the standard normal
//! (collocation) and from the germs of the Askey scheme (polynomial chaos).
//!
//! One type, [`Distribution`], for every input family: normal, log-normal,
//! uniform, truncated normal, Beta, Gamma, Weibull and the integer uniform.
//! `functions.rs` holds the density, CDF, survival function and quantile of
//! each, `maps.rs` the maps to and from the standard spaces ([`Germ`]),
//! `shapes.rs` the numerics of the Beta, Gamma and Weibull shapes and
//! `truncated.rs` those of the truncated normal.
//!
//! Tails are handled with complementary probabilities: for an upper-tail
//! point, `1 - u` is carried explicitly instead of being recomputed from `u`,
//! so that Gauss–Hermite nodes at 10 sigma still map to distinct,
//! correctly ordered physical values.

mod functions;
mod maps;
mod shapes;
#[cfg(test)]
mod shapes_tests;
#[cfg(test)]
mod tests;
mod truncated;

use serde::{Deserialize, Serialize};

pub use shapes::gamma_pq;
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
    /// Integer bounds out of order, or beyond the integers a double represents exactly.
    #[error(
        "integer_uniform needs low <= high, both within ±2^53 (got low = {low}, high = {high})"
    )]
    IntegerRange {
        /// Smallest value.
        low: i64,
        /// Largest value.
        high: i64,
    },
}

/// A one-dimensional input distribution.
///
/// Serialized with a `kind` tag, e.g. `{"kind": "normal", "mean": 1.0, "std": 0.1}`;
/// the log-normal kind is `log_normal` (`lognormal` is accepted on input); the others are
/// `uniform`, `truncated_normal`, `beta`, `gamma`, `weibull` and `integer_uniform`.
/// The constructors validate; deserialization and struct literals do not: call
/// [`Distribution::validate`] on such values. The methods' designs
/// ([`crate::uq::method::Sampling::design`]) validate their inputs and refuse invalid ones
/// with a typed error; the functions of an unvalidated distribution (quantile, maps, moments)
/// never panic, but their values are then meaningless (NaN or clamped).
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
    /// Beta(alpha, beta) scaled to `[low, high]`: density proportional to
    /// `u^(alpha-1) (1-u)^(beta-1)`, `u = (x - low) / (high - low)`.
    Beta {
        /// First shape (> 0).
        alpha: f64,
        /// Second shape (> 0).
        beta: f64,
        /// Lower end.
        low: f64,
        /// Upper end (> low).
        high: f64,
    },
    /// Gamma: density `x^(shape-1) e^(-x/scale) / (Gamma(shape) scale^shape)` on `[0, inf)`
    /// (mean `shape · scale`).
    Gamma {
        /// Shape `k` (> 0).
        shape: f64,
        /// Scale `theta` (> 0, units of the input).
        scale: f64,
    },
    /// Weibull: CDF `1 - exp(-(x/scale)^shape)` on `[0, inf)`.
    Weibull {
        /// Shape `k` (> 0).
        shape: f64,
        /// Scale `lambda` (> 0, units of the input).
        scale: f64,
    },
    /// Uniform on the integers `low..=high` (both included): a discrete input, for
    /// sampling designs (MC, LHS, QMC); polynomial chaos methods refuse it.
    IntegerUniform {
        /// Smallest value.
        low: i64,
        /// Largest value.
        high: i64,
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

    /// Beta(alpha, beta) on `[low, high]` (shapes finite and positive, finite `low < high`).
    pub fn beta(alpha: f64, beta: f64, low: f64, high: f64) -> Result<Self, DistributionError> {
        Distribution::Beta {
            alpha,
            beta,
            low,
            high,
        }
        .checked()
    }

    /// Gamma(shape, scale), both finite and positive.
    pub fn gamma(shape: f64, scale: f64) -> Result<Self, DistributionError> {
        Distribution::Gamma { shape, scale }.checked()
    }

    /// Weibull(shape, scale), both finite and positive.
    pub fn weibull(shape: f64, scale: f64) -> Result<Self, DistributionError> {
        Distribution::Weibull { shape, scale }.checked()
    }

    /// Uniform on the integers `low..=high` (`low <= high`, both within ±2^53).
    pub fn integer_uniform(low: i64, high: i64) -> Result<Self, DistributionError> {
        Distribution::IntegerUniform { low, high }.checked()
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
            Distribution::Beta {
                alpha,
                beta,
                low,
                high,
            } => {
                positive("alpha", alpha)?;
                positive("beta", beta)?;
                finite("low", low)?;
                finite("high", high)?;
                if low >= high || !(high - low).is_finite() {
                    return Err(DistributionError::EmptyInterval { low, high });
                }
            }
            Distribution::Gamma { shape, scale } | Distribution::Weibull { shape, scale } => {
                positive("shape", shape)?;
                positive("scale", scale)?;
            }
            Distribution::IntegerUniform { low, high } => {
                const EXACT: i64 = 1 << 53;
                if low > high || low < -EXACT || high > EXACT {
                    return Err(DistributionError::IntegerRange { low, high });
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

    /// Whether the input takes discrete values (the integer uniform).
    pub fn is_discrete(&self) -> bool {
        matches!(self, Distribution::IntegerUniform { .. })
    }

    /// The value a deterministic run uses: the mean, or for a discrete input the value of
    /// the support nearest to it (the lower one of two).
    pub fn nominal(&self) -> f64 {
        match *self {
            Distribution::IntegerUniform { low, high } => {
                // floor((low + high) / 2) without overflow (even for an unvalidated range).
                (i128::from(low) + i128::from(high)).div_euclid(2) as f64
            }
            _ => self.mean(),
        }
    }
}

/// A standard space in which designs are built: independent germs, one per input, each
/// mapped to its input by [`Distribution::from_germ`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Germ {
    /// Standard normal N(0, 1) for every input (Gauss–Hermite rules, Hermite chaos), each
    /// input by its isoprobabilistic map `F^-1(Phi(z))`.
    Normal,
    /// Uniform on (0, 1) (Monte Carlo and Latin hypercube designs): `F^-1(u)`.
    Uniform,
    /// Each input's own germ of the Askey scheme, mapped affinely
    /// ([`Distribution::askey_affine`]): N(0, 1) for a normal input, U(-1, 1) for a uniform
    /// one, Beta(alpha, beta) on [-1, 1] for a Beta input, Gamma(shape, 1) for a Gamma input;
    /// inputs without an Askey family take N(0, 1) and the normal map, as for `Normal`.
    Askey,
}

/// A named random input of a study (an FMU parameter).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RandomParameter {
    /// FMU variable name.
    pub name: String,
    /// Its distribution.
    pub distribution: Distribution,
}

impl RandomParameter {
    /// The input `name` with `distribution`.
    pub fn new(name: impl Into<String>, distribution: Distribution) -> RandomParameter {
        RandomParameter {
            name: name.into(),
            distribution,
        }
    }
}
