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

mod axis;
mod frame;
#[cfg(test)]
mod tests;

#[cfg(test)]
pub(crate) use axis::nice_ticks;
pub(crate) use axis::{finite_range, Axis};
pub(crate) use frame::{c, legend, legend_width, Frame, LegendEntry};

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
    /// Stroke width in px (1.8 when `None`).
    pub width: Option<f64>,
    /// Stroke opacity (opaque when `None`).
    pub opacity: Option<f64>,
    /// A dot at every point (e.g. a few estimates against an integer order).
    pub markers: bool,
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
            width: None,
            opacity: None,
            markers: false,
        }
    }

    /// The same line, dashed.
    pub fn dashed(mut self) -> Self {
        self.dashed = true;
        self
    }

    /// The same line, `width` px wide and drawn with `opacity`.
    pub fn thin(mut self, width: f64, opacity: f64) -> Self {
        self.width = Some(width);
        self.opacity = Some(opacity);
        self
    }

    /// The same line with a dot at every point.
    pub fn with_markers(mut self) -> Self {
        self.markers = true;
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
    /// Fill color.
    pub color: String,
    /// Fill opacity (0.25 unless set with [`Band::opacity`]).
    pub opacity: f64,
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
            opacity: 0.25,
        }
    }

    /// The same band with another fill opacity (e.g. stacked areas).
    pub fn opacity(mut self, opacity: f64) -> Self {
        self.opacity = opacity;
        self
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
    /// Logarithmic horizontal axis (non-positive values are skipped).
    pub log_x: bool,
    /// Fixed vertical range instead of the data's (e.g. `(0, 1)` for indices).
    pub y_range: Option<(f64, f64)>,
    /// The horizontal axis counts whole numbers (e.g. a chaos order): ticks at integers only,
    /// half a unit of room at each end.
    pub integer_x: bool,
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
        let x_axis = if self.log_x {
            Axis::log(finite_range(xs, true), false)
        } else if self.integer_x {
            Axis::integers(finite_range(xs, false))
        } else {
            Axis::linear_exact(finite_range(xs, false))
        };
        let y_axis = match self.y_range {
            Some((lo, hi)) if log => Axis::log(Some((lo, hi)), false),
            Some((lo, hi)) => Axis::linear(lo, hi),
            None if log => Axis::log(finite_range(ys, true), true),
            None => Axis::linear_padded(finite_range(ys, false)),
        };

        let mut legend: Vec<LegendEntry> = Vec::new();
        for b in &self.bands {
            legend.push(LegendEntry::fill(&b.label, &b.color).with_opacity(b.opacity));
        }
        for s in &self.series {
            legend.push(LegendEntry::of_series(s));
        }
        legend.retain(|e| !e.label.is_empty());

        let frame = Frame::with_legend(x_axis, y_axis, &legend);
        let mut out = frame.open_with_grid();
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
        frame.close_with_legend(&mut out, &legend);
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
    /// "probability density" in the inverse of that unit (from a trailing `[unit]` of this
    /// label: [`density_label`]).
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
    /// Renders the plot as an SVG document. The horizontal range is that of the curves and
    /// the histogram; a marker outside it is drawn as an arrow at the edge, and its legend
    /// entry says so.
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

        let data_xs = self
            .curves
            .iter()
            .flat_map(|s| paired(&s.x, &s.y).map(|(x, _)| x))
            .chain(bars.clone().flat_map(|(l, r, _)| [l, r]));
        let data = finite_range(data_xs, false);
        let markers_finite = self.markers.iter().map(|m| m.0).filter(|x| x.is_finite());
        // Without data, the markers set the range.
        let x_range = data.or_else(|| finite_range(markers_finite, false));
        let ys = self
            .curves
            .iter()
            .flat_map(|s| paired(&s.x, &s.y).map(|(_, y)| y))
            .chain(bars.clone().map(|b| b.2))
            .chain([0.0]);
        let x_axis = Axis::linear_exact(x_range);
        let y_axis = Axis::linear_padded(finite_range(ys, false));

        let mut legend: Vec<LegendEntry> = Vec::new();
        if self.histogram.is_some() {
            legend.push(
                LegendEntry::fill("histogram of the runs", HISTOGRAM_COLOR)
                    .with_opacity(HISTOGRAM_OPACITY),
            );
        }
        for s in &self.curves {
            legend.push(LegendEntry::line(&s.label, &s.color, s.dashed));
        }
        for (i, (x, label)) in self.markers.iter().enumerate() {
            let side = if *x < x_axis.lo {
                " (left of the plotted range ←)"
            } else if *x > x_axis.hi {
                " (right of the plotted range →)"
            } else {
                ""
            };
            let mut entry = LegendEntry::line(&format!("{label}{side}"), marker_color(i), true);
            if *x < x_axis.lo || *x > x_axis.hi {
                entry.arrow = Some(*x > x_axis.hi);
            }
            legend.push(entry);
        }
        legend.retain(|e| !e.label.is_empty());

        let frame = Frame::with_legend(x_axis, y_axis, &legend);
        let mut out = frame.open_with_grid();
        histogram(&frame, &mut out, bars);
        out.push_str("<g class=\"series\" clip-path=\"url(#plot-area)\">\n");
        for s in &self.curves {
            frame.series(&mut out, s);
        }
        out.push_str("</g>\n");
        markers(&frame, &mut out, &self.markers);
        let y_label = density_label(&self.x_label);
        frame.axes(&mut out, &self.title, &self.x_label, &y_label);
        frame.close_with_legend(&mut out, &legend);
        out
    }

    /// Writes [`Self::to_svg`] to `path`.
    pub fn write(&self, path: &Path) -> Result<(), ReportError> {
        write_bytes(path, self.to_svg().as_bytes())
    }
}

/// Draws histogram bars `(left, right, height)`.
fn histogram(frame: &Frame, out: &mut String, bars: impl Iterator<Item = (f64, f64, f64)>) {
    out.push_str("<g class=\"histogram\" clip-path=\"url(#plot-area)\">\n");
    let y0 = frame.py(0.0);
    for (l, r, h) in bars {
        let (xl, xr) = (frame.px(l.min(r)), frame.px(l.max(r)));
        let yt = frame.py(h.max(0.0));
        let _ = writeln!(
            out,
            "<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"{HISTOGRAM_COLOR}\" \
             fill-opacity=\"{HISTOGRAM_OPACITY}\" stroke=\"#fff\" stroke-width=\"0.5\"/>",
            c(xl),
            c(yt.min(y0)),
            c(xr - xl),
            c((y0 - yt).abs()),
        );
    }
    out.push_str("</g>\n");
}

/// Draws dashed vertical marker lines (their labels are in the legend, so nothing is drawn
/// over the data); a marker beyond the horizontal range becomes an arrow at that edge.
fn markers(frame: &Frame, out: &mut String, markers: &[(f64, String)]) {
    out.push_str("<g class=\"markers\">\n");
    for (i, (x, _)) in markers.iter().enumerate() {
        if !x.is_finite() {
            continue;
        }
        let color = marker_color(i);
        let y = frame.top + 14.0 + 12.0 * (i % 4) as f64;
        if *x < frame.x.lo || *x > frame.x.hi {
            let (edge, dir) = if *x < frame.x.lo {
                (frame.left, -1.0)
            } else {
                (frame.left + frame.width, 1.0)
            };
            // Inside the plot area, pointing at the edge beyond which the limit lies.
            let tip = edge - dir * 3.0;
            frame::arrow(out, tip - dir * 26.0, tip, dir, y, color);
            continue;
        }
        let px = frame.px(*x);
        let _ = writeln!(
            out,
            "<line x1=\"{0}\" y1=\"{1}\" x2=\"{0}\" y2=\"{2}\" stroke=\"{color}\" \
             stroke-width=\"1.5\" stroke-dasharray=\"6 4\"/>",
            c(px),
            c(frame.top),
            c(frame.top + frame.height),
        );
    }
    out.push_str("</g>\n");
}

/// Bars of several groups per category (e.g. first-order and total Sobol' indices per
/// parameter), each bar with an optional interval drawn as an error bar.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct BarChart {
    /// Title above the plot.
    pub title: String,
    /// Label of the vertical axis.
    pub y_label: String,
    /// Label under the categories.
    pub x_label: String,
    /// Category names (e.g. parameters), along the horizontal axis.
    pub categories: Vec<String>,
    /// Groups: (legend label, color, one value per category, optional interval per
    /// category).
    pub groups: Vec<BarGroup>,
    /// Fixed vertical range (e.g. `(0, 1)`); the data's range when `None`.
    pub y_range: Option<(f64, f64)>,
    /// Legend text of the whiskers (e.g. "95 % interval (8 replicates, Student t)");
    /// "95 % interval" when empty.
    pub interval_label: String,
}

/// One group of bars of a [`BarChart`].
#[derive(Debug, Clone, Default, PartialEq)]
pub struct BarGroup {
    /// Legend label.
    pub label: String,
    /// Fill color.
    pub color: String,
    /// One value per category (non-finite: no bar).
    pub values: Vec<f64>,
    /// An interval `(low, high)` per category, where there is one.
    pub intervals: Vec<Option<(f64, f64)>>,
}

impl BarChart {
    /// Renders the chart as an SVG document.
    pub fn to_svg(&self) -> String {
        let n = self.categories.len().max(1);
        let values = self.groups.iter().flat_map(|g| {
            g.values
                .iter()
                .copied()
                .chain(g.intervals.iter().flatten().flat_map(|&(lo, hi)| [lo, hi]))
        });
        let y_axis = match self.y_range {
            Some((lo, hi)) => {
                let (dlo, dhi) = finite_range(values, false).unwrap_or((lo, hi));
                Axis::linear(lo.min(dlo), hi.max(dhi))
            }
            None => Axis::linear_padded(finite_range(values.chain([0.0]), false)),
        };
        let mut x_axis = Axis::linear(0.0, n as f64);
        x_axis.ticks = (0..n).map(|i| i as f64 + 0.5).collect();
        x_axis.labels = self.categories.clone();
        x_axis.labels.resize(n, String::new());
        let longest = x_axis
            .labels
            .iter()
            .map(|l| l.chars().count())
            .max()
            .unwrap_or(0);
        let slot = 600.0 / n as f64;
        let rotate = longest as f64 * 6.4 > slot - 4.0;
        let mut legend: Vec<LegendEntry> = self
            .groups
            .iter()
            .map(|g| LegendEntry::fill(&g.label, &g.color).with_opacity(BAR_OPACITY))
            .collect();
        if self
            .groups
            .iter()
            .any(|g| g.intervals.iter().any(Option::is_some))
        {
            let label = if self.interval_label.is_empty() {
                "95 % interval"
            } else {
                &self.interval_label
            };
            legend.push(LegendEntry::line(label, "#222", false));
        }
        legend.retain(|e| !e.label.is_empty());
        let mut frame = Frame::with_legend(x_axis.clone(), y_axis, &legend);
        if rotate {
            frame.add_below(longest as f64 * 6.4 * 0.6);
        }
        let mut out = frame.open_with_grid();
        out.push_str("<g class=\"bars\" clip-path=\"url(#plot-area)\">\n");
        let k = self.groups.len().max(1) as f64;
        let bar_w = slot * 0.8 / k;
        let y0 = frame.py(0.0f64.clamp(frame.y.lo, frame.y.hi));
        for (gi, g) in self.groups.iter().enumerate() {
            for (ci, &v) in g.values.iter().enumerate().take(n) {
                let x = frame.left + slot * (ci as f64 + 0.1) + bar_w * gi as f64;
                if v.is_finite() {
                    let yv = frame.py(v);
                    let _ = writeln!(
                        out,
                        "<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"{}\" \
                         fill-opacity=\"{BAR_OPACITY}\"/>",
                        c(x),
                        c(yv.min(y0)),
                        c(bar_w * 0.92),
                        c((yv - y0).abs()),
                        escape_xml(&g.color)
                    );
                }
                if let Some(Some((lo, hi))) = g.intervals.get(ci) {
                    let xm = x + bar_w * 0.46;
                    let (a, b) = (frame.py(*lo), frame.py(*hi));
                    let _ = writeln!(
                        out,
                        "<path d=\"M{xm} {a}V{b}M{l} {a}H{r}M{l} {b}H{r}\" stroke=\"#222\" \
                         stroke-width=\"1.3\" fill=\"none\"/>",
                        xm = c(xm),
                        a = c(a),
                        b = c(b),
                        l = c(xm - 4.0),
                        r = c(xm + 4.0),
                    );
                }
            }
        }
        out.push_str("</g>\n");
        if rotate {
            // Category names slanted below the axis instead of the axis's own labels.
            frame.x.labels = vec![String::new(); n];
            frame.axes(&mut out, &self.title, &self.x_label, &self.y_label);
            out.push_str("<g font-size=\"11\" text-anchor=\"end\" fill=\"#222\">\n");
            for (i, name) in self.categories.iter().enumerate() {
                let (x, y) = (
                    frame.left + slot * (i as f64 + 0.5),
                    frame.top + frame.height + 14.0,
                );
                let _ = writeln!(
                    out,
                    "<text x=\"{0}\" y=\"{1}\" transform=\"rotate(-35 {0} {1})\">{2}</text>",
                    c(x),
                    c(y),
                    escape_xml(name)
                );
            }
            out.push_str("</g>\n");
        } else {
            frame.axes(&mut out, &self.title, &self.x_label, &self.y_label);
        }
        frame.close_with_legend(&mut out, &legend);
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

/// Color `i` of a ten-color qualitative palette (matplotlib's tab10), cycling.
pub fn palette(i: usize) -> &'static str {
    const TAB10: [&str; 10] = [
        "#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f",
        "#bcbd22", "#17becf",
    ];
    TAB10[i % TAB10.len()]
}

const HISTOGRAM_COLOR: &str = "#8c9db5";
/// Fill opacity of histogram bars (and of their legend swatch).
const HISTOGRAM_OPACITY: f64 = 0.55;
/// Fill opacity of the bars of a [`BarChart`] (and of their legend swatches).
const BAR_OPACITY: f64 = 0.8;

/// The colour of limit marker `i`: eight distinct colours (none the blue of the curves or the
/// grey-blue of the histogram) before they repeat.
fn marker_color(i: usize) -> &'static str {
    [
        "#d62728", "#222222", "#9467bd", "#ff7f0e", "#2ca02c", "#8c564b", "#e377c2", "#17becf",
    ][i % 8]
}

/// The label of a density axis for a quantity labelled `x_label`: `probability density
/// [1/m]` for `q [m]`, `[-]` for a dimensionless `W [-]`, plain `probability density`
/// without a unit.
pub fn density_label(x_label: &str) -> String {
    let unit = x_label
        .trim_end()
        .strip_suffix(']')
        .and_then(|l| l.rsplit_once('['))
        .map(|(_, u)| u.trim());
    match unit {
        Some("-") | Some("1") => "probability density [-]".into(),
        Some(u) if !u.is_empty() => match super::units::per(Some(u)) {
            Some(d) => format!("probability density [{d}]"),
            None => "probability density".into(),
        },
        _ => "probability density".into(),
    }
}

/// Points of `x` and `y` paired by index (the shorter length wins).
pub(super) fn paired<'a>(
    x: &'a [f64],
    y: &'a [f64],
) -> impl Iterator<Item = (f64, f64)> + Clone + 'a {
    x.iter().copied().zip(y.iter().copied())
}
