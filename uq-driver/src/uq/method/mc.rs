//! Monte Carlo: independent uniform draws mapped through each input's quantile function;
//! sample mean, unbiased Std and the standard error of the mean (`sample.rs`).

use serde::{Deserialize, Serialize};

use super::error::MethodError;
use super::sample::{Points, UnitCubeSample, SE_MONTE_CARLO};
use crate::uq::sampling;

/// `kind = "mc"`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Mc {
    /// Number of samples (at least 2).
    pub samples: usize,
}

impl UnitCubeSample for Mc {
    const KIND: &'static str = "mc";

    fn samples(&self) -> usize {
        self.samples
    }

    /// Point `i` takes its uniforms from the stream `(seed, i)` only.
    fn block(&self, d: usize, seed: u64, _replicate: Option<usize>) -> Result<Points, MethodError> {
        Ok(sampling::monte_carlo(self.samples, d, seed))
    }

    fn standard_error(&self) -> &'static str {
        SE_MONTE_CARLO
    }
}
