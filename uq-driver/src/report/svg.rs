//! Hand-written SVG plots: line plots with filled bands, and density plots with histograms.
//!
//! The SVG needs no fonts or scripts: axes with 1-2-5 ticks ([`nice_ticks`]), tick labels, axis
//! labels, a title and a legend. Axis ranges are taken from the finite data; non-finite points
//! (and non-positive values on a log axis) are skipped and break the line. Coordinates are
//! rounded to 0.01 px and sub-pixel steps are dropped, so files stay small.
//!
//! The frame, axis and legend helpers are shared with [`super::heatmap`].

use std::fmt::Write as _;
use std::path::Path;

use super::{escape_xml, write_bytes, ReportError};

/// A line in a plot: `y` against `x` (points are paired by index; the shorter length wins).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Series {
    /// Legend text; empty for no legend entry.
    pub label: String,
    /// Abscissae.
    pub x: Vec<f64>,
    /// Ordinates; non-finite values break the line.
    pub y: Vec<f64>,
    /// Any SVG color, e.g. `#1f77b4` (see [`palette`]).
    pub color: String,
    /// Draw dashed instead of solid.
    pub dashed: bool,
}

impl Series {
    /// A solid line.
    pub fn new(
        label: impl Into<String>,
        x: Vec<f64>,
        y: Vec<f64>,
        color: impl Into<String>,
    ) -> Self {
        Self {
            label: label.into(),
            x,
            y,
            color: color.into(),
            dashed: false,
        }
    }

    /// The same line, dashed.
    pub fn dashed(mut self) -> Self {
        self.dashed = true;
        self
    }
}

/// A filled region between `lower` and `upper` over `x` (e.g. mean ± 3σ).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Band {
    /// Legend text; empty for no legend entry.
    pub label: String,
    /// Abscissae.
    pub x: Vec<f64>,
    /// Lower edge; a non-finite value (in either edge) splits the band.
    pub lower: Vec<f64>,
    /// Upper edge.
    pub upper: Vec<f64>,
    /// Fill color, drawn with opacity 0.25.
    pub color: String,
}

impl Band {
    /// A band between `lower` and `upper`.
    pub fn new(
        label: impl Into<String>,
        x: Vec<f64>,
        lower: Vec<f64>,
        upper: Vec<f64>,
        color: impl Into<String>,
    ) -> Self {
        Self {
            label: label.into(),
            x,
            lower,
            upper,
            color: color.into(),
        }
    }
}

/// A plot of lines over filled bands, e.g. mean ± 3σ of q(t), or a difference SGM − LHS.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LinePlot {
    /// Title above the plot.
    pub title: String,
    /// Label of the horizontal axis, with unit, e.g. `time [s]`.
    pub x_label: String,
    /// Label of the vertical axis, with unit.
    pub y_label: String,
    /// Lines, drawn on top of the bands in order.
    pub series: Vec<Series>,
    /// Filled bands, drawn first.
    pub bands: Vec<Band>,
    /// Logarithmic vertical axis (non-positive values are skipped).
    pub log_y: bool,
}

impl LinePlot {
    /// An empty plot with the given title and axis labels.
    pub fn new(
        title: impl Into<String>,
        x_label: impl Into<String>,
        y_label: impl Into<String>,
    ) -> Self {
        Self {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            ..Self::default()
        }
    }

    /// Renders the plot as an SVG document.
    pub fn to_svg(&self) -> String {
        let log = self.log_y;
        let xs = self
            .series
            .iter()
            .flat_map(|s| paired(&s.x, &s.y).map(|(x, _)| x))
            .chain(self.bands.iter().flat_map(|b| b.x.iter().copied()));
        let ys = self
            .series
            .iter()
            .flat_map(|s| paired(&s.x, &s.y).map(|(_, y)| y))
            .chain(
                self.bands
                    .iter()
                    .flat_map(|b| b.lower.iter().chain(&b.upper).copied()),
            );
        let x_axis = Axis::linear_exact(finite_range(xs, false));
        let y_axis = if log {
            Axis::log(finite_range(ys, true), true)
        } else {
            Axis::linear_padded(finite_range(ys, false))
        };

        let mut legend: Vec<LegendEntry> = Vec::new();
        for b in &self.bands {
            legend.push(LegendEntry::fill(&b.label, &b.color));
        }
        for s in &self.series {
            legend.push(LegendEntry::line(&s.label, &s.color, s.dashed));
        }
        legend.retain(|e| !e.label.is_empty());

        let frame = Frame::new(x_axis, y_axis, legend_width(&legend));
        let mut out = String::new();
        frame.open(&mut out);
        frame.grid(&mut out);
        out.push_str("<g class=\"bands\" clip-path=\"url(#plot-area)\">\n");
        for b in &self.bands {
            frame.band(&mut out, b);
        }
        out.push_str("</g>\n<g class=\"series\" clip-path=\"url(#plot-area)\">\n");
        for s in &self.series {
            frame.series(&mut out, s);
        }
        out.push_str("</g>\n");
        frame.axes(&mut out, &self.title, &self.x_label, &self.y_label);
        frame.legend_outside(&mut out, &legend);
        out.push_str("</svg>\n");
        out
    }

    /// Writes [`Self::to_svg`] to `path`.
    pub fn write(&self, path: &Path) -> Result<(), ReportError> {
        write_bytes(path, self.to_svg().as_bytes())
    }
}

/// A plot of probability densities of a scalar quantity (e.g. critical speed, Sperling index):
/// PDF curves, optionally over a histogram of samples, with vertical marker lines for limits.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct DensityPlot {
    /// Title above the plot.
    pub title: String,
    /// Label of the horizontal axis (the quantity, with unit); the vertical axis is
    /// "probability density".
    pub x_label: String,
    /// PDF curves (e.g. kernel density estimates, one per method).
    pub curves: Vec<Series>,
    /// A histogram as (bin edges, density per bin), `edges.len() == density.len() + 1`;
    /// see [`histogram_density`]. Extra entries of either are ignored.
    pub histogram: Option<(Vec<f64>, Vec<f64>)>,
    /// Vertical marker lines at x with a label, e.g. `(2.5, "limit W = 2.5")`.
    pub markers: Vec<(f64, String)>,
}

impl DensityPlot {
    /// Renders the plot as an SVG document.
    pub fn to_svg(&self) -> String {
        let (edges, dens): (&[f64], &[f64]) = match &self.histogram {
            Some((e, d)) => (e, d),
            None => (&[], &[]),
        };
        let bins = edges.len().saturating_sub(1).min(dens.len());
        let bars = (0..bins).filter_map(|i| {
            let (l, r, h) = (edges[i], edges[i + 1], dens[i]);
            (l.is_finite() && r.is_finite() && h.is_finite()).then_some((l, r, h))
        });

        let xs = self
            .curves
            .iter()
            .flat_map(|s| paired(&s.x, &s.y).map(|(x, _)| x))
            .chain(bars.clone().flat_map(|(l, r, _)| [l, r]))
            .chain(self.markers.iter().map(|m| m.0));
        let ys = self
            .curves
            .iter()
            .flat_map(|s| paired(&s.x, &s.y).map(|(_, y)| y))
            .chain(bars.clone().map(|b| b.2))
            .chain([0.0]);
        let x_axis = Axis::linear_exact(finite_range(xs, false));
        let y_axis = Axis::linear_padded(finite_range(ys, false));

        let mut legend: Vec<LegendEntry> = Vec::new();
        if self.histogram.is_some() {
            legend.push(LegendEntry::fill("histogram", HISTOGRAM_COLOR));
        }
        for s in &self.curves {
            legend.push(LegendEntry::line(&s.label, &s.color, s.dashed));
        }
        for (i, (_, label)) in self.markers.iter().enumerate() {
            legend.push(LegendEntry::line(label, marker_color(i), true));
        }
        legend.retain(|e| !e.label.is_empty());

        let frame = Frame::new(x_axis, y_axis, legend_width(&legend));
        let mut out = String::new();
        frame.open(&mut out);
        frame.grid(&mut out);
        out.push_str("<g class=\"histogram\" clip-path=\"url(#plot-area)\">\n");
        let y0 = frame.py(0.0);
        for (l, r, h) in bars {
            let (xl, xr) = (frame.px(l.min(r)), frame.px(l.max(r)));
            let yt = frame.py(h.max(0.0));
            let _ = writeln!(
                out,
                "<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"{HISTOGRAM_COLOR}\" \
                 fill-opacity=\"0.55\" stroke=\"#fff\" stroke-width=\"0.5\"/>",
                c(xl),
                c(yt.min(y0)),
                c(xr - xl),
                c((y0 - yt).abs()),
            );
        }
        out.push_str("</g>\n<g class=\"series\" clip-path=\"url(#plot-area)\">\n");
        for s in &self.curves {
            frame.series(&mut out, s);
        }
        out.push_str("</g>\n<g class=\"markers\">\n");
        for (i, (x, label)) in self.markers.iter().enumerate() {
            if !x.is_finite() {
                continue;
            }
            let px = frame.px(*x);
            let color = marker_color(i);
            let _ = writeln!(
                out,
                "<line x1=\"{0}\" y1=\"{1}\" x2=\"{0}\" y2=\"{2}\" stroke=\"{color}\" \
                 stroke-width=\"1.5\" stroke-dasharray=\"6 4\"/>",
                c(px),
                c(frame.top),
                c(frame.top + frame.height),
            );
            let _ = writeln!(
                out,
                "<text x=\"{}\" y=\"{}\" fill=\"{color}\" font-size=\"11\">{}</text>",
                c(px + 4.0),
                c(frame.top + 14.0 + 14.0 * (i % 3) as f64),
                escape_xml(&truncate(label, 40)),
            );
        }
        out.push_str("</g>\n");
        frame.axes(&mut out, &self.title, &self.x_label, "probability density");
        frame.legend_outside(&mut out, &legend);
        out.push_str("</svg>\n");
        out
    }

    /// Writes [`Self::to_svg`] to `path`.
    pub fn write(&self, path: &Path) -> Result<(), ReportError> {
        write_bytes(path, self.to_svg().as_bytes())
    }
}

/// A histogram of the finite `samples` as (bin edges, density per bin), normalized so that
/// the bars integrate to 1. `bins == 0` chooses the number of bins by Sturges' rule.
/// No finite samples give empty vectors; equal samples get one unit-wide range around them.
pub fn histogram_density(samples: &[f64], bins: usize) -> (Vec<f64>, Vec<f64>) {
    let finite: Vec<f64> = samples.iter().copied().filter(|v| v.is_finite()).collect();
    if finite.is_empty() {
        return (Vec::new(), Vec::new());
    }
    let n = finite.len();
    let bins = if bins == 0 {
        // Sturges: ceil(log2 n) + 1.
        (usize::BITS - (n - 1).leading_zeros()) as usize + 1
    } else {
        bins
    };
    let (mut lo, mut hi) = finite
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    if hi - lo <= 0.0 || !(hi - lo).is_finite() {
        if hi - lo <= 0.0 {
            lo -= 0.5;
            hi += 0.5;
        } else {
            // Range overflows f64: clamp to a representable span.
            lo = lo.max(-f64::MAX / 2.0);
            hi = hi.min(f64::MAX / 2.0);
        }
    }
    let width = (hi - lo) / bins as f64;
    let edges: Vec<f64> = (0..=bins)
        .map(|i| if i == bins { hi } else { lo + width * i as f64 })
        .collect();
    let mut counts = vec![0usize; bins];
    for v in finite {
        let k = (((v - lo) / width).floor().max(0.0) as usize).min(bins - 1);
        counts[k] += 1;
    }
    let density = counts
        .iter()
        .map(|&k| k as f64 / (n as f64 * width))
        .collect();
    (edges, density)
}

/// Tick positions with a 1-2-5 step covering `[lo, hi]` with at most `max_intervals`
/// intervals (at least 1), e.g. `(0, 5, 6)` → 0, 1, …, 5 and `(0, 0.1, 6)` → 0, 0.02, …, 0.1.
/// Ticks are the nearest doubles to the decimal values. Non-finite bounds or a zero-width
/// range give the bounds themselves (deduplicated, finite only).
pub fn nice_ticks(lo: f64, hi: f64, max_intervals: usize) -> Vec<f64> {
    nice_step(lo, hi, max_intervals)
        .map(|s| s.ticks(lo.min(hi), lo.max(hi)))
        .unwrap_or_else(|| {
            let mut v: Vec<f64> = [lo.min(hi), lo.max(hi)]
                .into_iter()
                .filter(|v| v.is_finite())
                .collect();
            v.dedup();
            v
        })
}

/// Color `i` of a ten-color qualitative palette (matplotlib's tab10), cycling.
pub fn palette(i: usize) -> &'static str {
    const TAB10: [&str; 10] = [
        "#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f",
        "#bcbd22", "#17becf",
    ];
    TAB10[i % TAB10.len()]
}

const HISTOGRAM_COLOR: &str = "#8c9db5";
const TOP: f64 = 44.0;
const BOTTOM: f64 = 60.0;
const PLOT_W: f64 = 600.0;
const PLOT_H: f64 = 380.0;
/// Approximate advance of one character of 11 px sans-serif text (tick labels).
const TICK_CHAR_W: f64 = 6.4;
/// Approximate advance of one character of 12 px sans-serif text (legend).
const TEXT_CHAR_W: f64 = 6.9;
/// Values beyond this magnitude are clamped when choosing axis ranges.
const HUGE: f64 = 1e300;
/// Most intervals between major ticks on a plot axis (5–8 ticks in practice).
const AXIS_INTERVALS: usize = 8;

fn marker_color(i: usize) -> &'static str {
    ["#d62728", "#222222", "#9467bd"][i % 3]
}

/// Points of `x` and `y` paired by index (the shorter length wins).
fn paired<'a>(x: &'a [f64], y: &'a [f64]) -> impl Iterator<Item = (f64, f64)> + Clone + 'a {
    x.iter().copied().zip(y.iter().copied())
}

/// (min, max) of the finite values (positive only if `positive`), clamped to ±1e300.
pub(crate) fn finite_range(
    values: impl IntoIterator<Item = f64>,
    positive: bool,
) -> Option<(f64, f64)> {
    values
        .into_iter()
        .filter(|v| v.is_finite() && (!positive || *v > 0.0))
        .map(|v| v.clamp(-HUGE, HUGE))
        .fold(None, |acc, v| match acc {
            None => Some((v, v)),
            Some((a, b)) => Some((v.min(a), v.max(b))),
        })
}

/// Widens an empty or zero-width linear range to something drawable.
fn widen_linear(range: Option<(f64, f64)>) -> (f64, f64) {
    match range {
        None => (0.0, 1.0),
        Some((lo, hi)) if hi - lo <= lo.abs().max(hi.abs()) * 1e-12 => {
            let h = if lo == 0.0 { 1.0 } else { lo.abs() * 0.1 };
            (lo - h, hi + h)
        }
        Some(r) => r,
    }
}

/// A 1-2-5 step `mantissa × 10^exp`.
#[derive(Debug, Clone, Copy)]
struct Step {
    mantissa: f64,
    exp: i32,
}

impl Step {
    fn value(self) -> f64 {
        scale10(self.mantissa, self.exp)
    }

    /// Multiples of the step within `[lo, hi]` (with a small tolerance).
    fn ticks(self, lo: f64, hi: f64) -> Vec<f64> {
        let step = self.value();
        let eps = 1e-9;
        let k0 = (lo / step - eps).ceil();
        let k1 = (hi / step + eps).floor();
        if !(k0.is_finite() && k1.is_finite()) || k1 < k0 || k1 - k0 > 1000.0 {
            return Vec::new();
        }
        let mut out = Vec::new();
        let mut k = k0;
        while k <= k1 {
            // k × mantissa is an exact small integer; one scaling by 10^exp rounds once.
            out.push(scale10(k * self.mantissa, self.exp) + 0.0);
            k += 1.0;
        }
        out
    }

    /// Decimal places needed to print multiples of this step.
    fn decimals(self) -> usize {
        if self.exp >= 0 {
            0
        } else {
            (-self.exp) as usize
        }
    }
}

/// `m × 10^e`, rounded once when `|e| <= 22` (powers of ten up to 1e22 are exact).
fn scale10(m: f64, e: i32) -> f64 {
    if (0..=22).contains(&e) {
        m * 10f64.powi(e)
    } else if (-22..0).contains(&e) {
        m / 10f64.powi(-e)
    } else {
        m * 10f64.powi(e)
    }
}

fn nice_step(lo: f64, hi: f64, max_intervals: usize) -> Option<Step> {
    let range = (hi - lo).abs();
    if !range.is_finite() || range <= 0.0 {
        return None;
    }
    let raw = range / max_intervals.max(1) as f64;
    let mut exp = raw.log10().floor() as i32;
    let norm = raw / 10f64.powi(exp);
    let mantissa = if norm <= 1.0 + 1e-9 {
        1.0
    } else if norm <= 2.0 + 1e-9 {
        2.0
    } else if norm <= 5.0 + 1e-9 {
        5.0
    } else {
        exp += 1;
        1.0
    };
    Some(Step { mantissa, exp })
}

/// One axis of a plot: a data range mapped to a pixel range, with labelled major ticks.
#[derive(Debug, Clone)]
pub(crate) struct Axis {
    pub lo: f64,
    pub hi: f64,
    pub log: bool,
    pub ticks: Vec<f64>,
    pub labels: Vec<String>,
    /// Unlabelled minor ticks (log axes).
    pub minor: Vec<f64>,
}

impl Axis {
    /// A linear axis over exactly the data range.
    pub fn linear_exact(range: Option<(f64, f64)>) -> Self {
        let (lo, hi) = widen_linear(range);
        Self::linear(lo, hi)
    }

    /// A linear axis over the data range padded by 5 % at each end (a bound at 0 stays).
    pub fn linear_padded(range: Option<(f64, f64)>) -> Self {
        let (lo, hi) = widen_linear(range);
        let pad = 0.05 * (hi - lo);
        let lo = if lo == 0.0 { lo } else { lo - pad };
        let hi = if hi == 0.0 { hi } else { hi + pad };
        Self::linear(lo, hi)
    }

    fn linear(lo: f64, hi: f64) -> Self {
        let step = nice_step(lo, hi, AXIS_INTERVALS);
        let ticks = step.map(|s| s.ticks(lo, hi)).unwrap_or_default();
        let labels = match step {
            Some(s) => format_linear_labels(&ticks, s),
            None => Vec::new(),
        };
        Self {
            lo,
            hi,
            log: false,
            ticks,
            labels,
            minor: Vec::new(),
        }
    }

    /// A log10 axis over a positive range; `extend` widens it to whole decades.
    pub fn log(range: Option<(f64, f64)>, extend: bool) -> Self {
        let (mut lo, mut hi) = range.unwrap_or((1.0, 10.0));
        if !(lo > 0.0 && hi > 0.0) {
            (lo, hi) = (1.0, 10.0);
        }
        if hi / lo < 1.0 + 1e-9 {
            (lo, hi) = (lo / 10.0, hi * 10.0);
        }
        let (e0, e1) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
        if extend {
            lo = scale10(1.0, e0);
            hi = scale10(1.0, e1);
        }
        let decades = (e1 - e0).max(1);
        let every = (decades + 7) / 8;
        // Plain decimals if every decade label is short, else 1eN for all.
        let plain = e0 >= -4 && e1 <= 5;
        let in_range = |v: f64| v >= lo * (1.0 - 1e-9) && v <= hi * (1.0 + 1e-9);
        let mut ticks = Vec::new();
        let mut labels = Vec::new();
        let mut minor = Vec::new();
        for e in e0..=e1 {
            let v = scale10(1.0, e);
            if (e - e0) % every == 0 && in_range(v) {
                ticks.push(v);
                labels.push(if plain {
                    format!("{v}")
                } else {
                    format!("1e{e}")
                });
            }
            if decades <= 6 {
                minor.extend((2..10).map(|m| m as f64 * v).filter(|&m| in_range(m)));
            }
        }
        if ticks.len() < 2 {
            // Less than a decade: linear 1-2-5 ticks placed on the log scale.
            let lin = Self::linear(lo, hi);
            for (t, l) in lin.ticks.into_iter().zip(lin.labels) {
                if t > 0.0 && !ticks.contains(&t) {
                    ticks.push(t);
                    labels.push(l);
                }
            }
            minor.clear();
        }
        Self {
            lo,
            hi,
            log: true,
            ticks,
            labels,
            minor,
        }
    }

    /// Position of `v` on the axis as a fraction of its length (0 at `lo`, 1 at `hi`).
    pub fn frac(&self, v: f64) -> f64 {
        if self.log {
            let (a, b) = (self.lo.log10(), self.hi.log10());
            (v.log10() - a) / (b - a)
        } else {
            (v - self.lo) / (self.hi - self.lo)
        }
    }

    /// Whether `v` can be placed on this axis.
    pub fn accepts(&self, v: f64) -> bool {
        v.is_finite() && (!self.log || v > 0.0)
    }

    /// Width in characters of the longest tick label.
    pub fn label_chars(&self) -> usize {
        self.labels
            .iter()
            .map(|l| l.chars().count())
            .max()
            .unwrap_or(1)
    }
}

fn format_linear_labels(ticks: &[f64], step: Step) -> Vec<String> {
    let max = ticks.iter().fold(0.0f64, |m, t| m.max(t.abs()));
    let sci = step.exp < -4 || max >= 1e6;
    ticks
        .iter()
        .map(|&t| {
            if t == 0.0 {
                "0".to_string()
            } else if sci {
                format!("{t:e}")
            } else {
                format!("{t:.*}", step.decimals())
            }
        })
        .collect()
}

/// A legend entry: a line or a filled swatch with a label.
#[derive(Debug, Clone)]
pub(crate) struct LegendEntry {
    pub label: String,
    pub color: String,
    pub dashed: bool,
    pub filled: bool,
}

impl LegendEntry {
    pub fn line(label: &str, color: &str, dashed: bool) -> Self {
        Self {
            label: truncate(label, 36),
            color: color.to_string(),
            dashed,
            filled: false,
        }
    }

    pub fn fill(label: &str, color: &str) -> Self {
        Self {
            label: truncate(label, 36),
            color: color.to_string(),
            dashed: false,
            filled: true,
        }
    }
}

/// Width of a legend block (0 without entries).
pub(crate) fn legend_width(entries: &[LegendEntry]) -> f64 {
    let chars = entries
        .iter()
        .map(|e| e.label.chars().count())
        .max()
        .unwrap_or(0);
    if chars == 0 {
        0.0
    } else {
        36.0 + chars as f64 * TEXT_CHAR_W + 8.0
    }
}

fn truncate(text: &str, max: usize) -> String {
    if text.chars().count() <= max {
        text.to_string()
    } else {
        let mut t: String = text.chars().take(max - 1).collect();
        t.push('…');
        t
    }
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
        }
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
            c(bottom + 44.0),
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
        let _ = writeln!(
            out,
            "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\" font-size=\"15\" \
             font-weight=\"bold\">{}</text>",
            c(l + w / 2.0),
            c(t - 16.0),
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
        let _ = writeln!(
            out,
            "<path d=\"{d}\" fill=\"none\" stroke=\"{}\" stroke-width=\"1.8\" \
             stroke-linejoin=\"round\" stroke-linecap=\"round\"{dash}/>",
            escape_xml(&s.color)
        );
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
            "<path d=\"{d}\" fill=\"{}\" fill-opacity=\"0.25\" stroke=\"none\"/>",
            escape_xml(&b.color)
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
}

/// Draws legend entries starting at (x, y); `boxed` adds a translucent white background.
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
            c(entries.len() as f64 * 20.0 + 6.0)
        );
    }
    for (i, e) in entries.iter().enumerate() {
        let cy = y + 10.0 + 20.0 * i as f64;
        let color = escape_xml(&e.color);
        if e.filled {
            let _ = writeln!(
                out,
                "<rect x=\"{}\" y=\"{}\" width=\"24\" height=\"12\" fill=\"{color}\" \
                 fill-opacity=\"0.35\" stroke=\"{color}\" stroke-width=\"0.8\"/>",
                c(x),
                c(cy - 6.0)
            );
        } else {
            let dash = if e.dashed {
                " stroke-dasharray=\"7 4\""
            } else {
                ""
            };
            let _ = writeln!(
                out,
                "<path d=\"M{} {}h24\" stroke=\"{color}\" stroke-width=\"2\"{dash}/>",
                c(x),
                c(cy)
            );
        }
        let _ = writeln!(
            out,
            "<text x=\"{}\" y=\"{}\">{}</text>",
            c(x + 30.0),
            c(cy + 4.0),
            escape_xml(&e.label)
        );
    }
    out.push_str("</g>\n");
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

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: &[f64], b: &[f64]) -> bool {
        a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-12)
    }

    fn balanced(svg: &str, tag: &str) -> bool {
        let open =
            svg.matches(&format!("<{tag} ")).count() + svg.matches(&format!("<{tag}>")).count();
        open == svg.matches(&format!("</{tag}>")).count()
    }

    fn band_plot() -> LinePlot {
        let t: Vec<f64> = (0..=500).map(|i| i as f64 * 0.01).collect();
        let mean: Vec<f64> = t
            .iter()
            .map(|t| (3.0 * t).sin() * (-0.3 * t).exp())
            .collect();
        let sd: Vec<f64> = t.iter().map(|t| 0.02 + 0.05 * t).collect();
        let lower = mean.iter().zip(&sd).map(|(m, s)| m - 3.0 * s).collect();
        let upper = mean.iter().zip(&sd).map(|(m, s)| m + 3.0 * s).collect();
        let mut plot = LinePlot::new("Lateral displacement q(t)", "time [s]", "q [m]");
        plot.bands
            .push(Band::new("mean ± 3σ", t.clone(), lower, upper, palette(0)));
        plot.series.push(Series::new(
            "mean (SGM)",
            t.clone(),
            mean.clone(),
            palette(0),
        ));
        plot.series.push(
            Series::new(
                "mean (LHS)",
                t,
                mean.iter().map(|m| m * 1.05).collect(),
                palette(1),
            )
            .dashed(),
        );
        plot
    }

    #[test]
    fn ticks_are_nice_1_2_5_steps() {
        assert!(close(
            &nice_ticks(0.0, 5.0, 6),
            &[0.0, 1.0, 2.0, 3.0, 4.0, 5.0]
        ));
        assert_eq!(
            nice_ticks(0.0, 0.1, 6),
            vec![0.0, 0.02, 0.04, 0.06, 0.08, 0.1],
            "ticks should be the nearest doubles to the decimals"
        );
        assert!(close(
            &nice_ticks(-1.0, 1.0, 6),
            &[-1.0, -0.5, 0.0, 0.5, 1.0]
        ));
        assert!(close(
            &nice_ticks(0.0, 100.0, 6),
            &[0.0, 20.0, 40.0, 60.0, 80.0, 100.0]
        ));
        assert!(close(&nice_ticks(3.0, 7.0, 6), &[3.0, 4.0, 5.0, 6.0, 7.0]));
        // Reversed bounds are sorted; degenerate input does not panic.
        assert!(close(&nice_ticks(5.0, 0.0, 6), &nice_ticks(0.0, 5.0, 6)));
        assert_eq!(nice_ticks(2.0, 2.0, 6), vec![2.0]);
        assert_eq!(nice_ticks(f64::NAN, 1.0, 6), vec![1.0]);
        assert!(nice_ticks(f64::NEG_INFINITY, f64::INFINITY, 6).is_empty());
        assert_eq!(nice_ticks(0.0, 1.0, 0), vec![0.0, 1.0]);
    }

    #[test]
    fn tick_labels_use_step_decimals_or_exponents() {
        let a = Axis::linear(0.0, 0.1);
        assert_eq!(a.labels, ["0", "0.02", "0.04", "0.06", "0.08", "0.10"]);
        let a = Axis::linear(0.0, 5e-6);
        assert_eq!(a.labels[1], "1e-6");
        let a = Axis::linear(-2.0, 2.0);
        assert!(a.labels.iter().all(|l| l != "-0"), "{:?}", a.labels);
        let a = Axis::log(Some((2e-4, 3.0)), true);
        assert_eq!(a.labels, ["0.0001", "0.001", "0.01", "0.1", "1", "10"]);
        assert_eq!((a.lo, a.hi), (1e-4, 10.0));
        let a = Axis::log(Some((1e-30, 1.0)), true);
        assert!(
            a.ticks.len() <= 9 && a.labels[0] == "1e-30",
            "{:?}",
            a.labels
        );
    }

    #[test]
    fn band_plot_svg_is_well_formed() {
        let plot = band_plot();
        let svg = plot.to_svg();
        assert!(svg.starts_with("<svg "));
        assert!(svg.trim_end().ends_with("</svg>"));
        assert!(svg.contains("Lateral displacement q(t)"));
        assert!(svg.contains("mean ± 3σ"));
        assert!(svg.contains("time [s]") && svg.contains("q [m]"));
        assert!(balanced(&svg, "g"), "unbalanced <g>");
        assert!(balanced(&svg, "text"));
        assert!(svg.contains("stroke-dasharray"));
        assert!(svg.contains("fill-opacity=\"0.25\""));
        // Two data lines, one band, plus the tick path and two legend lines.
        assert_eq!(svg.matches("<path ").count(), 2 + 1 + 1 + 2);
        // Coordinates have at most two decimals.
        let d = svg.split("class=\"series\"").nth(1).unwrap();
        let d = &d[d.find("d=\"").unwrap() + 3..];
        let d = &d[..d.find('"').unwrap()];
        for num in d.split(|c: char| c.is_ascii_alphabetic() || c == ' ') {
            if let Some((_, frac)) = num.split_once('.') {
                assert!(frac.len() <= 2, "{num}");
            }
        }
        assert!(svg.len() < 60_000, "svg is {} bytes", svg.len());
    }

    #[test]
    fn non_finite_points_break_the_line() {
        let mut plot = LinePlot::new("gaps", "x", "y");
        plot.series.push(Series::new(
            "s",
            vec![0.0, 1.0, 2.0, f64::NAN, 4.0, 5.0, 6.0],
            vec![0.0, 1.0, f64::INFINITY, 3.0, 4.0, f64::NAN, 6.0],
            "red",
        ));
        let svg = plot.to_svg();
        assert!(!svg.contains("NaN") && !svg.contains("inf"));
        let d = svg.split("class=\"series\"").nth(1).unwrap();
        let d = &d[d.find("d=\"").unwrap() + 3..];
        let d = &d[..d.find('"').unwrap()];
        // Runs: {0,1}, {4}, {6}.
        assert_eq!(d.matches('M').count(), 3, "{d}");
    }

    #[test]
    fn empty_and_degenerate_plots_are_still_valid() {
        let empty = LinePlot::default().to_svg();
        assert!(empty.starts_with("<svg ") && balanced(&empty, "g"));
        let mut flat = LinePlot::new("flat", "x", "y");
        flat.series
            .push(Series::new("c", vec![1.0, 1.0], vec![2.0, 2.0], "black"));
        flat.series
            .push(Series::new("nan", vec![f64::NAN], vec![f64::NAN], "black"));
        flat.series
            .push(Series::new("short", vec![0.0, 1.0], vec![], "black"));
        let svg = flat.to_svg();
        assert!(!svg.contains("NaN") && !svg.contains("inf"));
        assert_eq!(svg.matches("<path d=\"\"").count(), 2);
        let mut log = LinePlot::new("log", "x", "y");
        log.log_y = true;
        log.series.push(Series::new(
            "s",
            vec![0.0, 1.0, 2.0],
            vec![-1.0, 0.0, 1e-3],
            "black",
        ));
        let svg = log.to_svg();
        assert!(!svg.contains("NaN") && !svg.contains("inf"));
        let huge = LinePlot {
            series: vec![Series::new(
                "h",
                vec![0.0, 1.0],
                vec![-f64::MAX, f64::MAX],
                "k",
            )],
            ..LinePlot::default()
        };
        let svg = huge.to_svg();
        assert!(!svg.contains("NaN") && !svg.contains("inf"));
    }

    #[test]
    fn labels_are_escaped() {
        let plot = LinePlot::new("<b>&</b>", "x", "y");
        let svg = plot.to_svg();
        assert!(svg.contains("&lt;b&gt;&amp;&lt;/b&gt;"));
        assert!(!svg.contains("<b>"));
    }

    #[test]
    fn histogram_density_integrates_to_one() {
        let samples: Vec<f64> = (0..1000).map(|i| (i as f64 * 0.7).sin()).collect();
        let (edges, dens) = histogram_density(&samples, 20);
        assert_eq!(edges.len(), 21);
        let total: f64 = dens
            .iter()
            .zip(edges.windows(2))
            .map(|(d, e)| d * (e[1] - e[0]))
            .sum();
        assert!((total - 1.0).abs() < 1e-12);
        let (edges, dens) = histogram_density(&[f64::NAN, 3.0, 3.0], 0);
        assert_eq!(edges.len(), dens.len() + 1);
        assert_eq!(edges.first(), Some(&2.5));
        assert!(histogram_density(&[f64::NAN], 5).0.is_empty());
    }

    #[test]
    fn density_plot_has_histogram_curves_and_markers() {
        let x: Vec<f64> = (0..=200).map(|i| i as f64 * 0.02).collect();
        let pdf: Vec<f64> = x
            .iter()
            .map(|x| (-(x - 2.0f64).powi(2) / 0.5).exp() / (0.5 * std::f64::consts::PI).sqrt())
            .collect();
        let samples: Vec<f64> = (0..400).map(|i| 2.0 + (i as f64 * 0.37).sin()).collect();
        let plot = DensityPlot {
            title: "Sperling index W".into(),
            x_label: "W [-]".into(),
            curves: vec![Series::new("KDE", x, pdf, palette(0))],
            histogram: Some(histogram_density(&samples, 0)),
            markers: vec![(2.5, "limit W = 2.5".into()), (f64::NAN, "bad".into())],
        };
        let svg = plot.to_svg();
        assert!(svg.starts_with("<svg ") && balanced(&svg, "g"));
        assert!(svg.matches("<rect ").count() >= 10);
        assert!(svg.contains("limit W = 2.5"));
        assert!(svg.contains("probability density"));
        assert!(!svg.contains("NaN"));
        let empty = DensityPlot::default().to_svg();
        assert!(empty.starts_with("<svg ") && balanced(&empty, "g"));
    }

    #[test]
    fn write_reports_the_path_on_error() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("no/such/dir/p.svg");
        let err = LinePlot::default().write(&path).unwrap_err();
        assert!(err.to_string().contains("p.svg"));
        let ok = dir.path().join("p.svg");
        band_plot().write(&ok).unwrap();
        assert!(std::fs::read_to_string(ok).unwrap().starts_with("<svg"));
    }
}
