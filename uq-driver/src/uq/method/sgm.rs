//! The stochastic Galerkin method on a linear second-order system given in the study file
//! (`[system]`): `M q'' + C q' + K q = f`, each matrix (and q0, v0) affine in the Gaussian
//! parameters, `A = A_given + Σ_j p_j · D_j`. The Galerkin system itself is in
//! `uq::galerkin`; this module reads the `[system]` table, checks it against the
//! study, solves, and returns the chaos of every output over time.

use serde::{Deserialize, Serialize};

use super::error::{InvalidSettings, MethodError};
use super::estimate::Estimate;
use super::traits::{
    details, Evaluation, Intrusive, KindNotes, Method, MethodSummary, Problem, Solution,
};
use crate::uq::galerkin::system::{linear_system, output_dof, SystemSpec};
use crate::uq::galerkin::{Definiteness, GalerkinSystem};

/// Highest chaos order accepted.
const MAX_ORDER: usize = 12;

/// `kind = "sgm"`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sgm {
    /// Total order of the Hermite chaos: C(order + d, d) terms (at most 12).
    pub order: usize,
}

fn system<'a>(problem: &Problem<'a>) -> Result<&'a SystemSpec, InvalidSettings> {
    problem
        .system
        .ok_or_else(|| InvalidSettings("method sgm needs a [system] (matrices M, C, K, q0)".into()))
}

fn output_dofs(
    sys: &SystemSpec,
    outputs: &[String],
) -> Result<Vec<(usize, bool)>, InvalidSettings> {
    outputs
        .iter()
        .map(|o| {
            output_dof(sys, o).ok_or_else(|| {
                InvalidSettings(format!(
                    "output '{o}' is not a DOF of the system (DOFs: {}; velocities: <dof>_dot)",
                    sys.dofs.join(", ")
                ))
            })
        })
        .collect()
}

impl Method for Sgm {
    fn kind(&self) -> &'static str {
        "sgm"
    }

    fn label(&self, _dim: usize) -> String {
        format!("sgm order {}", self.order)
    }

    fn validate(&self, problem: &Problem) -> Result<(), InvalidSettings> {
        if self.order > MAX_ORDER {
            return Err(InvalidSettings(format!(
                "SGM order {} is above {MAX_ORDER}",
                self.order
            )));
        }
        if let Some(p) = problem
            .parameters
            .iter()
            .find(|p| !p.distribution.is_gaussian())
        {
            return Err(InvalidSettings(format!(
                "SGM needs Gaussian parameters (Hermite chaos); '{}' is not",
                p.name
            )));
        }
        if problem.correlation.is_some() {
            return Err(InvalidSettings(
                "SGM needs independent Gaussian parameters; this study correlates some \
                 ([[correlation]]): use scm, sparse_grid or pce_regression"
                    .into(),
            ));
        }
        let sys = system(problem)?;
        linear_system(sys, problem.parameters)?;
        output_dofs(sys, problem.outputs)?;
        if problem.quantities > 0 {
            return Err(InvalidSettings(
                "[[qoi]] is not available with SGM (no time series of a model is run)".into(),
            ));
        }
        Ok(())
    }

    fn summary(&self, _dim: usize) -> MethodSummary {
        #[derive(Serialize)]
        struct Settings {
            order: usize,
        }
        MethodSummary::new(self.kind(), &Settings { order: self.order })
    }

    fn evaluation(&self) -> Evaluation<'_> {
        Evaluation::Intrusive(self)
    }

    fn notes() -> KindNotes {
        KindNotes {
            name: Some("an SGM study"),
            ..KindNotes::default()
        }
    }
}

/// Size and definiteness of the assembled system, for `summary.json`.
#[derive(Serialize)]
struct Diagnostics<'a> {
    terms: usize,
    galerkin_size: usize,
    definiteness: &'a Definiteness,
}

impl Intrusive for Sgm {
    /// Assembles and integrates the Galerkin system; the chaos of every output over time.
    fn solve(&self, problem: &Problem) -> Result<Solution, MethodError> {
        let sys = system(problem)?;
        let gs = GalerkinSystem::assemble(&linear_system(sys, problem.parameters)?, self.order)?;
        let dofs = output_dofs(sys, problem.outputs)?;
        let idx: Vec<usize> = dofs.iter().map(|d| d.0).collect();
        let trajectories = gs.solve(problem.times, sys.step, &idx)?;
        let outputs = dofs
            .iter()
            .zip(trajectories)
            .map(|(&(_, velocity), (q, v))| {
                Estimate::from_chaos(gs.pce(if velocity { v } else { q }))
            })
            .collect();
        let definiteness = gs.check_definiteness();
        let details = details(&Diagnostics {
            terms: gs.basis.len(),
            galerkin_size: gs.mm.nrows(),
            definiteness: &definiteness,
        });
        Ok(Solution {
            outputs,
            details,
            warnings: definiteness.warnings,
        })
    }
}
