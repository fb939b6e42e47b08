//! Latin hypercube sampling: one point in each of `samples` equal-probability strata of every
//! input; estimated like Monte Carlo (`sample.rs`).
//!
//! Without `replicates` the standard error is the plain Monte Carlo formula, an upper bound
//! for a Latin hypercube, often a far too pessimistic one (on the wheel with 2 048 samples the
//! actual errors are 0.001 to 0.8 of it, under 0.03 of it before 1 s). With
//! `replicates = R`, `R` independent Latin hypercubes of `samples` points each give an honest
//! standard error from the spread of their means. Replicate `r` is the Latin hypercube of
//! seed `s_r` = the first word of the ChaCha20 stream `rng::stream(seed, 2^63 + r)`.

use rand::RngCore;
use serde::{Deserialize, Serialize};

use super::error::MethodError;
use super::sample::{Points, UnitCubeSample, SE_REPLICATES};
use crate::uq::{rng, sampling};

/// `standard_error` of an unreplicated Latin hypercube.
const SE_LHS_UPPER_BOUND: &str = "Monte Carlo formula std / sqrt(samples): an upper bound \
     for a Latin hypercube, often far too pessimistic (on the wheel, up to hundreds of times); \
     set `replicates` for an honest one";

/// `kind = "lhs"`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Lhs {
    /// Number of samples (and strata per input; at least 2), per replicate.
    pub samples: usize,
    /// Independent Latin hypercubes (at least 2), for an honest standard error; absent: one
    /// Latin hypercube, the Monte Carlo formula (an upper bound) for the standard error.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub replicates: Option<usize>,
}

/// The seed of replicate `r` of a study seeded `seed`.
fn replicate_seed(seed: u64, r: usize) -> u64 {
    rng::stream(seed, (1u64 << 63) + r as u64).next_u64()
}

impl UnitCubeSample for Lhs {
    const KIND: &'static str = "lhs";
    const RUNS_AXIS: Option<&'static str> =
        Some("for a Latin hypercube the first n points are not a Latin hypercube themselves");

    fn samples(&self) -> usize {
        self.samples
    }

    fn replicates(&self) -> Option<usize> {
        self.replicates
    }

    /// A function of `(samples, d, seed)` only (of the replicate's seed when replicated).
    fn block(&self, d: usize, seed: u64, replicate: Option<usize>) -> Result<Points, MethodError> {
        let seed = replicate.map_or(seed, |r| replicate_seed(seed, r));
        Ok(sampling::latin_hypercube(self.samples, d, seed))
    }

    fn standard_error(&self) -> &'static str {
        match self.replicates {
            Some(_) => SE_REPLICATES,
            None => SE_LHS_UPPER_BOUND,
        }
    }
}
