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
//! kind = "scm"                 # "mc" | "lhs" | "scm"
//! nodes = 6                    # SCM: Gauss–Hermite nodes per dimension
//! order = 5                    # SCM: total order of the Hermite chaos (default nodes − 1)
//! # samples = 1000             # MC / LHS
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

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::uq::distributions::Distribution;

/// Errors in a study file.
#[derive(Debug, thiserror::Error)]
pub enum StudyError {
    /// The file could not be read.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// TOML syntax or a missing/unknown field.
    #[error("{origin}: {message}")]
    Parse {
        /// File or builtin name.
        origin: String,
        /// Parser message with line and column.
        message: String,
    },
    /// A value that parses but makes no sense.
    #[error("{origin}: {message}")]
    Invalid {
        /// File or builtin name.
        origin: String,
        /// What is wrong.
        message: String,
    },
    /// No built-in study of that name.
    #[error("no built-in study '{0}' (see `uq-driver list`)")]
    UnknownBuiltin(String),
}

/// The sampling or quadrature method.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Method {
    /// "mc", "lhs" or "scm".
    pub kind: MethodKind,
    /// MC/LHS: number of samples.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub samples: Option<usize>,
    /// SCM: Gauss–Hermite nodes per dimension (one number for all).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub nodes: Option<usize>,
    /// SCM: total order of the chaos (default nodes − 1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub order: Option<usize>,
}

/// Method names.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum MethodKind {
    /// Monte Carlo.
    Mc,
    /// Latin hypercube sampling.
    Lhs,
    /// Stochastic collocation: tensor Gauss–Hermite grid + Hermite chaos.
    Scm,
    /// Stochastic Galerkin method on a linear system given in the study file.
    Sgm,
    /// One deterministic run at the parameters' means.
    Nominal,
}

impl MethodKind {
    /// Name used in files and messages.
    pub fn as_str(self) -> &'static str {
        match self {
            MethodKind::Mc => "mc",
            MethodKind::Lhs => "lhs",
            MethodKind::Scm => "scm",
            MethodKind::Sgm => "sgm",
            MethodKind::Nominal => "nominal",
        }
    }
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
}

/// A random parameter as written in the file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParameterSpec {
    /// FMU variable name.
    pub name: String,
    /// "normal" (default), "lognormal", "uniform", "truncated_normal".
    #[serde(default = "default_distribution")]
    pub distribution: String,
    /// Mean (normal, truncated normal: of the parent normal; lognormal: of the variable).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mean: Option<f64>,
    /// Standard deviation (same convention as `mean`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub std: Option<f64>,
    /// Coefficient of variation, instead of `std`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cov: Option<f64>,
    /// Lower bound (uniform, truncated normal).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub low: Option<f64>,
    /// Upper bound (uniform, truncated normal).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub high: Option<f64>,
}

fn default_distribution() -> String {
    "normal".into()
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
    /// SCM: samples of the chaos surrogate used for densities and quantiles.
    pub surrogate_samples: usize,
    /// Quantile levels written to the CSV.
    pub quantiles: Vec<f64>,
    /// MC/LHS: continue when some points fail and report how many (SCM never does).
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
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StudyFile {
    /// Study name (used in reports).
    pub name: String,
    /// Free text.
    #[serde(default)]
    pub description: String,
    /// The FMU path (every method but SGM).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fmu: Option<String>,
    /// SGM: the linear system.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub system: Option<SystemSpec>,
    /// Seed of every random stream.
    #[serde(default = "default_seed")]
    pub seed: u64,
    /// Time grid.
    pub experiment: Experiment,
    /// Method.
    pub method: Method,
    /// Random parameters.
    pub parameters: Vec<ParameterSpec>,
    /// Deterministic parameter values set before every run.
    #[serde(default)]
    pub fixed: BTreeMap<String, f64>,
    /// Outputs.
    #[serde(default)]
    pub outputs: Outputs,
    /// Scalar quantities of interest computed from each run.
    #[serde(default)]
    pub qoi: Vec<QoiSpec>,
    /// Analysis settings.
    #[serde(default)]
    pub analysis: Analysis,
    /// Variants run one after the other into sub-folders, then compared.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub variants: Vec<Variant>,
    /// Name of the variant the others are compared against (default: the first).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reference: Option<String>,
    /// Published values to print beside ours in a suite's comparison table.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub paper: Vec<PaperValue>,
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
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Variant {
    /// Sub-folder and label.
    pub name: String,
    /// Method of this variant (default: the study's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub method: Option<Method>,
    /// Random parameters of this variant (default: the study's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub parameters: Option<Vec<ParameterSpec>>,
    /// Deterministic values of this variant, merged over the study's `[fixed]`.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub fixed: BTreeMap<String, f64>,
}

/// SGM: `M q'' + C q' + K q = f`, each matrix affine in the random parameters:
/// `A = A_given + Σ_j p_j · D_j` for each `[[system.dependence]]` (p_j Gaussian).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SystemSpec {
    /// DOF names (outputs refer to them; `<name>_dot` is the velocity).
    pub dofs: Vec<String>,
    /// Mass matrix (constant part), n × n.
    #[serde(rename = "M")]
    pub m: Vec<Vec<f64>>,
    /// Damping matrix (constant part).
    #[serde(rename = "C")]
    pub c: Vec<Vec<f64>>,
    /// Stiffness matrix (constant part).
    #[serde(rename = "K")]
    pub k: Vec<Vec<f64>>,
    /// Initial displacement (constant part).
    pub q0: Vec<f64>,
    /// Initial velocity (constant part; default zeros).
    #[serde(default)]
    pub v0: Vec<f64>,
    /// Constant load vector (default zeros).
    #[serde(default)]
    pub force: Vec<f64>,
    /// Largest RK4 step of the Galerkin system (s).
    #[serde(default = "default_sgm_step")]
    pub step: f64,
    /// How the random parameters enter.
    #[serde(default)]
    pub dependence: Vec<Dependence>,
}

fn default_sgm_step() -> f64 {
    1e-3
}

/// `matrix += parameter · d`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Dependence {
    /// Name of a random parameter.
    pub parameter: String,
    /// "M", "C", "K", "q0" or "v0".
    pub matrix: String,
    /// Coefficient matrix (n × n), or vector (n) for q0/v0.
    pub d: toml::Value,
}

/// A scalar quantity of interest computed from each run's time series.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum QoiSpec {
    /// Speed at which an oscillation dies out on a speed ramp (see qoi::critical_speed).
    CriticalSpeed {
        /// Name in reports.
        name: String,
        /// Oscillating signal (e.g. "Y").
        signal: String,
        /// Speed signal (e.g. "V").
        speed: String,
        /// Sliding window (s).
        #[serde(default = "default_window")]
        window: f64,
        /// Amplitude threshold (units of the signal).
        #[serde(default = "default_threshold")]
        threshold: f64,
        /// Exceedance limits: P(q > limit) is reported.
        #[serde(default)]
        limits: Vec<f64>,
    },
    /// Sperling ride index of an acceleration signal (see qoi::sperling).
    Sperling {
        /// Name in reports.
        name: String,
        /// Acceleration signal (m/s²).
        signal: String,
        /// "vertical" or "lateral".
        #[serde(default = "default_direction")]
        direction: String,
        /// FFT segment length (s).
        #[serde(default = "default_segment")]
        segment: f64,
        /// Lowest frequency (Hz).
        #[serde(default = "default_fmin")]
        f_min: f64,
        /// Highest frequency (Hz).
        #[serde(default = "default_fmax")]
        f_max: f64,
        /// Initial transient left out (s).
        #[serde(default)]
        skip: f64,
        /// Exceedance limits.
        #[serde(default)]
        limits: Vec<f64>,
    },
    /// Largest |signal| over [from, to] (s).
    MaxAbs {
        /// Name in reports.
        name: String,
        /// Signal.
        signal: String,
        /// Start of the interval (s).
        #[serde(default)]
        from: f64,
        /// End of the interval (s; default the stop time).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        to: Option<f64>,
        /// Exceedance limits.
        #[serde(default)]
        limits: Vec<f64>,
    },
    /// Value of a signal at the stop time.
    Final {
        /// Name in reports.
        name: String,
        /// Signal.
        signal: String,
        /// Exceedance limits.
        #[serde(default)]
        limits: Vec<f64>,
    },
}

fn default_window() -> f64 {
    1.0
}
fn default_threshold() -> f64 {
    1e-4
}
fn default_direction() -> String {
    "vertical".into()
}
fn default_segment() -> f64 {
    5.0
}
fn default_fmin() -> f64 {
    0.5
}
fn default_fmax() -> f64 {
    40.0
}

impl QoiSpec {
    /// The quantity's name.
    pub fn name(&self) -> &str {
        match self {
            QoiSpec::CriticalSpeed { name, .. }
            | QoiSpec::Sperling { name, .. }
            | QoiSpec::MaxAbs { name, .. }
            | QoiSpec::Final { name, .. } => name,
        }
    }

    /// The FMU signals it reads.
    pub fn signals(&self) -> Vec<&str> {
        match self {
            QoiSpec::CriticalSpeed { signal, speed, .. } => vec![signal, speed],
            QoiSpec::Sperling { signal, .. }
            | QoiSpec::MaxAbs { signal, .. }
            | QoiSpec::Final { signal, .. } => {
                vec![signal]
            }
        }
    }

    /// Exceedance limits.
    pub fn limits(&self) -> &[f64] {
        match self {
            QoiSpec::CriticalSpeed { limits, .. }
            | QoiSpec::Sperling { limits, .. }
            | QoiSpec::MaxAbs { limits, .. }
            | QoiSpec::Final { limits, .. } => limits,
        }
    }
}

fn default_seed() -> u64 {
    42
}

/// A random parameter, validated.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RandomParameter {
    /// FMU variable name.
    pub name: String,
    /// Its distribution.
    pub distribution: Distribution,
}

/// A validated study, ready to run.
#[derive(Clone, Debug, Serialize)]
pub struct Study {
    /// The file content.
    pub file: StudyFile,
    /// Resolved FMU path.
    pub fmu_path: PathBuf,
    /// Validated random parameters.
    pub parameters: Vec<RandomParameter>,
    /// Where it came from (file path or `builtin:NAME`).
    pub origin: String,
    /// The TOML text (stored with the results).
    pub source: String,
    /// Folder relative paths start from.
    #[serde(skip)]
    pub base: Option<PathBuf>,
}

/// The built-in studies, embedded in the binary: (name, TOML).
pub const BUILTINS: &[(&str, &str)] = &[
    ("wheel-scm", include_str!("../../studies/wheel-scm.toml")),
    (
        "wheel-lhs-1000",
        include_str!("../../studies/wheel-lhs-1000.toml"),
    ),
    (
        "wheel-lhs-10000",
        include_str!("../../studies/wheel-lhs-10000.toml"),
    ),
    (
        "wheel-lhs-50000",
        include_str!("../../studies/wheel-lhs-50000.toml"),
    ),
    ("wheel-mc", include_str!("../../studies/wheel-mc.toml")),
    ("wheel-sgm", include_str!("../../studies/wheel-sgm.toml")),
    (
        "paper-wheel",
        include_str!("../../studies/paper-wheel.toml"),
    ),
    (
        "bogie-nominal",
        include_str!("../../studies/bogie-nominal.toml"),
    ),
    ("bogie-scm", include_str!("../../studies/bogie-scm.toml")),
    (
        "bogie-lhs-500",
        include_str!("../../studies/bogie-lhs-500.toml"),
    ),
    (
        "bogie-lhs-20000",
        include_str!("../../studies/bogie-lhs-20000.toml"),
    ),
    (
        "paper-bogie",
        include_str!("../../studies/paper-bogie.toml"),
    ),
    (
        "vehicle-track-nominal",
        include_str!("../../studies/vehicle-track-nominal.toml"),
    ),
    (
        "vehicle-track-scm-cov10",
        include_str!("../../studies/vehicle-track-scm-cov10.toml"),
    ),
    (
        "vehicle-track-scm-cov20",
        include_str!("../../studies/vehicle-track-scm-cov20.toml"),
    ),
    (
        "vehicle-track-scm-cov30",
        include_str!("../../studies/vehicle-track-scm-cov30.toml"),
    ),
    (
        "vehicle-track-defect",
        include_str!("../../studies/vehicle-track-defect.toml"),
    ),
    (
        "paper-vehicle-track",
        include_str!("../../studies/paper-vehicle-track.toml"),
    ),
];

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
            let (_, text) = BUILTINS
                .iter()
                .find(|(n, _)| *n == name)
                .ok_or_else(|| StudyError::UnknownBuiltin(name.to_owned()))?;
            return Study::parse(text, spec, None);
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
            message: e.to_string(),
        })?;
        Study::from_file(file, origin, base, text)
    }

    /// Whether the study is a set of variants to compare.
    pub fn is_suite(&self) -> bool {
        !self.file.variants.is_empty()
    }

    /// The variants as complete studies (the study's method/parameters/fixed values replaced
    /// by each variant's), each named after the variant.
    pub fn variants(&self) -> Result<Vec<Study>, StudyError> {
        let base = self.base.as_deref();
        self.file
            .variants
            .iter()
            .map(|v| {
                let mut f = self.file.clone();
                f.variants.clear();
                f.reference = None;
                f.name = v.name.clone();
                if let Some(m) = &v.method {
                    f.method = m.clone();
                }
                if let Some(p) = &v.parameters {
                    f.parameters = p.clone();
                }
                for (k, x) in &v.fixed {
                    f.fixed.insert(k.clone(), *x);
                }
                let origin = format!("{} (variant {})", self.origin, v.name);
                Study::from_file(f, &origin, base, &self.source)
            })
            .collect()
    }

    fn from_file(
        file: StudyFile,
        origin: &str,
        base: Option<&Path>,
        text: &str,
    ) -> Result<Study, StudyError> {
        let invalid = |message: String| StudyError::Invalid {
            origin: origin.to_owned(),
            message,
        };
        let e = &file.experiment;
        if !(e.start.is_finite() && e.stop.is_finite() && e.step.is_finite())
            || e.step <= 0.0
            || e.stop <= e.start
        {
            return Err(invalid(format!(
                "experiment needs finite start < stop and step > 0 (got start {}, stop {}, step {})",
                e.start, e.stop, e.step
            )));
        }
        let ratio = (e.stop - e.start) / e.step;
        if (ratio - ratio.round()).abs() > 1e-6 * ratio.max(1.0) {
            return Err(invalid(format!(
                "stop − start = {} s is not a whole number of communication steps of {} s",
                e.stop - e.start,
                e.step
            )));
        }
        if file.parameters.is_empty() {
            return Err(invalid("no random [[parameters]]".into()));
        }
        if file.outputs.variables.is_empty() && file.qoi.is_empty() {
            return Err(invalid(
                "nothing to analyse: give [outputs] variables and/or [[qoi]]".into(),
            ));
        }
        let mut parameters = Vec::new();
        for p in &file.parameters {
            if parameters
                .iter()
                .any(|q: &RandomParameter| q.name == p.name)
            {
                return Err(invalid(format!("parameter '{}' is listed twice", p.name)));
            }
            if file.fixed.contains_key(&p.name) {
                return Err(invalid(format!(
                    "parameter '{}' is both random and fixed",
                    p.name
                )));
            }
            let distribution = p
                .to_distribution()
                .map_err(|m| invalid(format!("parameter '{}': {m}", p.name)))?;
            parameters.push(RandomParameter {
                name: p.name.clone(),
                distribution,
            });
        }
        for (name, v) in &file.fixed {
            if !v.is_finite() {
                return Err(invalid(format!("fixed value of '{name}' is not finite")));
            }
        }
        let mut names: Vec<&str> = file.outputs.variables.iter().map(String::as_str).collect();
        for q in &file.qoi {
            if names.contains(&q.name()) {
                return Err(invalid(format!(
                    "quantity name '{}' is used twice",
                    q.name()
                )));
            }
            names.push(q.name());
            let bad = match q {
                QoiSpec::CriticalSpeed {
                    window, threshold, ..
                } => !(*window > 0.0 && *threshold > 0.0),
                QoiSpec::Sperling {
                    direction,
                    segment,
                    f_min,
                    f_max,
                    skip,
                    ..
                } => {
                    !(direction == "vertical" || direction == "lateral")
                        || !(*segment > 0.0 && *f_min > 0.0 && f_max > f_min && *skip >= 0.0)
                        || *skip + *segment > e.stop - e.start + 1e-9
                }
                QoiSpec::MaxAbs { from, to, .. } => to.is_some_and(|t| t <= *from),
                QoiSpec::Final { .. } => false,
            };
            if bad || q.limits().iter().any(|l| !l.is_finite()) {
                return Err(invalid(format!(
                    "quantity '{}': invalid settings (windows, thresholds and segments > 0, \
                     a Sperling direction of vertical/lateral with f_min < f_max and skip + segment within the run, finite limits)",
                    q.name()
                )));
            }
        }
        let m = &file.method;
        match m.kind {
            MethodKind::Mc | MethodKind::Lhs => {
                let n = m.samples.ok_or_else(|| {
                    invalid(format!("method {} needs `samples`", m.kind.as_str()))
                })?;
                if n < 2 {
                    return Err(invalid("`samples` must be at least 2".into()));
                }
            }
            MethodKind::Scm => {
                let nodes = m
                    .nodes
                    .ok_or_else(|| invalid("method scm needs `nodes` (per dimension)".into()))?;
                if nodes == 0 || nodes > 64 {
                    return Err(invalid(format!("`nodes` = {nodes} must be in 1..=64")));
                }
                let order = m.order.unwrap_or(nodes.saturating_sub(1));
                if order >= nodes {
                    return Err(invalid(format!(
                        "chaos order {order} must be below the nodes per dimension ({nodes}): \
                         the quadrature cannot integrate the basis norms exactly otherwise"
                    )));
                }
                let total = (nodes as f64).powi(parameters.len() as i32);
                if total > 5e6 {
                    return Err(invalid(format!(
                        "tensor grid of {nodes}^{} points is too large",
                        parameters.len()
                    )));
                }
            }
            MethodKind::Nominal => {}
            MethodKind::Sgm => {
                let order = m
                    .order
                    .ok_or_else(|| invalid("method sgm needs `order`".into()))?;
                if order > 12 {
                    return Err(invalid(format!("SGM order {order} is above 12")));
                }
                if let Some(p) = parameters.iter().find(|p| !p.distribution.is_gaussian()) {
                    return Err(invalid(format!(
                        "SGM needs Gaussian parameters (Hermite chaos); '{}' is not",
                        p.name
                    )));
                }
                let sys = file.system.as_ref().ok_or_else(|| {
                    invalid("method sgm needs a [system] (matrices M, C, K, q0)".into())
                })?;
                super::sgm::validate(sys, &parameters, &file.outputs.variables).map_err(invalid)?;
                if !file.qoi.is_empty() {
                    return Err(invalid(
                        "[[qoi]] is not available with SGM (no time series of a model is run)"
                            .into(),
                    ));
                }
            }
        }
        if m.kind != MethodKind::Sgm && file.fmu.is_none() {
            return Err(invalid("`fmu` is required (the FMU to run)".into()));
        }
        let a = &file.analysis;
        if a.pdf_grid < 2 || a.pdf_times < 1 || a.quantiles.iter().any(|q| !(0.0..=1.0).contains(q))
        {
            return Err(invalid(
                "analysis: pdf_grid >= 2, pdf_times >= 1, quantiles in [0, 1]".into(),
            ));
        }
        let mut seen = Vec::new();
        for v in &file.variants {
            if seen.contains(&&v.name) || v.name.is_empty() || v.name.contains(['/', '\\', '.']) {
                return Err(invalid(format!(
                    "variant name '{}' is empty, repeated or not a plain folder name",
                    v.name
                )));
            }
            seen.push(&v.name);
        }
        if let Some(r) = &file.reference {
            if !file.variants.iter().any(|v| &v.name == r) {
                return Err(invalid(format!(
                    "reference '{r}' is not one of the variants"
                )));
            }
        }
        let fmu_path = file
            .fmu
            .as_deref()
            .map(|f| resolve_fmu(f, base))
            .unwrap_or_default();
        let study = Study {
            file,
            fmu_path,
            parameters,
            origin: origin.to_owned(),
            source: text.to_owned(),
            base: base.map(Path::to_path_buf),
        };
        // Every variant must be a valid study too.
        if study.is_suite() {
            study.variants()?;
        }
        Ok(study)
    }
}

fn resolve_fmu(fmu: &str, base: Option<&Path>) -> PathBuf {
    let p = Path::new(fmu);
    if p.is_absolute() {
        return p.to_path_buf();
    }
    if let Some(b) = base {
        let c = b.join(p);
        if c.exists() {
            return c;
        }
    }
    if p.exists() {
        return p.to_path_buf();
    }
    for d in fmu_search_path() {
        let c = d.join(p);
        if c.exists() {
            return c;
        }
    }
    base.map(|b| b.join(p)).unwrap_or_else(|| p.to_path_buf())
}

impl ParameterSpec {
    fn to_distribution(&self) -> Result<Distribution, String> {
        let need = |v: Option<f64>, what: &str| v.ok_or_else(|| format!("`{what}` is required"));
        let std = || -> Result<f64, String> {
            match (self.std, self.cov) {
                (Some(s), None) => Ok(s),
                (None, Some(c)) => Ok(need(self.mean, "mean")?.abs() * c),
                (Some(_), Some(_)) => Err("give `std` or `cov`, not both".into()),
                (None, None) => Err("`std` or `cov` is required".into()),
            }
        };
        let d = match self.distribution.as_str() {
            "normal" => Distribution::normal(need(self.mean, "mean")?, std()?),
            "lognormal" => Distribution::lognormal_from_mean_std(need(self.mean, "mean")?, std()?),
            "uniform" => Distribution::uniform(need(self.low, "low")?, need(self.high, "high")?),
            "truncated_normal" => Distribution::truncated_normal(
                need(self.mean, "mean")?,
                std()?,
                need(self.low, "low")?,
                need(self.high, "high")?,
            ),
            other => {
                return Err(format!(
                    "unknown distribution '{other}' (normal, lognormal, uniform, truncated_normal)"
                ))
            }
        };
        d.map_err(|e| e.to_string())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_builtin_parses() {
        for (name, _) in BUILTINS {
            let s = Study::load(&format!("builtin:{name}")).unwrap();
            assert_eq!(&s.file.name, name);
        }
    }

    #[test]
    fn wrong_study_files_give_clear_errors() {
        let base = include_str!("../../studies/wheel-scm.toml");
        let cases = [
            (base.replace("stop = 5.0", "stop = -1.0"), "start < stop"),
            (base.replace("order = 5", "order = 6"), "below the nodes"),
            (base.replace("std = 10.0", "std = -10.0"), "parameter 'K'"),
            (
                base.replace("kind = \"scm\"", "kind = \"magic\""),
                "unknown variant",
            ),
            (
                base.replace("[outputs]", "[outputs]\ncolour = 1"),
                "unknown field",
            ),
            (base.replace("step = 0.01", "step = 0.03"), "whole number"),
        ];
        for (text, needle) in cases {
            let err = Study::parse(&text, "t.toml", None).unwrap_err().to_string();
            assert!(err.contains(needle), "{err} should mention {needle}");
            assert!(err.starts_with("t.toml"), "{err}");
        }
        assert!(matches!(
            Study::load("builtin:nope"),
            Err(StudyError::UnknownBuiltin(_))
        ));
        assert!(matches!(
            Study::load("/nonexistent.toml"),
            Err(StudyError::Io { .. })
        ));
    }

    #[test]
    fn times_do_not_drift() {
        let e = Experiment {
            start: 0.0,
            stop: 5.0,
            step: 0.01,
        };
        let t = e.times();
        assert_eq!(t.len(), 501);
        assert_eq!(t[500], 5.0);
        assert_eq!(t[3], 0.03);
    }
}
