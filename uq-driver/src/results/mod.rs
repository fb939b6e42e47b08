//! Typed results of a study: statistics of every output over time and of every scalar
//! quantity, the design's points, and the summaries written to `summary.json`.
//!
//! The field names of [`Summary`] and [`SuiteSummary`] are a public interface (they are the
//! keys of `summary.json`): add fields, rename none.

#![forbid(unsafe_code)]

mod exceedance;
mod nested;
pub mod numbers;
mod reliability;

pub use crate::qoi::scalar::QuantityDefinition;
use crate::text::file_name::stem;
use std::collections::BTreeMap;

use serde::Serialize;

pub use exceedance::ExceedanceCount;
pub use nested::{
    ConditionalChaos, ConditionalTable, ExceedanceInterval, NestedScalar, OutputSplit,
    VarianceSplit,
};
pub(crate) use reliability::direction;
pub use reliability::{LimitProbability, MorrisScreening};

use crate::spec::{Experiment, FixedValue, PaperValue};
use crate::uq::distributions::RandomParameter;
use crate::uq::method::{ChaosError, Draws, MethodSummary, Sobol};
use crate::uq::random_inputs::Correlation;

/// Statistics of one output variable over time.
#[derive(Clone, Debug)]
#[non_exhaustive]
pub struct OutputStats {
    /// Variable name.
    pub name: String,
    /// Communication points (s).
    pub times: Vec<f64>,
    /// Mean over time.
    pub mean: Vec<f64>,
    /// Standard deviation over time.
    pub std: Vec<f64>,
    /// mean − 3 std.
    pub lower_3sigma: Vec<f64>,
    /// mean + 3 std.
    pub upper_3sigma: Vec<f64>,
    /// Quantiles over time: (level, values).
    pub quantiles: Vec<(f64, Vec<f64>)>,
    /// Std of the chaos surrogate where it differs from `std` (collocation).
    pub std_pce: Option<Vec<f64>>,
    /// Standard error of the mean over time, where the method estimates it (sampling).
    pub std_error_mean: Option<Vec<f64>>,
    /// First-order and total Sobol' indices over time.
    pub sobol: Option<Sobol>,
    /// PDF evolution: times of the columns.
    pub pdf_times: Vec<f64>,
    /// Grid of the densities.
    pub pdf_grid: Vec<f64>,
    /// `pdf[i][j]`: density at `pdf_times[i]`, `pdf_grid[j]`.
    pub pdf: Vec<Vec<f64>>,
    /// Where the quantiles and densities come from.
    pub draws: Draws,
    /// The chaos's estimated truncation error over time (a column of `<V>.csv` named after
    /// its kind: `loo`, `level_difference` or `order_difference`).
    pub chaos_error: Option<ChaosError>,
    /// Every run (or draw) has the same value at every time: no density is drawn.
    pub deterministic: bool,
    /// Unit of the variable, from the FMU's modelDescription (`None`: not declared).
    pub unit: Option<String>,
    /// Mean and Std at `convergence_time` against the work spent (runs, or chaos order).
    pub convergence: Option<Convergence>,
    /// The time of the convergence plot: where the Std is largest (s).
    pub convergence_time: Option<f64>,
    /// How a chaos method fitted the series (principal components or columns).
    pub functional: Option<FunctionalFit>,
}

/// How a chaos method fitted a series output (`summary.json`: `outputs.<V>.functional`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FunctionalFit {
    /// `pca`: one chaos per principal component of the centred runs; `columns`: one per
    /// distinct time column.
    pub method: String,
    /// Principal components kept (`pca`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub modes: Option<usize>,
    /// Chaoses fitted: the modes, or the distinct columns (identical columns are fitted once).
    pub fits: usize,
    /// The share of the variance the components were to keep (`[analysis] retained_variance`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub retained_variance: Option<f64>,
    /// The share of the series' variance (summed over its columns) the kept components miss.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub discarded_variance: Option<f64>,
    /// The largest share of one column's variance they miss (columns whose Std is above
    /// 1e-3 of the largest); part of that column's truncation-error estimate.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub discarded_max: Option<f64>,
}

impl OutputStats {
    /// The `mean ± k std` band.
    pub fn band(mean: &[f64], std: &[f64], k: f64) -> (Vec<f64>, Vec<f64>) {
        mean.iter()
            .zip(std)
            .map(|(m, s)| (m - k * s, m + k * s))
            .unzip()
    }

    /// An output `name` of constant `mean` and `std` at `times`, with its ±3σ band and
    /// nothing else (a fixture of the report's tests).
    #[cfg(test)]
    pub(crate) fn constant(name: &str, times: Vec<f64>, mean: f64, std: f64) -> OutputStats {
        let m = vec![mean; times.len()];
        let sd = vec![std; times.len()];
        let (lower_3sigma, upper_3sigma) = OutputStats::band(&m, &sd, 3.0);
        OutputStats {
            name: name.into(),
            times,
            mean: m,
            std: sd,
            lower_3sigma,
            upper_3sigma,
            quantiles: Vec::new(),
            std_pce: None,
            std_error_mean: None,
            sobol: None,
            pdf_times: Vec::new(),
            pdf_grid: Vec::new(),
            pdf: Vec::new(),
            draws: crate::uq::method::Draws::Runs,
            chaos_error: None,
            deterministic: false,
            unit: None,
            convergence: None,
            convergence_time: None,
            functional: None,
        }
    }
}

/// Statistics of one scalar quantity of interest.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[non_exhaustive]
pub struct ScalarStats {
    /// Quantity name.
    pub name: String,
    /// Mean.
    pub mean: f64,
    /// Standard deviation.
    pub std: f64,
    /// Standard error of the mean, where the method estimates it (sampling: e.g. std/√n);
    /// `None` (`null` in summary.json) for quadrature and chaos methods, which have none.
    pub std_error_mean: Option<f64>,
    /// Runs with a valid value.
    pub n_valid: usize,
    /// Critical speed: runs that never hunt.
    pub n_never_hunts: usize,
    /// Critical speed: runs whose oscillation never dies out.
    pub n_never_stops: usize,
    /// (level, value) quantiles (of the runs, or of the chaos surrogate).
    pub quantiles: Vec<(f64, f64)>,
    /// Smallest value over the runs.
    pub min: f64,
    /// Largest.
    pub max: f64,
    /// P(q > limit): (limit, p, standard error of p).
    pub exceedance: Vec<(f64, f64, f64)>,
    /// P(q > limit) as counts: how many of how many draws exceeded, with the exact
    /// (Clopper–Pearson) 95 % interval; the honest statement when none exceeded.
    pub exceedance_counts: Vec<ExceedanceCount>,
    /// Every run gives the same value (or there is one run): no density is estimated
    /// (`pdf_x` and `pdf` are empty).
    pub deterministic: bool,
    /// Unit of the quantity (from the FMU's modelDescription; `"1"` for a dimensionless
    /// index, `None` when not declared).
    pub unit: Option<String>,
    /// How the quantity is computed from each run: kind, signal and every setting
    /// (defaults included), and one line of text.
    pub definition: QuantityDefinition,
    /// Mean and Std against the work spent (runs, or chaos order), for the report.
    #[serde(skip)]
    pub convergence: Option<Convergence>,
    /// PDF grid.
    pub pdf_x: Vec<f64>,
    /// PDF values (KDE of the runs, or of the chaos surrogate).
    pub pdf: Vec<f64>,
    /// The valid values of the runs (for histograms).
    #[serde(skip)]
    pub samples: Vec<f64>,
    /// The samples the PDF and quantiles come from (runs, or the surrogate).
    #[serde(skip)]
    pub density_samples: Vec<f64>,
    /// First-order Sobol' indices per parameter, where the method gives them.
    pub sobol_first: Option<Vec<f64>>,
    /// Total Sobol' indices per parameter.
    pub sobol_total: Option<Vec<f64>>,
    /// The Sobol' indices labelled by parameter name, with their confidence intervals where
    /// the method gives them.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sobol: Option<SobolSummary>,
    /// Where the quantiles and the PDF come from.
    #[serde(skip)]
    pub draws: Draws,
    /// The chaos's estimated relative truncation error (chaos methods).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub chaos_error: Option<ScalarChaosError>,
    /// A nested study's variance split, intervals and conditional statistics (its keys
    /// `variance_split`, `mean_ci`, `std_ci`, `exceedance_ci`, ... sit beside the others).
    #[serde(flatten)]
    pub nested: Option<NestedScalar>,
    /// The probability of each limit (`limits`, above, then `limits_below`), from the
    /// reliability method, the runs or the chaos's draws (absent when the quantity has no
    /// limit).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reliability: Option<Vec<LimitProbability>>,
    /// Morris's screening measures (a `morris` study).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub morris: Option<MorrisScreening>,
    /// Spearman's and partial rank correlation coefficients of the quantity with each
    /// parameter, from the runs (designs that sample the inputs' law: `mc`, `lhs`, `qmc`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rank_correlation: Option<RankCorrelation>,
    /// The physical parameter values of the runs of `samples` (`[parameter][run]`), for the
    /// scatter plots (designs that sample the inputs' law).
    #[serde(skip)]
    pub run_inputs: Option<Vec<Vec<f64>>>,
}

/// Rank correlations of a scalar quantity with each parameter, by parameter name
/// (`quantities.NAME.rank_correlation` in `summary.json`; `null` where undefined: a
/// parameter or a quantity without spread).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RankCorrelation {
    /// Spearman's coefficient (the correlation of the ranks).
    pub spearman: BTreeMap<String, f64>,
    /// The partial rank correlation coefficient (the other parameters' linear effect on
    /// the ranks removed).
    pub prcc: BTreeMap<String, f64>,
}

/// A scalar quantity's chaos truncation error in `summary.json`:
/// `{"kind": "loo" | "level_difference" | "order_difference", "value": ...}`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ScalarChaosError {
    /// How it was estimated.
    pub kind: &'static str,
    /// The relative error.
    pub value: f64,
    /// The second estimate the warnings judge instead, where `value` is known to be biased
    /// (a sparse grid's level difference extrapolated to its own level; a sparse
    /// regression's k-fold cross-validation error where larger than its leave-one-out one).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub check: Option<f64>,
}

/// Sobol' indices of a scalar quantity by parameter name (`quantities.NAME.sobol` in
/// `summary.json`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SobolSummary {
    /// First-order index of each parameter.
    pub first: BTreeMap<String, f64>,
    /// Total index of each parameter (empty, and not written, for given-data estimates).
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub total: BTreeMap<String, f64>,
    /// `[low, high]` interval of each first-order index, where estimated.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub first_ci: Option<BTreeMap<String, [f64; 2]>>,
    /// `[low, high]` interval of each total index, where estimated.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub total_ci: Option<BTreeMap<String, [f64; 2]>>,
    /// Confidence level of the intervals.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ci_level: Option<f64>,
    /// How the indices were estimated where it is not from the method's own design:
    /// `"given_data"` (first-order indices from a sample of the inputs' law, by binning,
    /// with bootstrap intervals; no total indices).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub estimator: Option<&'static str>,
}

impl SobolSummary {
    /// Column `col` of `sobol`, labelled by `names` (the parameters, in study order).
    pub fn of(sobol: &Sobol, col: usize, names: &[&str]) -> SobolSummary {
        let label = |v: &[f64]| by_name(names, v.iter().copied());
        let label_ci = |v: &[(f64, f64)]| by_name(names, v.iter().map(|&(lo, hi)| [lo, hi]));
        let ci = sobol.intervals.as_ref();
        // Given data: first-order indices only.
        let total = !sobol.given_data;
        SobolSummary {
            first: label(&sobol.first[col]),
            total: if total {
                label(&sobol.total[col])
            } else {
                BTreeMap::new()
            },
            first_ci: ci.map(|c| label_ci(&c.first[col])),
            total_ci: ci.filter(|_| total).map(|c| label_ci(&c.total[col])),
            ci_level: ci.map(|c| c.level),
            estimator: sobol.given_data.then_some("given_data"),
        }
    }
}

/// `values` keyed by `names` (the parameters, in study order), as `summary.json` lists them.
pub(crate) fn by_name<T>(names: &[&str], values: impl Iterator<Item = T>) -> BTreeMap<String, T> {
    names.iter().map(|n| n.to_string()).zip(values).collect()
}

/// `1234567` as `1 234 567`.
pub fn group_digits(n: usize) -> String {
    let s = n.to_string();
    let mut out = String::new();
    for (i, ch) in s.chars().enumerate() {
        if i > 0 && (s.len() - i).is_multiple_of(3) {
            out.push('\u{202f}');
        }
        out.push(ch);
    }
    out
}

/// Three significant digits, plain for 1e-3 ≤ |x| < 1e5, else with an exponent.
pub fn sig(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let a = x.abs();
    if (1e-3..1e5).contains(&a) {
        let decimals = (2 - a.log10().floor() as i32).max(0) as usize;
        format!("{x:.decimals$}")
    } else {
        format!("{x:.2e}")
    }
}

/// Mean and Std of an estimate against the work spent.
#[derive(Clone, Debug, PartialEq)]
pub struct Convergence {
    /// What `x` counts: `runs` (running estimates over the first n runs) or `chaos order`.
    pub axis: String,
    /// Runs, or orders.
    pub x: Vec<f64>,
    /// Mean at each x.
    pub mean: Vec<f64>,
    /// Std at each x.
    pub std: Vec<f64>,
    /// Chaos: the Std of the terms of each total order alone (its decay shows the
    /// convergence of the expansion); empty for runs.
    pub std_of_order: Vec<f64>,
    /// The standard error of the mean at each x where the runs are not independent draws
    /// (a nested study: between its whole outer samples, whose runs `x` counts); empty when
    /// it is `Std/√n` of independent runs.
    pub std_error_mean: Vec<f64>,
}

/// Outcome of one point of a design.
#[derive(Clone, Debug, PartialEq)]
pub enum PointStatus {
    /// The run succeeded.
    Ok,
    /// The run failed, with the reason.
    Failed(String),
    /// Not run.
    Missing,
}

/// The design with the outcome of every point (`points.csv`).
#[derive(Clone, Debug, PartialEq)]
pub struct PointTable {
    /// Parameter names (columns).
    pub names: Vec<String>,
    /// Quadrature weights, if the design has them.
    pub weights: Option<Vec<f64>>,
    /// Parameter values per point.
    pub values: Vec<Vec<f64>>,
    /// Outcome per point.
    pub status: Vec<PointStatus>,
}

/// The FMU a study ran.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FmuInfo {
    /// Path as given.
    pub path: String,
    /// `modelName`.
    pub model_name: String,
    /// GUID.
    pub guid: String,
    /// `generationTool`.
    pub generation_tool: Option<String>,
    /// SHA-256 of the FMU.
    pub sha256: String,
    /// The FMU's String calculated parameters, name → value, read once after initializing an
    /// instance with its default parameters (e.g. VehicleTrack's `solver.kernel`: the
    /// instruction sets its solver runs on); empty when it has none.
    pub calculated_strings: BTreeMap<String, String>,
}

/// Versions of the driver and of FMI.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Versions {
    /// uq-driver version.
    pub uq_driver: String,
    /// FMI version.
    pub fmi: String,
}

impl Default for Versions {
    fn default() -> Self {
        Versions {
            uq_driver: env!("CARGO_PKG_VERSION").into(),
            fmi: "2.0".into(),
        }
    }
}

/// An output's entry in `summary.json`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct OutputSummary {
    /// `<V>.csv`.
    pub csv: String,
    /// `<V>_pdf.csv`; `null` for a deterministic output, which has no density (no file).
    pub pdf_csv: Option<String>,
    /// Mean at the stop time.
    pub mean_at_stop: f64,
    /// Std at the stop time.
    pub std_at_stop: f64,
    /// Largest Std over time.
    pub max_std: f64,
    /// When it is reached (s).
    pub time_of_max_std: f64,
    /// Unit of the variable (modelDescription); the unit of every column of `<V>.csv`
    /// except `time` (s).
    pub unit: Option<String>,
    /// Every run has the same value at every time (no density is drawn).
    pub deterministic: bool,
    /// How a chaos method fitted the series (absent for the other methods).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub functional: Option<FunctionalFit>,
}

impl OutputSummary {
    /// The entry of `s`.
    pub fn of(s: &OutputStats) -> OutputSummary {
        let last = s.times.len() - 1;
        let imax = (0..s.std.len())
            .max_by(|&a, &b| s.std[a].total_cmp(&s.std[b]))
            .unwrap_or(0);
        OutputSummary {
            csv: format!("{}.csv", stem(&s.name)),
            pdf_csv: (!s.deterministic).then(|| format!("{}_pdf.csv", stem(&s.name))),
            mean_at_stop: s.mean[last],
            std_at_stop: s.std[last],
            max_std: s.std[imax],
            time_of_max_std: s.times[imax],
            unit: s.unit.clone(),
            deterministic: s.deterministic,
            functional: s.functional.clone(),
        }
    }
}

/// The random parameters with the mean and Std of each (a truncated normal's own
/// moments, which the README promised in `summary.json`, were only on the page).
fn parameters_with_moments<S: serde::Serializer>(
    parameters: &[RandomParameter],
    s: S,
) -> Result<S::Ok, S::Error> {
    #[derive(Serialize)]
    struct WithMoments<'a> {
        name: &'a str,
        distribution: &'a crate::uq::Distribution,
        mean: f64,
        std: f64,
    }
    s.collect_seq(parameters.iter().map(|p| WithMoments {
        name: &p.name,
        distribution: &p.distribution,
        mean: p.distribution.mean(),
        std: p.distribution.std(),
    }))
}

/// `summary.json` of a study.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[non_exhaustive]
pub struct Summary {
    /// Study name.
    pub study: String,
    /// Free text.
    pub description: String,
    /// Study file or `builtin:NAME`.
    pub origin: String,
    /// Method settings and diagnostics.
    pub method: MethodSummary,
    /// Seed.
    pub seed: u64,
    /// Time grid.
    pub experiment: Experiment,
    /// Random parameters: each `{"name", "distribution", "mean", "std"}`, the last two those
    /// of the input itself (a truncated normal's own, not its parent normal's; a lognormal's
    /// of X, not of ln X). An infinite truncation bound is `null` (JSON has no infinity).
    #[serde(serialize_with = "parameters_with_moments")]
    pub parameters: Vec<RandomParameter>,
    /// Their correlation: the requested pairs and the normal-space matrix of the Gaussian
    /// copula (absent when the inputs are independent).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub correlation: Option<Correlation>,
    /// Deterministic values.
    pub fixed: BTreeMap<String, FixedValue>,
    /// The FMU (null for intrusive methods).
    pub fmu: Option<FmuInfo>,
    /// Model runs of the study (1 for intrusive methods, which run no model: their one solve).
    pub model_runs: usize,
    /// Runs made by this invocation.
    pub runs_this_invocation: usize,
    /// Runs found finished in the store.
    pub runs_resumed: usize,
    /// Failed runs (allowed for unweighted designs).
    pub failed_runs: usize,
    /// Wall time of this invocation (s).
    pub wall_time_s: f64,
    /// Worker threads.
    pub threads: usize,
    /// Versions.
    pub versions: Versions,
    /// Warnings for the user.
    pub warnings: Vec<String>,
    /// Per output.
    pub outputs: BTreeMap<String, OutputSummary>,
    /// Per scalar quantity.
    pub quantities: BTreeMap<String, ScalarStats>,
    /// Wall time of each stage of this invocation (s).
    pub timing: Timing,
    /// Unit of every variable the study names (parameters, outputs, signals of the
    /// quantities) and of every quantity, from the FMU's modelDescription; `time` is in s.
    /// Undeclared units are left out.
    pub units: BTreeMap<String, String>,
    /// The order of the values in each record of `store/records.bin` (what
    /// `uq-driver export` reads).
    pub record_layout: RecordLayout,
}

/// Wall time of the stages of one invocation (s).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Timing {
    /// The model runs (the same as `wall_time_s`): opening the store, running the points
    /// not yet finished, appending them.
    pub runs_s: f64,
    /// The statistics: estimators, quantiles, densities, surrogate draws.
    pub analysis_s: f64,
    /// Writing the CSV files, plots and `index.html` (everything but `summary.json`
    /// itself, which carries this number).
    pub report_s: f64,
}

/// What a record of the store holds, in order.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct RecordLayout {
    /// The outputs stored as time series (all times of the first, then the second, …).
    pub outputs: Vec<String>,
    /// The scalar quantities, each as (value, outcome code), after the series.
    pub quantities: Vec<String>,
}

/// An output of a suite variant against the reference variant.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct VariantOutput {
    /// Output name.
    pub name: String,
    /// max over time of |mean − mean of the reference|.
    pub max_abs_mean_diff_vs_reference: f64,
    /// max over time of |Std − Std of the reference|.
    pub max_abs_std_diff_vs_reference: f64,
}

/// A variant's entry in a suite's `summary.json`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct VariantSummary {
    /// Variant name.
    pub name: String,
    /// Method label (e.g. `lhs 1000`).
    pub method: String,
    /// Model runs.
    pub model_runs: usize,
    /// Wall time (s).
    pub wall_time_s: f64,
    /// Sub-folder with the variant's own report.
    pub folder: String,
    /// Outputs against the reference.
    pub outputs: Vec<VariantOutput>,
    /// Scalar quantities.
    pub quantities: Vec<ScalarStats>,
}

/// `summary.json` of a suite.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[non_exhaustive]
pub struct SuiteSummary {
    /// Suite name.
    pub suite: String,
    /// Free text.
    pub description: String,
    /// Study file or `builtin:NAME`.
    pub origin: String,
    /// Reference variant.
    pub reference: String,
    /// Per variant.
    pub variants: Vec<VariantSummary>,
    /// Published values.
    pub paper: Vec<PaperValue>,
    /// Total wall time (s).
    pub wall_time_s: f64,
}

/// A summary as pretty JSON with its keys in alphabetical order (as `summary.json` has
/// always been written).
pub fn to_json(summary: &impl Serialize) -> String {
    let value = serde_json::to_value(summary).expect("summaries serialize");
    serde_json::to_string_pretty(&value).expect("JSON values print")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn band_is_mean_plus_minus_k_std() {
        let (lo, hi) = OutputStats::band(&[1.0, 2.0], &[0.5, 0.0], 3.0);
        assert_eq!(lo, vec![-0.5, 2.0]);
        assert_eq!(hi, vec![2.5, 2.0]);
    }
}
