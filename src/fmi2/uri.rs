//! Resource-location URIs as importers pass them to fmi2Instantiate.

use std::path::PathBuf;

/// Converts a `file:` URI to a path. Accepts `file:///p`, `file:/p` and `file://localhost/p`,
/// with percent-encoding; returns None for other schemes or malformed escapes.
pub fn file_uri_to_path(uri: &str) -> Option<PathBuf> {
    let rest = uri
        .strip_prefix("file://localhost/")
        .map(|r| format!("/{r}"))
        .or_else(|| uri.strip_prefix("file:///").map(|r| format!("/{r}")))
        .or_else(|| {
            uri.strip_prefix("file:/")
                .filter(|r| !r.starts_with('/'))
                .map(|r| format!("/{r}"))
        })?;
    let bytes = rest.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = std::str::from_utf8(bytes.get(i + 1..i + 3)?).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    let s = String::from_utf8(out).ok()?;
    Some(PathBuf::from(s))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn accepts_the_forms_importers_send() {
        let p = Some(PathBuf::from("/tmp/my fmu/resources"));
        assert_eq!(file_uri_to_path("file:///tmp/my%20fmu/resources"), p);
        assert_eq!(file_uri_to_path("file:/tmp/my%20fmu/resources"), p);
        assert_eq!(
            file_uri_to_path("file://localhost/tmp/my%20fmu/resources"),
            p
        );
        assert_eq!(file_uri_to_path("http://x/y"), None);
        assert_eq!(file_uri_to_path("file:///bad%2"), None);
        assert_eq!(file_uri_to_path("file:///bad%zz"), None);
    }
}
