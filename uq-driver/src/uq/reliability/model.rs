//! The model as the reliability methods see it: a batch evaluator of a limit state in
//! standard normal space, its physical-space adapter, and the replay of stored runs.

#[cfg(test)]
use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

pub use super::error::Abort;
use super::error::ReliabilityError;
use crate::uq::distributions::Germ;
use crate::uq::random_inputs::RandomInputs;

/// The result of one run: the value of the limit state `g` (or of the quantity, for a
/// physical model), or why the run failed.
pub type Outcome = Result<f64, String>;

/// A point requested by a method: its run index and its coordinates in independent
/// standard normal space.
#[derive(Clone, Debug, PartialEq)]
pub struct Point {
    /// The run index: runs are numbered `0, 1, 2, ...` in the order a method requests them.
    pub run: u64,
    /// The standard normal coordinates.
    pub u: Vec<f64>,
}

/// A limit state `g(u)` in independent standard normal space; failure is `g <= 0`.
pub trait LimitState {
    /// Number of coordinates `d`.
    fn dim(&self) -> usize;

    /// `g` at every point of the batch (one outcome per point, in order). The batch may be
    /// evaluated in parallel; the outcomes must not depend on how.
    fn evaluate(&mut self, batch: &[Point]) -> Result<Vec<Outcome>, Abort>;

    /// The physical inputs at `u`, for reports and error messages (`None` for a model
    /// without a physical space).
    fn physical(&self, _u: &[f64]) -> Option<Vec<f64>> {
        None
    }
}

#[cfg(test)]
/// A limit state from a closure of one point (analytic models, tests).
pub struct FnLimitState<F> {
    dim: usize,
    g: F,
}

#[cfg(test)]
impl<F: FnMut(&[f64]) -> Outcome> FnLimitState<F> {
    /// `g` in `dim` coordinates.
    pub fn new(dim: usize, g: F) -> Self {
        FnLimitState { dim, g }
    }
}

#[cfg(test)]
impl<F: FnMut(&[f64]) -> Outcome> LimitState for FnLimitState<F> {
    fn dim(&self) -> usize {
        self.dim
    }

    fn evaluate(&mut self, batch: &[Point]) -> Result<Vec<Outcome>, Abort> {
        Ok(batch.iter().map(|p| (self.g)(&p.u)).collect())
    }
}

/// Which tail fails.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Side {
    /// Failure is `q > limit`: `g = limit - q`.
    Above,
    /// Failure is `q < limit`: `g = q - limit`.
    Below,
}

/// A limit on a quantity `q` and the side that fails.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Threshold {
    /// The limit, in the quantity's units.
    pub limit: f64,
    /// Which side of it fails.
    pub side: Side,
}

impl Threshold {
    /// The limit state of the value `q`: `limit - q` (above) or `q - limit` (below); in
    /// both cases `g <= 0` is failure (the limit itself counts as failure).
    pub fn g(&self, q: f64) -> f64 {
        match self.side {
            Side::Above => self.limit - q,
            Side::Below => q - self.limit,
        }
    }
}

/// A model of the physical inputs made a limit state in standard normal space:
/// `x = T(u)` by [`RandomInputs::to_physical`] with [`Germ::Normal`] (each input's
/// `F^-1(Phi(.))`, correlated inputs through the Gaussian copula), `q = model(x)`, and `g`
/// from the [`Threshold`].
///
/// The model receives the batch as `(run, x)` pairs. A discrete (`integer_uniform`) input
/// makes `g` a staircase in its coordinate: fine for the sampling methods, not for the
/// gradients of FORM and SORM.
pub struct PhysicalLimitState<'a, F> {
    inputs: &'a RandomInputs,
    threshold: Threshold,
    model: F,
}

impl<'a, F> PhysicalLimitState<'a, F>
where
    F: FnMut(&[(u64, Vec<f64>)]) -> Result<Vec<Outcome>, Abort>,
{
    /// `model` maps a batch of physical points to the quantity `q` at each.
    pub fn new(inputs: &'a RandomInputs, threshold: Threshold, model: F) -> Self {
        PhysicalLimitState {
            inputs,
            threshold,
            model,
        }
    }
}

impl<F> LimitState for PhysicalLimitState<'_, F>
where
    F: FnMut(&[(u64, Vec<f64>)]) -> Result<Vec<Outcome>, Abort>,
{
    fn dim(&self) -> usize {
        self.inputs.len()
    }

    fn evaluate(&mut self, batch: &[Point]) -> Result<Vec<Outcome>, Abort> {
        let physical: Vec<(u64, Vec<f64>)> = batch
            .iter()
            .map(|p| (p.run, self.inputs.to_physical(Germ::Normal, &p.u)))
            .collect();
        let q = (self.model)(&physical)?;
        Ok(q.into_iter()
            .map(|q| q.map(|q| self.threshold.g(q)))
            .collect())
    }

    fn physical(&self, u: &[f64]) -> Option<Vec<f64>> {
        Some(self.inputs.to_physical(Germ::Normal, u))
    }
}

#[cfg(test)]
/// A finished run as a runner stores it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StoredRun {
    /// The standard normal point.
    pub u: Vec<f64>,
    /// Its outcome (`Err`: the run failed, with the message).
    pub outcome: Outcome,
}

#[cfg(test)]
/// A limit state that answers the runs it has stored and forwards the others to `inner`,
/// storing their outcomes too: the resume of a method after a kill (see the module
/// documentation of [`crate::uq::reliability`]).
///
/// The stored runs need not be a prefix (a parallel batch may have been cut with some runs
/// done); each is checked bit for bit against the point requested now.
pub struct Replay<'a> {
    inner: &'a mut dyn LimitState,
    runs: BTreeMap<u64, StoredRun>,
    replayed: usize,
}

#[cfg(test)]
impl<'a> Replay<'a> {
    /// Replays `stored` (run index to run) in front of `inner`.
    pub fn new(inner: &'a mut dyn LimitState, stored: BTreeMap<u64, StoredRun>) -> Self {
        Replay {
            inner,
            runs: stored,
            replayed: 0,
        }
    }

    /// The runs answered from the store.
    pub fn replayed(&self) -> usize {
        self.replayed
    }

    /// The runs, stored and new.
    pub fn into_runs(self) -> BTreeMap<u64, StoredRun> {
        self.runs
    }
}

#[cfg(test)]
impl LimitState for Replay<'_> {
    fn dim(&self) -> usize {
        self.inner.dim()
    }

    fn evaluate(&mut self, batch: &[Point]) -> Result<Vec<Outcome>, Abort> {
        let mut missing = Vec::new();
        for p in batch {
            match self.runs.get(&p.run) {
                Some(s) => {
                    let same = s.u.len() == p.u.len()
                        && s.u
                            .iter()
                            .zip(&p.u)
                            .all(|(a, b)| a.to_bits() == b.to_bits());
                    if !same {
                        return Err(Abort::ReplayMismatch {
                            run: p.run,
                            stored: s.u.clone(),
                            requested: p.u.clone(),
                        });
                    }
                }
                None => missing.push(p.clone()),
            }
        }
        self.replayed += batch.len() - missing.len();
        if !missing.is_empty() {
            let outcomes = self.inner.evaluate(&missing)?;
            if outcomes.len() != missing.len() {
                return Err(Abort::Interrupted(format!(
                    "the model returned {} outcomes for a batch of {} points",
                    outcomes.len(),
                    missing.len()
                )));
            }
            for (p, outcome) in missing.into_iter().zip(outcomes) {
                self.runs.insert(p.run, StoredRun { u: p.u, outcome });
            }
        }
        Ok(batch
            .iter()
            .map(|p| self.runs[&p.run].outcome.clone())
            .collect())
    }

    fn physical(&self, u: &[f64]) -> Option<Vec<f64>> {
        self.inner.physical(u)
    }
}

/// What a sampling method does with a failed run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OnFailure {
    /// Stop with [`ReliabilityError::RunFailed`] (dropping the run would bias the estimate).
    #[default]
    Error,
    /// Count the run as a failure of the system (`g = -inf`): e.g. a simulation that breaks
    /// down because the vehicle derails.
    CountAsFailure,
}

/// The methods' access to the model: numbers the runs, checks the batch sizes and turns
/// failed or non-finite runs into errors (or failures, by [`OnFailure`]).
pub(crate) struct Runs<'m> {
    model: &'m mut dyn LimitState,
    next: u64,
}

impl<'m> Runs<'m> {
    pub(crate) fn new(model: &'m mut dyn LimitState) -> Result<Self, ReliabilityError> {
        if model.dim() == 0 {
            return Err(ReliabilityError::NoInputs);
        }
        Ok(Runs { model, next: 0 })
    }

    /// Continues the run numbering at `next` (a method called after another on the same
    /// model, e.g. SORM after FORM).
    pub(crate) fn starting_at(
        model: &'m mut dyn LimitState,
        next: u64,
    ) -> Result<Self, ReliabilityError> {
        let mut r = Runs::new(model)?;
        r.next = next;
        Ok(r)
    }

    pub(crate) fn dim(&self) -> usize {
        self.model.dim()
    }

    /// Runs so far (the index of the next run).
    pub(crate) fn count(&self) -> u64 {
        self.next
    }

    pub(crate) fn physical(&self, u: &[f64]) -> Option<Vec<f64>> {
        self.model.physical(u)
    }

    /// `g` at every point; a failed or non-finite run handled by `on_failure`.
    pub(crate) fn eval(
        &mut self,
        points: Vec<Vec<f64>>,
        on_failure: OnFailure,
    ) -> Result<Vec<f64>, ReliabilityError> {
        self.eval_each(points)?
            .into_iter()
            .map(|r| match (r, on_failure) {
                (Ok(v), _) => Ok(v),
                (Err(_), OnFailure::CountAsFailure) => Ok(f64::NEG_INFINITY),
                (Err(e), OnFailure::Error) => Err(e),
            })
            .collect()
    }

    /// `g` at every point, each failed or non-finite run as its
    /// [`ReliabilityError::RunFailed`] (an abort or a batch of the wrong size stops all).
    pub(crate) fn eval_each(
        &mut self,
        points: Vec<Vec<f64>>,
    ) -> Result<Vec<Result<f64, ReliabilityError>>, ReliabilityError> {
        if points.is_empty() {
            return Ok(Vec::new());
        }
        let batch: Vec<Point> = points
            .into_iter()
            .enumerate()
            .map(|(k, u)| Point {
                run: self.next + k as u64,
                u,
            })
            .collect();
        let outcomes = self.model.evaluate(&batch)?;
        if outcomes.len() != batch.len() {
            return Err(ReliabilityError::BatchSize {
                expected: batch.len(),
                got: outcomes.len(),
            });
        }
        self.next += batch.len() as u64;
        Ok(batch
            .into_iter()
            .zip(outcomes)
            .map(|(p, outcome)| {
                let message = match outcome {
                    Ok(v) if v.is_finite() => return Ok(v),
                    Ok(v) => format!("the value is {v}"),
                    Err(m) => m,
                };
                Err(ReliabilityError::RunFailed {
                    run: p.run,
                    x: self.model.physical(&p.u),
                    u: p.u,
                    message,
                })
            })
            .collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::uq::distributions::{Distribution, RandomParameter};

    #[test]
    fn thresholds_fail_on_their_side_and_at_the_limit() {
        let above = Threshold {
            limit: 2.0,
            side: Side::Above,
        };
        let below = Threshold {
            limit: 2.0,
            side: Side::Below,
        };
        assert_eq!(above.g(3.0), -1.0);
        assert_eq!(above.g(1.5), 0.5);
        assert_eq!(below.g(1.5), -0.5);
        assert_eq!(below.g(2.5), 0.5);
        assert_eq!(above.g(2.0), 0.0);
        assert_eq!(below.g(2.0), 0.0);
    }

    #[test]
    fn physical_adapter_maps_through_the_inputs() {
        let inputs = RandomInputs::independent(vec![
            RandomParameter::new("a", Distribution::normal(10.0, 2.0).unwrap()),
            RandomParameter::new("b", Distribution::lognormal(0.0, 0.5).unwrap()),
        ]);
        let threshold = Threshold {
            limit: 15.0,
            side: Side::Above,
        };
        let mut seen = Vec::new();
        let mut m = PhysicalLimitState::new(&inputs, threshold, |b: &[(u64, Vec<f64>)]| {
            seen.extend(b.iter().map(|(r, _)| *r));
            Ok(b.iter().map(|(_, x)| Ok(x[0] + x[1])).collect())
        });
        let out = m
            .evaluate(&[Point {
                run: 7,
                u: vec![1.0, 2.0],
            }])
            .unwrap();
        let q = 12.0 + 1.0f64.exp();
        assert!((out[0].clone().unwrap() - (15.0 - q)).abs() < 1e-12);
        assert_eq!(m.physical(&[1.0, 2.0]).unwrap()[0], 12.0);
        let _ = m;
        assert_eq!(seen, vec![7]);
    }

    #[test]
    fn failed_and_non_finite_runs_are_errors_or_failures() {
        let mut m = FnLimitState::new(1, |u: &[f64]| {
            if u[0] > 1.0 {
                Err("solver diverged".into())
            } else if u[0] < -1.0 {
                Ok(f64::NAN)
            } else {
                Ok(u[0])
            }
        });
        let mut runs = Runs::new(&mut m).unwrap();
        assert_eq!(
            runs.eval(vec![vec![0.5], vec![2.0]], OnFailure::CountAsFailure)
                .unwrap(),
            vec![0.5, f64::NEG_INFINITY]
        );
        let e = runs.eval(vec![vec![-2.0]], OnFailure::Error).unwrap_err();
        assert!(
            matches!(&e, ReliabilityError::RunFailed { run: 2, u, .. } if u == &vec![-2.0]),
            "{e}"
        );
        assert!(e.to_string().contains("the value is NaN"), "{e}");
    }
}
