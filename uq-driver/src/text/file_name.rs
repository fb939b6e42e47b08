//! File names made from variable and quantity names.
//!
//! An output's files are named after the variable (`<V>.csv`, `<V>_pdf.svg`, ...), but a
//! variable name comes from the FMU (or the study file) and may be anything: `../../x`,
//! `/tmp/x`, `a/b`, or `points` (whose `points.csv` would overwrite the design's). [`stem`]
//! maps a name to the stem of its files:
//! - an ordinary name is kept as it is (letters, digits, `_ . [ ] ( ) , + -`, spaces, any
//!   non-ASCII letter: `body.frame_a.r_0[1]` → `body.frame_a.r_0[1]`);
//! - `%`, `/`, `\`, control characters and the characters Windows does not allow in file
//!   names (`: * ? " < > |`) are percent-encoded as their UTF-8 bytes (`a/b` → `a%2Fb`,
//!   `../x` → `%2E.%2Fx`), and so is a leading `.` (no hidden files, never `.` or `..`);
//! - a name equal to one of the folder's own file stems ([`RESERVED`]: `points`, `units`,
//!   ...) has its first character encoded (`points` → `%70oints`);
//! - a stem longer than [`MAX_STEM`] bytes is cut and ended by `%~` and 16 hex digits of the
//!   name's SHA-256.
//!
//! Percent-decoding a stem (other than a cut one) gives the name back, so two names never
//! share a stem. Two names can still share a file when one name is another plus a file
//! suffix (`x` writes `x_pdf.csv`, and so would an output named `x_pdf`):
//! [`check_distinct`] finds that when the study is loaded, before any run.

use std::fmt::Write as _;

use sha2::{Digest, Sha256};

/// Stems of the files a study, plan, suite or comparison folder has of its own: a variable
/// with such a name has its first character encoded.
pub const RESERVED: &[&str] = &[
    "points",
    "units",
    "summary",
    "index",
    "design",
    "plan",
    "runs",
    "store",
    "surrogate",
    "variance_split",
    "manifest",
    "uq-driver",
];

/// Longest stem kept whole (bytes): the longest suffix (`_std_convergence.svg`) and the
/// temporary file's name still fit the usual 255-byte limit.
pub const MAX_STEM: usize = 200;

/// Suffixes of the files written for a variable or quantity (before the extension).
const SUFFIXES: &[&str] = &[
    "",
    "_pdf",
    "_band",
    "_sobol",
    "_sobol_overall",
    "_convergence",
    "_std_convergence",
    "_samples",
    "_split",
    "_conditional",
    "_conditional_mean",
    "_conditional_exceedance",
    "_bands",
    "_std",
    "_compare",
    "_std_diff",
    "_mean_diff",
    "_pdf_compare",
    "_mean_vs_runs",
    "_std_vs_runs",
];

fn must_encode(c: char) -> bool {
    c.is_control()
        || matches!(
            c,
            '%' | '/' | '\\' | ':' | '*' | '?' | '"' | '<' | '>' | '|'
        )
}

fn encode(out: &mut String, c: char) {
    let mut buf = [0; 4];
    for b in c.encode_utf8(&mut buf).bytes() {
        let _ = write!(out, "%{b:02X}");
    }
}

/// The stem of the files of the variable or quantity `name` (see the module docs).
pub fn stem(name: &str) -> String {
    let mut out = String::with_capacity(name.len());
    let reserved = RESERVED.contains(&name);
    for (i, c) in name.chars().enumerate() {
        if must_encode(c) || (i == 0 && (c == '.' || reserved)) {
            encode(&mut out, c);
        } else {
            out.push(c);
        }
    }
    if name.is_empty() {
        out.push_str("%~empty");
    }
    if out.len() > MAX_STEM {
        let mut cut = MAX_STEM - 18;
        while !out.is_char_boundary(cut) {
            cut -= 1;
        }
        // Never end inside a %XX escape.
        if let Some(p) = out[..cut].rfind('%').filter(|&p| p + 3 > cut) {
            cut = p;
        }
        out.truncate(cut);
        out.push_str("%~");
        for b in &Sha256::digest(name.as_bytes())[..8] {
            let _ = write!(out, "{b:02x}");
        }
    }
    out
}

/// Checks that no two of `names` (the outputs and quantities of a study) would write the
/// same file; the message names both and the file.
pub fn check_distinct(names: &[String]) -> Result<(), String> {
    let mut seen: std::collections::HashMap<String, &str> = std::collections::HashMap::new();
    for name in names {
        let s = stem(name);
        for suffix in SUFFIXES {
            let file = format!("{s}{suffix}");
            match seen.get(file.as_str()) {
                Some(&other) if other != name => {
                    return Err(format!(
                        "the outputs/quantities '{other}' and '{name}' would both write the \
                         file {file}.csv (or .svg): a name is another one plus a file suffix; \
                         record only one of them"
                    ));
                }
                _ => {
                    seen.insert(file, name);
                }
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Percent-decoding, written separately from [`stem`].
    fn decode(s: &str) -> String {
        let b = s.as_bytes();
        let mut out = Vec::new();
        let mut i = 0;
        while i < b.len() {
            if b[i] == b'%' {
                out.push(u8::from_str_radix(&s[i + 1..i + 3], 16).unwrap());
                i += 3;
            } else {
                out.push(b[i]);
                i += 1;
            }
        }
        String::from_utf8(out).unwrap()
    }

    #[test]
    fn ordinary_names_keep_their_file_names() {
        for n in [
            "x0",
            "q",
            "body.frame_a.r_0[1]",
            "T[1,2]",
            "der(x)",
            "wheel-rail force",
            "Sperling_W",
            "ämne",
            "points2",
            "my.points",
            "a.b.",
        ] {
            assert_eq!(stem(n), n);
        }
    }

    #[test]
    fn names_that_would_leave_the_output_folder_are_encoded() {
        assert_eq!(stem("../../escape_y"), "%2E.%2F..%2Fescape_y");
        assert_eq!(stem("/tmp/qa_abs_y"), "%2Ftmp%2Fqa_abs_y");
        assert_eq!(stem("a/b"), "a%2Fb");
        assert_eq!(stem("a\\b"), "a%5Cb");
        assert_eq!(stem("."), "%2E");
        assert_eq!(stem(".."), "%2E.");
        assert_eq!(stem(".hidden"), "%2Ehidden");
        assert_eq!(stem("nul\0x\n"), "nul%00x%0A");
        assert_eq!(stem("50%"), "50%25");
        assert_eq!(stem("a:b*?\"<>|"), "a%3Ab%2A%3F%22%3C%3E%7C");
        for n in [
            "../../escape_y",
            "/tmp/x",
            "a/b",
            "..",
            ".",
            "50%",
            "x\u{7f}é/",
        ] {
            let s = stem(n);
            assert!(!s.contains('/') && !s.starts_with('.'), "{s}");
            assert_eq!(decode(&s), n);
        }
    }

    #[test]
    fn outputs_named_like_the_folders_own_files_do_not_overwrite_them() {
        assert_eq!(stem("points"), "%70oints");
        assert_eq!(stem("units"), "%75nits");
        for r in RESERVED {
            let s = stem(r);
            assert_ne!(&s, r);
            assert_eq!(decode(&s), *r);
        }
    }

    #[test]
    fn very_long_names_are_cut_with_a_hash_and_stay_distinct() {
        let a = "x".repeat(300);
        let b = format!("{}y", "x".repeat(299));
        let (sa, sb) = (stem(&a), stem(&b));
        assert!(sa.len() <= MAX_STEM && sb.len() <= MAX_STEM, "{sa}");
        assert_ne!(sa, sb);
        assert!(sa.contains("%~"));
        let slashes = "/".repeat(100);
        let s = stem(&slashes);
        assert!(s.len() <= MAX_STEM && !s.contains('/'));
        // The cut never leaves half an escape.
        let before_hash = s.split("%~").next().unwrap();
        assert_eq!(decode(before_hash).len() * 3, before_hash.len());
        assert_eq!(stem(""), "%~empty");
    }

    #[test]
    fn a_name_that_is_another_plus_a_file_suffix_is_refused() {
        let names = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        let err = check_distinct(&names(&["x", "x_pdf"])).unwrap_err();
        assert!(err.contains("'x'") && err.contains("'x_pdf'"), "{err}");
        assert!(check_distinct(&names(&["q_sobol", "q"])).is_err());
        assert!(check_distinct(&names(&["x", "y", "x_y", "points", "units", "a/b"])).is_ok());
    }
}
