//! The study file as written (serde): every table and key, unknown keys refused.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};
use toml::Spanned;

use super::parameter::ParameterSpec;
use crate::fmu::FixedValue;
use crate::qoi::QoiSpec;
use crate::uq::galerkin::system::SystemSpec;
use crate::uq::method::MethodSpec;

/// Most communication points of one run (the limit of [`Experiment::check`]): 10^8 points
/// hold 800 MB per recorded variable.
pub const MAX_TIME_POINTS: f64 = 1e8;

/// Start, stop and communication step (s).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Experiment {
    /// Start time (s).
    #[serde(default)]
    pub start: f64,
    /// Stop time (s).
    pub stop: f64,
    /// Communication step (s).
    pub step: f64,
}

impl Experiment {
    /// Relative tolerance within which stop − start counts as a whole number of steps.
    const WHOLE: f64 = 1e-6;

    /// Number of communication steps (the last one shorter when stop − start is not a whole
    /// number of steps).
    pub fn n_steps(&self) -> usize {
        let (n, short_last) = self.grid();
        n + usize::from(short_last)
    }

    /// The number of full steps and whether a shorter last step follows.
    fn grid(&self) -> (usize, bool) {
        let ratio = (self.stop - self.start) / self.step;
        if !ratio.is_finite() || ratio <= 0.0 {
            return (0, false);
        }
        let whole = ratio.round();
        if (ratio - whole).abs() <= Self::WHOLE * ratio.max(1.0) {
            (whole as usize, false)
        } else {
            (ratio.floor() as usize, true)
        }
    }

    /// The communication points t_0 … t_n (s), computed as start + i·step (no drift) and
    /// ending at stop: when stop − start is not a whole number of steps, the last step is
    /// shorter (as fmpy does).
    ///
    /// Empty when the experiment is invalid ([`Experiment::check`]: stop <= start, a step
    /// that is 0, negative or not finite, more than `MAX_TIME_POINTS` points);
    /// [`Experiment::try_times`] says why.
    pub fn times(&self) -> Vec<f64> {
        self.try_times().unwrap_or_default()
    }

    /// [`Experiment::times`], or why the experiment has no valid grid.
    pub fn try_times(&self) -> Result<Vec<f64>, InvalidExperiment> {
        self.check()?;
        let (n, short_last) = self.grid();
        let mut t: Vec<f64> = (0..=n)
            .map(|i| {
                if i == n && !short_last {
                    self.stop
                } else {
                    self.start + i as f64 * self.step
                }
            })
            .collect();
        if short_last {
            t.push(self.stop);
        }
        Ok(t)
    }

    /// Checks that start < stop and step > 0, all finite, and that the grid has at most
    /// `MAX_TIME_POINTS` (1e8) points (before anything allocates it).
    pub fn check(&self) -> Result<(), InvalidExperiment> {
        if self.step == 0.0 {
            return Err(InvalidExperiment::ZeroStep);
        }
        let finite = self.start.is_finite() && self.stop.is_finite() && self.step.is_finite();
        if !finite || self.step <= 0.0 || self.stop <= self.start {
            return Err(InvalidExperiment::Range {
                start: self.start,
                stop: self.stop,
                step: self.step,
            });
        }
        // t_0 … t_n with n = ceil((stop − start) / step) at most (a shorter last step).
        let points = ((self.stop - self.start) / self.step).ceil() + 1.0;
        if points.is_nan() || points > MAX_TIME_POINTS {
            return Err(InvalidExperiment::TooManyPoints {
                points,
                step: self.step,
            });
        }
        Ok(())
    }
}

/// A time grid that cannot be run.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum InvalidExperiment {
    /// The communication step is zero.
    #[error("the communication step is 0 s: give a positive step (s), e.g. 0.01")]
    ZeroStep,
    /// Not start < stop with step > 0.
    #[error(
        "experiment needs finite start < stop and step > 0 (got start {start}, stop {stop}, step {step})"
    )]
    Range {
        /// Start (s).
        start: f64,
        /// Stop (s).
        stop: f64,
        /// Step (s).
        step: f64,
    },
    /// More communication points than `MAX_TIME_POINTS` (1e8).
    #[error(
        "experiment: {points:.3e} communication points (step {step:e} s), more than the limit of \
         1e8 per run (each recorded variable would take {:.1e} bytes of memory); use a \
         coarser step or a shorter experiment",
        8.0 * points
    )]
    TooManyPoints {
        /// Communication points (t_0 … t_n).
        points: f64,
        /// Step (s).
        step: f64,
    },
}

/// Time-varying inputs of every run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Inputs {
    /// A CSV file: a time column (s) first, then one column per input variable, named after
    /// it (relative paths start from the study file's folder).
    pub file: String,
}

/// Output variables to analyse as time series.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Outputs {
    /// FMU variable names (Real).
    #[serde(default)]
    pub variables: Vec<String>,
}

/// Analysis settings (all optional).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Analysis {
    /// Points of the density grid of the PDF evolution.
    pub pdf_grid: usize,
    /// Largest number of time columns in the PDF evolution (evenly thinned).
    pub pdf_times: usize,
    /// Samples of a chaos surrogate used for the densities, quantiles and exceedance
    /// probabilities of the scalar quantities.
    pub surrogate_samples: usize,
    /// Samples of a chaos surrogate used for the quantiles and densities over time of the
    /// outputs (at most `surrogate_samples`; the first of the same draws).
    pub series_samples: usize,
    /// Quantile levels written to the CSV.
    pub quantiles: Vec<f64>,
    /// Unweighted designs (MC, LHS, QMC, pce_regression, sobol_sampling): continue when some
    /// points fail and report how many.
    pub allow_failures: bool,
    /// How a chaos method fits a series output: on the principal components of its runs
    /// (`pca`, the default) or column by column (`columns`).
    pub functional: Functional,
    /// The share of a series' variance over the runs that its principal components keep, in
    /// (0, 1] (default 1 − 1e-6); the rest is the truncation error of the modes.
    pub retained_variance: f64,
}

/// How a chaos method fits a series output (`[analysis] functional`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Functional {
    /// One chaos per principal component (Karhunen–Loève mode) of the centred runs, as many
    /// as keep `retained_variance` of the variance; each column's chaos is their sum
    /// weighted by the modes, plus the column's mean.
    #[default]
    Pca,
    /// One chaos per time column.
    Columns,
}

/// Column name of a quantile level `p` (in [0, 1]): `q` and the percentage 100·p written
/// exactly, from the shortest decimal of `p` with its point moved two places (no
/// floating-point noise, nothing rounded): 0.01 → `q1`, 0.5 → `q50`, 0.025 → `q2.5`,
/// 0.0015 → `q0.15`, 0.9951 → `q99.51`. Distinct levels give distinct names. Every CSV
/// header and plot legend that names a quantile uses this.
pub fn quantile_column(p: f64) -> String {
    if !p.is_finite() {
        return format!("q{p}");
    }
    // `{}` writes the shortest decimal that reads back as `p`, never in exponent notation;
    // `+ 0.0` turns -0 into 0.
    let text = format!("{}", p + 0.0);
    let (sign, digits) = match text.strip_prefix('-') {
        Some(rest) => ("-", rest),
        None => ("", text.as_str()),
    };
    let (int, frac) = digits.split_once('.').unwrap_or((digits, ""));
    // 100·p: the first two fraction digits join the integer part.
    let frac = format!("{frac:0<2}");
    let (moved, rest) = frac.split_at(2);
    let int = format!("{int}{moved}");
    let int = match int.trim_start_matches('0') {
        "" => "0",
        t => t,
    };
    let rest = rest.trim_end_matches('0');
    if rest.is_empty() {
        format!("q{sign}{int}")
    } else {
        format!("q{sign}{int}.{rest}")
    }
}

impl Default for Analysis {
    fn default() -> Self {
        Analysis {
            pdf_grid: 200,
            pdf_times: 150,
            surrogate_samples: 20_000,
            series_samples: 4_000,
            quantiles: vec![0.01, 0.5, 0.99],
            allow_failures: false,
            functional: Functional::Pca,
            retained_variance: 1.0 - 1e-6,
        }
    }
}

/// A study file as written.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StudyFile {
    /// Study name (used in reports).
    pub name: String,
    /// Free text.
    #[serde(default)]
    pub description: String,
    /// The FMU path (every method that runs a model).
    #[serde(default)]
    pub fmu: Option<String>,
    /// An intrusive method's equations.
    #[serde(default)]
    pub system: Option<SystemSpec>,
    /// Seed of every random stream.
    #[serde(default = "default_seed")]
    pub seed: u64,
    /// Time grid.
    pub experiment: Spanned<Experiment>,
    /// Method.
    pub method: Spanned<MethodSpec>,
    /// Random parameters (none is refused with its own message, not serde's).
    #[serde(default)]
    pub parameters: Vec<Spanned<ParameterSpec>>,
    /// Correlations between random parameters (a Gaussian copula).
    #[serde(default)]
    pub correlation: Vec<Spanned<CorrelationSpec>>,
    /// Deterministic parameter values set before every run (numbers, Booleans or texts).
    #[serde(default)]
    pub fixed: BTreeMap<String, FixedValue>,
    /// Time-varying inputs.
    #[serde(default)]
    pub inputs: Option<Inputs>,
    /// Outputs.
    #[serde(default)]
    pub outputs: Outputs,
    /// Scalar quantities of interest computed from each run.
    #[serde(default)]
    pub qoi: Vec<Spanned<QoiSpec>>,
    /// Analysis settings.
    #[serde(default)]
    pub analysis: Analysis,
    /// Variants run one after the other into sub-folders, then compared.
    #[serde(default)]
    pub variants: Vec<Spanned<Variant>>,
    /// Name of the variant the others are compared against (default: the first).
    #[serde(default)]
    pub reference: Option<String>,
    /// Published values to print beside ours in a suite's comparison table.
    #[serde(default)]
    pub paper: Vec<PaperValue>,
}

fn default_seed() -> u64 {
    42
}

/// `[[correlation]]`: the Pearson correlation `rho` of two random parameters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CorrelationSpec {
    /// The two parameters, by name.
    pub between: [String; 2],
    /// Their correlation, in (-1, 1).
    pub rho: f64,
}

/// A published value: `statistic` ("mean", "std", or "p>LIMIT") of `quantity` in `variant`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PaperValue {
    /// Variant name.
    pub variant: String,
    /// Quantity (scalar QoI) name.
    pub quantity: String,
    /// "mean", "std" or "p>LIMIT" (e.g. "p>2.5").
    pub statistic: String,
    /// The published number.
    pub value: f64,
    /// Where it is published (e.g. "paper Table 3").
    #[serde(default)]
    pub source: String,
}

/// A variant of a study: another method and/or other random parameters.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Variant {
    /// Sub-folder and label.
    pub name: String,
    /// Method of this variant (default: the study's).
    #[serde(default)]
    pub method: Option<MethodSpec>,
    /// Random parameters of this variant (default: the study's).
    #[serde(default)]
    pub parameters: Option<Vec<ParameterSpec>>,
    /// Deterministic values of this variant, merged over the study's `[fixed]`.
    #[serde(default)]
    pub fixed: BTreeMap<String, FixedValue>,
    /// The study's `[[qoi]]` entries this variant computes, by name (default: all), e.g. to
    /// leave an expensive quantity out of a large design.
    #[serde(default)]
    pub quantities: Option<Vec<String>>,
}
