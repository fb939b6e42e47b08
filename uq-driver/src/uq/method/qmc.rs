//! Quasi-Monte Carlo: `replicates` independent Owen-scrambled Sobol' sequences (Joe–Kuo
//! direction numbers, `uq::hd::sobol_seq`) of `samples` points each, mapped through
//! each input's quantile function.
//!
//! Replicate `r` is the scrambling keyed by `(seed, r)`: its dimension `j` takes the `j`-th
//! word of the ChaCha20 stream `rng::stream(seed, r)`; point `i` of the design is point
//! `i % samples` of replicate `i / samples`. Each scrambled estimate is unbiased; the mean is
//! the mean of the replicate means and its standard error `sd(replicate means) / sqrt(R)`
//! (`sample.rs`). At least 2 replicates are required: a single scrambled sequence has no
//! error estimate (the Monte Carlo formula is not a bound for scrambled nets).
//! `samples` should be a power of two (the points are a net only then).

use serde::{Deserialize, Serialize};

use super::error::{InvalidSettings, MethodError};
use super::sample::{Points, UnitCubeSample, SE_REPLICATES};
use super::traits::Problem;
use crate::uq::hd::sobol_seq::{self, Sobol};

/// Default number of replicates.
pub const DEFAULT_REPLICATES: usize = 8;

/// `kind = "qmc"`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Qmc {
    /// Points per replicate (at least 2; best a power of two).
    pub samples: usize,
    /// Independent scramblings (at least 2; default 8): `samples × replicates` model runs.
    #[serde(default = "default_replicates")]
    pub replicates: usize,
}

fn default_replicates() -> usize {
    DEFAULT_REPLICATES
}

/// Whether a Sobol' sequence of `samples` points in `dim` dimensions exists (`hint`: what to
/// do instead when the dimension is too high, appended to the message).
pub(crate) fn check_sobol_points(
    dim: usize,
    samples: usize,
    hint: &str,
) -> Result<(), InvalidSettings> {
    if dim > sobol_seq::MAX_DIM {
        return Err(InvalidSettings(format!(
            "Sobol' points are available in at most {} dimensions (this design needs {dim}){hint}",
            sobol_seq::MAX_DIM
        )));
    }
    if samples as u64 > 1u64 << sobol_seq::BITS {
        return Err(InvalidSettings(format!(
            "`samples` = {samples} is more than the 2^{} points of a Sobol' sequence",
            sobol_seq::BITS
        )));
    }
    Ok(())
}

impl UnitCubeSample for Qmc {
    const KIND: &'static str = "qmc";

    fn samples(&self) -> usize {
        self.samples
    }

    fn replicates(&self) -> Option<usize> {
        Some(self.replicates)
    }

    fn block(&self, d: usize, seed: u64, replicate: Option<usize>) -> Result<Points, MethodError> {
        let r = replicate.unwrap_or(0) as u64;
        let invalid =
            |e: sobol_seq::SobolError| MethodError::Invalid(InvalidSettings(e.to_string()));
        Sobol::scrambled(d, seed, r)
            .map_err(invalid)?
            .points(0, self.samples)
            .map_err(invalid)
    }

    fn check(&self, problem: &Problem) -> Result<(), InvalidSettings> {
        check_sobol_points(problem.parameters.len(), self.samples, "")
    }

    fn notes(&self) -> Vec<String> {
        if self.samples.is_power_of_two() {
            return Vec::new();
        }
        let up = self.samples.next_power_of_two();
        vec![format!(
            "qmc: samples = {} is not a power of two: Sobol' points are balanced (a net) only \
             in blocks of 2^m points; the estimate stays unbiased but converges more slowly \
             (use samples = {} or {})",
            self.samples,
            up / 2,
            up
        )]
    }

    fn standard_error(&self) -> &'static str {
        SE_REPLICATES
    }
}
