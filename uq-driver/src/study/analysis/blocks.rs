//! The analysis of a time series in blocks of time columns, so that the runs of an output
//! need not fit in memory.
//!
//! Every estimator works column by column, so an output is estimated on `n × B` blocks of
//! its runs (read from the results store) and the per-column results are concatenated
//! ([`merge`]); the column summaries (quantiles, range, bandwidth) are taken per block, and
//! the densities from the draws of at most `pdf_times` columns kept on the way
//! (`SeriesColumns`). A chaos's surrogate draws are taken per block of its columns too.
//!
//! Block size: a block and one copy of it by the estimator stay within [`block_bytes`]
//! ([`BLOCK_BYTES`], 256 MiB, or [`BLOCK_SHARE`] of the memory available to the process,
//! whichever is less: a study under a memory limit analyses in smaller blocks instead of
//! failing an allocation; `RAILUQ_ANALYSIS_BLOCK_BYTES` overrides both). A block
//! is a whole multiple of [`BLOCK_ALIGN`] columns (at least that many, even beyond the
//! budget), or the whole series: the surrogate draws multiply the basis by the coefficients
//! in tasks of 32 columns (`surrogate.rs`), and blocks that split at the same columns give the
//! same products bit for bit. The results do not depend on the block size.

use nalgebra::DMatrix;
use rayon::prelude::*;

use super::columns::{column, Column};
use crate::study::plan::size::available_memory;
use crate::uq::method::{ChaosError, Estimate, MethodError, Sobol, SobolIntervals};
use crate::uq::pce::Pce;

/// Bytes of a block of runs (or draws) and of its copy, by default (256 MiB).
pub const BLOCK_BYTES: usize = 256 << 20;
/// Blocks are whole multiples of this many columns.
pub const BLOCK_ALIGN: usize = 32;

/// The share of the available memory a block and its copy may take (an eighth: the block is
/// held about 1.5 times over, a chaos's draws as much again, and the rest of the study and
/// the allocator's own reservations need room too).
pub const BLOCK_SHARE: f64 = 0.125;

/// The block budget (bytes): `RAILUQ_ANALYSIS_BLOCK_BYTES` if set to a number, else the least
/// of [`BLOCK_BYTES`] and [`BLOCK_SHARE`] of the memory available to the process now
/// ([`available_memory`]).
pub fn block_bytes() -> usize {
    block_bytes_for(available_memory())
}

/// [`block_bytes`] with `available` bytes of memory (`None`: not known).
pub(crate) fn block_bytes_for(available: Option<f64>) -> usize {
    if let Some(b) = std::env::var("RAILUQ_ANALYSIS_BLOCK_BYTES")
        .ok()
        .and_then(|v| v.trim().parse().ok())
    {
        return b;
    }
    match available {
        // A block never goes below BLOCK_ALIGN columns (block_width), whatever this says.
        Some(a) if a >= 0.0 => BLOCK_BYTES.min((a * BLOCK_SHARE) as usize),
        _ => BLOCK_BYTES,
    }
}

/// Columns per block of `rows` rows out of `nt` columns (see the module documentation).
pub fn block_width(nt: usize, rows: usize) -> usize {
    block_width_in(nt, rows, block_bytes())
}

/// [`block_width`] within a budget of `budget` bytes.
pub(crate) fn block_width_in(nt: usize, rows: usize, budget: usize) -> usize {
    let per_column = 2 * 8 * rows.max(1);
    let w = budget / per_column;
    if w >= nt {
        return nt.max(1);
    }
    (w / BLOCK_ALIGN * BLOCK_ALIGN).max(BLOCK_ALIGN)
}

/// The blocks `(first column, width)` of `nt` columns, `width` wide (the last narrower).
pub fn blocks(nt: usize, width: usize) -> impl Iterator<Item = (usize, usize)> {
    (0..nt)
        .step_by(width.max(1))
        .map(move |j0| (j0, width.min(nt - j0)))
}

/// The estimate of every column from the estimates of consecutive blocks of columns: per
/// column values concatenated, the chaoses joined into one over the union of their bases
/// (the same chaos as an estimate of all columns at once gives).
pub fn merge(mut parts: Vec<Estimate>) -> Result<Estimate, MethodError> {
    if parts.len() <= 1 {
        return parts.pop().ok_or_else(|| {
            MethodError::Invalid(crate::uq::method::InvalidSettings(
                "no column to estimate".into(),
            ))
        });
    }
    fn cat<T: Clone>(
        parts: &[Estimate],
        f: impl Fn(&Estimate) -> Option<&Vec<T>>,
    ) -> Option<Vec<T>> {
        let mut out = Vec::new();
        for p in parts {
            out.extend_from_slice(f(p)?);
        }
        Some(out)
    }
    let first = &parts[0];
    let sobol = first.sobol.as_ref().map(|s0| Sobol {
        first: cat(&parts, |p| p.sobol.as_ref().map(|s| &s.first)).unwrap_or_default(),
        total: cat(&parts, |p| p.sobol.as_ref().map(|s| &s.total)).unwrap_or_default(),
        intervals: s0.intervals.as_ref().map(|i0| SobolIntervals {
            level: i0.level,
            first: cat(&parts, |p| {
                p.sobol.as_ref()?.intervals.as_ref().map(|i| &i.first)
            })
            .unwrap_or_default(),
            total: cat(&parts, |p| {
                p.sobol.as_ref()?.intervals.as_ref().map(|i| &i.total)
            })
            .unwrap_or_default(),
        }),
        given_data: s0.given_data,
    });
    let chaos_error = first.chaos_error.as_ref().map(|e0| ChaosError {
        kind: e0.kind,
        values: cat(&parts, |p| p.chaos_error.as_ref().map(|e| &e.values)).unwrap_or_default(),
        check: cat(&parts, |p| {
            p.chaos_error.as_ref().and_then(|e| e.check.as_ref())
        }),
    });
    let chaos = match first.chaos {
        Some(_) => {
            let pces: Vec<&Pce> = parts.iter().filter_map(|p| p.chaos.as_ref()).collect();
            Some(merge_chaos(&pces)?)
        }
        None => None,
    };
    Ok(Estimate {
        mean: cat(&parts, |p| Some(&p.mean)).unwrap_or_default(),
        std: cat(&parts, |p| Some(&p.std)).unwrap_or_default(),
        std_error_mean: cat(&parts, |p| p.std_error_mean.as_ref()),
        std_chaos: cat(&parts, |p| p.std_chaos.as_ref()),
        chaos,
        sobol,
        draws: first.draws,
        chaos_error,
    })
}

/// One chaos of the columns of `pces` side by side: the coefficients joined when the bases
/// agree, else placed on the union of the bases (graded order, as [`Pce::from_columns`]
/// orders a union of per-column sets).
fn merge_chaos(pces: &[&Pce]) -> Result<Pce, MethodError> {
    let basis = &pces[0].basis;
    let cols: usize = pces.iter().map(|p| p.coeffs.ncols()).sum();
    if pces.iter().all(|p| &p.basis == basis) {
        let mut coeffs = DMatrix::<f64>::zeros(basis.len(), cols);
        let mut j = 0;
        for p in pces {
            let w = p.coeffs.ncols();
            coeffs.columns_mut(j, w).copy_from(&p.coeffs);
            j += w;
        }
        return Ok(Pce::new(basis.clone(), coeffs)?);
    }
    let columns: Vec<(Vec<Vec<usize>>, Vec<f64>)> = pces
        .iter()
        .flat_map(|p| {
            let indices = p.basis.set().indices().to_vec();
            p.coeffs
                .column_iter()
                .map(move |c| (indices.clone(), c.iter().copied().collect()))
        })
        .collect();
    Ok(Pce::from_columns(basis.families().to_vec(), &columns)?)
}

/// The column summaries of a series taken block by block, and the draws of the columns
/// whose densities are shown: at most `pdf_times + 1` evenly spaced (with the last), and
/// the columns where a feature of the series is extreme ([`SeriesColumns::picked`]).
pub(super) struct SeriesColumns {
    /// Summaries of the columns seen so far, in order.
    pub(super) cols: Vec<Column>,
    /// The evenly spaced columns whose densities may be shown.
    candidates: Vec<usize>,
    /// Their draws, in the order of `candidates` (as far as seen).
    kept: Vec<Vec<f64>>,
    quantiles: Vec<f64>,
    /// Per feature ([`features`]): the first column where it is largest so far, with its
    /// draws.
    extremes: Vec<Option<Extreme>>,
}

/// The column where a feature of the series is largest (the first such), and its draws.
struct Extreme {
    index: usize,
    score: f64,
    draws: Vec<f64>,
}

/// The features of a column whose extreme columns get a density: the least and the
/// greatest of each quantile and of the mean, and the largest Std (each as a score to
/// maximise).
fn features(c: &Column) -> Vec<f64> {
    let mut f: Vec<f64> = c.quantiles.iter().flat_map(|&q| [-q, q]).collect();
    f.extend([-c.mean, c.mean, c.std]);
    f
}

impl SeriesColumns {
    /// For `nt` columns, densities at `candidates`, quantiles at `quantiles`.
    pub(super) fn new(nt: usize, candidates: Vec<usize>, quantiles: &[f64]) -> SeriesColumns {
        SeriesColumns {
            cols: Vec::with_capacity(nt),
            candidates,
            kept: Vec::new(),
            quantiles: quantiles.to_vec(),
            extremes: Vec::new(),
        }
    }

    /// Adds the next block of columns (draws in rows), starting at column `j0`; every column
    /// is summarised in parallel.
    pub(super) fn add(&mut self, j0: usize, samples: &DMatrix<f64>) {
        self.add_slice(j0, samples.nrows(), samples.as_slice());
    }

    /// [`SeriesColumns::add`] of a column-major block of `rows` rows held in `all`.
    pub(super) fn add_slice(&mut self, j0: usize, rows: usize, all: &[f64]) {
        debug_assert_eq!(j0, self.cols.len());
        let ncols = all.len() / rows.max(1);
        let qs = &self.quantiles;
        let new: Vec<Column> = (0..ncols)
            .into_par_iter()
            .map(|k| column(&all[k * rows..(k + 1) * rows], qs))
            .collect();
        self.cols.extend(new);
        let end = j0 + ncols;
        for &c in self.candidates.iter().filter(|&&c| (j0..end).contains(&c)) {
            self.kept
                .push(all[(c - j0) * rows..(c - j0 + 1) * rows].to_vec());
        }
        self.update_extremes(j0, &|k| all[(k - j0) * rows..(k - j0 + 1) * rows].to_vec());
    }

    /// Updates the extreme columns with the columns from `j0` on (the last block added);
    /// `draws(k)` gives the draws of column `k` of that block. The first column wins a tie,
    /// so the choice does not depend on the blocks.
    fn update_extremes(&mut self, j0: usize, draws: &dyn Fn(usize) -> Vec<f64>) {
        for (k, c) in self.cols.iter().enumerate().skip(j0) {
            let f = features(c);
            if self.extremes.len() < f.len() {
                self.extremes.resize_with(f.len(), || None);
            }
            for (e, score) in self.extremes.iter_mut().zip(f) {
                let better = match e {
                    Some(e) => score > e.score,
                    None => !score.is_nan(),
                };
                if better {
                    // Draws are copied once the block's best is known (below).
                    *e = Some(Extreme {
                        index: k,
                        score,
                        draws: Vec::new(),
                    });
                }
            }
        }
        for e in self.extremes.iter_mut().flatten() {
            if e.index >= j0 && e.draws.is_empty() {
                e.draws = draws(e.index);
            }
        }
    }

    /// Adds the next `ncols` columns of `rows` draws, starting at column `j0`, generated in
    /// parallel tasks of `task` columns: `fill(j, buf)` writes columns `j..j + w` (column-major)
    /// into a buffer of the thread, and they are summarised while still in cache. The same
    /// summaries as [`SeriesColumns::add_slice`] of all the columns at once (the draws of a
    /// new extreme column are generated again, by its task).
    pub(super) fn add_generated(
        &mut self,
        j0: usize,
        rows: usize,
        ncols: usize,
        task: usize,
        fill: &(dyn Fn(usize, &mut [f64]) + Sync),
    ) {
        debug_assert_eq!(j0, self.cols.len());
        let task = task.max(1);
        let (qs, candidates) = (&self.quantiles, &self.candidates);
        let parts: Vec<(Vec<Column>, Vec<Vec<f64>>)> = (0..ncols.div_ceil(task))
            .into_par_iter()
            .map_init(Vec::new, |buf: &mut Vec<f64>, t| {
                let (j, w) = (j0 + t * task, task.min(ncols - t * task));
                buf.resize(rows * w, 0.0);
                fill(j, &mut buf[..rows * w]);
                let cols = (0..w)
                    .map(|k| column(&buf[k * rows..(k + 1) * rows], qs))
                    .collect();
                let kept = candidates
                    .iter()
                    .filter(|&&c| (j..j + w).contains(&c))
                    .map(|&c| buf[(c - j) * rows..(c - j + 1) * rows].to_vec())
                    .collect();
                (cols, kept)
            })
            .collect();
        for (cols, kept) in parts {
            self.cols.extend(cols);
            self.kept.extend(kept);
        }
        self.update_extremes(j0, &|k| {
            let j = j0 + (k - j0) / task * task;
            let w = task.min(j0 + ncols - j);
            let mut buf = vec![0.0; rows * w];
            fill(j, &mut buf);
            buf[(k - j) * rows..(k - j + 1) * rows].to_vec()
        });
    }

    /// The columns whose densities are shown, ascending, with their draws: the evenly spaced
    /// ones, each extreme column taking the place of the nearest of them (so that a short
    /// event, a peak between two evenly spaced columns, is among them; the count grows only
    /// when two extremes would take the same place).
    pub(super) fn picked(self) -> (Vec<usize>, Vec<Vec<f64>>) {
        let mut chosen: Vec<(usize, Vec<f64>, bool)> = self
            .candidates
            .into_iter()
            .zip(self.kept)
            .map(|(k, d)| (k, d, false))
            .collect();
        for e in self.extremes.into_iter().flatten() {
            if let Some(c) = chosen.iter_mut().find(|c| c.0 == e.index) {
                c.2 = true;
                continue;
            }
            let nearest = chosen
                .iter_mut()
                .filter(|c| !c.2)
                .min_by_key(|c| c.0.abs_diff(e.index));
            match nearest {
                Some(c) => *c = (e.index, e.draws, true),
                None => chosen.push((e.index, e.draws, true)),
            }
        }
        chosen.sort_by_key(|c| c.0);
        chosen.into_iter().map(|(k, d, _)| (k, d)).unzip()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::uq::pce::{Basis, Family, MultiIndexSet};

    #[test]
    fn blocks_cover_the_columns_in_aligned_widths() {
        assert_eq!(
            blocks(70, 32).collect::<Vec<_>>(),
            vec![(0, 32), (32, 32), (64, 6)]
        );
        assert_eq!(blocks(5, 5).collect::<Vec<_>>(), vec![(0, 5)]);
        // A block of 10 000 rows of 501 columns fits the default budget: one block.
        assert_eq!(block_width_in(501, 10_000, BLOCK_BYTES), 501);
        // 10^6 rows: 16 MB per column, 16 columns fit; at least 32 are taken.
        assert_eq!(block_width_in(100_000, 1_000_000, BLOCK_BYTES), 32);
        assert_eq!(
            block_width_in(100_000, 10_000, BLOCK_BYTES) % BLOCK_ALIGN,
            0
        );
    }

    /// Under a memory limit (`ulimit -v`) a study whose estimate fitted ran all its runs,
    /// then aborted in the analysis ("memory allocation failed"): its blocks took 256 MiB
    /// whatever the limit. They now take at most an eighth of the memory available.
    #[test]
    fn blocks_shrink_to_the_memory_available() {
        if std::env::var_os("RAILUQ_ANALYSIS_BLOCK_BYTES").is_some() {
            return;
        }
        const MIB: f64 = 1024.0 * 1024.0;
        assert_eq!(block_bytes_for(None), BLOCK_BYTES);
        assert_eq!(block_bytes_for(Some(16.0 * 1024.0 * MIB)), BLOCK_BYTES);
        assert_eq!(block_bytes_for(Some(512.0 * MIB)), 64 << 20);
        // 400 runs of 100 001 points: 6.4 kB per column (the block and its copy); 64 MiB
        // holds 10 464 columns (a multiple of 32), 256 MiB held 41 920.
        let w = block_width_in(100_001, 400, block_bytes_for(Some(512.0 * MIB)));
        assert_eq!(w, 10_464);
        assert_eq!(block_bytes_for(Some(0.0)), 0);
        assert_eq!(
            block_width_in(100_001, 400, 0),
            BLOCK_ALIGN,
            "never below 32 columns"
        );
    }

    #[test]
    fn generated_column_tasks_summarise_as_the_whole_block() {
        // 70 columns of 50 rows: tasks of 32 (the last one short), candidates across tasks.
        let (rows, nt) = (50, 70);
        let all: Vec<f64> = (0..rows * nt)
            .map(|i| ((i * 7919) % 1013) as f64 / 17.0 - (i / rows) as f64)
            .collect();
        let candidates = vec![0, 31, 32, 63, 64, 69];
        let mut whole = SeriesColumns::new(nt, candidates.clone(), &[0.01, 0.5, 0.99]);
        whole.add_slice(0, rows, &all);
        let mut tasks = SeriesColumns::new(nt, candidates, &[0.01, 0.5, 0.99]);
        tasks.add_generated(0, rows, nt, 32, &|j, buf| {
            buf.copy_from_slice(&all[j * rows..j * rows + buf.len()])
        });
        assert_eq!(format!("{:?}", whole.cols), format!("{:?}", tasks.cols));
        assert_eq!(whole.kept, tasks.kept);
        assert_eq!(tasks.kept.len(), 6);
        assert_eq!(whole.picked(), tasks.picked());
    }

    /// A two-column event between evenly spaced columns is among the picked
    /// columns (the extremes of its quantiles, mean and Std), whatever the blocks.
    #[test]
    fn picked_columns_catch_a_short_event_whatever_the_blocks() {
        let (rows, nt) = (40, 1000);
        // A slow ramp, and at columns 505 and 506 a peak with a larger spread.
        let all: Vec<f64> = (0..rows * nt)
            .map(|i| {
                let (k, r) = (i / rows, (i % rows) as f64);
                let base = k as f64 * 1e-3 + 0.01 * (r * 0.37).sin();
                match k {
                    505 => base + 50.0 + r,
                    506 => base - 30.0 - 0.5 * r,
                    _ => base,
                }
            })
            .collect();
        let even: Vec<usize> = (0..nt).step_by(10).chain([nt - 1]).collect();
        let qs = [0.01, 0.5, 0.99];
        let mut whole = SeriesColumns::new(nt, even.clone(), &qs);
        whole.add_slice(0, rows, &all);
        let mut blocked = SeriesColumns::new(nt, even.clone(), &qs);
        for (j0, w) in blocks(nt, 96) {
            blocked.add_slice(j0, rows, &all[j0 * rows..(j0 + w) * rows]);
        }
        let mut generated = SeriesColumns::new(nt, even.clone(), &qs);
        for (j0, w) in blocks(nt, 64) {
            generated.add_generated(j0, rows, w, 32, &|j, buf| {
                buf.copy_from_slice(&all[j * rows..j * rows + buf.len()])
            });
        }
        let picked = whole.picked();
        assert!(
            picked.0.contains(&505) && picked.0.contains(&506),
            "{:?}",
            picked.0
        );
        // The extremes take the places of their nearest evenly spaced columns.
        assert_eq!(picked.0.len(), even.len());
        assert!(picked.0.windows(2).all(|w| w[0] < w[1]));
        let k = picked.0.iter().position(|&c| c == 505).unwrap();
        assert_eq!(picked.1[k], all[505 * rows..506 * rows].to_vec());
        assert_eq!(blocked.picked(), picked);
        assert_eq!(generated.picked(), picked);
    }

    #[test]
    fn sparse_chaoses_of_column_blocks_join_into_the_chaos_of_all_columns() {
        // Per-column sets, as sparse regression gives them.
        let sets: Vec<(Vec<Vec<usize>>, Vec<f64>)> = vec![
            (vec![vec![0, 0], vec![1, 0]], vec![1.0, 0.5]),
            (vec![vec![0, 0], vec![0, 2]], vec![2.0, -0.25]),
            (
                vec![vec![0, 0], vec![1, 1], vec![1, 0]],
                vec![3.0, 0.125, 0.75],
            ),
        ];
        let families = vec![Family::Hermite, Family::Legendre];
        let all = Pce::from_columns(families.clone(), &sets).unwrap();
        let a = Pce::from_columns(families.clone(), &sets[..1]).unwrap();
        let b = Pce::from_columns(families.clone(), &sets[1..]).unwrap();
        assert_ne!(a.basis, b.basis);
        assert_eq!(merge_chaos(&[&a, &b]).unwrap(), all);
        // The same basis: coefficients side by side.
        let basis = Basis::new(families, MultiIndexSet::total_degree(2, 2).unwrap()).unwrap();
        let c = DMatrix::from_fn(basis.len(), 3, |t, k| (t * 3 + k) as f64);
        let whole = Pce::new(basis.clone(), c.clone()).unwrap();
        let left = Pce::new(basis.clone(), c.columns(0, 2).into_owned()).unwrap();
        let right = Pce::new(basis, c.columns(2, 1).into_owned()).unwrap();
        assert_eq!(merge_chaos(&[&left, &right]).unwrap(), whole);
    }
}
