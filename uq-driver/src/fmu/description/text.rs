//! Checks on the raw bytes of `modelDescription.xml` before any XML parsing (size, encoding,
//! NUL bytes), and line numbers of byte offsets computed in one forward pass.

use super::{DescriptionError, ParseLimits};

/// The UTF-8 byte-order mark, allowed (and skipped) at the start.
const UTF8_BOM: &[u8] = b"\xEF\xBB\xBF";

/// Checks size and encoding; returns the document without its UTF-8 byte-order mark.
///
/// FMI 2.0 requires modelDescription.xml in UTF-8, so UTF-16 and UTF-32 files, invalid UTF-8 and non-ASCII text under another declared encoding are refused
/// by name. XML 1.0 forbids U+0000 anywhere, and a NUL would cut a name short where FMI passes
/// it to C, so NUL bytes are refused too.
pub(super) fn check<'x>(xml: &'x [u8], limits: &ParseLimits) -> Result<&'x [u8], DescriptionError> {
    if xml.len() > limits.max_bytes {
        return Err(DescriptionError::TooLarge {
            size: xml.len(),
            limit: limits.max_bytes,
        });
    }
    if let Some(found) = wide_encoding(xml) {
        return Err(DescriptionError::NotUtf8 {
            found: found.into(),
        });
    }
    let xml = xml.strip_prefix(UTF8_BOM).unwrap_or(xml);
    if let Err(e) = std::str::from_utf8(xml) {
        let at = e.valid_up_to();
        let (line, column) = line_col(xml, at);
        return Err(DescriptionError::NotUtf8 {
            found: format!(
                "byte 0x{:02X} at line {line}, column {column} is not valid UTF-8",
                xml[at]
            ),
        });
    }
    // `contains` is a word-at-a-time memchr; the position is only needed for the message.
    if let Some(at) = xml
        .contains(&0)
        .then(|| xml.iter().position(|&b| b == 0))
        .flatten()
    {
        let (line, column) = line_col(xml, at);
        return Err(DescriptionError::Malformed {
            line,
            column,
            reason: "NUL byte (XML 1.0 forbids U+0000 anywhere in a document; in a name it \
                     would cut the name short where FMI passes it to C)"
                .into(),
        });
    }
    if let Some(declared) = declared_encoding(xml) {
        let utf8 = declared.eq_ignore_ascii_case("utf-8") || declared.eq_ignore_ascii_case("utf8");
        let non_ascii = || xml.iter().position(|b| !b.is_ascii());
        if let (false, Some(at)) = (utf8, (!utf8 && !xml.is_ascii()).then(non_ascii).flatten()) {
            // ASCII reads the same in every encoding that could be declared here; anything
            // else would be read differently from what the declaration says.
            let (line, column) = line_col(xml, at);
            return Err(DescriptionError::NotUtf8 {
                found: format!(
                    "it declares encoding=\"{declared}\" and has non-ASCII text (first at line \
                     {line}, column {column})"
                ),
            });
        }
    }
    Ok(xml)
}

/// Recognises UTF-16 and UTF-32 by their byte-order mark or by the NUL bytes around the
/// first `<` (XML 1.0, appendix F).
fn wide_encoding(xml: &[u8]) -> Option<&'static str> {
    Some(match xml {
        [0x00, 0x00, 0xFE, 0xFF, ..] => "it is UTF-32 (big-endian byte-order mark)",
        [0xFF, 0xFE, 0x00, 0x00, ..] => "it is UTF-32 (little-endian byte-order mark)",
        [0xFE, 0xFF, ..] => "it is UTF-16 (big-endian byte-order mark)",
        [0xFF, 0xFE, ..] => "it is UTF-16 (little-endian byte-order mark)",
        [0x00, 0x00, 0x00, b'<', ..] => "it looks like UTF-32 big-endian",
        [b'<', 0x00, 0x00, 0x00, ..] => "it looks like UTF-32 little-endian",
        [0x00, b'<', ..] => "it looks like UTF-16 big-endian",
        [b'<', 0x00, ..] => "it looks like UTF-16 little-endian",
        _ => {
            // Leading whitespace before the first `<`: many NULs early on mean UTF-16/32.
            let head = &xml[..xml.len().min(64)];
            let nuls = head.iter().filter(|&&b| b == 0).count();
            if head.len() >= 8 && nuls * 4 >= head.len() {
                "it looks like UTF-16 or UTF-32 (NUL bytes between the characters)"
            } else {
                return None;
            }
        }
    })
}

/// The `encoding` of the XML declaration (`<?xml version="1.0" encoding="..."?>`), if any.
fn declared_encoding(xml: &[u8]) -> Option<&str> {
    let rest = xml.strip_prefix(b"<?xml")?;
    let end = rest.windows(2).take(1024).position(|w| w == b"?>")?;
    let decl = std::str::from_utf8(&rest[..end]).ok()?;
    let after = &decl[decl.find("encoding")? + "encoding".len()..];
    let after = after.trim_start().strip_prefix('=')?.trim_start();
    let quote = after.chars().next().filter(|c| *c == '"' || *c == '\'')?;
    let value = &after[1..];
    Some(&value[..value.find(quote)?])
}

/// 1-based line and column (in bytes) of byte offset `pos`, by one scan from the start: for
/// error messages only.
pub(super) fn line_col(xml: &[u8], pos: usize) -> (usize, usize) {
    let before = &xml[..pos.min(xml.len())];
    let line = count_newlines(before) + 1;
    let line_start = before
        .iter()
        .rposition(|&b| b == b'\n')
        .map_or(0, |i| i + 1);
    (line, before.len() - line_start + 1)
}

fn count_newlines(bytes: &[u8]) -> usize {
    bytes.iter().filter(|&&b| b == b'\n').count()
}

/// Line numbers of increasing byte offsets, each newline counted once: linear in the file.
pub(super) struct Lines<'a> {
    xml: &'a [u8],
    pos: usize,
    line: usize,
}

impl<'a> Lines<'a> {
    pub(super) fn new(xml: &'a [u8]) -> Self {
        Lines {
            xml,
            pos: 0,
            line: 1,
        }
    }

    /// The 1-based line of byte offset `pos`. Offsets are expected in increasing order; an
    /// earlier one is still answered correctly, by a scan from the start.
    pub(super) fn line_at(&mut self, pos: usize) -> usize {
        let pos = pos.min(self.xml.len());
        if pos < self.pos {
            return line_col(self.xml, pos).0;
        }
        self.line += count_newlines(&self.xml[self.pos..pos]);
        self.pos = pos;
        self.line
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_match_a_rescan_from_the_start() {
        let xml = b"a\nbc\n\nd\ne";
        let mut lines = Lines::new(xml);
        for pos in 0..=xml.len() + 2 {
            assert_eq!(lines.line_at(pos), line_col(xml, pos).0, "{pos}");
        }
        assert_eq!(lines.line_at(2), 2, "going back still answers");
        assert_eq!(line_col(xml, 3), (2, 2));
    }

    #[test]
    fn declared_encoding_is_read() {
        assert_eq!(
            declared_encoding(b"<?xml version=\"1.0\" encoding=\"ISO-8859-1\"?><a/>"),
            Some("ISO-8859-1")
        );
        assert_eq!(
            declared_encoding(b"<?xml version='1.0' encoding = 'utf-8' ?>"),
            Some("utf-8")
        );
        assert_eq!(declared_encoding(b"<?xml version=\"1.0\"?><a/>"), None);
        assert_eq!(declared_encoding(b"<a encoding=\"x\"/>"), None);
        assert_eq!(declared_encoding(b"<?xml encoding=\"x"), None);
    }
}
