//! A validated study: what the runner, the methods and the report work from.

use std::collections::BTreeMap;
use std::path::PathBuf;

use super::file::{Analysis, Experiment, PaperValue};
use super::value::FixedValue;
use crate::qoi::QoiSpec;
use crate::uq::distributions::RandomParameter;
use crate::uq::galerkin::system::SystemSpec;
use crate::uq::method::{Method, MethodSpec, Problem};
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
