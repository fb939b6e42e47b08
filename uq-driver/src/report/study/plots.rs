//! The plots of a study's folder: the band of an output over time, its PDF evolution, its
//! Sobol' indices over time (stacked), and for a scalar quantity its PDF, its Sobol' bars
//! and the convergence of its mean and Std; the signal against the speed for a critical
//! speed. Every axis carries the unit the FMU declares.

use crate::report::file_name::stem;
use std::path::Path;

use super::super::svg::{finite_range, BarChart, BarGroup};
use super::super::units::{label, per, with_unit, DIMENSIONLESS};
use super::super::{
    histogram_density, palette, write_bytes, Band, DensityPlot, Heatmap, LinePlot, ReportError,
    Series,
};
use super::quantile_column;
use crate::qoi::QoiSpec;
use crate::results::{sig, Convergence, OutputStats, ScalarStats, Summary};
use crate::uq::method::MethodSummary;
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
        // Over a long or fast series dashes break up into noise: thin solid lines there.
        let long = s.times.len() > LONG_SERIES;
        for (i, (p, q)) in s.quantiles.iter().enumerate() {
            if *p != 0.5 {
                let line = Series::new(
                    format!("{} quantile", quantile_column(*p)),
                    s.times.clone(),
                    q.clone(),
                    palette(i + 2),
                )
                .thin(1.0, 0.9);
                plot.series.push(if long { line } else { line.dashed() });
            }
        }
    }
    plot.write(&dir.join(format!("{}_band.svg", stem(v))))
}

/// More time points than this make a series "long": its quantile lines are drawn solid.
const LONG_SERIES: usize = 1000;

/// Below this multiple of the largest value, a Std or an error estimate is round-off: on a
/// log axis such values (and zeros) are drawn at this level.
const ROUND_OFF: f64 = 1e-13;
/// A Std at most this multiple of an output's largest |mean| is no spread (every run agrees;
/// the analysis's own threshold).
const NO_SPREAD: f64 = 1e-9;

/// `<V>_std.svg`: the Std over time, the Std of the chaos surrogate where the method gives
/// one, and the chaos's truncation-error estimate (loo, order or level difference, a share
/// of the variance ε) as the Std it stands for, √ε · Std, in the same unit. On a log axis
/// when the curves span more than two decades, values below [`ROUND_OFF`] of the largest
/// (round-off, and zeros) drawn at that level (a note in the legend says so). Not written
/// for a deterministic output; returns whether it was written.
pub(super) fn std_plot(dir: &Path, s: &OutputStats) -> Result<bool, ReportError> {
    if s.deterministic || !s.std.iter().any(|d| *d > 0.0) {
        return Ok(false);
    }
    let v = &s.name;
    let unit = s.unit.as_deref();
    // Where every run agrees (a Std at most 1e-9 of the output's magnitude, as the analysis
    // counts no spread: e.g. a fixed initial state, or its round-off) there is no spread to
    // show: those times are left out of every curve, and the legend says so.
    let magnitude = s
        .mean
        .iter()
        .copied()
        .filter(|x| x.is_finite())
        .fold(0.0, |m: f64, x| m.max(x.abs()));
    let agrees: Vec<bool> = s.std.iter().map(|d| *d <= NO_SPREAD * magnitude).collect();
    let agree = agrees.iter().filter(|a| **a).count();
    let std_label = if agree > 0 {
        let times = if agree == 1 { "time" } else { "times" };
        format!("Std of {v} (no spread at {agree} {times} where every run agrees: not drawn)")
    } else {
        format!("Std of {v}")
    };
    let mut curves: Vec<(String, Vec<f64>, &str, bool)> =
        vec![(std_label, s.std.clone(), palette(0), false)];
    if let Some(sp) = &s.std_pce {
        curves.push((
            "Std of the chaos surrogate (std_pce)".into(),
            sp.clone(),
            palette(1),
            true,
        ));
    }
    if let Some(e) = &s.chaos_error {
        let kind = e.kind.name();
        let err = e
            .values
            .iter()
            .zip(&s.std)
            .map(|(eps, sd)| eps.max(0.0).sqrt() * sd)
            .collect();
        curves.push((
            format!("truncation-error estimate √{kind} × Std ({kind}: a share of the variance)"),
            err,
            palette(3),
            false,
        ));
    }
    for c in &mut curves {
        for (y, a) in c.1.iter_mut().zip(&agrees) {
            if *a {
                *y = f64::NAN;
            }
        }
    }
    let top = curves
        .iter()
        .flat_map(|c| c.1.iter().copied())
        .filter(|x| x.is_finite())
        .fold(0.0, f64::max);
    let smallest = curves
        .iter()
        .flat_map(|c| c.1.iter().copied())
        .filter(|x| x.is_finite() && *x > 0.0)
        .fold(f64::INFINITY, f64::min);
    let floor = ROUND_OFF * top;
    let log = top / smallest.max(floor) > 100.0;
    let mut plot = LinePlot::new(
        format!("Std of {v} over time"),
        "time [s]",
        label(&format!("Std {v}"), unit),
    );
    plot.log_y = log;
    let mut clipped = false;
    for (name, y, color, dashed) in curves {
        let y: Vec<f64> = if log {
            y.iter()
                .map(|&x| {
                    if x.is_finite() && x < floor {
                        clipped = true;
                        floor
                    } else {
                        x
                    }
                })
                .collect()
        } else {
            y
        };
        let line = Series::new(name, s.times.clone(), y, color);
        plot.series.push(if dashed { line.dashed() } else { line });
    }
    if clipped {
        plot.series.push(
            Series::new(
                "round-off level (1e-13 × the largest Std): smaller values and zeros are \
                 drawn on it",
                vec![s.times[0], s.times[s.times.len() - 1]],
                vec![floor; 2],
                "#999999",
            )
            .thin(1.0, 0.8)
            .dashed(),
        );
    }
    if log {
        let lo = if clipped { floor } else { smallest.max(floor) };
        plot.y_range = Some((lo / 2.0, top * 3.0));
    }
    plot.write(&dir.join(format!("{}_std.svg", stem(v))))?;
    Ok(true)
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
        // Thin and see-through: the density ridge under it stays visible.
        overlay: vec![
            Series::new("mean", s.times.clone(), s.mean.clone(), "#ffffff").thin(1.0, 0.6),
        ],
        log_scale: false,
    };
    let png = heat.to_png().map_err(|source| ReportError::Png {
        path: dir.join(format!("{}_pdf.png", stem(v))),
        source,
    })?;
    write_bytes(&dir.join(format!("{}_pdf.png", stem(v))), &png)?;
    write_bytes(
        &dir.join(format!("{}_pdf.svg", stem(v))),
        heat.to_svg(&Heatmap::data_uri(&png)).as_bytes(),
    )?;
    Ok(true)
}

/// Share of the largest Std below which the Sobol' indices over time are not drawn: there is
/// little variance to share, and its shares flicker with noise (a fast signal's quiet times).
const LITTLE_VARIANCE: f64 = 0.05;

/// `<V>_sobol.svg`: the first-order indices of every parameter stacked over time, and on top
/// the share of the variance from interactions, 1 − ΣS (one area each; readable for any
/// number of parameters). Where the Std is below [`LITTLE_VARIANCE`] of its largest value
/// the indices are not drawn: those times are greyed out (they are in the CSV).
pub(super) fn sobol_over_time(
    dir: &Path,
    s: &OutputStats,
    names: &[&str],
) -> Result<(), ReportError> {
    let Some(Sobol { first, .. }) = &s.sobol else {
        return Ok(());
    };
    let v = &s.name;
    let (times, var, shares) = windowed_shares(&s.times, &s.std, first, names.len());
    let max_var = var.iter().copied().fold(0.0, f64::max);
    let defined: Vec<bool> = var
        .iter()
        .map(|d| *d > LITTLE_VARIANCE * LITTLE_VARIANCE * max_var)
        .collect();
    let window = s.times.len().div_ceil(times.len().max(1));
    let title = if window > 1 {
        format!("Sobol' indices of {v} over time, in variance-weighted windows of {window} steps")
    } else {
        format!("Sobol' indices of {v} over time (first order stacked, interactions on top)")
    };
    let mut plot = LinePlot::new(title, "time [s]", "share of the variance [-]");
    plot.y_range = Some((0.0, 1.0));
    let mut lower = vec![0.0; times.len()];
    for (j, name) in names.iter().enumerate() {
        let col = &shares[j];
        let upper: Vec<f64> = lower
            .iter()
            .zip(col)
            .zip(&defined)
            .map(|((l, c), ok)| if *ok { l + c.max(0.0) } else { f64::NAN })
            .collect();
        plot.bands.push(
            Band::new(
                format!("S {name}"),
                times.clone(),
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
            "interactions 1 − ΣS (a negative estimate of S is drawn as 0)",
            times.clone(),
            lower,
            top,
            "#bbbbbb",
        )
        .opacity(0.75),
    );
    let grey: Vec<f64> = defined
        .iter()
        .map(|ok| if *ok { f64::NAN } else { 1.0 })
        .collect();
    if grey.iter().any(|g| g.is_finite()) {
        plot.bands.push(
            Band::new(
                format!(
                    "Std below {:.0} % of its largest: indices not drawn",
                    LITTLE_VARIANCE * 100.0
                ),
                times.clone(),
                vec![0.0; times.len()],
                grey,
                "#e0e0e0",
            )
            .opacity(0.9),
        );
    }
    plot.write(&dir.join(format!("{}_sobol.svg", stem(v))))
}

/// More time steps than this are drawn as windows ([`windowed_shares`]).
const MAX_SHARE_STEPS: usize = 1000;
/// The number of windows a long series' indices are drawn in.
const SHARE_WINDOWS: usize = 150;

/// The first-order indices over time, as drawn: at every time for a series of at most
/// [`MAX_SHARE_STEPS`] steps, else over [`SHARE_WINDOWS`] windows of equal numbers of steps,
/// each the variance-weighted mean of its steps' indices, S_i = Σ Var(t) S_i(t) / Σ Var(t)
/// (the indices of the window's variance, as the indices of the whole series are; a fast
/// signal's indices flicker from step to step). Returns the times (window centres), the
/// variance (window mean) and `shares[parameter][time]`; NaN indices do not count.
fn windowed_shares(
    times: &[f64],
    std: &[f64],
    first: &[Vec<f64>],
    parameters: usize,
) -> (Vec<f64>, Vec<f64>, Vec<Vec<f64>>) {
    let nt = times.len().min(std.len()).min(first.len());
    let width = if nt > MAX_SHARE_STEPS {
        nt.div_ceil(SHARE_WINDOWS)
    } else {
        1
    };
    let (mut t, mut var) = (Vec::new(), Vec::new());
    let mut shares = vec![Vec::new(); parameters];
    for start in (0..nt).step_by(width) {
        let end = (start + width).min(nt);
        t.push(0.5 * (times[start] + times[end - 1]));
        let v: Vec<f64> = std[start..end].iter().map(|s| s * s).collect();
        var.push(v.iter().sum::<f64>() / v.len() as f64);
        for (j, share) in shares.iter_mut().enumerate() {
            let (mut num, mut den) = (0.0, 0.0);
            for (k, w) in (start..end).zip(&v) {
                let x = first[k].get(j).copied().unwrap_or(f64::NAN);
                if x.is_finite() {
                    num += w * x;
                    den += w;
                }
            }
            share.push(if den > 0.0 { num / den } else { f64::NAN });
        }
    }
    (t, var, shares)
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
    .write(&dir.join(format!("{}_pdf.svg", stem(name))))
}

/// `<q>_sobol.svg`: first-order and total Sobol' indices per parameter as bars, with a
/// whisker for the interval of each where the method gives them (`first_ci`, `total_ci` of
/// the quantity's summary), labelled from the method's summary ([`interval_label`]).
pub(super) fn sobol_bars(
    dir: &Path,
    q: &ScalarStats,
    names: &[&str],
    method: &MethodSummary,
) -> Result<bool, ReportError> {
    let (Some(first), Some(total)) = (&q.sobol_first, &q.sobol_total) else {
        return Ok(false);
    };
    if first.iter().chain(total).all(|x| x.is_nan()) {
        // No variance: the indices are undefined, there is nothing to draw.
        return Ok(false);
    }
    let of =
        |ci: Option<&std::collections::BTreeMap<String, [f64; 2]>>| -> Vec<Option<(f64, f64)>> {
            names
                .iter()
                .map(|n| ci.and_then(|m| m.get(*n)).map(|[lo, hi]| (*lo, *hi)))
                .collect()
        };
    let summary = q.sobol.as_ref();
    let fi = of(summary.and_then(|s| s.first_ci.as_ref()));
    let ti = of(summary.and_then(|s| s.total_ci.as_ref()));
    let level = summary.and_then(|s| s.ci_level);
    let title = format!("Sobol' indices of {}", q.name);
    let file = dir.join(format!("{}_sobol.svg", stem(&q.name)));
    bars(
        &title,
        names,
        (first, fi),
        (total, ti),
        &interval_label(method, level),
        &file,
    )?;
    Ok(true)
}

/// The legend text of the intervals of Sobol' indices, in the words of the method's summary:
/// "95 % interval (8 replicates, Student t)", "95 % interval (percentile bootstrap, 500
/// resamples)", or "95 % interval".
pub(super) fn interval_label(method: &MethodSummary, level: Option<f64>) -> String {
    let level = level.unwrap_or(0.95);
    let percent = 100.0 * level;
    let head = if (percent - percent.round()).abs() < 1e-9 {
        format!("{percent:.0} % interval")
    } else {
        format!("{} % interval", sig(percent))
    };
    let d = &method.details;
    let words = d.get("intervals").and_then(|w| w.as_str()).unwrap_or("");
    if let Some(r) = d.get("replicates").and_then(|r| r.as_u64()) {
        if words.contains("Student") || words.starts_with("replicates") {
            return format!("{head} ({r} replicates, Student t)");
        }
    }
    if let Some(b) = d.get("bootstrap").and_then(|b| b.as_u64()) {
        if words.contains("bootstrap") {
            return format!("{head} (percentile bootstrap, {b} resamples)");
        }
    }
    match words.split_once(':') {
        Some((kind, _)) if !kind.is_empty() => format!("{head} ({kind})"),
        _ => head,
    }
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
    let file = dir.join(format!("{}_sobol_overall.svg", stem(output)));
    bars(
        &title,
        names,
        (first, none.clone()),
        (total, none),
        "",
        &file,
    )
}

/// Indices per parameter with their intervals (`None` where there are none).
type Indices<'a> = (&'a [f64], Vec<Option<(f64, f64)>>);

/// Bars of first-order and total indices per parameter, with intervals where given.
fn bars(
    title: &str,
    names: &[&str],
    first: Indices,
    total: Indices,
    interval_label: &str,
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
        interval_label: interval_label.to_owned(),
    }
    .write(file)?;
    Ok(())
}

/// Convergence plots; returns the files written. Runs: `<name>_convergence.svg`, the running
/// mean over the first n runs with ±2 iid standard errors (Std/√n of those runs), and
/// `<name>_std_convergence.svg`, the running Std (log axis of runs). Chaos:
/// `<name>_convergence.svg`, the Std of the terms of each total order (log axis: its decay
/// shows the convergence) with the Std of the expansion truncated there.
pub(super) fn convergence(
    dir: &Path,
    name: &str,
    unit: Option<&str>,
    c: &Convergence,
) -> Result<Vec<String>, ReportError> {
    if c.axis != "runs" {
        let file = format!("{}_convergence.svg", stem(name));
        chaos_convergence(name, unit, c).write(&dir.join(&file))?;
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
        "± 2 iid standard errors of the first n runs (Std/√n; a replicate estimate in the \
         table may be smaller)",
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
        format!("{}_convergence.svg", stem(name)),
        format!("{}_std_convergence.svg", stem(name)),
    ];
    mean.write(&dir.join(&files[0]))?;
    std.write(&dir.join(&files[1]))?;
    Ok(files)
}

/// The Std of the terms of each chaos order and of the chaos truncated there, against the
/// order: integer ticks, a dot at every order, values below [`ROUND_OFF`] of the total Std
/// (round-off, and zeros) drawn on that level (a dashed line and a legend note say so), and
/// room above the largest value.
fn chaos_convergence(name: &str, unit: Option<&str>, c: &Convergence) -> LinePlot {
    let mut p = LinePlot::new(
        format!("{name}: Std by chaos order"),
        "total order of the chaos",
        label(&format!("Std {name}"), unit),
    );
    p.log_y = true;
    p.integer_x = true;
    let x = c.x.get(1..).unwrap_or_default().to_vec();
    let top = c
        .std
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max);
    let floor = ROUND_OFF * top;
    let mut clipped = false;
    let mut clip = |y: &[f64]| -> Vec<f64> {
        y.get(1..)
            .unwrap_or_default()
            .iter()
            .map(|&v| {
                if v.is_finite() && v < floor {
                    clipped = true;
                    floor
                } else {
                    v
                }
            })
            .collect()
    };
    let (of_order, upto) = (clip(&c.std_of_order), clip(&c.std));
    p.series.push(
        Series::new(
            "Std of the terms of that order",
            x.clone(),
            of_order,
            palette(1),
        )
        .with_markers(),
    );
    p.series.push(
        Series::new(
            "Std of the chaos up to that order",
            x.clone(),
            upto,
            palette(0),
        )
        .dashed()
        .with_markers(),
    );
    if clipped && !x.is_empty() {
        p.series.push(
            Series::new(
                format!("round-off level ({ROUND_OFF:e} × Std): zeros and smaller values are drawn on it"),
                vec![x[0], x[x.len() - 1]],
                vec![floor; 2],
                "#999999",
            )
            .thin(1.0, 0.8)
            .dashed(),
        );
    }
    if top > 0.0 {
        let smallest = p
            .series
            .iter()
            .flat_map(|s| s.y.iter().copied())
            .filter(|v| v.is_finite() && *v > 0.0)
            .fold(top, f64::min);
        // Headroom: the total Std is not drawn on the frame.
        p.y_range = Some((smallest / 3.0, top * 4.0));
    }
    p
}

/// `<signal>_vs_<speed>.svg` for a critical-speed quantity whose signal and speed are both
/// outputs (the paper's Fig. 5a): the file name, or `None` when there is no such plot.
pub(super) fn speed_plot(
    dir: &Path,
    spec: &QoiSpec,
    outputs: &[OutputStats],
    quantities: &[ScalarStats],
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
    let what = if y.deterministic {
        format!("{signal} (the same in every run)")
    } else {
        format!("{signal} (mean)")
    };
    push_band(&mut plot, &v.mean, y, what);
    let ends = vec![v.mean[0], v.mean[v.mean.len() - 1]];
    let threshold_label = with_unit(&format!("threshold ±{threshold}"), y.unit.as_deref());
    plot.series.push(
        Series::new(
            threshold_label,
            ends.clone(),
            vec![*threshold; 2],
            palette(3),
        )
        .thin(1.0, 0.8)
        .dashed(),
    );
    plot.series.push(
        Series::new("", ends, vec![-*threshold; 2], palette(3))
            .thin(1.0, 0.8)
            .dashed(),
    );
    // The critical speed the study computed, where it has that quantity (Fig. 5a marks it).
    if let Some(q) = quantities.iter().find(|q| q.name == spec.name()) {
        if q.mean.is_finite() {
            let (lo, hi) = finite_range(
                y.lower_3sigma
                    .iter()
                    .chain(&y.upper_3sigma)
                    .chain(&y.mean)
                    .copied(),
                false,
            )
            .unwrap_or((-1.0, 1.0));
            let text = if q.deterministic {
                format!(
                    "{} = {}",
                    q.name,
                    with_unit(&sig(q.mean), v.unit.as_deref())
                )
            } else {
                format!(
                    "mean {} = {}",
                    q.name,
                    with_unit(&sig(q.mean), v.unit.as_deref())
                )
            };
            plot.series
                .push(Series::new(text, vec![q.mean; 2], vec![lo, hi], palette(2)).thin(1.5, 0.9));
        }
    }
    let file = format!("{}_vs_{}.svg", stem(signal), stem(speed));
    plot.write(&dir.join(&file))?;
    Ok(Some(file))
}
