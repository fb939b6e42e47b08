//! From a method's estimates to the statistics of the report: quantiles and the PDF evolution
//! of every output, the distribution of every scalar quantity. Quantiles and densities come
//! from the draws the estimate names: the runs, or a large sample of its chaos surrogate.
//! Nothing here depends on which method produced the estimate.

use std::borrow::Cow;

use nalgebra::DMatrix;

use super::store::Record;
use crate::qoi::scalar::Code;
use crate::qoi::{kde, QoiSpec};
use crate::results::{OutputStats, ScalarChaosError, ScalarStats, SobolSummary};
use crate::spec::{Analysis, Study};
use crate::uq::distributions::RandomParameter;
use crate::uq::method::{Design, Draws, Estimate, MethodError, Sampling, Solution};
use crate::uq::moments;
use crate::uq::surrogate::NamedChaos;

/// Offset of the surrogate's random streams from the design's (independent draws).
const SURROGATE_SEED: u64 = 0x5eed_5a4d_0000_0000;

/// Failures of the analysis.
#[derive(Debug, thiserror::Error)]
pub enum AnalysisError {
    /// Too few runs succeeded.
    #[error("only {ok} successful runs: nothing to analyse")]
    TooFewRuns {
        /// Successful runs.
        ok: usize,
    },
    /// The estimator refused an output.
    #[error("output '{name}'")]
    Output {
        /// The output.
        name: String,
        /// Why.
        #[source]
        source: MethodError,
    },
    /// No run gave a value of a quantity.
    #[error(
        "quantity '{name}': no run gave a value ({never_hunts} never hunt, {never_stops} never stop)"
    )]
    NoValue {
        /// The quantity.
        name: String,
        /// Runs that never hunt.
        never_hunts: usize,
        /// Runs whose oscillation never stops.
        never_stops: usize,
    },
    /// The estimator refused a quantity (e.g. a weighted point without a value).
    #[error(
        "quantity '{name}' ({never_hunts} runs never hunt, {never_stops} never stop; use a method \
         that can leave points out, such as LHS or MC, or change the detection settings or the run length)"
    )]
    Quantity {
        /// The quantity.
        name: String,
        /// Runs that never hunt.
        never_hunts: usize,
        /// Runs whose oscillation never stops.
        never_stops: usize,
        /// Why.
        #[source]
        source: MethodError,
    },
    /// A `hunting_speed` quantity whose bracket does not contain the transition at every
    /// point that needs a value (all points, or any point of a weighted design).
    #[error(
        "quantity '{name}': at {decays_at_high} points the disturbance dies out even at the top of \
         the bracket (high = {high}) and at {hunts_at_low} it keeps hunting even at the bottom \
         (low = {low}); widen the bracket{more}"
    )]
    OutsideBracket {
        /// The quantity.
        name: String,
        /// The bracket.
        low: f64,
        /// The bracket.
        high: f64,
        /// Points that die out at `high`.
        decays_at_high: usize,
        /// Points that keep hunting at `low`.
        hunts_at_low: usize,
        /// Further advice.
        more: &'static str,
    },
    /// An estimate asks for draws it cannot give.
    #[error("output '{0}': the estimate has neither runs nor a chaos to draw from")]
    NoDraws(String),
}

/// The analysis settings of a study.
#[derive(Clone, Copy, Debug)]
pub struct Settings<'a> {
    /// `[analysis]`.
    pub analysis: &'a Analysis,
    /// The study's seed.
    pub seed: u64,
    /// The names of the random parameters, in study order (labels of Sobol' indices).
    pub parameters: &'a [RandomParameter],
}

impl<'a> Settings<'a> {
    /// The settings of `study`.
    pub fn of(study: &'a Study) -> Settings<'a> {
        Settings {
            analysis: &study.analysis,
            seed: study.seed,
            parameters: &study.parameters,
        }
    }

    /// The matrix quantiles and densities are taken from: `runs`, or draws of the chaos.
    fn draws<'m>(
        &self,
        name: &str,
        estimate: &Estimate,
        runs: Option<&'m DMatrix<f64>>,
    ) -> Result<Cow<'m, DMatrix<f64>>, AnalysisError> {
        match (estimate.draws, &estimate.chaos, runs) {
            (Draws::Chaos, Some(pce), _) => {
                let n = self.analysis.surrogate_samples.max(2);
                Ok(Cow::Owned(pce.sample(n, self.seed ^ SURROGATE_SEED)))
            }
            (Draws::Runs, _, Some(r)) => Ok(Cow::Borrowed(r)),
            _ => Err(AnalysisError::NoDraws(name.to_owned())),
        }
    }
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

/// Statistics of an output over `times` from its estimate; `runs` are the successful runs
/// (rows) over time (columns), if the model was run.
pub fn output_stats(
    name: &str,
    times: &[f64],
    estimate: &Estimate,
    runs: Option<&DMatrix<f64>>,
    settings: &Settings,
) -> Result<OutputStats, AnalysisError> {
    let a = settings.analysis;
    let samples = settings.draws(name, estimate, runs)?;
    let cols = moments::column_quantiles(&samples, &a.quantiles);
    let quantiles = a
        .quantiles
        .iter()
        .enumerate()
        .map(|(qi, &p)| (p, cols.iter().map(|c| c[qi]).collect()))
        .collect();
    let picked = thinned(times.len(), a.pdf_times);
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for &k in &picked {
        for v in samples.column(k).iter() {
            lo = lo.min(*v);
            hi = hi.max(*v);
        }
    }
    let pad = 0.05 * (hi - lo).max(1e-12 * hi.abs().max(1.0));
    let grid = kde::auto_grid(lo - pad, hi + pad, a.pdf_grid);
    let pdf = picked
        .iter()
        .map(|&k| {
            let col: Vec<f64> = samples.column(k).iter().copied().collect();
            kde::gaussian_kde(&col, None, &grid, kde::silverman_bandwidth(&col))
        })
        .collect();
    let (lower_3sigma, upper_3sigma) = OutputStats::band(&estimate.mean, &estimate.std, 3.0);
    Ok(OutputStats {
        name: name.to_owned(),
        times: times.to_vec(),
        mean: estimate.mean.clone(),
        std: estimate.std.clone(),
        lower_3sigma,
        upper_3sigma,
        quantiles,
        std_pce: estimate.std_chaos.clone(),
        std_error_mean: estimate.std_error_mean.clone(),
        sobol: estimate.sobol.clone(),
        pdf_times: picked.iter().map(|&k| times[k]).collect(),
        pdf_grid: grid,
        pdf,
        draws: estimate.draws,
        chaos_error: estimate.chaos_error.clone(),
    })
}

/// The values of one quantity over the successful runs, with their outcome codes.
struct QuantityRuns {
    /// Design indices of the runs with a valid value.
    rows: Vec<usize>,
    /// Their values.
    valid: Vec<f64>,
    never_hunts: usize,
    never_stops: usize,
}

/// Statistics of the scalar quantity `name` (exceedance `limits`) from its estimate and its
/// valid run values.
fn scalar_stats(
    name: &str,
    limits: &[f64],
    estimate: &Estimate,
    runs: QuantityRuns,
    settings: &Settings,
) -> Result<ScalarStats, AnalysisError> {
    let a = settings.analysis;
    let data = DMatrix::from_column_slice(runs.valid.len(), 1, &runs.valid);
    let density_samples: Vec<f64> = settings
        .draws(name, estimate, Some(&data))?
        .column(0)
        .iter()
        .copied()
        .collect();
    let mut sorted = density_samples.clone();
    sorted.sort_by(f64::total_cmp);
    let quantiles = a
        .quantiles
        .iter()
        .map(|&p| (p, moments::quantile(&sorted, p)))
        .collect();
    let (lo, hi) = (sorted[0], sorted[sorted.len() - 1]);
    let bw = kde::silverman_bandwidth(&sorted);
    let grid = kde::auto_grid(lo - 3.0 * bw, hi + 3.0 * bw, a.pdf_grid);
    let pdf = kde::gaussian_kde(&sorted, None, &grid, bw);
    let exceedance = limits
        .iter()
        .map(|&l| {
            let (p, se) = moments::exceedance_probability(&density_samples, l);
            (l, p, se)
        })
        .collect();
    let valid = runs.valid;
    Ok(ScalarStats {
        name: name.to_owned(),
        mean: estimate.mean[0],
        std: estimate.std[0],
        std_error_mean: estimate.std_error_mean.as_ref().map_or(0.0, |s| s[0]),
        n_valid: valid.len(),
        n_never_hunts: runs.never_hunts,
        n_never_stops: runs.never_stops,
        quantiles,
        min: valid.iter().copied().fold(f64::INFINITY, f64::min),
        max: valid.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        exceedance,
        pdf_x: grid,
        pdf,
        samples: valid,
        density_samples,
        sobol_first: estimate.sobol.as_ref().map(|s| s.first[0].clone()),
        sobol_total: estimate.sobol.as_ref().map(|s| s.total[0].clone()),
        sobol: estimate.sobol.as_ref().map(|s| {
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
        }),
    })
}

/// The values of the successful runs, in design order.
struct Runs<'a> {
    /// Design indices.
    rows: Vec<usize>,
    values: Vec<&'a [f64]>,
}

impl<'a> Runs<'a> {
    fn of(records: &'a [Option<Record>]) -> Runs<'a> {
        let (rows, values) = records
            .iter()
            .enumerate()
            .filter_map(|(i, r)| match r {
                Some(Record::Ok(v)) => Some((i, v.as_slice())),
                _ => None,
            })
            .unzip();
        Runs { rows, values }
    }

    /// Output `o` (of `nt` times each) as runs × times.
    fn output(&self, o: usize, nt: usize) -> DMatrix<f64> {
        DMatrix::from_fn(self.rows.len(), nt, |r, k| self.values[r][o * nt + k])
    }

    /// Quantity `qi`, stored after `base` series values as (value, code) pairs.
    fn quantity(&self, base: usize, qi: usize) -> QuantityRuns {
        let mut out = QuantityRuns {
            rows: Vec::new(),
            valid: Vec::new(),
            never_hunts: 0,
            never_stops: 0,
        };
        for (&row, v) in self.rows.iter().zip(&self.values) {
            match Code::from_f64(v[base + 2 * qi + 1]) {
                Code::Ok => {
                    out.rows.push(row);
                    out.valid.push(v[base + 2 * qi]);
                }
                Code::NeverHunts => out.never_hunts += 1,
                Code::NeverStops => out.never_stops += 1,
            }
        }
        out
    }
}

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
pub fn analyse_runs(
    study: &Study,
    method: &dyn Sampling,
    design: &Design,
    records: &[Option<Record>],
) -> Result<Analysed, AnalysisError> {
    let settings = Settings::of(study);
    let times = study.times();
    let nt = times.len();
    let runs = Runs::of(records);
    if runs.rows.len() < method.min_runs() {
        return Err(AnalysisError::TooFewRuns {
            ok: runs.rows.len(),
        });
    }
    let mut outputs = Vec::new();
    let mut output_chaos = Vec::new();
    for (o, name) in study.outputs.iter().enumerate() {
        let data = runs.output(o, nt);
        let estimate = method
            .estimate(design, &runs.rows, &data)
            .map_err(|source| AnalysisError::Output {
                name: name.clone(),
                source,
            })?;
        outputs.push(output_stats(
            name,
            &times,
            &estimate,
            Some(&data),
            &settings,
        )?);
        if let Some(pce) = estimate.chaos {
            output_chaos.push(NamedChaos {
                name: name.clone(),
                times: Some(times.clone()),
                pce,
                error: estimate.chaos_error,
            });
        }
    }
    let base = study.outputs.len() * nt;
    let mut quantities = Vec::new();
    let mut quantity_chaos = Vec::new();
    let scalars = study
        .qoi
        .iter()
        .flat_map(|q| q.quantity_names().into_iter().map(move |n| (n, q)));
    for (qi, (name, q)) in scalars.enumerate() {
        let qr = runs.quantity(base, qi);
        let outside = |more| match q {
            QoiSpec::HuntingSpeed(h) => Some(AnalysisError::OutsideBracket {
                name: name.clone(),
                low: h.low,
                high: h.high,
                decays_at_high: qr.never_hunts,
                hunts_at_low: qr.never_stops,
                more,
            }),
            _ => None,
        };
        if qr.valid.is_empty() {
            if let Some(e) = outside("") {
                return Err(e);
            }
            return Err(AnalysisError::NoValue {
                name,
                never_hunts: qr.never_hunts,
                never_stops: qr.never_stops,
            });
        }
        let data = DMatrix::from_column_slice(qr.valid.len(), 1, &qr.valid);
        let estimate = method.estimate(design, &qr.rows, &data).map_err(|source| {
            let more = " (or use a method that can leave points out, such as LHS or MC)";
            outside(more)
                .filter(|_| qr.never_hunts + qr.never_stops > 0)
                .unwrap_or(AnalysisError::Quantity {
                    name: name.clone(),
                    never_hunts: qr.never_hunts,
                    never_stops: qr.never_stops,
                    source,
                })
        })?;
        quantities.push(scalar_stats(&name, q.limits(), &estimate, qr, &settings)?);
        if let Some(pce) = estimate.chaos {
            quantity_chaos.push(NamedChaos {
                name: name.clone(),
                times: None,
                pce,
                error: estimate.chaos_error,
            });
        }
    }
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
    let settings = Settings::of(study);
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

    #[test]
    fn thinning_keeps_ends() {
        assert_eq!(thinned(5, 10), vec![0, 1, 2, 3, 4]);
        let t = thinned(501, 100);
        assert_eq!(t[0], 0);
        assert_eq!(*t.last().unwrap(), 500);
        assert!(t.len() <= 101);
    }
}
