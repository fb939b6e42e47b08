//! One deterministic run with every random parameter at its mean.

use serde::{Deserialize, Serialize};

use super::design::Design;
use super::error::{InvalidSettings, MethodError};
use super::estimate::Estimate;
use super::traits::{
    DesignSize, Evaluation, KindNotes, Method, MethodSummary, Problem, RunResults, Sampling,
};
use crate::uq::distributions::Germ;
use crate::uq::random_inputs::RandomInputs;

/// `kind = "nominal"` (no settings).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Nominal {}

impl Method for Nominal {
    fn kind(&self) -> &'static str {
        "nominal"
    }

    fn label(&self, _dim: usize) -> String {
        "nominal".into()
    }

    fn validate(&self, _problem: &Problem) -> Result<(), InvalidSettings> {
        Ok(())
    }

    fn summary(&self, _dim: usize) -> MethodSummary {
        let size = DesignSize {
            samples: None,
            nodes_per_dimension: None,
            order: None,
        };
        MethodSummary::new(self.kind(), &size)
    }

    fn evaluation(&self) -> Evaluation<'_> {
        Evaluation::Sampling(self)
    }

    fn notes() -> KindNotes {
        KindNotes {
            deterministic: true,
            ..KindNotes::default()
        }
    }
}

impl Sampling for Nominal {
    /// One point of weight 1 at the parameters' means (a discrete input at the value of
    /// its support nearest to its mean, [`crate::uq::Distribution::nominal`]).
    fn make_design(&self, inputs: &RandomInputs, _seed: u64) -> Result<Design, MethodError> {
        Ok(Design {
            germ: Germ::Normal,
            points: vec![vec![0.0; inputs.len()]],
            values: vec![inputs.iter().map(|p| p.distribution.nominal()).collect()],
            weights: Some(vec![1.0]),
            warnings: Vec::new(),
            inputs: inputs.clone(),
        })
    }

    /// The run's values, Std 0.
    fn make_estimate(&self, results: RunResults) -> Result<Estimate, MethodError> {
        let RunResults { design, rows, data } = results;
        Ok(Estimate::from_quadrature(
            data,
            design.complete_weights(rows)?,
        ))
    }

    fn min_runs(&self) -> usize {
        1
    }

    fn planned_runs(&self, _dim: usize) -> Option<f64> {
        Some(1.0)
    }

    fn draws_from_chaos(&self) -> bool {
        false
    }
}
