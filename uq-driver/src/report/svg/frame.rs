//! The plotting frame: the plot area in pixels, grid, axes, series, bands and legends.

use std::fmt::Write as _;

use super::axis::{Axis, TICK_CHAR_W};
use super::{paired, Band, Series};
use crate::report::escape_xml;

const TOP: f64 = 44.0;
const BOTTOM: f64 = 60.0;
const PLOT_W: f64 = 600.0;
const PLOT_H: f64 = 380.0;
/// Approximate advance of one character of 12 px sans-serif text (legend).
const TEXT_CHAR_W: f64 = 6.9;

/// Characters per line of a legend label (longer labels wrap, never cut).
const LEGEND_CHARS: usize = 34;
/// Height of one text line of a legend (px).
const LEGEND_LINE: f64 = 15.0;
/// Gap between legend entries (px).
const LEGEND_GAP: f64 = 6.0;

/// A legend entry: a line or a filled swatch with a label (wrapped into lines).
#[derive(Debug, Clone)]
pub(crate) struct LegendEntry {
    pub label: String,
    pub lines: Vec<String>,
    pub color: String,
    pub dashed: bool,
    pub filled: bool,
    /// Opacity of the swatch (a fill) or of the line, as drawn in the plot.
    pub opacity: f64,
    /// An arrow glyph instead of a line: pointing left (`Some(false)`) or right.
    pub arrow: Option<bool>,
    /// A dot on the line, as on a series with markers.
    pub marker: bool,
}

impl LegendEntry {
    pub fn line(label: &str, color: &str, dashed: bool) -> Self {
        Self {
            label: label.to_string(),
            lines: wrap(label, LEGEND_CHARS),
            color: color.to_string(),
            dashed,
            filled: false,
            opacity: 1.0,
            arrow: None,
            marker: false,
        }
    }

    /// A filled swatch, drawn with the opacity of the bars or areas it stands for.
    pub fn fill(label: &str, color: &str) -> Self {
        Self {
            filled: true,
            opacity: 0.35,
            ..Self::line(label, color, false)
        }
    }

    /// The entry of a series, drawn as the series is (dash, opacity, markers).
    pub fn of_series(s: &Series) -> Self {
        Self {
            opacity: s.opacity.unwrap_or(1.0),
            marker: s.markers,
            ..Self::line(&s.label, &s.color, s.dashed)
        }
    }

    /// The same entry with another opacity.
    pub fn with_opacity(mut self, opacity: f64) -> Self {
        self.opacity = opacity;
        self
    }

    fn height(&self) -> f64 {
        self.lines.len().max(1) as f64 * LEGEND_LINE + LEGEND_GAP
    }
}

/// `text` broken at spaces into lines of at most `max` characters (a longer word stands
/// on a line of its own).
pub(crate) fn wrap(text: &str, max: usize) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    let mut cur = String::new();
    for word in text.split(' ') {
        let len = cur.chars().count();
        if len > 0 && len + 1 + word.chars().count() > max {
            lines.push(std::mem::take(&mut cur));
        }
        if !cur.is_empty() {
            cur.push(' ');
        }
        cur.push_str(word);
    }
    if !cur.is_empty() || lines.is_empty() {
        lines.push(cur);
    }
    lines
}

/// Width of a legend block (0 without entries).
pub(crate) fn legend_width(entries: &[LegendEntry]) -> f64 {
    let chars = entries
        .iter()
        .flat_map(|e| e.lines.iter().map(|l| l.chars().count()))
        .max()
        .unwrap_or(0);
    if chars == 0 {
        0.0
    } else {
        36.0 + chars as f64 * TEXT_CHAR_W + 8.0
    }
}

/// Height of a legend block (0 without entries).
pub(crate) fn legend_height(entries: &[LegendEntry]) -> f64 {
    entries.iter().map(LegendEntry::height).sum()
}

/// Formats a pixel coordinate rounded to 0.01 (and clamped to ±1e6 px).
pub(crate) fn c(v: f64) -> String {
    let v = if v.is_finite() {
        v.clamp(-1e6, 1e6)
    } else {
        0.0
    };
    let r = (v * 100.0).round() / 100.0 + 0.0;
    format!("{r}")
}

/// The plotting frame: the plot area in pixels and its two axes.
#[derive(Debug, Clone)]
pub(crate) struct Frame {
    pub left: f64,
    pub top: f64,
    pub width: f64,
    pub height: f64,
    /// Width of the whole image.
    pub total_w: f64,
    /// Height of the whole image.
    pub total_h: f64,
    pub x: Axis,
    pub y: Axis,
    /// Room below the x tick labels before the axis label (rotated category labels).
    pub below: f64,
}

impl Frame {
    /// A frame with room for the tick labels and `right` pixels beyond the plot area.
    pub fn new(x: Axis, y: Axis, right: f64) -> Self {
        let left = (46.0 + y.label_chars() as f64 * TICK_CHAR_W).max(64.0);
        let right = right.max(0.0) + 24.0;
        Self {
            left,
            top: TOP,
            width: PLOT_W,
            height: PLOT_H,
            total_w: (left + PLOT_W + right).ceil(),
            total_h: TOP + PLOT_H + BOTTOM,
            x,
            y,
            below: 0.0,
        }
    }

    /// A frame with room for the legend `entries` right of the plot area
    /// ([`Frame::legend_outside`]), the image tall enough for them.
    pub fn with_legend(x: Axis, y: Axis, entries: &[LegendEntry]) -> Self {
        let mut frame = Self::new(x, y, legend_width(entries));
        frame.fit_legend(entries);
        frame
    }

    /// Makes the image tall enough for a legend right of the plot area.
    pub fn fit_legend(&mut self, entries: &[LegendEntry]) {
        self.total_h = self
            .total_h
            .max(self.top + 4.0 + legend_height(entries) + 12.0);
    }

    /// Adds `px` of room below the x tick labels.
    pub fn add_below(&mut self, px: f64) {
        self.below += px;
        self.total_h += px;
    }

    pub fn px(&self, x: f64) -> f64 {
        self.left + self.x.frac(x) * self.width
    }

    pub fn py(&self, y: f64) -> f64 {
        self.top + (1.0 - self.y.frac(y)) * self.height
    }

    /// Opens the `<svg>` element with a white background and the `plot-area` clip path.
    pub fn open(&self, out: &mut String) {
        let _ = writeln!(
            out,
            "<svg xmlns=\"http://www.w3.org/2000/svg\" xmlns:xlink=\"http://www.w3.org/1999/xlink\" \
             width=\"{w}\" height=\"{h}\" viewBox=\"0 0 {w} {h}\" \
             font-family=\"DejaVu Sans, Helvetica, Arial, sans-serif\" font-size=\"12\">",
            w = c(self.total_w),
            h = c(self.total_h),
        );
        let _ = writeln!(
            out,
            "<rect width=\"100%\" height=\"100%\" fill=\"#fff\"/>\n<defs><clipPath id=\"plot-area\">\
             <rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\"/></clipPath></defs>",
            c(self.left),
            c(self.top),
            c(self.width),
            c(self.height),
        );
    }

    /// Light grid lines at the major ticks.
    pub fn grid(&self, out: &mut String) {
        out.push_str("<g class=\"grid\" stroke=\"#e4e4e4\" stroke-width=\"1\">\n");
        for &t in &self.x.ticks {
            let x = self.px(t);
            let _ = writeln!(
                out,
                "<line x1=\"{0}\" y1=\"{1}\" x2=\"{0}\" y2=\"{2}\"/>",
                c(x),
                c(self.top),
                c(self.top + self.height)
            );
        }
        for &t in &self.y.ticks {
            let y = self.py(t);
            let _ = writeln!(
                out,
                "<line x1=\"{1}\" y1=\"{0}\" x2=\"{2}\" y2=\"{0}\"/>",
                c(y),
                c(self.left),
                c(self.left + self.width)
            );
        }
        out.push_str("</g>\n");
    }

    /// The frame, ticks, tick labels, axis labels and title.
    pub fn axes(&self, out: &mut String, title: &str, x_label: &str, y_label: &str) {
        let (l, t, w, h) = (self.left, self.top, self.width, self.height);
        let bottom = t + h;
        out.push_str("<g class=\"axes\" fill=\"#222\">\n");
        let _ = writeln!(
            out,
            "<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"none\" stroke=\"#333\"/>",
            c(l),
            c(t),
            c(w),
            c(h)
        );
        let mut ticks = String::new();
        for &v in &self.x.ticks {
            let x = self.px(v);
            let _ = write!(ticks, "M{} {}v5", c(x), c(bottom));
        }
        for &v in &self.y.ticks {
            let y = self.py(v);
            let _ = write!(ticks, "M{} {}h-5", c(l), c(y));
        }
        for &v in &self.x.minor {
            let _ = write!(ticks, "M{} {}v3", c(self.px(v)), c(bottom));
        }
        for &v in &self.y.minor {
            let _ = write!(ticks, "M{} {}h-3", c(l), c(self.py(v)));
        }
        let _ = writeln!(out, "<path d=\"{ticks}\" stroke=\"#333\" fill=\"none\"/>");
        out.push_str("<g font-size=\"11\" text-anchor=\"middle\">\n");
        for (&v, label) in self.x.ticks.iter().zip(&self.x.labels) {
            let _ = writeln!(
                out,
                "<text x=\"{}\" y=\"{}\">{}</text>",
                c(self.px(v)),
                c(bottom + 18.0),
                escape_xml(label)
            );
        }
        out.push_str("</g>\n<g font-size=\"11\" text-anchor=\"end\">\n");
        for (&v, label) in self.y.ticks.iter().zip(&self.y.labels) {
            let _ = writeln!(
                out,
                "<text x=\"{}\" y=\"{}\">{}</text>",
                c(l - 8.0),
                c(self.py(v) + 4.0),
                escape_xml(label)
            );
        }
        out.push_str("</g>\n");
        let _ = writeln!(
            out,
            "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\" font-size=\"13\">{}</text>",
            c(l + w / 2.0),
            c(bottom + 44.0 + self.below),
            escape_xml(x_label)
        );
        let (yx, yy) = (16.0, t + h / 2.0);
        let _ = writeln!(
            out,
            "<text x=\"{0}\" y=\"{1}\" text-anchor=\"middle\" font-size=\"13\" \
             transform=\"rotate(-90 {0} {1})\">{2}</text>",
            c(yx),
            c(yy),
            escape_xml(y_label)
        );
        // A long title is set smaller so that it fits the image, never cut.
        let chars = title.chars().count().max(1) as f64;
        let size = (15.0f64)
            .min((self.total_w - 16.0) / (0.62 * chars))
            .max(8.0);
        let centre = (l + w / 2.0)
            .max(8.0 + 0.31 * size * chars)
            .min(self.total_w - 8.0 - 0.31 * size * chars);
        let _ = writeln!(
            out,
            "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\" font-size=\"{}\" \
             font-weight=\"bold\">{}</text>",
            c(centre),
            c(t - 16.0),
            c(size),
            escape_xml(title)
        );
        out.push_str("</g>\n");
    }

    /// A line as one `<path>`; non-finite points start a new sub-path.
    pub fn series(&self, out: &mut String, s: &Series) {
        let mut d = String::new();
        let mut run: Vec<(f64, f64)> = Vec::new();
        for (x, y) in paired(&s.x, &s.y) {
            if self.x.accepts(x) && self.y.accepts(y) {
                run.push((self.px(x), self.py(y)));
            } else {
                push_run(&mut d, &run);
                run.clear();
            }
        }
        push_run(&mut d, &run);
        let dash = if s.dashed {
            " stroke-dasharray=\"7 4\""
        } else {
            ""
        };
        let opacity = match s.opacity {
            Some(o) => format!(" stroke-opacity=\"{o}\""),
            None => String::new(),
        };
        let _ = writeln!(
            out,
            "<path d=\"{d}\" fill=\"none\" stroke=\"{}\" stroke-width=\"{}\" \
             stroke-linejoin=\"round\" stroke-linecap=\"round\"{dash}{opacity}/>",
            escape_xml(&s.color),
            s.width.unwrap_or(1.8)
        );
        if s.markers {
            for (x, y) in paired(&s.x, &s.y) {
                if self.x.accepts(x) && self.y.accepts(y) {
                    let _ = writeln!(
                        out,
                        "<circle cx=\"{}\" cy=\"{}\" r=\"3.2\" fill=\"{}\"/>",
                        c(self.px(x)),
                        c(self.py(y)),
                        escape_xml(&s.color)
                    );
                }
            }
        }
    }

    /// A band as one `<path>` of closed polygons, one per run of finite points.
    pub fn band(&self, out: &mut String, b: &Band) {
        let mut d = String::new();
        let mut run: Vec<(f64, f64, f64)> = Vec::new();
        let flush = |d: &mut String, run: &mut Vec<(f64, f64, f64)>| {
            if run.len() >= 2 {
                let upper: Vec<(f64, f64)> = run.iter().map(|p| (p.0, p.2)).collect();
                let lower: Vec<(f64, f64)> = run.iter().rev().map(|p| (p.0, p.1)).collect();
                push_run(d, &upper);
                // Continue along the lower edge backwards, then close.
                let mut rest = String::new();
                push_run(&mut rest, &lower);
                d.push_str(&rest.replacen('M', "L", 1));
                d.push('Z');
            }
            run.clear();
        };
        let n = b.x.len().min(b.lower.len()).min(b.upper.len());
        for i in 0..n {
            let (x, lo, hi) = (b.x[i], b.lower[i], b.upper[i]);
            if self.x.accepts(x) && self.y.accepts(lo) && self.y.accepts(hi) {
                run.push((self.px(x), self.py(lo), self.py(hi)));
            } else {
                flush(&mut d, &mut run);
            }
        }
        flush(&mut d, &mut run);
        let _ = writeln!(
            out,
            "<path d=\"{d}\" fill=\"{}\" fill-opacity=\"{}\" stroke=\"none\"/>",
            escape_xml(&b.color),
            b.opacity
        );
    }

    /// The legend to the right of the plot area.
    pub fn legend_outside(&self, out: &mut String, entries: &[LegendEntry]) {
        legend(
            out,
            entries,
            self.left + self.width + 16.0,
            self.top + 4.0,
            false,
        );
    }

    /// The `<svg>` element opened ([`Frame::open`]) and the grid drawn ([`Frame::grid`]).
    pub fn open_with_grid(&self) -> String {
        let mut out = String::new();
        self.open(&mut out);
        self.grid(&mut out);
        out
    }

    /// The legend `entries` drawn right of the plot area and the `<svg>` element closed.
    pub fn close_with_legend(&self, out: &mut String, entries: &[LegendEntry]) {
        self.legend_outside(out, entries);
        out.push_str("</svg>\n");
    }
}

/// Draws legend entries starting at (x, y); `boxed` adds a translucent white background.
/// A horizontal arrow at height `y` from `tail` to `tip` (`dir` = +1 pointing right, −1 left),
/// its head filled: the mark of a limit beyond the plotted range, and its legend glyph.
pub(crate) fn arrow(out: &mut String, tail: f64, tip: f64, dir: f64, y: f64, color: &str) {
    let _ = writeln!(
        out,
        "<path d=\"M{} {}L{} {}M{} {}L{} {}L{} {}Z\" stroke=\"{color}\" fill=\"{color}\" \
         stroke-width=\"1.5\"/>",
        c(tail),
        c(y),
        c(tip - dir * 6.0),
        c(y),
        c(tip),
        c(y),
        c(tip - dir * 7.0),
        c(y - 4.0),
        c(tip - dir * 7.0),
        c(y + 4.0),
    );
}

pub(crate) fn legend(out: &mut String, entries: &[LegendEntry], x: f64, y: f64, boxed: bool) {
    if entries.is_empty() {
        return;
    }
    out.push_str("<g class=\"legend\">\n");
    if boxed {
        let _ = writeln!(
            out,
            "<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"#fff\" fill-opacity=\"0.85\" \
             stroke=\"#bbb\" rx=\"3\"/>",
            c(x - 6.0),
            c(y - 4.0),
            c(legend_width(entries)),
            c(legend_height(entries) + 6.0)
        );
    }
    let mut top = y;
    for e in entries {
        let cy = top + 10.0;
        let color = escape_xml(&e.color);
        if e.filled {
            let _ = writeln!(
                out,
                "<rect x=\"{}\" y=\"{}\" width=\"24\" height=\"12\" fill=\"{color}\" \
                 fill-opacity=\"{}\" stroke=\"{color}\" stroke-width=\"0.8\"/>",
                c(x),
                c(cy - 6.0),
                e.opacity
            );
        } else if let Some(right) = e.arrow {
            // The glyph of a marker beyond the plotted range: an arrow towards that side.
            let (tail, tip, dir) = if right {
                (x, x + 24.0, 1.0)
            } else {
                (x + 24.0, x, -1.0)
            };
            arrow(out, tail, tip, dir, cy, &color);
        } else {
            let dash = if e.dashed {
                " stroke-dasharray=\"7 4\""
            } else {
                ""
            };
            if is_light(&e.color) {
                // A white line (drawn over a heat map) needs a dark ground to be seen.
                let _ = writeln!(
                    out,
                    "<rect x=\"{}\" y=\"{}\" width=\"28\" height=\"10\" fill=\"#440154\"/>",
                    c(x - 2.0),
                    c(cy - 5.0)
                );
            }
            let opacity = if e.opacity < 1.0 {
                format!(" stroke-opacity=\"{}\"", e.opacity)
            } else {
                String::new()
            };
            let _ = writeln!(
                out,
                "<path d=\"M{} {}h24\" stroke=\"{color}\" stroke-width=\"2\"{dash}{opacity}/>",
                c(x),
                c(cy)
            );
            if e.marker {
                let _ = writeln!(
                    out,
                    "<circle cx=\"{}\" cy=\"{}\" r=\"3.2\" fill=\"{color}\"/>",
                    c(x + 12.0),
                    c(cy)
                );
            }
        }
        for (i, line) in e.lines.iter().enumerate() {
            let _ = writeln!(
                out,
                "<text x=\"{}\" y=\"{}\">{}</text>",
                c(x + 30.0),
                c(cy + 4.0 + LEGEND_LINE * i as f64),
                escape_xml(line)
            );
        }
        top += e.height();
    }
    out.push_str("</g>\n");
}

/// Whether a `#rrggbb` colour is too light to be seen on white.
fn is_light(color: &str) -> bool {
    let hex = color.trim_start_matches('#');
    if hex.len() != 6 {
        return color.eq_ignore_ascii_case("white");
    }
    let v = |i: usize| u8::from_str_radix(&hex[i..i + 2], 16).unwrap_or(0) as u32;
    v(0) + v(2) + v(4) > 3 * 0xe8
}

/// Appends one sub-path through the pixel points, dropping sub-pixel steps (the last point
/// is always kept; a single point becomes a dot via the round line cap).
fn push_run(d: &mut String, run: &[(f64, f64)]) {
    let Some(&(x0, y0)) = run.first() else {
        return;
    };
    let _ = write!(d, "M{} {}", c(x0), c(y0));
    if run.len() == 1 {
        d.push_str("h0");
        return;
    }
    let mut last = (x0, y0);
    for (i, &(x, y)) in run.iter().enumerate().skip(1) {
        let is_last = i + 1 == run.len();
        if !is_last && (x - last.0).abs() < 0.3 && (y - last.1).abs() < 0.3 {
            continue;
        }
        let _ = write!(d, "L{} {}", c(x), c(y));
        last = (x, y);
    }
}
