//! The chaos as a guide to its own tail. A probability counted over draws of a chaos beyond
//! (or nearly beyond) the model runs rests on the chaos's extrapolation and is given no
//! interval; the model has to be run where the failures are. FORM on the chaos itself (no
//! model run: each evaluation is the polynomial) finds where that is, its design point, and
//! the analysis says it: `chaos_design_point` beside the probability in `summary.json`
//! (`beta`, `p_form` = Φ(−β), `design_point` in physical units by parameter, `iterations`),
//! and a warning naming the `centre` of an `importance_sampling` study that samples the
//! model there (importance sampling is unbiased whatever its centre; a centre near the
//! true design point makes it efficient).

use serde_json::json;

use super::Analysed;
use crate::text::csv::shortest;
use crate::uq::distributions::Germ;
use crate::uq::pce::Pce;
use crate::uq::random_inputs::RandomInputs;
use crate::uq::reliability::{
    form, Abort, Form, FormResult, Outcome, PhysicalLimitState, Side, Threshold,
};

/// FORM's design point of `pce` (its first column) for `threshold`, when the search
/// converges to a point with a finite β.
fn design_point(
    pce: &Pce,
    inputs: &RandomInputs,
    germ: Germ,
    threshold: Threshold,
) -> Option<FormResult> {
    // `u → x` (each input's `F⁻¹(Φ(·))`, through the Gaussian copula), `x → ξ` (the chaos's
    // germ), `q = chaos(ξ)`.
    let chaos = |batch: &[(u64, Vec<f64>)]| -> Result<Vec<Outcome>, Abort> {
        Ok(batch
            .iter()
            .map(|(_, x)| {
                let q = pce.eval_column(0, &inputs.to_germ(germ, x));
                if q.is_finite() {
                    Ok(q)
                } else {
                    Err(format!("the chaos is not finite at {x:?}"))
                }
            })
            .collect())
    };
    let mut g = PhysicalLimitState::new(inputs, threshold, chaos);
    let r = form(&mut g, &Form::default(), 0).ok()?;
    (r.converged && r.beta.is_finite() && r.x_star.is_some()).then_some(r)
}

/// `v` to 6 significant digits, as short as it prints.
fn six_digits(v: f64) -> String {
    shortest(format!("{v:.5e}").parse().unwrap_or(v))
}

/// Adds the chaos's design point to every probability of `analysed` counted over the
/// chaos's extrapolated tail (see the module documentation). `inputs` and `germ` are the
/// design's, which the quantities' chaoses expand.
pub(crate) fn guide_tails(analysed: &mut Analysed, inputs: &RandomInputs, germ: Germ) {
    for q in &mut analysed.quantities {
        let Some(chaos) = analysed.quantity_chaos.iter().find(|c| c.name == q.name) else {
            continue;
        };
        for p in q.reliability.iter_mut().flatten() {
            if !p.tail_extrapolated {
                continue;
            }
            let side = if p.direction == "below" {
                Side::Below
            } else {
                Side::Above
            };
            let threshold = Threshold {
                limit: p.limit,
                side,
            };
            let Some(r) = design_point(&chaos.pce, inputs, germ, threshold) else {
                continue;
            };
            let x = r.x_star.as_deref().unwrap_or_default();
            let point: serde_json::Map<String, serde_json::Value> = inputs
                .iter()
                .zip(x)
                .map(|(par, v)| (par.name.clone(), json!(v)))
                .collect();
            let centre: Vec<String> = inputs
                .iter()
                .zip(x)
                .map(|(par, v)| format!("{} = {}", toml_key(&par.name), six_digits(*v)))
                .collect();
            let centre = format!("{{ {} }}", centre.join(", "));
            p.warnings.push(format!(
                "the chaos's own design point for {} (FORM on the chaos, no model run: β = {:.3}, \
                 Φ(−β) = {:.3e}) is a place to run the model: `[method] kind = \
                 \"importance_sampling\"` with `centre = {centre}` samples it there",
                p.label(&q.name),
                r.beta,
                r.probability,
            ));
            let count = q
                .exceedance_counts
                .iter_mut()
                .find(|e| e.limit == p.limit && e.direction == p.direction);
            if let Some(e) = count {
                e.chaos_centre = Some(centre);
            }
            p.details.insert(
                "chaos_design_point".into(),
                json!({
                    "beta": r.beta,
                    "p_form": r.probability,
                    "design_point": point,
                    "iterations": r.iterations,
                }),
            );
        }
    }
}

/// A TOML key for a parameter name: bare when it can be, else quoted.
fn toml_key(name: &str) -> String {
    let bare = !name.is_empty()
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
    if bare {
        name.to_owned()
    } else {
        format!("{name:?}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::uq::distributions::{Distribution, RandomParameter};
    use crate::uq::pce::{Basis, MultiIndexSet};
    use crate::uq::special::norm_sf;
    use nalgebra::DMatrix;

    fn normal(name: &str, mean: f64, std: f64) -> RandomParameter {
        RandomParameter {
            name: name.into(),
            distribution: Distribution::Normal { mean, std },
        }
    }

    #[test]
    fn the_design_point_of_a_linear_chaos_is_the_closed_form_one() {
        // q = 10 + 2 ξ1 + 1 ξ2 (Hermite degree 1 on normal inputs K ~ N(100, 5²), C ~ N(20, 1)):
        // q > 10 + 3·√5 fails, β = 3 exactly, u* = 3 (2, 1)/√5, x* = mean + std u*.
        let inputs = RandomInputs {
            parameters: vec![normal("K", 100.0, 5.0), normal("C", 20.0, 1.0)],
            correlation: None,
        };
        let families = vec![crate::uq::pce::Family::Hermite; 2];
        let set = MultiIndexSet::from_indices(2, vec![vec![0, 0], vec![1, 0], vec![0, 1]]).unwrap();
        let pce = Pce::new(
            Basis::new(families, set).unwrap(),
            DMatrix::from_column_slice(3, 1, &[10.0, 2.0, 1.0]),
        )
        .unwrap();
        let limit = 10.0 + 3.0 * 5f64.sqrt();
        let threshold = Threshold {
            limit,
            side: Side::Above,
        };
        let r = design_point(&pce, &inputs, Germ::Normal, threshold).expect("converges");
        assert!((r.beta - 3.0).abs() < 1e-6, "β = {}", r.beta);
        assert!((r.probability - norm_sf(3.0)).abs() < 1e-9);
        let x = r.x_star.unwrap();
        let s5 = 5f64.sqrt();
        assert!(
            (x[0] - (100.0 + 5.0 * 3.0 * 2.0 / s5)).abs() < 1e-3,
            "{x:?}"
        );
        assert!((x[1] - (20.0 + 3.0 / s5)).abs() < 1e-4, "{x:?}");
    }

    #[test]
    fn a_parameter_name_that_is_not_a_bare_key_is_quoted() {
        assert_eq!(toml_key("K_sy"), "K_sy");
        assert_eq!(toml_key("wheel.k"), "\"wheel.k\"");
        assert_eq!(six_digits(130234.567), "130235");
    }
}
