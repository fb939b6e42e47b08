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
}

impl From<InvalidSystem> for InvalidSettings {
    fn from(e: InvalidSystem) -> Self {
        InvalidSettings(e.0)
    }
}
