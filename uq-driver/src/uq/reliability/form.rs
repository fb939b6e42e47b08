//! FORM: the design point by the improved Hasofer–Lind–Rackwitz–Fiessler iteration
//! (iHLRF, Zhang & Der Kiureghian 1997) and `P = Phi(-beta)`.
//!
//! The design point `u*` is the point of the limit-state surface `g(u) = 0` nearest to the
//! origin of standard normal space. At `u_k` with `g_k = g(u_k)` and gradient `grad_k`, the
//! HLRF direction is the step to the nearest point of the linearised surface,
//!
//! `d_k = ((grad_k . u_k - g_k) / |grad_k|^2) grad_k - u_k`,
//!
//! and iHLRF takes `u_{k+1} = u_k + t_k d_k` with the step `t_k = b^j` (`b = 1/2`, the first
//! `j = 0, 1, ...`) that satisfies Armijo's rule on the merit function
//!
//! `m(u) = |u|^2 / 2 + c_k |g(u)|`:  `m(u_k + t d_k) <= m(u_k) + a t m'(u_k; d_k)`,  `a = 1/2`,
//!
//! with `m'(u_k; d_k) = u_k . d_k - c_k |g_k|` (since `grad_k . d_k = -g_k`). The direction is
//! one of descent of `m` when `c_k > |u_k| / |grad_k|` (Zhang & Der Kiureghian 1997); here
//! `c_k = 2 max(|u_k|, |u_k + d_k|) / |grad_k|`, which also holds at the origin.
//!
//! Convergence: the linearised distance to the surface `|g| / |grad g|` below `tolerance_g`
//! and the part of `u` off the gradient's line `|u - (alpha . u) alpha|` below
//! `tolerance_u` (`alpha = -grad g / |grad g|`).
//!
//! Runs: the gradient is by finite differences ([`Differences`]); the first trial point of
//! each iteration is evaluated together with its difference points in one batch (`d + 1`
//! runs, `2d + 1` central), so the gradient is there when the full step is accepted, as it
//! is near the solution. A shortened step costs one run per trial, then one batch for the
//! gradient.
//!
//! Reported: `beta = alpha . u* + g(u*) / |grad g(u*)|`, the signed distance of the
//! linearised surface at the last point from the origin (negative when the origin fails;
//! exact for a linear `g` even before convergence), `P = Phi(-beta)`, `alpha` and the
//! importance factors `alpha_i^2` (sum 1) of the independent coordinates (with correlated
//! inputs, coordinate `i` is input `i`'s score after the Cholesky decorrelation of the
//! inputs before it).

use serde::{Deserialize, Serialize};

use super::error::ReliabilityError;
use super::gradient::Differences;
use super::model::{LimitState, OnFailure, Runs};
use super::{dot, norm};
use crate::uq::special::norm_sf;

/// Armijo's sufficient-decrease constant `a`.
const ARMIJO: f64 = 0.5;
/// Step reduction `b` of the line search.
const BACKTRACK: f64 = 0.5;
/// Trials of the line search before the smallest step is taken anyway.
const MAX_TRIALS: usize = 12;
/// Factor `gamma` of the merit-function weight `c = gamma max(|u|, |u + d|) / |grad g|`.
const MERIT_GAMMA: f64 = 2.0;
/// Beyond this distance `Phi(-|u|)` is below the smallest normal double: the search stops.
pub(crate) const MAX_RADIUS: f64 = 37.5;

/// FORM settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Form {
    /// Starting point in standard normal space (`None`: the origin, the median of every
    /// input).
    pub start: Option<Vec<f64>>,
    /// Finite differences of the gradient.
    pub differences: Differences,
    /// Iterations (gradients) at most.
    pub max_iterations: usize,
    /// Convergence: linearised distance to the surface `|g| / |grad g|` (standard normal
    /// units).
    pub tolerance_g: f64,
    /// Convergence: distance of `u` from the gradient's line through the origin. `beta`'s
    /// error is of second order in it (`~ tolerance_u^2 / (2 beta)` for a flat surface), and
    /// a forward-difference gradient of step `h` turns the line by about `h |H| / |grad g|`
    /// (`H` the Hessian): `1e-2` is met where a tighter value would stall.
    pub tolerance_u: f64,
}

impl Default for Form {
    fn default() -> Self {
        Form {
            start: None,
            differences: Differences::default(),
            max_iterations: 100,
            tolerance_g: 1e-4,
            tolerance_u: 1e-2,
        }
    }
}

impl Form {
    pub(crate) fn validate(&self, d: usize) -> Result<(), ReliabilityError> {
        self.differences.validate()?;
        if let Some(s) = &self.start {
            if s.len() != d || s.iter().any(|v| !v.is_finite()) {
                return Err(ReliabilityError::Invalid(format!(
                    "the FORM start must have {d} finite coordinates (got {s:?})"
                )));
            }
        }
        let positive = |v: f64| v.is_finite() && v > 0.0;
        if !positive(self.tolerance_g) || !positive(self.tolerance_u) {
            return Err(ReliabilityError::Invalid(format!(
                "FORM tolerances must be positive (got tolerance_g = {}, tolerance_u = {})",
                self.tolerance_g, self.tolerance_u
            )));
        }
        Ok(())
    }
}

/// One iteration of the search, at the point it started from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FormIteration {
    /// Signed distance of the linearised surface (`alpha . u + g / |grad g|`).
    pub beta: f64,
    /// `|u|`.
    pub distance: f64,
    /// `g(u)`.
    pub g: f64,
    /// `|grad g(u)|`.
    pub gradient_norm: f64,
    /// The line-search step `t` that led to this point (0 for the start).
    pub step: f64,
    /// Model runs so far.
    pub runs: u64,
}

/// What FORM found.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FormResult {
    /// Reliability index, signed (negative when the origin fails).
    pub beta: f64,
    /// `Phi(-beta)`.
    pub probability: f64,
    /// The design point (the last point when not converged).
    pub u_star: Vec<f64>,
    /// The physical inputs at the design point, when the model knows them.
    pub x_star: Option<Vec<f64>>,
    /// Unit vector `-grad g / |grad g|` at `u_star`.
    pub alpha: Vec<f64>,
    /// Importance factors `alpha_i^2` (sum 1).
    pub importance: Vec<f64>,
    /// `g(u_star)`.
    pub g: f64,
    /// The finite-difference gradient at `u_star`.
    pub gradient: Vec<f64>,
    /// Whether both tolerances were met.
    pub converged: bool,
    /// Iterations (search directions taken).
    pub iterations: usize,
    /// Model runs of this search.
    pub runs: u64,
    /// The run index after the last run of this search (where a following method on the
    /// same model starts numbering).
    pub next_run: u64,
    /// Per iteration.
    pub history: Vec<FormIteration>,
    /// For the user (non-convergence, no failing run seen, ...).
    pub warnings: Vec<String>,
}

/// FORM on `model` from run index `first_run` (0 for a fresh study).
///
/// Errors: invalid settings; a failed run ([`ReliabilityError::RunFailed`], naming the
/// point); a zero gradient ([`ReliabilityError::ZeroGradient`]); an aborted evaluation.
/// Non-convergence is not an error: the result says `converged: false` and warns.
pub fn form(
    model: &mut dyn LimitState,
    settings: &Form,
    first_run: u64,
) -> Result<FormResult, ReliabilityError> {
    let mut runs = Runs::starting_at(model, first_run)?;
    settings.validate(runs.dim())?;
    let start = settings
        .start
        .clone()
        .unwrap_or_else(|| vec![0.0; runs.dim()]);
    search(&mut runs, start, settings)
}

/// `g` and its gradient at `u`, in one batch.
fn value_and_gradient(
    runs: &mut Runs,
    fd: &Differences,
    u: &[f64],
) -> Result<(f64, Vec<f64>), ReliabilityError> {
    try_value_and_gradient(runs, fd, u)?
}

/// `g` and its gradient at `u`, or the first failed run of their batch (a run the model
/// could not make there: the line search then shortens its step).
fn try_value_and_gradient(
    runs: &mut Runs,
    fd: &Differences,
    u: &[f64],
) -> Result<Result<(f64, Vec<f64>), ReliabilityError>, ReliabilityError> {
    let mut pts = vec![u.to_vec()];
    pts.extend(fd.points(u));
    let g = match runs
        .eval_each(pts.clone())?
        .into_iter()
        .collect::<Result<Vec<_>, _>>()
    {
        Ok(g) => g,
        Err(failed) => return Ok(Err(failed)),
    };
    Ok(Ok((g[0], fd.gradient(u, g[0], &pts[1..], &g[1..]))))
}

/// The gradient at `u` where `g(u) = g0` is known.
fn gradient_at(
    runs: &mut Runs,
    fd: &Differences,
    u: &[f64],
    g0: f64,
) -> Result<Vec<f64>, ReliabilityError> {
    let pts = fd.points(u);
    let g = runs.eval(pts.clone(), OnFailure::Error)?;
    Ok(fd.gradient(u, g0, &pts, &g))
}

fn axpy(u: &[f64], t: f64, d: &[f64]) -> Vec<f64> {
    u.iter().zip(d).map(|(a, b)| a + t * b).collect()
}

/// The iHLRF search from `start` (settings validated).
pub(crate) fn search(
    runs: &mut Runs,
    start: Vec<f64>,
    settings: &Form,
) -> Result<FormResult, ReliabilityError> {
    let fd = &settings.differences;
    let first = runs.count();
    let mut warnings = Vec::new();
    let mut u = start;
    let (mut g, mut grad) = value_and_gradient(runs, fd, &u)?;
    let mut min_g = g;
    let mut step = 0.0;
    let mut history = Vec::new();
    let mut converged = false;
    let mut short_steps = 0usize;
    let mut failed_trials = 0usize;
    let mut iterations = 0;
    loop {
        let gn = norm(&grad);
        if !(gn > 0.0 && gn.is_finite()) {
            return Err(ReliabilityError::ZeroGradient { u, norm: gn });
        }
        let alpha: Vec<f64> = grad.iter().map(|v| -v / gn).collect();
        let along = dot(&alpha, &u);
        history.push(FormIteration {
            beta: along + g / gn,
            distance: norm(&u),
            g,
            gradient_norm: gn,
            step,
            runs: runs.count() - first,
        });
        let off_line = norm(&axpy(&u, -along, &alpha));
        if g.abs() / gn <= settings.tolerance_g && off_line <= settings.tolerance_u {
            converged = true;
            break;
        }
        if iterations == settings.max_iterations {
            warnings.push(format!(
                "FORM did not converge in {} iterations: |g|/|grad g| = {:.3e} (tolerance {:e}), \
                 |u - (alpha.u) alpha| = {:.3e} (tolerance {:e}); beta and P are those of the \
                 last point",
                iterations,
                g.abs() / gn,
                settings.tolerance_g,
                off_line,
                settings.tolerance_u
            ));
            break;
        }
        if norm(&u) > MAX_RADIUS {
            warnings.push(format!(
                "FORM stopped at |u| = {:.1} (beyond {MAX_RADIUS}, where Phi(-|u|) is below the \
                 smallest normal double) without finding the limit-state surface: the limit may \
                 never be reached (P about 0)",
                norm(&u)
            ));
            break;
        }
        iterations += 1;
        // HLRF direction and the merit function of this iteration.
        let s = (dot(&grad, &u) - g) / (gn * gn);
        let d: Vec<f64> = grad.iter().zip(&u).map(|(gi, ui)| s * gi - ui).collect();
        let c = MERIT_GAMMA * norm(&u).max(norm(&axpy(&u, 1.0, &d))) / gn;
        let merit = |v: &[f64], gv: f64| 0.5 * dot(v, v) + c * gv.abs();
        let m0 = merit(&u, g);
        let slope = dot(&u, &d) - c * g.abs();
        let armijo = |t: f64, v: &[f64], gv: f64| merit(v, gv) <= m0 + ARMIJO * t * slope;
        // Full step, with its gradient in the same batch. A run the model cannot make (a
        // stiffness below zero far from the median, a solver that breaks down) is taken as a
        // step too long: the line search shortens it, as it does for too little decrease.
        let trial = axpy(&u, 1.0, &d);
        let mut failure = None;
        match try_value_and_gradient(runs, fd, &trial)? {
            Ok((g1, grad1)) => {
                min_g = min_g.min(g1);
                if armijo(1.0, &trial, g1) {
                    (u, g, grad, step) = (trial, g1, grad1, 1.0);
                    continue;
                }
            }
            Err(failed) => {
                failed_trials += 1;
                failure = Some(failed);
            }
        }
        let mut t = 1.0;
        let mut accepted = None;
        for _ in 1..MAX_TRIALS {
            t *= BACKTRACK;
            let v = axpy(&u, t, &d);
            let gv = match runs.eval_each(vec![v.clone()])?.remove(0) {
                Ok(gv) => gv,
                Err(failed) => {
                    failed_trials += 1;
                    failure = Some(failed);
                    continue;
                }
            };
            min_g = min_g.min(gv);
            let ok = armijo(t, &v, gv);
            accepted = Some((t, v, gv));
            if ok {
                break;
            }
        }
        let Some((t, v, gv)) = accepted else {
            // Every trial failed: the last failure, with its run and point.
            return Err(failure.expect("a trial without a value failed"));
        };
        if !armijo(t, &v, gv) {
            short_steps += 1;
        }
        grad = gradient_at(runs, fd, &v, gv)?;
        (u, g, step) = (v, gv, t);
    }
    if failed_trials > 0 {
        warnings.push(format!(
            "the model could not run at {failed_trials} trial point(s) of the line search (a \
             value out of its range far from the median?): the steps were shortened"
        ));
    }
    if short_steps > 0 {
        warnings.push(format!(
            "the line search found no sufficient decrease in {short_steps} iteration(s) and \
             took its smallest step (noisy model values? try larger finite-difference steps)"
        ));
    }
    // A converged search stands on the surface (|g| within the tolerance, either side).
    if min_g > 0.0 && !converged {
        warnings.push(format!(
            "no run of FORM reached the failure domain (smallest g = {min_g:.4e})"
        ));
    }
    let gn = norm(&grad);
    let alpha: Vec<f64> = grad.iter().map(|v| -v / gn).collect();
    let beta = dot(&alpha, &u) + g / gn;
    Ok(FormResult {
        beta,
        probability: norm_sf(beta),
        x_star: runs.physical(&u),
        importance: alpha.iter().map(|a| a * a).collect(),
        alpha,
        u_star: u,
        g,
        gradient: grad,
        converged,
        iterations,
        runs: runs.count() - first,
        next_run: runs.count(),
        history,
        warnings,
    })
}

#[cfg(test)]
mod tests {
    use super::super::fixtures::*;
    use super::super::gradient::Scheme;
    use super::super::model::FnLimitState;
    use super::*;

    #[test]
    fn linear_limit_state_in_8_dims_is_exact_within_20_runs_per_dimension() {
        for p in [1e-3, 1e-4, 1e-6] {
            let lin = Linear::new(8, p);
            let mut m = lin.model();
            let r = form(&mut m, &Form::default(), 0).unwrap();
            let err = (r.probability - p).abs() / p;
            println!("linear P = {p}: FORM error {err:.1e}, {} runs", r.runs);
            assert!(r.converged, "{r:?}");
            assert!(err < 0.01, "P = {p}: FORM {} ({err:.2e})", r.probability);
            assert!(r.runs <= 20 * 8, "{} runs", r.runs);
            assert!((r.importance.iter().sum::<f64>() - 1.0).abs() < 1e-12);
            for (a, e) in r.alpha.iter().zip(&lin.direction) {
                assert!((a - e).abs() < 1e-6, "{:?} vs {:?}", r.alpha, lin.direction);
            }
            // Iterations recorded, beta of the last one is the result.
            assert_eq!(r.history.last().unwrap().beta, r.beta);
            assert_eq!(r.runs, 18, "two batches of d + 1 = 9");
        }
    }

    #[test]
    fn lognormal_response_is_exact_as_a_monotone_map_of_a_linear_one() {
        // y = exp(0.7 sum x_i / sqrt 8), x_i standard normal: ln y ~ N(0, 0.49), so
        // P(y > limit) = Phi(-ln(limit) / 0.7).
        for p in [1e-3, 1e-4, 1e-5] {
            let (inputs, limit) = lognormal_response(p);
            for scheme in [Scheme::Forward, Scheme::Central] {
                let settings = Form {
                    differences: Differences {
                        scheme,
                        ..Differences::default()
                    },
                    ..Form::default()
                };
                let mut m = lognormal_model(&inputs, limit);
                let r = form(&mut m, &settings, 0).unwrap();
                let err = (r.probability - p).abs() / p;
                println!(
                    "lognormal P = {p}, {scheme:?}: FORM error {err:.1e}, {} runs",
                    r.runs
                );
                assert!(r.converged && err < 0.01, "{p} {scheme:?}: {r:?}");
                assert!(r.runs <= 20 * 8, "{} runs", r.runs);
                let x = r.x_star.unwrap();
                let y = (0.7 * x.iter().sum::<f64>() / 8f64.sqrt()).exp();
                assert!(
                    (y - limit).abs() < 1e-3 * limit,
                    "y(x*) = {y}, limit {limit}"
                );
            }
        }
    }

    #[test]
    fn a_failing_origin_gives_a_negative_beta() {
        let mut m = FnLimitState::new(3, |u: &[f64]| Ok(-1.5 + u[0] + 0.5 * u[2]));
        let r = form(&mut m, &Form::default(), 0).unwrap();
        let beta = -1.5 / 1.25f64.sqrt();
        assert!((r.beta - beta).abs() < 1e-9, "{}", r.beta);
        assert!(r.probability > 0.5);
    }

    #[test]
    fn a_failed_run_mid_form_is_an_error_naming_the_point() {
        // Run 11, a finite-difference point of the start, where no step can be shortened.
        let mut calls = 0;
        let mut m = FnLimitState::new(2, |u: &[f64]| {
            calls += 1;
            if calls == 2 {
                Err("the solver diverged".into())
            } else {
                Ok(3.0 - u[0] - u[1] * u[1] * 0.1)
            }
        });
        let e = form(&mut m, &Form::default(), 10).unwrap_err();
        match &e {
            ReliabilityError::RunFailed {
                run, u, message, ..
            } => {
                assert_eq!(*run, 11);
                assert_eq!(u.len(), 2);
                assert_eq!(message, "the solver diverged");
            }
            other => panic!("{other:?}"),
        }
        assert!(e.to_string().contains("run 11 failed at u = ["), "{e}");
    }

    /// A full step into a region where the model cannot run (a stiffness below zero far from
    /// the median) stopped FORM with an error; it is a step too long, which the line search
    /// shortens.
    #[test]
    fn a_step_where_the_model_cannot_run_is_shortened_not_an_error() {
        // g = 2.5 − u1 − 0.3 u1², root u1 = (√4 − 1)/0.6 = 5/3; from the origin the HLRF
        // step goes to u1 = 2.5, where the model fails (u1 > 2).
        let g = |u: &[f64]| {
            if u[0] > 2.0 {
                Err("negative stiffness".into())
            } else {
                Ok(2.5 - u[0] - 0.3 * u[0] * u[0] + 0.0 * u[1])
            }
        };
        let mut m = FnLimitState::new(2, g);
        let f = form(&mut m, &Form::default(), 0).unwrap();
        assert!(f.converged, "{:?}", f.warnings);
        assert!((f.beta - 5.0 / 3.0).abs() < 1e-3, "beta {}", f.beta);
        assert!(
            f.warnings
                .iter()
                .any(|w| w.contains("could not run at 1 trial point")),
            "{:?}",
            f.warnings
        );
        // Where no trial of the line search can run, the last failure is the error.
        let mut m = FnLimitState::new(2, |u: &[f64]| {
            if u[0] > 1e-3 {
                Err("negative stiffness".into())
            } else {
                Ok(2.5 - u[0] + 0.0 * u[1])
            }
        });
        let e = form(&mut m, &Form::default(), 0).unwrap_err();
        assert!(e.to_string().contains("negative stiffness"), "{e}");
    }

    #[test]
    fn a_limit_never_reached_is_said_without_nan_or_panic() {
        // q = s / (1 + |s|) < 1 with s = sum u: the limit 2 is never reached.
        let mut m = FnLimitState::new(4, |u: &[f64]| {
            let s: f64 = u.iter().sum();
            Ok(2.0 - s / (1.0 + s.abs()))
        });
        let r = form(&mut m, &Form::default(), 0).unwrap();
        assert!(!r.converged);
        assert!(r.beta.is_finite() && r.probability.is_finite() && r.probability < 1e-6);
        assert!(
            r.warnings
                .iter()
                .any(|w| w.contains("no run of FORM reached")),
            "{:?}",
            r.warnings
        );
    }

    #[test]
    fn a_zero_gradient_at_the_start_is_a_typed_error() {
        let mut m = FnLimitState::new(
            3,
            |u: &[f64]| Ok(9.0 - u.iter().map(|v| v * v).sum::<f64>()),
        );
        let settings = Form {
            differences: Differences {
                scheme: Scheme::Central,
                ..Differences::default()
            },
            ..Form::default()
        };
        assert!(matches!(
            form(&mut m, &settings, 0),
            Err(ReliabilityError::ZeroGradient { .. })
        ));
    }

    #[test]
    fn same_settings_give_bit_identical_results() {
        let (inputs, limit) = lognormal_response(1e-4);
        let a = form(&mut lognormal_model(&inputs, limit), &Form::default(), 0).unwrap();
        let b = form(&mut lognormal_model(&inputs, limit), &Form::default(), 0).unwrap();
        assert_eq!(format!("{a:?}"), format!("{b:?}"));
    }
}
