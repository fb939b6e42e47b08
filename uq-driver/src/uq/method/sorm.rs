//! `kind = "sorm"`: the second-order reliability method, FORM's design point with the
//! curvatures of the limit-state surface there.
//!
//! After FORM (its settings in `[method.form]`), the Hessian of `g` at `u*` in the `d − 1`
//! directions orthogonal to `α` is taken by finite differences (central: `2(d − 1)²` runs
//! in one parallel batch; forward: `(d − 1)(d + 2)/2`), and its eigenvalues divided by
//! `|∇g|` are the principal curvatures `κ_i`. Reported (`crate::uq::reliability::sorm`):
//! Breitung's `P ≈ Φ(−β) Π (1 + β κ_i)^(−1/2)` (1984), Hohenbichler & Rackwitz's (1988),
//! Tvedt's three-term formula (1990) and the exact probability of the paraboloid with these
//! curvatures (by Tvedt's integral), the last being `P`. It is exact for a quadratic `g` with
//! one design point, and has no error estimate otherwise.

use serde::{Deserialize, Serialize};

use super::adaptive::{per_target_items, AnalyseTarget, PerTarget, Target};
use super::error::{InvalidSettings, MethodError};
use super::form::Form;
use super::traits::{adaptive_method_items, Adaptive, Method, Problem};
use crate::uq::random_inputs::RandomInputs;
use crate::uq::reliability::{self, LimitState, Scheme};

/// `kind = "sorm"`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Sorm {
    /// The FORM search that finds the design point (`[method.form]`, the keys of
    /// `kind = "form"` but `quantities`).
    pub form: Form,
    /// Step of the Hessian's finite differences (standard normal units).
    pub hessian_step: f64,
    /// Central differences for the Hessian (`2(d − 1)²` runs) instead of forward
    /// (`(d − 1)(d + 2)/2`).
    pub hessian_central: bool,
    /// The quantities analysed (default: every quantity with limits).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub quantities: Vec<String>,
}

impl Default for Sorm {
    fn default() -> Self {
        let n = reliability::Sorm::default();
        Sorm {
            form: Form::default(),
            hessian_step: n.step,
            hessian_central: n.scheme == Scheme::Central,
            quantities: Vec::new(),
        }
    }
}

impl Sorm {
    fn hessian_runs(&self, d: usize) -> usize {
        let n = d.saturating_sub(1);
        if self.hessian_central {
            2 * n * n
        } else {
            n * (n + 3) / 2
        }
    }
}

/// Refuses `quantities` inside the FORM settings of another method.
pub(crate) fn check_nested_form(form: &Form, kind: &str) -> Result<(), InvalidSettings> {
    if form.quantities.is_empty() {
        Ok(())
    } else {
        Err(InvalidSettings(format!(
            "`quantities` belongs to [method] of {kind}, not to [method.form]"
        )))
    }
}

impl Method for Sorm {
    fn kind(&self) -> &'static str {
        "sorm"
    }

    fn label(&self, _dim: usize) -> String {
        "sorm".into()
    }

    fn validate(&self, problem: &Problem) -> Result<(), InvalidSettings> {
        check_nested_form(&self.form, "sorm")?;
        self.form.check(problem, "SORM")?;
        if !(self.hessian_step.is_finite() && self.hessian_step > 0.0) {
            return Err(InvalidSettings(format!(
                "`hessian_step` must be positive (got {})",
                self.hessian_step
            )));
        }
        Ok(())
    }

    adaptive_method_items!("a SORM study");
}

impl Adaptive for Sorm {
    fn max_runs(&self, dim: usize, targets: usize) -> usize {
        targets * (self.form.max_runs_per_target(dim) + self.hessian_runs(dim))
    }

    fn expected_runs(&self, dim: usize, targets: usize) -> f64 {
        targets as f64 * (self.form.expected_runs_per_target(dim) + self.hessian_runs(dim) as f64)
    }

    per_target_items!();
}

impl PerTarget for Sorm {
    fn analyser(
        &self,
        inputs: &RandomInputs,
        seed: u64,
    ) -> Result<impl AnalyseTarget, MethodError> {
        let settings = reliability::Sorm {
            step: self.hessian_step,
            scheme: if self.hessian_central {
                Scheme::Central
            } else {
                Scheme::Forward
            },
        };
        Ok(move |g: &mut dyn LimitState, t: &Target, first| {
            let mut out = self.form.analyse(g, t, first, inputs, seed)?;
            let mut f = out.form_analysis()?.clone();
            // The Hessian's runs follow every run of the FORM analysis.
            f.next_run = out.next_run();
            let s = reliability::sorm(g, &f, &settings)?;
            out.method = "sorm";
            out.probability = s.probability;
            out.runs += s.runs;
            out.warnings.extend(s.warnings.iter().cloned());
            out.sorm = Some(s);
            Ok(out)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::super::adaptive::tests::{above, standard_inputs, Analytic};
    use super::*;
    use crate::uq::special::norm_sf;

    #[test]
    fn a_paraboloid_limit_state_gives_its_exact_probability() {
        // q = x1 + k (x2^2 + x3^2) / 2, P(q > b): the failure domain is bounded by the
        // paraboloid x1 = b - k r^2 / 2 with curvature k at its apex (design point (b, 0, 0)
        // for small k). Exact: P = E[Phi(-(b - k chi2_2 / 2))] = int_0^inf e^{-t/2}/2
        // Phi(-(b - k t / 2)) dt, computed here by Simpson's rule.
        let (b, k) = (3.0, 0.1);
        let f = |t: f64| 0.5 * (-t / 2.0).exp() * norm_sf(b - k * t / 2.0);
        let (n, top) = (100_000, 60.0);
        let h = top / n as f64;
        let mut s = f(0.0) + f(top);
        for i in 1..n {
            s += if i % 2 == 1 { 4.0 } else { 2.0 } * f(i as f64 * h);
        }
        let exact = s * h / 3.0;
        let inputs = standard_inputs(3);
        let t = above("q", b);
        let mut model = Analytic::new(&inputs, |x: &[f64]| {
            vec![Ok(x[0] + k * (x[1] * x[1] + x[2] * x[2]) / 2.0)]
        });
        let r = Sorm::default()
            .run(&mut model, &inputs, &t, &["q".into()], 1)
            .unwrap();
        let l = &r.limits[0];
        let err = (l.probability - exact).abs() / exact;
        assert!(err < 0.01, "SORM {} vs {exact} ({err:.3})", l.probability);
        // FORM alone is off by the curvature (about 30 % here).
        let form = l.form.as_ref().unwrap().probability;
        assert!((form - exact).abs() / exact > 0.2, "{form} vs {exact}");
        assert_eq!(l.method, "sorm");
        assert_eq!(r.runs, model.runs);
    }
}
