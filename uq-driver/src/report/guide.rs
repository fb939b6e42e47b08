//! `guide.html`, written beside every report page: the user guide's page "Reading the report"
//! (`docs/src/getting-started/reading-the-report.md`, embedded when uq-driver is built), so
//! that the "how to read it" link under each figure works offline and wherever the folder is
//! copied, with no web address to keep alive.
//!
//! Which section explains a figure is decided from the figure's file name, the names the
//! report gives its plots (`<V>_band.svg`, `<q>_pdf.svg`, ...; the guide page lists them
//! under each heading). Two names serve two kinds of plot: `<x>_pdf.svg` and `<x>_sobol.svg`
//! are an output's plots over time in a section that also shows `<x>_band.svg`, and a scalar
//! quantity's otherwise.

use pulldown_cmark::{html, Event, HeadingLevel, Options, Parser, Tag, TagEnd};

use super::{escape_xml, ReportError};
use std::path::Path;

/// The Markdown source of the page.
const PAGE: &str = include_str!("../../../docs/src/getting-started/reading-the-report.md");

/// The file name the page is written under, beside `index.html`.
pub(crate) const FILE: &str = "guide.html";

const BAND: &str = "Band: mean ± 3σ and quantiles";
const STD: &str = "Standard deviation over time";
const HEATMAP: &str = "Density over time (heat map)";
const SOBOL: &str = "Sobol' indices over time";
const CONVERGENCE: &str = "Convergence";
const SCALAR: &str = "Scalar quantities: density, exceedance, indices";
const SPEED: &str = "Critical speed: signal against speed";
const NESTED: &str = "Two-level (nested) studies";
const SUITES: &str = "Suites and comparisons";
const SCATTER: &str = "Sensitivity from the runs: scatter plots";
const RELIABILITY: &str = "Small probabilities: design point and convergence";
const MORRIS: &str = "Morris screening";

/// The endings of plot file names and the heading that explains them, longest ending first
/// (`_std_diff.svg` before `_std.svg`, `_pdf_compare.svg` before `_pdf.svg`).
const ENDINGS: &[(&str, &str)] = &[
    ("_conditional_exceedance.svg", NESTED),
    ("_conditional_mean.svg", NESTED),
    ("_std_convergence.svg", CONVERGENCE),
    ("_sobol_overall.svg", SOBOL),
    ("_pdf_compare.svg", SUITES),
    ("_mean_vs_runs.svg", SUITES),
    ("_std_vs_runs.svg", SUITES),
    ("_convergence.svg", CONVERGENCE),
    ("_importance.svg", RELIABILITY),
    ("_mean_diff.svg", SUITES),
    ("_std_diff.svg", SUITES),
    ("_std_log.svg", STD),
    ("_scatter.svg", SCATTER),
    ("_bands.svg", SUITES),
    ("_morris.svg", MORRIS),
    ("_split.svg", NESTED),
    ("_band.svg", BAND),
    ("_std.svg", STD),
    ("_pdf.png", HEATMAP),
];

/// The anchor in `guide.html` of the section that explains figure `file`, one of the figures
/// `section_files` of a report section (see the module's documentation).
pub(crate) fn anchor_for(file: &str, section_files: &[String]) -> Option<String> {
    let name = file.rsplit('/').next().unwrap_or(file);
    if let Some((_, heading)) = ENDINGS.iter().find(|(end, _)| name.ends_with(end)) {
        return Some(slug(heading));
    }
    let over_time = |stem: &str| {
        section_files
            .iter()
            .any(|f| f.rsplit('/').next() == Some(&format!("{stem}_band.svg")))
    };
    // An output's plot over time, or a scalar quantity's.
    let of = |stem: &str, over: &'static str| if over_time(stem) { over } else { SCALAR };
    let heading = if let Some(stem) = name.strip_suffix("_pdf.svg") {
        of(stem, HEATMAP)
    } else if let Some(stem) = name.strip_suffix("_sobol.svg") {
        of(stem, SOBOL)
    } else if name.contains("_vs_") && name.ends_with(".svg") {
        SPEED
    } else {
        return None;
    };
    Some(slug(heading))
}

/// A heading's anchor: ASCII letters lower-cased, letters, digits, `-` and `_` kept, white
/// space made `-`, the rest dropped (as mdBook makes them, so that the anchors are those of
/// the published guide).
fn slug(heading: &str) -> String {
    heading
        .chars()
        .filter_map(|c| {
            if c.is_alphanumeric() || c == '-' || c == '_' {
                Some(c.to_ascii_lowercase())
            } else if c.is_whitespace() {
                Some('-')
            } else {
                None
            }
        })
        .collect()
}

/// The page as HTML (rendered once per process: every report page writes it beside itself).
pub(crate) fn to_html() -> &'static str {
    static PAGE_HTML: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    PAGE_HTML.get_or_init(render)
}

/// The page as HTML: headings with their anchors; pictures of the guide (not in a report
/// folder) left out; links to other pages of the guide kept as their text.
fn render() -> String {
    let mut body = String::new();
    let mut heading: Option<(HeadingLevel, String)> = None;
    let mut events = Vec::new();
    let mut skip_image = 0usize;
    let mut links: Vec<bool> = Vec::new();
    for event in Parser::new_ext(PAGE, Options::empty()) {
        match event {
            Event::Start(Tag::Heading { level, .. }) => heading = Some((level, String::new())),
            Event::End(TagEnd::Heading(_)) => {
                if let Some((level, text)) = heading.take() {
                    events.push(Event::Html(
                        format!(
                            "<{level} id=\"{}\">{}</{level}>\n",
                            slug(&text),
                            escape_xml(&text)
                        )
                        .into(),
                    ));
                }
            }
            Event::Text(t) | Event::Code(t) if heading.is_some() => {
                if let Some((_, text)) = heading.as_mut() {
                    text.push_str(&t);
                }
            }
            _ if heading.is_some() => {}
            Event::Start(Tag::Image { .. }) => skip_image += 1,
            Event::End(TagEnd::Image) => skip_image = skip_image.saturating_sub(1),
            _ if skip_image > 0 => {}
            Event::Start(Tag::Link { ref dest_url, .. }) => {
                // A link to another page of the guide would be broken in a report folder:
                // its text stays, the link goes; links within the page and to the web stay.
                let keep = dest_url.starts_with("http") || dest_url.starts_with('#');
                links.push(keep);
                if keep {
                    events.push(event);
                }
            }
            Event::End(TagEnd::Link) => {
                if links.pop().unwrap_or(false) {
                    events.push(event);
                }
            }
            e => events.push(e),
        }
    }
    html::push_html(&mut body, events.into_iter());
    format!(
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n\
         <title>Reading the report</title>\n<style>{}</style>\n</head>\n<body>\n{body}\
         <footer>From the railuq user guide (Getting started: Reading the report), as this \
         uq-driver was built. <a href=\"index.html\">Back to the report</a>.</footer>\n\
         </body>\n</html>\n",
        super::style::CSS
    )
}

/// Writes the page into `dir` as [`FILE`].
pub(crate) fn write(dir: &Path) -> Result<(), ReportError> {
    super::write_bytes(&dir.join(FILE), to_html().as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ids(page: &str) -> Vec<String> {
        page.split(" id=\"")
            .skip(1)
            .filter_map(|s| s.split('"').next())
            .map(str::to_string)
            .collect()
    }

    #[test]
    fn every_plot_ending_points_at_a_heading_of_the_page() {
        let page = to_html();
        let ids = ids(page);
        for (end, heading) in ENDINGS {
            assert!(
                ids.contains(&slug(heading)),
                "{end}: no heading {heading:?}"
            );
        }
        for heading in [SCALAR, SPEED, HEATMAP, SOBOL] {
            assert!(ids.contains(&slug(heading)), "no heading {heading:?}");
        }
    }

    #[test]
    fn a_pdf_or_sobol_plot_beside_a_band_is_over_time_else_a_quantity() {
        let output = vec![
            "q_band.svg".to_string(),
            "q_pdf.svg".into(),
            "q_sobol.svg".into(),
        ];
        assert_eq!(anchor_for("q_pdf.svg", &output), Some(slug(HEATMAP)));
        assert_eq!(anchor_for("q_sobol.svg", &output), Some(slug(SOBOL)));
        let quantity = vec!["q_peak_pdf.svg".to_string(), "q_peak_sobol.svg".into()];
        assert_eq!(anchor_for("q_peak_pdf.svg", &quantity), Some(slug(SCALAR)));
        assert_eq!(
            anchor_for("q_peak_sobol.svg", &quantity),
            Some(slug(SCALAR))
        );
        assert_eq!(anchor_for("y1_vs_v.svg", &[]), Some(slug(SPEED)));
        assert_eq!(anchor_for("q.csv", &[]), None);
    }

    #[test]
    fn the_page_keeps_no_link_to_another_page_of_the_guide_and_no_picture() {
        let page = to_html();
        assert!(!page.contains(".md\""), "a link to a guide page survived");
        assert!(!page.contains("<img"), "a picture of the guide survived");
        assert!(page.contains("Reading the report"));
        assert!(page.contains("<code>&lt;V&gt;_band.svg</code>"));
    }

    #[test]
    fn slugs_are_those_of_mdbook() {
        assert_eq!(slug(BAND), "band-mean--3σ-and-quantiles");
        assert_eq!(slug(SOBOL), "sobol-indices-over-time");
        assert_eq!(slug(NESTED), "two-level-nested-studies");
    }
}
