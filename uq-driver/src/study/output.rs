//! Writes a study's results: `summary.json`, `<V>.csv`, `<V>_pdf.csv`, `<V>_sobol.csv`,
//! `points.csv`, plots and `index.html`.

use std::path::Path;

use serde_json::json;

use super::analysis::{OutputStats, ScalarStats};
use super::spec::Study;
use crate::report::{
    self, Band, DensityPlot, Heatmap, LinePlot, ReportError, ReportPage, Section, Series, Table,
};

/// Facts about a run that go into the summary and the report.
#[derive(Clone, Debug, Default)]
pub struct RunContext {
    /// Model runs of the study (points of the design; 1 for SGM).
    pub model_runs: usize,
    /// Runs made by this invocation.
    pub runs_new: usize,
    /// Runs found finished in the store.
    pub runs_resumed: usize,
    /// Failed runs (MC/LHS with failures allowed).
    pub failed: usize,
    /// Wall time (s) of this invocation.
    pub wall_time: f64,
    /// Worker threads.
    pub threads: usize,
    /// FMU facts (path, model, GUID, SHA-256) or null.
    pub fmu: serde_json::Value,
    /// Method details (kind, samples, nodes, order, …).
    pub method: serde_json::Value,
    /// Warnings for the user.
    pub warnings: Vec<String>,
    /// `points.csv` content, if the method has points.
    pub points_csv: Option<String>,
    /// How the densities were obtained (for the report text).
    pub density_source: &'static str,
}

/// Column name of a quantile level: 0.01 → `q1`, 0.5 → `q50`, 0.025 → `q2.5`.
pub fn quantile_column(p: f64) -> String {
    format!("q{}", (p * 1000.0).round() / 10.0)
}

/// Writes every file of a finished study into `dir` and returns the summary JSON.
pub fn write_all(
    dir: &Path,
    study: &Study,
    ctx: &RunContext,
    stats: &[OutputStats],
    scalars: &[ScalarStats],
) -> Result<serde_json::Value, ReportError> {
    let mut sections = Vec::new();
    let mut outputs_json = serde_json::Map::new();
    for s in stats {
        let v = &s.name;
        let lower: Vec<f64> = s
            .mean
            .iter()
            .zip(&s.std)
            .map(|(m, d)| m - 3.0 * d)
            .collect();
        let upper: Vec<f64> = s
            .mean
            .iter()
            .zip(&s.std)
            .map(|(m, d)| m + 3.0 * d)
            .collect();
        let mut header: Vec<String> = ["time", "mean", "std", "lower_3sigma", "upper_3sigma"]
            .iter()
            .map(|x| x.to_string())
            .collect();
        let mut cols: Vec<&[f64]> = vec![&s.times, &s.mean, &s.std, &lower, &upper];
        for (p, q) in &s.quantiles {
            header.push(quantile_column(*p));
            cols.push(q);
        }
        if let Some(sp) = &s.std_pce {
            header.push("std_pce".into());
            cols.push(sp);
        }
        let hdr: Vec<&str> = header.iter().map(String::as_str).collect();
        report::write_columns(&dir.join(format!("{v}.csv")), &hdr, &cols)?;
        report::write_grid(
            &dir.join(format!("{v}_pdf.csv")),
            &s.pdf_times,
            &s.pdf_grid,
            &s.pdf,
        )?;
        let mut files = vec![format!("{v}_band.svg"), format!("{v}_pdf.svg")];
        if let Some((first, total)) = &s.sobol {
            let mut sh = vec!["time".to_string()];
            let mut sc: Vec<Vec<f64>> = Vec::new();
            for (j, p) in study.parameters.iter().enumerate() {
                sh.push(format!("S_{}", p.name));
                sc.push(first.iter().map(|r| r[j]).collect());
            }
            for (j, p) in study.parameters.iter().enumerate() {
                sh.push(format!("ST_{}", p.name));
                sc.push(total.iter().map(|r| r[j]).collect());
            }
            let mut cols: Vec<&[f64]> = vec![&s.times];
            cols.extend(sc.iter().map(Vec::as_slice));
            let hdr: Vec<&str> = sh.iter().map(String::as_str).collect();
            report::write_columns(&dir.join(format!("{v}_sobol.csv")), &hdr, &cols)?;
            let mut plot = LinePlot::new(format!("Sobol' indices of {v}"), "time [s]", "index [-]");
            for (j, p) in study.parameters.iter().enumerate() {
                plot.series.push(Series::new(
                    format!("S {}", p.name),
                    s.times.clone(),
                    sc[j].clone(),
                    report::palette(j),
                ));
                plot.series.push(
                    Series::new(
                        format!("ST {}", p.name),
                        s.times.clone(),
                        sc[study.parameters.len() + j].clone(),
                        report::palette(j),
                    )
                    .dashed(),
                );
            }
            plot.write(&dir.join(format!("{v}_sobol.svg")))?;
            files.push(format!("{v}_sobol.svg"));
        }
        let mut band = LinePlot::new(
            format!(
                "{v}: mean ± 3σ ({}, {})",
                study.file.name,
                study.file.method.kind.as_str()
            ),
            "time [s]",
            v.clone(),
        );
        band.bands.push(Band::new(
            "mean ± 3σ",
            s.times.clone(),
            lower.clone(),
            upper.clone(),
            report::palette(0),
        ));
        band.series.push(Series::new(
            "mean",
            s.times.clone(),
            s.mean.clone(),
            report::palette(0),
        ));
        for (i, (p, q)) in s.quantiles.iter().enumerate() {
            if *p != 0.5 {
                band.series.push(
                    Series::new(
                        format!("{} quantile", quantile_column(*p)),
                        s.times.clone(),
                        q.clone(),
                        report::palette(i + 2),
                    )
                    .dashed(),
                );
            }
        }
        band.write(&dir.join(format!("{v}_band.svg")))?;
        // Heat map: clip at the 99th percentile of densities so a degenerate start (every run
        // at the same initial value) does not wash out the rest.
        let mut all: Vec<f64> = s
            .pdf
            .iter()
            .flatten()
            .copied()
            .filter(|x| x.is_finite())
            .collect();
        all.sort_by(f64::total_cmp);
        let cap = all
            .get((all.len() as f64 * 0.99) as usize)
            .copied()
            .unwrap_or(f64::INFINITY);
        let heat = Heatmap {
            title: format!("PDF evolution of {v}"),
            x_label: "time [s]".into(),
            y_label: v.clone(),
            x: s.pdf_times.clone(),
            y: s.pdf_grid.clone(),
            z: s.pdf
                .iter()
                .map(|c| c.iter().map(|x| x.min(cap)).collect())
                .collect(),
            colorbar_label: format!("PDF of {v} (clipped at the 99th percentile)"),
            overlay: vec![Series::new(
                "mean",
                s.times.clone(),
                s.mean.clone(),
                "#ffffff",
            )],
            log_scale: false,
        };
        heat.write_png(&dir.join(format!("{v}_pdf.png")))?;
        heat.write_svg_embedded(&dir.join(format!("{v}_pdf.svg")))?;
        let last = s.times.len() - 1;
        let imax = (0..s.std.len())
            .max_by(|&a, &b| s.std[a].total_cmp(&s.std[b]))
            .unwrap_or(0);
        outputs_json.insert(
            v.clone(),
            json!({
                "csv": format!("{v}.csv"),
                "pdf_csv": format!("{v}_pdf.csv"),
                "mean_at_stop": s.mean[last],
                "std_at_stop": s.std[last],
                "max_std": s.std[imax],
                "time_of_max_std": s.times[imax],
            }),
        );
        files.push(format!("{v}.csv"));
        files.push(format!("{v}_pdf.csv"));
        sections.push(Section {
            heading: format!("Output {v}"),
            text: format!(
                "Mean, standard deviation and the μ ± 3σ band over time; the PDF evolution heat map ({}).",
                ctx.density_source
            ),
            images: files,
            table: None,
        });
    }
    let mut scalars_json = serde_json::Map::new();
    for q in scalars {
        let name = &q.name;
        let (edges, dens) = report::histogram_density(&q.samples, 0);
        let markers = q
            .exceedance
            .iter()
            .map(|(l, p, _)| (*l, format!("limit {l}: P(>) = {p:.4}")))
            .collect();
        DensityPlot {
            title: format!("PDF of {name} ({})", study.file.name),
            x_label: name.clone(),
            curves: vec![Series::new(
                format!("KDE ({})", ctx.density_source),
                q.pdf_x.clone(),
                q.pdf.clone(),
                report::palette(0),
            )],
            histogram: (q.samples.len() > 10).then_some((edges, dens)),
            markers,
        }
        .write(&dir.join(format!("{name}_pdf.svg")))?;
        report::write_columns(
            &dir.join(format!("{name}_pdf.csv")),
            &["x", "density"],
            &[&q.pdf_x, &q.pdf],
        )?;
        let idx: Vec<f64> = (0..q.samples.len()).map(|i| i as f64).collect();
        report::write_columns(
            &dir.join(format!("{name}_samples.csv")),
            &["run", name],
            &[&idx, &q.samples],
        )?;
        let mut rows = vec![
            vec!["mean".to_string(), format!("{:.6}", q.mean)],
            vec!["std".into(), format!("{:.6}", q.std)],
            vec![
                "std error of the mean".into(),
                format!("{:.3e}", q.std_error_mean),
            ],
            vec!["valid runs".into(), q.n_valid.to_string()],
        ];
        if q.n_never_hunts + q.n_never_stops > 0 {
            rows.push(vec![
                "never hunt / never stop".into(),
                format!("{} / {}", q.n_never_hunts, q.n_never_stops),
            ]);
        }
        for (p, v) in &q.quantiles {
            rows.push(vec![format!("quantile {p}"), format!("{v:.6}")]);
        }
        for (l, p, se) in &q.exceedance {
            rows.push(vec![
                format!("P({name} > {l})"),
                format!("{p:.5} ± {se:.1e}"),
            ]);
        }
        sections.push(Section {
            heading: format!("Quantity {name}"),
            text: format!(
                "Distribution of {name} over the runs ({}).",
                ctx.density_source
            ),
            images: vec![
                format!("{name}_pdf.svg"),
                format!("{name}_pdf.csv"),
                format!("{name}_samples.csv"),
            ],
            table: Some(Table {
                header: vec!["statistic".into(), "value".into()],
                rows,
            }),
        });
        scalars_json.insert(name.clone(), serde_json::to_value(q).expect("serializable"));
    }
    // Signal against speed for the critical-speed quantities (the paper's Fig. 5a) when both
    // are recorded as outputs.
    for q in &study.file.qoi {
        if let crate::study::spec::QoiSpec::CriticalSpeed {
            name,
            signal,
            speed,
            threshold,
            ..
        } = q
        {
            let find = |n: &str| stats.iter().find(|s| s.name == n);
            if let (Some(y), Some(v)) = (find(signal), find(speed)) {
                let mut plot = LinePlot::new(
                    format!("{signal} against {speed} ({})", study.file.name),
                    speed.clone(),
                    signal.clone(),
                );
                let up: Vec<f64> = y
                    .mean
                    .iter()
                    .zip(&y.std)
                    .map(|(m, d)| m + 3.0 * d)
                    .collect();
                let lo: Vec<f64> = y
                    .mean
                    .iter()
                    .zip(&y.std)
                    .map(|(m, d)| m - 3.0 * d)
                    .collect();
                if y.std.iter().any(|d| *d > 0.0) {
                    plot.bands.push(Band::new(
                        "mean ± 3σ",
                        v.mean.clone(),
                        lo,
                        up,
                        report::palette(0),
                    ));
                }
                plot.series.push(Series::new(
                    format!("{signal} (mean)"),
                    v.mean.clone(),
                    y.mean.clone(),
                    report::palette(0),
                ));
                let ends = vec![v.mean[0], v.mean[v.mean.len() - 1]];
                plot.series.push(
                    Series::new(
                        format!("threshold ±{threshold}"),
                        ends.clone(),
                        vec![*threshold; 2],
                        report::palette(3),
                    )
                    .dashed(),
                );
                plot.series
                    .push(Series::new("", ends, vec![-*threshold; 2], report::palette(3)).dashed());
                let file = format!("{signal}_vs_{speed}.svg");
                plot.write(&dir.join(&file))?;
                if let Some(sec) = sections
                    .iter_mut()
                    .find(|s| s.heading == format!("Quantity {name}"))
                {
                    sec.images.insert(0, file);
                }
            }
        }
    }
    if let Some(points) = &ctx.points_csv {
        let ppath = dir.join("points.csv");
        std::fs::write(&ppath, points).map_err(|source| ReportError::Io {
            path: ppath,
            source,
        })?;
    }
    let summary = json!({
        "study": study.file.name,
        "description": study.file.description,
        "origin": study.origin,
        "method": ctx.method,
        "seed": study.file.seed,
        "experiment": study.file.experiment,
        "parameters": study.parameters,
        "fixed": study.file.fixed,
        "fmu": ctx.fmu,
        "model_runs": ctx.model_runs,
        "runs_this_invocation": ctx.runs_new,
        "runs_resumed": ctx.runs_resumed,
        "failed_runs": ctx.failed,
        "wall_time_s": ctx.wall_time,
        "threads": ctx.threads,
        "versions": { "uq_driver": env!("CARGO_PKG_VERSION"), "fmi": "2.0" },
        "warnings": ctx.warnings,
        "outputs": outputs_json,
        "quantities": scalars_json,
    });
    let spath = dir.join("summary.json");
    std::fs::write(
        &spath,
        serde_json::to_string_pretty(&summary).expect("json"),
    )
    .map_err(|source| ReportError::Io {
        path: spath,
        source,
    })?;
    let mut head = vec![
        Section {
            heading: "Study".into(),
            text: format!(
                "{}\n\n{} model runs ({} this time, {} resumed from earlier), {} failed, wall time {:.2} s on {} threads.",
                study.file.description, ctx.model_runs, ctx.runs_new, ctx.runs_resumed, ctx.failed, ctx.wall_time, ctx.threads
            ),
            images: if ctx.points_csv.is_some() {
                vec!["points.csv".into(), "summary.json".into()]
            } else {
                vec!["summary.json".into()]
            },
            table: Some(Table {
                header: vec!["parameter".into(), "distribution".into()],
                rows: study
                    .parameters
                    .iter()
                    .map(|p| vec![p.name.clone(), format!("{:?}", p.distribution)])
                    .collect(),
            }),
        },
    ];
    if !ctx.warnings.is_empty() {
        head.push(Section {
            heading: "Warnings".into(),
            text: ctx.warnings.join("\n\n"),
            images: vec![],
            table: None,
        });
    }
    head.extend(sections);
    ReportPage {
        title: format!("railuq study {}", study.file.name),
        summary_json: serde_json::to_string_pretty(&summary).expect("json"),
        sections: head,
    }
    .write(&dir.join("index.html"))?;
    Ok(summary)
}
