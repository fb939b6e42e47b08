//! The files of one study's output folder: `summary.json`, `<V>.csv`, `<V>_pdf.csv`,
//! `<V>_sobol.csv`, `points.csv`, `units.csv`, the plots and `index.html` (data files in
//! `files`, plots in `plots`, the page's sections here).

mod files;
mod given_data;
mod plots;
mod reliability;
mod system;

use crate::report::file_name::stem;
use std::path::Path;
use std::time::Instant;

use rayon::prelude::*;

use super::inputs;
use super::units::with_unit;
use super::{write_bytes, ReportError, ReportPage, Section, Table};
use crate::qoi::QoiSpec;
use crate::results::numbers::{count, to_spread};
use crate::results::{self, group_digits, sig, OutputStats, PointTable, ScalarStats, Summary};
use crate::uq::method::{ChaosErrorKind, Draws};

pub use files::points_csv as write_points_csv;
pub use system::system_section;

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
        let title = match variant_of(r.summary) {
            Some(suite) => format!(
                "railuq study {}, a variant of the suite {suite}",
                r.summary.study
            ),
            None => format!("railuq study {}", r.summary.study),
        };
        ReportPage {
            title,
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
    let nominal = is_nominal(s);
    let mut text = if s.fmu.is_none() {
        // An intrusive method (SGM): no model, no runs; its own system, solved once.
        format!(
            "{}\n\nMethod: {}. No model runs: the Galerkin system (the system of the study \
             file, shown at the end of this page) was solved once. Wall time of this \
             invocation: solve {:.3} s, analysis {:.3} s, report {:.3} s.",
            s.description, s.method.kind, t.runs_s, t.analysis_s, t.report_s,
        )
    } else {
        format!(
            "{}\n\nMethod: {}. {} ({} this time, {} resumed from earlier), {} failed, on {}. \
             Wall time of this invocation: runs {:.3} s, analysis {:.3} s, report {:.3} s.",
            s.description,
            s.method.kind,
            count(s.model_runs, "model run", "model runs"),
            group_digits(s.runs_this_invocation),
            group_digits(s.runs_resumed),
            group_digits(s.failed_runs),
            count(s.threads, "thread", "threads"),
            t.runs_s,
            t.analysis_s,
            t.report_s,
        )
    };
    if let Some(suite) = variant_of(s) {
        text.push_str(&format!(
            "\n\nThis is the variant {} of the suite {suite}; the suite's page (../index.html, \
             linked below) compares it with the other variants.",
            s.study
        ));
        images.push("../index.html".into());
    }
    if nominal {
        text.push_str(
            "\n\nNominal study: one run with every random parameter held at its mean (a \
             discrete one at the value of its support nearest the mean). The distributions \
             below were not sampled, so the results have no spread, no density and no \
             probability.",
        );
    }
    if !s.fixed.is_empty() {
        let fixed: Vec<String> = s
            .fixed
            .iter()
            .map(|(k, v)| with_unit(&format!("{k} = {v}"), s.units.get(k).map(String::as_str)))
            .collect();
        text.push_str(&format!("\n\nFixed values: {}.", fixed.join(", ")));
    }
    text.push_str(if s.fmu.is_none() {
        "\n\nUnits: no FMU, and the study's system declares no unit (time in s); the CSV \
         files keep plain column names (units.csv lists time only)."
    } else {
        "\n\nUnits are those the FMU declares in its modelDescription (time in s); the CSV \
         files keep plain column names, their units are listed in units.csv and in \
         summary.json (units)."
    });
    let unit =
        |p: &crate::uq::distributions::RandomParameter| s.units.get(&p.name).map(String::as_str);
    let table = if nominal {
        Table {
            header: inputs::nominal_header(),
            rows: s
                .parameters
                .iter()
                .map(|p| inputs::nominal_row(p, unit(p)))
                .collect(),
        }
    } else {
        Table {
            header: inputs::header(),
            rows: s
                .parameters
                .iter()
                .map(|p| inputs::row(p, unit(p)))
                .collect(),
        }
    };
    let mut head = vec![Section {
        heading: "Study".into(),
        text,
        images,
        table: Some(table),
    }];
    let correlation = s.correlation.as_ref();
    if let Some((header, rows)) =
        correlation.and_then(|c| inputs::correlation_table(c, &s.parameters))
    {
        head.push(Section {
            heading: "Correlation of the inputs".into(),
            text: "The study's [[correlation]]: each cell is the Pearson correlation of the two \
                   inputs' values it asked for (0: not given, independent), and in brackets \
                   the correlation of their normal scores with which the Gaussian copula \
                   (Nataf transformation) draws them."
                .into(),
            images: vec![],
            table: Some(Table { header, rows }),
        });
    }
    if !s.warnings.is_empty() {
        let warnings: Vec<String> = s.warnings.iter().map(|w| plain_quotes(w)).collect();
        head.push(Section {
            heading: "Warnings".into(),
            text: warnings.join("\n\n"),
            images: vec![],
            table: None,
        });
    }
    head
}

/// The suite a study is a variant of (its origin reads `<suite origin> (variant <name>)`),
/// whose page is in the folder above.
fn variant_of(s: &Summary) -> Option<&str> {
    s.origin
        .strip_suffix(&format!(" (variant {})", s.study))
        .filter(|o| !o.is_empty())
}

/// A nominal study: one deterministic run at the parameters' means.
fn is_nominal(s: &Summary) -> bool {
    crate::uq::method::notes_of_kind(&s.method.kind).deterministic
}

/// Markdown code spans of a message (`order`) as quotes (‘order’): the page is not Markdown.
fn plain_quotes(text: &str) -> String {
    let mut open = false;
    text.chars()
        .map(|c| match c {
            '`' => {
                open = !open;
                if open {
                    '‘'
                } else {
                    '’'
                }
            }
            c => c,
        })
        .collect()
}

/// Where the quantiles come from (they are empirical: order statistics of the runs or of the
/// draws; the kernel density is only the PDF's).
fn quantile_source(draws: Draws) -> &'static str {
    match draws {
        Draws::Runs => "empirical, of the runs",
        Draws::Chaos => "empirical, of a large sample of the chaos surrogate",
    }
}

/// The words for a kind of chaos truncation-error estimate.
fn chaos_error_words(kind: ChaosErrorKind) -> &'static str {
    match kind {
        ChaosErrorKind::Loo => "the corrected leave-one-out error of the regression",
        ChaosErrorKind::LevelDifference => {
            "the difference between the chaoses of the last two sparse-grid levels"
        }
        ChaosErrorKind::OrderDifference => {
            "the difference between the chaoses of the last two orders"
        }
    }
}

/// The sentence on an output's chaos truncation error: its largest value over time.
fn chaos_error_sentence(s: &OutputStats) -> Option<String> {
    let e = s.chaos_error.as_ref()?;
    let (i, max) = e
        .values
        .iter()
        .copied()
        .enumerate()
        .filter(|(_, v)| v.is_finite())
        .max_by(|a, b| a.1.total_cmp(&b.1))?;
    Some(format!(
        "\n\nTruncation error of the chaos, estimated by {}: largest {} (relative to the \
         variance) at t = {} s (every time: column {} of {}.csv).",
        chaos_error_words(e.kind),
        sig(max),
        to_spread(s.times.get(i).copied().unwrap_or(f64::NAN), 0.0),
        e.kind.name(),
        stem(&s.name)
    ))
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
    let std_plot = plots::std_plot(dir, s)?;
    if std_plot {
        images.push(format!("{}_std.svg", stem(v)));
    }
    let mut text = if s.deterministic && is_nominal(summary) {
        format!(
            "{v} of the one nominal run (every parameter at its mean): no spread and no \
             density. The plot shows its value."
        )
    } else if s.deterministic {
        format!(
            "{v} has the same value in every run at every time: it is deterministic in this \
             study, so it has no spread and no density. The plot shows its value."
        )
    } else {
        format!(
            "Mean, standard deviation and the μ ± 3σ band of {v} over time, with its quantiles \
             ({}).",
            quantile_source(s.draws)
        )
    };
    if std_plot {
        text.push_str(&format!(
            " The standard deviation of {v} over time is also plotted on its own ({}_std.svg).",
            stem(v)
        ));
    }
    if plots::pdf_heatmap(dir, s)? {
        images.push(format!("{}_pdf.svg", stem(v)));
        text.push_str(&format!(
            "\n\nPDF evolution: the density of {v} ({}) at {} times (columns) on a grid of \
             {} values, colour from 0 upwards. Columns where every run has the same value (for \
             instance a fixed initial state) have no density and are left blank.",
            s.draws.describe(),
            group_digits(s.pdf_times.len()),
            group_digits(s.pdf_grid.len())
        ));
    }
    if s.sobol.is_some() && !s.deterministic {
        plots::sobol_over_time(dir, s, names)?;
        images.push(format!("{}_sobol.svg", stem(v)));
        text.push_str(
            "\n\nSobol' indices over time: the first-order index of each parameter (the share \
             of the variance it causes alone) stacked, and on top the share from interactions \
             (1 − ΣS). Where the Std is zero the indices are undefined and left blank. ",
        );
        text.push_str(files::sobol_csv_sentence(s));
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
            to_spread(s.convergence_time.unwrap_or(f64::NAN), 0.0),
            convergence_axis(c, &summary.method.kind)
        ));
        images.push(format!("{}_convergence.csv", stem(v)));
    }
    if let Some(e) = chaos_error_sentence(s) {
        text.push_str(&e);
    }
    images.push(format!("{}.csv", stem(v)));
    if !s.deterministic {
        images.push(format!("{}_pdf.csv", stem(v)));
    }
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

/// What the convergence plot's x axis is, in words that fit the method `kind`.
fn convergence_axis(c: &results::Convergence, kind: &str) -> String {
    let notes = crate::uq::method::notes_of_kind(kind);
    if c.axis == "runs" {
        let note = notes
            .runs_axis
            .map(|n| format!("; {n}"))
            .unwrap_or_default();
        format!(
            "the number of runs (running estimates over the first n runs in design order{note})"
        )
    } else {
        let truncation = notes
            .truncation
            .unwrap_or("the chaos with its higher-order terms dropped, not computed again");
        format!(
            "the total order of the chaos: the Std of the terms of each order alone (a fast \
             decay means the expansion has converged) and of the expansion truncated there \
             ({truncation})"
        )
    }
}

/// The plots and the section of a scalar quantity, with its table of statistics.
fn quantity_section(
    dir: &Path,
    q: &ScalarStats,
    summary: &Summary,
    names: &[&str],
) -> Result<Section, ReportError> {
    if reliability::is_adaptive(summary) {
        return reliability::section(dir, q, summary, names);
    }
    let name = &q.name;
    let unit = q.unit.as_deref();
    // Means, quantiles and extremes to the resolution the Std allows.
    let num = |v: f64| with_unit(&to_spread(v, q.std), unit);
    let nominal = is_nominal(summary);
    let mut images = Vec::new();
    let mut text = format!("{name}: {}.", q.definition.text);
    if nominal {
        text.push_str(&format!(
            "\n\n{name} = {} from the one nominal run (every parameter at its mean): no \
             spread, no density and no probability.",
            num(q.mean)
        ));
        // Each limit: a row of the table below.
    } else if q.deterministic {
        let why = if q.n_valid < 2 {
            format!("there is {}", count(q.n_valid, "run", "runs"))
        } else {
            format!(
                "every one of the {} runs gives the same value",
                group_digits(q.n_valid)
            )
        };
        text.push_str(&format!(
            "\n\n{name} = {} — {why}: it is deterministic in this study, so it has no \
             spread and no density is drawn.",
            num(q.mean)
        ));
    } else {
        plots::scalar_pdf(dir, q, &summary.study)?;
        images.push(format!("{}_pdf.svg", stem(name)));
        text.push_str(&format!(
            "\n\nDistribution of {name} ({}; the table's quantiles are {}).",
            q.draws.describe(),
            quantile_source(q.draws)
        ));
        if plots::sobol_bars(dir, q, names, &summary.method)? {
            images.push(format!("{}_sobol.svg", stem(name)));
        }
        let (said, scatter) = given_data::section(dir, q, names)?;
        text.push_str(&said);
        images.extend(scatter);
        if let Some(c) = &q.convergence {
            images.extend(plots::convergence(dir, name, unit, c)?);
            text.push_str(&format!(
                "\n\nConvergence: mean and Std against {}.",
                convergence_axis(c, &summary.method.kind)
            ));
            images.push(format!("{}_convergence.csv", stem(name)));
        }
    }
    if let Some(e) = &q.chaos_error {
        text.push_str(&format!(
            "\n\nTruncation error of the chaos, estimated by {}: {} (relative to the variance).",
            chaos_error_words(kind_of(e.kind)),
            sig(e.value)
        ));
    }
    if !q.deterministic {
        images.push(format!("{}_pdf.csv", stem(name)));
    }
    let rows = if nominal {
        nominal_rows(q)
    } else {
        statistics_rows(q, names)
    };
    Ok(quantity_table(name, text, images, rows))
}

/// The section of quantity `name`: `text`, the `images` and then the quantity's samples CSV,
/// and a table of (statistic, value) `rows`.
fn quantity_table(
    name: &str,
    text: String,
    mut images: Vec<String>,
    rows: Vec<Vec<String>>,
) -> Section {
    images.push(format!("{}_samples.csv", stem(name)));
    Section {
        heading: format!("Quantity {name}"),
        text,
        images,
        table: Some(Table::new(&["statistic", "value"], rows)),
    }
}

/// `W = 2.31 is below the limit 2.5 (nominal run; no probability)`, or `exceeds`.
fn against_limit(q: &ScalarStats, limit: f64) -> String {
    let unit = q.unit.as_deref();
    let relation = if q.mean > limit {
        "exceeds"
    } else if q.mean == limit {
        "equals"
    } else {
        "is below"
    };
    format!(
        "{} = {} {relation} the limit {} (nominal run; no probability)",
        q.name,
        with_unit(&to_spread(q.mean, 0.0), unit),
        with_unit(&limit.to_string(), unit)
    )
}

/// The kind of a scalar's truncation-error estimate from its name in `summary.json`.
fn kind_of(name: &str) -> ChaosErrorKind {
    match name {
        "loo" => ChaosErrorKind::Loo,
        "level_difference" => ChaosErrorKind::LevelDifference,
        _ => ChaosErrorKind::OrderDifference,
    }
}

/// The table of a quantity of a nominal study: its definition, unit and value, and where it
/// stands against each limit.
fn nominal_rows(q: &ScalarStats) -> Vec<Vec<String>> {
    let unit = q.unit.as_deref();
    let mut rows = vec![
        vec!["computed as".to_string(), q.definition.text.clone()],
        vec!["unit".into(), unit.unwrap_or("(not declared)").to_owned()],
        vec![
            "value (nominal run)".into(),
            with_unit(&to_spread(q.mean, 0.0), unit),
        ],
    ];
    for e in &q.exceedance_counts {
        rows.push(vec![
            format!(
                "{} against {}",
                q.name,
                with_unit(&e.limit.to_string(), unit)
            ),
            against_limit(q, e.limit),
        ]);
    }
    rows
}

/// The table of statistics of a quantity (no Std, quantiles or extremes when it is the same
/// in every run).
fn statistics_rows(q: &ScalarStats, names: &[&str]) -> Vec<Vec<String>> {
    let name = &q.name;
    let unit = q.unit.as_deref();
    let num = |v: f64| with_unit(&to_spread(v, q.std), unit);
    let mut rows = vec![
        vec!["computed as".to_string(), q.definition.text.clone()],
        vec!["unit".into(), unit.unwrap_or("(not declared)").to_owned()],
    ];
    if q.deterministic {
        rows.push(vec!["value (every run)".into(), num(q.mean)]);
    } else {
        rows.push(vec!["mean".into(), num(q.mean)]);
        rows.push(vec![
            "Std".into(),
            with_unit(&to_spread(q.std, q.std), unit),
        ]);
        // A deterministic value's standard error is round-off: left out.
        if let Some(se) = q.std_error_mean.filter(|&se| se > 0.0) {
            rows.push(vec![
                "standard error of the mean".into(),
                with_unit(&sig(se), unit),
            ]);
        }
    }
    rows.push(vec!["valid runs".into(), group_digits(q.n_valid)]);
    if !q.deterministic {
        rows.push(vec![
            "smallest / largest run".into(),
            format!("{} / {}", num(q.min), num(q.max)),
        ]);
    }
    if q.n_never_hunts + q.n_never_stops > 0 {
        rows.push(vec![
            "never hunt / never stop".into(),
            format!("{} / {}", q.n_never_hunts, q.n_never_stops),
        ]);
    }
    if !q.deterministic {
        for (p, v) in &q.quantiles {
            rows.push(vec![format!("quantile {p}"), num(*v)]);
        }
    }
    for e in &q.exceedance_counts {
        let value = |x: f64| with_unit(&x.to_string(), unit);
        rows.push(vec![
            format!("P({name} > {})", value(e.limit)),
            e.describe_with(&value),
        ]);
    }
    if let Some(e) = &q.chaos_error {
        rows.push(vec![
            format!("chaos truncation error ({}, relative)", e.kind),
            sig(e.value),
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
        let order = plots::by_importance(f, t);
        let sorted = order
            .iter()
            .filter_map(|&i| Some((i, *names.get(i)?)))
            .filter(|_| !undefined);
        for (i, n) in sorted {
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
    rows.extend(given_data::rows(q, names));
    rows
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn warnings_on_the_page_have_no_markdown_backticks() {
        // "raise `order` (below `nodes`)" was shown with its backticks.
        assert_eq!(
            plain_quotes("raise `order` (below `nodes`) or `nodes`"),
            "raise ‘order’ (below ‘nodes’) or ‘nodes’"
        );
    }
}
