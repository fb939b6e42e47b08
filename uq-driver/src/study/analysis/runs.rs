//! The successful runs of a study as the analysis reads them from the results store: a block
//! of time columns of an output, one column, or a scalar quantity with its outcome codes.

use nalgebra::DMatrix;
use rayon::prelude::*;

use super::AnalysisError;
use crate::qoi::evaluate::Code;
use crate::study::store::{StoredRuns, Values};

/// Runs read by one task of [`Runs::block`].
const CHUNK_RUNS: usize = 256;
/// Runs read before their values are transposed into the block (8 values of a column make
/// one cache line).
const STEP_RUNS: usize = 8;

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

    /// [`Runs::of`], refused when fewer than `min` points have a valid run.
    pub(crate) fn at_least(stored: &'a StoredRuns, min: usize) -> Result<Runs<'a>, AnalysisError> {
        let runs = Runs::of(stored);
        if runs.rows.len() < min {
            return Err(AnalysisError::TooFewRuns {
                ok: runs.rows.len(),
            });
        }
        Ok(runs)
    }

    /// Output `o` (of `nt` times each) as runs × times.
    pub(crate) fn output(&self, o: usize, nt: usize) -> Result<DMatrix<f64>, AnalysisError> {
        self.block(o, nt, 0, nt)
    }

    /// Columns `j0..j0 + w` of output `o` (of `nt` times each) as runs × times. Chunks of
    /// runs are read in parallel, one positioned read per run, a few runs at a time into a
    /// small buffer, and each buffer is transposed straight into the chunk's rows of the
    /// matrix (no intermediate copy of the block).
    pub(crate) fn block(
        &self,
        o: usize,
        nt: usize,
        j0: usize,
        w: usize,
    ) -> Result<DMatrix<f64>, AnalysisError> {
        let n = self.rows.len();
        if n == 0 || w == 0 {
            return Ok(DMatrix::zeros(n, w));
        }
        let first = o * nt + j0;
        let mut data = vec![0.0; n * w];
        // Per chunk of runs, its part of every column (disjoint borrows of the matrix).
        let mut parts: Vec<Vec<&mut [f64]>> = (0..n.div_ceil(CHUNK_RUNS))
            .map(|_| Vec::with_capacity(w))
            .collect();
        for col in data.chunks_exact_mut(n) {
            for (c, part) in col.chunks_mut(CHUNK_RUNS).enumerate() {
                parts[c].push(part);
            }
        }
        self.values
            .par_chunks(CHUNK_RUNS)
            .zip(parts.par_iter_mut())
            .try_for_each(|(values, parts)| {
                let mut buf = vec![0.0; STEP_RUNS * w];
                for (s, step) in values.chunks(STEP_RUNS).enumerate() {
                    for (v, row) in step.iter().zip(buf.chunks_exact_mut(w)) {
                        v.try_read_into(first..first + w, row)?;
                    }
                    let r0 = s * STEP_RUNS;
                    for (k, part) in parts.iter_mut().enumerate() {
                        let out = &mut part[r0..r0 + step.len()];
                        for (i, x) in out.iter_mut().enumerate() {
                            *x = buf[i * w + k];
                        }
                    }
                }
                Ok::<(), AnalysisError>(())
            })?;
        Ok(DMatrix::from_vec(n, w, data))
    }

    /// Column `k` of output `o` (of `nt` times each) over the runs (read in parallel).
    pub(crate) fn column(&self, o: usize, nt: usize, k: usize) -> Result<Vec<f64>, AnalysisError> {
        self.values
            .par_iter()
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
        // The pairs read in parallel, then sorted out in order.
        let pairs = self
            .values
            .par_iter()
            .map(|v| {
                let mut pair = [0.0; 2];
                v.try_read_into(base + 2 * qi..base + 2 * qi + 2, &mut pair)?;
                Ok(pair)
            })
            .collect::<Result<Vec<_>, AnalysisError>>()?;
        for (&row, pair) in self.rows.iter().zip(pairs) {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::study::store::Record;

    #[test]
    fn blocks_read_in_steps_of_runs_hold_every_value_in_its_place() {
        // Regression: a block is read a few runs at a time and transposed straight into the
        // matrix. Every entry must be the run's value at that column: 601 points (not a
        // multiple of the chunk or step), some failed or not run, 2 outputs of 7 times,
        // blocks at either output, of any width.
        let (outputs, nt) = (2, 7);
        let value = |i: usize, v: usize| (i * 1000 + v) as f64 + 0.5;
        let records: Vec<Option<Record>> = (0..601)
            .map(|i| match i % 11 {
                3 => None,
                7 => Some(Record::Failed("diverged".into())),
                _ => Some(Record::Ok((0..outputs * nt).map(|v| value(i, v)).collect())),
            })
            .collect();
        let stored = StoredRuns::from_records(&records, outputs * nt);
        let runs = Runs::of(&stored);
        let ok = (0..601).filter(|i| i % 11 != 3 && i % 11 != 7).count();
        assert_eq!(runs.rows.len(), ok);
        for (o, j0, w) in [(0, 0, 7), (1, 0, 7), (1, 2, 3), (0, 6, 1), (1, 3, 0)] {
            let m = runs.block(o, nt, j0, w).unwrap();
            assert_eq!((m.nrows(), m.ncols()), (runs.rows.len(), w));
            for (r, &i) in runs.rows.iter().enumerate() {
                for k in 0..w {
                    assert_eq!(m[(r, k)], value(i, o * nt + j0 + k), "run {i}, column {k}");
                }
            }
        }
        assert_eq!(
            runs.column(1, nt, 4).unwrap(),
            runs.rows
                .iter()
                .map(|&i| value(i, nt + 4))
                .collect::<Vec<_>>()
        );
    }
}
