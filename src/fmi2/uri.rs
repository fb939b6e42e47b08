//! Resource-location URIs as importers pass them to fmi2Instantiate.

use std::path::PathBuf;

/// Converts a `file:` URI to a path. Accepts `file:///p`, `file:/p` and `file://localhost/p`,
/// with percent-encoding; returns None for other schemes or malformed escapes. On Windows a
/// drive letter loses the slash before it (`file:///C:/x` is `C:/x`).
pub fn file_uri_to_path(uri: &str) -> Option<PathBuf> {
    uri_path(uri, cfg!(windows)).map(PathBuf::from)
}

/// The decoded path of a `file:` URI; `windows` drops the `/` before a drive letter.
fn uri_path(uri: &str, windows: bool) -> Option<String> {
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
    let b = s.as_bytes();
    let drive = b.len() >= 3
        && b[1].is_ascii_alphabetic()
        && b[2] == b':'
        && (b.len() == 3 || b[3] == b'/' || b[3] == b'\\');
    Some(if windows && drive {
        s[1..].to_owned()
    } else {
        s
    })
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

    #[test]
    fn windows_drive_letter_uris_lose_the_leading_slash() {
        let p = Some("C:/Users/a b/resources".to_owned());
        assert_eq!(uri_path("file:///C:/Users/a%20b/resources", true), p);
        assert_eq!(uri_path("file:/C:/Users/a%20b/resources", true), p);
        assert_eq!(
            uri_path("file://localhost/C:/Users/a%20b/resources", true),
            p
        );
        assert_eq!(uri_path("file:///Z:", true), Some("Z:".to_owned()));
        // Not a drive: kept as it is; on other systems the slash stays.
        assert_eq!(uri_path("file:///CD:/x", true), Some("/CD:/x".to_owned()));
        assert_eq!(uri_path("file:///C:/x", false), Some("/C:/x".to_owned()));
    }
}
