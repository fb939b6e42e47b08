//! `kind = "form"`: the first-order reliability method, one design point per limit.
//!
//! For each target (a quantity against a limit, see `adaptive`) the design point `u*`, the
//! point of the limit-state surface `g(u) = 0` nearest to the origin of the independent
//! standard normal space, is found by the iHLRF iteration (Zhang & Der Kiureghian 1997;
//! `crate::uq::reliability::form`), with gradients by finite differences whose `d + 1`
//! (forward) or `2d + 1` (central) points run as one parallel batch. Reported:
//! `β = α·u*` (signed), `P = Φ(−β)`, the design point in physical units `x* = T(u*)`, the
//! importance factors `α_i²` (`α = −∇g/|∇g|`; with correlated inputs those of the
//! independent coordinates, in study order), the inputs' importance `γ_i²` (the same for
//! independent inputs; with correlated ones `γ = L⁻ᵀα / |L⁻ᵀα|`,
//! `RandomInputs::importance`), the runs and the history of the iteration.
//!
//! `P = Φ(−β)` is exact when `g` is linear in `u`, and for a monotone map of a linear `g`
//! (e.g. a lognormal response); otherwise it is the first-order approximation, with no
//! error estimate: `importance_sampling` corrects it. A limit state with several design
//! points (e.g. `g = c − |u|²`) is beyond FORM: after converging, FORM runs the model once
//! at `−u*`, and when the limit state there has come within a tenth of its value at the
//! origin to failure, it warns that a second design point is suspected (`multistart = true`
//! searches from `2d + 1` points and reports the distinct design points; `subset` handles
//! such shapes).

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::adaptive::{
    check_continuous, per_target_items, standard_point, AnalyseTarget, LimitResult, PerTarget,
    Target,
};
use super::error::{InvalidSettings, MethodError};
use super::traits::{adaptive_method_items, Adaptive, Method, Problem};
use crate::uq::random_inputs::RandomInputs;
use crate::uq::reliability::{
    self, Differences, LimitState, MultiStart, Point, ReliabilityError, Scheme,
};

/// Line-search trials per iteration at most (`crate::uq::reliability::form`).
const LINE_SEARCH_TRIALS: usize = 12;

/// `kind = "form"`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Form {
    /// Finite-difference step in standard normal space, at least (units of each input's
    /// standard deviation near its median: the step is relative to each input's scatter).
    /// A model with numerical noise or a resolution of its own (a bisection tolerance, a
    /// solver tolerance) needs a step well above it.
    pub step: f64,
    /// Step relative to `|u_i|` where that is larger than `step` (far from the median).
    pub relative_step: f64,
    /// Central differences (`2d` runs per gradient, error `O(h²)`) instead of forward
    /// (`d` runs, `O(h)`).
    pub central: bool,
    /// Iterations (gradients) at most.
    pub max_iterations: usize,
    /// Convergence: the linearised distance to the surface `|g|/|∇g|` (standard normal
    /// units).
    pub tolerance_g: f64,
    /// Convergence: the distance of `u` from the gradient's line through the origin.
    pub tolerance_u: f64,
    /// Search from the origin, from `±1` on every axis and from `random_starts` random
    /// points (about `(2d + 1 + random_starts)` times the runs), and report the distinct
    /// design points; a warning when several have comparable probabilities.
    pub multistart: bool,
    /// Random starting points of a multi-start search (on the unit sphere).
    pub random_starts: usize,
    /// Where the search starts, in physical units by parameter name (default: the median
    /// of every input, the origin of the standard space).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub start: Option<BTreeMap<String, f64>>,
    /// The quantities analysed (default: every quantity with limits).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub quantities: Vec<String>,
}

impl Default for Form {
    fn default() -> Self {
        let n = reliability::Form::default();
        Form {
            step: n.differences.absolute,
            relative_step: n.differences.relative,
            central: false,
            max_iterations: n.max_iterations,
            tolerance_g: n.tolerance_g,
            tolerance_u: n.tolerance_u,
            multistart: false,
            random_starts: 0,
            start: None,
            quantities: Vec::new(),
        }
    }
}

impl Form {
    /// The numerics' settings, starting at `start` (standard normal).
    fn numerics(&self, start: Option<Vec<f64>>) -> reliability::Form {
        reliability::Form {
            start,
            differences: Differences {
                scheme: if self.central {
                    Scheme::Central
                } else {
                    Scheme::Forward
                },
                relative: self.relative_step,
                absolute: self.step,
            },
            max_iterations: self.max_iterations,
            tolerance_g: self.tolerance_g,
            tolerance_u: self.tolerance_u,
        }
    }

    /// Checks the settings against the inputs (also for the FORM run before SORM and
    /// importance sampling).
    pub(crate) fn check(&self, problem: &Problem, kind: &str) -> Result<(), InvalidSettings> {
        let positive = |v: f64| v.is_finite() && v > 0.0;
        if !(positive(self.step) && self.relative_step.is_finite() && self.relative_step >= 0.0) {
            return Err(InvalidSettings(format!(
                "`step` must be positive and `relative_step` non-negative (got {}, {})",
                self.step, self.relative_step
            )));
        }
        if !positive(self.tolerance_g) || !positive(self.tolerance_u) {
            return Err(InvalidSettings(format!(
                "`tolerance_g` and `tolerance_u` must be positive (got {}, {})",
                self.tolerance_g, self.tolerance_u
            )));
        }
        if self.max_iterations == 0 {
            return Err(InvalidSettings(
                "`max_iterations` must be at least 1".into(),
            ));
        }
        if self.start.is_some() && self.multistart {
            return Err(InvalidSettings(
                "`start` and `multistart` exclude each other (a multi-start search chooses its \
                 own starting points)"
                    .into(),
            ));
        }
        if let Some(start) = &self.start {
            let inputs = RandomInputs {
                parameters: problem.parameters.to_vec(),
                correlation: problem.correlation.cloned(),
            };
            standard_point(&inputs, start, "`start`")?;
        }
        check_continuous(problem.parameters, kind)
    }

    /// Runs per iterative search at most for `d` inputs.
    fn search_runs(&self, d: usize) -> usize {
        let r = if self.central { 2 * d } else { d };
        (1 + r) + self.max_iterations * (1 + r + (LINE_SEARCH_TRIALS - 1) + r)
    }

    /// Runs of one target at most (with the check at `−u*`).
    pub(crate) fn max_runs_per_target(&self, d: usize) -> usize {
        let starts = if self.multistart {
            1 + 2 * d + self.random_starts
        } else {
            1
        };
        starts * self.search_runs(d) + 1
    }

    /// About how many runs one target takes (five iterations of full steps).
    pub(crate) fn expected_runs_per_target(&self, d: usize) -> f64 {
        let r = if self.central { 2 * d } else { d };
        let starts = if self.multistart {
            1 + 2 * d + self.random_starts
        } else {
            1
        };
        (starts * 5 * (1 + r)) as f64
    }

    /// FORM on the limit state `g` of `target` from run `first`: the design point, then the
    /// check for a second one at `−u*` (a single search).
    pub(crate) fn analyse(
        &self,
        g: &mut dyn LimitState,
        target: &Target,
        first: u64,
        inputs: &RandomInputs,
        seed: u64,
    ) -> Result<LimitResult, ReliabilityError> {
        let mut out = LimitResult::new(target, "form", first);
        let f = if self.multistart {
            let settings = MultiStart {
                form: self.numerics(None),
                random: self.random_starts,
                ..MultiStart::default()
            };
            let ms = reliability::form_multistart(g, &settings, seed, first)?;
            out.warnings.extend(ms.warnings.iter().cloned());
            let best = ms.best().cloned();
            out.runs = ms.runs;
            out.multistart = Some(ms);
            match best {
                Some(f) => f,
                None => {
                    return Err(ReliabilityError::Invalid(
                        "no start of the multi-start search converged to a design point".into(),
                    ))
                }
            }
        } else {
            let start = match &self.start {
                Some(s) => Some(
                    standard_point(inputs, s, "`start`")
                        .map_err(|e| ReliabilityError::Invalid(e.0))?,
                ),
                None => None,
            };
            let f = reliability::form(g, &self.numerics(start), first)?;
            out.runs = f.runs;
            out.warnings.extend(f.warnings.iter().cloned());
            if let Some(w) = mirror_check(g, &f, first + f.runs)? {
                out.warnings.push(w);
                out.second_design_point_suspected = true;
            }
            out.runs += 1;
            f
        };
        out.probability = f.probability;
        out.with_form(&f, inputs);
        out.form = Some(f);
        Ok(out)
    }
}

/// One run at `−u*`: when the limit state there has come within a tenth of its value at
/// the start (the origin) to failure, a second design point is suspected. The run is made
/// whatever the outcome (so that the run numbering does not depend on it); a failed run
/// checks nothing.
fn mirror_check(
    g: &mut dyn LimitState,
    f: &reliability::FormResult,
    run: u64,
) -> Result<Option<String>, ReliabilityError> {
    let u: Vec<f64> = f.u_star.iter().map(|v| -v).collect();
    let out = g.evaluate(&[Point { run, u }])?;
    let g0 = f.history.first().map_or(f64::NAN, |h| h.g);
    let Some(Ok(gm)) = out.into_iter().next() else {
        return Ok(None);
    };
    let suspected = f.converged && f.beta > 0.0 && g0 > 0.0 && gm <= 0.1 * g0;
    Ok(suspected.then(|| {
        format!(
            "a second design point is suspected: at −u* (the design point mirrored through the \
             median) the limit state is {gm:.4e}, within a tenth of its value at the median \
             ({g0:.4e}) of failure; Φ(−β) may miss part of the failure domain (multistart = \
             true finds the distinct design points; subset simulation handles any shape)"
        )
    }))
}

impl Method for Form {
    fn kind(&self) -> &'static str {
        "form"
    }

    fn label(&self, _dim: usize) -> String {
        if self.multistart {
            "form (multi-start)".into()
        } else {
            "form".into()
        }
    }

    fn validate(&self, problem: &Problem) -> Result<(), InvalidSettings> {
        self.check(problem, "FORM")
    }

    adaptive_method_items!("a FORM study");
}

impl Adaptive for Form {
    fn max_runs(&self, dim: usize, targets: usize) -> usize {
        targets * self.max_runs_per_target(dim)
    }

    fn expected_runs(&self, dim: usize, targets: usize) -> f64 {
        targets as f64 * self.expected_runs_per_target(dim)
    }

    per_target_items!();
}

impl PerTarget for Form {
    fn analyser(
        &self,
        inputs: &RandomInputs,
        seed: u64,
    ) -> Result<impl AnalyseTarget, MethodError> {
        Ok(
            move |g: &mut dyn LimitState, t: &Target, first| {
                self.analyse(g, t, first, inputs, seed)
            },
        )
    }
}

#[cfg(test)]
mod tests {
    use super::super::adaptive::targets;
    use super::super::adaptive::tests::{above, standard_inputs, Analytic};
    use super::*;
    use crate::uq::distributions::{Distribution, RandomParameter};
    use crate::uq::special::{norm_isf, norm_sf};

    #[test]
    fn a_linear_quantity_in_8_inputs_gives_the_exact_probability_within_20_runs_per_input() {
        // q = sum c_i x_i with x_i ~ N(m_i, s_i): q ~ N(sum c m, sum c^2 s^2), exactly.
        let params: Vec<RandomParameter> = (0..8)
            .map(|i| {
                RandomParameter::new(
                    format!("x{i}"),
                    Distribution::normal(1.0 + i as f64, 0.5 + 0.1 * i as f64).unwrap(),
                )
            })
            .collect();
        let inputs = RandomInputs::independent(params.clone());
        let c: Vec<f64> = (0..8)
            .map(|i| if i % 2 == 0 { 1.0 } else { -0.5 })
            .collect();
        let mean: f64 = params
            .iter()
            .zip(&c)
            .map(|(p, c)| c * p.distribution.mean())
            .sum();
        let sd = params
            .iter()
            .zip(&c)
            .map(|(p, c)| (c * p.distribution.std()).powi(2))
            .sum::<f64>()
            .sqrt();
        for p in [1e-3, 1e-4, 1e-6] {
            let above = mean + sd * norm_isf(p);
            let below = mean - sd * norm_isf(p);
            let q = vec![("q".to_string(), vec![above], vec![below])];
            let t = targets(&q, &[]).unwrap();
            let cc = c.clone();
            let mut model = Analytic::new(&inputs, move |x: &[f64]| {
                vec![Ok(x.iter().zip(&cc).map(|(a, b)| a * b).sum())]
            });
            let r = Form::default()
                .run(&mut model, &inputs, &t, &["q".into()], 1)
                .unwrap();
            assert_eq!(r.limits.len(), 2);
            for l in &r.limits {
                let err = (l.probability - p).abs() / p;
                assert!(
                    err < 0.01,
                    "{}: {} ({err:.2e})",
                    l.target.label(),
                    l.probability
                );
                assert!(l.runs <= 20 * 8, "{} runs", l.runs);
                let imp: f64 = l.importance.as_ref().unwrap().iter().sum();
                assert!((imp - 1.0).abs() < 1e-9);
                assert!(l.warnings.is_empty(), "{:?}", l.warnings);
                // q(x*) is the limit.
                let (_, x) = l.design_point.as_ref().unwrap();
                let qx: f64 = x.iter().zip(&c).map(|(a, b)| a * b).sum();
                assert!((qx - l.target.threshold.limit).abs() < 1e-3 * sd);
            }
            assert_eq!(r.runs, model.runs);
            assert_eq!(r.limits[1].first_run, r.limits[0].runs);
        }
    }

    #[test]
    fn a_sum_of_squares_warns_of_a_second_design_point() {
        let inputs = standard_inputs(4);
        let t = above("r2", 16.0);
        let mut model = Analytic::new(&inputs, |x: &[f64]| {
            // Off-centre by a little, so that the gradient at the median is not zero.
            vec![Ok(x.iter().map(|v| (v - 0.01).powi(2)).sum())]
        });
        let r = Form::default()
            .run(&mut model, &inputs, &t, &["r2".into()], 1)
            .unwrap();
        let w = &r.limits[0].warnings;
        assert!(
            w.iter()
                .any(|w| w.contains("second design point is suspected")),
            "{w:?}"
        );
        assert!(w[0].starts_with("P(r2 > 16): "), "{w:?}");
        // FORM's P = Phi(-beta), beta = 2 (2 - 0.01) on the diagonal, is far below the
        // chi-square tail P(chi2_4 > 16) = 0.0030.
        let exact = norm_sf(3.98);
        assert!(r.limits[0].probability < 0.1 * 0.003);
        assert!((r.limits[0].probability - exact).abs() < 0.01 * exact);
    }

    #[test]
    fn correlated_inputs_are_ranked_by_their_own_scale_not_by_their_order() {
        // q = sum c_i x_i, x normal with correlation R: in u (x = m + D L u) the gradient of
        // q is L^T D c, so alpha = L^T D c / |.|, which credits the first input with what it
        // shares with the others; the inputs' importance is gamma_i^2 = (c_i s_i)^2 / sum,
        // whatever R (Der Kiureghian 2005).
        use crate::uq::random_inputs::{Correlation, CorrelationPair};
        let (m, s, c) = ([1.0, 2.0, 3.0], [0.5, 0.3, 0.8], [1.0, 2.0, -0.25]);
        let params: Vec<RandomParameter> = (0..3)
            .map(|i| {
                RandomParameter::new(format!("x{i}"), Distribution::normal(m[i], s[i]).unwrap())
            })
            .collect();
        let pair = |a: &str, b: &str, rho: f64| CorrelationPair {
            between: [a.into(), b.into()],
            rho,
        };
        let pairs = vec![pair("x0", "x1", 0.7), pair("x1", "x2", -0.4)];
        let inputs = RandomInputs {
            correlation: Correlation::new(&params, pairs).unwrap(),
            parameters: params,
        };
        // The exact sd of q: c^T D R D c.
        let r = [[1.0, 0.7, 0.0], [0.7, 1.0, -0.4], [0.0, -0.4, 1.0]];
        let cs: Vec<f64> = (0..3).map(|i| c[i] * s[i]).collect();
        let var: f64 = (0..3)
            .flat_map(|i| (0..3).map(move |j| (i, j)))
            .map(|(i, j)| cs[i] * r[i][j] * cs[j])
            .sum();
        let mean: f64 = (0..3).map(|i| c[i] * m[i]).sum();
        let limit = mean + var.sqrt() * norm_isf(1e-4);
        let t = above("q", limit);
        let mut model = Analytic::new(&inputs, move |x: &[f64]| {
            vec![Ok(x.iter().zip(&c).map(|(a, b)| a * b).sum())]
        });
        let res = Form::default()
            .run(&mut model, &inputs, &t, &["q".into()], 1)
            .unwrap();
        let l = &res.limits[0];
        assert!((l.probability - 1e-4).abs() < 1e-6, "{}", l.probability);
        let alpha2 = l.importance.as_ref().unwrap();
        let gamma2 = l.importance_gamma.as_ref().unwrap();
        let sum: f64 = cs.iter().map(|v| v * v).sum();
        for i in 0..3 {
            let want = cs[i] * cs[i] / sum;
            assert!(
                (gamma2[i] - want).abs() < 1e-6,
                "{gamma2:?} against {want} at {i}"
            );
        }
        // The two rankings differ: the test sees which one is reported.
        let off = (0..3)
            .map(|i| (alpha2[i] - gamma2[i]).abs())
            .fold(0.0, f64::max);
        assert!(off > 0.05, "{alpha2:?} {gamma2:?}");
        // Independent inputs: gamma^2 is alpha^2, to the bit (no renormalisation).
        let independent = RandomInputs::independent(inputs.parameters.clone());
        let a = [0.6, -0.7, 0.1];
        let want: Vec<f64> = a.iter().map(|v| v * v).collect();
        assert_eq!(independent.importance(&a), want);
    }

    #[test]
    fn a_failed_run_is_a_typed_error_naming_the_target_and_the_inputs() {
        let inputs = standard_inputs(2);
        let t = above("q", 3.0);
        let mut model = Analytic::new(&inputs, |x: &[f64]| {
            if x[0] > 1.5 {
                vec![Err("the solver diverged".into())]
            } else {
                vec![Ok(x[0] + x[1])]
            }
        });
        let e = Form::default()
            .run(&mut model, &inputs, &t, &["q".into()], 1)
            .unwrap_err();
        match &e {
            MethodError::RunFailed {
                target,
                values,
                message,
                ..
            } => {
                assert_eq!(target, "P(q > 3)");
                assert_eq!(values[0].0, "x1");
                assert!(values[0].1 > 1.5);
                assert_eq!(message, "the solver diverged");
            }
            other => panic!("{other:?}"),
        }
        assert!(e.to_string().contains("--retry-failed"), "{e}");
    }

    #[test]
    fn settings_are_checked() {
        let inputs = standard_inputs(2);
        let problem = Problem::of_inputs(&inputs);
        for bad in [
            Form {
                step: 0.0,
                ..Form::default()
            },
            Form {
                tolerance_u: -1.0,
                ..Form::default()
            },
            Form {
                max_iterations: 0,
                ..Form::default()
            },
            Form {
                start: Some([("x1".to_string(), 0.0)].into_iter().collect()),
                ..Form::default()
            },
        ] {
            assert!(bad.validate(&problem).is_err(), "{bad:?}");
        }
        let discrete = RandomInputs::independent(vec![RandomParameter::new(
            "n",
            Distribution::integer_uniform(1, 4).unwrap(),
        )]);
        let e = Form::default()
            .validate(&Problem::of_inputs(&discrete))
            .unwrap_err();
        assert!(e.0.contains("discrete"), "{e}");
        // TOML: defaults, and no unknown key.
        let f: Form = toml::from_str("step = 0.01\ncentral = true").unwrap();
        assert!(f.central && f.step == 0.01 && f.max_iterations == 100);
        assert!(toml::from_str::<Form>("steps = 0.01").is_err());
    }
}
