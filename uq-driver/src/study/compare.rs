//! Suites: a study with `[[variants]]` runs each variant into `DIR/<variant>/` (each one
//! resumable on its own) and then compares them: differences of mean and Std over time
//! against the reference variant, PDFs of the scalar quantities side by side, mean and Std
//! against the number of model runs, and a table with published values where given.

use std::path::Path;

use serde_json::json;

use super::analysis::{OutputStats, ScalarStats};
use super::spec::Study;
use super::{run_study, RunOptions, StudyResult, StudyRunError};
use crate::report::{self, DensityPlot, LinePlot, ReportPage, Section, Series, Table};

struct Done {
    study: Study,
    result: StudyResult,
}

fn method_label(s: &Study) -> String {
    let m = &s.file.method;
    match (m.samples, m.nodes, m.order) {
        (Some(n), _, _) => format!("{} {n}", m.kind.as_str()),
        (_, Some(n), _) => format!("{} {n}^{}", m.kind.as_str(), s.parameters.len()),
        (_, _, Some(o)) => format!("{} order {o}", m.kind.as_str()),
        _ => m.kind.as_str().to_string(),
    }
}

fn max_abs_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// Runs every variant and writes the comparison into `out_dir`.
pub fn run_suite(
    suite: &Study,
    out_dir: &Path,
    opts: &RunOptions,
) -> Result<StudyResult, StudyRunError> {
    let variants = suite.variants()?;
    let mut done: Vec<Done> = Vec::new();
    for v in variants {
        let dir = out_dir.join(&v.file.name);
        eprintln!(
            "{}: variant {} ({}) …",
            suite.file.name,
            v.file.name,
            method_label(&v)
        );
        let result = run_study(&v, &dir, opts)?;
        done.push(Done { study: v, result });
    }
    let ref_name = suite
        .file
        .reference
        .clone()
        .unwrap_or_else(|| done[0].study.file.name.clone());
    let r = done
        .iter()
        .position(|d| d.study.file.name == ref_name)
        .expect("validated reference");
    let mut sections = Vec::new();
    let mut summary_variants = Vec::new();
    // Per-variant table.
    let mut rows = Vec::new();
    for d in &done {
        let mut row = vec![
            d.study.file.name.clone(),
            method_label(&d.study),
            d.result.model_runs.to_string(),
            format!("{:.3}", d.result.wall_time),
        ];
        for (o, s) in d.result.stats.iter().enumerate() {
            let rs = &done[r].result.stats[o];
            row.push(format!("{:.3e}", max_abs_diff(&s.mean, &rs.mean)));
            row.push(format!("{:.3e}", max_abs_diff(&s.std, &rs.std)));
        }
        for q in &d.result.scalars {
            row.push(format!("{:.5}", q.mean));
            row.push(format!("{:.5}", q.std));
            for (l, p, _) in &q.exceedance {
                let _ = l;
                row.push(format!("{:.4}", p));
            }
        }
        rows.push(row);
        summary_variants.push(json!({
            "name": d.study.file.name,
            "method": method_label(&d.study),
            "model_runs": d.result.model_runs,
            "wall_time_s": d.result.wall_time,
            "folder": d.study.file.name,
            "outputs": d.result.stats.iter().map(|s| json!({
                "name": s.name,
                "max_abs_mean_diff_vs_reference": max_abs_diff(&s.mean, &done[r].result.stats.iter().find(|x| x.name == s.name).map(|x| x.mean.clone()).unwrap_or_default()),
                "max_abs_std_diff_vs_reference": max_abs_diff(&s.std, &done[r].result.stats.iter().find(|x| x.name == s.name).map(|x| x.std.clone()).unwrap_or_default()),
            })).collect::<Vec<_>>(),
            "quantities": d.result.scalars,
        }));
    }
    let mut header = vec![
        "variant".to_string(),
        "method".into(),
        "model runs".into(),
        "wall time [s]".into(),
    ];
    for s in &done[r].result.stats {
        header.push(format!("max |Δmean {}| vs {ref_name}", s.name));
        header.push(format!("max |ΔStd {}| vs {ref_name}", s.name));
    }
    for q in &done[r].result.scalars {
        header.push(format!("mean {}", q.name));
        header.push(format!("Std {}", q.name));
        for (l, _, _) in &q.exceedance {
            header.push(format!("P({} > {l})", q.name));
        }
    }
    sections.push(Section {
        heading: "Variants".into(),
        text: format!(
            "{}\n\nEach variant's full report is in its own folder. Differences are taken against the reference variant '{ref_name}'.",
            suite.file.description
        ),
        images: done.iter().map(|d| format!("{}/index.html", d.study.file.name)).collect(),
        table: Some(Table { header, rows }),
    });
    for (o, rs) in done[r].result.stats.iter().enumerate() {
        sections.push(compare_output(out_dir, &done, r, o, rs)?);
    }
    for (qi, rq) in done[r].result.scalars.iter().enumerate() {
        sections.push(compare_scalar(out_dir, &done, qi, rq)?);
    }
    if !suite.file.paper.is_empty() {
        let mut rows = Vec::new();
        for pv in &suite.file.paper {
            let ours = done
                .iter()
                .find(|d| d.study.file.name == pv.variant)
                .and_then(|d| d.result.scalars.iter().find(|q| q.name == pv.quantity))
                .and_then(|q| match pv.statistic.as_str() {
                    "mean" => Some(q.mean),
                    "std" => Some(q.std),
                    s => s
                        .strip_prefix("p>")
                        .and_then(|l| l.parse::<f64>().ok())
                        .and_then(|l| {
                            q.exceedance
                                .iter()
                                .find(|e| (e.0 - l).abs() < 1e-12)
                                .map(|e| e.1)
                        }),
                });
            rows.push(vec![
                pv.variant.clone(),
                pv.quantity.clone(),
                pv.statistic.clone(),
                format!("{}", pv.value),
                ours.map(|v| format!("{v:.5}"))
                    .unwrap_or_else(|| "n/a".into()),
                ours.map(|v| format!("{:+.2} %", 100.0 * (v - pv.value) / pv.value))
                    .unwrap_or_default(),
                pv.source.clone(),
            ]);
        }
        sections.push(Section {
            heading: "Against the paper".into(),
            text: "Published values beside ours.".into(),
            images: vec![],
            table: Some(Table {
                header: [
                    "variant",
                    "quantity",
                    "statistic",
                    "paper",
                    "railuq",
                    "difference",
                    "source",
                ]
                .iter()
                .map(|s| s.to_string())
                .collect(),
                rows,
            }),
        });
    }
    let wall: f64 = done.iter().map(|d| d.result.wall_time).sum();
    let summary = json!({
        "suite": suite.file.name,
        "description": suite.file.description,
        "origin": suite.origin,
        "reference": ref_name,
        "variants": summary_variants,
        "paper": suite.file.paper,
        "wall_time_s": wall,
    });
    let spath = out_dir.join("summary.json");
    std::fs::write(
        &spath,
        serde_json::to_string_pretty(&summary).expect("json"),
    )
    .map_err(|source| report::ReportError::Io {
        path: spath,
        source,
    })?;
    ReportPage {
        title: format!("railuq suite {}", suite.file.name),
        summary_json: serde_json::to_string_pretty(&summary).expect("json"),
        sections,
    }
    .write(&out_dir.join("index.html"))?;
    let reference = done.swap_remove(r);
    Ok(StudyResult {
        summary,
        wall_time: wall,
        ..reference.result
    })
}

fn compare_output(
    dir: &Path,
    done: &[Done],
    r: usize,
    o: usize,
    rs: &OutputStats,
) -> Result<Section, StudyRunError> {
    let v = &rs.name;
    let ref_name = &done[r].study.file.name;
    let mut header = vec!["time".to_string()];
    let mut cols: Vec<Vec<f64>> = Vec::new();
    let mut mean_plot = LinePlot::new(
        format!("{v}: mean − mean({ref_name})"),
        "time [s]",
        format!("Δ mean {v}"),
    );
    let mut std_plot = LinePlot::new(
        format!("{v}: Std − Std({ref_name})"),
        "time [s]",
        format!("Δ Std {v}"),
    );
    let mut means = LinePlot::new(
        format!("{v}: mean ± 3σ of every variant"),
        "time [s]",
        v.clone(),
    );
    for (i, d) in done.iter().enumerate() {
        let s = &d.result.stats[o];
        let name = &d.study.file.name;
        header.push(format!("mean_{name}"));
        cols.push(s.mean.clone());
        header.push(format!("std_{name}"));
        cols.push(s.std.clone());
        let up: Vec<f64> = s
            .mean
            .iter()
            .zip(&s.std)
            .map(|(m, d)| m + 3.0 * d)
            .collect();
        let lo: Vec<f64> = s
            .mean
            .iter()
            .zip(&s.std)
            .map(|(m, d)| m - 3.0 * d)
            .collect();
        means.series.push(Series::new(
            format!("{name} mean"),
            s.times.clone(),
            s.mean.clone(),
            report::palette(i),
        ));
        means.series.push(
            Series::new(
                format!("{name} ±3σ"),
                s.times.clone(),
                up,
                report::palette(i),
            )
            .dashed(),
        );
        means
            .series
            .push(Series::new("", s.times.clone(), lo, report::palette(i)).dashed());
        if i != r {
            let dm: Vec<f64> = s.mean.iter().zip(&rs.mean).map(|(a, b)| a - b).collect();
            let ds: Vec<f64> = s.std.iter().zip(&rs.std).map(|(a, b)| a - b).collect();
            header.push(format!("dmean_{name}"));
            cols.push(dm.clone());
            header.push(format!("dstd_{name}"));
            cols.push(ds.clone());
            mean_plot.series.push(Series::new(
                name.clone(),
                s.times.clone(),
                dm,
                report::palette(i),
            ));
            std_plot.series.push(Series::new(
                name.clone(),
                s.times.clone(),
                ds,
                report::palette(i),
            ));
        }
    }
    let mut all: Vec<&[f64]> = vec![&rs.times];
    all.extend(cols.iter().map(Vec::as_slice));
    let hdr: Vec<&str> = header.iter().map(String::as_str).collect();
    report::write_columns(&dir.join(format!("{v}_compare.csv")), &hdr, &all)?;
    mean_plot.write(&dir.join(format!("{v}_mean_diff.svg")))?;
    std_plot.write(&dir.join(format!("{v}_std_diff.svg")))?;
    means.write(&dir.join(format!("{v}_bands.svg")))?;
    Ok(Section {
        heading: format!("Output {v}: differences against {ref_name}"),
        text: format!(
            "Mean and Std of every variant minus those of '{ref_name}', over time (the paper's Fig. 3 for the wheel). \
             The reference's band and PDF evolution are in {ref_name}/index.html."
        ),
        images: vec![
            format!("{v}_mean_diff.svg"),
            format!("{v}_std_diff.svg"),
            format!("{v}_bands.svg"),
            format!("{v}_compare.csv"),
        ],
        table: None,
    })
}

fn compare_scalar(
    dir: &Path,
    done: &[Done],
    qi: usize,
    rq: &ScalarStats,
) -> Result<Section, StudyRunError> {
    let q = &rq.name;
    let mut curves = Vec::new();
    let mut runs = Vec::new();
    let mut means = Vec::new();
    let mut stds = Vec::new();
    let mut ses = Vec::new();
    let mut labels = Vec::new();
    for (i, d) in done.iter().enumerate() {
        let s = &d.result.scalars[qi];
        // A single deterministic run has no distribution: it would be a spike in the plots.
        if d.result.model_runs > 1 {
            curves.push(Series::new(
                d.study.file.name.clone(),
                s.pdf_x.clone(),
                s.pdf.clone(),
                report::palette(i),
            ));
        }
        runs.push(d.result.model_runs as f64);
        means.push(s.mean);
        stds.push(s.std);
        ses.push(s.std_error_mean);
        labels.push(d.study.file.name.clone());
    }
    let markers = rq
        .exceedance
        .iter()
        .map(|(l, _, _)| (*l, format!("limit {l}")))
        .collect();
    DensityPlot {
        title: format!("PDF of {q}, every variant"),
        x_label: q.clone(),
        curves,
        histogram: None,
        markers,
    }
    .write(&dir.join(format!("{q}_pdf_compare.svg")))?;
    let mut mplot = LinePlot::new(
        format!("mean of {q} against model runs"),
        "log10(model runs)",
        format!("mean {q}"),
    );
    let mut splot = LinePlot::new(
        format!("Std of {q} against model runs"),
        "log10(model runs)",
        format!("Std {q}"),
    );
    // Group by method kind so each method is one line (e.g. SCM 2,3,4,5 nodes; LHS 500, 20000).
    let mut kinds: Vec<String> = done
        .iter()
        .map(|d| d.study.file.method.kind.as_str().to_string())
        .collect();
    kinds.dedup();
    for (ki, kind) in kinds.iter().enumerate() {
        let idx: Vec<usize> = (0..done.len())
            .filter(|&i| done[i].study.file.method.kind.as_str() == kind && runs[i] > 1.0)
            .collect();
        if idx.is_empty() {
            continue;
        }
        let x: Vec<f64> = idx.iter().map(|&i| runs[i].log10()).collect();
        mplot.series.push(Series::new(
            kind.clone(),
            x.clone(),
            idx.iter().map(|&i| means[i]).collect(),
            report::palette(ki),
        ));
        splot.series.push(Series::new(
            kind.clone(),
            x,
            idx.iter().map(|&i| stds[i]).collect(),
            report::palette(ki),
        ));
    }
    mplot.write(&dir.join(format!("{q}_mean_vs_runs.svg")))?;
    splot.write(&dir.join(format!("{q}_std_vs_runs.svg")))?;
    let idx: Vec<f64> = (0..done.len()).map(|i| i as f64).collect();
    report::write_columns(
        &dir.join(format!("{q}_compare.csv")),
        &[
            "variant_index",
            "model_runs",
            "mean",
            "std",
            "std_error_mean",
        ],
        &[&idx, &runs, &means, &stds, &ses],
    )?;
    Ok(Section {
        heading: format!("Quantity {q} across variants"),
        text: format!(
            "PDFs side by side, and mean and Std against the number of model runs. Variant order: {}.",
            labels.join(", ")
        ),
        images: vec![
            format!("{q}_pdf_compare.svg"),
            format!("{q}_mean_vs_runs.svg"),
            format!("{q}_std_vs_runs.svg"),
            format!("{q}_compare.csv"),
        ],
        table: None,
    })
}
