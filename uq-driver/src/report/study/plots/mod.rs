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
use crate::results::{sig, OutputStats, ScalarStats, Summary};
use crate::uq::given_data::RESAMPLES;
use crate::uq::method::MethodSummary;

mod convergence;
mod over_time;

pub(super) use convergence::convergence;
pub(super) use over_time::{sobol_over_time, std_plot};

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
    let Some(first) = &q.sobol_first else {
        return Ok(false);
    };
    // Indices from given data have no total index: first-order bars only.
    let given_data = q.sobol.as_ref().and_then(|s| s.estimator).is_some();
    let total = match &q.sobol_total {
        Some(t) => t.as_slice(),
        None if given_data => &[],
        None => return Ok(false),
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
    let title = if given_data {
        format!(
            "First-order Sobol' indices of {} (estimated from the runs)",
            q.name
        )
    } else {
        format!("Sobol' indices of {}", q.name)
    };
    let file = dir.join(format!("{}_sobol.svg", stem(&q.name)));
    bars(
        &title,
        names,
        (first, fi),
        (total, ti),
        &if given_data {
            format!(
                "{} (bootstrap of the runs, {RESAMPLES} resamples)",
                interval_label(method, level)
            )
        } else {
            interval_label(method, level)
        },
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

/// The parameters in the order their indices are shown: largest total index first (then
/// largest first-order index; undefined indices last).
pub(in crate::report::study) fn by_importance(first: &[f64], total: &[f64]) -> Vec<usize> {
    let key = |v: &[f64], i: usize| v.get(i).copied().filter(|x| !x.is_nan());
    let mut order: Vec<usize> = (0..first.len().max(total.len())).collect();
    order.sort_by(|&a, &b| {
        let desc = |x: Option<f64>, y: Option<f64>| match (x, y) {
            (Some(x), Some(y)) => y.total_cmp(&x),
            (Some(_), None) => std::cmp::Ordering::Less,
            (None, Some(_)) => std::cmp::Ordering::Greater,
            (None, None) => std::cmp::Ordering::Equal,
        };
        desc(key(total, a), key(total, b)).then(desc(key(first, a), key(first, b)))
    });
    order
}

/// Bars of first-order and total indices per parameter, with intervals where given (no
/// total bars when `total` is empty), the parameters sorted by [`by_importance`].
fn bars(
    title: &str,
    names: &[&str],
    first: Indices,
    total: Indices,
    interval_label: &str,
    file: &Path,
) -> Result<(), ReportError> {
    let order = by_importance(first.0, total.0);
    let pick = |v: &[f64]| -> Vec<f64> {
        if v.is_empty() {
            return Vec::new();
        }
        order
            .iter()
            .map(|&i| v.get(i).copied().unwrap_or(f64::NAN))
            .collect()
    };
    let pick_ci = |v: &[Option<(f64, f64)>]| -> Vec<Option<(f64, f64)>> {
        order.iter().map(|&i| v.get(i).copied().flatten()).collect()
    };
    let names: Vec<&str> = order
        .iter()
        .filter_map(|&i| names.get(i).copied())
        .collect();
    let (first_values, total_values) = (pick(first.0), pick(total.0));
    let (first, total) = (
        (&first_values[..], pick_ci(&first.1)),
        (&total_values[..], pick_ci(&total.1)),
    );
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
        ]
        .into_iter()
        .filter(|g| !g.values.is_empty())
        .collect(),
        y_range: Some((0.0, 1.0)),
        interval_label: interval_label.to_owned(),
    }
    .write(file)?;
    Ok(())
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
