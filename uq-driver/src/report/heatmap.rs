//! Heat maps of a field over two axes, e.g. the PDF of q over time: a viridis PNG of raw
//! pixels, and an SVG frame around it with axes, ticks, labels, a colorbar and overlay lines.
//!
//! `x[ix]` and `y[iy]` are cell centres; each cell extends half-way to its neighbours, so
//! non-uniform grids are drawn faithfully (each pixel takes the nearest cell). Non-finite
//! cells (and cells missing from a short `z`) are transparent.

use std::fmt::Write as _;

use super::svg::{c, finite_range, legend, legend_width, Axis, Frame, LegendEntry, Series};

/// Where the colorbar's label sits right of the bar's tick labels (px).
const BAR_LABEL_GAP: f64 = 14.0;
use super::escape_xml;

/// A heat map `z[ix][iy]` over `x` (horizontal, e.g. time) and `y` (vertical, e.g. the grid
/// of a density).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Heatmap {
    /// Title above the plot.
    pub title: String,
    /// Label of the horizontal axis, with unit.
    pub x_label: String,
    /// Label of the vertical axis, with unit.
    pub y_label: String,
    /// Horizontal cell centres (length nx), e.g. times (s).
    pub x: Vec<f64>,
    /// Vertical cell centres (length ny), e.g. the grid of q.
    pub y: Vec<f64>,
    /// Values, `z[ix][iy]`; missing or non-finite entries are transparent.
    pub z: Vec<Vec<f64>>,
    /// Label of the colorbar, with unit, e.g. `PDF [1/m]`.
    pub colorbar_label: String,
    /// Lines drawn on top, in data coordinates (e.g. the mean and ±3σ).
    pub overlay: Vec<Series>,
    /// Logarithmic color scale over at most six decades below the maximum; values at or
    /// below the lower end (including zeros) get the lowest color.
    pub log_scale: bool,
}

/// Viridis at 0, 0.1, …, 1 (matplotlib), interpolated linearly in sRGB.
const VIRIDIS: [[u8; 3]; 11] = [
    [0x44, 0x01, 0x54],
    [0x48, 0x24, 0x75],
    [0x41, 0x44, 0x87],
    [0x35, 0x5f, 0x8d],
    [0x2a, 0x78, 0x8e],
    [0x21, 0x91, 0x8c],
    [0x22, 0xa8, 0x84],
    [0x44, 0xbf, 0x70],
    [0x7a, 0xd1, 0x51],
    [0xbd, 0xdf, 0x26],
    [0xfd, 0xe7, 0x25],
];

/// The viridis color at `t` in [0, 1] (clamped; NaN gives the lowest color).
pub fn viridis(t: f64) -> [u8; 3] {
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
    let s = t * (VIRIDIS.len() - 1) as f64;
    let i = (s.floor() as usize).min(VIRIDIS.len() - 2);
    let f = s - i as f64;
    let (a, b) = (VIRIDIS[i], VIRIDIS[i + 1]);
    let mix = |k: usize| (a[k] as f64 + (b[k] as f64 - a[k] as f64) * f).round() as u8;
    [mix(0), mix(1), mix(2)]
}

/// Decades shown below the maximum on a log color scale.
const LOG_DECADES: f64 = 6.0;
/// Minimum PNG size in pixels; small grids are scaled up by whole numbers of pixels per cell.
const MIN_W: usize = 600;
const MIN_H: usize = 400;
/// Maximum PNG size in pixels per direction; larger grids are subsampled.
const MAX_PIXELS: usize = 4096;
/// Gap between the plot and the colorbar (px).
const BAR_GAP: f64 = 22.0;
/// Width of the colorbar (px).
const BAR_W: f64 = 16.0;

impl Heatmap {
    /// Size (width, height) of the PNG in pixels: at least one pixel per cell (up to 4096),
    /// scaled up by a whole factor to at least 600 × 400 for small grids.
    pub fn png_size(&self) -> (u32, u32) {
        let nx = Cells::new(&self.x).len();
        let ny = Cells::new(&self.y).len();
        (pixels(nx, MIN_W), pixels(ny, MIN_H))
    }

    /// The RGBA color of cell `(ix, iy)` (transparent outside the grid or without a value).
    fn cell_color(
        &self,
        ix: Option<usize>,
        iy: Option<usize>,
        scale: Option<&ColorScale>,
    ) -> [u8; 4] {
        let v = match (ix, iy) {
            (Some(ix), Some(iy)) => self
                .z
                .get(ix)
                .and_then(|r| r.get(iy))
                .copied()
                .unwrap_or(f64::NAN),
            _ => f64::NAN,
        };
        match scale.and_then(|s| s.t(v)) {
            Some(t) => {
                let [r, g, b] = viridis(t);
                [r, g, b, 255]
            }
            None => [0, 0, 0, 0],
        }
    }

    /// Encodes the heat map as an RGBA PNG (no text; the top row is the largest `y`).
    pub fn to_png(&self) -> Result<Vec<u8>, png::EncodingError> {
        let (w, h) = self.png_size();
        let (xc, yc) = (Cells::new(&self.x), Cells::new(&self.y));
        let scale = self.color_scale();
        let col: Vec<Option<usize>> = (0..w as usize)
            .map(|i| xc.at((i as f64 + 0.5) / w as f64))
            .collect();
        let row_bytes = w as usize * 4;
        let mut data = Vec::with_capacity(row_bytes * h as usize);
        let mut prev_iy = None;
        for j in 0..h as usize {
            let iy = yc.at(1.0 - (j as f64 + 0.5) / h as f64);
            if j > 0 && iy == prev_iy {
                // Pixel rows of one grid cell are equal: copy the previous one.
                data.extend_from_within(data.len() - row_bytes..);
                continue;
            }
            prev_iy = iy;
            // Pixels of one cell share its color: computed once per cell.
            let mut last: Option<(Option<usize>, [u8; 4])> = None;
            for &ix in &col {
                let rgba = match last {
                    Some((cell, rgba)) if cell == ix => rgba,
                    _ => {
                        let rgba = self.cell_color(ix, iy, scale.as_ref());
                        last = Some((ix, rgba));
                        rgba
                    }
                };
                data.extend_from_slice(&rgba);
            }
        }
        let mut bytes = Vec::new();
        let mut enc = png::Encoder::new(&mut bytes, w, h);
        enc.set_color(png::ColorType::Rgba);
        enc.set_depth(png::BitDepth::Eight);
        // Runs of equal pixels compress well even on the fast setting (5× faster).
        enc.set_compression(png::Compression::Fast);
        let mut writer = enc.write_header()?;
        writer.write_image_data(&data)?;
        writer.finish()?;
        Ok(bytes)
    }

    /// Renders the SVG frame (axes, colorbar, overlay) around an `<image>` with `href`
    /// `png_href` (a file name relative to the SVG, or a `data:` URI).
    pub fn to_svg(&self, png_href: &str) -> String {
        let (xc, yc) = (Cells::new(&self.x), Cells::new(&self.y));
        let x_axis = Axis::linear_exact(Some((xc.lo, xc.hi)));
        let y_axis = Axis::linear_exact(Some((yc.lo, yc.hi)));
        let scale = self.color_scale();
        let bar_axis = match &scale {
            Some(s) if s.log => Axis::log(Some((s.lo, s.hi)), false),
            Some(s) => Axis::linear_exact(Some((s.lo, s.hi))),
            None => Axis::linear_exact(None),
        };
        let mut entries: Vec<LegendEntry> =
            self.overlay.iter().map(LegendEntry::of_series).collect();
        entries.retain(|e| !e.label.is_empty());
        let bar_right = BAR_GAP + BAR_W + 10.0 + bar_axis.label_chars() as f64 * 6.4;
        let right = bar_right + BAR_LABEL_GAP + 12.0 + legend_width(&entries);
        let mut frame = Frame::new(x_axis, y_axis, right);
        frame.fit_legend(&entries);

        let mut out = String::new();
        frame.open(&mut out);
        let href = escape_xml(png_href);
        let _ = writeln!(
            out,
            "<image x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" preserveAspectRatio=\"none\" \
             style=\"image-rendering:pixelated\" href=\"{href}\" xlink:href=\"{href}\"/>",
            c(frame.left),
            c(frame.top),
            c(frame.width),
            c(frame.height),
        );
        out.push_str("<g class=\"series\" clip-path=\"url(#plot-area)\">\n");
        for s in &self.overlay {
            frame.series(&mut out, s);
        }
        out.push_str("</g>\n");
        frame.axes(&mut out, &self.title, &self.x_label, &self.y_label);

        let label_x = frame.left + frame.width + bar_right + BAR_LABEL_GAP;
        self.colorbar(&mut out, &frame, scale.is_some(), &bar_axis, label_x);
        // Outside the plot, right of the colorbar: nothing is drawn over the map.
        legend(&mut out, &entries, label_x + 16.0, frame.top + 4.0, false);
        out.push_str("</svg>\n");
        out
    }

    /// The colorbar right of `frame`: a gradient through the viridis table (grey when there
    /// is no scale), with its own axis and label.
    fn colorbar(
        &self,
        out: &mut String,
        frame: &Frame,
        scaled: bool,
        bar_axis: &Axis,
        label_x: f64,
    ) {
        let bx = frame.left + frame.width + BAR_GAP;
        let (top, h) = (frame.top, frame.height);
        out.push_str("<g class=\"colorbar\">\n<defs><linearGradient id=\"cmap\" x1=\"0\" y1=\"1\" x2=\"0\" y2=\"0\">");
        for (i, rgb) in VIRIDIS.iter().enumerate() {
            let _ = write!(
                out,
                "<stop offset=\"{}\" stop-color=\"#{:02x}{:02x}{:02x}\"/>",
                i as f64 / (VIRIDIS.len() - 1) as f64,
                rgb[0],
                rgb[1],
                rgb[2]
            );
        }
        out.push_str("</linearGradient></defs>\n");
        let fill = if scaled { "url(#cmap)" } else { "#eee" };
        let _ = writeln!(
            out,
            "<rect x=\"{}\" y=\"{}\" width=\"{BAR_W}\" height=\"{}\" fill=\"{fill}\" stroke=\"#333\"/>",
            c(bx),
            c(top),
            c(h)
        );
        if scaled {
            let bar_y = |v: f64| top + (1.0 - bar_axis.frac(v)) * h;
            let mut ticks = String::new();
            for &v in &bar_axis.ticks {
                let _ = write!(ticks, "M{} {}h4", c(bx + BAR_W), c(bar_y(v)));
            }
            for &v in &bar_axis.minor {
                let _ = write!(ticks, "M{} {}h2", c(bx + BAR_W), c(bar_y(v)));
            }
            let _ = writeln!(out, "<path d=\"{ticks}\" stroke=\"#333\" fill=\"none\"/>");
            out.push_str("<g font-size=\"11\" fill=\"#222\">\n");
            for (&v, label) in bar_axis.ticks.iter().zip(&bar_axis.labels) {
                let _ = writeln!(
                    out,
                    "<text x=\"{}\" y=\"{}\">{}</text>",
                    c(bx + BAR_W + 7.0),
                    c(bar_y(v) + 4.0),
                    escape_xml(label)
                );
            }
            out.push_str("</g>\n");
        }
        let (lx, ly) = (label_x, top + h / 2.0);
        let _ = writeln!(
            out,
            "<text x=\"{0}\" y=\"{1}\" text-anchor=\"middle\" font-size=\"13\" fill=\"#222\" \
             transform=\"rotate(-90 {0} {1})\">{2}</text>\n</g>",
            c(lx),
            c(ly),
            escape_xml(&self.colorbar_label)
        );
    }

    /// A `data:` URI of PNG bytes, for [`Self::to_svg`] (a self-contained SVG).
    pub fn data_uri(png: &[u8]) -> String {
        format!("data:image/png;base64,{}", base64(png))
    }

    fn color_scale(&self) -> Option<ColorScale> {
        let values = self.z.iter().flatten().copied();
        if self.log_scale {
            let (_, hi) = finite_range(values, true)?;
            let lo_all = finite_range(self.z.iter().flatten().copied(), true)?.0;
            let lo = lo_all.max(hi / 10f64.powf(LOG_DECADES));
            let lo = if hi / lo < 1.0 + 1e-9 { hi / 10.0 } else { lo };
            Some(ColorScale { lo, hi, log: true })
        } else {
            // Colours start at 0 (a density is never negative); no scale without a
            // positive value.
            let (lo, hi) = finite_range(values, false)?;
            if hi <= 0.0 {
                return None;
            }
            Some(ColorScale {
                lo: lo.min(0.0),
                hi,
                log: false,
            })
        }
    }
}

/// Maps values to [0, 1] for the colormap.
#[derive(Debug, Clone, Copy)]
struct ColorScale {
    lo: f64,
    hi: f64,
    log: bool,
}

impl ColorScale {
    /// Position of `v` in the scale; `None` for values that are not drawn.
    fn t(&self, v: f64) -> Option<f64> {
        if !v.is_finite() {
            return None;
        }
        let t = if self.log {
            if v <= self.lo {
                0.0
            } else {
                (v.log10() - self.lo.log10()) / (self.hi.log10() - self.lo.log10())
            }
        } else if self.hi > self.lo {
            (v - self.lo) / (self.hi - self.lo)
        } else {
            0.5
        };
        Some(t.clamp(0.0, 1.0))
    }
}

/// The cells of one axis: finite centres sorted, with the extent `[lo, hi]` they cover.
#[derive(Debug, Clone)]
struct Cells {
    /// (centre, index into the original vector), sorted by centre.
    sorted: Vec<(f64, usize)>,
    lo: f64,
    hi: f64,
}

impl Cells {
    fn new(centres: &[f64]) -> Self {
        let mut sorted: Vec<(f64, usize)> = centres
            .iter()
            .copied()
            .enumerate()
            .filter(|(_, v)| v.is_finite())
            .map(|(i, v)| (v.clamp(-1e300, 1e300), i))
            .collect();
        sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
        let (lo, hi) = match (sorted.first(), sorted.last()) {
            (Some(&(a, _)), Some(&(b, _))) if b > a => {
                let first_gap = sorted[1].0 - a;
                let last_gap = b - sorted[sorted.len() - 2].0;
                (a - first_gap / 2.0, b + last_gap / 2.0)
            }
            (Some(&(a, _)), _) => {
                let h = if a == 0.0 { 0.5 } else { a.abs() * 0.05 };
                (a - h, a + h)
            }
            _ => (0.0, 1.0),
        };
        Self { sorted, lo, hi }
    }

    fn len(&self) -> usize {
        self.sorted.len()
    }

    /// Original index of the cell nearest to the fraction `f` of the extent.
    fn at(&self, f: f64) -> Option<usize> {
        let v = self.lo + f * (self.hi - self.lo);
        let k = self.sorted.partition_point(|p| p.0 < v);
        let best = match (k.checked_sub(1), self.sorted.get(k)) {
            (Some(a), Some(b)) if v - self.sorted[a].0 <= b.0 - v => a,
            (Some(a), None) => a,
            (_, Some(_)) => k,
            (None, None) => return None,
        };
        Some(self.sorted[best].1)
    }
}

/// Pixels for `n` cells: one per cell (capped), scaled up by a whole factor to `min`.
fn pixels(n: usize, min: usize) -> u32 {
    let p = match n {
        0 => 1,
        n if n >= min => n.min(MAX_PIXELS),
        n => n * min.div_ceil(n),
    };
    p as u32
}

/// Standard base64 with padding.
fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            chunk.get(1).copied().unwrap_or(0),
            chunk.get(2).copied().unwrap_or(0),
        ];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(ALPHABET[(n >> (18 - 6 * k)) as usize & 63] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn decode(bytes: &[u8]) -> (png::OutputInfo, Vec<u8>) {
        let decoder = png::Decoder::new(bytes);
        let mut reader = decoder.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size()];
        let info = reader.next_frame(&mut buf).unwrap();
        buf.truncate(info.buffer_size());
        (info, buf)
    }

    fn gaussian_map() -> Heatmap {
        let x: Vec<f64> = (0..=50).map(|i| i as f64 * 0.1).collect();
        let y: Vec<f64> = (0..100).map(|j| -1.0 + 2.0 * j as f64 / 99.0).collect();
        let mean: Vec<f64> = x.iter().map(|t| 0.5 * (2.0 * t).sin()).collect();
        let sd: Vec<f64> = x.iter().map(|t| 0.05 + 0.04 * t).collect();
        let z = x
            .iter()
            .enumerate()
            .map(|(i, _)| {
                y.iter()
                    .map(|q| {
                        let u = (q - mean[i]) / sd[i];
                        (-0.5 * u * u).exp() / (sd[i] * (2.0 * std::f64::consts::PI).sqrt())
                    })
                    .collect()
            })
            .collect();
        Heatmap {
            title: "PDF of q(t)".into(),
            x_label: "time [s]".into(),
            y_label: "q [m]".into(),
            x: x.clone(),
            y,
            z,
            colorbar_label: "PDF [1/m]".into(),
            overlay: vec![Series::new("mean", x, mean, "#ffffff")],
            log_scale: false,
        }
    }

    #[test]
    fn viridis_endpoints_and_midpoint() {
        assert_eq!(viridis(0.0), [0x44, 0x01, 0x54]);
        assert_eq!(viridis(1.0), [0xfd, 0xe7, 0x25]);
        assert_eq!(viridis(0.5), [0x21, 0x91, 0x8c]);
        assert_eq!(viridis(f64::NAN), viridis(0.0));
        assert_eq!(viridis(7.0), viridis(1.0));
    }

    #[test]
    fn png_decodes_to_the_documented_size() {
        let map = gaussian_map();
        let (w, h) = map.png_size();
        // 51 times scaled by 12 → 612; 100 grid points scaled by 4 → 400.
        assert_eq!((w, h), (612, 400));
        let (info, buf) = decode(&map.to_png().unwrap());
        assert_eq!((info.width, info.height), (w, h));
        assert_eq!(info.color_type, png::ColorType::Rgba);
        assert_eq!(buf.len(), (w * h * 4) as usize);
        // The peak of the density (bright) follows the mean: column 0 has q=0 at mid-height.
        let px = |x: u32, y: u32| &buf[((y * w + x) * 4) as usize..((y * w + x) * 4 + 4) as usize];
        assert!(
            px(0, h / 2)[1] > px(0, 0)[1],
            "peak should be brighter than the edge"
        );
        assert_eq!(px(0, 0)[3], 255);
    }

    #[test]
    fn large_grids_get_one_pixel_per_cell() {
        let map = Heatmap {
            x: (0..700).map(f64::from).collect(),
            y: (0..5000).map(f64::from).collect(),
            ..Heatmap::default()
        };
        assert_eq!(map.png_size(), (700, 4096));
    }

    #[test]
    fn odd_input_still_gives_a_valid_png_and_svg() {
        let cases = [
            Heatmap::default(),
            Heatmap {
                x: vec![1.0],
                y: vec![f64::NAN, 2.0],
                z: vec![vec![f64::NAN, 3.0]],
                ..Heatmap::default()
            },
            Heatmap {
                x: vec![0.0, 1.0, 3.0],
                y: vec![0.0, 1.0],
                z: vec![vec![0.0, 0.0], vec![0.0]],
                log_scale: true,
                ..Heatmap::default()
            },
            Heatmap {
                x: vec![2.0, 0.0, 1.0],
                y: vec![0.0, 1.0],
                z: vec![vec![1.0; 2]; 3],
                ..Heatmap::default()
            },
        ];
        for (k, map) in cases.iter().enumerate() {
            let (info, _) = decode(&map.to_png().unwrap());
            assert_eq!((info.width, info.height), map.png_size());
            let svg = map.to_svg("h.png");
            assert!(svg.starts_with("<svg "), "{k}");
            assert!(!svg.contains("NaN") && !svg.contains("inf"), "{k}: {svg}");
            assert_eq!(svg.matches("<g").count(), svg.matches("</g>").count());
        }
    }

    #[test]
    fn non_uniform_cells_take_the_nearest_centre() {
        let cells = Cells::new(&[0.0, 1.0, 3.0]);
        assert_eq!((cells.lo, cells.hi), (-0.5, 4.0));
        assert_eq!(cells.at(0.0), Some(0));
        assert_eq!(cells.at(0.5), Some(1)); // 1.75 is nearer 1 than 3
        assert_eq!(cells.at(0.99), Some(2));
        let unsorted = Cells::new(&[2.0, f64::NAN, 0.0]);
        assert_eq!(unsorted.at(0.0), Some(2));
        assert_eq!(unsorted.at(1.0), Some(0));
        assert_eq!(Cells::new(&[]).at(0.5), None);
    }

    #[test]
    fn log_scale_maps_decades_linearly() {
        let s = ColorScale {
            lo: 1e-6,
            hi: 1.0,
            log: true,
        };
        assert_eq!(s.t(0.0), Some(0.0));
        assert!((s.t(1e-3).unwrap() - 0.5).abs() < 1e-12);
        assert_eq!(s.t(f64::NAN), None);
    }

    #[test]
    fn svg_references_png_and_has_colorbar_and_overlay() {
        let map = gaussian_map();
        let svg = map.to_svg("pdf_q.png");
        assert!(svg.contains("href=\"pdf_q.png\""));
        assert!(svg.contains("PDF of q(t)") && svg.contains("PDF [1/m]"));
        assert!(svg.contains("linearGradient"));
        assert!(svg.contains("class=\"legend\""));
        assert_eq!(svg.matches("<g").count(), svg.matches("</g>").count());
    }

    #[test]
    fn colour_scale_starts_at_zero_and_needs_a_positive_value() {
        let mut map = gaussian_map();
        let s = map.color_scale().unwrap();
        assert_eq!(s.lo, 0.0);
        assert!(map.to_svg("x.png").contains(">0</text>"));
        map.z = vec![vec![0.0; 5]; 3];
        assert!(map.color_scale().is_none(), "no density, no scale");
        map.z = vec![vec![f64::NAN; 5]; 3];
        assert!(map.color_scale().is_none());
    }

    #[test]
    fn embedded_svg_carries_the_png() {
        // As the study report embeds it.
        let map = gaussian_map();
        let svg = map.to_svg(&Heatmap::data_uri(&map.to_png().unwrap()));
        assert!(svg.contains("href=\"data:image/png;base64,iVBORw0KGgo"));
    }

    #[test]
    fn base64_matches_rfc4648_vectors() {
        for (input, expected) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(base64(input.as_bytes()), expected);
        }
    }
}
