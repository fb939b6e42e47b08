//! Writers for CSV, JSON, plots and the HTML report.
//!
//! One concept per file:
//! - [`csv`]: column and long-format grid CSV files (full round-trip float precision);
//! - [`svg`]: hand-written SVG line plots (mean, ±3σ bands, differences) and density plots
//!   (PDF curves, histograms, limit markers), with 1-2-5 ticks;
//! - [`heatmap`]: PDF-evolution heat maps as a viridis PNG plus an SVG frame with axes and colorbar;
//! - [`html`]: the self-contained `index.html` that ties the files together;
//! - [`study`]: the files of one study's output folder (one writer per file);
//! - [`nested`]: what a two-level study adds (conditional statistics, the variance split);
//! - [`suite`]: the comparison of a suite's variants;
//! - [`compare`]: one page comparing finished study folders (`uq-driver compare`);
//! - [`units`]: units from the modelDescription, on axes and in `units.csv`;
//! - [`inputs`]: the random inputs as written in a study file.
//!
//! Plots never fail on odd data: empty series, NaN values and zero ranges still give a valid
//! file. Only I/O (and, for CSV, inconsistent column lengths) produce a [`ReportError`].

#![forbid(unsafe_code)]

pub mod compare;
pub mod csv;
mod guide;
pub use crate::text::file_name;
pub mod heatmap;
pub mod html;
pub mod inputs;
pub mod nested;
pub mod study;
mod style;
pub mod suite;
pub mod svg;
pub mod units;

use std::path::{Path, PathBuf};

pub use csv::{write_columns, write_grid};
pub use heatmap::Heatmap;
pub use html::{ReportPage, Section, Table};
pub use study::StudyReport;
pub use svg::{histogram_density, palette, Band, DensityPlot, LinePlot, Series};

/// Errors of the report writers.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// Writing a file failed.
    #[error("cannot write {}", path.display())]
    Io {
        /// The file that could not be written.
        path: PathBuf,
        /// The underlying I/O error.
        #[source]
        source: std::io::Error,
    },
    /// Encoding a PNG image failed.
    #[error("cannot encode PNG {}", path.display())]
    Png {
        /// The image that could not be encoded.
        path: PathBuf,
        /// The underlying encoder error.
        #[source]
        source: png::EncodingError,
    },
    /// Two inputs that must have the same length do not.
    #[error("{}: {what} has {len} values, expected {expected}", path.display())]
    LengthMismatch {
        /// The file that was to be written.
        path: PathBuf,
        /// Which input is inconsistent (e.g. `column 2 ("std")`).
        what: String,
        /// Its length.
        len: usize,
        /// The length it should have.
        expected: usize,
    },
}

/// Writes `bytes` to `path`, attaching the path to any I/O error; never through a symbolic
/// link, never half-written (the `out-file` crate).
pub fn write_bytes(path: &Path, bytes: &[u8]) -> Result<(), ReportError> {
    out_file::write(path, bytes).map_err(|source| ReportError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// Escapes text for HTML/SVG element content and attribute values (`&`, `<`, `>`, `"`, `'`).
pub(crate) fn escape_xml(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            // Control characters other than tab/newline are not allowed in XML 1.0.
            c if (c as u32) < 0x20 && c != '\t' && c != '\n' && c != '\r' => out.push('\u{fffd}'),
            c => out.push(c),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escape_xml_escapes_markup_and_quotes() {
        assert_eq!(
            escape_xml(r#"<a href="x">'&'</a>"#),
            "&lt;a href=&quot;x&quot;&gt;&#39;&amp;&#39;&lt;/a&gt;"
        );
        assert_eq!(escape_xml("a\u{1}b"), "a\u{fffd}b");
    }

    /// Renders example plots, a heat map and an index page for looking at by eye:
    /// `REPORT_DEMO_DIR=/tmp/report-demo cargo test -p uq-driver --lib -- --ignored render_demo`.
    #[test]
    #[ignore = "writes demo files for visual inspection"]
    fn render_demo() {
        let dir = std::env::var_os("REPORT_DEMO_DIR")
            .map(PathBuf::from)
            .unwrap_or_else(|| std::env::temp_dir().join("report-demo"));
        std::fs::create_dir_all(&dir).unwrap();

        let t: Vec<f64> = (0..=500).map(|i| i as f64 * 0.01).collect();
        let mean: Vec<f64> = t
            .iter()
            .map(|t| 0.004 * (2.0 * std::f64::consts::PI * 1.1 * t).sin() * (-0.25 * t).exp())
            .collect();
        let sd: Vec<f64> = t.iter().map(|t| 2e-4 + 3e-4 * t).collect();
        let band = |k: f64| -> Vec<f64> { mean.iter().zip(&sd).map(|(m, s)| m + k * s).collect() };
        let lhs: Vec<f64> = mean
            .iter()
            .zip(&t)
            .map(|(m, t)| m * 1.02 + 2e-5 * (9.0 * t).cos())
            .collect();
        let plot = LinePlot {
            title: "Lateral displacement q(t): mean ± 3σ".into(),
            x_label: "time [s]".into(),
            y_label: "q [m]".into(),
            bands: vec![Band::new(
                "SGM mean ± 3σ",
                t.clone(),
                band(-3.0),
                band(3.0),
                palette(0),
            )],
            series: vec![
                Series::new("SGM mean", t.clone(), mean.clone(), palette(0)),
                Series::new("LHS mean", t.clone(), lhs.clone(), palette(1)).dashed(),
            ],
            ..LinePlot::default()
        };
        plot.write(&dir.join("q_band.svg")).unwrap();
        let diff: Vec<f64> = mean.iter().zip(&lhs).map(|(a, b)| a - b).collect();
        LinePlot {
            series: vec![Series::new("SGM − LHS", t.clone(), diff, palette(3))],
            ..LinePlot::new("Difference of means", "time [s]", "Δq [m]")
        }
        .write(&dir.join("q_diff.svg"))
        .unwrap();
        LinePlot {
            series: vec![Series::new("Std", t.clone(), sd.clone(), palette(2))],
            log_y: true,
            ..LinePlot::new("Standard deviation (log)", "time [s]", "Std q [m]")
        }
        .write(&dir.join("q_std_log.svg"))
        .unwrap();

        let samples: Vec<f64> = (0..2000)
            .map(|i| {
                let u = (i as f64 + 0.5) / 2000.0;
                2.1 + 0.25 * (u * 12.0 - 6.0).tanh() + 0.05 * (i as f64 * 1.7).sin()
            })
            .collect();
        let x: Vec<f64> = (0..=300).map(|i| 1.6 + i as f64 * 0.004).collect();
        let pdf: Vec<f64> = x
            .iter()
            .map(|x| (-(x - 2.1f64).powi(2) / (2.0 * 0.16f64.powi(2))).exp() / (0.16 * 2.5066))
            .collect();
        DensityPlot {
            title: "Sperling ride index W".into(),
            x_label: "W [-]".into(),
            curves: vec![Series::new("Gaussian fit", x, pdf, palette(0))],
            histogram: Some(histogram_density(&samples, 0)),
            markers: vec![(2.5, "limit W = 2.5".into())],
        }
        .write(&dir.join("sperling_pdf.svg"))
        .unwrap();

        let grid: Vec<f64> = (0..160).map(|j| -0.02 + 0.04 * j as f64 / 159.0).collect();
        let z: Vec<Vec<f64>> = (0..t.len())
            .step_by(5)
            .map(|i| {
                grid.iter()
                    .map(|q| {
                        let u = (q - mean[i]) / sd[i];
                        (-0.5 * u * u).exp() / (sd[i] * 2.5066)
                    })
                    .collect()
            })
            .collect();
        let ts: Vec<f64> = t.iter().step_by(5).copied().collect();
        let map = Heatmap {
            title: "PDF of q over time".into(),
            x_label: "time [s]".into(),
            y_label: "q [m]".into(),
            x: ts,
            y: grid.clone(),
            z,
            colorbar_label: "PDF [1/m]".into(),
            overlay: vec![
                Series::new("mean", t.clone(), mean.clone(), "#ffffff"),
                Series::new("mean ± 3σ", t.clone(), band(3.0), "#ff7f0e").dashed(),
                Series::new("", t.clone(), band(-3.0), "#ff7f0e").dashed(),
            ],
            log_scale: false,
        };
        let png = map.to_png().unwrap();
        write_bytes(&dir.join("q_pdf.png"), &png).unwrap();
        write_bytes(&dir.join("q_pdf.svg"), map.to_svg("q_pdf.png").as_bytes()).unwrap();
        let embedded = map.to_svg(&Heatmap::data_uri(&png));
        write_bytes(&dir.join("q_pdf_embedded.svg"), embedded.as_bytes()).unwrap();
        let log_map = Heatmap {
            log_scale: true,
            title: "PDF of q over time (log colour)".into(),
            ..map.clone()
        };
        let log_png = log_map.to_png().unwrap();
        let log_svg = log_map.to_svg(&Heatmap::data_uri(&log_png));
        write_bytes(&dir.join("q_pdf_log.svg"), log_svg.as_bytes()).unwrap();

        csv::write_columns(
            &dir.join("q_stats.csv"),
            &["time", "mean", "std"],
            &[&t, &mean, &sd],
        )
        .unwrap();
        ReportPage {
            title: "railuq demo report".into(),
            summary_json: r#"{"study":"demo","method":"sgm","runs":64}"#.into(),
            sections: vec![
                Section {
                    heading: "Lateral displacement".into(),
                    text: "Mean and ±3σ band of q(t).".into(),
                    images: vec![
                        "q_band.svg".into(),
                        "q_diff.svg".into(),
                        "q_std_log.svg".into(),
                        "q_stats.csv".into(),
                    ],
                    table: None,
                },
                Section {
                    heading: "PDF evolution".into(),
                    text: String::new(),
                    images: vec!["q_pdf_embedded.svg".into(), "q_pdf_log.svg".into()],
                    table: None,
                },
                Section {
                    heading: "Sperling index".into(),
                    text: String::new(),
                    images: vec!["sperling_pdf.svg".into()],
                    table: Some(Table {
                        header: vec!["quantity".into(), "mean".into(), "P(W > 2.5)".into()],
                        rows: vec![vec!["W".into(), "2.10".into(), "0.012".into()]],
                    }),
                },
            ],
        }
        .write(&dir.join("index.html"))
        .unwrap();
    }

    #[test]
    fn io_error_names_the_path() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("missing-dir").join("x.csv");
        let err = write_bytes(&path, b"x").unwrap_err();
        assert!(err.to_string().contains("missing-dir"), "{err}");
    }
}
