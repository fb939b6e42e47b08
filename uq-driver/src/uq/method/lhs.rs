//! Latin hypercube sampling: one point in each of `samples` equal-probability strata of every
//! input; estimated like Monte Carlo (`sample.rs`; the MC standard error is valid, if
//! pessimistic).

use serde::{Deserialize, Serialize};

use super::sample::UnitCubeSample;
use crate::uq::sampling;

/// `kind = "lhs"`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Lhs {
    /// Number of samples (and strata per input; at least 2).
    pub samples: usize,
}

impl UnitCubeSample for Lhs {
    const KIND: &'static str = "lhs";

    fn samples(&self) -> usize {
        self.samples
    }

    /// A function of `(n, d, seed)` only.
    fn points(n: usize, d: usize, seed: u64) -> Vec<Vec<f64>> {
        sampling::latin_hypercube(n, d, seed)
    }
}
