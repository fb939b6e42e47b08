//! The files of a suite's output folder: differences of mean and Std over time against the
//! reference variant, PDFs of the scalar quantities side by side, mean and Std against the
//! number of model runs, a table with published values where given, `summary.json` and
//! `index.html`. Each variant's own report is in its sub-folder.

use crate::report::file_name::stem;
use std::path::Path;

use super::units::label;
use super::{
    palette, write_bytes, write_columns, DensityPlot, LinePlot, ReportError, ReportPage, Section,
    Series, Table,
};
use crate::results::numbers::to_spread;
use crate::results::{
    self, group_digits, sig, ExceedanceCount, OutputStats, ScalarStats, SuiteSummary, Summary,
};
use crate::spec::PaperValue;

/// One variant's results.
#[derive(Clone, Copy, Debug)]
pub struct VariantResults<'a> {
    /// Its summary.
    pub summary: &'a Summary,
    /// Statistics per output.
    pub outputs: &'a [OutputStats],
    /// Statistics per scalar quantity.
    pub quantities: &'a [ScalarStats],
}

/// Writes the suite's comparison into `dir` (`variants` in the order of `summary.variants`).
pub fn write(
    dir: &Path,
    summary: &SuiteSummary,
    variants: &[VariantResults],
) -> Result<(), ReportError> {
    let r = summary
        .variants
        .iter()
        .position(|v| v.name == summary.reference)
        .unwrap_or(0);
    let mut sections = vec![variants_section(summary, variants, r)];
    for (o, rs) in variants[r].outputs.iter().enumerate() {
        sections.push(compare_output(dir, summary, variants, r, o, rs)?);
    }
    for q in quantity_names(variants, r) {
        sections.push(compare_scalar(dir, summary, variants, &q)?);
    }
    if !summary.paper.is_empty() {
        sections.push(paper_section(summary));
    }
    if super::nested::write_suite(dir, summary)?.is_some() {
        sections.extend(super::nested::suite_section(summary));
    }
    let json = results::to_json(summary);
    write_bytes(&dir.join("summary.json"), json.as_bytes())?;
    ReportPage {
        title: format!("railuq suite {}", summary.suite),
        summary_json: json,
        sections,
    }
    .write(&dir.join("index.html"))
}

/// The scalar quantities of every variant, by name: the reference's first, then those only
/// other variants compute (a variant may leave quantities out, `quantities = [...]`).
fn quantity_names(variants: &[VariantResults], r: usize) -> Vec<String> {
    let mut names: Vec<String> = Vec::new();
    let order = std::iter::once(&variants[r]).chain(variants);
    for q in order.flat_map(|v| v.quantities) {
        if !names.contains(&q.name) {
            names.push(q.name.clone());
        }
    }
    names
}

/// The quantity `name` of a variant, if it computes it.
fn find<'a>(quantities: &'a [ScalarStats], name: &str) -> Option<&'a ScalarStats> {
    quantities.iter().find(|q| q.name == name)
}

/// A probability in the table of variants: `0.3125`, or, when no draw exceeded, the 95 %
/// upper bound with the count, `< 0.221 (0 of 12)`, as the variant's page gives it
/// ("0.0000" from 12 runs read as certainty).
///
/// A count over a chaos's draws that has no interval (the limit beyond every model run, or
/// only a few runs beyond it: `upper_95` is NaN) is shown as the variant's page words it,
/// with the reason and "no interval": `0 (0 of 20 000, beyond every model run: no
/// interval)`, not `< NaN`.
fn probability_cell(e: &ExceedanceCount) -> String {
    let no_interval = if let Some([_, largest]) = e.beyond_runs {
        if e.ci_kind == "none_extrapolation" {
            Some(if e.limit > largest {
                "beyond every model run: no interval".to_owned()
            } else {
                "below every model run: no interval".to_owned()
            })
        } else {
            None
        }
    } else {
        e.runs_in_tail.map(|[k, n]| {
            format!(
                "only {} of {} model runs beyond the limit: no interval",
                group_digits(k),
                group_digits(n)
            )
        })
    };
    let no_interval = no_interval.or_else(|| {
        (e.exceeded == 0 && e.of > 0 && !e.upper_95.is_finite()).then(|| "no interval".to_owned())
    });
    match no_interval {
        Some(why) if e.exceeded == 0 => format!("0 (0 of {}, {why})", group_digits(e.of)),
        Some(why) => format!("{:.4} ({why})", e.p),
        None if e.exceeded == 0 && e.of > 0 => {
            format!("< {} (0 of {})", sig(e.upper_95), group_digits(e.of))
        }
        None => format!("{:.4}", e.p),
    }
}

/// The table of variants: method, runs, wall time, differences against the reference, and
/// the scalar quantities (blank where a variant does not compute one).
fn variants_section(summary: &SuiteSummary, variants: &[VariantResults], r: usize) -> Section {
    let reference = &variants[r];
    let ref_name = &summary.reference;
    let names = quantity_names(variants, r);
    // Exceedance limits of each quantity (the same in every variant that has it).
    let limits: Vec<Vec<f64>> = names
        .iter()
        .map(|n| {
            variants
                .iter()
                .find_map(|v| find(v.quantities, n))
                .map(|q| q.exceedance.iter().map(|e| e.0).collect())
                .unwrap_or_default()
        })
        .collect();
    let mut header: Vec<String> = ["variant", "method", "model runs", "wall time [s]"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    // The unit of a variable or quantity, from any variant that ran the model.
    let unit_of = |name: &str| {
        variants
            .iter()
            .find_map(|d| d.summary.units.get(name))
            .map(String::as_str)
    };
    for s in reference.outputs {
        let u = unit_of(&s.name);
        header.push(label(&format!("max |Δmean {}| vs {ref_name}", s.name), u));
        header.push(label(&format!("max |ΔStd {}| vs {ref_name}", s.name), u));
    }
    for (n, ls) in names.iter().zip(&limits) {
        header.push(label(&format!("mean {n}"), unit_of(n)));
        header.push(label(&format!("Std {n}"), unit_of(n)));
        for l in ls {
            header.push(format!("P({n} > {l})"));
        }
    }
    let rows = summary
        .variants
        .iter()
        .zip(variants)
        .map(|(v, d)| {
            // An intrusive method (SGM) runs no model: it solves its own system once.
            let runs = if d.summary.fmu.is_none() {
                "none (Galerkin system solved once)".to_owned()
            } else {
                group_digits(v.model_runs)
            };
            let mut row = vec![
                v.name.clone(),
                v.method.clone(),
                runs,
                format!("{:.3}", v.wall_time_s),
            ];
            for o in &v.outputs {
                if v.name == *ref_name {
                    // Against itself: no difference to show ("0.000e0").
                    row.extend(["(reference)".to_string(), "(reference)".to_string()]);
                } else {
                    row.push(sig(o.max_abs_mean_diff_vs_reference));
                    row.push(sig(o.max_abs_std_diff_vs_reference));
                }
            }
            for (n, ls) in names.iter().zip(&limits) {
                match find(&v.quantities, n) {
                    Some(q) => {
                        row.push(to_spread(q.mean, q.std));
                        row.push(to_spread(q.std, q.std));
                        row.extend(q.exceedance.iter().enumerate().map(|(k, (_, p, _))| {
                            match q.exceedance_counts.get(k) {
                                Some(e) => probability_cell(e),
                                None => format!("{p:.4}"),
                            }
                        }));
                    }
                    None => row.extend(std::iter::repeat_n(String::new(), 2 + ls.len())),
                }
            }
            row
        })
        .collect();
    Section {
        heading: "Variants".into(),
        text: format!(
            "{}\n\nEach variant's full report is in its own folder. Differences are taken against the reference variant '{ref_name}'.",
            summary.description
        ),
        images: summary
            .variants
            .iter()
            .map(|v| format!("{}/index.html", v.folder))
            .collect(),
        table: Some(Table { header, rows }),
    }
}

/// Whether two variants' mean ± 3σ bands of an output coincide on a plot: the same times,
/// and mean and bounds within 1e-6 of the band's largest magnitude everywhere.
fn same_band(a: &OutputStats, b: &OutputStats) -> bool {
    let scale = a
        .upper_3sigma
        .iter()
        .chain(&a.lower_3sigma)
        .map(|x| x.abs())
        .filter(|x| x.is_finite())
        .fold(0.0, f64::max);
    let close = |x: &[f64], y: &[f64]| {
        x.len() == y.len()
            && x.iter()
                .zip(y)
                .all(|(p, q)| (p - q).abs() <= 1e-6 * scale || (p.is_nan() && q.is_nan()) || p == q)
    };
    a.times == b.times
        && close(&a.mean, &b.mean)
        && close(&a.upper_3sigma, &b.upper_3sigma)
        && close(&a.lower_3sigma, &b.lower_3sigma)
}

/// `<V>_compare.csv`, `<V>_mean_diff.svg`, `<V>_std_diff.svg`, `<V>_bands.svg`.
fn compare_output(
    dir: &Path,
    summary: &SuiteSummary,
    variants: &[VariantResults],
    r: usize,
    o: usize,
    rs: &OutputStats,
) -> Result<Section, ReportError> {
    let v = &rs.name;
    let ref_name = &summary.reference;
    // The reference may have no FMU (SGM): any variant that ran the model knows the unit.
    let unit = variants
        .iter()
        .find_map(|d| d.summary.units.get(v))
        .map(String::as_str);
    let mut header = vec!["time".to_string()];
    let mut cols: Vec<Vec<f64>> = Vec::new();
    let mut mean_plot = LinePlot::new(
        format!("{v}: mean − mean({ref_name})"),
        "time [s]",
        label(&format!("Δ mean {v}"), unit),
    );
    let mut std_plot = LinePlot::new(
        format!("{v}: Std − Std({ref_name})"),
        "time [s]",
        label(&format!("Δ Std {v}"), unit),
    );
    let mut bands = LinePlot::new(
        format!("{v}: mean ± 3σ of every variant"),
        "time [s]",
        label(v, unit),
    );
    // Each distinct band once: variants whose bands coincide share one legend entry.
    let mut drawn: Vec<(usize, &OutputStats, Vec<&str>)> = Vec::new();
    for (i, (d, vs)) in variants.iter().zip(&summary.variants).enumerate() {
        let s = &d.outputs[o];
        let (name, t, color) = (&vs.name, &s.times, palette(i));
        header.push(format!("mean_{name}"));
        cols.push(s.mean.clone());
        header.push(format!("std_{name}"));
        cols.push(s.std.clone());
        if let Some((at, _, names)) = drawn.iter_mut().find(|(_, b, _)| same_band(b, s)) {
            names.push(name.as_str());
            let names = names.join(", ");
            bands.series[*at].label = format!("{names} mean");
            bands.series[*at + 1].label = format!("{names} ±3σ");
        } else {
            drawn.push((bands.series.len(), s, vec![name.as_str()]));
            bands.series.extend([
                Series::new(format!("{name} mean"), t.clone(), s.mean.clone(), color),
                Series::new(
                    format!("{name} ±3σ"),
                    t.clone(),
                    s.upper_3sigma.clone(),
                    color,
                )
                .dashed(),
                Series::new("", t.clone(), s.lower_3sigma.clone(), color).dashed(),
            ]);
        }
        if i != r {
            let dm: Vec<f64> = s.mean.iter().zip(&rs.mean).map(|(a, b)| a - b).collect();
            let ds: Vec<f64> = s.std.iter().zip(&rs.std).map(|(a, b)| a - b).collect();
            header.push(format!("dmean_{name}"));
            cols.push(dm.clone());
            header.push(format!("dstd_{name}"));
            cols.push(ds.clone());
            mean_plot
                .series
                .push(Series::new(name.clone(), t.clone(), dm, color));
            std_plot
                .series
                .push(Series::new(name.clone(), t.clone(), ds, color));
        }
    }
    let mut all: Vec<&[f64]> = vec![&rs.times];
    all.extend(cols.iter().map(Vec::as_slice));
    let hdr: Vec<&str> = header.iter().map(String::as_str).collect();
    write_columns(&dir.join(format!("{}_compare.csv", stem(v))), &hdr, &all)?;
    let log_mean = spans_decades(&mean_plot);
    let log_std = spans_decades(&std_plot);
    absolute_on_log(
        &mut mean_plot,
        log_mean,
        &format!("|mean − mean({ref_name})| of {v}"),
    );
    absolute_on_log(
        &mut std_plot,
        log_std,
        &format!("|Std − Std({ref_name})| of {v}"),
    );
    mean_plot.write(&dir.join(format!("{}_mean_diff.svg", stem(v))))?;
    std_plot.write(&dir.join(format!("{}_std_diff.svg", stem(v))))?;
    bands.write(&dir.join(format!("{}_bands.svg", stem(v))))?;
    Ok(output_section(v, ref_name))
}

/// Whether the differences of the variants lie decades apart (more than a factor 100
/// between the largest |Δ| of two variants): then a log axis shows them (SCM against SGM
/// at 1e-10, LHS at 1e-5: on a linear axis the first is a flat zero).
fn spans_decades(plot: &LinePlot) -> bool {
    let peaks: Vec<f64> = plot
        .series
        .iter()
        .map(|s| {
            s.y.iter()
                .filter(|y| y.is_finite())
                .fold(0.0f64, |m, y| m.max(y.abs()))
        })
        .filter(|p| *p > 0.0)
        .collect();
    let (lo, hi) = peaks
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), &p| (a.min(p), b.max(p)));
    peaks.len() > 1 && hi / lo > 1e2
}

/// With `log`: the plot shows |Δ| on a log axis (its zeros drop out), titled `title`.
fn absolute_on_log(plot: &mut LinePlot, log: bool, title: &str) {
    if !log {
        return;
    }
    for s in &mut plot.series {
        for y in &mut s.y {
            *y = y.abs();
        }
    }
    plot.log_y = true;
    plot.title = format!("{title} (log axis)");
    plot.y_label = format!("|{}|", plot.y_label);
}

fn output_section(v: &str, ref_name: &str) -> Section {
    Section {
        heading: format!("Output {v}: differences against {ref_name}"),
        text: format!(
            "Mean and Std of every variant minus those of '{ref_name}', over time (the paper's Fig. 3 for the wheel). \
             The reference's band and PDF evolution are in {ref_name}/index.html."
        ),
        images: vec![
            format!("{}_mean_diff.svg", stem(v)),
            format!("{}_std_diff.svg", stem(v)),
            format!("{}_bands.svg", stem(v)),
            format!("{}_compare.csv", stem(v)),
        ],
        table: None,
    }
}

/// `<q>_pdf_compare.svg`, `<q>_mean_vs_runs.svg`, `<q>_std_vs_runs.svg`, `<q>_compare.csv`,
/// over the variants that compute quantity `q`.
fn compare_scalar(
    dir: &Path,
    summary: &SuiteSummary,
    variants: &[VariantResults],
    q: &str,
) -> Result<Section, ReportError> {
    // (index of the variant, its statistics of q)
    let having: Vec<(usize, &ScalarStats)> = variants
        .iter()
        .enumerate()
        .filter_map(|(i, d)| find(d.quantities, q).map(|s| (i, s)))
        .collect();
    let rq = having[0].1;
    let runs: Vec<f64> = having
        .iter()
        .map(|(i, _)| variants[*i].summary.model_runs as f64)
        .collect();
    let stats: Vec<&ScalarStats> = having.iter().map(|(_, s)| *s).collect();
    // A single deterministic run has no distribution: it would be a spike in the plots.
    let curves = having
        .iter()
        .zip(&runs)
        .filter(|((_, s), &n)| n > 1.0 && !s.deterministic)
        .map(|((i, s), _)| {
            let v = &summary.variants[*i];
            Series::new(v.name.clone(), s.pdf_x.clone(), s.pdf.clone(), palette(*i))
        })
        .collect();
    DensityPlot {
        title: format!("PDF of {q}, every variant"),
        x_label: label(q, rq.unit.as_deref()),
        curves,
        histogram: None,
        markers: rq
            .exceedance
            .iter()
            .map(|(l, _, _)| (*l, format!("limit {l}")))
            .collect(),
    }
    .write(&dir.join(format!("{}_pdf_compare.svg", stem(q))))?;
    let kinds: Vec<&str> = having
        .iter()
        .map(|(i, _)| variants[*i].summary.method.kind.as_str())
        .collect();
    let means: Vec<f64> = stats.iter().map(|s| s.mean).collect();
    let stds: Vec<f64> = stats.iter().map(|s| s.std).collect();
    // No standard error (chaos, quadrature): `nan`, not 0.
    let ses: Vec<f64> = stats
        .iter()
        .map(|s| s.std_error_mean.unwrap_or(f64::NAN))
        .collect();
    let unit = variants
        .iter()
        .find_map(|d| d.summary.units.get(q))
        .map(String::as_str);
    for (what, values, file) in [("mean", &means, "mean"), ("Std", &stds, "std")] {
        let mut plot = LinePlot::new(
            format!("{what} of {q} against model runs"),
            "model runs",
            label(&format!("{what} {q}"), unit),
        );
        plot.log_x = true;
        convergence(plot, &kinds, &runs, values)
            .write(&dir.join(format!("{}_{file}_vs_runs.svg", stem(q))))?;
    }
    let idx: Vec<f64> = having.iter().map(|(i, _)| *i as f64).collect();
    write_columns(
        &dir.join(format!("{}_compare.csv", stem(q))),
        &[
            "variant_index",
            "model_runs",
            "mean",
            "std",
            "std_error_mean",
        ],
        &[&idx, &runs, &means, &stds, &ses],
    )?;
    let labels: Vec<&str> = having
        .iter()
        .map(|(i, _)| summary.variants[*i].name.as_str())
        .collect();
    Ok(scalar_section(q, &labels))
}

fn scalar_section(q: &str, labels: &[&str]) -> Section {
    Section {
        heading: format!("Quantity {q} across variants"),
        text: format!(
            "PDFs side by side, and mean and Std against the number of model runs. Variant order: {}.",
            labels.join(", ")
        ),
        images: vec![
            format!("{}_pdf_compare.svg", stem(q)),
            format!("{}_mean_vs_runs.svg", stem(q)),
            format!("{}_std_vs_runs.svg", stem(q)),
            format!("{}_compare.csv", stem(q)),
        ],
        table: None,
    }
}

/// `plot` with `y` against the model runs (log axis), one line per method kind (e.g. SCM 2, 3, 4, 5
/// nodes; LHS 500, 20 000); single runs are left out.
fn convergence(mut plot: LinePlot, kinds: &[&str], runs: &[f64], y: &[f64]) -> LinePlot {
    let mut distinct: Vec<&str> = kinds.to_vec();
    distinct.dedup();
    for (ki, kind) in distinct.iter().enumerate() {
        let idx: Vec<usize> = (0..kinds.len())
            .filter(|&i| kinds[i] == *kind && runs[i] > 1.0)
            .collect();
        if idx.is_empty() {
            continue;
        }
        plot.series.push(Series::new(
            kind.to_string(),
            idx.iter().map(|&i| runs[i]).collect(),
            idx.iter().map(|&i| y[i]).collect(),
            palette(ki),
        ));
    }
    plot
}

/// Our value of a published statistic, if the suite has it.
fn ours(summary: &SuiteSummary, pv: &PaperValue) -> Option<f64> {
    let q = summary
        .variants
        .iter()
        .find(|v| v.name == pv.variant)?
        .quantities
        .iter()
        .find(|q| q.name == pv.quantity)?;
    match pv.statistic.as_str() {
        "mean" => Some(q.mean),
        "std" => Some(q.std),
        s => {
            let limit: f64 = s.strip_prefix("p>")?.parse().ok()?;
            q.exceedance
                .iter()
                .find(|e| (e.0 - limit).abs() < 1e-12)
                .map(|e| e.1)
        }
    }
}

/// Published values beside ours.
fn paper_section(summary: &SuiteSummary) -> Section {
    let rows = summary
        .paper
        .iter()
        .map(|pv| {
            let ours = ours(summary, pv);
            vec![
                pv.variant.clone(),
                pv.quantity.clone(),
                pv.statistic.clone(),
                format!("{}", pv.value),
                ours.map(|v| to_spread(v, 0.0))
                    .unwrap_or_else(|| "n/a".into()),
                ours.map(|v| format!("{:+.2} %", 100.0 * (v - pv.value) / pv.value))
                    .unwrap_or_default(),
                pv.source.clone(),
            ]
        })
        .collect();
    Section {
        heading: "Against the paper".into(),
        text: "Published values beside ours.".into(),
        images: vec![],
        table: Some(Table::new(
            &[
                "variant",
                "quantity",
                "statistic",
                "paper",
                "railuq",
                "difference",
                "source",
            ],
            rows,
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::study::analysis::exceedance_count;
    use crate::uq::method::Draws;

    #[test]
    fn the_suite_table_shows_the_upper_bound_when_no_run_exceeded() {
        let none = exceedance_count(&[1.0; 12], 2.0, Draws::Runs);
        // 1 - 0.05^(1/12) = 0.2209.
        let bound = 1.0 - 0.05f64.powf(1.0 / 12.0);
        assert!((bound - 0.2209).abs() < 1e-4);
        assert_eq!(
            probability_cell(&none),
            format!("< {} (0 of 12)", sig(bound))
        );
        assert_eq!(probability_cell(&none), "< 0.221 (0 of 12)");
        let some = exceedance_count(&[1.0, 3.0, 1.0, 1.0], 2.0, Draws::Runs);
        assert_eq!(probability_cell(&some), "0.2500");
    }

    #[test]
    fn the_suite_table_shows_no_nan_when_a_chaos_count_has_no_interval() {
        // 0 of 20 000 draws of a chaos above a limit beyond every run: no interval, and
        // `upper_95` is NaN (the variant's page: "P = 0, no interval").
        let mut beyond = exceedance_count(&[1.0; 20_000], 2.0, Draws::Chaos);
        beyond.note_range(Draws::Chaos, [0.5, 1.5]);
        assert!(beyond.upper_95.is_nan());
        let cell = probability_cell(&beyond);
        assert!(!cell.contains("NaN"), "{cell}");
        assert_eq!(
            cell,
            format!(
                "0 (0 of {}, beyond every model run: no interval)",
                group_digits(20_000)
            )
        );
        // Draws above a limit that only 3 of 40 runs reach.
        let mut draws = vec![1.0; 100];
        draws[0] = 3.0;
        let mut tail = exceedance_count(&draws, 2.0, Draws::Chaos);
        tail.note_tail(Draws::Chaos, 3, 40);
        assert_eq!(
            probability_cell(&tail),
            "0.0100 (only 3 of 40 model runs beyond the limit: no interval)"
        );
        // Below every run.
        let mut below = exceedance_count(&[3.0; 10], 2.0, Draws::Chaos);
        below.note_range(Draws::Chaos, [2.5, 3.0]);
        assert_eq!(
            probability_cell(&below),
            "1.0000 (below every model run: no interval)"
        );
    }

    fn band(mean: f64, std: f64) -> OutputStats {
        OutputStats::constant("y", vec![0.0, 1.0, 2.0], mean, std)
    }

    /// The suite page stacked ten identical mean ± 3σ bands, one per variant.
    #[test]
    fn the_suite_page_draws_identical_bands_once() {
        let a = band(1.0, 0.1);
        assert!(same_band(&a, &band(1.0, 0.1)));
        assert!(same_band(&a, &band(1.0 + 1e-9, 0.1)));
        assert!(!same_band(&a, &band(1.0, 0.2)));
        assert!(!same_band(&a, &band(1.01, 0.1)));
    }
}
