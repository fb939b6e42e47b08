//! The `[[parameters]]` of a study file: a name and a distribution chosen by the
//! `distribution` key (default `normal`), each distribution with its own keys.

use serde::de::{Deserializer, Error as _};
use serde::Deserialize;

use crate::uq::distributions::{Distribution, DistributionError, RandomParameter};

/// A random parameter as written.
#[derive(Clone, Debug, PartialEq)]
pub struct ParameterSpec {
    /// FMU variable name.
    pub name: String,
    /// Its distribution, as written.
    pub distribution: DistributionSpec,
    /// `level = "outer" | "inner"` (default inner): in a nested study, whether the
    /// parameter is drawn by the outer design or by the inner method.
    pub level: Level,
    /// `allow_negative = true`: values <= 0 are meant (no warning about a positive-mean
    /// normal input reaching them, whatever the FMU declares).
    pub allow_negative: bool,
}

/// The level of a random parameter in a two-level (nested) study.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Level {
    /// Drawn by the inner method, anew for every outer sample (the default).
    #[default]
    Inner,
    /// Drawn by the outer design (e.g. the track: an irregularity seed).
    Outer,
}

/// A distribution as written: `distribution = "<kind>"` and the kind's keys only.
///
/// `mean` and `std` are those of the variable (normal, lognormal) or of the parent normal
/// (truncated normal); `cov` (coefficient of variation) replaces `std` as `std = |mean| cov`.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(tag = "distribution", rename_all = "snake_case", deny_unknown_fields)]
pub enum DistributionSpec {
    /// `distribution = "normal"` (the default): `mean` and `std` or `cov`.
    Normal {
        /// Mean.
        mean: f64,
        /// Standard deviation.
        #[serde(default)]
        std: Option<f64>,
        /// Coefficient of variation.
        #[serde(default)]
        cov: Option<f64>,
    },
    /// `distribution = "lognormal"`: mean and `std` or `cov` of the variable itself.
    #[serde(alias = "log_normal")]
    Lognormal {
        /// Mean (> 0).
        mean: f64,
        /// Standard deviation.
        #[serde(default)]
        std: Option<f64>,
        /// Coefficient of variation.
        #[serde(default)]
        cov: Option<f64>,
    },
    /// `distribution = "uniform"` on `[low, high]`.
    Uniform {
        /// Lower bound.
        low: f64,
        /// Upper bound.
        high: f64,
    },
    /// `distribution = "truncated_normal"`: the parent normal's `mean` and `std` or `cov`,
    /// conditioned on `[low, high]` (bounds may be `inf`).
    TruncatedNormal {
        /// Mean of the parent normal.
        mean: f64,
        /// Standard deviation of the parent normal.
        #[serde(default)]
        std: Option<f64>,
        /// Coefficient of variation of the parent normal.
        #[serde(default)]
        cov: Option<f64>,
        /// Lower bound.
        low: f64,
        /// Upper bound.
        high: f64,
    },
    /// `distribution = "beta"`: Beta(`alpha`, `beta`) scaled to `[low, high]`.
    Beta {
        /// First shape (> 0).
        alpha: f64,
        /// Second shape (> 0).
        beta: f64,
        /// Lower end.
        low: f64,
        /// Upper end.
        high: f64,
    },
    /// `distribution = "gamma"`: `shape` and `scale` (mean `shape · scale`).
    Gamma {
        /// Shape (> 0).
        shape: f64,
        /// Scale (> 0, units of the parameter).
        scale: f64,
    },
    /// `distribution = "weibull"`: CDF `1 - exp(-(x/scale)^shape)`.
    Weibull {
        /// Shape (> 0).
        shape: f64,
        /// Scale (> 0, units of the parameter).
        scale: f64,
    },
    /// `distribution = "integer_uniform"`: the integers `low..=high`, equally likely
    /// (sampling methods only).
    IntegerUniform {
        /// Smallest value.
        low: i64,
        /// Largest value (included).
        high: i64,
    },
}

/// Why a parameter's distribution is refused.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum InvalidParameter {
    /// Both spreads were given.
    #[error("give `std` or `cov`, not both")]
    BothSpreads,
    /// No spread was given.
    #[error("`std` or `cov` is required")]
    NoSpread,
    /// The coefficient of variation is not positive (or the mean is zero).
    #[error("`cov` must be positive and the mean non-zero (got cov = {cov}, mean = {mean})")]
    BadCov {
        /// The coefficient of variation given.
        cov: f64,
        /// The mean.
        mean: f64,
    },
    /// The distribution's parameters are invalid.
    #[error(transparent)]
    Distribution(#[from] DistributionError),
}

impl<'de> Deserialize<'de> for ParameterSpec {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let mut table = toml::Table::deserialize(d)?;
        let name = match table.remove("name") {
            Some(toml::Value::String(s)) => s,
            Some(other) => {
                return Err(D::Error::custom(format!(
                    "`name` must be a string, not {}",
                    other.type_str()
                )))
            }
            None => return Err(D::Error::missing_field("name")),
        };
        let level = match table.remove("level") {
            None => Level::Inner,
            Some(v) => Level::deserialize(v).map_err(|_| {
                D::Error::custom(format!(
                    "parameter '{name}': `level` must be \"outer\" or \"inner\""
                ))
            })?,
        };
        let allow_negative = match table.remove("allow_negative") {
            None => false,
            Some(toml::Value::Boolean(b)) => b,
            Some(_) => {
                return Err(D::Error::custom(format!(
                    "parameter '{name}': `allow_negative` must be true or false"
                )))
            }
        };
        table
            .entry("distribution")
            .or_insert_with(|| "normal".into());
        let distribution = DistributionSpec::deserialize(toml::Value::Table(table))
            .map_err(|e| D::Error::custom(format!("parameter '{name}': {}", e.message())))?;
        Ok(ParameterSpec {
            name,
            distribution,
            level,
            allow_negative,
        })
    }
}

/// `std`, or `|mean| cov`.
fn spread(mean: f64, std: Option<f64>, cov: Option<f64>) -> Result<f64, InvalidParameter> {
    match (std, cov) {
        (Some(s), None) => Ok(s),
        // Checked here: a bad cov would otherwise be reported as the std it gives.
        (None, Some(c)) if !(c > 0.0 && c.is_finite() && mean != 0.0) => {
            Err(InvalidParameter::BadCov { cov: c, mean })
        }
        (None, Some(c)) => Ok(mean.abs() * c),
        (Some(_), Some(_)) => Err(InvalidParameter::BothSpreads),
        (None, None) => Err(InvalidParameter::NoSpread),
    }
}

impl DistributionSpec {
    /// The validated distribution.
    pub fn to_distribution(&self) -> Result<Distribution, InvalidParameter> {
        Ok(match *self {
            DistributionSpec::Normal { mean, std, cov } => {
                Distribution::normal(mean, spread(mean, std, cov)?)?
            }
            DistributionSpec::Lognormal { mean, std, cov } => {
                Distribution::lognormal_from_mean_std(mean, spread(mean, std, cov)?)?
            }
            DistributionSpec::Uniform { low, high } => Distribution::uniform(low, high)?,
            DistributionSpec::TruncatedNormal {
                mean,
                std,
                cov,
                low,
                high,
            } => Distribution::truncated_normal(mean, spread(mean, std, cov)?, low, high)?,
            DistributionSpec::Beta {
                alpha,
                beta,
                low,
                high,
            } => Distribution::beta(alpha, beta, low, high)?,
            DistributionSpec::Gamma { shape, scale } => Distribution::gamma(shape, scale)?,
            DistributionSpec::Weibull { shape, scale } => Distribution::weibull(shape, scale)?,
            DistributionSpec::IntegerUniform { low, high } => {
                Distribution::integer_uniform(low, high)?
            }
        })
    }
}

impl ParameterSpec {
    /// The validated parameter.
    pub fn to_parameter(&self) -> Result<RandomParameter, InvalidParameter> {
        Ok(RandomParameter {
            name: self.name.clone(),
            distribution: self.distribution.to_distribution()?,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<ParameterSpec, toml::de::Error> {
        toml::from_str(text)
    }

    #[test]
    fn a_negative_cov_is_reported_as_cov_not_as_std() {
        // Regression: cov = -0.1 was reported as "std must be positive (got -10)".
        let p = parse("name = \"K\"\nmean = 100\ncov = -0.1").unwrap();
        let e = p.distribution.to_distribution().unwrap_err().to_string();
        assert!(
            e.contains("`cov` must be positive") && e.contains("-0.1"),
            "{e}"
        );
        assert!(!e.contains("std"), "{e}");
        let p = parse("name = \"K\"\nmean = 0\ncov = 0.1").unwrap();
        let e = p.distribution.to_distribution().unwrap_err().to_string();
        assert!(e.contains("mean non-zero"), "{e}");
    }

    #[test]
    fn distribution_defaults_to_normal_and_std_or_cov() {
        let p = parse("name = \"K\"\nmean = 100.0\ncov = 0.1").unwrap();
        assert_eq!(p.name, "K");
        assert_eq!(
            p.to_parameter().unwrap().distribution,
            Distribution::normal(100.0, 10.0).unwrap()
        );
        let p = parse("name = \"K\"\ndistribution = \"uniform\"\nlow = 1\nhigh = 2").unwrap();
        assert_eq!(
            p.distribution.to_distribution().unwrap(),
            Distribution::uniform(1.0, 2.0).unwrap()
        );
        let p = parse(
            "name = \"K\"\ndistribution = \"truncated_normal\"\nmean = 0\nstd = 1\nlow = 0\nhigh = inf",
        )
        .unwrap();
        assert!(p.to_parameter().is_ok());
        for (text, want) in [
            (
                "distribution = \"beta\"\nalpha = 2\nbeta = 5\nlow = 1\nhigh = 3",
                Distribution::beta(2.0, 5.0, 1.0, 3.0).unwrap(),
            ),
            (
                "distribution = \"gamma\"\nshape = 2.5\nscale = 4e3",
                Distribution::gamma(2.5, 4e3).unwrap(),
            ),
            (
                "distribution = \"weibull\"\nshape = 1.5\nscale = 2",
                Distribution::weibull(1.5, 2.0).unwrap(),
            ),
            (
                "distribution = \"integer_uniform\"\nlow = 1\nhigh = 16",
                Distribution::integer_uniform(1, 16).unwrap(),
            ),
        ] {
            let p = parse(&format!("name = \"K\"\n{text}")).unwrap();
            assert_eq!(p.to_parameter().unwrap().distribution, want, "{text}");
        }
        let bad = parse("name = \"K\"\ndistribution = \"gamma\"\nshape = -1\nscale = 1").unwrap();
        assert!(bad.to_parameter().is_err());
        let bad =
            parse("name = \"K\"\ndistribution = \"integer_uniform\"\nlow = 5\nhigh = 1").unwrap();
        assert!(bad.to_parameter().is_err());
    }

    #[test]
    fn wrong_keys_and_spreads_are_refused() {
        let e = parse("name = \"K\"\nmean = 1.0\nstd = 0.1\nlow = 0.0").unwrap_err();
        assert!(e.to_string().contains("unknown field `low`"), "{e}");
        assert!(e.to_string().contains("parameter 'K'"), "{e}");
        let e = parse("name = \"K\"\ndistribution = \"gamma\"\nmean = 1.0").unwrap_err();
        assert!(e.to_string().contains("unknown field `mean`"), "{e}");
        let e = parse("name = \"K\"\ndistribution = \"cauchy\"\nmean = 1.0").unwrap_err();
        assert!(e.to_string().contains("unknown variant `cauchy`"), "{e}");
        assert!(parse("mean = 1.0\nstd = 0.1").is_err());
        let both = parse("name = \"K\"\nmean = 1.0\nstd = 0.1\ncov = 0.1").unwrap();
        assert_eq!(both.to_parameter(), Err(InvalidParameter::BothSpreads));
        let none = parse("name = \"K\"\nmean = 1.0").unwrap();
        assert_eq!(none.to_parameter(), Err(InvalidParameter::NoSpread));
        let neg = parse("name = \"K\"\nmean = 1.0\nstd = -1.0").unwrap();
        assert!(matches!(
            neg.to_parameter(),
            Err(InvalidParameter::Distribution(_))
        ));
    }
}
