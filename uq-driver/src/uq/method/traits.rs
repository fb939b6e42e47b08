//! What a method is, as the study runner and the report see it: [`Method`] with its
//! evaluation, [`Sampling`] (a design and an estimator) or [`Intrusive`] (its own solve).

use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

use super::design::Design;
use super::error::{InvalidSettings, MethodError};
use super::estimate::Estimate;
use crate::uq::distributions::RandomParameter;
use crate::uq::galerkin::system::SystemSpec;
use crate::uq::random_inputs::{Correlation, RandomInputs};

/// What a method knows of the study it belongs to.
#[derive(Clone, Copy, Debug)]
pub struct Problem<'a> {
    /// The random parameters, in study order.
    pub parameters: &'a [RandomParameter],
    /// Their correlation, if the study correlates some.
    pub correlation: Option<&'a Correlation>,
    /// The output variables analysed over time.
    pub outputs: &'a [String],
    /// Number of scalar quantities of interest.
    pub quantities: usize,
    /// Communication points (s).
    pub times: &'a [f64],
    /// The study's `[system]` (the equations of an intrusive method), if any.
    pub system: Option<&'a SystemSpec>,
}

impl<'a> Problem<'a> {
    /// The part of a study a design depends on: these random inputs (and their
    /// correlation), no outputs, no quantities, no times, no `[system]`. The settings checks
    /// of [`Sampling::design`] and [`Sampling::estimate`] use it.
    pub fn of_inputs(inputs: &'a RandomInputs) -> Problem<'a> {
        Problem {
            parameters: &inputs.parameters,
            correlation: inputs.correlation.as_ref(),
            outputs: &[],
            quantities: 0,
            times: &[],
            system: None,
        }
    }
}

/// What every [`Sampling::design`] checks before it builds anything: each input is a valid
/// distribution (struct literals and deserialized values are not validated on their own),
/// and the method's settings fit these inputs ([`Method::validate`] on
/// [`Problem::of_inputs`]: e.g. a chaos refuses a discrete input, `confidence` must be in
/// (0, 1)).
pub(crate) fn check_design(method: &dyn Method, inputs: &RandomInputs) -> Result<(), MethodError> {
    for p in &inputs.parameters {
        p.distribution
            .validate()
            .map_err(|source| MethodError::InvalidInput {
                name: p.name.clone(),
                source,
            })?;
    }
    method.validate(&Problem::of_inputs(inputs))?;
    Ok(())
}

/// What every [`Sampling::estimate`] checks before it estimates: the design's inputs and
/// the settings as [`check_design`] does (the settings may have changed since the design
/// was built), and that the results fit the design ([`Design::check_results`]).
pub(crate) fn check_estimate(
    method: &dyn Method,
    design: &Design,
    rows: &[usize],
    data: &DMatrix<f64>,
) -> Result<(), MethodError> {
    check_design(method, &design.inputs)?;
    design.check_results(rows, data)
}

/// The `method` entry of `summary.json`: the kind and the method's settings and diagnostics.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MethodSummary {
    /// `kind` of the study file.
    pub kind: String,
    /// Per method (e.g. `samples`, `nodes_per_dimension`, `order`, `terms`, `definiteness`).
    #[serde(flatten)]
    pub details: serde_json::Map<String, serde_json::Value>,
}

impl MethodSummary {
    /// A summary of `kind` with the fields of `settings` (a struct or map).
    pub fn new(kind: &str, settings: &impl Serialize) -> MethodSummary {
        MethodSummary {
            kind: kind.to_owned(),
            details: details(settings),
        }
    }
}

/// The fields of a struct (or map) as the entries of a JSON object; empty for anything else.
pub fn details(value: &impl Serialize) -> serde_json::Map<String, serde_json::Value> {
    match serde_json::to_value(value) {
        Ok(serde_json::Value::Object(map)) => map,
        _ => serde_json::Map::new(),
    }
}

/// The size of a design as summary.json has always reported it (`null` where it does not apply).
#[derive(Clone, Copy, Debug, Serialize)]
pub(crate) struct DesignSize {
    /// Samples (MC, LHS).
    pub samples: Option<usize>,
    /// Nodes per dimension (tensor grids).
    pub nodes_per_dimension: Option<usize>,
    /// Chaos order.
    pub order: Option<usize>,
}

/// How a method obtains its results.
pub enum Evaluation<'a> {
    /// The model is run at the points of a design.
    Sampling(&'a dyn Sampling),
    /// The method solves its own projected system; the model is not run.
    Intrusive(&'a dyn Intrusive),
}

/// A UQ method as the study runner and the report see it.
pub trait Method: std::fmt::Debug + Send + Sync {
    /// The `kind` in study files and summaries.
    fn kind(&self) -> &'static str;

    /// A short label for tables and logs, e.g. `lhs 1000`, `scm 6^2`, `sgm order 6`
    /// (`dim`: number of random parameters).
    fn label(&self, dim: usize) -> String;

    /// Checks the settings against the study; called once, when the study is loaded.
    fn validate(&self, problem: &Problem) -> Result<(), InvalidSettings>;

    /// The settings written under `method` in `summary.json`.
    fn summary(&self, dim: usize) -> MethodSummary;

    /// Whether the method runs the model at a design or solves its own system.
    fn evaluation(&self) -> Evaluation<'_>;
}

/// A method that runs the model at the points of a design.
pub trait Sampling {
    /// The design for `inputs` (deterministic in `seed`): points in an independent standard
    /// space mapped to physical values by [`Design::mapped`], which honours the inputs'
    /// correlation.
    ///
    /// Checks first that every input is a valid distribution
    /// ([`MethodError::InvalidInput`]) and that the settings fit the inputs
    /// ([`Method::validate`] on [`Problem::of_inputs`], [`MethodError::Invalid`]); no need to
    /// call `validate` first.
    fn design(&self, inputs: &RandomInputs, seed: u64) -> Result<Design, MethodError>;

    /// Estimates from the results `data` (one row per entry of `rows`, the design indices of
    /// the points that gave a value; one column per time step or quantity).
    ///
    /// `rows` must be distinct indices of `design` with `data.nrows() == rows.len()`
    /// ([`MethodError::ResultsMismatch`] otherwise); the settings are checked as in
    /// [`Sampling::design`].
    fn estimate(
        &self,
        design: &Design,
        rows: &[usize],
        data: &DMatrix<f64>,
    ) -> Result<Estimate, MethodError>;

    /// The rows of `data` (indices into `rows`) that the estimate's mean and Std are taken
    /// from, in the order a running estimate should take them, where they are not all the
    /// rows in order (`None`): e.g. only the runs of `A` and `B` of a pick-freeze design.
    fn moment_rows(&self, _design: &Design, _rows: &[usize]) -> Option<Vec<usize>> {
        None
    }

    /// The fewest successful runs the estimator can work with.
    fn min_runs(&self) -> usize {
        2
    }

    /// The number of model runs of the design for `dim` random parameters, computed without
    /// building it (as a float: it may be far beyond any integer type), or `None` when only
    /// the design knows. The study checks it before anything is allocated (`study::size`):
    /// every method should give it.
    fn planned_runs(&self, _dim: usize) -> Option<f64> {
        None
    }

    /// [`Sampling::planned_runs`] for these `parameters`, for a method whose design size
    /// depends on their distributions too (a sparse grid: the rule of each input's germ).
    fn planned_runs_for(&self, parameters: &[RandomParameter]) -> Option<f64> {
        self.planned_runs(parameters.len())
    }

    /// Whether the estimates may draw their quantiles and densities from a chaos surrogate
    /// (`[analysis] surrogate_samples` draws of every output time): counted in the memory
    /// estimate of `study::size`. `true` unless the method never builds a chaos.
    fn draws_from_chaos(&self) -> bool {
        true
    }
}

/// A method that solves a projected (intrusive) system instead of running the model.
pub trait Intrusive {
    /// One estimate per output of `problem`, over its times.
    fn solve(&self, problem: &Problem) -> Result<Solution, MethodError>;
}

/// What an intrusive method returns.
#[derive(Clone, Debug)]
pub struct Solution {
    /// One estimate per output.
    pub outputs: Vec<Estimate>,
    /// Diagnostics for the method's entry in `summary.json`.
    pub details: serde_json::Map<String, serde_json::Value>,
    /// Warnings for the user.
    pub warnings: Vec<String>,
}
