//! What the size estimate needs to know of a study ([`Shape`]), from its settings alone.

use super::chaos::ChaosShape;
use super::Memory;
use crate::qoi::QoiSpec;
use crate::spec::Study;
use crate::study::analysis::blocks;
use crate::uq::method::Evaluation;

/// What the estimate needs to know of a study.
#[derive(Clone, Copy, Debug)]
pub struct Shape {
    /// Model runs, if known.
    pub runs: Option<f64>,
    /// Communication points per run.
    pub time_points: f64,
    /// Stored outputs.
    pub outputs: usize,
    /// Scalar quantities.
    pub quantities: usize,
    /// Signals read at every step (outputs and the quantities' signals).
    pub signals: usize,
    /// Random parameters.
    pub dim: usize,
    /// Worker threads.
    pub threads: usize,
    /// Draws of a chaos surrogate per output (`[analysis] surrogate_samples`; 0 for a method
    /// that draws from its runs).
    pub surrogate_samples: usize,
    /// Simulated time of a point over that of its run: 1, plus the runs of its own of each
    /// `hunting_speed` quantity.
    pub cost_factor: f64,
    /// Surrogate draws of a time series (`min(series_samples, surrogate_samples)`; 0 for a
    /// method that draws from its runs).
    pub series_draws: usize,
    /// Columns whose densities are shown (`pdf_times + 1`).
    pub pdf_columns: usize,
    /// Points of each density's grid (`pdf_grid`).
    pub pdf_grid: usize,
    /// Whether the method estimates Sobol' indices over time (a chaos, `sobol_sampling`).
    pub sobol: bool,
    /// Quantile levels.
    pub quantile_levels: usize,
    /// The analysis's block budget (bytes; [`blocks::block_bytes`]).
    pub block_bytes: f64,
    /// Whether the whole series of an output is analysed at once (nested studies).
    pub whole_series: bool,
    /// The chaos of a method whose arrays grow with its terms (`sparse_grid`,
    /// `pce_regression`).
    pub chaos: Option<ChaosShape>,
}

impl Shape {
    /// The shape of `study` run on `threads` threads.
    pub fn of(study: &Study, threads: usize) -> Shape {
        let (runs, chaos, sobol, whole_series) = match study.method().evaluation() {
            Evaluation::Sampling(m) => (
                m.planned_runs_for(&study.parameters),
                m.draws_from_chaos(),
                m.estimates_sobol(),
                m.whole_series(),
            ),
            Evaluation::Intrusive(_) => (Some(0.0), true, true, false),
            Evaluation::Adaptive(a) => {
                let targets = study.adaptive_targets().map_or(0, |t| t.len());
                (
                    Some(a.0.expected_runs(study.parameters.len(), targets)),
                    false,
                    false,
                    false,
                )
            }
        };
        let mut signals: Vec<&str> = study.outputs.iter().map(String::as_str).collect();
        for s in study.qoi.iter().flat_map(|q| q.signals()) {
            if !signals.contains(&s) {
                signals.push(s);
            }
        }
        let e = &study.experiment;
        let own_runs: f64 = study
            .qoi
            .iter()
            .filter_map(|q| match q {
                QoiSpec::HuntingSpeed(h) => Some(h.runs_when_found() as f64 * h.duration),
                _ => None,
            })
            .sum();
        Shape {
            runs,
            time_points: ((e.stop - e.start) / e.step).round() + 1.0,
            outputs: study.outputs.len(),
            quantities: study.qoi.iter().map(|q| q.quantity_names().len()).sum(),
            signals: signals.len(),
            dim: study.parameters.len(),
            threads: threads.max(1),
            surrogate_samples: if chaos {
                study.analysis.surrogate_samples
            } else {
                0
            },
            cost_factor: 1.0 + own_runs / (e.stop - e.start),
            series_draws: if chaos {
                study
                    .analysis
                    .series_samples
                    .min(study.analysis.surrogate_samples)
            } else {
                0
            },
            pdf_columns: study.analysis.pdf_times + 1,
            pdf_grid: study.analysis.pdf_grid,
            sobol,
            quantile_levels: study.analysis.quantiles.len(),
            block_bytes: blocks::block_bytes() as f64,
            whole_series,
            chaos: ChaosShape::of(study),
        }
    }

    /// The memory estimate for `runs` runs (see the module documentation).
    pub fn memory(&self, runs: f64) -> Memory {
        let (n, nt) = (runs, self.time_points);
        let (s, d) = (self.outputs as f64, self.dim as f64);
        let draws = self.series_draws as f64;
        let scalars = 1.5 * 8.0 * n + 8.0 * self.surrogate_samples as f64;
        let k = self.quantile_levels as f64;
        // The densities shown: at most `pdf_columns` columns (never more than there are).
        let pdf_columns = (self.pdf_columns as f64).min(nt);
        // Kept for every output until the report: its statistics over time (times, mean,
        // Std, the 3σ band, the standard error or the chaos's Std, the chaos error, the
        // quantiles; the Sobol' indices and their intervals, a few small vectors per
        // column), and its densities (with their rows and the text of one being written:
        // Measured: about 1.4 × 8 P G per output).
        let sobol = if self.sobol { 6.0 * d + 20.0 } else { 0.0 };
        let kept_per_output =
            8.0 * nt * (8.0 + k + sobol) + 1.5 * 8.0 * pdf_columns * self.pdf_grid as f64;
        // The output being analysed: its column summaries (a small struct and the
        // quantiles' vector per column) and the draws kept for its densities.
        let current = 8.0 * nt * (10.0 + k) + 8.0 * pdf_columns * n.max(draws);
        let series = if self.outputs == 0 {
            0.0
        } else if self.whole_series {
            // The pooled series of an output and the estimator's copies of it
            // (2.0 × 8 n nt measured at 20 000 × 10⁴ and 1000 × 10⁵).
            2.5 * 8.0 * n * nt + 8.0 * draws * nt + current + s * kept_per_output
        } else {
            let w = block_columns(nt, n, self.block_bytes);
            let w_draws = block_columns(nt, draws, self.block_bytes);
            3.0 * 8.0 * n * w + 2.0 * 8.0 * draws * w_draws + current + s * kept_per_output
        };
        // The workers' buffers are freed when the runs end, before the analysis starts.
        let workers = 3.0 * 8.0 * (self.threads * self.signals) as f64 * nt;
        Memory {
            records: n * (96.0 + 16.0 * self.quantities as f64),
            store: 0.0,
            analysis: series.max(scalars).max(workers),
            design: 4.0 * n * (8.0 * d + 24.0),
            grid: 4.0 * 8.0 * nt,
            chaos: self.chaos.map_or(0.0, |c| {
                c.memory(n, nt, block_columns(nt, n, self.block_bytes))
            }),
        }
    }
}

/// The columns of a block of `rows` rows out of `nt` within `budget` bytes: as
/// [`blocks::block_width`], in floating point (the counts may be beyond any integer type).
pub(super) fn block_columns(nt: f64, rows: f64, budget: f64) -> f64 {
    let align = blocks::BLOCK_ALIGN as f64;
    let w = (budget / (2.0 * 8.0 * rows.max(1.0))).floor();
    if w >= nt {
        return nt.max(1.0);
    }
    ((w / align).floor() * align).max(align)
}
