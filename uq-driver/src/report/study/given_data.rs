//! What the page says of a scalar quantity's sensitivity estimated from the runs of a design
//! that samples the inputs' law (`mc`, `lhs`, `qmc`): the caption of its first-order Sobol'
//! bars, its rank correlations in the table, and `<q>_scatter.svg`, the quantity against
//! each parameter with the binned means (small multiples, the most influential first).

use std::fmt::Write as _;
use std::path::Path;

use crate::report::file_name::stem;
use crate::report::svg::{c, Axis};
use crate::report::{escape_xml, palette, write_bytes, ReportError};
use crate::results::{sig, ScalarStats};
use crate::uq::given_data::{bin_count, RESAMPLES};

/// At most this many panels (parameters) in a scatter grid.
pub(super) const MAX_PANELS: usize = 12;
/// At most this many points drawn per panel (every k-th run beyond).
const MAX_POINTS: usize = 1500;
/// Panels per row.
const COLUMNS: usize = 4;
/// Panel width and height (px).
const PANEL_W: f64 = 230.0;
const PANEL_H: f64 = 170.0;
/// Margins left of and above the grid, and between panels (px).
const LEFT: f64 = 62.0;
const TOP: f64 = 48.0;
const GAP_X: f64 = 78.0;
const GAP_Y: f64 = 62.0;

/// Whether the quantity's indices are estimates from given data.
fn given_data(q: &ScalarStats) -> bool {
    q.sobol.as_ref().and_then(|s| s.estimator) == Some("given_data")
}

/// The paragraph under the Sobol' bars and `<q>_scatter.svg` of a quantity estimated from
/// given data (its text and the images it adds); nothing otherwise.
pub(super) fn section(
    dir: &Path,
    q: &ScalarStats,
    names: &[&str],
) -> Result<(String, Vec<String>), ReportError> {
    let (Some(inputs), true) = (&q.run_inputs, given_data(q)) else {
        return Ok((String::new(), Vec::new()));
    };
    let level = q.sobol.as_ref().and_then(|s| s.ci_level).unwrap_or(0.95);
    let mut text = format!(
        "\n\nSensitivity of {name}, estimated from the {n} runs themselves (given data, not a \
         design made for it): first-order Sobol' indices by binning each parameter's values \
         into {m} equally likely bins (the variance of the bin means, corrected for their \
         noise, over the variance of {name}), with {p:.0} % bootstrap intervals \
         ({RESAMPLES} resamples); no total indices. Under correlated parameters an index is the \
         share of the variance that knowing that parameter alone removes, what it carries of \
         the parameters it is correlated with included. Rank correlations (Spearman, PRCC) are \
         in the table.",
        name = q.name,
        n = crate::results::group_digits(q.samples.len()),
        m = bin_count(q.samples.len()),
        p = 100.0 * level,
    );
    let order = by_importance(q, names);
    if order.is_empty() || q.deterministic {
        return Ok((text, Vec::new()));
    }
    let file = format!("{}_scatter.svg", stem(&q.name));
    let shown = order.len().min(MAX_PANELS);
    write_bytes(
        &dir.join(&file),
        scatter_svg(q, names, inputs, &order[..shown]).as_bytes(),
    )?;
    let _ = write!(
        text,
        "\n\nScatter plots of {name} against {which}, with the mean of {name} in each of the \
         bins (line): a trend shows a first-order effect, a spread around it the rest.",
        name = q.name,
        which = if shown < order.len() {
            format!(
                "the {shown} most influential of the {} parameters (by first-order index)",
                order.len()
            )
        } else {
            "each parameter, the most influential first".into()
        }
    );
    Ok((text, vec![file]))
}

/// The parameters by decreasing first-order index (|Spearman| where the index is undefined).
fn by_importance(q: &ScalarStats, names: &[&str]) -> Vec<usize> {
    let first = q.sobol_first.as_deref().unwrap_or(&[]);
    let spearman = |i: usize| {
        q.rank_correlation
            .as_ref()
            .and_then(|r| r.spearman.get(names[i]).copied())
            .unwrap_or(f64::NAN)
    };
    let key = |i: usize| {
        let s = first.get(i).copied().unwrap_or(f64::NAN);
        let v = if s.is_finite() { s } else { spearman(i).abs() };
        if v.is_finite() {
            v
        } else {
            -1.0
        }
    };
    let mut order: Vec<usize> = (0..names.len()).collect();
    order.sort_by(|&a, &b| key(b).total_cmp(&key(a)).then(a.cmp(&b)));
    order
}

/// The rows of the statistics table: each parameter's first-order index with its interval,
/// and its Spearman coefficient and PRCC.
pub(super) fn rows(q: &ScalarStats, names: &[&str]) -> Vec<Vec<String>> {
    let mut rows = Vec::new();
    if !given_data(q) || q.deterministic {
        return rows;
    }
    // NaN: a parameter (or the quantity) without spread.
    let sig = |x: f64| {
        if x.is_finite() {
            sig(x)
        } else {
            "undefined".into()
        }
    };
    let s = q.sobol.as_ref();
    let level = s.and_then(|s| s.ci_level).unwrap_or(0.95);
    for n in names {
        let value = s.and_then(|s| s.first.get(*n)).copied().unwrap_or(f64::NAN);
        let ci = s.and_then(|s| s.first_ci.as_ref()?.get(*n));
        let interval = ci
            .filter(|[lo, hi]| lo.is_finite() && hi.is_finite())
            .map_or(String::new(), |[lo, hi]| {
                format!(" [{}, {}]", sig(*lo), sig(*hi))
            });
        rows.push(vec![
            format!(
                "first-order Sobol' index of {n} (from the runs, {:.0} % interval)",
                100.0 * level
            ),
            format!("{}{interval}", sig(value)),
        ]);
    }
    if let Some(r) = &q.rank_correlation {
        for n in names {
            let get = |m: &std::collections::BTreeMap<String, f64>| {
                sig(m.get(*n).copied().unwrap_or(f64::NAN))
            };
            rows.push(vec![
                format!("rank correlation with {n}: Spearman / PRCC"),
                format!("{} / {}", get(&r.spearman), get(&r.prcc)),
            ]);
        }
    }
    rows
}

/// The small-multiples SVG: one panel per parameter of `order`.
fn scatter_svg(q: &ScalarStats, names: &[&str], inputs: &[Vec<f64>], order: &[usize]) -> String {
    let y = &q.samples;
    let cols = order.len().min(COLUMNS);
    let rows = order.len().div_ceil(COLUMNS);
    let width = LEFT + cols as f64 * (PANEL_W + GAP_X);
    let height = TOP + rows as f64 * (PANEL_H + GAP_Y);
    let mut out = String::new();
    let _ = writeln!(
        out,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" \
         viewBox=\"0 0 {w} {h}\" font-family=\"DejaVu Sans, Helvetica, Arial, sans-serif\" \
         font-size=\"11\">\n<rect width=\"100%\" height=\"100%\" fill=\"#fff\"/>",
        w = c(width),
        h = c(height)
    );
    let unit = q
        .unit
        .as_deref()
        .map_or(String::new(), |u| format!(" [{u}]"));
    let _ = writeln!(
        out,
        "<text x=\"{}\" y=\"20\" font-size=\"14\" text-anchor=\"middle\">{}</text>",
        c(width / 2.0),
        escape_xml(&format!(
            "{}{unit} against each parameter (runs, binned means)",
            q.name
        ))
    );
    let ya = Axis::linear_exact(Some(padded(y)));
    let (ylo, yhi) = (ya.lo, ya.hi);
    let step = y.len().div_ceil(MAX_POINTS).max(1);
    for (k, &i) in order.iter().enumerate() {
        let x = &inputs[i];
        let xa = Axis::linear_exact(Some(padded(x)));
        let (xlo, xhi) = (xa.lo, xa.hi);
        let left = LEFT + (k % COLUMNS) as f64 * (PANEL_W + GAP_X);
        let top = TOP + (k / COLUMNS) as f64 * (PANEL_H + GAP_Y);
        let px = |v: f64| left + (v - xlo) / (xhi - xlo) * PANEL_W;
        let py = |v: f64| top + (1.0 - (v - ylo) / (yhi - ylo)) * PANEL_H;
        let _ = writeln!(
            out,
            "<g class=\"panel\"><rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"none\" \
             stroke=\"#888\"/>",
            c(left),
            c(top),
            c(PANEL_W),
            c(PANEL_H)
        );
        let s1 = q
            .sobol
            .as_ref()
            .and_then(|s| s.first.get(names[i]))
            .copied();
        let rho = q
            .rank_correlation
            .as_ref()
            .and_then(|r| r.spearman.get(names[i]))
            .copied();
        let caption = format!(
            "{} (S = {}, ρ = {})",
            names[i],
            s1.filter(|v| v.is_finite()).map_or("–".into(), sig),
            rho.filter(|v| v.is_finite()).map_or("–".into(), sig)
        );
        let _ = writeln!(
            out,
            "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\" font-size=\"12\">{}</text>",
            c(left + PANEL_W / 2.0),
            c(top - 6.0),
            escape_xml(&caption)
        );
        for (t, label) in xa.ticks.iter().zip(&xa.labels).step_by(2) {
            let _ = writeln!(
                out,
                "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\" fill=\"#444\">{}</text>",
                c(px(*t)),
                c(top + PANEL_H + 14.0),
                escape_xml(label)
            );
        }
        for (t, label) in ya.ticks.iter().zip(&ya.labels).step_by(2) {
            let _ = writeln!(
                out,
                "<text x=\"{}\" y=\"{}\" text-anchor=\"end\" fill=\"#444\">{}</text>",
                c(left - 4.0),
                c(py(*t) + 4.0),
                escape_xml(label)
            );
        }
        out.push_str("<g fill=\"");
        out.push_str(palette(0));
        out.push_str("\" fill-opacity=\"0.35\">\n");
        for j in (0..y.len().min(x.len())).step_by(step) {
            if x[j].is_finite() && y[j].is_finite() {
                let _ = writeln!(
                    out,
                    "<circle cx=\"{}\" cy=\"{}\" r=\"1.6\"/>",
                    c(px(x[j])),
                    c(py(y[j]))
                );
            }
        }
        out.push_str("</g>\n");
        let trend: Vec<String> = binned_means(x, y)
            .iter()
            .map(|(mx, my)| format!("{},{}", c(px(*mx)), c(py(*my))))
            .collect();
        let _ = writeln!(
            out,
            "<polyline class=\"trend\" fill=\"none\" stroke=\"{}\" stroke-width=\"2\" \
             points=\"{}\"/>\n</g>",
            palette(3),
            trend.join(" ")
        );
    }
    out.push_str("</svg>\n");
    out
}

/// The range of the finite values of `v`, padded by 4 % (a unit range around a constant).
fn padded(v: &[f64]) -> (f64, f64) {
    let (lo, hi) = v
        .iter()
        .filter(|x| x.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    if lo >= hi || !lo.is_finite() || !hi.is_finite() {
        let m = if lo.is_finite() { lo } else { 0.0 };
        return (m - 0.5, m + 0.5);
    }
    let pad = 0.04 * (hi - lo);
    (lo - pad, hi + pad)
}

/// The means of `x` and `y` over the runs in each of [`bin_count`] bins of equal count along
/// `x` (the trend line).
fn binned_means(x: &[f64], y: &[f64]) -> Vec<(f64, f64)> {
    let mut pairs: Vec<(f64, f64)> = x
        .iter()
        .zip(y)
        .filter(|(a, b)| a.is_finite() && b.is_finite())
        .map(|(a, b)| (*a, *b))
        .collect();
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    let n = pairs.len();
    if n == 0 {
        return Vec::new();
    }
    let m = bin_count(n).min(n);
    (0..m)
        .filter_map(|b| {
            let chunk = &pairs[b * n / m..(b + 1) * n / m];
            let k = chunk.len() as f64;
            (k > 0.0).then(|| {
                let (sx, sy) = chunk
                    .iter()
                    .fold((0.0, 0.0), |(sx, sy), (a, b)| (sx + a, sy + b));
                (sx / k, sy / k)
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn binned_means_follow_a_linear_trend() {
        let x: Vec<f64> = (0..100).map(|i| i as f64).collect();
        let y: Vec<f64> = x.iter().map(|v| 2.0 * v + 1.0).collect();
        let m = binned_means(&x, &y);
        assert_eq!(m.len(), 10);
        for (mx, my) in m {
            assert!((my - (2.0 * mx + 1.0)).abs() < 1e-9);
        }
    }
}
