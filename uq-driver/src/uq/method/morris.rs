//! `kind = "morris"`: Morris's elementary-effects screening (Morris 1991) with the spread
//! trajectories of Campolongo, Cariboni & Saltelli (2007), at `r (d + 1)` runs.
//!
//! Each input moves on a grid of `levels` probability levels (`(k + 1/2)/levels`, mapped by
//! its quantile function, through the Gaussian copula of correlated inputs); a trajectory
//! moves one input at a time by half the probability range. Of `candidates` random
//! trajectories the `trajectories` most spread out are kept (greedy maximisation of
//! Campolongo's distance), and all `r (d + 1)` points run as one parallel batch. Per scalar
//! quantity and input: `μ* = mean |EE_i|` (the ranking), `σ` the standard deviation of the
//! elementary effects (non-linearity and interactions) and `μ = mean EE_i`, each per unit of
//! probability level (`crate::uq::reliability::morris`). The points are not samples of the
//! inputs' law: no moments, densities or probabilities come from them.

use super::adaptive::{AdaptiveResult, BatchModel, Screening, Target};
use super::error::{InvalidSettings, MethodError};
use super::traits::{
    Adaptive, AdaptiveMethod, Evaluation, KindNotes, Method, MethodSummary, Problem,
};
use crate::uq::random_inputs::RandomInputs;
use crate::uq::reliability::{MorrisDesign, Point};
use crate::uq::special::norm_ppf;

/// `kind = "morris"`: the screening's settings are those of the numerics.
pub use crate::uq::reliability::Morris;

impl Method for Morris {
    fn kind(&self) -> &'static str {
        "morris"
    }

    fn label(&self, dim: usize) -> String {
        format!("morris {} × {}", self.trajectories, dim + 1)
    }

    fn validate(&self, _problem: &Problem) -> Result<(), InvalidSettings> {
        if self.trajectories < 2 || self.levels < 2 || !self.levels.is_multiple_of(2) {
            return Err(InvalidSettings(format!(
                "Morris needs at least 2 trajectories and an even number of levels (got \
                 trajectories = {}, levels = {})",
                self.trajectories, self.levels
            )));
        }
        Ok(())
    }

    fn summary(&self, dim: usize) -> MethodSummary {
        let mut s = MethodSummary::new(self.kind(), self);
        s.details.insert(
            "runs".into(),
            serde_json::json!(self.trajectories * (dim + 1)),
        );
        s
    }

    fn evaluation(&self) -> Evaluation<'_> {
        Evaluation::Adaptive(AdaptiveMethod(self))
    }

    fn notes() -> KindNotes {
        KindNotes {
            name: Some("a Morris screening"),
            adaptive: true,
            ..KindNotes::default()
        }
    }
}

impl Adaptive for Morris {
    fn max_runs(&self, dim: usize, _targets: usize) -> usize {
        self.trajectories * (dim + 1)
    }

    fn expected_runs(&self, dim: usize, _targets: usize) -> f64 {
        (self.trajectories * (dim + 1)) as f64
    }

    fn needs_limits(&self) -> bool {
        false
    }

    fn run(
        &self,
        model: &mut dyn BatchModel,
        inputs: &RandomInputs,
        _targets: &[Target],
        names: &[String],
        seed: u64,
    ) -> Result<AdaptiveResult, MethodError> {
        let label = "Morris screening";
        let design = MorrisDesign::new(inputs.len(), self, seed)
            .map_err(|e| super::adaptive::method_error(e, label, inputs))?;
        let batch: Vec<Point> = design
            .points()
            .into_iter()
            .enumerate()
            .map(|(k, q)| Point {
                run: k as u64,
                u: q.into_iter().map(norm_ppf).collect(),
            })
            .collect();
        let values = model
            .evaluate(&batch)
            .map_err(|a| super::adaptive::method_error(a.into(), label, inputs))?;
        let mut screening = Vec::with_capacity(names.len());
        for (k, name) in names.iter().enumerate() {
            let outcomes: Vec<_> = values
                .iter()
                .map(|v| {
                    v.get(k)
                        .cloned()
                        .unwrap_or_else(|| Err("no value".to_string()))
                })
                .collect();
            let morris = design
                .estimate(&outcomes)
                .map_err(|e| super::adaptive::method_error(e, label, inputs))?;
            screening.push(Screening {
                quantity: k,
                name: name.clone(),
                morris,
            });
        }
        Ok(AdaptiveResult {
            limits: Vec::new(),
            screening,
            runs: batch.len() as u64,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::super::adaptive::tests::{standard_inputs, Analytic};
    use super::*;
    use crate::uq::distributions::{Distribution, RandomParameter};

    #[test]
    fn a_linear_model_ranks_its_inputs_by_their_effect_at_r_d_plus_1_runs() {
        // y = 3 x1 + 0.5 x2 + 0 x3 with x uniform on [0, 1]: EE_i = c_i exactly (per unit of
        // probability level), so mu* = |c_i| and sigma = 0; y2 = x1 x2 interacts.
        let inputs = RandomInputs::independent(
            (1..=3)
                .map(|i| {
                    RandomParameter::new(format!("x{i}"), Distribution::uniform(0.0, 1.0).unwrap())
                })
                .collect(),
        );
        let mut model = Analytic::new(&inputs, |x: &[f64]| {
            vec![Ok(3.0 * x[0] + 0.5 * x[1]), Ok(x[0] * x[1])]
        });
        let m = Morris::default();
        let r = m
            .run(&mut model, &inputs, &[], &["y".into(), "y2".into()], 4)
            .unwrap();
        assert_eq!(r.runs, 10 * 4);
        assert_eq!(model.runs, 40);
        assert_eq!(model.batches, 1, "one parallel batch");
        let y = &r.screening[0].morris;
        for (got, want) in y.mu_star.iter().zip([3.0, 0.5, 0.0]) {
            assert!((got - want).abs() < 1e-9, "{:?}", y.mu_star);
        }
        assert!(y.sigma.iter().all(|s| s.abs() < 1e-9), "{:?}", y.sigma);
        assert_eq!(y.ranking, vec![0, 1, 2]);
        let y2 = &r.screening[1].morris;
        assert!(y2.sigma[0] > 0.0 && y2.mu_star[2] == 0.0, "{y2:?}");
        // Standard normal inputs work too (levels through the normal quantile).
        let normal = standard_inputs(2);
        let mut model = Analytic::new(&normal, |x: &[f64]| vec![Ok(x[0])]);
        let r = m.run(&mut model, &normal, &[], &["x1".into()], 1).unwrap();
        assert!(r.screening[0].morris.mu_star[0] > 0.0);
        assert_eq!(r.screening[0].morris.mu_star[1], 0.0);
    }
}
