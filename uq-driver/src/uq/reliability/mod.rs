//! Small failure probabilities and screening: the algorithm cores, on an abstract model in
//! independent standard normal space.
//!
//! # The model
//!
//! Every method works on a *limit state* `g(u)`, `u` in the independent standard normal space
//! of the study's inputs (`d` coordinates, `U ~ N(0, I)`), failure `g(u) <= 0`
//! ([`LimitState`]). A quantity `q` and a limit give `g = limit - q` when failure is
//! `q > limit` ([`Side::Above`]) and `g = q - limit` when it is `q < limit` ([`Side::Below`]);
//! [`PhysicalLimitState`] maps a model of the physical inputs through
//! [`RandomInputs::to_physical`](crate::uq::RandomInputs::to_physical) (every input family,
//! Nataf correlation) into such a `g`.
//!
//! The methods ask for *batches* of points and receive one [`Outcome`] per point (a run may
//! fail); the caller evaluates a batch in parallel. Batches are as large as each method
//! allows: the `d + 1` (forward) or `2d + 1` (central) points of a finite-difference gradient
//! together, the Hessian's points together, a block of importance samples, one step of all
//! Markov chains of a subset level, the whole Morris design.
//!
//! # Runs, replay and resume
//!
//! Every point a method requests is a *run* with an index (`0, 1, 2, ...` in the order of
//! the requests, [`Point::run`]). The points requested are a deterministic function of the
//! settings, the seed and the values returned for the earlier runs: random numbers come from
//! [`crate::uq::rng::stream`]`(seed, index)` streams (fixed per sample, chain or
//! start, never per thread), and nothing depends on timing or on the thread count. So a
//! runner
//! 1. stores each finished run as `(run index, u, outcome)` ([`StoredRun`]) as it finishes;
//! 2. after a kill, wraps its model in [`Replay`] with the stored runs and calls the method
//!    again with the same settings and seed: every stored run is answered from the store
//!    (its point is checked bit for bit against the request, a mismatch is
//!    [`Abort::ReplayMismatch`]), only the missing ones are evaluated, and the result is
//!    bit-identical to an uninterrupted run.
//!
//! A runner that wants to stop (Ctrl-C, a budget) returns [`Abort::Interrupted`] from
//! [`LimitState::evaluate`]; the method returns [`ReliabilityError::Aborted`].
//!
//! # Methods (one file each)
//! - [`form`](mod@form): the design point by iHLRF (Zhang & Der Kiureghian 1997), `P = Phi(-beta)`;
//!   [`multistart`]: several starting points, distinct design points flagged;
//! - [`sorm`](mod@sorm): principal curvatures at the design point; Breitung (1984),
//!   Hohenbichler & Rackwitz (1988), Tvedt (1990);
//! - [`importance`]: importance sampling around the design point;
//! - [`subset`]: subset simulation (Au & Beck 2001) with adaptive conditional sampling
//!   (Papaioannou et al. 2015);
//! - [`morris`]: Morris screening with Campolongo et al.'s (2007) spread trajectories (a
//!   design and an estimator, not adaptive).
//!
//! `gradient` holds the finite differences FORM and SORM share.

pub mod error;
pub mod form;
pub(crate) mod gradient;
pub mod importance;
pub mod model;
pub mod morris;
pub mod multistart;
pub mod sorm;
pub mod subset;

#[cfg(test)]
mod fixtures;
#[cfg(test)]
mod tests;

pub use error::ReliabilityError;
pub use form::{form, Form, FormResult};
pub use gradient::{Differences, Scheme};
#[cfg(test)]
pub(crate) use importance::importance_sampling;
pub use importance::{
    importance_sampling_mixture, ImportanceSampling, ImportanceSamplingResult, MixtureComponent,
};
pub use model::{
    Abort, LimitState, OnFailure, Outcome, PhysicalLimitState, Point, Side, Threshold,
};
#[cfg(test)]
pub use model::{Replay, StoredRun};
pub use morris::{Morris, MorrisDesign, MorrisResult};
pub use multistart::{form_multistart, MultiStart, MultiStartResult};
pub use sorm::{sorm, Sorm, SormResult};
pub use subset::{subset_simulation, Spread, Subset, SubsetResult};

use crate::uq::rng::{self, ChaCha20};

/// Which use a random stream serves: the top byte of its stream index, so that the draws of
/// different purposes never share a stream under one seed.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Purpose {
    /// Importance sample `i`.
    ImportanceSample = 1,
    /// Subset simulation: sample `i` of level 0, or chain `c` of level `l >= 1`
    /// (`l << 32 | c`).
    Subset = 2,
    /// Random starting point `k` of a multi-start FORM.
    Start = 3,
    /// Candidate trajectory `m` of a Morris design.
    Morris = 4,
}

/// The stream of `index` (below `2^56`) for `purpose` under `seed`:
/// `rng::stream(seed, purpose << 56 | index)`.
pub(crate) fn stream(seed: u64, purpose: Purpose, index: u64) -> ChaCha20 {
    debug_assert!(index < 1 << 56);
    rng::stream(seed, (purpose as u64) << 56 | index)
}

/// `d` independent standard normals from `rng` (by inversion, one word each).
pub(crate) fn normals(rng: &mut ChaCha20, d: usize) -> Vec<f64> {
    (0..d).map(|_| rng::standard_normal(rng)).collect()
}

/// Euclidean norm.
pub(crate) fn norm(v: &[f64]) -> f64 {
    dot(v, v).sqrt()
}

/// Scalar product.
pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// A 95 % interval for a positive estimate `p` with coefficient of variation `cov`, on the
/// log scale: `p exp(-+1.96 s)` with `s^2 = ln(1 + cov^2)` (the log-normal with this mean and
/// CoV). It never goes below 0 and is skewed upwards as the estimates of small probabilities
/// are. `None` when `p` is not positive or `cov` is not finite.
pub(crate) fn log_interval(p: f64, cov: f64) -> Option<[f64; 2]> {
    if !positive(p) || !cov.is_finite() {
        return None;
    }
    let s = (1.0 + cov * cov).ln().sqrt();
    Some([p * (-Z95 * s).exp(), p * (Z95 * s).exp()])
}

/// `x > 0` (false for NaN).
pub(crate) fn positive(x: f64) -> bool {
    x > 0.0
}

/// The 0.975 quantile of the standard normal.
pub(crate) const Z95: f64 = 1.959_963_984_540_054;
