//! The analysis of a two-level (nested) study: for every output and quantity, the inner
//! method's estimate per outer sample ([`Nested::conditional`]), the variance split with its
//! bootstrap intervals ([`split`]), and the marginal statistics over both levels.
//!
//! - Marginal mean and Std: from the split (the mean of the conditional means; the Std from
//!   `E[Var_inner] + Var_outer[E_inner]`, the latter corrected for the inner sampling error).
//! - Marginal P(q > limit): the mean over the outer samples of the conditional probabilities,
//!   each from the inner runs (sampled inner designs) or from draws of the inner chaos; its
//!   standard error `sd / sqrt(N)` and a bootstrap interval.
//! - Marginal quantiles and densities: from the pooled conditional draws, the same number from
//!   every outer sample (chaos inner methods), or from all runs (sampled inner designs).
//! - Outputs over time: the marginal mean and Std and the split at every time; quantiles and
//!   the PDF evolution from at most [`SERIES_DRAWS`] pooled draws.

use crate::text::file_name::stem;
use nalgebra::DMatrix;
use rand::RngCore;
use rayon::prelude::*;

use crate::qoi::QoiSpec;
use crate::results::{
    ConditionalChaos, ConditionalTable, Convergence, ExceedanceCount, ExceedanceInterval,
    NestedScalar, OutputSplit, OutputStats, ScalarStats, VarianceSplit,
};
use crate::spec::Study;
use crate::study::analysis::{
    nest_exceedance_count, output_error, output_stats, quantity_error, scalar_stats, series_error,
    surrogates_of, Analysed, AnalysisError, QuantityRuns, Runs, Settings, CHAOS_ERROR,
};
use crate::study::store::StoredRuns;
use crate::uq::method::nested::split::{self, Split};
use crate::uq::method::nested::{marginal, Blocks, Conditional, Nested};
use crate::uq::method::{Design, Draws, Estimate, MethodError, Sampling};
use crate::uq::{moments, rng};

/// Tag of the streams of the conditional chaos draws.
const DRAWS_SEED: u64 = 0x6e65_7374_6564_0d00;
/// Tag of the bootstrap streams.
const BOOTSTRAP_SEED: u64 = 0x6e65_7374_6564_0b00;
/// Most pooled draws of an output over time (memory: draws × times).
pub const SERIES_DRAWS: usize = 4096;

/// What [`analyse`] finds.
#[derive(Clone, Debug)]
pub struct NestedAnalysed {
    /// Marginal statistics of every output and quantity (quantities with their split).
    pub analysed: Analysed,
    /// The split of every output over time.
    pub splits: Vec<OutputSplit>,
    /// Notes for the user.
    pub warnings: Vec<String>,
}

/// Statistics of every output and quantity of a nested study whose points have all been run.
pub fn analyse(
    study: &Study,
    method: &Nested,
    design: &Design,
    records: &StoredRuns,
) -> Result<NestedAnalysed, AnalysisError> {
    let surrogates = surrogates_of(study);
    let settings = Settings::of(study, &surrogates);
    let times = study.times();
    let nt = times.len();
    let runs = Runs::at_least(records, method.min_runs())?;
    let blocks = method
        .blocks(design)
        .map_err(output_error("(the nested design)"))?;
    let mut out = NestedAnalysed {
        analysed: Analysed {
            outputs: Vec::new(),
            quantities: Vec::new(),
            output_chaos: Vec::new(),
            quantity_chaos: Vec::new(),
        },
        splits: Vec::new(),
        warnings: few_outer_samples(blocks.outer_values.len())
            .into_iter()
            .collect(),
    };
    for (o, name) in study.outputs.iter().enumerate() {
        let data = runs.output(o, nt)?;
        let (stats, split, warning) =
            output(method, &blocks, name, &times, &runs.rows, &data, &settings)?;
        out.warnings.extend(warning);
        out.splits.push(split);
        out.analysed.outputs.push(stats);
    }
    let base = study.outputs.len() * nt;
    for (qi, (name, q)) in study.scalar_quantities().enumerate() {
        let qr = runs.quantity(base, qi)?;
        if qr.valid.is_empty() {
            return Err(quantity_error(&name, q, &qr, None));
        }
        let scalar = Scalar { name: &name, q, qi };
        let (stats, warnings) = quantity(study, method, &blocks, scalar, qr, &settings)?;
        out.warnings.extend(warnings);
        out.analysed.quantities.push(stats);
    }
    Ok(out)
}

/// Fewer outer samples than this get a note that the intervals of the Std and of the split
/// may cover less than their level.
pub const FEW_OUTER: usize = 32;

/// The note of a design of `n` outer samples, below [`FEW_OUTER`]: an interval of a variance
/// over few outer samples rests on their spread alone (simulated 16 × 16 studies: 89–96 %
/// coverage of nominal 95 % depending on the skewness of the outer level; the percentile
/// bootstrap alone 73–87 %).
fn few_outer_samples(n: usize) -> Option<String> {
    (n < FEW_OUTER).then(|| {
        format!(
            "only {n} outer samples: the intervals of the Std and of the variance split over \
             the outer samples may cover less than {} % (a variance from fewer than {FEW_OUTER} \
             samples is itself uncertain, more so when the outer level is skewed); use at \
             least {FEW_OUTER} outer samples for intervals to rely on",
            split::LEVEL * 100.0
        )
    })
}

/// The marginal statistics of output `name` (its runs `data`, design rows `rows`), its split
/// over time and the note of a large inner chaos error.
fn output(
    method: &Nested,
    blocks: &Blocks,
    name: &str,
    times: &[f64],
    rows: &[usize],
    data: &DMatrix<f64>,
    settings: &Settings,
) -> Result<(OutputStats, OutputSplit, Option<String>), AnalysisError> {
    let nt = data.ncols();
    let fail = output_error(name);
    let cond = method.conditional(blocks, rows, data).map_err(fail)?;
    let estimate = marginal(&cond, nt).map_err(fail)?;
    let splits: Vec<Split> = (0..nt).map(|j| Split::all(&cond.column(j))).collect();
    let pooled = pooled_series(&cond, data, settings, nt);
    let mut stats: OutputStats = output_stats(name, times, &estimate, Some(&pooled), settings)?;
    stats.draws = draws_of(&cond);
    // Over the outer samples and their runs, not over the pooled draws.
    let at = stats
        .convergence_time
        .and_then(|t| times.iter().position(|&x| x == t));
    stats.convergence = at.and_then(|k| outer_convergence(&cond.column(k), &runs_of(&cond)));
    let split = OutputSplit {
        name: name.to_owned(),
        times: times.to_vec(),
        mean: stats.mean.clone(),
        std: stats.std.clone(),
        var_inner: splits.iter().map(|s| s.var_inner).collect(),
        var_outer: splits.iter().map(|s| s.var_outer).collect(),
        outer_samples: cond.present().len(),
    };
    Ok((stats, split, inner_chaos_warning(name, &cond, Some(times))))
}

/// The nested estimate over the first n outer samples against the runs they hold (in design
/// order, at about 30 values of n on a log scale): its mean, Std and the standard error of
/// its mean between outer samples. So the axis counts the study's real runs, not the pooled
/// draws its densities are taken from.
fn outer_convergence(c: &split::Conditionals, runs_of: &[usize]) -> Option<Convergence> {
    let n = c.len();
    if n < 4 || runs_of.len() != n {
        return None;
    }
    let mut points: Vec<usize> = (0..=30)
        .map(|i| (2.0 * (n as f64 / 2.0).powf(i as f64 / 30.0)).round() as usize)
        .collect();
    points.dedup();
    let idx: Vec<usize> = (0..n).collect();
    let splits: Vec<Split> = points.iter().map(|&m| Split::of(c, &idx[..m])).collect();
    Some(Convergence {
        axis: "runs".into(),
        x: points
            .iter()
            .map(|&m| runs_of[..m].iter().sum::<usize>() as f64)
            .collect(),
        mean: splits.iter().map(|s| s.mean).collect(),
        std: splits.iter().map(Split::std).collect(),
        std_of_order: Vec::new(),
        std_error_mean: splits.iter().map(|s| s.std_error_mean).collect(),
    })
}

/// The runs of each outer sample that has an estimate, in the order of
/// [`Conditional::column`].
fn runs_of(cond: &Conditional) -> Vec<usize> {
    cond.present()
        .iter()
        .map(|&k| cond.data_rows[k].len())
        .collect()
}

/// Where the densities of the conditional estimates come from.
fn draws_of(cond: &Conditional) -> Draws {
    match cond.estimates.iter().flatten().next() {
        Some(e) => e.draws,
        None => Draws::Runs,
    }
}

/// `n` draws of every column of outer sample `k`'s inner estimate: its runs (the rows of
/// `data` that belong to it, all of them) or draws of its chaos.
fn draws(cond: &Conditional, k: usize, data: &DMatrix<f64>, n: usize, seed: u64) -> DMatrix<f64> {
    let e = cond.estimates[k].as_ref().expect("present outer sample");
    match (&e.chaos, e.draws) {
        (Some(pce), Draws::Chaos) => {
            pce.sample(n, rng::stream(seed ^ DRAWS_SEED, k as u64).next_u64())
        }
        _ => data.select_rows(&cond.data_rows[k]),
    }
}

/// The pooled draws of an output over time: at most [`SERIES_DRAWS`] in all, the same number
/// from every outer sample (chaos), or every run (sampled inner designs).
fn pooled_series(
    cond: &Conditional,
    data: &DMatrix<f64>,
    settings: &Settings,
    nt: usize,
) -> DMatrix<f64> {
    let present = cond.present();
    if draws_of(cond) == Draws::Runs {
        let rows: Vec<usize> = present
            .iter()
            .flat_map(|&k| cond.data_rows[k].iter().copied())
            .collect();
        return data.select_rows(&rows);
    }
    let total = settings.analysis.surrogate_samples.clamp(2, SERIES_DRAWS);
    let per = total.div_ceil(present.len()).max(1);
    let parts: Vec<DMatrix<f64>> = present
        .par_iter()
        .map(|&k| draws(cond, k, data, per, settings.seed))
        .collect();
    let mut pooled = DMatrix::zeros(per * parts.len(), nt);
    for (i, p) in parts.iter().enumerate() {
        pooled.rows_mut(i * per, per).copy_from(p);
    }
    pooled
}

/// One scalar quantity: its name, the `[[qoi]]` that defines it, its number among the
/// study's scalars.
#[derive(Clone, Copy)]
struct Scalar<'a> {
    name: &'a str,
    q: &'a QoiSpec,
    qi: usize,
}

/// The statistics of a scalar quantity and notes: its corrected outer variance is negative,
/// the inner chaos's error estimate is large in some outer samples.
fn quantity(
    study: &Study,
    method: &Nested,
    blocks: &Blocks,
    scalar: Scalar,
    qr: QuantityRuns,
    settings: &Settings,
) -> Result<(ScalarStats, Vec<String>), AnalysisError> {
    let Scalar { name, q, qi } = scalar;
    let fail = |source: MethodError| quantity_error(name, q, &qr, Some(source));
    let data = DMatrix::from_column_slice(qr.valid.len(), 1, &qr.valid);
    let cond = method.conditional(blocks, &qr.rows, &data).map_err(fail)?;
    let estimate: Estimate = marginal(&cond, 1).map_err(fail)?;
    let present = cond.present();
    let n_draws = settings.analysis.surrogate_samples.max(2);
    let per_outer: Vec<Vec<f64>> = present
        .par_iter()
        .map(|&k| {
            draws(&cond, k, &data, n_draws, settings.seed ^ qi as u64)
                .column(0)
                .iter()
                .copied()
                .collect()
        })
        .collect();
    let limits = q.limits().to_vec();
    let exceedance: Vec<Vec<f64>> = limits
        .iter()
        .map(|&l| {
            per_outer
                .iter()
                .map(|d| moments::exceedance_probability(d, l).0)
                .collect()
        })
        .collect();
    let c = cond.column(0);
    let s = Split::all(&c);
    let ci = split::bootstrap(
        &c,
        &exceedance,
        split::RESAMPLES,
        settings.seed ^ BOOTSTRAP_SEED ^ qi as u64,
    );
    // The same number of draws from every outer sample, so that the pool is the mixture.
    let equal = per_outer.iter().map(Vec::len).min().unwrap_or(0);
    let pooled: Vec<f64> = if draws_of(&cond) == Draws::Runs {
        per_outer.iter().flatten().copied().collect()
    } else {
        let per = n_draws.div_ceil(present.len()).clamp(1, equal.max(1));
        per_outer
            .iter()
            .flat_map(|d| d[..per].iter().copied())
            .collect()
    };
    let table = conditional_table(study, blocks, &cond, &limits, &exceedance);
    let n = present.len() as f64;
    let mut stats = scalar_stats(name, q, &estimate, qr, settings, Some(pooled), None)?;
    stats.draws = draws_of(&cond);
    stats.convergence = outer_convergence(&c, &runs_of(&cond)).filter(|_| !stats.deterministic);
    stats.exceedance = exceedance
        .iter()
        .zip(&limits)
        .map(|(p, &l)| {
            let m = p.iter().sum::<f64>() / n;
            let var = p.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0);
            (l, m, (var / n).sqrt())
        })
        .collect();
    let parts = Parts {
        split: &s,
        ci: &ci,
        limits: &limits,
        exceedance: &exceedance,
    };
    let nested = nested_scalar(name, parts, table);
    let range = [stats.min, stats.max];
    for (count, e) in stats
        .exceedance_counts
        .iter_mut()
        .zip(&nested.exceedance_ci)
    {
        nested_count(count, e, &per_outer, stats.draws, range);
    }
    if !stats.exceedance_counts.is_empty() {
        stats.reliability = Some(super::counted_probabilities(
            &stats.exceedance_counts,
            settings.kind,
        ));
    }
    stats.nested = Some(nested);
    let mut warnings: Vec<String> = inner_chaos_warning(name, &cond, None).into_iter().collect();
    warnings.extend((s.var_outer < 0.0).then(|| {
        format!(
            "{}: the estimated variance between outer samples, {:.3e}, is below the inner \
             sampling error it is corrected for ({:.3e}); the outer share is counted as 0 \
             (more inner runs or outer samples would resolve it)",
            name, s.var_outer_plugin, s.correction
        )
    }));
    Ok((stats, warnings))
}

/// The count of P(q > `e.limit`) of a nested study: every draw of every outer sample
/// counted (the draws the conditional probabilities come from, `per_outer`), so that with
/// the same number from each outer sample `exceeded / of` is the marginal P of the two-level
/// table (the count line said 0.613 from 1 250 draws per outer
/// sample beside an interval of the mean of the conditional probabilities, 0.608); `p` is
/// that mean in any case (outer samples with different numbers of successful runs weigh
/// equally); the interval and its kind are those of `e`. `range`: the smallest and largest
/// model run; a limit outside it, counted over chaos draws, rests on the extrapolation of the
/// inner chaoses alone (`beyond_runs`).
fn nested_count(
    count: &mut ExceedanceCount,
    e: &ExceedanceInterval,
    per_outer: &[Vec<f64>],
    draws: Draws,
    range: [f64; 2],
) {
    count.of = per_outer.iter().map(Vec::len).sum();
    count.exceeded = per_outer.iter().flatten().filter(|&&x| x > e.limit).count();
    count.p = e.p;
    nest_exceedance_count(count, e.ci, per_outer.len(), draws);
    count.ci_kind = e.ci_kind;
    count.note_range(draws, range);
}

/// The inner chaos's own truncation-error estimate (per outer sample: its largest over the
/// columns whose Std is above 1e-3 of the largest; `order_difference` over a series weighted
/// by the variance) where it exceeds [`CHAOS_ERROR`] in some outer samples, summarised: how
/// many, the largest and where. A stand-alone chaos study warns of each; the nested study
/// dropped them. `times`: those of an output, `None` for a quantity.
fn inner_chaos_warning(name: &str, cond: &Conditional, times: Option<&[f64]>) -> Option<String> {
    let mut kind = None;
    let mut present = 0;
    let mut over: Vec<(usize, f64, Option<usize>)> = Vec::new();
    for (k, e) in cond.estimates.iter().enumerate() {
        let Some(e) = e else { continue };
        present += 1;
        let Some(err) = &e.chaos_error else { continue };
        kind = Some(err.kind);
        let worst = series_error(err, &e.std);
        if let Some((v, j)) = worst.filter(|w| w.0 > CHAOS_ERROR) {
            over.push((k, v, j));
        }
    }
    let (k, v, j) = *over.iter().max_by(|a, b| a.1.total_cmp(&b.1))?;
    let at = match (times, j) {
        (Some(t), Some(j)) => t.get(j).map_or(String::new(), |t| format!(", t = {t} s")),
        _ => String::new(),
    };
    Some(format!(
        "{name}: the inner chaos's own truncation-error estimate ({}; as the warnings judge \
         it: a sparse grid's extrapolated to its level, a sparse regression's checked by \
         k-fold cross-validation) exceeds {} % of the conditional variance in {} of {present} outer samples (largest {:.1} % at outer \
         sample {k}{at}): the conditional mean, Std, P(q > limit | outer) and Sobol' indices \
         of those samples may be far off, and the intervals over the outer samples do not \
         cover this error; raise the inner order or number of runs (per outer sample: the \
         `{}` column of the conditional table)",
        kind.map_or("", |k| k.name()),
        100.0 * CHAOS_ERROR,
        over.len(),
        100.0 * v,
        kind.map_or("", |k| k.name()),
    ))
}

/// The split of a quantity with its intervals and the conditional exceedance probabilities
/// (`exceedance[l][k]`: limit `l`, outer sample `k`).
struct Parts<'a> {
    split: &'a Split,
    ci: &'a split::Intervals,
    limits: &'a [f64],
    exceedance: &'a [Vec<f64>],
}

/// What a nested study adds to the statistics of quantity `name`.
fn nested_scalar(name: &str, parts: Parts, table: ConditionalTable) -> NestedScalar {
    let outer = table.mean.len();
    let Parts {
        split: s,
        ci,
        limits,
        exceedance,
    } = parts;
    let n = exceedance.first().map_or(0, Vec::len);
    let (fi, fo) = s.fractions();
    let (mean_ci, mean_ci_kind) = split::mean_interval(&table.mean, ci.mean);
    NestedScalar {
        variance_split: VarianceSplit {
            inner: fi,
            outer: fo,
            inner_ci: ci.inner,
            outer_ci: ci.outer,
            var_inner: s.var_inner,
            var_outer: s.var_outer,
            var_outer_plugin: s.var_outer_plugin,
            correction: s.correction,
        },
        mean_ci,
        mean_ci_kind,
        std_ci: ci.std,
        exceedance_ci: exceedance
            .iter()
            .zip(limits)
            .zip(&ci.exceedance)
            .map(|((p, &limit), &boot)| {
                let mut sorted = p.clone();
                sorted.sort_by(f64::total_cmp);
                let (ci, ci_kind) = split::exceedance_interval(p, boot);
                ExceedanceInterval {
                    limit,
                    p: p.iter().sum::<f64>() / n as f64,
                    ci,
                    ci_kind,
                    conditional_min: sorted[0],
                    conditional_median: moments::quantile(&sorted, 0.5),
                    conditional_max: sorted[sorted.len() - 1],
                }
            })
            .collect(),
        intervals: format!(
            "{} % percentile bootstrap over the {} outer samples ({} resamples); for the mean \
             and P(q > limit) Student's t on the mean over the outer samples where that is \
             wider (few outer samples), and when every conditional P is 0 (or 1) the \
             one-sided bound 1 − 0.05^(1/{outer}) (or 0.05^(1/{outer})); for the Std and the \
             split joined with Student's t on ln(variance) and logit(outer share) with the \
             jackknife standard error over the outer samples",
            split::LEVEL * 100.0,
            outer,
            split::RESAMPLES
        ),
        outer_samples: outer,
        conditional_csv: format!("{}_conditional.csv", stem(name)),
        conditional: table,
    }
}

/// One row per outer sample with an estimate.
fn conditional_table(
    study: &Study,
    blocks: &Blocks,
    cond: &Conditional,
    limits: &[f64],
    exceedance: &[Vec<f64>],
) -> ConditionalTable {
    let names = |idx: &[usize]| -> Vec<String> {
        idx.iter()
            .map(|&j| study.parameters[j].name.clone())
            .collect()
    };
    let present = cond.present();
    let est: Vec<&Estimate> = cond.estimates.iter().flatten().collect();
    let all = |f: &dyn Fn(&Estimate) -> Option<f64>| -> Option<Vec<f64>> {
        est.iter().map(|e| f(e)).collect()
    };
    let chaos = est
        .iter()
        .map(|e| e.chaos.as_ref())
        .collect::<Option<Vec<_>>>()
        .map(|c| union_of_bases(&c));
    let chaos_error = est
        .iter()
        .map(|e| e.chaos_error.as_ref())
        .collect::<Option<Vec<_>>>()
        .and_then(|errs| {
            let name = errs.first()?.kind.name().to_owned();
            Some((name, errs.iter().map(|e| e.values[0]).collect()))
        });
    ConditionalTable {
        outer_names: names(&blocks.levels.outer),
        inner_names: names(&blocks.levels.inner),
        outer_index: present.clone(),
        outer_values: present
            .iter()
            .map(|&k| blocks.outer_values[k].clone())
            .collect(),
        runs: present.iter().map(|&k| cond.data_rows[k].len()).collect(),
        mean: est.iter().map(|e| e.mean[0]).collect(),
        std: est.iter().map(|e| e.std[0]).collect(),
        std_chaos: all(&|e| e.std_chaos.as_ref().map(|s| s[0])),
        std_error_mean: all(&|e| e.std_error_mean.as_ref().map(|s| s[0])),
        limits: limits.to_vec(),
        exceedance: exceedance.to_vec(),
        sobol_first: est
            .iter()
            .map(|e| {
                // An outer sample whose inner variance is zero has undefined indices (NaN).
                e.sobol
                    .as_ref()
                    .map(|s| s.undefined_without_variance(&e.mean, &e.std).first[0].clone())
            })
            .collect(),
        chaos,
        chaos_error,
    }
}

/// The coefficients of every outer sample's chaos (column 0) on the union of their
/// multi-indices, in graded order (total degree, then as the total-degree set lists them:
/// the first input's degree highest first); 0 where a basis does not keep a term. A sparse
/// inner chaos keeps a different basis per outer sample: the
/// first sample's labels over rows of 31 to 44 coefficients under a 41-field header.
fn union_of_bases(chaoses: &[&crate::uq::pce::Pce]) -> ConditionalChaos {
    let mut indices: Vec<Vec<usize>> = chaoses
        .iter()
        .flat_map(|p| p.set().indices().iter().cloned())
        .collect();
    let key = |a: &Vec<usize>| a.iter().sum::<usize>();
    indices.sort_by(|a, b| key(a).cmp(&key(b)).then_with(|| b.cmp(a)));
    indices.dedup();
    let coeffs = chaoses
        .iter()
        .map(|p| {
            indices
                .iter()
                .map(|a| p.set().position(a).map_or(0.0, |i| p.coeffs[(i, 0)]))
                .collect()
        })
        .collect();
    (indices, coeffs)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A nested study's convergence plot said "runs n" with an axis to 4 096 (its pooled
    /// draws) for a 256-run study.
    #[test]
    fn nested_convergence_counts_the_studys_runs_not_its_pooled_draws() {
        use crate::uq::method::nested::split::Conditionals;
        // 16 outer samples of 16 runs each: 256 runs.
        let m: Vec<f64> = (0..16).map(|k| (k as f64 * 0.7).sin()).collect();
        let c = Conditionals {
            mean: m.clone(),
            var: vec![0.25; 16],
            se2: vec![0.0; 16],
        };
        let conv = outer_convergence(&c, &[16; 16]).unwrap();
        assert_eq!(conv.axis, "runs");
        assert_eq!(conv.x.first(), Some(&32.0));
        assert_eq!(conv.x.last(), Some(&256.0));
        assert!(conv.x.windows(2).all(|w| w[0] < w[1]), "{:?}", conv.x);
        assert!(conv.x.iter().all(|x| x % 16.0 == 0.0), "{:?}", conv.x);
        // At all 16: the mean of the conditional means, Std² = mean inner var + var of means,
        // standard error sd(means)/4.
        let mean = m.iter().sum::<f64>() / 16.0;
        let var_m = m.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / 15.0;
        assert!((conv.mean.last().unwrap() - mean).abs() < 1e-12);
        assert!((conv.std.last().unwrap() - (0.25 + var_m).sqrt()).abs() < 1e-12);
        assert!((conv.std_error_mean.last().unwrap() - (var_m / 16.0).sqrt()).abs() < 1e-12);
        assert!(outer_convergence(&c, &[16; 15]).is_none());
    }
}
