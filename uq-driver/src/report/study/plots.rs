//! The plots of a study's folder: the band of an output over time, its PDF evolution, its
//! Sobol' indices over time (stacked), and for a scalar quantity its PDF, its Sobol' bars
//! and the convergence of its mean and Std; the signal against the speed for a critical
//! speed. Every axis carries the unit the FMU declares.

use std::path::Path;

use super::super::svg::{BarChart, BarGroup};
use super::super::units::{label, per, DIMENSIONLESS};
use super::super::{
    histogram_density, palette, write_bytes, Band, DensityPlot, Heatmap, LinePlot, ReportError,
    Series,
};
use super::files::column;
use super::quantile_column;
use crate::qoi::QoiSpec;
use crate::results::{Convergence, OutputStats, ScalarStats, Summary};
use crate::uq::method::Sobol;

/// `<V>_band.svg`: mean ± 3σ and the quantiles other than the median (only the value, for
/// a deterministic output).
pub(super) fn band(dir: &Path, s: &OutputStats, summary: &Summary) -> Result<(), ReportError> {
    let v = &s.name;
    let title = format!(
        "{v}: mean ± 3σ ({}, {})",
        summary.study, summary.method.kind
    );
    let mut plot = LinePlot::new(title, "time [s]", label(v, s.unit.as_deref()));
    if s.deterministic {
        plot.title = format!("{v}: the same in every run ({})", summary.study);
        plot.series.push(Series::new(
            "value (every run)",
            s.times.clone(),
            s.mean.clone(),
            palette(0),
        ));
    } else {
        push_band(&mut plot, &s.times, s, "mean".into());
        for (i, (p, q)) in s.quantiles.iter().enumerate() {
            if *p != 0.5 {
                plot.series.push(
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
    }
    plot.write(&dir.join(format!("{v}_band.svg")))
}

/// Adds the mean ± 3σ band of `s` (unless its Std is zero throughout) and its mean, both
/// against `x`, to `plot`.
pub(super) fn push_band(plot: &mut LinePlot, x: &[f64], s: &OutputStats, mean_label: String) {
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

/// `<V>_pdf.png` and `<V>_pdf.svg`: the PDF evolution heat map, colours from 0 to the 99th
/// percentile of the densities (larger ones are clipped to it, so that a narrow start, every
/// run near the same initial value, does not wash out the rest). Columns where every run
/// agrees have no density and stay blank. Not written for a deterministic output.
pub(super) fn pdf_heatmap(dir: &Path, s: &OutputStats) -> Result<bool, ReportError> {
    if s.deterministic || s.pdf.is_empty() {
        return Ok(false);
    }
    let v = &s.name;
    let mut all: Vec<f64> = s
        .pdf
        .iter()
        .flatten()
        .copied()
        .filter(|x| x.is_finite() && *x > 0.0)
        .collect();
    if all.is_empty() {
        return Ok(false);
    }
    all.sort_by(f64::total_cmp);
    let cap = all[((all.len() as f64 * 0.99) as usize).min(all.len() - 1)];
    let unit = s.unit.as_deref();
    let density_unit = per(unit).map(|u| format!(" [{u}]")).unwrap_or_default();
    let heat = Heatmap {
        title: format!("PDF evolution of {v}"),
        x_label: "time [s]".into(),
        y_label: label(v, unit),
        x: s.pdf_times.clone(),
        y: s.pdf_grid.clone(),
        z: s.pdf
            .iter()
            // NaN (no density) stays NaN: f64::min would turn it into the cap.
            .map(|c| c.iter().map(|x| if *x > cap { cap } else { *x }).collect())
            .collect(),
        colorbar_label: format!("PDF of {v}{density_unit}, clipped at its 99th percentile"),
        overlay: vec![Series::new(
            "mean",
            s.times.clone(),
            s.mean.clone(),
            "#ffffff",
        )],
        log_scale: false,
    };
    let png = heat.to_png().map_err(|source| ReportError::Png {
        path: dir.join(format!("{v}_pdf.png")),
        source,
    })?;
    write_bytes(&dir.join(format!("{v}_pdf.png")), &png)?;
    write_bytes(
        &dir.join(format!("{v}_pdf.svg")),
        heat.to_svg(&Heatmap::data_uri(&png)).as_bytes(),
    )?;
    Ok(true)
}

/// Relative Std below which Sobol' indices over time are undefined (no variance to share).
const NO_VARIANCE: f64 = 1e-9;

/// `<V>_sobol.svg`: the first-order indices of every parameter stacked over time, and on top
/// the share of the variance from interactions, 1 − ΣS (one area each; readable for any
/// number of parameters). Where the Std vanishes the indices are undefined: left blank.
pub(super) fn sobol_over_time(
    dir: &Path,
    s: &OutputStats,
    names: &[&str],
) -> Result<(), ReportError> {
    let Some(Sobol { first, .. }) = &s.sobol else {
        return Ok(());
    };
    let v = &s.name;
    let max_std = s.std.iter().copied().fold(0.0, f64::max);
    let defined: Vec<bool> = s.std.iter().map(|d| *d > NO_VARIANCE * max_std).collect();
    let mut plot = LinePlot::new(
        format!("Sobol' indices of {v} over time (first order stacked, interactions on top)"),
        "time [s]",
        "share of the variance [-]",
    );
    plot.y_range = Some((0.0, 1.0));
    let mut lower = vec![0.0; s.times.len()];
    for (j, name) in names.iter().enumerate() {
        let col = column(first, j);
        let upper: Vec<f64> = lower
            .iter()
            .zip(&col)
            .zip(&defined)
            .map(|((l, c), ok)| if *ok { l + c.max(0.0) } else { f64::NAN })
            .collect();
        plot.bands.push(
            Band::new(
                format!("S {name}"),
                s.times.clone(),
                lower.clone(),
                upper.clone(),
                palette(j),
            )
            .opacity(0.75),
        );
        lower = upper;
    }
    let top: Vec<f64> = lower
        .iter()
        .map(|l| if l.is_finite() { l.max(1.0) } else { f64::NAN })
        .collect();
    plot.bands.push(
        Band::new(
            "interactions 1 − ΣS",
            s.times.clone(),
            lower,
            top,
            "#bbbbbb",
        )
        .opacity(0.75),
    );
    plot.write(&dir.join(format!("{v}_sobol.svg")))
}

/// `<q>_pdf.svg`: the density, a histogram of the runs (more than 10) and the limits. The
/// horizontal range is that of the data; a limit beyond it is an arrow at the edge.
pub(super) fn scalar_pdf(dir: &Path, q: &ScalarStats, study: &str) -> Result<(), ReportError> {
    let name = &q.name;
    let (edges, dens) = histogram_density(&q.samples, 0);
    let what = match q.draws {
        crate::uq::method::Draws::Runs => format!("{} runs", q.samples.len()),
        crate::uq::method::Draws::Chaos => {
            format!("{} draws of the chaos surrogate", q.density_samples.len())
        }
    };
    let with_unit = |v: f64| match q.unit.as_deref() {
        Some(u) if u != DIMENSIONLESS => format!("{v} {u}"),
        _ => format!("{v}"),
    };
    DensityPlot {
        title: format!("PDF of {name} ({study})"),
        x_label: label(name, q.unit.as_deref()),
        curves: vec![Series::new(
            format!("kernel density of {what}"),
            q.pdf_x.clone(),
            q.pdf.clone(),
            palette(0),
        )],
        // A histogram of weighted nodes (collocation) would not be a distribution.
        histogram: (q.draws == crate::uq::method::Draws::Runs && q.samples.len() > 10)
            .then_some((edges, dens)),
        markers: q
            .exceedance_counts
            .iter()
            .map(|e| {
                (
                    e.limit,
                    format!(
                        "limit {}: {} of {} above",
                        with_unit(e.limit),
                        e.exceeded,
                        e.of
                    ),
                )
            })
            .collect(),
    }
    .write(&dir.join(format!("{name}_pdf.svg")))
}

/// 95 % intervals of the first-order and the total indices, per parameter (where given).
pub(super) type SobolIntervals<'a> = (&'a [Option<(f64, f64)>], &'a [Option<(f64, f64)>]);

/// `<q>_sobol.svg`: first-order and total Sobol' indices per parameter as bars (with their
/// intervals where the method gives them).
pub(super) fn sobol_bars(
    dir: &Path,
    q: &ScalarStats,
    names: &[&str],
    intervals: Option<SobolIntervals>,
) -> Result<bool, ReportError> {
    let (Some(first), Some(total)) = (&q.sobol_first, &q.sobol_total) else {
        return Ok(false);
    };
    if first.iter().chain(total).all(|x| x.is_nan()) {
        // No variance: the indices are undefined, there is nothing to draw.
        return Ok(false);
    }
    let (fi, ti) = match intervals {
        Some((f, t)) => (f.to_vec(), t.to_vec()),
        None => (vec![None; first.len()], vec![None; total.len()]),
    };
    let title = format!("Sobol' indices of {}", q.name);
    let file = dir.join(format!("{}_sobol.svg", q.name));
    bars(&title, names, (first, fi), (total, ti), &file)?;
    Ok(true)
}

/// `<V>_sobol_overall.svg`: the bar chart of the Sobol' indices of the whole series of an
/// output (`first`, `total`: [`Sobol::integrated`](crate::uq::method::Sobol::integrated)).
pub(super) fn sobol_overall_bars(
    dir: &Path,
    output: &str,
    names: &[&str],
    first: &[f64],
    total: &[f64],
) -> Result<(), ReportError> {
    let title = format!("Sobol' indices of {output} over the whole series");
    let none = vec![None; first.len()];
    let file = dir.join(format!("{output}_sobol_overall.svg"));
    bars(&title, names, (first, none.clone()), (total, none), &file)
}

/// Indices per parameter with their intervals (`None` where there are none).
type Indices<'a> = (&'a [f64], Vec<Option<(f64, f64)>>);

/// Bars of first-order and total indices per parameter, with intervals where given.
fn bars(
    title: &str,
    names: &[&str],
    first: Indices,
    total: Indices,
    file: &Path,
) -> Result<(), ReportError> {
    BarChart {
        title: title.to_owned(),
        y_label: "share of the variance [-]".into(),
        x_label: "parameter".into(),
        categories: names.iter().map(|n| n.to_string()).collect(),
        groups: vec![
            BarGroup {
                label: "first order S".into(),
                color: palette(0).into(),
                values: first.0.to_vec(),
                intervals: first.1,
            },
            BarGroup {
                label: "total ST".into(),
                color: palette(1).into(),
                values: total.0.to_vec(),
                intervals: total.1,
            },
        ],
        y_range: Some((0.0, 1.0)),
    }
    .write(file)?;
    Ok(())
}

/// Convergence plots; returns the files written. Runs: `<name>_convergence.svg`, the running
/// mean over the first n runs with ±2 standard errors, and `<name>_std_convergence.svg`,
/// the running Std (log axis of runs). Chaos: `<name>_convergence.svg`, the Std of the
/// terms of each total order (log axis: its decay shows the convergence) with the Std of
/// the expansion truncated there.
pub(super) fn convergence(
    dir: &Path,
    name: &str,
    unit: Option<&str>,
    c: &Convergence,
) -> Result<Vec<String>, ReportError> {
    if c.axis != "runs" {
        let mut p = LinePlot::new(
            format!("{name}: Std by chaos order"),
            "total order of the chaos",
            label(&format!("Std {name}"), unit),
        );
        p.log_y = true;
        let (x, y) = (c.x[1..].to_vec(), c.std_of_order[1..].to_vec());
        p.series.push(Series::new(
            "Std of the terms of that order",
            x.clone(),
            y,
            palette(1),
        ));
        p.series.push(
            Series::new(
                "Std of the chaos up to that order",
                x,
                c.std[1..].to_vec(),
                palette(0),
            )
            .dashed(),
        );
        let file = format!("{name}_convergence.svg");
        p.write(&dir.join(&file))?;
        return Ok(vec![file]);
    }
    let mut mean = LinePlot::new(
        format!("{name}: running mean over the first n runs"),
        "runs n (design order)",
        label(&format!("mean {name}"), unit),
    );
    mean.log_x = true;
    let se: Vec<f64> = c
        .std
        .iter()
        .zip(&c.x)
        .map(|(s, n)| 2.0 * s / n.sqrt())
        .collect();
    mean.bands.push(Band::new(
        "± 2 standard errors",
        c.x.clone(),
        c.mean.iter().zip(&se).map(|(m, e)| m - e).collect(),
        c.mean.iter().zip(&se).map(|(m, e)| m + e).collect(),
        palette(0),
    ));
    mean.series
        .push(Series::new("mean", c.x.clone(), c.mean.clone(), palette(0)));
    let mut std = LinePlot::new(
        format!("{name}: running Std over the first n runs"),
        "runs n (design order)",
        label(&format!("Std {name}"), unit),
    );
    std.log_x = true;
    std.series
        .push(Series::new("Std", c.x.clone(), c.std.clone(), palette(1)));
    let files = vec![
        format!("{name}_convergence.svg"),
        format!("{name}_std_convergence.svg"),
    ];
    mean.write(&dir.join(&files[0]))?;
    std.write(&dir.join(&files[1]))?;
    Ok(files)
}

/// `<signal>_vs_<speed>.svg` for a critical-speed quantity whose signal and speed are both
/// outputs (the paper's Fig. 5a): the file name, or `None` when there is no such plot.
pub(super) fn speed_plot(
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
        label(speed, v.unit.as_deref()),
        label(signal, y.unit.as_deref()),
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
