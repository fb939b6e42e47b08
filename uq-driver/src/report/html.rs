//! The report's `index.html`: one self-contained page (inline CSS, no scripts) with a table of
//! contents, sections of text, figures and tables, and a link to the run's `summary.json`.

use std::fmt::Write as _;
use std::path::Path;

use super::{escape_xml, write_bytes, ReportError};

/// The whole report page.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ReportPage {
    /// Page title and top heading.
    pub title: String,
    /// The run summary, written beside the page as `summary.json`: the page links that file
    /// (relative link) instead of pasting it; no link if empty.
    pub summary_json: String,
    /// Sections in order.
    pub sections: Vec<Section>,
}

/// One section of the page.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Section {
    /// Section heading.
    pub heading: String,
    /// Plain text; blank lines separate paragraphs.
    pub text: String,
    /// Figures as file names relative to the page (`.svg`, `.png`, …); other files (e.g.
    /// `.csv`) become download links.
    pub images: Vec<String>,
    /// An optional table.
    pub table: Option<Table>,
}

/// A table of text cells.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Table {
    /// Column headings.
    pub header: Vec<String>,
    /// Rows of cells; rows may be shorter or longer than the header.
    pub rows: Vec<Vec<String>>,
}

pub(super) const CSS: &str = "\
body{font-family:system-ui,-apple-system,'Segoe UI',Helvetica,Arial,sans-serif;color:#222;\
max-width:1100px;margin:0 auto;padding:24px;line-height:1.5;background:#fafafa}\
h1{font-size:1.7em;border-bottom:2px solid #ddd;padding-bottom:.3em}\
h2{font-size:1.3em;margin-top:2em;border-bottom:1px solid #e4e4e4;padding-bottom:.2em}\
nav ul{columns:2;padding-left:1.2em}\
figure{margin:1em 0;background:#fff;border:1px solid #e4e4e4;padding:8px;display:inline-block;\
max-width:100%;box-sizing:border-box;vertical-align:top}\
figure img{max-width:100%;height:auto;display:block}\
figcaption{font-size:.85em;color:#666;margin-top:4px}\
table{border-collapse:collapse;margin:1em 0;background:#fff;font-size:.92em}\
th,td{border:1px solid #ddd;padding:4px 10px;text-align:left}\
th{background:#f0f0f0}tr:nth-child(even) td{background:#f8f8f8}\
td.num{text-align:right;font-variant-numeric:tabular-nums}\
pre{background:#fff;border:1px solid #e4e4e4;padding:12px;overflow:auto;font-size:.85em}\
footer{margin-top:3em;color:#888;font-size:.8em}";

impl ReportPage {
    /// Renders the page as HTML; all text is escaped.
    pub fn to_html(&self) -> String {
        let mut out = String::new();
        let title = escape_xml(&self.title);
        let _ = write!(
            out,
            "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
             <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n\
             <title>{title}</title>\n<style>{CSS}</style>\n</head>\n<body>\n<h1>{title}</h1>\n"
        );
        let has_summary = !self.summary_json.trim().is_empty();
        if !self.sections.is_empty() {
            out.push_str("<nav>\n<ul>\n");
            for (i, s) in self.sections.iter().enumerate() {
                let _ = writeln!(
                    out,
                    "<li><a href=\"#s{}\">{}</a></li>",
                    i + 1,
                    escape_xml(&s.heading)
                );
            }
            if has_summary {
                out.push_str("<li><a href=\"#summary\">Summary file</a></li>\n");
            }
            out.push_str("</ul>\n</nav>\n");
        }
        for (i, s) in self.sections.iter().enumerate() {
            let _ = writeln!(
                out,
                "<section id=\"s{}\">\n<h2>{}</h2>",
                i + 1,
                escape_xml(&s.heading)
            );
            for para in paragraphs(&s.text) {
                let _ = writeln!(out, "<p>{}</p>", escape_xml(&para));
            }
            if let Some(t) = &s.table {
                push_table(&mut out, t);
            }
            let mut links = Vec::new();
            for file in &s.images {
                let src = escape_xml(&url_path(file));
                let name = escape_xml(file);
                if is_image(file) {
                    // The guide's section on this kind of plot (guide.html, written beside).
                    let how = super::guide::anchor_for(file, &s.images)
                        .map(|a| {
                            format!(
                                " · <a href=\"{}#{}\">how to read it</a>",
                                super::guide::FILE,
                                escape_xml(&a)
                            )
                        })
                        .unwrap_or_default();
                    let _ = writeln!(
                        out,
                        "<figure><a href=\"{src}\"><img src=\"{src}\" alt=\"{name}\" \
                         loading=\"lazy\"></a><figcaption>{name}{how}</figcaption></figure>"
                    );
                } else {
                    links.push(format!("<a href=\"{src}\">{name}</a>"));
                }
            }
            if !links.is_empty() {
                let _ = writeln!(out, "<p>Files: {}</p>", links.join(", "));
            }
            out.push_str("</section>\n");
        }
        if has_summary {
            out.push_str(
                "<section id=\"summary\">\n<h2>Summary file</h2>\n<p>Every number of this page, \
                 the study and the FMU it ran, machine-readable: \
                 <a href=\"summary.json\">summary.json</a> (beside this page).</p>\n</section>\n",
            );
        }
        out.push_str("<footer>Generated by uq-driver.</footer>\n</body>\n</html>\n");
        out
    }

    /// Writes [`Self::to_html`] to `path` (usually `<out>/index.html`), and beside it
    /// `guide.html`, the guide's page on reading the report, which the figures link to.
    pub fn write(&self, path: &Path) -> Result<(), ReportError> {
        write_bytes(path, self.to_html().as_bytes())?;
        match path.parent() {
            Some(dir) => super::guide::write(if dir.as_os_str().is_empty() {
                Path::new(".")
            } else {
                dir
            }),
            None => Ok(()),
        }
    }
}

fn push_table(out: &mut String, t: &Table) {
    out.push_str("<table>\n");
    if !t.header.is_empty() {
        out.push_str("<thead><tr>");
        for h in &t.header {
            let _ = write!(out, "<th>{}</th>", escape_xml(h));
        }
        out.push_str("</tr></thead>\n");
    }
    out.push_str("<tbody>\n");
    for row in &t.rows {
        out.push_str("<tr>");
        for cell in row {
            let class = if looks_numeric(cell) {
                " class=\"num\""
            } else {
                ""
            };
            let _ = write!(out, "<td{class}>{}</td>", escape_xml(cell));
        }
        out.push_str("</tr>\n");
    }
    out.push_str("</tbody>\n</table>\n");
}

fn looks_numeric(cell: &str) -> bool {
    let t = cell.trim();
    !t.is_empty() && t.parse::<f64>().is_ok()
}

/// Paragraphs of `text`, split on blank lines.
fn paragraphs(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut cur: Vec<&str> = Vec::new();
    for line in text.lines() {
        if line.trim().is_empty() {
            if !cur.is_empty() {
                out.push(cur.join("\n"));
                cur.clear();
            }
        } else {
            cur.push(line);
        }
    }
    if !cur.is_empty() {
        out.push(cur.join("\n"));
    }
    out
}

fn is_image(file: &str) -> bool {
    let lower = file.to_ascii_lowercase();
    [".svg", ".png", ".jpg", ".jpeg", ".gif", ".webp"]
        .iter()
        .any(|ext| lower.ends_with(ext))
}

/// Percent-encodes a relative file name for use as a URL path: only unreserved characters and
/// `/` pass, so a name can never become a `javascript:` URL or break out of the attribute.
fn url_path(file: &str) -> String {
    let mut out = String::with_capacity(file.len());
    for b in file.bytes() {
        if b.is_ascii_alphanumeric() || matches!(b, b'-' | b'_' | b'.' | b'~' | b'/') {
            out.push(b as char);
        } else {
            let _ = write!(out, "%{b:02X}");
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn page() -> ReportPage {
        ReportPage {
            title: "Study <script>alert(1)</script>".into(),
            summary_json: r#"{"n_runs":64,"method":"sgm","note":"</pre><script>"}"#.into(),
            sections: vec![
                Section {
                    heading: "Lateral displacement".into(),
                    text: "Mean & std of q.\n\nSecond <para>.".into(),
                    images: vec!["q_band.svg".into(), "pdf q.png".into(), "q.csv".into()],
                    table: Some(Table {
                        header: vec!["method".into(), "mean".into()],
                        rows: vec![vec!["SGM".into(), "0.0123".into()], vec!["<i>".into()]],
                    }),
                },
                Section {
                    heading: "Empty".into(),
                    ..Section::default()
                },
            ],
        }
    }

    #[test]
    fn html_escapes_script_everywhere() {
        let html = page().to_html();
        assert!(html.starts_with("<!DOCTYPE html>"));
        assert!(!html.contains("<script>"), "{html}");
        assert!(html.contains("Study &lt;script&gt;alert(1)&lt;/script&gt;"));
        assert!(html.contains("<td>&lt;i&gt;</td>"));
        assert!(html.contains("Second &lt;para&gt;."));
    }

    #[test]
    fn html_has_figures_tables_links_and_pretty_json() {
        let html = page().to_html();
        assert!(html.contains("<img src=\"q_band.svg\""));
        assert!(html.contains("<img src=\"pdf%20q.png\""));
        assert!(html.contains("<a href=\"q.csv\">q.csv</a>"));
        assert!(html.contains("<th>method</th>"));
        assert!(html.contains("<td class=\"num\">0.0123</td>"));
        assert!(
            html.contains("<a href=\"summary.json\">summary.json</a>"),
            "{html}"
        );
        assert!(html.contains("href=\"#s2\""));
        assert_eq!(html.matches("<section").count(), 3);
        // The two paragraphs and the files of the first section, the summary file's link.
        assert_eq!(html.matches("<p>").count(), 4);
    }

    /// Every report page ended with the whole summary.json pasted in (77 % of its bytes).
    #[test]
    fn the_page_links_summary_json_instead_of_pasting_it() {
        let html = page().to_html();
        assert!(!html.contains("<pre>"), "{html}");
        assert!(!html.contains("n_runs") && !html.contains("sgm"), "{html}");
        assert_eq!(html.matches("href=\"summary.json\"").count(), 1);
        let mut p = page();
        p.summary_json.clear();
        assert!(!p.to_html().contains("summary.json"));
    }

    #[test]
    fn image_names_cannot_inject_urls() {
        assert_eq!(url_path("javascript:alert(1)"), "javascript%3Aalert%281%29");
        assert_eq!(url_path("sub/a\"b.svg"), "sub/a%22b.svg");
    }

    #[test]
    fn write_creates_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("index.html");
        page().write(&path).unwrap();
        assert!(std::fs::read_to_string(&path).unwrap().contains("</html>"));
    }
}
