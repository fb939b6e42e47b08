//! Analytic limit states with closed-form probabilities, shared by the tests.

use statrs::distribution::{ChiSquared, ContinuousCDF};

use super::form::FormResult;
use super::importance::{importance_sampling, ImportanceSampling, ImportanceSamplingResult};
use super::model::{FnLimitState, LimitState, Outcome, PhysicalLimitState, Side, Threshold};
use crate::uq::distributions::{Distribution, RandomParameter};
use crate::uq::random_inputs::RandomInputs;
use crate::uq::special::norm_isf;

/// `g(u) = scale (beta - a . u)` with `|a| = 1`: `P = Phi(-beta)` exactly.
pub(super) struct Linear {
    pub beta: f64,
    pub direction: Vec<f64>,
    pub scale: f64,
}

impl Linear {
    /// In `d` dimensions with `P = p`; the direction weighs the coordinates unevenly and
    /// with both signs, the scale is not 1.
    pub fn new(d: usize, p: f64) -> Linear {
        let raw: Vec<f64> = (0..d)
            .map(|i| (1.0 + (i % 3) as f64) * if i % 2 == 0 { 1.0 } else { -1.0 })
            .collect();
        let n = raw.iter().map(|v| v * v).sum::<f64>().sqrt();
        Linear {
            beta: norm_isf(p),
            direction: raw.iter().map(|v| v / n).collect(),
            scale: 2.5,
        }
    }

    pub fn model(&self) -> FnLimitState<impl FnMut(&[f64]) -> Outcome> {
        let (beta, a, scale) = (self.beta, self.direction.clone(), self.scale);
        FnLimitState::new(a.len(), move |u: &[f64]| {
            Ok(scale * (beta - a.iter().zip(u).map(|(x, y)| x * y).sum::<f64>()))
        })
    }
}

/// Eight standard normal inputs and the limit of `y = exp(0.7 sum x_i / sqrt 8)` exceeded
/// with probability `p`: `ln y ~ N(0, 0.7^2)`, so `limit = exp(0.7 Phi^-1(1 - p))`.
pub(super) fn lognormal_response(p: f64) -> (RandomInputs, f64) {
    let parameters = (0..8)
        .map(|i| RandomParameter::new(format!("x{i}"), Distribution::normal(0.0, 1.0).unwrap()))
        .collect();
    (
        RandomInputs::independent(parameters),
        (0.7 * norm_isf(p)).exp(),
    )
}

/// `y = exp(0.7 sum x_i / sqrt 8)` against `limit` (failure above).
pub(super) fn lognormal_model(inputs: &RandomInputs, limit: f64) -> impl LimitState + '_ {
    let threshold = Threshold {
        limit,
        side: Side::Above,
    };
    PhysicalLimitState::new(inputs, threshold, |batch: &[(u64, Vec<f64>)]| {
        Ok(batch
            .iter()
            .map(|(_, x)| Ok((0.7 * x.iter().sum::<f64>() / 8f64.sqrt()).exp()))
            .collect())
    })
}

/// `g = c - |u|^2`.
pub(super) fn sum_of_squares(c: f64, u: &[f64]) -> f64 {
    c - u.iter().map(|v| v * v).sum::<f64>()
}

/// `P(chi^2_d > c)` (statrs).
pub(super) fn chi_square_sf(d: usize, c: f64) -> f64 {
    ChiSquared::new(d as f64).unwrap().sf(c)
}

/// The `c` with `P(chi^2_d > c) = p`, by bisection.
pub(super) fn chi_square_limit(d: usize, p: f64) -> f64 {
    let (mut lo, mut hi) = (0.0, 1000.0);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if chi_square_sf(d, mid) > p {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Importance sampling with the default settings around FORM's design point `f`, seeded
/// `seed`, its runs numbered from `first_run`.
pub(super) fn sampling_at_design_point(
    model: &mut dyn LimitState,
    f: &FormResult,
    seed: u64,
    first_run: u64,
) -> ImportanceSamplingResult {
    importance_sampling(
        model,
        &ImportanceSampling::default(),
        &f.u_star,
        seed,
        first_run,
    )
    .unwrap()
}
