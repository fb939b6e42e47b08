//! The files of one study's output folder, one writer per file:
//! `summary.json`, `<V>.csv`, `<V>_pdf.csv`, `<V>_sobol.csv`, `points.csv`, the plots and
//! `index.html`.

use std::fmt::Write as _;
use std::path::Path;

use super::csv::push_shortest;
use super::{
    histogram_density, palette, write_bytes, write_columns, write_grid, Band, DensityPlot, Heatmap,
    LinePlot, ReportError, ReportPage, Section, Series, Table,
};
use crate::qoi::QoiSpec;
use crate::results::{self, OutputStats, PointStatus, PointTable, ScalarStats, Summary};
use crate::uq::method::Sobol;

/// Everything a study's report shows.
#[derive(Clone, Copy, Debug)]
pub struct StudyReport<'a> {
    /// The summary (also written as `summary.json`).
    pub summary: &'a Summary,
    /// Statistics per output.
    pub outputs: &'a [OutputStats],
    /// Statistics per scalar quantity.
    pub quantities: &'a [ScalarStats],
    /// The quantities' definitions (for the signal-against-speed plots).
    pub qoi: &'a [QoiSpec],
    /// The design and the outcome of each point, if the model was run.
    pub points: Option<&'a PointTable>,
}

/// Column name of a quantile level: 0.01 → `q1`, 0.5 → `q50`, 0.025 → `q2.5`.
pub fn quantile_column(p: f64) -> String {
    format!("q{}", (p * 1000.0).round() / 10.0)
}

/// Writes every file of a finished study into `dir`.
pub fn write(dir: &Path, r: &StudyReport) -> Result<(), ReportError> {
    let names: Vec<&str> = r
        .summary
        .parameters
        .iter()
        .map(|p| p.name.as_str())
        .collect();
    let mut sections = Vec::new();
    for s in r.outputs {
        write_output_csv(dir, s)?;
        write_pdf_csv(dir, s)?;
        write_band_plot(dir, s, r.summary)?;
        write_pdf_heatmap(dir, s)?;
        let mut images = vec![
            format!("{}_band.svg", s.name),
            format!("{}_pdf.svg", s.name),
        ];
        if s.sobol.is_some() {
            write_sobol_csv(dir, s, &names)?;
            write_sobol_plot(dir, s, &names)?;
            images.push(format!("{}_sobol.svg", s.name));
        }
        images.push(format!("{}.csv", s.name));
        images.push(format!("{}_pdf.csv", s.name));
        sections.push(Section {
            heading: format!("Output {}", s.name),
            text: format!(
                "Mean, standard deviation and the μ ± 3σ band over time; the PDF evolution heat map ({}).",
                s.draws.describe()
            ),
            images,
            table: None,
        });
    }
    for q in r.quantities {
        write_scalar_pdf_plot(dir, q, &r.summary.study)?;
        write_scalar_pdf_csv(dir, q)?;
        write_scalar_samples(dir, q)?;
        sections.push(scalar_section(q));
    }
    for spec in r.qoi {
        if let Some(file) = write_speed_plot(dir, spec, r.outputs, &r.summary.study)? {
            let heading = format!("Quantity {}", spec.name());
            if let Some(sec) = sections.iter_mut().find(|s| s.heading == heading) {
                sec.images.insert(0, file);
            }
        }
    }
    if let Some(points) = r.points {
        write_points_csv(&dir.join("points.csv"), points)?;
    }
    let json = results::to_json(r.summary);
    write_bytes(&dir.join("summary.json"), json.as_bytes())?;
    let mut page = head_sections(r);
    page.extend(sections);
    ReportPage {
        title: format!("railuq study {}", r.summary.study),
        summary_json: json,
        sections: page,
    }
    .write(&dir.join("index.html"))
}

/// `<V>_pdf.csv`: the PDF evolution in long format.
fn write_pdf_csv(dir: &Path, s: &OutputStats) -> Result<(), ReportError> {
    write_grid(
        &dir.join(format!("{}_pdf.csv", s.name)),
        &s.pdf_times,
        &s.pdf_grid,
        &s.pdf,
    )
}

/// `<V>.csv`: time, mean, std, the ±3σ band, the quantiles and (collocation) `std_pce`.
fn write_output_csv(dir: &Path, s: &OutputStats) -> Result<(), ReportError> {
    let mut header: Vec<String> = ["time", "mean", "std", "lower_3sigma", "upper_3sigma"]
        .iter()
        .map(|x| x.to_string())
        .collect();
    let mut cols: Vec<&[f64]> = vec![&s.times, &s.mean, &s.std, &s.lower_3sigma, &s.upper_3sigma];
    for (p, q) in &s.quantiles {
        header.push(quantile_column(*p));
        cols.push(q);
    }
    if let Some(sp) = &s.std_pce {
        header.push("std_pce".into());
        cols.push(sp);
    }
    if let Some(se) = &s.std_error_mean {
        header.push("std_error_mean".into());
        cols.push(se);
    }
    if let Some(e) = &s.chaos_error {
        header.push(e.kind.name().into());
        cols.push(&e.values);
    }
    let hdr: Vec<&str> = header.iter().map(String::as_str).collect();
    write_columns(&dir.join(format!("{}.csv", s.name)), &hdr, &cols)
}

/// Index `j` of every row.
fn column(rows: &[Vec<f64>], j: usize) -> Vec<f64> {
    rows.iter().map(|r| r[j]).collect()
}

/// `<V>_sobol.csv`: `time,S_<p>...,ST_<p>...`, then, where the method gives confidence
/// intervals, `S_<p>_lo,S_<p>_hi...,ST_<p>_lo,ST_<p>_hi...`.
fn write_sobol_csv(dir: &Path, s: &OutputStats, names: &[&str]) -> Result<(), ReportError> {
    let Some(Sobol {
        first,
        total,
        intervals,
    }) = &s.sobol
    else {
        return Ok(());
    };
    let mut header = vec!["time".to_string()];
    header.extend(names.iter().map(|n| format!("S_{n}")));
    header.extend(names.iter().map(|n| format!("ST_{n}")));
    let mut data: Vec<Vec<f64>> = (0..names.len())
        .map(|j| column(first, j))
        .chain((0..names.len()).map(|j| column(total, j)))
        .collect();
    if let Some(ci) = intervals {
        for (label, rows) in [("S", &ci.first), ("ST", &ci.total)] {
            for (j, n) in names.iter().enumerate() {
                header.push(format!("{label}_{n}_lo"));
                header.push(format!("{label}_{n}_hi"));
                data.push(rows.iter().map(|r| r[j].0).collect());
                data.push(rows.iter().map(|r| r[j].1).collect());
            }
        }
    }
    let mut cols: Vec<&[f64]> = vec![&s.times];
    cols.extend(data.iter().map(Vec::as_slice));
    let hdr: Vec<&str> = header.iter().map(String::as_str).collect();
    write_columns(&dir.join(format!("{}_sobol.csv", s.name)), &hdr, &cols)
}

/// `<V>_sobol.svg`: first-order (solid) and total (dashed) indices over time.
fn write_sobol_plot(dir: &Path, s: &OutputStats, names: &[&str]) -> Result<(), ReportError> {
    let Some(Sobol { first, total, .. }) = &s.sobol else {
        return Ok(());
    };
    let v = &s.name;
    let mut plot = LinePlot::new(format!("Sobol' indices of {v}"), "time [s]", "index [-]");
    for (j, name) in names.iter().enumerate() {
        let t = s.times.clone();
        plot.series.push(Series::new(
            format!("S {name}"),
            t.clone(),
            column(first, j),
            palette(j),
        ));
        plot.series
            .push(Series::new(format!("ST {name}"), t, column(total, j), palette(j)).dashed());
    }
    plot.write(&dir.join(format!("{v}_sobol.svg")))
}

/// `<V>_band.svg`: mean ± 3σ and the quantiles other than the median.
fn write_band_plot(dir: &Path, s: &OutputStats, summary: &Summary) -> Result<(), ReportError> {
    let v = &s.name;
    let title = format!(
        "{v}: mean ± 3σ ({}, {})",
        summary.study, summary.method.kind
    );
    let mut band = LinePlot::new(title, "time [s]", v.clone());
    push_band(&mut band, &s.times, s, "mean".into());
    for (i, (p, q)) in s.quantiles.iter().enumerate() {
        if *p != 0.5 {
            band.series.push(
                Series::new(
                    format!("{} quantile", quantile_column(*p)),
                    s.times.clone(),
                    q.clone(),
                    palette(i + 2),
                )
                .dashed(),
            );
        }
    }
    band.write(&dir.join(format!("{v}_band.svg")))
}

/// Adds the mean ± 3σ band of `s` (unless its Std is zero throughout) and its mean, both
/// against `x`, to `plot`.
fn push_band(plot: &mut LinePlot, x: &[f64], s: &OutputStats, mean_label: String) {
    if s.std.iter().any(|d| *d > 0.0) {
        plot.bands.push(Band::new(
            "mean ± 3σ",
            x.to_vec(),
            s.lower_3sigma.clone(),
            s.upper_3sigma.clone(),
            palette(0),
        ));
    }
    plot.series.push(Series::new(
        mean_label,
        x.to_vec(),
        s.mean.clone(),
        palette(0),
    ));
}

/// `<V>_pdf.png` and `<V>_pdf.svg`: the PDF evolution heat map, clipped at the 99th
/// percentile of the densities so that a degenerate start (every run at the same initial
/// value) does not wash out the rest.
fn write_pdf_heatmap(dir: &Path, s: &OutputStats) -> Result<(), ReportError> {
    let v = &s.name;
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
    heat.write_svg_embedded(&dir.join(format!("{v}_pdf.svg")))
}

/// `<q>_pdf.svg`: the density, a histogram of the runs and the limits.
fn write_scalar_pdf_plot(dir: &Path, q: &ScalarStats, study: &str) -> Result<(), ReportError> {
    let name = &q.name;
    let (edges, dens) = histogram_density(&q.samples, 0);
    DensityPlot {
        title: format!("PDF of {name} ({study})"),
        x_label: name.clone(),
        curves: vec![Series::new(
            format!("KDE ({})", q.draws.describe()),
            q.pdf_x.clone(),
            q.pdf.clone(),
            palette(0),
        )],
        histogram: (q.samples.len() > 10).then_some((edges, dens)),
        markers: q
            .exceedance
            .iter()
            .map(|(l, p, _)| (*l, format!("limit {l}: P(>) = {p:.4}")))
            .collect(),
    }
    .write(&dir.join(format!("{name}_pdf.svg")))
}

/// `<q>_pdf.csv`: `x,density`.
fn write_scalar_pdf_csv(dir: &Path, q: &ScalarStats) -> Result<(), ReportError> {
    write_columns(
        &dir.join(format!("{}_pdf.csv", q.name)),
        &["x", "density"],
        &[&q.pdf_x, &q.pdf],
    )
}

/// `<q>_samples.csv`: `run,<q>`, the valid values of the runs.
fn write_scalar_samples(dir: &Path, q: &ScalarStats) -> Result<(), ReportError> {
    let idx: Vec<f64> = (0..q.samples.len()).map(|i| i as f64).collect();
    write_columns(
        &dir.join(format!("{}_samples.csv", q.name)),
        &["run", &q.name],
        &[&idx, &q.samples],
    )
}

/// The report section of a scalar quantity, with its table of statistics.
fn scalar_section(q: &ScalarStats) -> Section {
    let name = &q.name;
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
    if let Some(sobol) = &q.sobol {
        for (label, values, ci) in [
            ("first-order Sobol' index", &sobol.first, &sobol.first_ci),
            ("total Sobol' index", &sobol.total, &sobol.total_ci),
        ] {
            for (p, v) in values {
                let interval = ci
                    .as_ref()
                    .and_then(|c| c.get(p))
                    .map_or(String::new(), |[lo, hi]| format!(" [{lo:.4}, {hi:.4}]"));
                rows.push(vec![format!("{label} of {p}"), format!("{v:.4}{interval}")]);
            }
        }
    }
    Section {
        heading: format!("Quantity {name}"),
        text: format!(
            "Distribution of {name} over the runs ({}).",
            q.draws.describe()
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
    }
}

/// `<signal>_vs_<speed>.svg` for a critical-speed quantity whose signal and speed are both
/// outputs (the paper's Fig. 5a): the file name, or `None` when there is no such plot.
fn write_speed_plot(
    dir: &Path,
    spec: &QoiSpec,
    outputs: &[OutputStats],
    study: &str,
) -> Result<Option<String>, ReportError> {
    let QoiSpec::CriticalSpeed {
        signal,
        speed,
        threshold,
        ..
    } = spec
    else {
        return Ok(None);
    };
    let find = |n: &str| outputs.iter().find(|s| s.name == n);
    let (Some(y), Some(v)) = (find(signal), find(speed)) else {
        return Ok(None);
    };
    let mut plot = LinePlot::new(
        format!("{signal} against {speed} ({study})"),
        speed.clone(),
        signal.clone(),
    );
    push_band(&mut plot, &v.mean, y, format!("{signal} (mean)"));
    let ends = vec![v.mean[0], v.mean[v.mean.len() - 1]];
    plot.series.push(
        Series::new(
            format!("threshold ±{threshold}"),
            ends.clone(),
            vec![*threshold; 2],
            palette(3),
        )
        .dashed(),
    );
    plot.series
        .push(Series::new("", ends, vec![-*threshold; 2], palette(3)).dashed());
    let file = format!("{signal}_vs_{speed}.svg");
    plot.write(&dir.join(&file))?;
    Ok(Some(file))
}

/// `points.csv`: `index[,weight],<parameters>,status`.
pub fn write_points_csv(path: &Path, t: &PointTable) -> Result<(), ReportError> {
    let mut text = String::from("index");
    if t.weights.is_some() {
        text.push_str(",weight");
    }
    for n in &t.names {
        text.push(',');
        text.push_str(n);
    }
    text.push_str(",status\n");
    for (i, vals) in t.values.iter().enumerate() {
        let _ = write!(text, "{i}");
        if let Some(w) = &t.weights {
            text.push(',');
            push_shortest(&mut text, w[i]);
        }
        for v in vals {
            text.push(',');
            push_shortest(&mut text, *v);
        }
        let status = match &t.status[i] {
            PointStatus::Ok => "ok".to_string(),
            PointStatus::Failed(m) => format!("\"failed: {}\"", m.replace('"', "'")),
            PointStatus::Missing => "missing".into(),
        };
        let _ = writeln!(text, ",{status}");
    }
    write_bytes(path, text.as_bytes())
}

/// The study, its parameters and its warnings: the first sections of `index.html`.
fn head_sections(r: &StudyReport) -> Vec<Section> {
    let s = r.summary;
    let mut images = vec!["summary.json".to_string()];
    if r.points.is_some() {
        images.insert(0, "points.csv".into());
    }
    let mut head = vec![Section {
        heading: "Study".into(),
        text: format!(
            "{}\n\n{} model runs ({} this time, {} resumed from earlier), {} failed, wall time {:.2} s on {} threads.",
            s.description,
            s.model_runs,
            s.runs_this_invocation,
            s.runs_resumed,
            s.failed_runs,
            s.wall_time_s,
            s.threads
        ),
        images,
        table: Some(Table {
            header: vec!["parameter".into(), "distribution".into()],
            rows: s
                .parameters
                .iter()
                .map(|p| vec![p.name.clone(), format!("{:?}", p.distribution)])
                .collect(),
        }),
    }];
    if let Some(se) = s
        .method
        .details
        .get("standard_error")
        .and_then(|v| v.as_str())
    {
        head[0]
            .text
            .push_str(&format!("\n\nStandard error of the mean: {se}."));
    }
    if !s.warnings.is_empty() {
        head.push(Section {
            heading: "Warnings".into(),
            text: s.warnings.join("\n\n"),
            images: vec![],
            table: None,
        });
    }
    head
}
