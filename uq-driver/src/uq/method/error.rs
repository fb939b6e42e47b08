//! Errors of the methods: settings that do not fit the study, and failures of designs and
//! estimators.

use crate::uq::galerkin::system::InvalidSystem;
use crate::uq::galerkin::GalerkinError;
use crate::uq::hd::sensitivity::SensitivityError;
use crate::uq::pce::PceError;
use crate::uq::quadrature::QuadratureError;

/// Settings that make no sense for the study they are in (reported as a study-file error).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct InvalidSettings(pub String);

/// Failures of designs and estimators.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum MethodError {
    /// A quadrature rule could not be built.
    #[error(transparent)]
    Quadrature(#[from] QuadratureError),
    /// A chaos could not be projected.
    #[error(transparent)]
    Chaos(#[from] PceError),
    /// The Galerkin system could not be assembled or solved.
    #[error(transparent)]
    Galerkin(#[from] GalerkinError),
    /// The settings do not fit the study.
    #[error(transparent)]
    Invalid(#[from] InvalidSettings),
    /// The `[system]` does not describe a valid system.
    #[error(transparent)]
    System(#[from] InvalidSystem),
    /// Sobol' indices could not be estimated from a pick-freeze design.
    #[error(transparent)]
    Sensitivity(#[from] SensitivityError),
    /// The results passed to an estimator do not match the design (`rows` and `data` of
    /// different lengths, a row that is not a point of the design, a row given twice).
    #[error("the results do not match the design: {0}")]
    ResultsMismatch(String),
    /// A random input is not a valid distribution (e.g. a `Distribution` struct literal
    /// with `low > high`).
    #[error("random input '{name}': {source}")]
    InvalidInput {
        /// The input's name.
        name: String,
        /// What is wrong with its distribution.
        source: crate::uq::distributions::DistributionError,
    },
    /// A weighted design lacks results at some of its points.
    #[error(
        "{missing} of {total} weighted points have no value; a weighted design cannot drop a point"
    )]
    MissingPoints {
        /// Points without a value.
        missing: usize,
        /// Points of the design.
        total: usize,
    },
    /// A run an adaptive method needs failed (every run of FORM and SORM; those of
    /// importance sampling and subset simulation unless failed runs count as failures).
    #[error(
        "{target}: run {run} failed at {}: {message}. The runs before it are kept in the \
         results store; run again with --retry-failed (RunOptions::retry_failed) to run it \
         again once the cause is fixed",
        named_values(.values)
    )]
    RunFailed {
        /// The probability being estimated, e.g. `P(v_hunt < 60)`.
        target: String,
        /// The run index.
        run: u64,
        /// The physical inputs of the run, by name.
        values: Vec<(String, f64)>,
        /// What the model reported.
        message: String,
    },
    /// FORM found no search direction: the gradient of the limit state is zero or not
    /// finite at a point.
    #[error(
        "{target}: the gradient of the limit state is zero or not finite at {} (|grad g| = \
         {norm} in standard normal space): FORM has no search direction there (a quantity \
         that does not change with the inputs, or finite-difference steps below the model's \
         resolution: raise `step`)",
        named_values(.values)
    )]
    NoSearchDirection {
        /// The probability being estimated.
        target: String,
        /// The physical inputs of the point, by name.
        values: Vec<(String, f64)>,
        /// The norm of the finite-difference gradient.
        norm: f64,
    },
    /// An adaptive method was stopped from outside (a budget of runs, a fatal error of the
    /// model) or the runs stored by an earlier invocation do not match those requested now.
    #[error("{target}: {why}")]
    Stopped {
        /// The probability being estimated (or the method).
        target: String,
        /// Why.
        why: String,
    },
}

/// `K = 1.5, C = 20`.
fn named_values(values: &[(String, f64)]) -> String {
    values
        .iter()
        .map(|(n, v)| format!("{n} = {v}"))
        .collect::<Vec<_>>()
        .join(", ")
}

impl From<InvalidSystem> for InvalidSettings {
    fn from(e: InvalidSystem) -> Self {
        InvalidSettings(e.0)
    }
}
