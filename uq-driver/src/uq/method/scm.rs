//! Stochastic collocation: a tensor Gauss–Hermite grid in standard-normal space, quadrature
//! moments, and a Hermite chaos of total order below the nodes projected from the same runs
//! (with the exact norms), which gives `std_chaos`, the Sobol' indices and, sampled, the
//! quantiles and densities.

use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

use super::chaos::{continuous_inputs, order_difference};
use super::design::Design;
use super::error::{InvalidSettings, MethodError};
use super::estimate::{Draws, Estimate, Sobol};
use super::traits::{DesignSize, Evaluation, Method, MethodSummary, Problem, Sampling};
use crate::uq::distributions::Germ;
use crate::uq::random_inputs::RandomInputs;
use crate::uq::pce::{Basis, Family, MultiIndexSet, Pce, PceError};
use crate::uq::quadrature;

/// Most nodes per dimension.
const MAX_NODES: usize = 64;
/// Most points of the tensor grid.
const MAX_POINTS: f64 = 5e6;

/// `kind = "scm"`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scm {
    /// Gauss–Hermite nodes per dimension (1 to 64).
    pub nodes: usize,
    /// Total order of the chaos, below `nodes` (default `nodes − 1`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub order: Option<usize>,
}

impl Scm {
    /// The chaos order.
    pub fn order(&self) -> usize {
        self.order.unwrap_or(self.nodes.saturating_sub(1))
    }
}

impl Method for Scm {
    fn kind(&self) -> &'static str {
        "scm"
    }

    fn label(&self, dim: usize) -> String {
        format!("scm {}^{dim}", self.nodes)
    }

    fn validate(&self, problem: &Problem) -> Result<(), InvalidSettings> {
        let nodes = self.nodes;
        if nodes == 0 || nodes > MAX_NODES {
            return Err(InvalidSettings(format!(
                "`nodes` = {nodes} must be in 1..={MAX_NODES}"
            )));
        }
        let order = self.order();
        if order >= nodes {
            return Err(InvalidSettings(format!(
                "chaos order {order} must be below the nodes per dimension ({nodes}): \
                 the quadrature cannot integrate the basis norms exactly otherwise"
            )));
        }
        continuous_inputs(problem, "scm")?;
        let dim = problem.parameters.len();
        if (nodes as f64).powi(dim as i32) > MAX_POINTS {
            return Err(InvalidSettings(format!(
                "tensor grid of {nodes}^{dim} = {:.3e} points is too large (at most {MAX_POINTS:.0e}); \
                 in {dim} dimensions use `kind = \"sparse_grid\"` or `kind = \"pce_regression\"`, \
                 which need far fewer runs",
                (nodes as f64).powi(dim as i32)
            )));
        }
        Ok(())
    }

    fn summary(&self, _dim: usize) -> MethodSummary {
        let size = DesignSize {
            samples: None,
            nodes_per_dimension: Some(self.nodes),
            order: Some(self.order()),
        };
        MethodSummary::new(self.kind(), &size)
    }

    fn evaluation(&self) -> Evaluation<'_> {
        Evaluation::Sampling(self)
    }
}

impl Sampling for Scm {
    /// The tensor grid, last parameter varying fastest; weights sum to one.
    fn design(&self, inputs: &RandomInputs, _seed: u64) -> Result<Design, MethodError> {
        let grid = quadrature::tensor_grid(&vec![self.nodes; inputs.len()])?;
        Ok(Design::mapped(
            Germ::Normal,
            grid.points,
            Some(grid.weights),
            inputs,
        ))
    }

    fn planned_runs(&self, dim: usize) -> Option<f64> {
        Some((self.nodes as f64).powi(dim as i32))
    }

    /// Needs every node: a missing weighted node would bias every moment.
    fn estimate(
        &self,
        design: &Design,
        rows: &[usize],
        data: &DMatrix<f64>,
    ) -> Result<Estimate, MethodError> {
        let weights = design.complete_weights(rows)?;
        let dim = design.points.first().map_or(0, Vec::len);
        let set = MultiIndexSet::total_degree(dim, self.order()).map_err(PceError::from)?;
        let basis = Basis::new(vec![Family::Hermite; dim], set).map_err(PceError::from)?;
        let pce = Pce::project(
            basis,
            &design.points,
            weights,
            data,
            &vec![self.nodes; dim],
        )?;
        let mut estimate = Estimate::from_quadrature(data, weights);
        estimate.std_chaos = Some(pce.std());
        estimate.chaos_error = order_difference(&pce);
        estimate.sobol = Some(Sobol::from_chaos(&pce));
        estimate.chaos = Some(pce);
        estimate.draws = Draws::Chaos;
        Ok(estimate)
    }
}
