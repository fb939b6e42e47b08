//! Stochastic collocation: a tensor grid of Gauss rules, quadrature moments, and a chaos of
//! total order below the nodes projected from the same runs (with the exact norms), which
//! gives `std_chaos`, the Sobol' indices and, sampled, the quantiles and densities.
//!
//! The rule and chaos of each input follow `chaos` ([`ChaosBasis`]): by default (`askey`) the
//! input's own family, Gauss–Hermite and Hermite for a normal input (and for log-normal,
//! truncated normal and Weibull inputs, through the normal map), Gauss–Legendre and Legendre
//! for a uniform one, Gauss–Jacobi for a Beta input, Gauss–Laguerre for a Gamma input; with
//! `hermite` every input goes through the normal map to Gauss–Hermite nodes (the paper's SCM,
//! which converges slowly for bounded inputs: F⁻¹(Φ(z)) flattens in the tails). A study whose
//! inputs all have a Hermite germ gets the same design either way.

use serde::{Deserialize, Serialize};

use super::chaos::{continuous_inputs, order_difference, ChaosBasis};
use super::design::Design;
use super::error::{InvalidSettings, MethodError};
use super::estimate::{Draws, Estimate, Sobol};
use super::traits::{
    DesignSize, Evaluation, HashEntry, KindNotes, Method, MethodSummary, Problem, RunResults,
    Sampling,
};
use crate::uq::distributions::{Germ, RandomParameter};
use crate::uq::pce::{Basis, Family, MultiIndexSet, Pce, PceError};
use crate::uq::quadrature;
use crate::uq::random_inputs::RandomInputs;

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
    /// The rule and chaos of each input (`askey`, default, or `hermite`). Left out of the
    /// serialised settings when `askey`, so that studies written before the key keep their
    /// hash (the study hash adds it where it changes the design).
    #[serde(default, skip_serializing_if = "ChaosBasis::is_askey")]
    pub chaos: ChaosBasis,
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

    /// SCM follows each input's Askey family since `chaos` became one of its keys: where that
    /// changes the design (an input with a non-Hermite germ) the hash says so, so that a store
    /// of the old Gauss–Hermite design is not resumed; other SCM studies keep their hash.
    fn hash_entry(&self, parameters: &[RandomParameter]) -> Option<HashEntry> {
        (self.chaos == ChaosBasis::Askey && ChaosBasis::some_own_family(parameters))
            .then(|| ("scm_germ", serde_json::json!("askey")))
    }

    fn notes() -> KindNotes {
        KindNotes {
            truncation: Some(
                "each term is projected on its own, so the truncation is the lower-order chaos \
                 of the same runs",
            ),
            ..KindNotes::default()
        }
    }
}

impl Scm {
    /// The tensor grid of the inputs' Gauss rules (Gauss–Hermite when every input goes
    /// through the normal map).
    fn grid(&self, inputs: &RandomInputs) -> Result<Design, MethodError> {
        let families = self.chaos.families(inputs);
        if families.iter().all(|f| *f == Family::Hermite) {
            // Every input through the normal map: the Gauss–Hermite grid.
            let grid = quadrature::tensor_grid(&vec![self.nodes; inputs.len()])?;
            return Ok(Design::mapped(
                Germ::Normal,
                grid.points,
                Some(grid.weights),
                inputs,
            ));
        }
        let rules: Vec<(Vec<f64>, Vec<f64>)> = families
            .iter()
            .map(|f| match f {
                Family::Hermite => quadrature::gauss_hermite(self.nodes).map_err(MethodError::from),
                f => f
                    .gauss(self.nodes)
                    .map_err(|e| MethodError::Invalid(InvalidSettings(format!("scm: {e}")))),
            })
            .collect::<Result<_, _>>()?;
        let grid = quadrature::tensor_product(&rules)?;
        Ok(Design::mapped(
            Germ::Askey,
            grid.points,
            Some(grid.weights),
            inputs,
        ))
    }
}

impl Sampling for Scm {
    /// One: `nodes = 1` is a single run at the centre of the inputs (a chaos of order 0: the
    /// mean, Std 0), as a sparse grid of level 0 is; a weighted design never drops a point.
    fn min_runs(&self) -> usize {
        1
    }

    /// The tensor grid, last parameter varying fastest; weights sum to one.
    fn make_design(&self, inputs: &RandomInputs, _seed: u64) -> Result<Design, MethodError> {
        let mut design = self.grid(inputs)?;
        if self.nodes == 1 {
            design.warnings.push(
                "scm with `nodes = 1` is one run at the centre of the inputs: a chaos of order \
                 0, whose mean is the model there and whose Std is 0 (no scatter is estimated, \
                 no Sobol' index); 2 or more nodes estimate the scatter"
                    .into(),
            );
        }
        Ok(design)
    }

    fn planned_runs(&self, dim: usize) -> Option<f64> {
        Some((self.nodes as f64).powi(dim as i32))
    }

    /// Needs every node: a missing weighted node would bias every moment.
    fn make_estimate(&self, results: RunResults) -> Result<Estimate, MethodError> {
        let RunResults { design, rows, data } = results;
        let weights = design.complete_weights(rows)?;
        let dim = design.points.first().map_or(0, Vec::len);
        let set = MultiIndexSet::total_degree(dim, self.order()).map_err(PceError::from)?;
        let families = design.families().ok_or_else(|| {
            MethodError::Invalid(InvalidSettings("scm needs a chaos germ".into()))
        })?;
        let basis = Basis::new(families, set).map_err(PceError::from)?;
        let pce = Pce::project(basis, &design.points, weights, data, &vec![self.nodes; dim])?;
        let mut estimate = Estimate::from_quadrature(data, weights);
        estimate.std_chaos = Some(pce.std());
        estimate.chaos_error = order_difference(&pce);
        estimate.sobol = Some(Sobol::from_chaos(&pce));
        estimate.chaos = Some(pce);
        estimate.draws = Draws::Chaos;
        Ok(estimate)
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::DMatrix;

    use std::f64::consts::PI;

    use super::*;
    use crate::uq::distributions::{Distribution, RandomParameter};

    fn ishigami(x: &[f64]) -> f64 {
        x[0].sin() + 7.0 * x[1].sin().powi(2) + 0.1 * x[2].powi(4) * x[0].sin()
    }

    fn inputs(law: Distribution) -> RandomInputs {
        RandomInputs::independent(
            (0..3)
                .map(|i| RandomParameter::new(format!("x{}", i + 1), law.clone()))
                .collect(),
        )
    }

    fn run(scm: &Scm, inputs: &RandomInputs, f: fn(&[f64]) -> f64) -> (Design, Estimate) {
        let design = scm.design(inputs, 0).unwrap();
        let y: Vec<f64> = design.values.iter().map(|x| f(x)).collect();
        let data = DMatrix::from_column_slice(y.len(), 1, &y);
        let rows: Vec<usize> = (0..y.len()).collect();
        let e = scm.estimate(&design, &rows, &data).unwrap();
        (design, e)
    }

    #[test]
    fn scm_of_uniform_inputs_takes_gauss_legendre_nodes_and_meets_the_ishigami_closed_form() {
        // Before: every input went through the normal map to Gauss–Hermite nodes, and with
        // 12 nodes per input the Ishigami mean came out 4.09 instead of 3.5.
        let (a, b) = (7.0, 0.1);
        let v1 = 0.5 * (1.0 + b * PI.powi(4) / 5.0).powi(2);
        let v2 = a * a / 8.0;
        let v13 = 8.0 * b * b * PI.powi(8) / 225.0;
        let var = v1 + v2 + v13;
        let x = inputs(Distribution::uniform(-PI, PI).unwrap());
        let scm = Scm {
            nodes: 12,
            order: Some(11),
            chaos: ChaosBasis::Askey,
        };
        let (design, e) = run(&scm, &x, ishigami);
        assert_eq!(design.germ, Germ::Askey);
        assert_eq!(design.len(), 12 * 12 * 12);
        // Gauss–Legendre nodes: every value inside [-pi, pi], symmetric about 0.
        assert!(design.values.iter().flatten().all(|v| v.abs() < PI));
        assert!((e.mean[0] - a / 2.0).abs() < 1e-6, "mean {}", e.mean[0]);
        assert!(
            (e.std[0] - var.sqrt()).abs() < 1e-5 * var.sqrt(),
            "std {} vs {}",
            e.std[0],
            var.sqrt()
        );
        let s = e.sobol.as_ref().unwrap();
        let first = [v1 / var, v2 / var, 0.0];
        let total = [(v1 + v13) / var, v2 / var, v13 / var];
        for p in 0..3 {
            assert!((s.first[0][p] - first[p]).abs() < 2e-3, "S{p} {s:?}");
            assert!((s.total[0][p] - total[p]).abs() < 2e-3, "ST{p} {s:?}");
        }
        // The paper's mapping through the normal, kept as `chaos = "hermite"`, is far off
        // with the same nodes (the reason it is no longer the default).
        let hermite = Scm {
            chaos: ChaosBasis::Hermite,
            ..scm
        };
        let (design, e) = run(&hermite, &x, ishigami);
        assert_eq!(design.germ, Germ::Normal);
        assert!((e.mean[0] - a / 2.0).abs() > 0.1, "mean {}", e.mean[0]);
    }

    #[test]
    fn scm_of_normal_inputs_keeps_the_gauss_hermite_design_under_either_chaos() {
        let x = inputs(Distribution::normal(1.0, 0.2).unwrap());
        let askey = Scm {
            nodes: 4,
            order: None,
            chaos: ChaosBasis::Askey,
        };
        let hermite = Scm {
            chaos: ChaosBasis::Hermite,
            ..askey.clone()
        };
        let (da, ea) = run(&askey, &x, |x| x[0] * x[1] + x[2].powi(3));
        let (dh, eh) = run(&hermite, &x, |x| x[0] * x[1] + x[2].powi(3));
        assert_eq!(da.germ, Germ::Normal);
        assert_eq!(da.points, dh.points);
        assert_eq!(da.values, dh.values);
        assert_eq!(ea.mean, eh.mean);
        assert_eq!(ea.std, eh.std);
        // Closed form: E[x1 x2] = 1, Var = E[x1^2]E[x2^2] - 1 + Var(x3^3) with
        // E[x^2] = 1.04, Var(x^3) = E[x^6] - E[x^3]^2 for N(1, 0.2^2).
        let m = |k: i32| -> f64 {
            // E[(1 + 0.2 Z)^k] by the binomial sum with E[Z^(2j)] = (2j - 1)!!.
            (0..=k)
                .map(|j| {
                    let binom = (0..j).fold(1.0, |c, i| c * f64::from(k - i) / f64::from(i + 1));
                    let zj = if j % 2 == 1 {
                        0.0
                    } else {
                        (1..j).step_by(2).map(f64::from).product::<f64>()
                    };
                    binom * 0.2f64.powi(j) * zj
                })
                .sum()
        };
        let var = m(2) * m(2) - 1.0 + m(6) - m(3) * m(3);
        assert!((ea.mean[0] - (1.0 + m(3))).abs() < 1e-12);
        assert!((ea.std[0] - var.sqrt()).abs() < 1e-12);
    }
}
