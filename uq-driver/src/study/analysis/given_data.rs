//! Sensitivity from the runs of a design that samples the inputs' law (Monte Carlo, Latin
//! hypercube, quasi-Monte Carlo): first-order Sobol' indices from given data (`uq::given_data`)
//! and rank correlations (`uq::rank_correlation`), on the physical input values of the runs.
//!
//! A scalar quantity gets its first-order indices with bootstrap intervals, Spearman's
//! coefficients and PRCCs; a series of at most [`MAX_SERIES_TIMES`] times gets its first-order
//! indices at every time column (no intervals: a bootstrap per column would cost more than
//! the rest of the analysis; longer series none: their rows of indices would cost more
//! memory than the blocked analysis of their runs: 400 runs × 100 001 times went from 66 to
//! 86 MB).

use nalgebra::DMatrix;

use crate::results::RankCorrelation;
use crate::uq::distributions::RandomParameter;
use crate::uq::given_data::{self, Bins, LEVEL, RESAMPLES};
use crate::uq::method::{Design, Sampling, Sobol, SobolIntervals};
use crate::uq::rank_correlation::RankInputs;

/// The longest series (time columns) whose first-order indices over time are estimated.
pub(crate) const MAX_SERIES_TIMES: usize = 20_001;
/// Offset of the bootstrap's random streams from the design's.
const BOOTSTRAP_SEED: u64 = 0x6976_656e_0000_0000;

/// The physical values of the inputs at the design points `rows`, `[input][run]`.
pub(crate) fn inputs_at(design: &Design, rows: &[usize]) -> Vec<Vec<f64>> {
    let d = design.values.first().map_or(0, Vec::len);
    (0..d)
        .map(|i| rows.iter().map(|&r| design.values[r][i]).collect())
        .collect()
}

/// The bins of the runs at the design points `rows` (`inputs[i][k]`, the inputs at `rows[k]`),
/// grouped by the replicate each row belongs to where `method`'s design is made of
/// independent replicates.
pub(crate) fn bins(method: &dyn Sampling, inputs: &[Vec<f64>], rows: &[usize]) -> Bins {
    let bins = Bins::of(inputs);
    match method.replicate_size() {
        Some(size) if size > 0 => {
            bins.with_replicates(rows.iter().map(|&r| (r / size) as u32).collect())
        }
        _ => bins,
    }
}

/// The first-order indices of a series, estimated a block of time columns at a time.
pub(crate) struct SeriesIndices<'a> {
    bins: &'a Bins,
    first: Vec<Vec<f64>>,
}

impl<'a> SeriesIndices<'a> {
    /// No column yet; runs binned by `bins`.
    pub(crate) fn new(bins: &'a Bins) -> SeriesIndices<'a> {
        SeriesIndices {
            bins,
            first: Vec::new(),
        }
    }

    /// The indices of every column of `data` (one row per run of the bins), in order.
    pub(crate) fn add(&mut self, data: &DMatrix<f64>) {
        let bins = self.bins;
        self.first.extend(
            data.column_iter()
                .map(|col| bins.first_order(col.as_slice())),
        );
    }

    /// The indices of the columns added, without intervals, as a [`Sobol`] marked as given
    /// data (total indices not estimated: an empty row per column, which allocates nothing
    /// on a long series).
    pub(crate) fn sobol(self) -> Sobol {
        let total = vec![Vec::new(); self.first.len()];
        Sobol {
            first: self.first,
            total,
            intervals: None,
            given_data: true,
        }
    }
}

/// A scalar quantity's sensitivity from its valid runs (`inputs[i][k]`, `values[k]`, binned
/// by `bins`, which [`bins`] made of the same runs): its
/// first-order indices with bootstrap intervals (a [`Sobol`] of one column marked as given
/// data) and its rank correlations labelled by the names of `parameters`; `None` below
/// [`given_data::MIN_RUNS`] runs.
pub(crate) fn scalar(
    inputs: &[Vec<f64>],
    bins: &Bins,
    values: &[f64],
    parameters: &[RandomParameter],
    seed: u64,
) -> Option<(Sobol, RankCorrelation)> {
    let names: Vec<&str> = parameters.iter().map(|p| p.name.as_str()).collect();
    if values.len() < given_data::MIN_RUNS || inputs.is_empty() {
        return None;
    }
    let first = bins.first_order(values);
    let ci = bins.intervals(values, RESAMPLES, LEVEL, seed ^ BOOTSTRAP_SEED);
    let d = first.len();
    let sobol = Sobol {
        first: vec![first],
        total: vec![vec![f64::NAN; d]],
        intervals: Some(SobolIntervals {
            level: LEVEL,
            first: vec![ci],
            total: vec![vec![(f64::NAN, f64::NAN); d]],
        }),
        given_data: true,
    };
    let (spearman, prcc) = RankInputs::of(inputs).of_output(values);
    let label = |v: Vec<f64>| {
        names
            .iter()
            .map(|n| n.to_string())
            .zip(v)
            .collect::<std::collections::BTreeMap<_, _>>()
    };
    Some((
        sobol,
        RankCorrelation {
            spearman: label(spearman),
            prcc: label(prcc),
        },
    ))
}
