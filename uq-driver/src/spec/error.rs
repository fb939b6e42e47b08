//! Errors in a study file, with the place in the file where it has one.

use std::ops::Range;
use std::path::PathBuf;

/// A line and column (1-based) in a study file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Location {
    /// Line.
    pub line: usize,
    /// Column (in characters).
    pub column: usize,
}

impl Location {
    /// The location of byte `offset` of `text`.
    pub fn of(text: &str, offset: usize) -> Location {
        let before = &text[..offset.min(text.len())];
        let line_start = before.rfind('\n').map_or(0, |i| i + 1);
        Location {
            line: before.matches('\n').count() + 1,
            column: before[line_start..].chars().count() + 1,
        }
    }
}

impl std::fmt::Display for Location {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}:{}", self.line, self.column)
    }
}

/// Errors in a study file.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum StudyError {
    /// The file could not be read.
    #[error("cannot read {}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// TOML syntax, a missing or unknown key, a wrong type.
    #[error("{origin}:{at}: {message}")]
    Parse {
        /// File or builtin name.
        origin: String,
        /// Where.
        at: Location,
        /// What the parser says.
        message: String,
    },
    /// A value that parses but makes no sense.
    #[error("{origin}{}: {message}", at.map(|l| format!(":{l}")).unwrap_or_default())]
    Invalid {
        /// File or builtin name (and variant).
        origin: String,
        /// Where, when known.
        at: Option<Location>,
        /// What is wrong.
        message: String,
    },
    /// No built-in study of that name.
    #[error("no built-in study '{0}' (see `uq-driver list`)")]
    UnknownBuiltin(String),
}

/// The location of the start of `span` in `text`.
pub(super) fn location(text: &str, span: Range<usize>) -> Location {
    Location::of(text, span.start)
}

/// Where a TOML error of `text` is: for ``unknown field `X` `` the key `X` itself, found in
/// the table the parser names by `span` (a tagged table such as `[method]` is read as a
/// whole, so toml's own span is that of the table); otherwise the start of `span`.
pub(super) fn parse_error_location(
    text: &str,
    span: Option<Range<usize>>,
    message: &str,
) -> Location {
    let span = span.unwrap_or(0..0);
    const UNKNOWN: &str = "unknown field `";
    let key = message
        .find(UNKNOWN)
        .and_then(|i| message[i + UNKNOWN.len()..].split_once('`'))
        .map(|(k, _)| k);
    let at = key
        .and_then(|k| key_span(text, k, &span))
        .unwrap_or(span.start);
    Location::of(text, at)
}

/// The first key named `name` inside `within` (a table's span) of the TOML `text`, or
/// after its start.
fn key_span(text: &str, name: &str, within: &Range<usize>) -> Option<usize> {
    let doc = toml_edit::ImDocument::parse(text).ok()?;
    let mut found = Vec::new();
    keys_named(doc.as_table(), name, &mut found);
    found.sort_unstable();
    // Within the span; else (an array of tables is spanned by its first header) the first
    // after its start.
    let after = found.iter().copied().filter(|&k| k >= within.start);
    after
        .clone()
        .find(|&k| k < within.end)
        .or_else(|| after.min())
}

/// The start of every key named `name` in `table` and the tables below it.
fn keys_named(table: &dyn toml_edit::TableLike, name: &str, out: &mut Vec<usize>) {
    for (key, item) in table.iter() {
        if key == name {
            if let Some(s) = table.key(key).and_then(toml_edit::Key::span) {
                out.push(s.start);
            }
        }
        match item {
            toml_edit::Item::Table(t) => keys_named(t, name, out),
            toml_edit::Item::ArrayOfTables(a) => {
                for t in a.iter() {
                    keys_named(t, name, out);
                }
            }
            toml_edit::Item::Value(v) => value_keys_named(v, name, out),
            toml_edit::Item::None => {}
        }
    }
}

fn value_keys_named(value: &toml_edit::Value, name: &str, out: &mut Vec<usize>) {
    match value {
        toml_edit::Value::InlineTable(t) => keys_named(t, name, out),
        toml_edit::Value::Array(a) => {
            for v in a.iter() {
                value_keys_named(v, name, out);
            }
        }
        _ => {}
    }
}
