//! Convergence plots: running estimates against the runs, or the Std against the chaos order.

use std::path::Path;

use crate::report::file_name::stem;
use crate::report::units::label;
use crate::report::{palette, Band, LinePlot, ReportError, Series};
use crate::results::Convergence;

use super::over_time::{raise_to_round_off, round_off_line, ROUND_OFF};

/// Convergence plots; returns the files written. Runs: `<name>_convergence.svg`, the running
/// mean over the first n runs with ±2 iid standard errors (Std/√n of those runs), and
/// `<name>_std_convergence.svg`, the running Std (log axis of runs). Chaos:
/// `<name>_convergence.svg`, the Std of the terms of each total order (log axis: its decay
/// shows the convergence) with the Std of the expansion truncated there.
pub(in crate::report::study) fn convergence(
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
    // A nested study's estimate grows by whole outer samples: its standard error is the one
    // between them, and its axis the runs those samples hold.
    let nested = !c.std_error_mean.is_empty();
    let axis = if nested {
        "runs n (design order, whole outer samples)"
    } else {
        "runs n (design order)"
    };
    let mut mean = LinePlot::new(
        format!("{name}: running mean over the first n runs"),
        axis,
        label(&format!("mean {name}"), unit),
    );
    mean.log_x = true;
    let se: Vec<f64> = if nested {
        c.std_error_mean.iter().map(|e| 2.0 * e).collect()
    } else {
        c.std
            .iter()
            .zip(&c.x)
            .map(|(s, n)| 2.0 * s / n.sqrt())
            .collect()
    };
    let band = if nested {
        "± 2 standard errors between the outer samples of the first n runs"
    } else {
        "± 2 iid standard errors of the first n runs (Std/√n; a replicate estimate in the \
         table may be smaller)"
    };
    mean.bands.push(Band::new(
        band,
        c.x.clone(),
        c.mean.iter().zip(&se).map(|(m, e)| m - e).collect(),
        c.mean.iter().zip(&se).map(|(m, e)| m + e).collect(),
        palette(0),
    ));
    mean.series
        .push(Series::new("mean", c.x.clone(), c.mean.clone(), palette(0)));
    let mut std = LinePlot::new(
        format!("{name}: running Std over the first n runs"),
        axis,
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
    let mut clip =
        |y: &[f64]| raise_to_round_off(y.get(1..).unwrap_or_default(), floor, &mut clipped);
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
        p.series.push(round_off_line(
            format!(
                "round-off level ({ROUND_OFF:e} × Std): zeros and smaller values are drawn on it"
            ),
            [x[0], x[x.len() - 1]],
            floor,
        ));
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
