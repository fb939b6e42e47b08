//! `kind = "subset"`: subset simulation (Au & Beck 2001) with adaptive conditional sampling
//! (Papaioannou et al. 2015), for limit states of any shape.
//!
//! For each target, `P = P(F_1) Π P(F_{l+1} | F_l)` over nested domains
//! `F_l = {g ≤ b_l}` whose thresholds are the `p0`-quantiles of each level's `N` samples
//! (level 0 independent, the others Markov chains of length `1/p0` seeded by the samples
//! below the threshold, each step of all chains one parallel batch), until a threshold
//! reaches 0 (`crate::uq::reliability::subset`). Each level costs `N(1 − p0)` runs (`N` at
//! level 0), so `P = 1e-6` at `p0 = 0.1` takes 6 levels, `N(1 + 5 · 0.9)` runs.
//!
//! The coefficient of variation accounts for the correlation of the chains (Au & Beck's
//! `γ_l`): `cov` takes the levels as independent (the figure usually quoted, which the
//! numerics' calibration found 1.2 to 1.4 times too small), `cov_upper` as fully correlated;
//! the 95 % interval is built on `cov_upper` (conservative). When no sample fails at the last
//! level, `P` is 0 and a 95 % upper bound is given instead.
//!
//! Reported `beta` is the generalised reliability index `−Φ⁻¹(P)`; there is no design point.

use serde::{Deserialize, Serialize};

use super::adaptive::{
    generalised_beta, per_target_items, AnalyseTarget, FailedRuns, LimitResult, PerTarget, Target,
};
use super::error::{InvalidSettings, MethodError};
use super::traits::{adaptive_method_items, Adaptive, Method, Problem};
use crate::uq::random_inputs::RandomInputs;
use crate::uq::reliability::{self, LimitState, Spread};

/// `kind = "subset"`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Subset {
    /// Samples per level `N`.
    pub samples_per_level: usize,
    /// The conditional probability of the intermediate levels.
    pub p0: f64,
    /// Levels at most (level 0 included).
    pub max_levels: usize,
    /// A fixed standard deviation of the proposal in every coordinate (`0 < σ ≤ 1`)
    /// instead of the adaptive spread (aCS, the default).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub proposal_spread: Option<f64>,
    /// What a failed run counts as.
    pub failed_runs: FailedRuns,
    /// The quantities analysed (default: every quantity with limits).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub quantities: Vec<String>,
}

impl Default for Subset {
    fn default() -> Self {
        let n = reliability::Subset::default();
        Subset {
            samples_per_level: n.samples_per_level,
            p0: n.p0,
            max_levels: n.max_levels,
            proposal_spread: None,
            failed_runs: FailedRuns::default(),
            quantities: Vec::new(),
        }
    }
}

impl Subset {
    fn numerics(&self) -> reliability::Subset {
        reliability::Subset {
            samples_per_level: self.samples_per_level,
            p0: self.p0,
            max_levels: self.max_levels,
            spread: match self.proposal_spread {
                Some(sigma) => Spread::Fixed { sigma },
                None => Spread::default(),
            },
            on_failure: self.failed_runs.policy(),
        }
    }
}

impl Method for Subset {
    fn kind(&self) -> &'static str {
        "subset"
    }

    fn label(&self, _dim: usize) -> String {
        format!("subset (N = {}, p0 = {})", self.samples_per_level, self.p0)
    }

    fn validate(&self, _problem: &Problem) -> Result<(), InvalidSettings> {
        let seeds = (self.samples_per_level as f64 * self.p0).round();
        if !(self.p0 > 0.0 && self.p0 <= 0.5) || seeds < 2.0 || self.max_levels < 1 {
            return Err(InvalidSettings(format!(
                "subset simulation needs 0 < p0 <= 0.5, samples_per_level * p0 >= 2 and \
                 max_levels >= 1 (got p0 = {}, samples_per_level = {}, max_levels = {})",
                self.p0, self.samples_per_level, self.max_levels
            )));
        }
        if let Some(s) = self.proposal_spread {
            if !(s > 0.0 && s <= 1.0) {
                return Err(InvalidSettings(format!(
                    "`proposal_spread` must be in (0, 1] (got {s})"
                )));
            }
        }
        Ok(())
    }

    adaptive_method_items!("a subset-simulation study");
}

impl Adaptive for Subset {
    fn max_runs(&self, _dim: usize, targets: usize) -> usize {
        targets * self.samples_per_level * self.max_levels
    }

    fn expected_runs(&self, _dim: usize, targets: usize) -> f64 {
        // Four levels (P about 1e-4 at p0 = 0.1).
        let n = self.samples_per_level as f64;
        targets as f64 * n * (1.0 + 3.0 * (1.0 - self.p0))
    }

    per_target_items!();
}

impl PerTarget for Subset {
    fn analyser(
        &self,
        _inputs: &RandomInputs,
        seed: u64,
    ) -> Result<impl AnalyseTarget, MethodError> {
        let settings = self.numerics();
        Ok(move |g: &mut dyn LimitState, t: &Target, first| {
            let r = reliability::subset_simulation(g, &settings, seed, first)?;
            let mut out = LimitResult::new(t, "subset", first);
            out.probability = r.probability;
            out.cov = r.cov;
            out.ci_95 = r.interval;
            out.upper_95 = r.upper_bound;
            out.beta = generalised_beta(r.probability);
            out.runs = r.runs;
            out.warnings.extend(r.warnings.iter().cloned());
            out.subset = Some(r);
            Ok(out)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::super::adaptive::targets;
    use super::super::adaptive::tests::{standard_inputs, Analytic};
    use super::*;
    use statrs::distribution::{ChiSquared, ContinuousCDF};

    #[test]
    fn a_sum_of_squares_is_within_its_cov_and_a_limit_never_reached_has_a_bound() {
        // |x|^2 ~ chi-square with 6 degrees of freedom: P(|x|^2 > 30) = 3.7e-5.
        let inputs = standard_inputs(6);
        let exact = ChiSquared::new(6.0).unwrap().sf(30.0);
        let q = vec![
            ("r2".to_string(), vec![30.0], vec![]),
            ("bounded".to_string(), vec![2.0], vec![]),
        ];
        let t = targets(&q, &[]).unwrap();
        let mut model = Analytic::new(&inputs, |x: &[f64]| {
            let r2: f64 = x.iter().map(|v| v * v).sum();
            // tanh < 1 never reaches 2.
            vec![Ok(r2), Ok(x[0].tanh())]
        });
        let settings = Subset {
            samples_per_level: 1000,
            max_levels: 6,
            ..Subset::default()
        };
        let r = settings
            .run(
                &mut model,
                &inputs,
                &t,
                &["r2".into(), "bounded".into()],
                11,
            )
            .unwrap();
        let l = &r.limits[0];
        let cov = l.cov_upper();
        assert!(
            (l.probability - exact).abs() < 3.0 * cov * exact,
            "{} vs {exact} (cov_upper {cov})",
            l.probability
        );
        let [lo, hi] = l.ci_95.unwrap();
        assert!(lo <= exact && exact <= hi, "[{lo}, {hi}] vs {exact}");
        let n = &r.limits[1];
        assert_eq!(n.probability, 0.0);
        assert!(n.ci_95.is_none() && n.cov.is_none() && n.beta.is_none());
        let bound = n.upper_95.unwrap();
        assert!(bound > 0.0 && bound < 1e-3, "{bound}");
        assert!(!n.warnings.is_empty());
        assert_eq!(r.runs, model.runs);
    }

    impl LimitResult {
        fn cov_upper(&self) -> f64 {
            self.subset.as_ref().unwrap().cov_upper.unwrap()
        }
    }
}
