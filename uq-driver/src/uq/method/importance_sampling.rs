//! `kind = "importance_sampling"`: importance sampling around FORM's design point (or a
//! point of the user's), until a target coefficient of variation or a budget of runs.
//!
//! For each target, FORM (its settings in `[method.form]`) finds the design point `u*`
//! unless `centre` gives the point; then samples `u_i = c + z_i`, `z_i ~ N(0, I)`, run in
//! parallel batches of `batch`, weigh each failing sample by the ratio of the standard
//! normal densities `w_i = φ(u_i)/φ(u_i − c) = exp(−c·z_i − |c|²/2)`:
//! `P̂ = (1/N) Σ 1{g(u_i) ≤ 0} w_i` (unbiased whatever the centre), with its coefficient of
//! variation from the weights and a 95 % interval on the log scale
//! (`crate::uq::reliability::importance`). Centred at the design point of a limit state
//! with one design point, about 1 400 to 2 150 runs reach a CoV of 5 % at `P` from 1e-3 to
//! 1e-6 (linear `g`). The sampling stops at `target_cov` (with at least 10 failing samples)
//! or after `max_runs` samples, whichever comes first.
//!
//! With `[method.form] multistart = true`, where the search finds several design points of
//! comparable probability (`Φ(−β_j)` within a factor 100 of the largest), the samples come
//! from the mixture of normals around all of them, each drawn with probability `∝ Φ(−β_j)`
//! (`importance_sampling.mixture` in `summary.json`): around the first alone, the failure
//! domain near the others was missed, with an interval that did not show it.
//!
//! The reported `beta`, design point and importance factors are FORM's (`null` with a
//! `centre`); `P`, its CoV and interval are the sampling's, which corrects FORM's `Φ(−β)`
//! for the curvature of the surface.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::adaptive::{
    per_target_items, standard_point, AnalyseTarget, FailedRuns, LimitResult, PerTarget, Target,
};
use super::error::{InvalidSettings, MethodError};
use super::form::Form;
use super::sorm::check_nested_form;
use super::traits::{adaptive_method_items, Adaptive, Method, Problem};
use crate::uq::random_inputs::RandomInputs;
use crate::uq::reliability::{self, LimitState, MixtureComponent, ReliabilityError};

/// `kind = "importance_sampling"`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ImportanceSampling {
    /// The FORM search that finds the centre (`[method.form]`, the keys of `kind = "form"`
    /// but `quantities`); not run when `centre` is given.
    pub form: Form,
    /// The centre of the sampling density in physical units, by parameter name (every
    /// random parameter), instead of FORM's design point.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub centre: Option<BTreeMap<String, f64>>,
    /// Stop when the estimated coefficient of variation of `P` is at or below this.
    pub target_cov: f64,
    /// Samples (model runs) at most, FORM's runs not counted.
    pub max_runs: usize,
    /// Samples per batch, run in parallel.
    pub batch: usize,
    /// What a failed run counts as.
    pub failed_runs: FailedRuns,
    /// The quantities analysed (default: every quantity with limits).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub quantities: Vec<String>,
}

impl Default for ImportanceSampling {
    fn default() -> Self {
        let n = reliability::ImportanceSampling::default();
        ImportanceSampling {
            form: Form::default(),
            centre: None,
            target_cov: n.target_cov,
            max_runs: n.max_runs,
            batch: n.batch,
            failed_runs: FailedRuns::default(),
            quantities: Vec::new(),
        }
    }
}

impl ImportanceSampling {
    fn numerics(&self) -> reliability::ImportanceSampling {
        reliability::ImportanceSampling {
            target_cov: self.target_cov,
            max_runs: self.max_runs,
            batch: self.batch,
            on_failure: self.failed_runs.policy(),
        }
    }

    /// FORM's runs of one target, at most (none with a centre).
    fn form_runs(&self, d: usize) -> usize {
        if self.centre.is_some() {
            0
        } else {
            self.form.max_runs_per_target(d)
        }
    }
}

impl Method for ImportanceSampling {
    fn kind(&self) -> &'static str {
        "importance_sampling"
    }

    fn label(&self, _dim: usize) -> String {
        format!(
            "importance sampling (CoV {}, ≤ {} runs)",
            self.target_cov, self.max_runs
        )
    }

    fn validate(&self, problem: &Problem) -> Result<(), InvalidSettings> {
        check_nested_form(&self.form, "importance_sampling")?;
        if !(self.target_cov.is_finite() && self.target_cov > 0.0) {
            return Err(InvalidSettings(format!(
                "`target_cov` must be positive (got {})",
                self.target_cov
            )));
        }
        if self.max_runs < 2 || self.batch == 0 {
            return Err(InvalidSettings(format!(
                "`max_runs` must be at least 2 and `batch` at least 1 (got {}, {})",
                self.max_runs, self.batch
            )));
        }
        match &self.centre {
            Some(c) => {
                let inputs = RandomInputs {
                    parameters: problem.parameters.to_vec(),
                    correlation: problem.correlation.cloned(),
                };
                standard_point(&inputs, c, "`centre`").map(|_| ())
            }
            None => self.form.check(problem, "importance sampling after FORM"),
        }
    }

    adaptive_method_items!("an importance-sampling study");
}

impl Adaptive for ImportanceSampling {
    fn max_runs(&self, dim: usize, targets: usize) -> usize {
        targets * (self.form_runs(dim) + self.max_runs)
    }

    fn expected_runs(&self, dim: usize, targets: usize) -> f64 {
        let form = if self.centre.is_some() {
            0.0
        } else {
            self.form.expected_runs_per_target(dim)
        };
        targets as f64 * (form + self.max_runs as f64)
    }

    per_target_items!();
}

impl PerTarget for ImportanceSampling {
    fn analyser(
        &self,
        inputs: &RandomInputs,
        seed: u64,
    ) -> Result<impl AnalyseTarget, MethodError> {
        let settings = self.numerics();
        let centre = match &self.centre {
            Some(c) => Some(standard_point(inputs, c, "`centre`")?),
            None => None,
        };
        Ok(move |g: &mut dyn LimitState, t: &Target, first| {
            let (mut out, components) = match &centre {
                Some(c) => (
                    LimitResult::new(t, "importance_sampling", first),
                    vec![MixtureComponent {
                        centre: c.clone(),
                        weight: 1.0,
                    }],
                ),
                None => {
                    let out = self.form.analyse(g, t, first, inputs, seed)?;
                    let components = centres(&out)?;
                    (out, components)
                }
            };
            if out.second_design_point_suspected {
                out.warnings.push(
                    "importance sampling around this one design point: its estimate and \
                     interval leave out failures near a second one (`[method.form] multistart = \
                     true` samples around every design point found; `subset` needs none)"
                        .into(),
                );
            }
            if components.len() > 1 {
                out.warnings.push(format!(
                    "importance sampling draws from a mixture around the {} design points of \
                     comparable probability, each with probability ∝ Φ(−β_j)",
                    components.len()
                ));
            }
            let r = reliability::importance_sampling_mixture(
                g,
                &settings,
                &components,
                seed,
                out.next_run(),
            )?;
            out.method = "importance_sampling";
            out.probability = r.probability;
            out.cov = r.cov;
            out.ci_95 = r.interval;
            out.runs += r.runs;
            out.warnings.extend(r.warnings.iter().cloned());
            out.importance_sampling = Some(r);
            Ok(out)
        })
    }
}

/// The centres of the sampling density after FORM: its design point, or where a multi-start
/// search found several of comparable probability, all of them weighted by `Φ(−β_j)`.
fn centres(out: &LimitResult) -> Result<Vec<MixtureComponent>, ReliabilityError> {
    let relevant = reliability::MultiStart::default().relevant;
    match &out.multistart {
        Some(ms) if ms.several => Ok(ms
            .comparable(relevant)
            .into_iter()
            .map(|f| MixtureComponent {
                centre: f.u_star.clone(),
                weight: f.probability,
            })
            .collect()),
        _ => Ok(vec![MixtureComponent {
            centre: out.form_analysis()?.u_star.clone(),
            weight: 1.0,
        }]),
    }
}

#[cfg(test)]
mod tests {
    use super::super::adaptive::tests::{above, standard_inputs, Analytic};
    use super::*;
    use crate::uq::special::norm_isf;

    #[test]
    fn after_form_a_linear_limit_state_is_within_its_cov_in_2000_runs() {
        let inputs = standard_inputs(8);
        for p in [1e-3, 1e-6] {
            let b = 8f64.sqrt() * norm_isf(p);
            let t = above("s", b);
            let mut model = Analytic::new(&inputs, |x: &[f64]| vec![Ok(x.iter().sum::<f64>())]);
            let r = ImportanceSampling::default()
                .run(&mut model, &inputs, &t, &["s".into()], 3)
                .unwrap();
            let l = &r.limits[0];
            let cov = l.cov.unwrap();
            let err = (l.probability - p).abs() / p;
            assert!(cov <= 0.055, "CoV {cov}");
            assert!(err < 4.0 * cov, "P = {p}: {} ({err:.3})", l.probability);
            let [lo, hi] = l.ci_95.unwrap();
            assert!(lo < l.probability && l.probability < hi);
            let is = l.importance_sampling.as_ref().unwrap();
            assert!(is.runs <= 2000);
            assert_eq!(l.runs, l.form.as_ref().unwrap().runs + 1 + is.runs);
            assert!(l.beta.is_some() && l.design_point.is_some());
        }
    }

    #[test]
    fn a_symmetric_limit_state_after_multistart_is_sampled_around_both_design_points() {
        // P(|x1 + x2| > 5) = 2 Φ(−5/√2) = 4.07e-4, half of it at each of ±(2.5, 2.5); around
        // one design point the estimate was half of it, its interval excluding P.
        let inputs = standard_inputs(2);
        let exact = 2.0 * crate::uq::special::norm_sf(5.0 / 2f64.sqrt());
        let t = above("s", 5.0);
        let mut model = Analytic::new(&inputs, |x: &[f64]| vec![Ok((x[0] + x[1]).abs())]);
        // A single FORM search: about half of P, and a warning that says so.
        let one = ImportanceSampling::default()
            .run(&mut model, &inputs, &t, &["s".into()], 7)
            .unwrap();
        let l = &one.limits[0];
        assert!(l.probability < 0.75 * exact, "{}", l.probability);
        assert_warned(l, "leave out failures near a second one");
        let mut settings = ImportanceSampling::default();
        settings.form.multistart = true;
        let mut model = Analytic::new(&inputs, |x: &[f64]| vec![Ok((x[0] + x[1]).abs())]);
        let r = settings
            .run(&mut model, &inputs, &t, &["s".into()], 7)
            .unwrap();
        let l = &r.limits[0];
        let is = l.importance_sampling.as_ref().unwrap();
        assert_eq!(is.mixture.len(), 2, "{:?}", l.warnings);
        let [lo, hi] = l.ci_95.unwrap();
        assert!(
            lo <= exact && exact <= hi,
            "{} [{lo}, {hi}] vs {exact}",
            l.probability
        );
        assert_warned(l, "mixture around the 2 design points");
    }

    /// `l` has a warning with `words` in it.
    fn assert_warned(l: &LimitResult, words: &str) {
        assert!(
            l.warnings.iter().any(|w| w.contains(words)),
            "no {words:?} in {:?}",
            l.warnings
        );
    }

    #[test]
    fn a_user_centre_skips_form_and_still_gives_an_unbiased_estimate() {
        // P(x1 > 3) = Phi(-3), sampled around (2.8, 0.3), off the design point (3, 0).
        let inputs = standard_inputs(2);
        let t = above("x1", 3.0);
        let mut model = Analytic::new(&inputs, |x: &[f64]| vec![Ok(x[0] + 0.0 * x[1])]);
        let settings = ImportanceSampling {
            centre: Some(
                [("x1".to_string(), 2.8), ("x2".to_string(), 0.3)]
                    .into_iter()
                    .collect(),
            ),
            target_cov: 0.03,
            ..ImportanceSampling::default()
        };
        let r = settings
            .run(&mut model, &inputs, &t, &["x1".into()], 5)
            .unwrap();
        let l = &r.limits[0];
        assert!(l.form.is_none() && l.beta.is_none() && l.design_point.is_none());
        let exact = crate::uq::special::norm_sf(3.0);
        let cov = l.cov.unwrap();
        assert!(
            (l.probability - exact).abs() < 4.0 * cov * exact,
            "{}",
            l.probability
        );
    }
}
