//! Sobol' indices by sampling: the pick-freeze design of Saltelli — two base samples `A` and
//! `B` of `samples` points each and, for every input `i`, `AB_i` (`A` with column `i` from
//! `B`): `samples × (d + 2)` model runs, laid out `A`, `B`, `AB_1`, …, `AB_d` (point `k` of
//! block `b` is design point `b × samples + k`).
//!
//! `A` and `B` are the two halves of a `2d`-dimensional design of `samples` points, mapped
//! through each input's quantile function:
//! - `base = "qmc"` (the default): `replicates` (R, default 8) independently scrambled Sobol'
//!   sequences of `samples / R` points each (the scramblings of the `qmc` method: replicate `r`
//!   keyed by `(seed, r)`); base row `k` is point `k % (samples / R)` of replicate
//!   `k / (samples / R)`;
//! - `"mc"`: Monte Carlo; `"lhs"`: a Latin hypercube (one design of `samples` points).
//!
//! Estimators (`uq::hd::sensitivity`): first order by Saltelli (2010), total by
//! Jansen (1999), normalised by the variance of the `2 × samples` values of `A` and `B`, on
//! the values less their mean over `A` and `B` (same expectation; centring cuts the variance
//! of the first-order estimator when the mean is large against the spread), always on all
//! the rows. Intervals at `confidence`:
//! - base `qmc`: from the spread of the R replicate estimates (each replicate's rows alone),
//!   `estimate ± t_{R-1, (1 + confidence)/2} sd_R / sqrt(R)`. The rows of one scrambled net
//!   are not independent: a bootstrap over them missed the indices of the Morris function in
//!   every seed, since the error of one net depends on its scrambling;
//! - bases `mc` and `lhs`: percentile bootstrap from `bootstrap` resamples of the rows (the
//!   same resampled rows for every column; resample `k` from the ChaCha20 stream
//!   `(0x5eed_b007, k)`, so the intervals are reproducible).
//!
//! A row whose runs did not all succeed is left out of every block (and of its replicate: a
//! replicate left with fewer than 2 rows does not count, and fewer than 2 counting replicates
//! give NaN intervals). A column without variance (e.g. a fixed initial value) gets indices 0
//! with intervals `[0, 0]`, as a chaos gives.
//!
//! Mean, Std and the standard error of the mean come from the runs of `A` and `B`
//! (Monte Carlo formula); quantiles and densities from every run (each block follows the
//! input law). Exceedance counts and their Clopper–Pearson intervals come from the `2N`
//! independent runs of `A` and `B` ([`Sampling::moment_rows`]; the analysis counts over them):
//! the `AB_i` blocks reuse their columns, so all the runs are not independent draws.

use nalgebra::DMatrix;
use rayon::prelude::*;
use serde::ser::SerializeStruct;
use serde::{Deserialize, Serialize, Serializer};

use super::design::Design;
use super::error::{InvalidSettings, MethodError};
use super::estimate::{Estimate, Sobol, SobolIntervals};
use super::qmc::{check_sobol_points, Qmc, DEFAULT_REPLICATES};
use super::sample::UnitCubeSample;
use super::traits::{DesignSize, Evaluation, Method, MethodSummary, Problem, RunResults, Sampling};
use crate::uq::distributions::Germ;
use crate::uq::hd::sensitivity::{self, SensitivityError};
use crate::uq::random_inputs::RandomInputs;
use crate::uq::sampling;

/// Most bootstrap resamples.
const MAX_BOOTSTRAP: usize = 10_000;

/// Seed of the bootstrap resamples.
const BOOTSTRAP_SEED: u64 = 0x5eed_b007;

/// The base design `A`, `B` are drawn from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Base {
    /// Scrambled Sobol' points.
    #[default]
    Qmc,
    /// Monte Carlo.
    Mc,
    /// Latin hypercube.
    Lhs,
}

/// `kind = "sobol_sampling"`.
///
/// Serialized (the study hash) as `samples`, `base` and, for the `qmc` base only, the number
/// of replicates: a `qmc` study of the single-net design of before does not resume, an `mc`
/// or `lhs` study keeps its hash.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SobolSampling {
    /// Base sample size N (at least 2): N (d + 2) model runs.
    pub samples: usize,
    /// Where `A` and `B` come from (default `qmc`).
    #[serde(default)]
    pub base: Base,
    /// Independently scrambled Sobol' designs the `qmc` base is made of (default 8, at least
    /// 2; `samples / replicates` a power of two); refused for the `mc` and `lhs` bases.
    #[serde(default)]
    pub replicates: Option<usize>,
    /// Bootstrap resamples for the intervals of the `mc` and `lhs` bases (default 200, at
    /// most 10 000; 0: no intervals); the `qmc` base takes its intervals from the replicates
    /// and ignores it (with a warning). Analysis only: not part of the study hash, so a
    /// changed value re-analyses the stored runs instead of refusing the folder.
    #[serde(default)]
    pub bootstrap: Option<usize>,
    /// Confidence level of the intervals (default 0.95; analysis only, like `bootstrap`).
    #[serde(default = "default_confidence")]
    pub confidence: f64,
}

impl Serialize for SobolSampling {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let qmc = self.base == Base::Qmc;
        let mut s = serializer.serialize_struct("SobolSampling", 2 + usize::from(qmc))?;
        s.serialize_field("samples", &self.samples)?;
        s.serialize_field("base", &self.base)?;
        if qmc {
            s.serialize_field("replicates", &self.replicate_count())?;
        }
        s.end()
    }
}

/// Default bootstrap resamples (bases `mc` and `lhs`).
const DEFAULT_BOOTSTRAP: usize = 200;

fn default_confidence() -> f64 {
    0.95
}

impl Method for SobolSampling {
    fn kind(&self) -> &'static str {
        "sobol_sampling"
    }

    fn label(&self, dim: usize) -> String {
        let base = match self.base {
            Base::Qmc => format!("qmc, {} replicates", self.replicate_count()),
            other => format!("{other:?}"),
        };
        format!("sobol_sampling {}x{} ({base})", self.samples, dim + 2).to_lowercase()
    }

    fn validate(&self, problem: &Problem) -> Result<(), InvalidSettings> {
        let d = problem.parameters.len();
        if self.samples < 2 {
            return Err(InvalidSettings("`samples` must be at least 2".into()));
        }
        let bootstrap = self.bootstrap_resamples();
        if bootstrap > MAX_BOOTSTRAP {
            return Err(InvalidSettings(format!(
                "`bootstrap` = {bootstrap} resamples: at most {MAX_BOOTSTRAP}"
            )));
        }
        if !(self.confidence > 0.0 && self.confidence < 1.0) {
            return Err(InvalidSettings(format!(
                "`confidence` = {} must be between 0 and 1",
                self.confidence
            )));
        }
        if self.base == Base::Qmc {
            let per = self.points_per_replicate()?;
            let hint = " (twice the random parameters); use base = \"lhs\"";
            check_sobol_points(2 * d, per, hint)?;
        } else if let Some(r) = self.replicates {
            return Err(InvalidSettings(format!(
                "`replicates` = {r} applies to base = \"qmc\" only (independently scrambled \
                 Sobol' designs); base = \"{}\" takes its intervals from the bootstrap over \
                 the rows (`bootstrap`)",
                format!("{:?}", self.base).to_lowercase()
            )));
        }
        Ok(())
    }

    fn summary(&self, dim: usize) -> MethodSummary {
        let size = DesignSize {
            samples: Some(self.samples),
            nodes_per_dimension: None,
            order: None,
        };
        let mut s = MethodSummary::new(self.kind(), &size);
        let d = &mut s.details;
        d.insert("base".into(), serde_json::json!(self.base));
        if self.base == Base::Qmc {
            d.insert("replicates".into(), self.replicate_count().into());
            d.insert("bootstrap".into(), serde_json::Value::Null);
        } else {
            d.insert("bootstrap".into(), self.bootstrap_resamples().into());
        }
        d.insert("confidence".into(), self.confidence.into());
        d.insert("runs".into(), (self.samples.saturating_mul(dim + 2)).into());
        let estimators = match self.base {
            Base::Qmc => {
                "first order: Saltelli (2010); total: Jansen (1999); on all rows; intervals \
                 from the independently scrambled replicates"
            }
            Base::Mc | Base::Lhs => {
                "first order: Saltelli (2010); total: Jansen (1999); percentile bootstrap \
                 intervals"
            }
        };
        d.insert("estimators".into(), estimators.into());
        let intervals = match self.base {
            Base::Qmc => format!(
                "replicates: estimate on all rows ± t(R - 1, (1 + confidence)/2) sd(replicate \
                 estimates) / sqrt(R), R = {} independently scrambled Sobol' designs of {} \
                 base points each (Student's t)",
                self.replicate_count(),
                self.samples / self.replicate_count().max(1)
            ),
            Base::Mc | Base::Lhs => format!(
                "percentile bootstrap over the base rows ({} resamples)",
                self.bootstrap_resamples()
            ),
        };
        d.insert("intervals".into(), intervals.into());
        let standard_error = match self.base {
            Base::Qmc => {
                "replicates: the spread of the replicate means over the runs of A and B, \
                 sd(replicate means) / sqrt(replicates)"
            }
            Base::Mc | Base::Lhs => {
                "Monte Carlo formula std / sqrt(2 samples) over the runs of A and B (exact for \
                 base = \"mc\", an overestimate for lhs)"
            }
        };
        d.insert("standard_error".into(), standard_error.into());
        s
    }

    fn evaluation(&self) -> Evaluation<'_> {
        Evaluation::Sampling(self)
    }
}

impl SobolSampling {
    /// Replicates of the `qmc` base (the given number or 8).
    pub fn replicate_count(&self) -> usize {
        self.replicates.unwrap_or(DEFAULT_REPLICATES)
    }

    /// Bootstrap resamples of the `mc` and `lhs` bases (the given number or 200).
    pub fn bootstrap_resamples(&self) -> usize {
        self.bootstrap.unwrap_or(DEFAULT_BOOTSTRAP)
    }

    /// Base points of each replicate of the `qmc` base: `samples / replicates`, a power of two
    /// (at least 2).
    fn points_per_replicate(&self) -> Result<usize, InvalidSettings> {
        let (n, r) = (self.samples, self.replicate_count());
        if r < 2 {
            return Err(InvalidSettings(format!(
                "`replicates` = {r}: at least 2 independently scrambled replicates are needed \
                 for intervals from their spread"
            )));
        }
        let suggest = |per: usize| per.max(2).next_power_of_two() * r;
        if n % r != 0 {
            return Err(InvalidSettings(format!(
                "`samples` = {n} is not a multiple of `replicates` = {r}: each replicate takes \
                 samples / replicates base points, a power of two (e.g. samples = {})",
                suggest(n / r)
            )));
        }
        let per = n / r;
        if per < 2 || !per.is_power_of_two() {
            let down = suggest(per) / 2;
            let others = if down >= 2 * r && down != suggest(per) {
                format!("{down} or {}", suggest(per))
            } else {
                suggest(per).to_string()
            };
            return Err(InvalidSettings(format!(
                "`samples` / `replicates` = {n} / {r} = {per} base points per replicate: must \
                 be a power of two, at least 2 (the scrambled Sobol' points are a net only in \
                 blocks of 2^m); use samples = {others}, or other `replicates`"
            )));
        }
        Ok(per)
    }

    /// The `samples` points of the `2d`-dimensional base design in the unit cube (for `qmc`,
    /// replicate after replicate).
    fn base_points(&self, d: usize, seed: u64) -> Result<Vec<Vec<f64>>, MethodError> {
        let n = self.samples;
        Ok(match self.base {
            Base::Qmc => {
                let per = self.points_per_replicate()?;
                let r = self.replicate_count();
                // The scramblings of the `qmc` method: replicate `k` keyed by `(seed, k)`.
                let qmc = Qmc {
                    samples: per,
                    replicates: r,
                };
                let blocks = (0..r)
                    .into_par_iter()
                    .map(|k| qmc.block(2 * d, seed, Some(k)))
                    .collect::<Result<Vec<_>, _>>()?;
                blocks.into_iter().flatten().collect()
            }
            Base::Mc => sampling::monte_carlo(n, 2 * d, seed),
            Base::Lhs => sampling::latin_hypercube(n, 2 * d, seed),
        })
    }
}

impl Sampling for SobolSampling {
    /// In the independent uniform space (with correlated inputs the indices are those of the
    /// independent germs, one per input in study order, as for a chaos).
    fn make_design(&self, inputs: &RandomInputs, seed: u64) -> Result<Design, MethodError> {
        let d = inputs.len();
        let base = self.base_points(d, seed)?;
        let (a, b): (Vec<Vec<f64>>, Vec<Vec<f64>>) = base
            .into_iter()
            .map(|p| (p[..d].to_vec(), p[d..].to_vec()))
            .unzip();
        let points = sensitivity::pick_freeze_design(&a, &b)?;
        let mut design = Design::mapped(Germ::Uniform, points, None, inputs);
        if let (Base::Qmc, Some(b)) = (self.base, self.bootstrap) {
            design.warnings.push(format!(
                "sobol_sampling: `bootstrap` = {b} does not apply to base = \"qmc\": its \
                 intervals come from the spread of its {} independently scrambled replicates",
                self.replicate_count()
            ));
        }
        Ok(design)
    }

    fn make_estimate(&self, results: RunResults) -> Result<Estimate, MethodError> {
        let RunResults { design, rows, data } = results;
        let n = self.samples;
        let d = design.points.first().map_or(0, Vec::len);
        let blocks = PickFreezeRows::new(n, d, rows);
        if blocks.complete.len() < 2 {
            return Err(SensitivityError::TooFew(blocks.complete.len()).into());
        }
        let (moments, columns) = self.columns(&blocks, data)?;
        let intervals = (self.intervals() != Intervals::None).then(|| SobolIntervals {
            level: self.confidence,
            first: columns.iter().map(|c| c.first_ci.clone()).collect(),
            total: columns.iter().map(|c| c.total_ci.clone()).collect(),
        });
        Ok(Estimate {
            sobol: Some(Sobol {
                first: columns.iter().map(|c| c.first.clone()).collect(),
                total: columns.iter().map(|c| c.total.clone()).collect(),
                intervals,
                given_data: false,
            }),
            ..moments
        })
    }

    /// The runs of `A` and `B` at the complete base rows (those the mean and Std use),
    /// alternating `A_k`, `B_k`.
    fn moment_rows(&self, design: &Design, rows: &[usize]) -> Option<Vec<usize>> {
        let d = design.points.first().map_or(0, Vec::len);
        let blocks = PickFreezeRows::new(self.samples, d, rows);
        let b: Vec<usize> = blocks.block_rows(1).collect();
        Some(
            blocks
                .block_rows(0)
                .zip(b)
                .flat_map(|(a, b)| [a, b])
                .collect(),
        )
    }

    fn planned_runs(&self, dim: usize) -> Option<f64> {
        Some(self.samples as f64 * (dim as f64 + 2.0))
    }

    fn draws_from_chaos(&self) -> bool {
        false
    }

    fn estimates_sobol(&self) -> bool {
        true
    }
}

/// Where the intervals of the indices come from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Intervals {
    /// No intervals (`bootstrap = 0` on an `mc` or `lhs` base).
    None,
    /// Percentile bootstrap over the rows, with this many resamples.
    Bootstrap(usize),
    /// Student's t from the spread of the estimates of replicates of this many base rows.
    Replicates(usize),
}

impl SobolSampling {
    fn intervals(&self) -> Intervals {
        match (self.base, self.bootstrap_resamples()) {
            (Base::Qmc, _) => Intervals::Replicates(self.samples / self.replicate_count().max(1)),
            (_, 0) => Intervals::None,
            (_, b) => Intervals::Bootstrap(b),
        }
    }
}

/// The indices of one column.
struct ColumnIndices {
    first: Vec<f64>,
    total: Vec<f64>,
    first_ci: Vec<(f64, f64)>,
    total_ci: Vec<(f64, f64)>,
}

impl SobolSampling {
    /// The moments of every column over the blocks `A` and `B`, and the indices of every
    /// column: the bootstrap resamples drawn once and applied to all the columns with
    /// variance together. Each column is gathered once (in parallel) for both.
    fn columns(
        &self,
        blocks: &PickFreezeRows,
        data: &DMatrix<f64>,
    ) -> Result<(Estimate, Vec<ColumnIndices>), MethodError> {
        let (m, d) = (blocks.complete.len(), blocks.d);
        let order: Vec<usize> = (0..d + 2).flat_map(|b| blocks.block_rows(b)).collect();
        let contiguous = order.iter().enumerate().all(|(i, &r)| i == r);
        let replicate_of = match self.intervals() {
            Intervals::Replicates(per) => Some(blocks.replicate_of(per, self.replicate_count())),
            _ => None,
        };
        let (moments, values): (Vec<Estimate>, Vec<Option<Vec<f64>>>) = data
            .as_slice()
            .par_chunks(data.nrows().max(1))
            .map(|col| {
                let values: Vec<f64> = if contiguous {
                    col[..order.len()].to_vec()
                } else {
                    order.iter().map(|&r| col[r]).collect()
                };
                // The moments of the column over A and B, as of the whole matrix's rows.
                let ab = DMatrix::from_column_slice(2 * m, 1, &values[..2 * m]);
                let mut moments = Estimate::from_sample(&ab);
                if let Some(replicate_of) = &replicate_of {
                    // No spread, no error (the replicate means differ there by rounding only).
                    let se = if has_variance(&values[..2 * m]) {
                        replicate_standard_error(&values[..2 * m], replicate_of)
                    } else {
                        0.0
                    };
                    moments.std_error_mean = Some(vec![se]);
                }
                (moments, centred(values, m))
            })
            .unzip();
        let mut moments = moments.into_iter();
        let mut all = moments
            .next()
            .unwrap_or_else(|| Estimate::from_sample(&DMatrix::zeros(2 * m, 0)));
        for e in moments {
            all.mean.extend(e.mean);
            all.std.extend(e.std);
            if let (Some(a), Some(b)) = (&mut all.std_error_mean, e.std_error_mean) {
                a.extend(b);
            }
        }
        let varying: Vec<&Vec<f64>> = values.iter().flatten().collect();
        let with_ci = |e: sensitivity::SobolWithCi| ColumnIndices {
            first: e.estimate.first,
            total: e.estimate.total,
            first_ci: e.first_ci,
            total_ci: e.total_ci,
        };
        let mut indices = match self.intervals() {
            Intervals::None => varying
                .par_iter()
                .map(|v| {
                    let e = sensitivity::pick_freeze(v, m, d)?;
                    Ok(ColumnIndices {
                        first: e.first,
                        total: e.total,
                        first_ci: Vec::new(),
                        total_ci: Vec::new(),
                    })
                })
                .collect::<Result<Vec<_>, SensitivityError>>()?,
            Intervals::Bootstrap(resamples) => sensitivity::pick_freeze_bootstrap_columns(
                &varying,
                m,
                d,
                resamples,
                self.confidence,
                BOOTSTRAP_SEED,
            )?
            .into_iter()
            .map(with_ci)
            .collect(),
            Intervals::Replicates(per) => {
                let sizes = blocks.replicate_sizes(per, self.replicate_count());
                varying
                    .par_iter()
                    .map(|v| {
                        sensitivity::pick_freeze_replicates(v, m, d, &sizes, self.confidence)
                            .map(with_ci)
                    })
                    .collect::<Result<Vec<_>, SensitivityError>>()?
            }
        }
        .into_iter();
        let indices = values
            .iter()
            .map(|v| match v {
                Some(_) => indices.next().expect("one result per varying column"),
                None => ColumnIndices {
                    first: vec![0.0; d],
                    total: vec![0.0; d],
                    first_ci: vec![(0.0, 0.0); d],
                    total_ci: vec![(0.0, 0.0); d],
                },
            })
            .collect();
        Ok((all, indices))
    }
}

/// The standard error of the mean of the rows of `A` and `B` (`ab`: the `m` rows of `A`, then
/// those of `B`) from the spread of the replicate means, `sd(replicate means) / sqrt(R')`,
/// over the `R'` replicates with at least 2 complete base rows (as the intervals of the
/// indices); `replicate_of[i]` is the replicate of complete row `i`. NaN with fewer than 2.
fn replicate_standard_error(ab: &[f64], replicate_of: &[usize]) -> f64 {
    let m = replicate_of.len();
    let count = replicate_of.iter().max().map_or(0, |&r| r + 1);
    let mut sums = vec![(0.0, 0usize); count];
    for (i, v) in ab.iter().enumerate() {
        let r = replicate_of[i % m.max(1)];
        sums[r].0 += v;
        sums[r].1 += 1;
    }
    let means: Vec<f64> = sums
        .iter()
        .filter(|(_, k)| *k >= 4)
        .map(|(s, k)| s / *k as f64)
        .collect();
    sensitivity::replicate_summary(&means).std_error
}

/// The `values` of a column in the blocks `A`, `B`, `AB_1`, ... at the `m` complete rows,
/// less their mean over `A` and `B`; `None` for a column without variance.
fn centred(mut values: Vec<f64>, m: usize) -> Option<Vec<f64>> {
    if !has_variance(&values[..2 * m]) {
        return None;
    }
    // Centred values: the same indices in expectation, a far smaller variance of the
    // first-order estimator f(B) (f(AB_i) - f(A)) when the mean is large against the spread.
    let mean = values[..2 * m].iter().sum::<f64>() / (2 * m) as f64;
    values.iter_mut().for_each(|v| *v -= mean);
    Some(values)
}

/// Whether `values` vary beyond rounding: not all equal, and a variance (two-pass, with the
/// mean corrected for its rounding) above that of a relative perturbation of 64 ulp.
fn has_variance(values: &[f64]) -> bool {
    let Some(&first) = values.first() else {
        return false;
    };
    if values.iter().all(|&v| v == first) {
        return false;
    }
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let mean = mean + values.iter().map(|v| v - mean).sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n;
    let scale = values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    var.is_finite() && var > (64.0 * f64::EPSILON * scale).powi(2)
}

/// Which rows of the results belong to which block, for the base rows whose runs all succeeded.
struct PickFreezeRows {
    n: usize,
    d: usize,
    /// Base rows `k` (0..n) with a result in every block.
    complete: Vec<usize>,
    /// Row of the results matrix of each design point, if it succeeded.
    position: Vec<Option<usize>>,
}

impl PickFreezeRows {
    fn new(n: usize, d: usize, rows: &[usize]) -> PickFreezeRows {
        let mut position = vec![None; n * (d + 2)];
        for (r, &i) in rows.iter().enumerate() {
            if let Some(p) = position.get_mut(i) {
                *p = Some(r);
            }
        }
        let complete = (0..n)
            .filter(|&k| (0..d + 2).all(|b| position[b * n + k].is_some()))
            .collect();
        PickFreezeRows {
            n,
            d,
            complete,
            position,
        }
    }

    /// The number of complete rows of each of the `replicates` replicates of `per` base rows
    /// (base row `k` in replicate `k / per`).
    /// The replicate of each complete base row (replicates of `per` base rows).
    fn replicate_of(&self, per: usize, replicates: usize) -> Vec<usize> {
        self.complete
            .iter()
            .map(|&k| (k / per.max(1)).min(replicates.saturating_sub(1)))
            .collect()
    }

    /// The complete base rows of each replicate.
    fn replicate_sizes(&self, per: usize, replicates: usize) -> Vec<usize> {
        let mut sizes = vec![0; replicates.max(1)];
        for r in self.replicate_of(per, replicates) {
            sizes[r] += 1;
        }
        sizes
    }

    /// The result rows of block `b` (0: A, 1: B, 2 + i: AB_i) at the complete base rows.
    fn block_rows(&self, b: usize) -> impl Iterator<Item = usize> + '_ {
        self.complete
            .iter()
            .map(move |&k| self.position[b * self.n + k].expect("complete row"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::uq::distributions::RandomParameter;
    use crate::uq::Distribution;
    use std::f64::consts::PI;

    fn uniform_params(d: usize, low: f64, high: f64) -> RandomInputs {
        RandomInputs::independent(
            (0..d)
                .map(|i| {
                    RandomParameter::new(
                        format!("x{}", i + 1),
                        Distribution::uniform(low, high).unwrap(),
                    )
                })
                .collect(),
        )
    }

    fn run(m: &SobolSampling, params: &RandomInputs, f: impl Fn(&[f64]) -> f64) -> Estimate {
        let design = m.design(params, 11).unwrap();
        assert_eq!(design.len(), m.samples * (params.len() + 2));
        let values: Vec<f64> = design.values.iter().map(|v| f(v)).collect();
        let data = DMatrix::from_column_slice(values.len(), 1, &values);
        let rows: Vec<usize> = (0..design.len()).collect();
        m.estimate(&design, &rows, &data).unwrap()
    }

    /// The additive f = x1 + 2 x2 on U(0, 1)²: S = ST = (1/5, 4/5) exactly.
    #[test]
    fn additive_function_indices_from_every_base() {
        let params = uniform_params(2, 0.0, 1.0);
        for base in [Base::Qmc, Base::Mc, Base::Lhs] {
            let m = SobolSampling {
                samples: 4096,
                base,
                replicates: None,
                bootstrap: Some(100),
                confidence: 0.95,
            };
            let e = run(&m, &params, |x| x[0] + 2.0 * x[1]);
            let s = e.sobol.unwrap();
            let ci = s.intervals.unwrap();
            for (i, exact) in [0.2, 0.8].into_iter().enumerate() {
                assert!((s.first[0][i] - exact).abs() < 0.03, "{base:?} S{i}");
                assert!((s.total[0][i] - exact).abs() < 0.03, "{base:?} ST{i}");
                assert!(ci.first[0][i].0 <= s.first[0][i] && s.first[0][i] <= ci.first[0][i].1);
            }
            // Mean 1.5, variance 5/12.
            assert!((e.mean[0] - 1.5).abs() < 0.02, "{base:?}");
            assert!((e.std[0] - (5.0f64 / 12.0).sqrt()).abs() < 0.02, "{base:?}");
        }
    }

    #[test]
    fn failed_points_drop_their_row_from_every_block() {
        let params = uniform_params(3, -PI, PI);
        let m = SobolSampling {
            samples: 512,
            base: Base::Qmc,
            replicates: None,
            bootstrap: None,
            confidence: 0.95,
        };
        let design = m.design(&params, 3).unwrap();
        let f = |x: &[f64]| x[0].sin() + 7.0 * x[1].sin().powi(2);
        let estimate = |keep: &dyn Fn(usize) -> bool, m: &SobolSampling| {
            let rows: Vec<usize> = (0..design.len()).filter(|&i| keep(i)).collect();
            let values: Vec<f64> = rows.iter().map(|&i| f(&design.values[i])).collect();
            let data = DMatrix::from_column_slice(values.len(), 1, &values);
            m.estimate(&design, &rows, &data)
        };
        // Every 7th point fails.
        let e = estimate(&|i| i % 7 != 3, &m).unwrap();
        // x3 does not matter: its indices are 0 up to sampling error.
        let s = e.sobol.unwrap();
        assert!(s.first[0][2].abs() < 0.05 && s.total[0][2].abs() < 1e-12);
        let ci = s.intervals.unwrap();
        assert!(ci.first[0][0].0 < s.first[0][0] && s.first[0][0] < ci.first[0][0].1);
        // Base rows k of replicate k / 64. Replicate 0 keeps one row (too few for its own
        // estimate) and replicate 5 none: the intervals come from the other six.
        let base_row = |i: usize| i % 512;
        let some = |i: usize| !(base_row(i) < 63 || (320..384).contains(&base_row(i)));
        let s = estimate(&some, &m).unwrap().sobol.unwrap();
        let ci = s.intervals.unwrap();
        assert!(ci.total[0]
            .iter()
            .all(|&(lo, hi)| lo.is_finite() && hi.is_finite()));
        // Only replicate 2 left: indices, but no spread, so NaN intervals (not a panic).
        let one = |i: usize| (128..192).contains(&base_row(i));
        let s = estimate(&one, &m).unwrap().sobol.unwrap();
        assert!(s.first[0][0].is_finite());
        let ci = s.intervals.unwrap();
        assert!(ci.first[0]
            .iter()
            .all(|&(lo, hi)| lo.is_nan() && hi.is_nan()));
        // Too few complete rows is an error, not a panic.
        assert!(estimate(&|i| base_row(i) < 1, &m).is_err());
        // `bootstrap = 0`: no intervals for the other bases.
        let lhs = SobolSampling {
            base: Base::Lhs,
            bootstrap: Some(0),
            ..m.clone()
        };
        let design = lhs.design(&params, 3).unwrap();
        let values: Vec<f64> = design.values.iter().map(|x| f(x)).collect();
        let data = DMatrix::from_column_slice(values.len(), 1, &values);
        let rows: Vec<usize> = (0..design.len()).collect();
        let s = lhs.estimate(&design, &rows, &data).unwrap().sobol.unwrap();
        assert!(s.intervals.is_none());
    }

    /// The `qmc` base's standard error of the mean was the Monte Carlo formula over the runs
    /// of A and B, many times the error of the scrambled nets' mean; it is now the spread of
    /// the replicate means. Mean of exp(x1) sin(x2 + x3) on U(0, 1)^3: (e - 1)(2 sin 1 - sin 2).
    #[test]
    fn qmc_base_standard_error_of_the_mean_is_the_replicate_spread_and_covers_the_mean() {
        let params = uniform_params(3, 0.0, 1.0);
        let m = SobolSampling {
            samples: 256,
            base: Base::Qmc,
            replicates: None,
            bootstrap: None,
            confidence: 0.95,
        };
        let f = |x: &[f64]| x[0].exp() * (x[1] + x[2]).sin();
        let exact = (1f64.exp() - 1.0) * (2.0 * 1f64.sin() - 2f64.sin());
        let (n, per) = (m.samples, m.samples / m.replicate_count());
        let mut covered = 0;
        for seed in 0..20 {
            let design = m.design(&params, seed).unwrap();
            let values: Vec<f64> = design.values.iter().map(|x| f(x)).collect();
            let data = DMatrix::from_column_slice(values.len(), 1, &values);
            let rows: Vec<usize> = (0..design.len()).collect();
            let e = m.estimate(&design, &rows, &data).unwrap();
            let se = e.std_error_mean.unwrap()[0];
            // Independently: base row k of replicate k / per, at row k of A and n + k of B.
            let means: Vec<f64> = (0..m.replicate_count())
                .map(|r| {
                    let ks = r * per..(r + 1) * per;
                    ks.map(|k| values[k] + values[n + k]).sum::<f64>() / (2 * per) as f64
                })
                .collect();
            let avg = means.iter().sum::<f64>() / means.len() as f64;
            let var = means.iter().map(|v| (v - avg).powi(2)).sum::<f64>() / 7.0;
            assert!((se - (var / 8.0).sqrt()).abs() <= 1e-12 * se, "seed {seed}");
            // Far below the Monte Carlo formula of before.
            assert!(se < 0.2 * e.std[0] / ((2 * n) as f64).sqrt(), "seed {seed}");
            // t(7) at 97.5 %: 2.365.
            if (e.mean[0] - exact).abs() <= 2.365 * se {
                covered += 1;
            }
        }
        assert!(
            covered >= 16,
            "the interval covered the mean in {covered} of 20 seeds"
        );
        // The other bases keep the Monte Carlo formula.
        let lhs = SobolSampling {
            base: Base::Lhs,
            bootstrap: Some(0),
            ..m.clone()
        };
        let design = lhs.design(&params, 1).unwrap();
        let values: Vec<f64> = design.values.iter().map(|x| f(x)).collect();
        let data = DMatrix::from_column_slice(values.len(), 1, &values);
        let rows: Vec<usize> = (0..design.len()).collect();
        let e = lhs.estimate(&design, &rows, &data).unwrap();
        let se = e.std_error_mean.unwrap()[0];
        assert!((se - e.std[0] / ((2 * n) as f64).sqrt()).abs() <= 1e-12 * se);
        // A column without spread has no error, whatever the rounding of replicate means.
        let e = run(&m, &params, |_| 0.1);
        assert_eq!(e.std_error_mean.unwrap(), vec![0.0]);
    }

    #[test]
    fn moments_from_the_gathered_columns_are_those_of_the_selected_rows_bit_for_bit() {
        // Regression: the moments are taken from each column as gathered for the indices (in
        // parallel), no longer from a copy of the A and B rows of the whole matrix. Every
        // point run (rows in place) and every 5th point failed (rows gathered), columns of
        // several magnitudes and a constant one.
        let params = uniform_params(2, 0.0, 1.0);
        let m = SobolSampling {
            samples: 128,
            base: Base::Qmc,
            replicates: None,
            bootstrap: Some(10),
            confidence: 0.9,
        };
        let design = m.design(&params, 5).unwrap();
        for skip in [usize::MAX, 5] {
            let rows: Vec<usize> = (0..design.len()).filter(|i| i % skip != 2).collect();
            let data = DMatrix::from_fn(rows.len(), 7, |r, c| {
                let x = &design.values[rows[r]];
                let c = c as f64;
                if c == 3.0 {
                    2.5
                } else {
                    10f64.powf(c - 2.0) * (x[0] + c * x[1] * x[1]) + 1e3 * c
                }
            });
            let e = m.estimate(&design, &rows, &data).unwrap();
            // The old computation: the A and B rows selected, then the moments.
            let blocks = PickFreezeRows::new(m.samples, 2, &rows);
            let ab: Vec<usize> = blocks.block_rows(0).chain(blocks.block_rows(1)).collect();
            let want = Estimate::from_sample(&data.select_rows(&ab));
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&e.mean), bits(&want.mean), "skip {skip}");
            assert_eq!(bits(&e.std), bits(&want.std), "skip {skip}");
            // The Monte Carlo standard error of the mc base (the qmc base's comes from its
            // replicates: qmc_base_standard_error_of_the_mean_is_the_replicate_spread_...).
            let mc = SobolSampling {
                base: Base::Mc,
                ..m.clone()
            };
            let mc_design = mc.design(&params, 5).unwrap();
            let mc_data = DMatrix::from_fn(rows.len(), 7, |r, c| {
                mc_design.values[rows[r]][0] * (c as f64 + 1.0) + mc_design.values[rows[r]][1]
            });
            let se = mc.estimate(&mc_design, &rows, &mc_data).unwrap();
            let want = Estimate::from_sample(&mc_data.select_rows(&ab));
            assert_eq!(
                bits(se.std_error_mean.as_ref().unwrap()),
                bits(want.std_error_mean.as_ref().unwrap()),
                "skip {skip}"
            );
            assert_eq!(e.draws, want.draws);
        }
    }

    #[test]
    fn a_constant_column_has_zero_indices() {
        let params = uniform_params(2, 0.0, 1.0);
        let m = SobolSampling {
            samples: 64,
            base: Base::Lhs,
            replicates: None,
            bootstrap: Some(20),
            confidence: 0.9,
        };
        let e = run(&m, &params, |_| 0.1);
        let s = e.sobol.unwrap();
        assert_eq!(s.first[0], vec![0.0, 0.0]);
        assert_eq!(s.intervals.unwrap().total[0], vec![(0.0, 0.0); 2]);
        // Rounding noise is no variance either.
        let e = run(&m, &params, |x| 0.1 + if x[0] > 0.5 { 1e-17 } else { 0.0 });
        assert_eq!(e.sobol.unwrap().total[0], vec![0.0, 0.0]);
    }

    #[test]
    fn settings_are_checked() {
        let params = uniform_params(600, 0.0, 1.0);
        let problem = Problem {
            parameters: &params,
            outputs: &[],
            quantities: 0,
            times: &[0.0, 1.0],
            system: None,
            correlation: None,
        };
        let m: SobolSampling = toml::from_str("samples = 64").unwrap();
        assert_eq!(m.base, Base::Qmc);
        assert!(m.validate(&problem).is_err(), "2d > 1000 Sobol' dimensions");
        let m: SobolSampling = toml::from_str("samples = 64\nbase = \"lhs\"").unwrap();
        assert!(m.validate(&problem).is_ok());
        let m: SobolSampling = toml::from_str("samples = 64\nconfidence = 1.0").unwrap();
        assert!(m.validate(&problem).is_err());
        let m: SobolSampling = toml::from_str("samples = 64\nbootstrap = 100000").unwrap();
        assert!(m.validate(&problem).is_err());
        // The analysis settings are not in the serialized settings (the study hash); the qmc
        // base's replicates are (the design of before, one net, gave no `replicates`: such a
        // folder is not resumed), and the mc and lhs bases serialize as before.
        let m: SobolSampling =
            toml::from_str("samples = 64\nbootstrap = 50\nconfidence = 0.9").unwrap();
        assert_eq!(
            serde_json::to_string(&m).unwrap(),
            r#"{"samples":64,"base":"qmc","replicates":8}"#
        );
        let m: SobolSampling = toml::from_str("samples = 64\nreplicates = 4").unwrap();
        assert_eq!(
            serde_json::to_string(&m).unwrap(),
            r#"{"samples":64,"base":"qmc","replicates":4}"#
        );
        for base in ["mc", "lhs"] {
            let text = format!("samples = 64\nbase = \"{base}\"\nbootstrap = 7");
            let m: SobolSampling = toml::from_str(&text).unwrap();
            assert_eq!(
                serde_json::to_string(&m).unwrap(),
                format!(r#"{{"samples":64,"base":"{base}"}}"#)
            );
        }
        assert!(toml::from_str::<SobolSampling>("samples = 64\nbase = \"grid\"").is_err());
        // Replicates of the qmc base: at least 2, dividing `samples` into powers of two.
        let params = uniform_params(3, 0.0, 1.0);
        let problem = Problem {
            parameters: &params,
            ..problem
        };
        let err = |text: &str| {
            let m: SobolSampling = toml::from_str(text).unwrap();
            m.validate(&problem).map(|_| ()).map_err(|e| e.0)
        };
        assert_eq!(err("samples = 64"), Ok(()));
        assert_eq!(err("samples = 12\nreplicates = 3"), Ok(()));
        let e = err("samples = 64\nreplicates = 1").unwrap_err();
        assert!(
            e.contains("`replicates` = 1") && e.contains("at least 2"),
            "{e}"
        );
        let e = err("samples = 100").unwrap_err();
        assert!(e.contains("not a multiple of `replicates` = 8"), "{e}");
        assert!(e.contains("samples = 128"), "{e}");
        let e = err("samples = 96").unwrap_err();
        assert!(
            e.contains("96 / 8 = 12") && e.contains("power of two"),
            "{e}"
        );
        assert!(e.contains("samples = 64 or 128"), "{e}");
        let e = err("samples = 8").unwrap_err();
        assert!(e.contains("8 / 8 = 1") && e.contains("samples = 16"), "{e}");
        assert_eq!(err("samples = 96\nreplicates = 3"), Ok(()));
        let e = err("samples = 64\nbase = \"mc\"\nreplicates = 4").unwrap_err();
        assert!(
            e.contains("`replicates` = 4 applies to base = \"qmc\" only"),
            "{e}"
        );
        assert!(e.contains("base = \"mc\""), "{e}");
        // `bootstrap` on a qmc base is not used: said so in the design's warnings.
        let m: SobolSampling = toml::from_str("samples = 16\nbootstrap = 50").unwrap();
        let w = m.design(&params, 1).unwrap().warnings;
        assert!(w[0].contains("`bootstrap` = 50 does not apply"), "{w:?}");
        let m: SobolSampling = toml::from_str("samples = 16").unwrap();
        assert!(m.design(&params, 1).unwrap().warnings.is_empty());
    }
}
