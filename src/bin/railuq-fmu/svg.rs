//! Plain SVG line plots: a grid of panels, each with axes, ticks and labelled curves.

use std::fmt::Write;

/// One curve: its legend, colour and points (x, y).
pub struct Curve {
    /// Legend text.
    pub label: String,
    /// SVG colour.
    pub color: &'static str,
    /// Points, in drawing order.
    pub points: Vec<(f64, f64)>,
}

/// One panel: title, axis labels and curves.
pub struct Panel {
    /// Title above the panel.
    pub title: String,
    /// Label of the x axis.
    pub x_label: String,
    /// Label of the y axis.
    pub y_label: String,
    /// The curves.
    pub curves: Vec<Curve>,
}

const PANEL_W: f64 = 460.0;
const PANEL_H: f64 = 330.0;
const LEFT: f64 = 70.0;
const RIGHT: f64 = 20.0;
const TOP: f64 = 40.0;
const BOTTOM: f64 = 50.0;

/// Tick positions covering [lo, hi] with a 1-2-5 step, about 5 to 8 of them.
fn ticks(lo: f64, hi: f64) -> Vec<f64> {
    let span = (hi - lo).max(1e-300);
    let raw = span / 8.0;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * mag);
    let first = (lo / step).ceil() as i64;
    let last = (hi / step).floor() as i64;
    (first..=last).map(|k| k as f64 * step).collect()
}

/// A number for a tick label: no trailing zeros, no "-0".
fn label(v: f64) -> String {
    let s = format!("{:.6}", v);
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".to_owned()
    } else {
        s.to_owned()
    }
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// The panels laid out `columns` to a row, with an overall `title`.
pub fn render(title: &str, panels: &[Panel], columns: usize) -> String {
    let columns = columns.max(1);
    let rows = panels.len().div_ceil(columns);
    let (w, h) = (PANEL_W * columns as f64, PANEL_H * rows as f64 + 30.0);
    let mut out = String::new();
    let _ = writeln!(
        out,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" font-family="sans-serif" font-size="12">"#
    );
    let _ = writeln!(out, r#"<rect width="{w}" height="{h}" fill="white"/>"#);
    let _ = writeln!(
        out,
        r#"<text x="{}" y="20" text-anchor="middle" font-size="15">{}</text>"#,
        w / 2.0,
        escape(title)
    );
    for (k, p) in panels.iter().enumerate() {
        let ox = PANEL_W * (k % columns) as f64;
        let oy = 30.0 + PANEL_H * (k / columns) as f64;
        panel(&mut out, p, ox, oy);
    }
    out.push_str("</svg>\n");
    out
}

fn panel(out: &mut String, p: &Panel, ox: f64, oy: f64) {
    let pts = p.curves.iter().flat_map(|c| c.points.iter());
    let finite: Vec<(f64, f64)> = pts
        .copied()
        .filter(|(x, y)| x.is_finite() && y.is_finite())
        .collect();
    let fold = |f: fn(&(f64, f64)) -> f64| {
        finite
            .iter()
            .map(f)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                (a.min(v), b.max(v))
            })
    };
    let (mut x0, mut x1) = fold(|p| p.0);
    let (mut y0, mut y1) = fold(|p| p.1);
    if finite.is_empty() {
        (x0, x1, y0, y1) = (0.0, 1.0, 0.0, 1.0);
    }
    if x0.is_nan() || x0 >= x1 {
        (x0, x1) = (x0 - 1.0, x0 + 1.0);
    }
    if y0.is_nan() || y0 >= y1 {
        (y0, y1) = (y0 - 1.0, y0 + 1.0);
    }
    let pad = 0.05 * (y1 - y0);
    (y0, y1) = (y0 - pad, y1 + pad);
    let (px0, px1) = (ox + LEFT, ox + PANEL_W - RIGHT);
    let (py0, py1) = (oy + PANEL_H - BOTTOM, oy + TOP);
    let sx = |x: f64| px0 + (x - x0) / (x1 - x0) * (px1 - px0);
    let sy = |y: f64| py0 + (y - y0) / (y1 - y0) * (py1 - py0);
    let _ = writeln!(
        out,
        r#"<text x="{}" y="{}" text-anchor="middle" font-size="13">{}</text>"#,
        (px0 + px1) / 2.0,
        oy + TOP - 12.0,
        escape(&p.title)
    );
    for t in ticks(x0, x1) {
        let x = sx(t);
        let _ = writeln!(
            out,
            r##"<line x1="{x:.1}" y1="{py0:.1}" x2="{x:.1}" y2="{py1:.1}" stroke="#e4e4e4"/><text x="{x:.1}" y="{:.1}" text-anchor="middle">{}</text>"##,
            py0 + 15.0,
            label(t)
        );
    }
    for t in ticks(y0, y1) {
        let y = sy(t);
        let _ = writeln!(
            out,
            r##"<line x1="{px0:.1}" y1="{y:.1}" x2="{px1:.1}" y2="{y:.1}" stroke="#e4e4e4"/><text x="{:.1}" y="{:.1}" text-anchor="end">{}</text>"##,
            px0 - 5.0,
            y + 4.0,
            label(t)
        );
    }
    let _ = writeln!(
        out,
        r#"<rect x="{px0:.1}" y="{py1:.1}" width="{:.1}" height="{:.1}" fill="none" stroke="black"/>"#,
        px1 - px0,
        py0 - py1
    );
    let _ = writeln!(
        out,
        r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">{}</text>"#,
        (px0 + px1) / 2.0,
        py0 + 35.0,
        escape(&p.x_label)
    );
    let (lx, ly) = (ox + 18.0, (py0 + py1) / 2.0);
    let _ = writeln!(
        out,
        r#"<text x="{lx:.1}" y="{ly:.1}" text-anchor="middle" transform="rotate(-90 {lx:.1} {ly:.1})">{}</text>"#,
        escape(&p.y_label)
    );
    for (k, c) in p.curves.iter().enumerate() {
        let path: Vec<String> = c
            .points
            .iter()
            .filter(|(x, y)| x.is_finite() && y.is_finite())
            .map(|&(x, y)| format!("{:.2},{:.2}", sx(x), sy(y)))
            .collect();
        let _ = writeln!(
            out,
            r#"<polyline fill="none" stroke="{}" stroke-width="1.4" points="{}"/>"#,
            c.color,
            path.join(" ")
        );
        let ty = py1 + 14.0 + 14.0 * k as f64;
        let _ = writeln!(
            out,
            r#"<line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="{}" stroke-width="2"/><text x="{:.1}" y="{:.1}">{}</text>"#,
            px0 + 8.0,
            ty - 4.0,
            px0 + 24.0,
            ty - 4.0,
            c.color,
            px0 + 28.0,
            ty,
            escape(&c.label)
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_cover_the_range_with_round_steps() {
        let t = ticks(0.0, 1.0);
        assert_eq!(t.len(), 6);
        assert!(t
            .iter()
            .enumerate()
            .all(|(k, v)| (v - 0.2 * k as f64).abs() < 1e-12));
        assert_eq!(
            ticks(-17.0, 17.0),
            vec![-15.0, -10.0, -5.0, 0.0, 5.0, 10.0, 15.0]
        );
        assert_eq!(label(-0.0), "0");
        assert_eq!(label(2.5), "2.5");
    }

    #[test]
    fn a_plot_is_one_svg_with_a_polyline_per_curve() {
        let p = Panel {
            title: "a < b".into(),
            x_label: "x".into(),
            y_label: "y".into(),
            curves: vec![Curve {
                label: "c".into(),
                color: "red",
                points: vec![(0.0, 1.0), (1.0, 2.0), (2.0, f64::NAN)],
            }],
        };
        let s = render("t", &[p], 2);
        assert!(s.starts_with("<svg") && s.ends_with("</svg>\n"));
        assert_eq!(s.matches("<polyline").count(), 1);
        assert!(s.contains("a &lt; b") && !s.contains("NaN"));
        let empty = Panel {
            title: "none".into(),
            x_label: "x".into(),
            y_label: "y".into(),
            curves: vec![],
        };
        let s = render("t", &[empty], 1);
        assert!(!s.contains("NaN") && !s.contains("inf"), "{s}");
    }
}
