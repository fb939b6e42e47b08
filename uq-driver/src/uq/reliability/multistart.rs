//! FORM from several starting points: distinct design points are found and flagged.
//!
//! A limit-state surface may have several local design points (series systems, a symmetric
//! response such as `|q| > limit`) or none that dominates (`g = c - |u|^2`: every point of
//! the sphere is one). FORM from one start sees one; from several starts (the origin,
//! `+-r e_i` along every axis, random points at radius `r`, given points) the converged
//! points are grouped (two are the same when `|u_a - u_b| <= distinct max(|u_a|, |u_b|, 1)`),
//! sorted by `beta`, and the result flags `several` when two or more have probabilities
//! `Phi(-beta_j)` within the factor `relevant` of the largest: then FORM's `Phi(-beta)`
//! misses part of the failure domain. `sum_j Phi(-beta_j)` over the distinct points is the
//! first-order union bound (Boole) of the series system they span.
//!
//! The starts run one after the other (each with its own batches of `d + 1` runs); random
//! starts draw from the stream of their index (`3 << 56 | k`).

use serde::{Deserialize, Serialize};

use super::error::ReliabilityError;
use super::form::{search, Form, FormResult};
use super::model::{LimitState, Runs};
use super::{norm, normals, stream, Purpose};

/// Multi-start settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MultiStart {
    /// The settings of each search (`start` is ignored).
    pub form: Form,
    /// Start at the origin.
    pub origin: bool,
    /// Start at `+-r e_i` for every axis `i` (`2d` starts), with this `r`.
    pub axes: Option<f64>,
    /// Random starts, uniform in direction at radius `random_radius`.
    pub random: usize,
    /// Radius of the random starts.
    pub random_radius: f64,
    /// Further starts.
    pub points: Vec<Vec<f64>>,
    /// Relative distance beyond which two design points are distinct.
    pub distinct: f64,
    /// Ratio of probabilities `Phi(-beta_j) / Phi(-beta_min)` above which a further design
    /// point counts.
    pub relevant: f64,
}

impl Default for MultiStart {
    fn default() -> Self {
        MultiStart {
            form: Form::default(),
            origin: true,
            axes: Some(1.0),
            random: 0,
            random_radius: 1.0,
            points: Vec::new(),
            distinct: 0.05,
            relevant: 0.01,
        }
    }
}

/// A distinct design point and the starts that led to it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DesignPoint {
    /// FORM at this point (from the first start that found it).
    pub form: FormResult,
    /// Indices of the starts (in [`MultiStartResult::starts`]) that converged to it.
    pub starts: Vec<usize>,
}

/// What happened from one start.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Start {
    /// The starting point.
    pub u: Vec<f64>,
    /// `beta` where the search ended, or why it stopped (zero gradient).
    pub beta: Result<f64, String>,
    /// Whether the search converged.
    pub converged: bool,
    /// Runs of this search.
    pub runs: u64,
}

/// The design points of a multi-start FORM.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MultiStartResult {
    /// Distinct converged design points, by increasing `beta`.
    pub design_points: Vec<DesignPoint>,
    /// Every start, in order: origin, `+r e_1, -r e_1, +r e_2, ...`, random, given.
    pub starts: Vec<Start>,
    /// Whether two or more design points have comparable probabilities.
    pub several: bool,
    /// `sum_j Phi(-beta_j)` over the distinct design points.
    pub union_bound: f64,
    /// Model runs in all.
    pub runs: u64,
    /// The run index after the last run.
    pub next_run: u64,
    /// For the user.
    pub warnings: Vec<String>,
}

impl MultiStartResult {
    /// The design point with the smallest `beta`, if any search converged.
    pub fn best(&self) -> Option<&FormResult> {
        self.design_points.first().map(|p| &p.form)
    }

    /// The design points whose `Phi(-beta_j)` is at least `relevant` times the largest, by
    /// increasing `beta` (those `several` counts with the same `relevant`).
    pub(crate) fn comparable(&self, relevant: f64) -> Vec<&FormResult> {
        comparable(&self.design_points, relevant).collect()
    }
}

/// The points of `found` (by increasing `beta`) whose probability is at least `relevant`
/// times the first's.
fn comparable(found: &[DesignPoint], relevant: f64) -> impl Iterator<Item = &FormResult> {
    let p_max = found.first().map_or(f64::INFINITY, |p| p.form.probability);
    found
        .iter()
        .map(|p| &p.form)
        .filter(move |f| f.probability >= relevant * p_max)
}

/// FORM from every start of `settings`, from run index `first_run`; `seed` for the random
/// starts. A start with a zero gradient (e.g. the origin of `c - |u|^2`) is recorded and
/// skipped; a failed run or an abort stops everything.
pub fn form_multistart(
    model: &mut dyn LimitState,
    settings: &MultiStart,
    seed: u64,
    first_run: u64,
) -> Result<MultiStartResult, ReliabilityError> {
    let mut runs = Runs::starting_at(model, first_run)?;
    let d = runs.dim();
    let mut form = settings.form.clone();
    form.start = None;
    form.validate(d)?;
    let valid = |v: f64| v.is_finite() && v > 0.0;
    if !valid(settings.distinct) || !valid(settings.relevant) || settings.relevant > 1.0 {
        return Err(ReliabilityError::Invalid(format!(
            "multi-start: `distinct` must be positive and `relevant` in (0, 1] (got {}, {})",
            settings.distinct, settings.relevant
        )));
    }
    let starts = starting_points(settings, d, seed)?;
    let mut found: Vec<DesignPoint> = Vec::new();
    let mut record = Vec::new();
    let mut warnings = Vec::new();
    for (k, start) in starts.into_iter().enumerate() {
        let before = runs.count();
        let outcome = search(&mut runs, start.clone(), &form);
        let used = runs.count() - before;
        let r = match outcome {
            Ok(r) => r,
            Err(ReliabilityError::ZeroGradient { u, norm }) => {
                record.push(Start {
                    u: start,
                    beta: Err(format!("zero gradient (|grad g| = {norm}) at u = {u:?}")),
                    converged: false,
                    runs: used,
                });
                continue;
            }
            Err(e) => return Err(e),
        };
        record.push(Start {
            u: start,
            beta: Ok(r.beta),
            converged: r.converged,
            runs: used,
        });
        if !r.converged {
            continue;
        }
        let same = found.iter_mut().find(|p| {
            let (a, b) = (&p.form.u_star, &r.u_star);
            let gap: f64 = a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>();
            gap.sqrt() <= settings.distinct * norm(a).max(norm(b)).max(1.0)
        });
        match same {
            Some(p) => p.starts.push(k),
            None => found.push(DesignPoint {
                form: r,
                starts: vec![k],
            }),
        }
    }
    found.sort_by(|a, b| a.form.beta.total_cmp(&b.form.beta));
    let unconverged = record
        .iter()
        .filter(|s| !s.converged && s.beta.is_ok())
        .count();
    let zero = record.iter().filter(|s| s.beta.is_err()).count();
    if unconverged + zero > 0 {
        warnings.push(format!(
            "{unconverged} start(s) did not converge and {zero} met a zero gradient, of {}",
            record.len()
        ));
    }
    let union_bound = found.iter().map(|p| p.form.probability).sum();
    let mut several = false;
    if let Some(best) = found.first() {
        let p_max = best.form.probability;
        let comparable: Vec<f64> = comparable(&found, settings.relevant)
            .map(|p| p.beta)
            .collect();
        if comparable.len() > 1 {
            several = true;
            warnings.push(format!(
                "{} distinct design points with comparable probabilities (beta = {}): \
                 Phi(-beta_min) = {p_max:.4e} misses part of the failure domain (their union \
                 bound is {union_bound:.4e}); importance sampling after a multi-start FORM \
                 samples around all of them, subset simulation needs no design point",
                comparable.len(),
                comparable
                    .iter()
                    .map(|b| format!("{b:.4}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            ));
        }
    } else {
        warnings.push("no start converged to a design point".into());
    }
    Ok(MultiStartResult {
        design_points: found,
        starts: record,
        several,
        union_bound,
        runs: runs.count() - first_run,
        next_run: runs.count(),
        warnings,
    })
}

/// The starts in order: origin, axes, random, given.
fn starting_points(s: &MultiStart, d: usize, seed: u64) -> Result<Vec<Vec<f64>>, ReliabilityError> {
    let mut out = Vec::new();
    if s.origin {
        out.push(vec![0.0; d]);
    }
    if let Some(r) = s.axes {
        if !(r.is_finite() && r > 0.0) {
            return Err(ReliabilityError::Invalid(format!(
                "multi-start: the axes radius must be positive (got {r})"
            )));
        }
        for i in 0..d {
            for sign in [1.0, -1.0] {
                let mut u = vec![0.0; d];
                u[i] = sign * r;
                out.push(u);
            }
        }
    }
    if s.random > 0 && !(s.random_radius.is_finite() && s.random_radius > 0.0) {
        return Err(ReliabilityError::Invalid(format!(
            "multi-start: the random radius must be positive (got {})",
            s.random_radius
        )));
    }
    for k in 0..s.random {
        let z = normals(&mut stream(seed, Purpose::Start, k as u64), d);
        let n = norm(&z);
        out.push(z.iter().map(|v| v * s.random_radius / n).collect());
    }
    for p in &s.points {
        if p.len() != d || p.iter().any(|v| !v.is_finite()) {
            return Err(ReliabilityError::Invalid(format!(
                "multi-start: a start must have {d} finite coordinates (got {p:?})"
            )));
        }
        out.push(p.clone());
    }
    if out.is_empty() {
        return Err(ReliabilityError::Invalid(
            "multi-start: no starting point".into(),
        ));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::super::fixtures::*;
    use super::super::model::FnLimitState;
    use super::*;
    use crate::uq::special::norm_sf as p_of;

    #[test]
    fn sum_of_squares_has_a_design_point_on_every_axis_and_is_flagged() {
        // g = c - sum u_i^2: every point of the sphere |u| = sqrt(c) is a design point.
        let d = 8;
        let c = chi_square_limit(d, 1e-4);
        let mut m = FnLimitState::new(d, move |u: &[f64]| Ok(sum_of_squares(c, u)));
        let r = form_multistart(&mut m, &MultiStart::default(), 1, 0).unwrap();
        assert!(r.several, "{:?}", r.warnings);
        // One per axis start, and the origin's: its forward-difference gradient (-h, ..., -h)
        // leads along the diagonal.
        assert_eq!(r.design_points.len(), 2 * d + 1);
        for p in &r.design_points {
            assert!((p.form.beta - c.sqrt()).abs() < 1e-6);
        }
        // FORM's single point is far below the chi-square tail.
        let exact = chi_square_sf(d, c);
        assert!(r.best().unwrap().probability < 0.05 * exact);
        assert!(r
            .warnings
            .iter()
            .any(|w| w.contains("distinct design points")));
    }

    #[test]
    fn a_start_with_a_zero_gradient_is_recorded_and_skipped() {
        let mut m = FnLimitState::new(3, |u: &[f64]| Ok(sum_of_squares(9.0, u)));
        let mut settings = MultiStart::default();
        settings.form.differences.scheme = super::super::gradient::Scheme::Central;
        let r = form_multistart(&mut m, &settings, 1, 0).unwrap();
        assert!(r.starts[0]
            .beta
            .as_ref()
            .unwrap_err()
            .contains("zero gradient"));
        assert_eq!(r.design_points.len(), 6);
        assert!(r
            .warnings
            .iter()
            .any(|w| w.contains("1 met a zero gradient")));
    }

    #[test]
    fn a_linear_limit_state_has_one_design_point() {
        let lin = Linear::new(4, 1e-4);
        let mut m = lin.model();
        let settings = MultiStart {
            random: 3,
            ..MultiStart::default()
        };
        let r = form_multistart(&mut m, &settings, 5, 0).unwrap();
        assert!(!r.several);
        assert_eq!(r.design_points.len(), 1);
        assert_eq!(r.design_points[0].starts.len(), 1 + 8 + 3);
        assert!((r.best().unwrap().probability - 1e-4).abs() < 1e-6);
        assert_eq!(r.runs, r.starts.iter().map(|s| s.runs).sum::<u64>());
    }

    #[test]
    fn two_symmetric_design_points_are_both_found() {
        // |u_1| > 3: two design points at +-3 e_1, P = 2 Phi(-3).
        let mut m = FnLimitState::new(3, |u: &[f64]| Ok(3.0 - (u[0] * u[0] + 1e-12).sqrt()));
        let settings = MultiStart {
            origin: false,
            ..MultiStart::default()
        };
        let r = form_multistart(&mut m, &settings, 0, 0).unwrap();
        assert!(r.several);
        assert!((r.union_bound - 2.0 * p_of(3.0)).abs() < 1e-6 * p_of(3.0));
    }
}
