//! The memory of the chaos methods whose arrays grow with the number of chaos terms
//! (`sparse_grid`, `pce_regression`), estimated before anything is built.
//!
//! Bytes, with `n` runs, `d` random parameters, `nt` communication points, `s` stored
//! outputs, `w` the columns of an analysis block, `T` the terms of an output's chaos,
//! `R` the surrogate draws whose basis is computed (`series_samples` when the study stores
//! outputs, `surrogate_samples` when it has scalar quantities: the larger) and
//! `I = 16 d + 96` the bytes of a multi-index kept with its look-up entry:
//! - **the fit** of one block of columns (the outputs are fitted one after the other):
//!   - `pce_regression`, `sparse = true` (LARS over the degrees `1..=order`, `m_p`
//!     candidate terms of degree `p`, `M = sum_p m_p`): the candidates at the runs of every
//!     degree (`8 n M`), their multi-indices (`I M`), and for every degree tried the
//!     standardised design and its transpose and the Gram rows of the active columns
//!     (`8 m_p (2 n + min(n, m_order))`, counted for every degree: the degree search may
//!     try them all); `T = min(m_order, n)` (each column's chaos has fewer terms than runs;
//!     columns of a series that pick different terms may hold more);
//!   - `sparse = false` (least squares on the `m` terms of the basis): the design, its QR
//!     copy and `Q`, the copy kept by the fit (`4 × 8 n m`), `R` and its inverse
//!     (`2 × 8 m^2`), the multi-indices (`I m`); `T = m`;
//!   - `sparse_grid` (sizes counted by [`total_level_size`](crate::uq::hd::smolyak::total_level_size)): the grid rebuilt by the
//!     estimate and the coarser one of the level difference (`2 × (n (16 d + 104) + 16 N)`,
//!     `N` the nodes of its tensor terms), and the two projections
//!     (`2 × T (8 d + 96 + 16 w)`); `T` the terms of the projection;
//! - **the surrogate's basis at its draws** (`8 R T`), kept per distinct basis for the whole
//!   analysis, plus one copy while one is built: one basis for a sparse grid or a least-squares
//!   chaos, one per output (and one for the quantities) for LARS;
//! - **the coefficients** of every output's chaos, and a merged copy: `8 T nt (s + 1)`.

use crate::spec::Study;
use crate::uq::method::{ChaosFit, Evaluation};

/// The shape of a study's chaos for the memory estimate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChaosShape {
    /// The fit.
    pub fit: ChaosFit,
    /// Random parameters.
    pub dim: f64,
    /// Rows of the surrogate's basis at its draws (`R`).
    pub draws: f64,
    /// Stored outputs.
    pub outputs: f64,
    /// Whether the study has scalar quantities (their chaos has a basis of its own).
    pub quantities: bool,
}

impl ChaosShape {
    /// The chaos shape of `study`, for the methods whose arrays grow with the chaos terms
    /// (`None` for the others, and when the sizes cannot be known: the method's own checks
    /// then refuse the study).
    pub fn of(study: &Study) -> Option<ChaosShape> {
        let dim = study.parameters.len();
        let fit = match study.method().evaluation() {
            Evaluation::Sampling(m) => m.chaos_fit(&study.parameters)?,
            Evaluation::Intrusive(_) | Evaluation::Adaptive(_) => return None,
        };
        let a = &study.analysis;
        let series = if study.outputs.is_empty() {
            0
        } else {
            a.series_samples.min(a.surrogate_samples).max(2)
        };
        let scalars = if study.qoi.is_empty() {
            0
        } else {
            a.surrogate_samples
        };
        Some(ChaosShape {
            fit,
            dim: dim as f64,
            draws: series.max(scalars) as f64,
            outputs: study.outputs.len() as f64,
            quantities: !study.qoi.is_empty(),
        })
    }

    /// The terms `T` of an output's chaos with `n` runs.
    pub fn terms(&self, n: f64) -> f64 {
        match self.fit {
            ChaosFit::Lars { largest, .. } => largest.min(n),
            ChaosFit::LeastSquares { terms } => terms,
            ChaosFit::Projection(g) => g.chaos_terms,
        }
    }

    /// The memory (bytes) of the chaos with `n` runs of `nt` communication points, analysed
    /// in blocks of `w` columns (see the module documentation).
    pub fn memory(&self, n: f64, nt: f64, w: f64) -> f64 {
        let d = self.dim;
        let index = 16.0 * d + 96.0;
        let t = self.terms(n);
        let (fit, bases) = match self.fit {
            ChaosFit::Lars {
                candidates,
                largest,
            } => (
                candidates * (8.0 * (3.0 * n + n.min(largest)) + index),
                self.outputs + f64::from(u8::from(self.quantities)),
            ),
            ChaosFit::LeastSquares { terms: m } => {
                (8.0 * (4.0 * n * m + 2.0 * m * m) + index * m, 1.0)
            }
            ChaosFit::Projection(g) => (
                2.0 * (n * (16.0 * d + 104.0) + 16.0 * g.tensor_nodes)
                    + 2.0 * t * (8.0 * d + 96.0 + 16.0 * w),
                1.0,
            ),
        };
        let surrogate = 8.0 * self.draws * t * (bases.min(1.0) + bases);
        let coefficients = 8.0 * t * nt * (self.outputs + 1.0);
        fit + surrogate + coefficients
    }
}

#[cfg(test)]
mod tests {
    use crate::uq::method::hyperbolic_terms;
    use crate::uq::pce::MultiIndexSet;

    #[test]
    fn hyperbolic_counts_equal_the_sets() {
        for (d, p, q) in [
            (1, 5, 1.0),
            (3, 4, 1.0),
            (8, 3, 1.0),
            (5, 0, 1.0),
            (4, 6, 0.5),
            (6, 5, 0.75),
            (10, 4, 0.4),
            (3, 10, 0.3),
        ] {
            assert_eq!(
                hyperbolic_terms(d, p, q),
                MultiIndexSet::hyperbolic(d, p, q).unwrap().len() as f64,
                "d = {d}, order {p}, q = {q}"
            );
        }
        // C(35, 5), the LARS candidates in 30 inputs.
        assert_eq!(hyperbolic_terms(30, 5, 1.0), 324_632.0);
    }
}
