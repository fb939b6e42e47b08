//! The plots of an output against time beside its band: its Std (`<V>_std.svg`) and its
//! Sobol' indices (`<V>_sobol.svg`).

use std::path::Path;

use crate::report::file_name::stem;
use crate::report::units::label;
use crate::report::{palette, Band, LinePlot, ReportError, Series};
use crate::results::OutputStats;
use crate::uq::method::Sobol;

/// Below this multiple of the largest value, a Std or an error estimate is round-off: on a
/// log axis such values (and zeros) are drawn at this level.
pub(super) const ROUND_OFF: f64 = 1e-13;
/// A Std at most this multiple of an output's largest |mean| is no spread (every run agrees;
/// the analysis's own threshold).
const NO_SPREAD: f64 = 1e-9;

/// `y` with every finite value below the round-off level `floor` (the unit of `y`) raised to
/// it (on a log axis, round-off and zeros are drawn on that level); sets `clipped` when one
/// was.
pub(super) fn raise_to_round_off(y: &[f64], floor: f64, clipped: &mut bool) -> Vec<f64> {
    y.iter()
        .map(|&v| {
            if v.is_finite() && v < floor {
                *clipped = true;
                floor
            } else {
                v
            }
        })
        .collect()
}

/// The thin dashed grey line of the round-off level `floor` (the unit of the plotted values)
/// from `x[0]` to `x[1]` (the unit of the horizontal axis), with the legend text `label`.
pub(super) fn round_off_line(label: impl Into<String>, x: [f64; 2], floor: f64) -> Series {
    Series::new(label, x.to_vec(), vec![floor; 2], "#999999")
        .thin(1.0, 0.8)
        .dashed()
}

/// `<V>_std.svg`: the Std over time, the Std of the chaos surrogate where the method gives
/// one, and the chaos's truncation-error estimate (loo, order or level difference, a share
/// of the variance ε) as the Std it stands for, √ε · Std, in the same unit. On a log axis
/// when the curves span more than two decades, values below [`ROUND_OFF`] of the largest
/// (round-off, and zeros) drawn at that level (a note in the legend says so). Not written
/// for a deterministic output; returns whether it was written.
pub(in crate::report::study) fn std_plot(dir: &Path, s: &OutputStats) -> Result<bool, ReportError> {
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
        let y = if log {
            raise_to_round_off(&y, floor, &mut clipped)
        } else {
            y
        };
        let line = Series::new(name, s.times.clone(), y, color);
        plot.series.push(if dashed { line.dashed() } else { line });
    }
    if clipped {
        plot.series.push(round_off_line(
            "round-off level (1e-13 × the largest Std): smaller values and zeros are \
             drawn on it",
            [s.times[0], s.times[s.times.len() - 1]],
            floor,
        ));
    }
    if log {
        let lo = if clipped { floor } else { smallest.max(floor) };
        plot.y_range = Some((lo / 2.0, top * 3.0));
    }
    plot.write(&dir.join(format!("{}_std.svg", stem(v))))?;
    Ok(true)
}

/// Share of the largest Std below which the Sobol' indices over time are not drawn: there is
/// little variance to share, and its shares flicker with noise (a fast signal's quiet times).
const LITTLE_VARIANCE: f64 = 0.05;

/// `<V>_sobol.svg`: the first-order indices of every parameter stacked over time, and on top
/// the share of the variance from interactions, 1 − ΣS (one area each; readable for any
/// number of parameters). Where the Std is below [`LITTLE_VARIANCE`] of its largest value
/// the indices are not drawn: those times are greyed out (they are in the CSV).
pub(in crate::report::study) fn sobol_over_time(
    dir: &Path,
    s: &OutputStats,
    names: &[&str],
) -> Result<(), ReportError> {
    let Some(Sobol {
        first, given_data, ..
    }) = &s.sobol
    else {
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
    let title = if *given_data {
        format!("First-order Sobol' indices of {v} over time, estimated from the runs")
    } else if window > 1 {
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
