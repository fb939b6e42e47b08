//! A validated study: what the runner, the methods and the report work from.

use std::collections::BTreeMap;
use std::path::PathBuf;

use super::error::StudyError;
use super::file::{Analysis, Experiment, PaperValue};
use crate::fmu::FixedValue;
use crate::qoi::QoiSpec;
use crate::uq::distributions::RandomParameter;
use crate::uq::galerkin::system::SystemSpec;
use crate::uq::method::adaptive::{self, Target};
use crate::uq::method::{Evaluation, InvalidSettings, Method, MethodSpec, Problem};
use crate::uq::random_inputs::{Correlation, RandomInputs};

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
    /// Random parameters whose values may be <= 0 (`allow_negative = true`): no warning when
    /// a positive-mean normal one reaches them.
    pub allow_negative: Vec<String>,
    /// Their correlation (`[[correlation]]`), if any.
    pub correlation: Option<Correlation>,
    /// Deterministic values.
    pub fixed: BTreeMap<String, FixedValue>,
    /// Time-varying inputs: the CSV file, resolved against the study's folder.
    pub inputs: Option<PathBuf>,
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

impl Study {
    /// Whether the study is a set of variants to compare.
    pub fn is_suite(&self) -> bool {
        self.suite.is_some()
    }

    /// The method.
    pub fn method(&self) -> &dyn Method {
        self.method.method()
    }

    /// The random inputs: parameters and correlation, as designs map to them.
    pub fn random_inputs(&self) -> RandomInputs {
        RandomInputs {
            parameters: self.parameters.clone(),
            correlation: self.correlation.clone(),
        }
    }

    /// The communication points (s).
    pub fn times(&self) -> Vec<f64> {
        self.experiment.times()
    }

    /// Checks again what [`Study::parse`] validated and what a change of the public fields
    /// can break: a valid time grid, at least one random parameter (each a valid
    /// distribution, named once, not also fixed), something to analyse (outputs or
    /// quantities), finite fixed values, the quantities' windows, the method's settings
    /// against the study, and an FMU for a method that runs one; each variant of a suite
    /// too. [`crate::study::run_study`] calls it before anything else.
    pub fn check(&self) -> Result<(), StudyError> {
        let invalid = |message: String| StudyError::Invalid {
            origin: self.origin.clone(),
            at: None,
            message,
        };
        let e = &self.experiment;
        e.check()
            .map_err(|err| invalid(format!("[experiment]: {err}")))?;
        if self.parameters.is_empty() {
            return Err(invalid(
                "no random parameters: a study needs at least one (a `nominal` study runs \
                 the FMU at their means); to run the FMU once, use \
                 `study::runner::simulate` (CLI: `uq-driver simulate`)"
                    .into(),
            ));
        }
        for (i, p) in self.parameters.iter().enumerate() {
            if self.parameters[..i].iter().any(|q| q.name == p.name) {
                return Err(invalid(format!("parameter '{}' is listed twice", p.name)));
            }
            if self.fixed.contains_key(&p.name) {
                return Err(invalid(format!(
                    "parameter '{}' is both random and fixed",
                    p.name
                )));
            }
            p.distribution
                .validate()
                .map_err(|err| invalid(format!("parameter '{}': {err}", p.name)))?;
        }
        if let Some((name, _)) = self.fixed.iter().find(|(_, v)| !v.is_finite()) {
            return Err(invalid(format!("fixed value of '{name}' is not finite")));
        }
        if self.outputs.is_empty() && self.qoi.is_empty() {
            return Err(invalid(
                "nothing to analyse: give output variables and/or quantities of interest".into(),
            ));
        }
        for q in &self.qoi {
            q.validate(e.stop - e.start)
                .and_then(|()| q.check_grid(e.start, e.stop, e.step))
                .map_err(|err| invalid(err.to_string()))?;
        }
        if let Some(problem) = crate::qoi::ended::ended_value_problem(&self.qoi, &self.outputs) {
            return Err(invalid(problem));
        }
        let times = self.times();
        self.method()
            .validate(&self.problem(&times))
            .map_err(|err| invalid(format!("method {}: {err}", self.method().kind())))?;
        if self.method.nested().is_some() {
            if let Some(q) = self.qoi.iter().find(|q| !q.limits_below().is_empty()) {
                return Err(invalid(format!(
                    "quantity '{}': `limits_below` is not available in a nested study (its \
                     two-level intervals are of P(q > limit)); give the limit of -q, or run \
                     one level",
                    q.name()
                )));
            }
        }
        if let Evaluation::Adaptive(a) = self.method().evaluation() {
            let targets = self
                .adaptive_targets()
                .map_err(|err| invalid(format!("method {}: {err}", self.method().kind())))?;
            if a.needs_limits() && targets.is_empty() {
                return Err(invalid(format!(
                    "method {} estimates probabilities: give a quantity `limits` (P(q > limit)) \
                     or `limits_below` (P(q < limit))",
                    self.method().kind()
                )));
            }
            if self.qoi.is_empty() {
                return Err(invalid(format!(
                    "method {} works on scalar quantities ([[qoi]]); the study has none",
                    self.method().kind()
                )));
            }
        }
        if !matches!(self.method().evaluation(), Evaluation::Intrusive(_)) {
            match &self.fmu_path {
                None => return Err(invalid("no FMU (`fmu_path` is None) to run".into())),
                Some(p) if p.as_os_str().is_empty() => {
                    return Err(invalid("the FMU path is empty".into()))
                }
                Some(_) => {}
            }
        }
        if let Some(suite) = &self.suite {
            for v in &suite.variants {
                v.check()?;
            }
        }
        Ok(())
    }

    /// The scalar quantities in record order, each named, with the quantity of interest it
    /// comes from.
    pub(crate) fn scalar_quantities(&self) -> impl Iterator<Item = (String, &QoiSpec)> {
        self.qoi
            .iter()
            .flat_map(|q| q.quantity_names().into_iter().map(move |n| (n, q)))
    }

    /// The scalar quantities in record order, each with its limits above and below.
    pub(crate) fn quantity_limits(&self) -> Vec<(String, Vec<f64>, Vec<f64>)> {
        self.scalar_quantities()
            .map(|(n, q)| (n, q.limits().to_vec(), q.limits_below().to_vec()))
            .collect()
    }

    /// The probabilities an adaptive method estimates (one per quantity and limit, within
    /// the method's `quantities`); empty for other methods.
    pub(crate) fn adaptive_targets(&self) -> Result<Vec<Target>, InvalidSettings> {
        match self.method().evaluation() {
            Evaluation::Adaptive(a) if a.needs_limits() => {
                adaptive::targets(&self.quantity_limits(), a.0.only())
            }
            _ => Ok(Vec::new()),
        }
    }

    /// What the method sees of the study; `times` are [`Study::times`].
    pub fn problem<'a>(&'a self, times: &'a [f64]) -> Problem<'a> {
        Problem {
            parameters: &self.parameters,
            correlation: self.correlation.as_ref(),
            outputs: &self.outputs,
            quantities: self.qoi.iter().map(|q| q.quantity_names().len()).sum(),
            times,
            system: self.system.as_ref(),
        }
    }
}
