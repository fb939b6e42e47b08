//! The experimental design of a study: the parameter points, their germ coordinates and,
//! for collocation, their quadrature weights.

use serde::Serialize;

use super::spec::{MethodKind, Study};
use crate::uq::{quadrature, sampling};

/// Points at which the model is run.
#[derive(Clone, Debug, Serialize)]
pub struct Design {
    /// Method that produced the points.
    pub method: MethodKind,
    /// Germ coordinates per point: standard-normal (SCM) or uniform in (0, 1) (MC, LHS).
    pub germ: Vec<Vec<f64>>,
    /// Physical parameter values per point, in the order of the study's parameters.
    pub values: Vec<Vec<f64>>,
    /// Quadrature weights (SCM), summing to one.
    pub weights: Option<Vec<f64>>,
    /// SCM: nodes per dimension.
    pub nodes_per_dim: Vec<usize>,
    /// SCM: total order of the chaos.
    pub order: usize,
    /// Notes for the user (e.g. nodes where a Gaussian stiffness is negative).
    pub warnings: Vec<String>,
}

/// Design failures.
#[derive(Debug, thiserror::Error)]
pub enum DesignError {
    /// Quadrature could not be built.
    #[error("quadrature: {0}")]
    Quadrature(String),
    /// The method has no design (SGM).
    #[error("method {0} has no sampling design")]
    NoDesign(&'static str),
}

impl Design {
    /// Number of points.
    pub fn len(&self) -> usize {
        self.values.len()
    }

    /// Whether there are no points.
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }

    /// Builds the design of a study (deterministic in the study's seed).
    pub fn build(study: &Study) -> Result<Design, DesignError> {
        let d = study.parameters.len();
        let m = &study.file.method;
        let seed = study.file.seed;
        let (germ, weights, nodes_per_dim, order) = match m.kind {
            MethodKind::Mc => (
                sampling::monte_carlo(m.samples.unwrap_or(0), d, seed),
                None,
                vec![],
                0,
            ),
            MethodKind::Lhs => (
                sampling::latin_hypercube(m.samples.unwrap_or(0), d, seed),
                None,
                vec![],
                0,
            ),
            MethodKind::Scm => {
                let nodes = m.nodes.unwrap_or(1);
                let npd = vec![nodes; d];
                let grid = quadrature::tensor_grid(&npd)
                    .map_err(|e| DesignError::Quadrature(e.to_string()))?;
                (
                    grid.points,
                    Some(grid.weights),
                    npd,
                    m.order.unwrap_or(nodes - 1),
                )
            }
            MethodKind::Sgm => return Err(DesignError::NoDesign("sgm")),
            MethodKind::Nominal => (vec![vec![0.0; d]], Some(vec![1.0]), vec![], 0),
        };
        let values: Vec<Vec<f64>> = germ
            .iter()
            .map(|g| {
                g.iter()
                    .zip(&study.parameters)
                    .map(|(&x, p)| match m.kind {
                        MethodKind::Scm => p.distribution.from_standard_normal(x),
                        MethodKind::Nominal => p.distribution.mean(),
                        _ => p.distribution.inverse_cdf(x),
                    })
                    .collect()
            })
            .collect();
        let mut warnings = Vec::new();
        for (j, p) in study.parameters.iter().enumerate() {
            if p.distribution.mean() > 0.0 {
                let neg: Vec<usize> = (0..values.len()).filter(|&i| values[i][j] <= 0.0).collect();
                if !neg.is_empty() {
                    let total_w: f64 = weights
                        .as_ref()
                        .map(|w| neg.iter().map(|&i| w[i]).sum())
                        .unwrap_or(neg.len() as f64 / values.len() as f64);
                    warnings.push(format!(
                        "{} of {} points have {} <= 0 (a positive-mean Gaussian reaches negative values in its tail; \
                         probability weight {:.3e}); they are run, not dropped — consider a lognormal or truncated_normal input",
                        neg.len(),
                        values.len(),
                        p.name,
                        total_w
                    ));
                }
            }
        }
        Ok(Design {
            method: m.kind,
            germ,
            values,
            weights,
            nodes_per_dim,
            order,
            warnings,
        })
    }
}
