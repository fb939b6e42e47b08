//! CSV text: fields quoted only where they must be (RFC 4180), lines split back into fields,
//! and numbers in the shortest form that parses back to the same value ([`push_shortest`]:
//! plain for 1e-4 <= |x| < 1e16, exponent notation outside, as Python's `repr`; NaN as `nan`,
//! infinities as `inf` / `-inf`, which pandas and spreadsheets read).

use std::fmt::Write as _;

/// Appends a CSV header line: the names separated by commas, each quoted (RFC 4180) only
/// where it must be ([`push_field`]), and a newline.
pub fn push_header(out: &mut String, header: &[&str]) {
    for (j, name) in header.iter().enumerate() {
        if j > 0 {
            out.push(',');
        }
        push_field(out, name);
    }
    out.push('\n');
}

/// Appends one CSV field: as it is, or, when it contains a comma, a double quote, a CR or an
/// LF, in double quotes with its quotes doubled (RFC 4180): `T[1,2]` → `"T[1,2]"`.
pub fn push_field(out: &mut String, field: &str) {
    if field.contains([',', '"', '\n', '\r']) {
        out.push('"');
        out.push_str(&field.replace('"', "\"\""));
        out.push('"');
    } else {
        out.push_str(field);
    }
}

/// The fields of one CSV line (RFC 4180: a field in double quotes may hold commas, and `""`
/// is a quote), as [`push_field`] writes them.
pub fn split_line(line: &str) -> Vec<String> {
    let mut fields = vec![String::new()];
    let mut quoted = false;
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        let field = fields.last_mut().expect("never empty");
        match c {
            '"' if quoted && chars.peek() == Some(&'"') => {
                field.push('"');
                chars.next();
            }
            '"' if quoted => quoted = false,
            '"' if field.is_empty() => quoted = true,
            ',' if !quoted => fields.push(String::new()),
            c => field.push(c),
        }
    }
    fields
}

/// Appends `v` in the shortest form that reads back as the same `f64`: Rust's shortest
/// round-trip digits, in plain notation for 0 and 1e-4 <= |v| < 1e16 and in exponent notation
/// otherwise (`2.2250738585072014e-308`, not a 326-character decimal), as Python's `repr` does.
/// NaN is `nan`, infinities `inf` / `-inf`.
pub fn push_shortest(out: &mut String, v: f64) {
    // Writing to a String cannot fail.
    if v.is_nan() {
        out.push_str("nan");
    } else if v.is_infinite() || v == 0.0 || (1e-4..1e16).contains(&v.abs()) {
        let _ = write!(out, "{v}");
    } else {
        let _ = write!(out, "{v:e}");
    }
}

/// [`push_shortest`] as a new string.
pub fn shortest(v: f64) -> String {
    let mut s = String::new();
    push_shortest(&mut s, v);
    s
}
