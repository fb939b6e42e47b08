//! The successful runs of a study as the analysis reads them from the results store: a block
//! of time columns of an output, one column, or a scalar quantity with its outcome codes.

use nalgebra::DMatrix;
use rayon::prelude::*;

use super::AnalysisError;
use crate::qoi::scalar::Code;
use crate::study::store::{StoredRuns, Values};

/// The values of one quantity over the successful runs, with their outcome codes.
pub(crate) struct QuantityRuns {
    /// Design indices of the runs with a valid value.
    pub rows: Vec<usize>,
    /// Their values.
    pub valid: Vec<f64>,
    pub never_hunts: usize,
    pub never_stops: usize,
}

/// The values of the successful runs, in design order, read in place from the store.
pub(crate) struct Runs<'a> {
    /// Design indices.
    pub rows: Vec<usize>,
    values: Vec<Values<'a>>,
}

impl<'a> Runs<'a> {
    pub(crate) fn of(stored: &'a StoredRuns) -> Runs<'a> {
        let (rows, values) = (0..stored.len())
            .filter_map(|i| stored.values(i).map(|v| (i, v)))
            .unzip();
        Runs { rows, values }
    }

    /// Output `o` (of `nt` times each) as runs × times.
    pub(crate) fn output(&self, o: usize, nt: usize) -> Result<DMatrix<f64>, AnalysisError> {
        self.block(o, nt, 0, nt)
    }

    /// Columns `j0..j0 + w` of output `o` (of `nt` times each) as runs × times. Chunks of
    /// runs are read in parallel, one read per run, into column-major pieces; the pieces are
    /// then copied into the matrix (groups of columns in parallel).
    pub(crate) fn block(
        &self,
        o: usize,
        nt: usize,
        j0: usize,
        w: usize,
    ) -> Result<DMatrix<f64>, AnalysisError> {
        const ROWS: usize = 256;
        const GROUP: usize = 64;
        let n = self.rows.len();
        if n == 0 || w == 0 {
            return Ok(DMatrix::zeros(n, w));
        }
        let first = o * nt + j0;
        let pieces: Vec<DMatrix<f64>> = self
            .values
            .par_chunks(ROWS)
            .map(|values| {
                let mut piece = DMatrix::<f64>::zeros(values.len(), w);
                let mut row = vec![0.0; w];
                for (r, v) in values.iter().enumerate() {
                    v.try_read_into(first..first + w, &mut row)?;
                    for (k, x) in row.iter().enumerate() {
                        piece[(r, k)] = *x;
                    }
                }
                Ok(piece)
            })
            .collect::<Result<_, AnalysisError>>()?;
        let mut m = DMatrix::<f64>::zeros(n, w);
        m.as_mut_slice()
            .par_chunks_mut(n * GROUP)
            .enumerate()
            .for_each(|(g, out)| {
                for (k, col) in out.chunks_exact_mut(n).enumerate() {
                    for (p, part) in pieces.iter().zip(col.chunks_mut(ROWS)) {
                        part.copy_from_slice(p.column(g * GROUP + k).as_slice());
                    }
                }
            });
        Ok(m)
    }

    /// Column `k` of output `o` (of `nt` times each) over the runs.
    pub(crate) fn column(&self, o: usize, nt: usize, k: usize) -> Result<Vec<f64>, AnalysisError> {
        self.values
            .iter()
            .map(|v| {
                let mut x = [0.0];
                v.try_read_into(o * nt + k..o * nt + k + 1, &mut x)?;
                Ok(x[0])
            })
            .collect()
    }

    /// Quantity `qi`, stored after `base` series values as (value, code) pairs.
    pub(crate) fn quantity(&self, base: usize, qi: usize) -> Result<QuantityRuns, AnalysisError> {
        let mut out = QuantityRuns {
            rows: Vec::new(),
            valid: Vec::new(),
            never_hunts: 0,
            never_stops: 0,
        };
        for (&row, v) in self.rows.iter().zip(&self.values) {
            let mut pair = [0.0; 2];
            v.try_read_into(base + 2 * qi..base + 2 * qi + 2, &mut pair)?;
            match Code::from_f64(pair[1]) {
                Code::Ok => {
                    out.rows.push(row);
                    out.valid.push(pair[0]);
                }
                Code::NeverHunts => out.never_hunts += 1,
                Code::NeverStops => out.never_stops += 1,
            }
        }
        Ok(out)
    }
}
