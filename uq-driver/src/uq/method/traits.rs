//! What a method is, as the study runner and the report see it: [`Method`] with its
//! evaluation, [`Sampling`] (a design and an estimator) or [`Intrusive`] (its own solve).

use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

use super::adaptive::{AdaptiveResult, BatchModel, Target};
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
fn check_design<M: Method + ?Sized>(method: &M, inputs: &RandomInputs) -> Result<(), MethodError> {
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
fn check_estimate<M: Method + ?Sized>(method: &M, results: RunResults) -> Result<(), MethodError> {
    check_design(method, &results.design.inputs)?;
    results.design.check_results(results.rows, results.data)
}

/// The results of a design's runs, as [`Sampling::make_estimate`] takes them.
#[derive(Clone, Copy, Debug)]
pub struct RunResults<'a> {
    /// The design that was run.
    pub design: &'a Design,
    /// The design indices of the points that gave a value (distinct).
    pub rows: &'a [usize],
    /// The results: one row per entry of `rows`, one column per time step or quantity.
    pub data: &'a DMatrix<f64>,
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
    /// The method chooses its points as it goes, a batch at a time (the reliability methods
    /// `form`, `sorm`, `importance_sampling`, `subset`), or runs one batch of points that
    /// are not samples of the inputs' law (`morris`); the study runs every batch and
    /// stores every run.
    Adaptive(AdaptiveMethod<'a>),
}

/// An adaptive method, as the study runs it (opaque: the study runs it batch by batch
/// through its runner and results store).
#[derive(Clone, Copy)]
pub struct AdaptiveMethod<'a>(pub(crate) &'a dyn Adaptive);

impl AdaptiveMethod<'_> {
    /// Whether the method estimates probabilities, so that the study needs `limits` or
    /// `limits_below` (a screening method does not).
    pub fn needs_limits(&self) -> bool {
        self.0.needs_limits()
    }
}

/// A method of [`Evaluation::Adaptive`]: it asks for batches of points of the independent
/// standard normal space through a [`BatchModel`] and numbers its runs, so that a study
/// can store each and resume by replaying them (see `adaptive`).
pub(crate) trait Adaptive: Method {
    /// At most how many runs the method makes for `dim` inputs and `targets` probabilities
    /// (the capacity of the results store).
    fn max_runs(&self, dim: usize, targets: usize) -> usize;

    /// About how many runs it makes (for the size and time estimate before a study).
    fn expected_runs(&self, dim: usize, targets: usize) -> f64;

    /// Whether it estimates probabilities (and so needs limits).
    fn needs_limits(&self) -> bool {
        true
    }

    /// The quantities it is restricted to (empty: all).
    fn only(&self) -> &[String] {
        &[]
    }

    /// Runs the method on `model` for `targets` (one probability each; the quantities by
    /// name in record order are `names`), deterministic in `seed`.
    fn run(
        &self,
        model: &mut dyn BatchModel,
        inputs: &RandomInputs,
        targets: &[Target],
        names: &[String],
        seed: u64,
    ) -> Result<AdaptiveResult, MethodError>;
}

/// An entry of the study's hash: its key and value.
pub(crate) type HashEntry = (&'static str, serde_json::Value);

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

    /// What besides its settings makes the results of this method on `parameters` differ,
    /// as an entry of the study's hash (so that a store of another design is not resumed).
    fn hash_entry(&self, _parameters: &[RandomParameter]) -> Option<HashEntry> {
        None
    }

    /// Resolves the files the settings name (e.g. a points file) against `base`, the study
    /// file's folder.
    fn resolve_files(&mut self, _base: Option<&std::path::Path>) -> Result<(), InvalidSettings> {
        Ok(())
    }

    /// Takes the parameters marked `level = "outer"` (names, study order): only a nested
    /// study has two levels; any other method refuses them.
    fn set_outer_parameters(&mut self, outer: &[String]) -> Result<(), InvalidSettings> {
        match outer.first() {
            None => Ok(()),
            Some(name) => Err(InvalidSettings(format!(
                "parameter '{name}' has level = \"outer\", which only a nested study \
                 ([method] kind = \"nested\") has; {} draws every parameter in one design",
                self.kind()
            ))),
        }
    }

    /// What the report and the terminal say of this method's results (by `kind`, for a
    /// `summary.json` read back: see [`notes_of_kind`](crate::uq::method::notes_of_kind)).
    fn notes() -> KindNotes
    where
        Self: Sized,
    {
        KindNotes::default()
    }
}

/// The [`Method::summary`], [`Method::evaluation`] and [`Method::notes`] that every method of
/// the adaptive path shares (a method that also implements [`Adaptive`]): its settings as
/// written under `method`, evaluation by the adaptive session, and `$study`, the method's
/// name in a sentence ("a FORM study"). Used inside `impl Method for …`.
macro_rules! adaptive_method_items {
    ($study:literal) => {
        fn summary(&self, _dim: usize) -> $crate::uq::method::traits::MethodSummary {
            $crate::uq::method::traits::MethodSummary::new(self.kind(), self)
        }

        fn evaluation(&self) -> $crate::uq::method::traits::Evaluation<'_> {
            $crate::uq::method::traits::Evaluation::Adaptive(
                $crate::uq::method::traits::AdaptiveMethod(self),
            )
        }

        fn notes() -> $crate::uq::method::traits::KindNotes {
            $crate::uq::method::traits::KindNotes {
                name: Some($study),
                adaptive: true,
                ..$crate::uq::method::traits::KindNotes::default()
            }
        }
    };
}
pub(crate) use adaptive_method_items;

/// What the report and the terminal say of a method's results.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct KindNotes {
    /// One deterministic run (no spread, no statistics).
    pub deterministic: bool,
    /// Said of a convergence plot over the number of runs (e.g. that the first n points of
    /// a Latin hypercube are not a Latin hypercube).
    pub runs_axis: Option<&'static str>,
    /// Said of a convergence plot over the chaos order: how the truncated chaos is obtained.
    pub truncation: Option<&'static str>,
    /// The method's name in a sentence ("an SGM study").
    pub name: Option<&'static str>,
    /// The method chooses its runs, which are not samples of the inputs' law (the
    /// reliability methods, Morris screening): no moments, densities or quantiles.
    pub adaptive: bool,
}

/// A method that runs the model at the points of a design.
///
/// A method implements [`Sampling::make_design`] and [`Sampling::make_estimate`]; callers
/// call [`Sampling::design`] and [`Sampling::estimate`], which run the checks every method
/// shares first (valid inputs, settings that fit them, results that fit the design), so
/// that no method can skip them.
pub trait Sampling: Method {
    /// The design for `inputs` (deterministic in `seed`): points in an independent standard
    /// space mapped to physical values by [`Design::mapped`], which honours the inputs'
    /// correlation.
    ///
    /// Checks first that every input is a valid distribution
    /// ([`MethodError::InvalidInput`]) and that the settings fit the inputs
    /// ([`Method::validate`] on [`Problem::of_inputs`], [`MethodError::Invalid`]); no need to
    /// call `validate` first.
    fn design(&self, inputs: &RandomInputs, seed: u64) -> Result<Design, MethodError> {
        check_design(self, inputs)?;
        self.make_design(inputs, seed)
    }

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
    ) -> Result<Estimate, MethodError> {
        let results = RunResults { design, rows, data };
        check_estimate(self, results)?;
        self.make_estimate(results)
    }

    /// The method's own design, called by [`Sampling::design`] once the inputs and the
    /// settings have passed the shared checks.
    fn make_design(&self, inputs: &RandomInputs, seed: u64) -> Result<Design, MethodError>;

    /// The method's own estimator, called by [`Sampling::estimate`] once the inputs, the
    /// settings and the shape of the results have passed the shared checks.
    fn make_estimate(&self, results: RunResults) -> Result<Estimate, MethodError>;

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

    /// Whether the estimates carry Sobol' indices over time (counted in the memory estimate).
    fn estimates_sobol(&self) -> bool {
        self.draws_from_chaos() || self.samples_the_law()
    }

    /// Whether the runs are an equally weighted sample of the inputs' law (Monte Carlo, Latin
    /// hypercube, quasi-Monte Carlo), from which first-order Sobol' indices and rank
    /// correlations are estimated as given data.
    fn samples_the_law(&self) -> bool {
        false
    }

    /// Points per independent replicate where the design is made of replicates (design
    /// point `i` in replicate `i / size`): the sensitivity from the runs measures the noise
    /// of its bin means from their spread. `None` for the others.
    fn replicate_size(&self) -> Option<usize> {
        None
    }

    /// The size of the chaos the estimator fits, for a method whose arrays grow with the
    /// chaos's terms (counted in the memory estimate before anything is built); `None` for the
    /// others, and when the sizes cannot be known (the method's own checks then refuse).
    fn chaos_fit(&self, _parameters: &[RandomParameter]) -> Option<ChaosFit> {
        None
    }

    /// Whether the estimator needs the whole series of an output at once, not a block of
    /// columns at a time (a nested study: its outer samples' inner estimates).
    fn whole_series(&self) -> bool {
        false
    }

    /// Why the chaos has no truncation-error estimate, where the method can have none.
    fn no_error_estimate(&self) -> Option<&'static str> {
        None
    }

    /// Whether the estimator fits a chaos to each column on its own, so that identical columns
    /// may be fitted once and a series on its principal components instead (`[analysis]
    /// functional = "pca"`, for a design without quadrature weights): regression and
    /// sparse-grid chaoses; not a quadrature whose moments come from the runs themselves.
    fn chaos_per_column(&self) -> bool {
        false
    }
}

/// The size of the chaos a method's estimator fits (see [`Sampling::chaos_fit`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ChaosFit {
    /// Regression with least-angle regression (`pce_regression`, `sparse = true`): the
    /// candidates of all the degrees tried (`sum_p m_p`) and of the highest (`m_order`).
    Lars {
        /// `sum_p m_p`, `p = 1..=order`.
        candidates: f64,
        /// `m_order`.
        largest: f64,
    },
    /// Least squares on a fixed basis (`pce_regression`, `sparse = false`): its terms.
    LeastSquares {
        /// Terms.
        terms: f64,
    },
    /// Sparse pseudo-spectral projection (`sparse_grid`): the grid's counted sizes.
    Projection(crate::uq::hd::smolyak::GridSize),
}

/// Terms of the hyperbolic (q-norm) truncation `{k : sum_i k_i^q <= order^q}` in `dim`
/// dimensions (the set of `MultiIndexSet::hyperbolic`), counted without building it: over
/// the non-increasing lists of non-zero degrees within the bound, the ways of placing them
/// among the dimensions. `q = 1` gives `C(dim + order, order)`.
pub fn hyperbolic_terms(dim: usize, order: usize, q: f64) -> f64 {
    // Beyond 1e10 terms any estimate is refused: counting further would only take time.
    crate::uq::pce::MultiIndexSet::hyperbolic_count_upto(dim, order, q, 1e10)
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
