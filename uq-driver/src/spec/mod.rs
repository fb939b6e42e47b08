//! The study file (TOML): which FMU, which random parameters, which method, which outputs.
//!
//! ```toml
//! name = "wheel-scm"
//! fmu = "Wheel.fmu"            # relative to the study file, or found in the FMU folder
//! seed = 42
//! [experiment]
//! start = 0.0
//! stop = 5.0
//! step = 0.01                  # communication step (s)
//! [method]
//! kind = "scm"                 # a method of crate::uq::method, with its own keys
//! nodes = 6                    # SCM: Gauss–Hermite nodes per dimension
//! order = 5                    # SCM: total order of the Hermite chaos (default nodes − 1)
//! [[parameters]]
//! name = "K"
//! distribution = "normal"      # "normal" | "lognormal" | "uniform" | "truncated_normal"
//! mean = 100.0
//! std = 10.0                   # or cov = 0.1
//! [fixed]                      # deterministic parameter values
//! h = 0.001
//! [outputs]
//! variables = ["q"]
//! ```
//!
//! [`Study::parse`] reads the file into [`StudyFile`] (serde: tagged enums for the method,
//! the distributions and the quantities of interest, unknown keys refused) and validates it
//! in one place (`validate.rs`) into a [`Study`]. Errors carry the origin and, where the
//! file has them, the line and column.

mod builtins;
mod parameter;
mod validate;

use std::collections::BTreeMap;
use std::ops::Range;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use toml::Spanned;

pub use builtins::BUILTINS;
pub use parameter::{DistributionSpec, InvalidParameter, ParameterSpec};

use crate::qoi::QoiSpec;
use crate::uq::distributions::RandomParameter;
use crate::uq::method::sgm::SystemSpec;
use crate::uq::method::{Method, MethodSpec, Problem};

/// A line and column (1-based) in a study file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Location {
    /// Line.
    pub line: usize,
    /// Column (in characters).
    pub column: usize,
}

impl Location {
    /// The location of byte `offset` of `text`.
    pub fn of(text: &str, offset: usize) -> Location {
        let before = &text[..offset.min(text.len())];
        let line_start = before.rfind('\n').map_or(0, |i| i + 1);
        Location {
            line: before.matches('\n').count() + 1,
            column: before[line_start..].chars().count() + 1,
        }
    }
}

impl std::fmt::Display for Location {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}:{}", self.line, self.column)
    }
}

/// Errors in a study file.
#[derive(Debug, thiserror::Error)]
pub enum StudyError {
    /// The file could not be read.
    #[error("cannot read {}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// TOML syntax, a missing or unknown key, a wrong type.
    #[error("{origin}:{at}: {message}")]
    Parse {
        /// File or builtin name.
        origin: String,
        /// Where.
        at: Location,
        /// What the parser says.
        message: String,
    },
    /// A value that parses but makes no sense.
    #[error("{origin}{}: {message}", at.map(|l| format!(":{l}")).unwrap_or_default())]
    Invalid {
        /// File or builtin name (and variant).
        origin: String,
        /// Where, when known.
        at: Option<Location>,
        /// What is wrong.
        message: String,
    },
    /// No built-in study of that name.
    #[error("no built-in study '{0}' (see `uq-driver list`)")]
    UnknownBuiltin(String),
}

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
    /// Number of communication steps.
    pub fn n_steps(&self) -> usize {
        ((self.stop - self.start) / self.step).round() as usize
    }

    /// The communication points t_0 … t_n (s), computed as start + i·step (no drift).
    pub fn times(&self) -> Vec<f64> {
        let n = self.n_steps();
        (0..=n)
            .map(|i| {
                if i == n {
                    self.stop
                } else {
                    self.start + i as f64 * self.step
                }
            })
            .collect()
    }

    /// Checks that start < stop and step > 0 (all finite) and that stop − start is a whole
    /// number of steps.
    pub fn check(&self) -> Result<(), InvalidExperiment> {
        let finite = self.start.is_finite() && self.stop.is_finite() && self.step.is_finite();
        if !finite || self.step <= 0.0 || self.stop <= self.start {
            return Err(InvalidExperiment::Range {
                start: self.start,
                stop: self.stop,
                step: self.step,
            });
        }
        let ratio = (self.stop - self.start) / self.step;
        if (ratio - ratio.round()).abs() > 1e-6 * ratio.max(1.0) {
            return Err(InvalidExperiment::NotWholeSteps {
                span: self.stop - self.start,
                step: self.step,
            });
        }
        Ok(())
    }
}

/// A time grid that cannot be run.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum InvalidExperiment {
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
    /// The span is not a whole number of steps.
    #[error("stop − start = {span} s is not a whole number of communication steps of {step} s")]
    NotWholeSteps {
        /// stop − start (s).
        span: f64,
        /// Step (s).
        step: f64,
    },
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
    /// Samples of a chaos surrogate used for densities and quantiles.
    pub surrogate_samples: usize,
    /// Quantile levels written to the CSV.
    pub quantiles: Vec<f64>,
    /// Unweighted designs (MC/LHS): continue when some points fail and report how many.
    pub allow_failures: bool,
}

impl Default for Analysis {
    fn default() -> Self {
        Analysis {
            pdf_grid: 200,
            pdf_times: 250,
            surrogate_samples: 20_000,
            quantiles: vec![0.01, 0.5, 0.99],
            allow_failures: false,
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
    /// Random parameters.
    pub parameters: Vec<Spanned<ParameterSpec>>,
    /// Deterministic parameter values set before every run.
    #[serde(default)]
    pub fixed: BTreeMap<String, f64>,
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
    pub fixed: BTreeMap<String, f64>,
}

/// A validated study, ready to run.
#[derive(Clone, Debug)]
pub struct Study {
    /// Study name.
    pub name: String,
    /// Free text.
    pub description: String,
    /// Where it came from (file path or `builtin:NAME`; a variant's names the variant).
    pub origin: String,
    /// The TOML text (stored with plans).
    pub source: String,
    /// Folder relative paths start from.
    pub base: Option<PathBuf>,
    /// Resolved FMU path (methods that run a model).
    pub fmu_path: Option<PathBuf>,
    /// Seed of every random stream.
    pub seed: u64,
    /// Time grid.
    pub experiment: Experiment,
    /// Method settings.
    pub method: MethodSpec,
    /// Random parameters.
    pub parameters: Vec<RandomParameter>,
    /// Deterministic values.
    pub fixed: BTreeMap<String, f64>,
    /// Outputs analysed over time.
    pub outputs: Vec<String>,
    /// Scalar quantities of interest.
    pub qoi: Vec<QoiSpec>,
    /// Analysis settings.
    pub analysis: Analysis,
    /// An intrusive method's equations.
    pub system: Option<SystemSpec>,
    /// The variants, when the study is a suite.
    pub suite: Option<Suite>,
}

/// The variants of a suite, each a complete study.
#[derive(Clone, Debug)]
pub struct Suite {
    /// The variants in file order.
    pub variants: Vec<Study>,
    /// Index of the reference variant.
    pub reference: usize,
    /// Published values.
    pub paper: Vec<PaperValue>,
}

/// Folders searched for an FMU named by a relative path that is not next to the study file:
/// `$RAILUQ_FMU_DIR`, `<folder of the executable>/../fmu` (i.e. `target/fmu` for a cargo
/// build), `./target/fmu`.
pub fn fmu_search_path() -> Vec<PathBuf> {
    let mut dirs = Vec::new();
    if let Some(d) = std::env::var_os("RAILUQ_FMU_DIR") {
        dirs.push(PathBuf::from(d));
    }
    if let Ok(exe) = std::env::current_exe() {
        if let Some(parent) = exe.parent().and_then(Path::parent) {
            dirs.push(parent.join("fmu"));
        }
    }
    dirs.push(PathBuf::from("target/fmu"));
    dirs
}

impl Study {
    /// Loads `builtin:NAME` or a TOML file.
    pub fn load(spec: &str) -> Result<Study, StudyError> {
        if let Some(name) = spec.strip_prefix("builtin:") {
            return Study::parse(builtin(name)?, spec, None);
        }
        let path = Path::new(spec);
        let text = std::fs::read_to_string(path).map_err(|source| StudyError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Study::parse(&text, spec, path.parent())
    }

    /// Parses and validates a study; `base` is the folder relative FMU paths start from.
    pub fn parse(text: &str, origin: &str, base: Option<&Path>) -> Result<Study, StudyError> {
        let file: StudyFile = toml::from_str(text).map_err(|e| StudyError::Parse {
            origin: origin.to_owned(),
            at: Location::of(text, e.span().map_or(0, |s| s.start)),
            message: e.message().to_owned(),
        })?;
        validate::study(file, origin, base, text)
    }

    /// Whether the study is a set of variants to compare.
    pub fn is_suite(&self) -> bool {
        self.suite.is_some()
    }

    /// The method.
    pub fn method(&self) -> &dyn Method {
        self.method.method()
    }

    /// The communication points (s).
    pub fn times(&self) -> Vec<f64> {
        self.experiment.times()
    }

    /// What the method sees of the study; `times` are [`Study::times`].
    pub fn problem<'a>(&'a self, times: &'a [f64]) -> Problem<'a> {
        Problem {
            parameters: &self.parameters,
            outputs: &self.outputs,
            quantities: self.qoi.len(),
            times,
            system: self.system.as_ref(),
        }
    }
}

/// The text of a built-in study.
pub fn builtin(name: &str) -> Result<&'static str, StudyError> {
    BUILTINS
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, text)| *text)
        .ok_or_else(|| StudyError::UnknownBuiltin(name.to_owned()))
}

/// The location of the start of `span` in `text`.
fn location(text: &str, span: Range<usize>) -> Location {
    Location::of(text, span.start)
}

#[cfg(test)]
mod tests;
