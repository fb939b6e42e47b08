//! From a method's estimates to the statistics of the report: quantiles and the PDF evolution
//! of every output, the distribution of every scalar quantity. Quantiles and densities come
//! from the draws the estimate names: the runs, or a large sample of its chaos surrogate.
//! Nothing here depends on which method produced the estimate.

use std::borrow::Cow;

use nalgebra::DMatrix;
use rayon::prelude::*;

pub mod blocks;
mod chaos_gap;
mod chaos_guide;
mod columns;
mod convergence;
mod error;
mod exceedance;
mod functional;
mod given_data;
pub mod nested;
mod runs;
mod series;
mod surrogate;
#[cfg(test)]
mod truncation_checks;

pub(crate) use chaos_gap::{chaos_error_warnings, chaos_gap_warnings, series_error, CHAOS_ERROR};
pub(crate) use chaos_guide::guide_tails;
pub use error::AnalysisError;
pub(crate) use error::{output_error, quantity_error};
#[cfg(test)]
pub use exceedance::exceedance_count;
pub use exceedance::{count_on_side, counted_probabilities, nest_exceedance_count};

use blocks::SeriesColumns;
use columns::{column, Column};
use convergence::convergence;
use series::{equal_column, output_in_blocks};
pub(crate) use surrogate::Surrogates;

pub(crate) use runs::{QuantityRuns, Runs};

use super::store::StoredRuns;
use crate::qoi::kde::{self, KdeKind};
use crate::qoi::QoiSpec;
use crate::results::{ExceedanceCount, OutputStats, ScalarChaosError, ScalarStats, SobolSummary};
use crate::spec::{Analysis, Study};
use crate::uq::distributions::RandomParameter;
use crate::uq::method::{Design, Draws, Estimate, Sampling, Sobol, Solution};
use crate::uq::reliability::Side;
use crate::uq::surrogate::NamedChaos;

/// Offset of the surrogate's random streams from the design's (independent draws).
pub(crate) const SURROGATE_SEED: u64 = 0x5eed_5a4d_0000_0000;

/// The analysis settings of a study, and the surrogate draws it shares.
#[derive(Clone, Copy)]
pub struct Settings<'a> {
    /// `[analysis]`.
    pub analysis: &'a Analysis,
    /// The study's seed.
    pub seed: u64,
    /// The names of the random parameters, in study order (labels of Sobol' indices).
    pub parameters: &'a [RandomParameter],
    /// The method's `kind` (the `method` of probabilities counted over its runs).
    pub kind: &'a str,
    surrogates: &'a Surrogates,
}

impl<'a> Settings<'a> {
    /// The settings of `study`, drawing from `surrogates`.
    pub(crate) fn of(study: &'a Study, surrogates: &'a Surrogates) -> Settings<'a> {
        Settings {
            analysis: &study.analysis,
            seed: study.seed,
            parameters: &study.parameters,
            kind: study.method().kind(),
            surrogates,
        }
    }

    /// The matrix the quantiles and density of a scalar quantity are taken from: `runs`, or
    /// `surrogate_samples` draws of the chaos (a time series: [`chaos_columns`]).
    fn draws<'m>(
        &self,
        name: &str,
        estimate: &Estimate,
        runs: Option<&'m DMatrix<f64>>,
    ) -> Result<Cow<'m, DMatrix<f64>>, AnalysisError> {
        match (estimate.draws, &estimate.chaos, runs) {
            (Draws::Chaos, Some(pce), _) => {
                let n = self.analysis.surrogate_samples;
                Ok(Cow::Owned(self.surrogates.draws(pce, n.max(2))))
            }
            (Draws::Runs, _, Some(r)) => Ok(Cow::Borrowed(r)),
            _ => Err(AnalysisError::NoDraws(name.to_owned())),
        }
    }
}

/// The surrogate draws of `study`: streams independent of the design's, and, when the study
/// has scalar quantities, `surrogate_samples` germ points computed at once.
pub(crate) fn surrogates_of(study: &Study) -> Surrogates {
    let rows = if study.qoi.is_empty() {
        0
    } else {
        study.analysis.surrogate_samples
    };
    Surrogates::new(study.seed ^ SURROGATE_SEED).with_min_rows(rows)
}

/// Column indices of at most `max` evenly spaced columns out of `n`, always with the last.
fn thinned(n: usize, max: usize) -> Vec<usize> {
    if n <= max {
        return (0..n).collect();
    }
    let step = n.div_ceil(max);
    let mut v: Vec<usize> = (0..n).step_by(step).collect();
    if *v.last().expect("n > 0") != n - 1 {
        v.push(n - 1);
    }
    v
}

/// A spread at or below this fraction of the largest magnitude of an output counts as none
/// (a chaos surrogate of a deterministic value scatters at the rounding level of its
/// coefficients).
const ZERO_SPREAD: f64 = 1e-9;

/// Statistics of an output over `times` from its estimate; `runs` are the successful runs
/// (rows) over time (columns), if the model was run.
///
/// Every column is summarised in parallel (quantiles by selection, Silverman's bandwidth),
/// then the densities of at most `pdf_times` columns are taken on one common grid by the
/// binned kernel estimate. A column whose values all agree (to [`ZERO_SPREAD`] of the
/// output's magnitude) has no density: its entries are NaN. The results do not depend on
/// the thread count.
pub(crate) fn output_stats(
    name: &str,
    times: &[f64],
    estimate: &Estimate,
    runs: Option<&DMatrix<f64>>,
    settings: &Settings,
) -> Result<OutputStats, AnalysisError> {
    let mut cols = series_columns(times.len(), settings);
    match (estimate.draws, runs) {
        (Draws::Runs, Some(r)) => cols.add(0, r),
        (Draws::Runs, None) => return Err(AnalysisError::NoDraws(name.to_owned())),
        (Draws::Chaos, _) => chaos_columns(name, estimate, settings, &mut cols)?,
    }
    let run_column =
        |k: usize| Ok(runs.map_or_else(Vec::new, |r| r.column(k).iter().copied().collect()));
    summarise(name, times, estimate, cols, &run_column, settings)
}

/// The estimate's Sobol' indices, NaN where a column has no variance (there they are 0/0:
/// [`Sobol::undefined_without_variance`]).
fn defined_sobol(estimate: &Estimate) -> Option<Sobol> {
    estimate
        .sobol
        .as_ref()
        .map(|s| s.undefined_without_variance(&estimate.mean, &estimate.std))
}

/// `x`, with −0 written as 0 (a standard deviation is never negative).
fn unsigned_zero(x: f64) -> f64 {
    if x == 0.0 {
        0.0
    } else {
        x
    }
}

/// An empty summary of `nt` columns under the settings.
fn series_columns(nt: usize, settings: &Settings) -> SeriesColumns {
    let a = settings.analysis;
    SeriesColumns::new(nt, thinned(nt, a.pdf_times), &a.quantiles)
}

/// The column summaries of a chaos estimate's surrogate draws, a block of columns at a time.
fn chaos_columns(
    name: &str,
    estimate: &Estimate,
    settings: &Settings,
    cols: &mut SeriesColumns,
) -> Result<(), AnalysisError> {
    let Some(pce) = &estimate.chaos else {
        return Err(AnalysisError::NoDraws(name.to_owned()));
    };
    let a = settings.analysis;
    let n = a.series_samples.min(a.surrogate_samples).max(2);
    let nt = pce.coeffs.ncols();
    // Each task of 32 columns draws into a buffer of its thread and summarises the columns
    // while they are in cache: no matrix of every column is allocated. The tasks run in
    // groups of the analysis's block width, so that the buffers in use at once stay within
    // its budget.
    let task = surrogate::COLUMNS_PER_TASK;
    let width = blocks::block_width(nt, n).div_ceil(task) * task;
    for (j0, w) in blocks::blocks(nt, width) {
        cols.add_generated(j0, n, w, task, &|j, buf| {
            settings.surrogates.draws_task(pce, n, j, buf)
        });
    }
    Ok(())
}

/// The statistics of an output from its estimate and the summaries of its draws;
/// `run_column(k)` gives the runs of column `k` (for the convergence of a sampled estimate).
fn summarise(
    name: &str,
    times: &[f64],
    estimate: &Estimate,
    series: SeriesColumns,
    run_column: &dyn Fn(usize) -> Result<Vec<f64>, AnalysisError>,
    settings: &Settings,
) -> Result<OutputStats, AnalysisError> {
    let a = settings.analysis;
    let mut series = series;
    let all_cols = std::mem::take(&mut series.cols);
    let cols = &all_cols;
    let quantiles: Vec<(f64, Vec<f64>)> = a
        .quantiles
        .iter()
        .enumerate()
        .map(|(qi, &p)| (p, cols.iter().map(|c| c.quantiles[qi]).collect()))
        .collect();
    let magnitude = cols
        .iter()
        .map(|c| c.min.abs().max(c.max.abs()))
        .filter(|m| m.is_finite())
        .fold(0.0, f64::max);
    let spread = |c: &Column| c.max - c.min > ZERO_SPREAD * magnitude;
    let deterministic = !cols.iter().any(spread);
    let (picked, kept): (Vec<usize>, Vec<Vec<f64>>) = if deterministic {
        (Vec::new(), Vec::new())
    } else {
        series.picked()
    };
    let (lo, hi) = density_range(estimate, &quantiles, cols, &picked);
    let pad = 0.05 * (hi - lo).max(1e-12 * hi.abs().max(1.0));
    // A quantity whose every picked value is >= 0 is taken as non-negative: its densities
    // are reflected at 0 and the grid starts there.
    let non_negative = picked.iter().all(|&k| cols[k].min >= 0.0);
    let start = if non_negative && lo - pad < 0.0 && hi + pad > 0.0 {
        0.0
    } else {
        lo - pad
    };
    let grid = if picked.is_empty() {
        Vec::new()
    } else {
        kde::auto_grid(start, hi + pad, a.pdf_grid)
    };
    let (g0, g1) = (
        grid.first().copied().unwrap_or(0.0),
        grid.last().copied().unwrap_or(0.0),
    );
    let step = (g1 - g0) / grid.len().saturating_sub(1).max(1) as f64;
    let pdf = picked
        .par_iter()
        .zip(&kept)
        .map(|(&k, col)| {
            if spread(&cols[k]) {
                let h = cols[k].bandwidth;
                // Narrower than the grid: averages over the grid cells keep its mass.
                let kind = if h < 2.0 * step {
                    KdeKind::CellAverages
                } else {
                    KdeKind::Points
                };
                let bound = (cols[k].min >= 0.0).then_some(0.0);
                kde::bounded_kde(col, g0, g1, grid.len(), h, bound, kind)
            } else {
                vec![f64::NAN; grid.len()]
            }
        })
        .collect();
    let (lower_3sigma, upper_3sigma) = OutputStats::band(&estimate.mean, &estimate.std, 3.0);
    let k_max = (0..estimate.std.len())
        .max_by(|&i, &j| estimate.std[i].total_cmp(&estimate.std[j]))
        .filter(|_| !deterministic);
    let convergence = match (k_max, estimate.draws) {
        (Some(k), Draws::Runs) => convergence(estimate, k, &run_column(k)?),
        (Some(k), Draws::Chaos) => convergence(estimate, k, &[]),
        (None, _) => None,
    };
    Ok(OutputStats {
        name: name.to_owned(),
        times: times.to_vec(),
        mean: estimate.mean.clone(),
        std: estimate.std.iter().map(|&s| unsigned_zero(s)).collect(),
        lower_3sigma,
        upper_3sigma,
        quantiles,
        std_pce: estimate.std_chaos.clone(),
        std_error_mean: estimate.std_error_mean.clone(),
        sobol: defined_sobol(estimate),
        pdf_times: picked.iter().map(|&k| times[k]).collect(),
        pdf_grid: grid,
        pdf,
        draws: estimate.draws,
        chaos_error: estimate.chaos_error.clone(),
        deterministic,
        unit: None,
        convergence,
        convergence_time: k_max.map(|k| times[k]),
        functional: None,
    })
}

/// The range of the density grid: the band of the whole series, from the least of its
/// lowest quantile and of μ − 3σ to the greatest of its highest quantile and of μ + 3σ over
/// every time (so that a short event between the columns is inside it); the range of the
/// picked columns' draws where there is no finite band.
fn density_range(
    estimate: &Estimate,
    quantiles: &[(f64, Vec<f64>)],
    cols: &[Column],
    picked: &[usize],
) -> (f64, f64) {
    let (lower, upper) = OutputStats::band(&estimate.mean, &estimate.std, 3.0);
    let lowest = quantiles.iter().min_by(|a, b| a.0.total_cmp(&b.0));
    let highest = quantiles.iter().max_by(|a, b| a.0.total_cmp(&b.0));
    // The finite values of a band and of a quantile's series, folded by `pick` from `start`.
    let extreme =
        |band: &[f64], q: Option<&(f64, Vec<f64>)>, start: f64, pick: fn(f64, f64) -> f64| {
            band.iter()
                .chain(q.map(|q| &q.1).into_iter().flatten())
                .copied()
                .filter(|v| v.is_finite())
                .fold(start, pick)
        };
    let lo = extreme(&lower, lowest, f64::INFINITY, f64::min);
    let hi = extreme(&upper, highest, f64::NEG_INFINITY, f64::max);
    if lo < hi {
        return (lo, hi);
    }
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for &k in picked {
        lo = lo.min(cols[k].min);
        hi = hi.max(cols[k].max);
    }
    (lo, hi)
}

/// Statistics of the scalar quantity `name` (one of those `q` defines) from its estimate and
/// its valid run values; quantiles and the density from `density` where given (e.g. the
/// pooled draws of a nested study), else from the draws the estimate names; the exceedance
/// counted over `independent` where given: the run values that are independent draws of the
/// input law (e.g. the runs of `A` and `B` of a pick-freeze design, whose other blocks reuse
/// their columns), named by `of_what`.
pub(crate) fn scalar_stats(
    name: &str,
    q: &QoiSpec,
    estimate: &Estimate,
    runs: QuantityRuns,
    settings: &Settings,
    density: Option<Vec<f64>>,
    independent: Option<(&[f64], &str)>,
) -> Result<ScalarStats, AnalysisError> {
    let a = settings.analysis;
    let data = DMatrix::from_column_slice(runs.valid.len(), 1, &runs.valid);
    let density_samples: Vec<f64> = match density {
        Some(d) => d,
        None => settings
            .draws(name, estimate, Some(&data))?
            .column(0)
            .iter()
            .copied()
            .collect(),
    };
    let c = column(&density_samples, &a.quantiles);
    let quantiles = a.quantiles.iter().copied().zip(c.quantiles).collect();
    let magnitude = c.min.abs().max(c.max.abs());
    let deterministic = runs.valid.len() < 2 || c.max - c.min <= ZERO_SPREAD * magnitude;
    let (pdf_x, pdf) = if deterministic {
        (Vec::new(), Vec::new())
    } else {
        let bw = c.bandwidth;
        // Every value >= 0: a non-negative quantity, its density reflected at 0.
        let bound = (c.min >= 0.0).then_some(0.0);
        let (lo, hi) = (c.min - 3.0 * bw, c.max + 3.0 * bw);
        let lo = bound.map_or(lo, |b| lo.max(b));
        (
            kde::auto_grid(lo, hi, a.pdf_grid),
            kde::bounded_kde(
                &density_samples,
                lo,
                hi,
                a.pdf_grid,
                bw,
                bound,
                KdeKind::Points,
            ),
        )
    };
    let (smallest, largest) = runs
        .valid
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &x| {
            (lo.min(x), hi.max(x))
        });
    let sides = q
        .limits()
        .iter()
        .map(|&l| (l, Side::Above))
        .chain(q.limits_below().iter().map(|&l| (l, Side::Below)));
    let exceedance_counts: Vec<ExceedanceCount> = sides
        .map(|(l, side)| {
            let mut e = match independent {
                Some((values, of_what)) if estimate.draws == Draws::Runs => {
                    let mut e = count_on_side(values, l, side, Draws::Runs);
                    e.of_what = of_what.to_owned();
                    e
                }
                _ => count_on_side(&density_samples, l, side, estimate.draws),
            };
            // A chaos's draws beyond every model run: its extrapolation alone; or beyond a
            // handful of them: mostly so.
            e.note_range(estimate.draws, [smallest, largest]);
            let beyond = runs
                .valid
                .iter()
                .filter(|&&x| match side {
                    Side::Above => x > l,
                    Side::Below => x < l,
                })
                .count();
            e.note_tail(estimate.draws, beyond, runs.valid.len());
            e
        })
        .collect();
    let exceedance = exceedance_counts
        .iter()
        .filter(|e| !e.is_below())
        .map(|e| {
            let se = (e.p * (1.0 - e.p) / e.of as f64).sqrt();
            (e.limit, e.p, se)
        })
        .collect();
    let valid = runs.valid;
    let sobol = defined_sobol(estimate);
    Ok(ScalarStats {
        name: name.to_owned(),
        mean: estimate.mean[0],
        std: unsigned_zero(estimate.std[0]),
        std_error_mean: estimate.std_error_mean.as_ref().map(|s| s[0]),
        n_valid: valid.len(),
        n_never_hunts: runs.never_hunts,
        n_never_stops: runs.never_stops,
        quantiles,
        min: smallest,
        max: largest,
        exceedance,
        pdf_x,
        pdf,
        deterministic,
        convergence: convergence(estimate, 0, &valid).filter(|_| !deterministic),
        definition: q.definition(),
        unit: None,
        samples: valid,
        density_samples,
        sobol_first: sobol.as_ref().map(|s| s.first[0].clone()),
        // Given data: first-order indices only.
        sobol_total: sobol
            .as_ref()
            .filter(|s| !s.given_data)
            .map(|s| s.total[0].clone()),
        sobol: sobol.as_ref().map(|s| {
            let names: Vec<&str> = settings
                .parameters
                .iter()
                .map(|p| p.name.as_str())
                .collect();
            SobolSummary::of(s, 0, &names)
        }),
        draws: estimate.draws,
        chaos_error: estimate.chaos_error.as_ref().map(|e| ScalarChaosError {
            kind: e.kind.name(),
            value: e.values[0],
            check: e.check.as_ref().map(|c| c[0]),
        }),
        nested: None,
        reliability: (!exceedance_counts.is_empty())
            .then(|| counted_probabilities(&exceedance_counts, settings.kind)),
        exceedance_counts,
        morris: None,
        rank_correlation: None,
        run_inputs: None,
    })
}

/// What an exceedance counted over the runs a method names as its independent draws
/// ([`Sampling::moment_rows`], e.g. `A` and `B` of `sobol_sampling`) counts.
const INDEPENDENT_RUNS: &str = "independent runs (A and B)";

/// What [`analyse_runs`] finds.
#[derive(Clone, Debug)]
pub struct Analysed {
    /// Per output.
    pub outputs: Vec<OutputStats>,
    /// Per scalar quantity.
    pub quantities: Vec<ScalarStats>,
    /// The chaos of each output that has one (chaos methods).
    pub output_chaos: Vec<NamedChaos>,
    /// The chaos of each quantity that has one.
    pub quantity_chaos: Vec<NamedChaos>,
}

/// Statistics of every output and quantity of a study whose points have all been run
/// (`records` holds one record per point of `design`), and the chaoses of a chaos method.
/// Each output is analysed in blocks of time columns ([`blocks`]): its runs need not fit in
/// memory.
pub fn analyse_runs(
    study: &Study,
    method: &dyn Sampling,
    design: &Design,
    records: &StoredRuns,
) -> Result<Analysed, AnalysisError> {
    let surrogates = surrogates_of(study);
    let settings = Settings::of(study, &surrogates);
    let times = study.times();
    let nt = times.len();
    let runs = Runs::at_least(records, method.min_runs())?;
    // A sample of the inputs' law: sensitivity from the runs themselves.
    let given = method.samples_the_law();
    // Over time only up to a length: a row of indices per time costs memory (see
    // `given_data::MAX_SERIES_TIMES`).
    let bins = (given && nt <= given_data::MAX_SERIES_TIMES).then(|| {
        given_data::bins(
            method,
            &given_data::inputs_at(design, &runs.rows),
            &runs.rows,
        )
    });
    let mut outputs = Vec::new();
    let mut estimates = Vec::new();
    // Per output, the hash of every column (a chaos fitted per column): a quantity equal to
    // a column takes that column's estimate.
    let mut hashes: Vec<Vec<u64>> = Vec::new();
    for (o, name) in study.outputs.iter().enumerate() {
        let (estimate, stats, h) = output_in_blocks(
            method,
            (design, bins.as_ref()),
            &runs,
            (o, name, &times),
            &settings,
        )?;
        outputs.push(stats);
        estimates.push(estimate);
        hashes.push(h);
    }
    let base = study.outputs.len() * nt;
    let mut quantities = Vec::new();
    let mut quantity_chaos = Vec::new();
    for (qi, (name, q)) in study.scalar_quantities().enumerate() {
        let qr = runs.quantity(base, qi)?;
        if qr.valid.is_empty() {
            return Err(quantity_error(&name, q, &qr, None));
        }
        let data = DMatrix::from_column_slice(qr.valid.len(), 1, &qr.valid);
        let equal = match qr.rows == runs.rows {
            true => equal_column(&runs, &hashes, nt, &qr.valid)?,
            false => None,
        };
        let mut estimate = match equal {
            Some((o, t)) => functional::select(&estimates[o], &[t]),
            None => method
                .estimate(design, &qr.rows, &data)
                .map_err(|source| quantity_error(&name, q, &qr, Some(source)))?,
        };
        let inputs = given.then(|| given_data::inputs_at(design, &qr.rows));
        let sensitivity = inputs.as_ref().and_then(|x| {
            let bins = given_data::bins(method, x, &qr.rows);
            given_data::scalar(
                x,
                &bins,
                &qr.valid,
                &study.parameters,
                study.seed ^ qi as u64,
            )
        });
        if let Some((sobol, _)) = &sensitivity {
            estimate.sobol = Some(sobol.clone());
        }
        // The running estimate takes the rows the reported mean and Std use.
        let moment_values = method.moment_rows(design, &qr.rows).map(|rows| {
            rows.iter()
                .filter_map(|&r| qr.valid.get(r).copied())
                .collect::<Vec<_>>()
        });
        // A pick-freeze design's exceedance is counted over its independent runs only.
        let independent = moment_values.as_deref().map(|v| (v, INDEPENDENT_RUNS));
        let mut stats = scalar_stats(&name, q, &estimate, qr, &settings, None, independent)?;
        if let Some(values) = moment_values {
            stats.convergence = convergence(&estimate, 0, &values).filter(|_| !stats.deterministic);
        }
        stats.rank_correlation = sensitivity.map(|s| s.1);
        stats.run_inputs = inputs;
        quantities.push(stats);
        if let Some(pce) = estimate.chaos {
            quantity_chaos.push(NamedChaos {
                name: name.clone(),
                times: None,
                pce,
                error: estimate.chaos_error,
            });
        }
    }
    let output_chaos = study
        .outputs
        .iter()
        .zip(estimates)
        .filter_map(|(name, estimate)| {
            Some(NamedChaos {
                name: name.clone(),
                times: Some(times.clone()),
                pce: estimate.chaos?,
                error: estimate.chaos_error,
            })
        })
        .collect();
    Ok(Analysed {
        outputs,
        quantities,
        output_chaos,
        quantity_chaos,
    })
}

/// Statistics of every output of an intrusive method's solution.
pub fn analyse_solution(
    study: &Study,
    solution: &Solution,
) -> Result<Vec<OutputStats>, AnalysisError> {
    // No scalar quantities here: only the series' draws.
    let surrogates = Surrogates::new(study.seed ^ SURROGATE_SEED);
    let settings = Settings::of(study, &surrogates);
    let times = study.times();
    study
        .outputs
        .iter()
        .zip(&solution.outputs)
        .map(|(name, estimate)| output_stats(name, &times, estimate, None, &settings))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Where the analysis of a chaos study spends its time:
    /// `cargo test --release -p uq-driver --lib -- --ignored analysis_timing --nocapture`.
    #[test]
    #[ignore = "prints timings"]
    fn analysis_timing() {
        use crate::uq::pce::{Basis, Family, MultiIndexSet, Pce};
        let set = MultiIndexSet::total_degree(2, 5).unwrap();
        let basis = Basis::new(vec![Family::Hermite; 2], set).unwrap();
        let coeffs = DMatrix::from_fn(basis.len(), 501, |t, k| {
            ((t + 1) as f64).recip() * (0.01 * k as f64).sin()
        });
        let pce = Pce { basis, coeffs };
        let t = std::time::Instant::now();
        let draws = Surrogates::new(1).draws(&pce, 4_000);
        eprintln!("sample: {:?}", t.elapsed());
        let t = std::time::Instant::now();
        let rows = draws.nrows();
        let cols: Vec<Column> = (0..draws.ncols())
            .map(|k| {
                column(
                    &draws.as_slice()[k * rows..(k + 1) * rows],
                    &[0.01, 0.5, 0.99],
                )
            })
            .collect();
        eprintln!("columns: {:?}", t.elapsed());
        let t = std::time::Instant::now();
        for (k, c) in cols.iter().enumerate().step_by(2) {
            let col = &draws.as_slice()[k * rows..(k + 1) * rows];
            kde::gaussian_kde_binned(col, -1.0, 1.0, 200, c.bandwidth);
        }
        eprintln!("kde: {:?}", t.elapsed());
    }

    #[test]
    fn thinning_keeps_ends() {
        assert_eq!(thinned(5, 10), vec![0, 1, 2, 3, 4]);
        let t = thinned(501, 100);
        assert_eq!(t[0], 0);
        assert_eq!(*t.last().unwrap(), 500);
        assert!(t.len() <= 101);
    }
}
