//! The files of one study's output folder: `summary.json`, `<V>.csv`, `<V>_pdf.csv`,
//! `<V>_sobol.csv`, `points.csv`, `units.csv`, the plots and `index.html` (data files in
//! [`files`], plots in [`plots`], the page's sections here).

mod files;
mod plots;

use crate::report::file_name::stem;
use std::path::Path;
use std::time::Instant;

use rayon::prelude::*;

use super::inputs;
use super::units::with_unit;
use super::{write_bytes, ReportError, ReportPage, Section, Table};
use crate::qoi::QoiSpec;
use crate::results::{self, sig, OutputStats, PointTable, ScalarStats, Summary};

pub use files::points_csv as write_points_csv;

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
    /// Write the plots and `index.html` (false: the CSV files and `summary.json` only).
    pub plots: bool,
    /// Further sections of `index.html` (e.g. a nested study's split), after the others.
    pub extra: &'a [Section],
}

/// Column name of a quantile level (the study file's one function: exact, e.g. `q0.15`).
pub use crate::spec::quantile_column;

/// Writes every file of a finished study into `dir`; returns the wall time of the writing
/// (s), which `summary.json` reports as `timing.report_s` (written last, with that number).
pub fn write(dir: &Path, r: &StudyReport) -> Result<f64, ReportError> {
    let started = Instant::now();
    let names: Vec<&str> = r
        .summary
        .parameters
        .iter()
        .map(|p| p.name.as_str())
        .collect();
    // Each output and quantity writes its own files: in parallel, the data files beside the
    // plots; the sections are kept in order.
    let outputs: Vec<Option<Section>> = r
        .outputs
        .par_iter()
        .map(|s| {
            let (files, section) = rayon::join(
                || -> Result<(), ReportError> {
                    files::output_csv(dir, s)?;
                    files::pdf_csv(dir, s)?;
                    files::sobol_csv(dir, s, &names)?;
                    files::sobol_overall_csv(dir, s, &names)?;
                    if let Some(c) = &s.convergence {
                        files::convergence_csv(dir, &s.name, c)?;
                    }
                    Ok(())
                },
                || {
                    r.plots
                        .then(|| output_section(dir, s, r.summary, &names))
                        .transpose()
                },
            );
            files?;
            section
        })
        .collect::<Result<_, _>>()?;
    let quantities: Vec<Option<Section>> = r
        .quantities
        .par_iter()
        .map(|q| {
            files::scalar_pdf_csv(dir, q)?;
            files::scalar_samples(dir, q)?;
            if let Some(c) = &q.convergence {
                files::convergence_csv(dir, &q.name, c)?;
            }
            r.plots
                .then(|| quantity_section(dir, q, r.summary, &names))
                .transpose()
        })
        .collect::<Result<_, _>>()?;
    let mut sections: Vec<Section> = outputs.into_iter().chain(quantities).flatten().collect();
    if r.plots {
        for spec in r.qoi {
            let file = plots::speed_plot(dir, spec, r.outputs, r.quantities, &r.summary.study)?;
            if let Some(file) = file {
                let heading = format!("Quantity {}", spec.name());
                if let Some(sec) = sections.iter_mut().find(|s| s.heading == heading) {
                    sec.images.insert(0, file);
                }
            }
        }
    }
    if let Some(points) = r.points {
        files::points_csv(&dir.join("points.csv"), points)?;
    }
    files::units_csv(
        dir,
        r.outputs,
        r.quantities,
        &names,
        &r.summary.units,
        r.points,
    )?;
    let mut summary = r.summary.clone();
    summary.timing.report_s = started.elapsed().as_secs_f64();
    let json = results::to_json(&summary);
    if r.plots {
        let mut page = head_sections(r, &summary);
        page.extend(sections);
        page.extend(r.extra.iter().cloned());
        ReportPage {
            title: format!("railuq study {}", r.summary.study),
            summary_json: json.clone(),
            sections: page,
        }
        .write(&dir.join("index.html"))?;
    }
    write_bytes(&dir.join("summary.json"), json.as_bytes())?;
    Ok(summary.timing.report_s)
}

/// The study, its parameters and its warnings: the first sections of `index.html`.
fn head_sections(r: &StudyReport, s: &Summary) -> Vec<Section> {
    let mut images = vec!["summary.json".to_string(), "units.csv".to_string()];
    if r.points.is_some() {
        images.insert(0, "points.csv".into());
    }
    let t = &s.timing;
    let mut text = format!(
        "{}\n\nMethod: {}. {} model runs ({} this time, {} resumed from earlier), {} failed, \
         on {} threads. Wall time of this invocation: runs {:.3} s, analysis {:.3} s, report \
         {:.3} s.",
        s.description,
        s.method.kind,
        s.model_runs,
        s.runs_this_invocation,
        s.runs_resumed,
        s.failed_runs,
        s.threads,
        t.runs_s,
        t.analysis_s,
        t.report_s,
    );
    if !s.fixed.is_empty() {
        let fixed: Vec<String> = s
            .fixed
            .iter()
            .map(|(k, v)| with_unit(&format!("{k} = {v}"), s.units.get(k).map(String::as_str)))
            .collect();
        text.push_str(&format!("\n\nFixed values: {}.", fixed.join(", ")));
    }
    text.push_str(
        "\n\nUnits are those the FMU declares in its modelDescription (time in s); the CSV \
         files keep plain column names, their units are listed in units.csv and in \
         summary.json (units).",
    );
    let mut head = vec![Section {
        heading: "Study".into(),
        text,
        images,
        table: Some(Table {
            header: inputs::header(),
            rows: s
                .parameters
                .iter()
                .map(|p| inputs::row(p, s.units.get(&p.name).map(String::as_str)))
                .collect(),
        }),
    }];
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

/// The plots and the section of an output.
fn output_section(
    dir: &Path,
    s: &OutputStats,
    summary: &Summary,
    names: &[&str],
) -> Result<Section, ReportError> {
    let v = &s.name;
    plots::band(dir, s, summary)?;
    let mut images = vec![format!("{}_band.svg", stem(v))];
    if plots::std_plot(dir, s)? {
        images.push(format!("{}_std.svg", stem(v)));
    }
    let mut text = if s.deterministic {
        format!(
            "{v} has the same value in every run at every time: it is deterministic in this \
             study, so it has no spread and no density. The plot shows its value."
        )
    } else {
        format!(
            "Mean, standard deviation and the μ ± 3σ band of {v} over time, with its quantiles \
             ({}).",
            s.draws.describe()
        )
    };
    if plots::pdf_heatmap(dir, s)? {
        images.push(format!("{}_pdf.svg", stem(v)));
        text.push_str(&format!(
            "\n\nPDF evolution: the density of {v} at {} times (columns) on a grid of {} \
             values, colour from 0 upwards. Columns where every run has the same value (for \
             instance a fixed initial state) have no density and are left blank.",
            s.pdf_times.len(),
            s.pdf_grid.len()
        ));
    }
    if s.sobol.is_some() && !s.deterministic {
        plots::sobol_over_time(dir, s, names)?;
        images.push(format!("{}_sobol.svg", stem(v)));
        text.push_str(
            "\n\nSobol' indices over time: the first-order index of each parameter (the share \
             of the variance it causes alone) stacked, and on top the share from interactions \
             (1 − ΣS). Where the Std is zero the indices are undefined and left blank. The \
             total indices are in the CSV file.",
        );
    }
    let overall = files::overall_sobol(s);
    if let Some((first, total)) = &overall {
        plots::sobol_overall_bars(dir, v, names, first, total)?;
        images.push(format!("{}_sobol_overall.svg", stem(v)));
        text.push_str(&format!(
            "\n\nSobol' indices of the whole series: each time's indices weighted by its \
             variance, S = ∫ Var(t) S(t) dt / ∫ Var(t) dt, the share of the variance of {v} \
             over the whole run that each parameter causes alone (S) and with its \
             interactions (ST)."
        ));
    }
    if let Some(c) = &s.convergence {
        images.extend(plots::convergence(dir, v, s.unit.as_deref(), c)?);
        text.push_str(&format!(
            "\n\nConvergence: mean and Std of {v} at t = {} s (where its Std is largest) \
             against {}.",
            sig(s.convergence_time.unwrap_or(f64::NAN)),
            convergence_axis(c)
        ));
        images.push(format!("{}_convergence.csv", stem(v)));
    }
    images.push(format!("{}.csv", stem(v)));
    images.push(format!("{}_pdf.csv", stem(v)));
    if s.sobol.is_some() {
        images.push(format!("{}_sobol.csv", stem(v)));
    }
    if overall.is_some() {
        images.push(format!("{}_sobol_overall.csv", stem(v)));
    }
    Ok(Section {
        heading: format!("Output {v}"),
        text,
        images,
        table: None,
    })
}

fn convergence_axis(c: &results::Convergence) -> &'static str {
    if c.axis == "runs" {
        "the number of runs (running estimates over the first n runs in design order; for a \
         Latin hypercube the first n points are not a Latin hypercube themselves)"
    } else {
        "the total order of the chaos: the Std of the terms of each order alone (a fast \
         decay means the expansion has converged) and of the expansion truncated there (each \
         term is projected on its own, so the truncation is the lower-order chaos of the same \
         runs)"
    }
}

/// The plots and the section of a scalar quantity, with its table of statistics.
fn quantity_section(
    dir: &Path,
    q: &ScalarStats,
    summary: &Summary,
    names: &[&str],
) -> Result<Section, ReportError> {
    let study = &summary.study;
    let name = &q.name;
    let unit = q.unit.as_deref();
    let num = |v: f64| with_unit(&format!("{v:.6}"), unit);
    let mut images = Vec::new();
    let mut text = format!("{name}: {}.", q.definition.text);
    if q.deterministic {
        let why = if q.n_valid < 2 {
            format!("there is {} run", q.n_valid)
        } else {
            format!("every one of the {} runs gives the same value", q.n_valid)
        };
        text.push_str(&format!(
            "\n\n{name} = {} — {why}: it is deterministic in this study, so it has no \
             spread and no density is drawn.",
            num(q.mean)
        ));
    } else {
        plots::scalar_pdf(dir, q, study)?;
        images.push(format!("{}_pdf.svg", stem(name)));
        text.push_str(&format!(
            "\n\nDistribution of {name} ({}).",
            q.draws.describe()
        ));
        if plots::sobol_bars(dir, q, names, &summary.method)? {
            images.push(format!("{}_sobol.svg", stem(name)));
        }
        if let Some(c) = &q.convergence {
            images.extend(plots::convergence(dir, name, unit, c)?);
            text.push_str(&format!(
                "\n\nConvergence: mean and Std against {}.",
                convergence_axis(c)
            ));
            images.push(format!("{}_convergence.csv", stem(name)));
        }
    }
    images.push(format!("{}_pdf.csv", stem(name)));
    images.push(format!("{}_samples.csv", stem(name)));
    let mut rows = vec![
        vec!["computed as".to_string(), q.definition.text.clone()],
        vec!["unit".into(), unit.unwrap_or("(not declared)").to_owned()],
        vec!["mean".into(), num(q.mean)],
        vec!["Std".into(), num(q.std)],
    ];
    if let Some(se) = q.std_error_mean.filter(|&se| se > 0.0) {
        rows.push(vec![
            "standard error of the mean".into(),
            with_unit(&sig(se), unit),
        ]);
    }
    rows.push(vec!["valid runs".into(), q.n_valid.to_string()]);
    rows.push(vec![
        "smallest / largest run".into(),
        format!("{} / {}", num(q.min), num(q.max)),
    ]);
    if q.n_never_hunts + q.n_never_stops > 0 {
        rows.push(vec![
            "never hunt / never stop".into(),
            format!("{} / {}", q.n_never_hunts, q.n_never_stops),
        ]);
    }
    for (p, v) in &q.quantiles {
        rows.push(vec![format!("quantile {p}"), num(*v)]);
    }
    for e in &q.exceedance_counts {
        rows.push(vec![
            format!("P({name} > {})", with_unit(&e.limit.to_string(), unit)),
            e.describe(),
        ]);
    }
    if let (Some(f), Some(t)) = (&q.sobol_first, &q.sobol_total) {
        let undefined = f.iter().chain(t).all(|x| x.is_nan());
        if undefined {
            // No variance: the indices are 0/0 (NaN in the files).
            rows.push(vec![
                "Sobol' indices".into(),
                "undefined: the quantity has no variance".into(),
            ]);
        }
        for (i, n) in names.iter().enumerate().filter(|_| !undefined) {
            rows.push(vec![
                format!("Sobol' index of {n}: first order / total"),
                format!(
                    "{} / {}",
                    sig(f.get(i).copied().unwrap_or(f64::NAN)),
                    sig(t.get(i).copied().unwrap_or(f64::NAN))
                ),
            ]);
        }
    }
    Ok(Section {
        heading: format!("Quantity {name}"),
        text,
        images,
        table: Some(Table {
            header: vec!["statistic".into(), "value".into()],
            rows,
        }),
    })
}
