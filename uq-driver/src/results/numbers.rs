//! Numbers as a person reads them on the report page: inputs as the study file wrote them,
//! statistics to the resolution their spread allows, counts with grouped digits. The CSV
//! files and `summary.json` keep every digit; these are for text only.

/// `x` rounded to 12 significant digits: drops the round-off of a computed value
/// (`0.1 · 182300 = 18230.000000000004` → `18230`) and keeps every digit a person writes.
pub fn clean(x: f64) -> f64 {
    rounded(x, 12)
}

/// `x` rounded to `digits` significant digits.
pub(crate) fn rounded(x: f64, digits: usize) -> f64 {
    if x == 0.0 || !x.is_finite() {
        return x;
    }
    format!("{x:.*e}", digits.max(1) - 1).parse().unwrap_or(x)
}

/// The numbers of one row as a study file writes them: the shortest text that reads back as
/// each ([`clean`]ed) value, all in the same notation — with an exponent (`1.823e5`,
/// `1.823e4`) when any non-zero one is at least 1e6 or below 1e-4, plain (`182300`, `18230`)
/// otherwise. Infinities read `∞` / `−∞`.
pub fn as_written(xs: &[f64]) -> Vec<String> {
    in_one_notation(xs, 12)
}

/// Computed numbers of one row (a truncated normal's mean and Std, a CoV): as
/// [`as_written`], at six significant digits (`20.7437`, `3.24722`).
pub fn computed(xs: &[f64]) -> Vec<String> {
    in_one_notation(xs, 6)
}

fn in_one_notation(xs: &[f64], digits: usize) -> Vec<String> {
    let exponent = xs
        .iter()
        .any(|x| x.is_finite() && *x != 0.0 && !(1e-4..1e6).contains(&x.abs()));
    xs.iter()
        .map(|&x| {
            let c = rounded(x, digits);
            if x == f64::INFINITY {
                "∞".into()
            } else if x == f64::NEG_INFINITY {
                "−∞".into()
            } else if exponent && c != 0.0 {
                format!("{c:e}")
            } else {
                format!("{c}")
            }
        })
        .collect()
}

/// One number as written ([`as_written`] of it alone).
pub fn written(x: f64) -> String {
    as_written(&[x]).swap_remove(0)
}

/// `x` to the resolution its spread allows: rounded at the second significant digit of
/// `spread` (a mean of 115131.07 N with a Std of 43.2 N reads `115 131`), with 3 to 6
/// significant digits; 6 significant digits without trailing zeros (`64.865`) when the
/// spread is zero or unknown. Plain from 1e-3 to 1e6, with digits grouped by three
/// (narrow no-break spaces) from 1e4; with an exponent outside (`1.23e-5`).
pub fn to_spread(x: f64, spread: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return if x == 0.0 { "0".into() } else { format!("{x}") };
    }
    let mag = x.abs().log10().floor() as i32;
    let (digits, trim) = if spread > 0.0 && spread.is_finite() {
        let s = spread.log10().floor() as i32;
        ((mag - s + 2).clamp(3, 6), false)
    } else {
        (6, true)
    };
    let text = if (1e-3..1e6).contains(&x.abs()) {
        let decimals = (digits - 1 - mag).max(0) as usize;
        // Round to the last significant digit, also left of the decimal point.
        let unit = 10f64.powi(mag - digits + 1);
        let rounded = if decimals == 0 {
            (x / unit).round() * unit
        } else {
            x
        };
        let mut t = format!("{rounded:.decimals$}");
        if trim && t.contains('.') {
            t = t.trim_end_matches('0').trim_end_matches('.').to_owned();
        }
        group(&t)
    } else {
        let mut t = format!("{x:.*e}", (digits - 1) as usize);
        if trim {
            if let Some((m, e)) = t.split_once('e') {
                let m = if m.contains('.') {
                    m.trim_end_matches('0').trim_end_matches('.')
                } else {
                    m
                };
                t = format!("{m}e{e}");
            }
        }
        t
    };
    if text
        .trim_start_matches('-')
        .chars()
        .all(|c| matches!(c, '0' | '.' | '\u{202f}'))
    {
        "0".into()
    } else {
        text
    }
}

/// The integer part of a plain decimal grouped by three from 10 000 (`115131.5` →
/// `115 131.5`, narrow no-break spaces).
fn group(t: &str) -> String {
    let (sign, rest) = match t.strip_prefix('-') {
        Some(r) => ("-", r),
        None => ("", t),
    };
    let (int, frac) = match rest.split_once('.') {
        Some((i, f)) => (i, Some(f)),
        None => (rest, None),
    };
    if int.len() < 5 {
        return t.to_owned();
    }
    let mut out = String::from(sign);
    for (i, ch) in int.chars().enumerate() {
        if i > 0 && (int.len() - i).is_multiple_of(3) {
            out.push('\u{202f}');
        }
        out.push(ch);
    }
    if let Some(f) = frac {
        out.push('.');
        out.push_str(f);
    }
    out
}

/// `1 model run`, `2 000 model runs`: a count with grouped digits and the noun in the
/// right number (`noun` singular, `plural` its plural).
pub fn count(n: usize, noun: &str, plural: &str) -> String {
    format!(
        "{} {}",
        super::group_digits(n),
        if n == 1 { noun } else { plural }
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inputs_read_as_written_in_one_notation() {
        // `mean = 0.1823e6, cov = 0.1` read "mean 1.82e5, std 18230".
        assert_eq!(as_written(&[0.1823e6, 0.1 * 0.1823e6]), ["182300", "18230"]);
        assert_eq!(
            as_written(&[1773000.0, 0.1 * 1773000.0]),
            ["1.773e6", "1.773e5"]
        );
        assert_eq!(as_written(&[0.0015, 1e-7]), ["1.5e-3", "1e-7"]);
        assert_eq!(as_written(&[100.0, 10.0]), ["100", "10"]);
        assert_eq!(as_written(&[0.0, f64::INFINITY]), ["0", "∞"]);
        assert_eq!(written(0.1 + 0.2), "0.3");
        assert_eq!(written(-2.5), "-2.5");
        assert_eq!(
            computed(&[20.743669604312, 3.247221937228]),
            ["20.7437", "3.24722"]
        );
    }

    #[test]
    fn statistics_to_the_resolution_of_their_spread() {
        // "mean 115131.073578 N", "Std 43.224931 N".
        assert_eq!(to_spread(115131.073578, 43.224931), "115\u{202f}131");
        assert_eq!(to_spread(43.224931, 43.224931), "43.2");
        assert_eq!(to_spread(0.035097011, 0.0045246), "0.0351");
        assert_eq!(to_spread(115131.07, 4300.0), "115\u{202f}100");
        // No spread: six significant digits, no trailing zeros ("64.865000").
        assert_eq!(to_spread(64.865, 0.0), "64.865");
        assert_eq!(to_spread(69.296875, 0.0), "69.2969");
        assert_eq!(to_spread(2.0, f64::NAN), "2");
        assert_eq!(to_spread(1.234567e-9, 0.0), "1.23457e-9");
        assert_eq!(to_spread(2.5e7, 1e3), "2.50000e7");
        assert_eq!(to_spread(-0.5, 0.01), "-0.500");
        assert_eq!(to_spread(0.0, 1.0), "0");
        // A value far below its spread still shows three digits.
        assert_eq!(to_spread(1e-3, 1.0), "0.00100");
    }

    #[test]
    fn counts_agree_with_their_noun() {
        assert_eq!(count(1, "model run", "model runs"), "1 model run");
        assert_eq!(count(20000, "run", "runs"), "20\u{202f}000 runs");
        assert_eq!(count(0, "thread", "threads"), "0 threads");
    }
}
