//! One output's statistics from the runs, a block of time columns at a time or on its
//! principal components, and the column a scalar quantity equals (fitted once).

use super::blocks;
use super::runs::Runs;
use super::{chaos_columns, functional, given_data, series_columns, summarise};
use super::{output_error, AnalysisError, Settings};
use crate::results::OutputStats;
use crate::spec::Functional;
use crate::uq::given_data::Bins;
use crate::uq::method::{Design, Draws, Estimate, Sampling};

/// The output and column `(o, t)` whose runs are `values` bit for bit, among the columns
/// whose hashes are known (`hashes[o][t]`, of `nt` columns each).
pub(super) fn equal_column(
    runs: &Runs,
    hashes: &[Vec<u64>],
    nt: usize,
    values: &[f64],
) -> Result<Option<(usize, usize)>, AnalysisError> {
    let h = functional::column_hash(values);
    for (o, of_output) in hashes.iter().enumerate() {
        for (t, _) in of_output.iter().enumerate().filter(|(_, &x)| x == h) {
            let column = runs.column(o, nt, t)?;
            if column
                .iter()
                .zip(values)
                .all(|(a, b)| a.to_bits() == b.to_bits())
            {
                return Ok(Some((o, t)));
            }
        }
    }
    Ok(None)
}

/// The estimate and the statistics of output `o`, estimated a block of time columns at a
/// time (see [`blocks`]), or on its principal components ([`functional`]); with the hash of
/// every column where a chaos is fitted per column (else none).
pub(super) fn output_in_blocks(
    method: &dyn Sampling,
    (design, bins): (&Design, Option<&Bins>),
    runs: &Runs,
    (o, name, times): (usize, &str, &[f64]),
    settings: &Settings,
) -> Result<(Estimate, OutputStats, Vec<u64>), AnalysisError> {
    let nt = times.len();
    let fail = output_error(name);
    let a = settings.analysis;
    let per_column = method.chaos_per_column() && !method.whole_series();
    let pca = match per_column && a.functional == Functional::Pca && nt > 1 {
        true => functional::pca_estimate(method, design, runs, (o, name, nt), a.retained_variance)?,
        false => None,
    };
    let mut cols = series_columns(nt, settings);
    let (estimate, fit, hashes) = match pca {
        Some((estimate, fit, hashes)) => (estimate, Some(fit), hashes),
        None => {
            let (mut parts, mut fits, mut hashes) = (Vec::new(), 0, Vec::new());
            let mut given = bins.map(given_data::SeriesIndices::new);
            for (j0, w) in blocks::blocks(nt, blocks::block_width(nt, runs.rows.len())) {
                let data = runs.block(o, nt, j0, w)?;
                let estimate = if per_column {
                    let (e, k, h) =
                        functional::estimate_distinct(method, design, &runs.rows, &data)
                            .map_err(fail)?;
                    fits += k;
                    hashes.extend(h);
                    e
                } else {
                    method.estimate(design, &runs.rows, &data).map_err(fail)?
                };
                if estimate.draws == Draws::Runs {
                    cols.add(j0, &data);
                }
                if let Some(g) = &mut given {
                    g.add(&data);
                }
                parts.push(estimate);
            }
            let fit = per_column.then(|| crate::results::FunctionalFit {
                method: "columns".into(),
                modes: None,
                fits,
                retained_variance: None,
                discarded_variance: None,
                discarded_max: None,
            });
            let mut estimate = blocks::merge(parts).map_err(fail)?;
            if let Some(g) = given {
                estimate.sobol = Some(g.sobol());
            }
            (estimate, fit, hashes)
        }
    };
    if estimate.draws == Draws::Chaos {
        chaos_columns(name, &estimate, settings, &mut cols)?;
    }
    // The running estimate takes the rows the reported mean and Std use.
    let moment_rows = method.moment_rows(design, &runs.rows);
    let run_column = |k: usize| {
        let all = runs.column(o, nt, k)?;
        Ok(match &moment_rows {
            Some(rows) => rows.iter().filter_map(|&r| all.get(r).copied()).collect(),
            None => all,
        })
    };
    let mut stats = summarise(name, times, &estimate, cols, &run_column, settings)?;
    stats.functional = fit;
    Ok((estimate, stats, hashes))
}
