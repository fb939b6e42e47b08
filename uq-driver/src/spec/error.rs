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
