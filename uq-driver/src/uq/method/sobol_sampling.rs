//! Sobol' indices by sampling: the pick-freeze design of Saltelli — two base samples `A` and
//! `B` of `samples` points each and, for every input `i`, `AB_i` (`A` with column `i` from
//! `B`): `samples × (d + 2)` model runs, laid out `A`, `B`, `AB_1`, …, `AB_d` (point `k` of
//! block `b` is design point `b × samples + k`).
//!
//! `A` and `B` are the two halves of one `2d`-dimensional design of `samples` points: a
//! scrambled Sobol' sequence (`base = "qmc"`, the default; scrambling key `(seed, 0)`), Monte
//! Carlo (`"mc"`) or a Latin hypercube (`"lhs"`), mapped through each input's quantile function.
//!
//! Estimators ([`crate::uq::hd::sensitivity`]): first order by Saltelli (2010), total by
//! Jansen (1999), normalised by the variance of the `2 × samples` values of `A` and `B`, on
//! the values less their mean over `A` and `B` (same expectation; centring cuts the variance
//! of the first-order estimator when the mean is large against the spread);
//! percentile bootstrap intervals at `confidence` from `bootstrap` resamples of the rows
//! (the same resampled rows for every column; resample `k` from the ChaCha20 stream
//! `(0x5eed_b007, k)`, so the intervals are reproducible). A row whose runs did not all
//! succeed is left out of every block. A column without variance (e.g. a fixed initial value)
//! gets indices 0 with intervals `[0, 0]`, as a chaos gives.
//!
//! Mean, Std and the standard error of the mean come from the runs of `A` and `B`
//! (Monte Carlo formula); quantiles and densities from every run (each block follows the
//! input law).

use nalgebra::DMatrix;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::design::Design;
use super::error::{InvalidSettings, MethodError};
use super::qmc::check_sobol_points;
use super::estimate::{Estimate, Sobol, SobolIntervals};
use super::traits::{DesignSize, Evaluation, Method, MethodSummary, Problem, Sampling};
use crate::uq::distributions::Germ;
use crate::uq::hd::sensitivity::{self, SensitivityError};
use crate::uq::hd::sobol_seq::{self, Sobol as SobolSequence};
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
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SobolSampling {
    /// Base sample size N (at least 2): N (d + 2) model runs.
    pub samples: usize,
    /// Where `A` and `B` come from (default `qmc`).
    #[serde(default)]
    pub base: Base,
    /// Bootstrap resamples for the confidence intervals (default 200, at most 10 000; 0: no
    /// intervals). Analysis only: not part of the study hash, so a changed value re-analyses
    /// the stored runs instead of refusing the folder.
    #[serde(default = "default_bootstrap", skip_serializing)]
    pub bootstrap: usize,
    /// Confidence level of the intervals (default 0.95; analysis only, like `bootstrap`).
    #[serde(default = "default_confidence", skip_serializing)]
    pub confidence: f64,
}

fn default_bootstrap() -> usize {
    200
}

fn default_confidence() -> f64 {
    0.95
}

impl Method for SobolSampling {
    fn kind(&self) -> &'static str {
        "sobol_sampling"
    }

    fn label(&self, dim: usize) -> String {
        format!(
            "sobol_sampling {}x{} ({:?})",
            self.samples,
            dim + 2,
            self.base
        )
        .to_lowercase()
    }

    fn validate(&self, problem: &Problem) -> Result<(), InvalidSettings> {
        let d = problem.parameters.len();
        if self.samples < 2 {
            return Err(InvalidSettings("`samples` must be at least 2".into()));
        }
        if self.bootstrap > MAX_BOOTSTRAP {
            return Err(InvalidSettings(format!(
                "`bootstrap` = {} resamples: at most {MAX_BOOTSTRAP}",
                self.bootstrap
            )));
        }
        if !(self.confidence > 0.0 && self.confidence < 1.0) {
            return Err(InvalidSettings(format!(
                "`confidence` = {} must be between 0 and 1",
                self.confidence
            )));
        }
        if self.base == Base::Qmc {
            let hint = " (twice the random parameters); use base = \"lhs\"";
            check_sobol_points(2 * d, self.samples, hint)?;
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
        d.insert("bootstrap".into(), self.bootstrap.into());
        d.insert("confidence".into(), self.confidence.into());
        d.insert(
            "runs".into(),
            (self.samples.saturating_mul(dim + 2)).into(),
        );
        d.insert(
            "estimators".into(),
            "first order: Saltelli (2010); total: Jansen (1999); percentile bootstrap intervals"
                .into(),
        );
        d.insert(
            "standard_error".into(),
            "Monte Carlo formula std / sqrt(2 samples) over the runs of A and B (exact for \
             base = \"mc\", an overestimate for lhs and, typically, qmc)"
                .into(),
        );
        s
    }

    fn evaluation(&self) -> Evaluation<'_> {
        Evaluation::Sampling(self)
    }
}

impl SobolSampling {
    /// The `samples` points of the `2d`-dimensional base design in the unit cube.
    fn base_points(&self, d: usize, seed: u64) -> Result<Vec<Vec<f64>>, MethodError> {
        let n = self.samples;
        Ok(match self.base {
            Base::Qmc => {
                let invalid =
                    |e: sobol_seq::SobolError| MethodError::Invalid(InvalidSettings(e.to_string()));
                SobolSequence::scrambled(2 * d, seed, 0)
                    .map_err(invalid)?
                    .points(0, n)
                    .map_err(invalid)?
            }
            Base::Mc => sampling::monte_carlo(n, 2 * d, seed),
            Base::Lhs => sampling::latin_hypercube(n, 2 * d, seed),
        })
    }
}

impl Sampling for SobolSampling {
    /// In the independent uniform space (with correlated inputs the indices are those of the
    /// independent germs, one per input in study order, as for a chaos).
    fn design(&self, inputs: &RandomInputs, seed: u64) -> Result<Design, MethodError> {
        let d = inputs.len();
        let base = self.base_points(d, seed)?;
        let (a, b): (Vec<Vec<f64>>, Vec<Vec<f64>>) = base
            .into_iter()
            .map(|p| (p[..d].to_vec(), p[d..].to_vec()))
            .unzip();
        let points = sensitivity::pick_freeze_design(&a, &b)?;
        let mut design = Design::mapped(Germ::Uniform, points, None, inputs);
        if self.base == Base::Qmc && !self.samples.is_power_of_two() {
            design.warnings.push(format!(
                "sobol_sampling: samples = {} is not a power of two: the Sobol' base points are \
                 balanced only in blocks of 2^m points (use samples = {})",
                self.samples,
                self.samples.next_power_of_two()
            ));
        }
        Ok(design)
    }

    fn estimate(
        &self,
        design: &Design,
        rows: &[usize],
        data: &DMatrix<f64>,
    ) -> Result<Estimate, MethodError> {
        let n = self.samples;
        let d = design.points.first().map_or(0, Vec::len);
        let blocks = PickFreezeRows::new(n, d, rows);
        if blocks.complete.len() < 2 {
            return Err(SensitivityError::TooFew(blocks.complete.len()).into());
        }
        let (moments, columns) = self.columns(&blocks, data)?;
        let intervals = (self.bootstrap > 0).then(|| SobolIntervals {
            level: self.confidence,
            first: columns.iter().map(|c| c.first_ci.clone()).collect(),
            total: columns.iter().map(|c| c.total_ci.clone()).collect(),
        });
        Ok(Estimate {
            sobol: Some(Sobol {
                first: columns.iter().map(|c| c.first.clone()).collect(),
                total: columns.iter().map(|c| c.total.clone()).collect(),
                intervals,
            }),
            ..moments
        })
    }

    fn planned_runs(&self, dim: usize) -> Option<f64> {
        Some(self.samples as f64 * (dim as f64 + 2.0))
    }

    fn draws_from_chaos(&self) -> bool {
        false
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
                (Estimate::from_sample(&ab), centred(values, m))
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
        let mut indices = if self.bootstrap == 0 {
            varying
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
                .collect::<Result<Vec<_>, SensitivityError>>()?
        } else {
            sensitivity::pick_freeze_bootstrap_columns(
                &varying,
                m,
                d,
                self.bootstrap,
                self.confidence,
                BOOTSTRAP_SEED,
            )?
            .into_iter()
            .map(|e| ColumnIndices {
                first: e.estimate.first,
                total: e.estimate.total,
                first_ci: e.first_ci,
                total_ci: e.total_ci,
            })
            .collect()
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
                .map(|i| RandomParameter {
                    name: format!("x{}", i + 1),
                    distribution: Distribution::uniform(low, high).unwrap(),
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
                bootstrap: 100,
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
            bootstrap: 0,
            confidence: 0.95,
        };
        let design = m.design(&params, 3).unwrap();
        let f = |x: &[f64]| x[0].sin() + 7.0 * x[1].sin().powi(2);
        // Every 7th point fails.
        let rows: Vec<usize> = (0..design.len()).filter(|i| i % 7 != 3).collect();
        let values: Vec<f64> = rows.iter().map(|&i| f(&design.values[i])).collect();
        let data = DMatrix::from_column_slice(values.len(), 1, &values);
        let e = m.estimate(&design, &rows, &data).unwrap();
        // x3 does not matter: its indices are 0 up to sampling error.
        let s = e.sobol.unwrap();
        assert!(s.first[0][2].abs() < 0.05 && s.total[0][2].abs() < 1e-12);
        assert!(s.intervals.is_none());
        // Too few complete rows is an error, not a panic.
        let e = m.estimate(&design, &rows[..3], &data.rows(0, 3).into_owned());
        assert!(e.is_err());
    }

    #[test]
    fn moments_from_the_gathered_columns_are_those_of_the_selected_rows_bit_for_bit() {
        // Issue 15: the moments are taken from each column as gathered for the indices (in
        // parallel), no longer from a copy of the A and B rows of the whole matrix. Every
        // point run (rows in place) and every 5th point failed (rows gathered), columns of
        // several magnitudes and a constant one.
        let params = uniform_params(2, 0.0, 1.0);
        let m = SobolSampling {
            samples: 128,
            base: Base::Qmc,
            bootstrap: 10,
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
            assert_eq!(
                bits(e.std_error_mean.as_ref().unwrap()),
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
            bootstrap: 20,
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
        // The analysis settings are not in the serialized settings (the study hash).
        let m: SobolSampling =
            toml::from_str("samples = 64\nbootstrap = 50\nconfidence = 0.9").unwrap();
        assert_eq!(
            serde_json::to_string(&m).unwrap(),
            r#"{"samples":64,"base":"qmc"}"#
        );
        assert!(toml::from_str::<SobolSampling>("samples = 64\nbase = \"grid\"").is_err());
    }
}
