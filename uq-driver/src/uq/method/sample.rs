//! What the equally weighted random designs (Monte Carlo, Latin hypercube) share: `samples`
//! points in the open unit cube, mapped through each input's quantile function, and the
//! sample estimator (mean, unbiased Std, standard error of the mean).

use nalgebra::DMatrix;

use super::design::Design;
use super::error::{InvalidSettings, MethodError};
use super::estimate::Estimate;
use super::traits::{DesignSize, Evaluation, Method, MethodSummary, Problem, Sampling};
use crate::uq::distributions::Germ;
use crate::uq::random_inputs::RandomInputs;

/// A method that draws `samples` equally weighted points in the unit cube.
pub(crate) trait UnitCubeSample: std::fmt::Debug + Send + Sync {
    /// `kind` in study files.
    const KIND: &'static str;

    /// Number of points.
    fn samples(&self) -> usize;

    /// `n` points of dimension `d`, strictly inside (0, 1), deterministic in `seed`.
    fn points(n: usize, d: usize, seed: u64) -> Vec<Vec<f64>>;
}

impl<T: UnitCubeSample> Method for T {
    fn kind(&self) -> &'static str {
        T::KIND
    }

    fn label(&self, _dim: usize) -> String {
        format!("{} {}", T::KIND, self.samples())
    }

    /// At least two samples: one has no spread.
    fn validate(&self, _problem: &Problem) -> Result<(), InvalidSettings> {
        if self.samples() < 2 {
            return Err(InvalidSettings("`samples` must be at least 2".into()));
        }
        Ok(())
    }

    fn summary(&self, _dim: usize) -> MethodSummary {
        let size = DesignSize {
            samples: Some(self.samples()),
            nodes_per_dimension: None,
            order: None,
        };
        MethodSummary::new(T::KIND, &size)
    }

    fn evaluation(&self) -> Evaluation<'_> {
        Evaluation::Sampling(self)
    }
}

impl<T: UnitCubeSample> Sampling for T {
    fn design(&self, inputs: &RandomInputs, seed: u64) -> Result<Design, MethodError> {
        let points = T::points(self.samples(), inputs.len(), seed);
        Ok(Design::mapped(Germ::Uniform, points, None, inputs))
    }

    /// Any subset of the points is a valid (smaller) sample: failed points may be left out.
    fn estimate(
        &self,
        _design: &Design,
        _rows: &[usize],
        data: &DMatrix<f64>,
    ) -> Result<Estimate, MethodError> {
        Ok(Estimate::from_sample(data))
    }
}
