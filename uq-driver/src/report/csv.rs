//! CSV writers: columns side by side, and density grids in long format.
//!
//! Numbers are written in the shortest form that parses back to the same value
//! ([`push_shortest`]: plain for 1e-4 <= |x| < 1e16, exponent notation outside, as Python's
//! `repr`). NaN is written as `nan` and infinities as `inf` / `-inf`; pandas and spreadsheets
//! read all three.

use std::path::Path;

use super::{write_bytes, ReportError};
pub use crate::text::csv::{push_field, push_header, push_shortest, shortest};

/// Writes a CSV file with one header line and one row per index of the columns.
///
/// `header[j]` names `columns[j]`; all columns must have the same length, and there must be
/// as many names as columns, otherwise [`ReportError::LengthMismatch`] is returned and no
/// file is written. Header names containing a comma, quote or line break are quoted.
pub fn write_columns(path: &Path, header: &[&str], columns: &[&[f64]]) -> Result<(), ReportError> {
    same_length(path, || "header".into(), header.len(), columns.len())?;
    let rows = columns.first().map_or(0, |c| c.len());
    for (j, column) in columns.iter().enumerate() {
        same_length(
            path,
            || format!("column {j} ({:?})", header[j]),
            column.len(),
            rows,
        )?;
    }

    let mut out = String::with_capacity(16 * (rows + 1) * columns.len().max(1));
    push_header(&mut out, header);
    for i in 0..rows {
        for (j, column) in columns.iter().enumerate() {
            if j > 0 {
                out.push(',');
            }
            push_number(&mut out, column[i]);
        }
        out.push('\n');
    }
    write_bytes(path, out.as_bytes())
}

/// Refuses `len` values of `what` where `expected` are needed (nothing is written to `path`).
fn same_length(
    path: &Path,
    what: impl FnOnce() -> String,
    len: usize,
    expected: usize,
) -> Result<(), ReportError> {
    if len == expected {
        return Ok(());
    }
    Err(ReportError::LengthMismatch {
        path: path.to_path_buf(),
        what: what(),
        len,
        expected,
    })
}

/// Writes densities on a grid over time in long format: header `time,x,density`, then one row
/// per (time, grid point), time-major.
///
/// `density[k][i]` is the density at `times[k]` and `grid[i]`. `density` must have one entry
/// per time and each entry one value per grid point, otherwise
/// [`ReportError::LengthMismatch`] is returned and no file is written. Load with
/// `pd.read_csv(p).pivot(index="x", columns="time", values="density")`.
pub fn write_grid(
    path: &Path,
    times: &[f64],
    grid: &[f64],
    density: &[Vec<f64>],
) -> Result<(), ReportError> {
    same_length(
        path,
        || "density (number of times)".into(),
        density.len(),
        times.len(),
    )?;
    for (k, row) in density.iter().enumerate() {
        same_length(
            path,
            || format!("density at time index {k}"),
            row.len(),
            grid.len(),
        )?;
    }

    let mut out = String::with_capacity(32 * (times.len() * grid.len() + 1));
    push_header(&mut out, &["time", "x", "density"]);
    // Each time and grid value is formatted once ("x," is the same on every time's rows).
    let xs: Vec<String> = grid
        .iter()
        .map(|&x| {
            let mut s = String::new();
            push_number(&mut s, x);
            s.push(',');
            s
        })
        .collect();
    let mut t_text = String::new();
    for (&t, row) in times.iter().zip(density) {
        t_text.clear();
        push_number(&mut t_text, t);
        t_text.push(',');
        for (x, &d) in xs.iter().zip(row) {
            out.push_str(&t_text);
            out.push_str(x);
            push_number(&mut out, d);
            out.push('\n');
        }
    }
    write_bytes(path, out.as_bytes())
}

fn push_number(out: &mut String, v: f64) {
    push_shortest(out, v);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::text::csv::split_line;

    fn parse(text: &str) -> Vec<Vec<f64>> {
        text.lines()
            .skip(1)
            .map(|l| l.split(',').map(|f| f.parse::<f64>().unwrap()).collect())
            .collect()
    }

    #[test]
    fn columns_round_trip_exactly() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("c.csv");
        let t = [0.0, 0.1, 1.0 / 3.0, 1e-300, 1.7976931348623157e308];
        let q = [
            -0.0,
            f64::MIN_POSITIVE,
            std::f64::consts::PI,
            -2.5e-7,
            123456789.125,
        ];
        write_columns(&path, &["time", "q"], &[&t, &q]).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(text.starts_with("time,q\n"));
        let body = text.split_once('\n').unwrap().1;
        assert!(
            body.starts_with("0,-0\n0.1,2.2250738585072014e-308\n"),
            "{body}"
        );
        let rows = parse(&text);
        assert_eq!(rows.len(), t.len());
        for (i, row) in rows.iter().enumerate() {
            assert_eq!(row[0].to_bits(), t[i].to_bits());
            assert_eq!(row[1].to_bits(), q[i].to_bits());
        }
    }

    #[test]
    fn tiny_and_huge_numbers_are_written_short_not_as_long_decimals() {
        // Regression: 2.2e-308 was written as a 326-character decimal.
        assert_eq!(shortest(2.2e-308), "2.2e-308");
        assert_eq!(shortest(f64::MIN_POSITIVE), "2.2250738585072014e-308");
        assert_eq!(shortest(5e-324), "5e-324");
        assert_eq!(shortest(f64::MAX), "1.7976931348623157e308");
        assert_eq!(shortest(1e16), "1e16");
        assert_eq!(shortest(-2.5e-7), "-2.5e-7");
        // Plain where Python's repr is plain.
        assert_eq!(shortest(0.0001), "0.0001");
        assert_eq!(shortest(0.01), "0.01");
        assert_eq!(shortest(123456789.125), "123456789.125");
        assert_eq!(shortest(9999999999999998.0), "9999999999999998");
        assert_eq!(shortest(3.0), "3");
    }

    #[test]
    fn every_number_round_trips_in_at_most_24_characters() {
        // Bit patterns from a fixed-seed xorshift: every exponent range is hit.
        let mut x = 0x9E37_79B9_7F4A_7C15_u64;
        for _ in 0..200_000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let v = f64::from_bits(x);
            if !v.is_finite() {
                continue;
            }
            let s = shortest(v);
            assert!(s.len() <= 24, "{s}");
            assert_eq!(s.parse::<f64>().unwrap().to_bits(), v.to_bits(), "{s}");
        }
    }

    #[test]
    fn non_finite_values_are_written_readably() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("nan.csv");
        write_columns(
            &path,
            &["a"],
            &[&[f64::NAN, f64::INFINITY, f64::NEG_INFINITY]],
        )
        .unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert_eq!(text, "a\nnan\ninf\n-inf\n");
        let rows = parse(&text);
        assert!(rows[0][0].is_nan());
        assert_eq!(rows[1][0], f64::INFINITY);
        assert_eq!(rows[2][0], f64::NEG_INFINITY);
    }

    #[test]
    fn header_names_with_commas_are_quoted() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("h.csv");
        write_columns(&path, &["mean", "q, \"lateral\""], &[&[1.0], &[2.0]]).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert_eq!(text, "mean,\"q, \"\"lateral\"\"\"\n1,2\n");
    }

    #[test]
    fn header_names_with_commas_quotes_or_line_breaks_are_quoted_and_read_back() {
        let names = ["index", "T[1,2]", "q\"uote", "cr\rlf\n", "plain.x[1]"];
        let mut line = String::new();
        push_header(&mut line, &names);
        assert_eq!(
            line,
            "index,\"T[1,2]\",\"q\"\"uote\",\"cr\rlf\n\",plain.x[1]\n"
        );
        assert_eq!(split_line(line.strip_suffix('\n').unwrap()), names);
        // Ordinary names: the same bytes as before quoting existed.
        let mut plain = String::new();
        push_header(
            &mut plain,
            &["index", "weight", "body.frame_a.r_0[1]", "status"],
        );
        assert_eq!(plain, "index,weight,body.frame_a.r_0[1],status\n");
        assert_eq!(split_line("1,,\"failed: a, b\""), ["1", "", "failed: a, b"]);
    }

    #[test]
    fn empty_columns_give_header_only() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("e.csv");
        write_columns(&path, &["a", "b"], &[&[], &[]]).unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "a,b\n");
    }

    #[test]
    fn mismatched_column_lengths_are_an_error_and_write_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("bad.csv");
        let err = write_columns(&path, &["a", "b"], &[&[1.0, 2.0], &[1.0]]).unwrap_err();
        assert!(matches!(
            err,
            ReportError::LengthMismatch {
                len: 1,
                expected: 2,
                ..
            }
        ));
        assert!(err.to_string().contains("\"b\""), "{err}");
        assert!(!path.exists());
        let err = write_columns(&path, &["a"], &[&[1.0], &[1.0]]).unwrap_err();
        assert!(matches!(err, ReportError::LengthMismatch { .. }));
    }

    #[test]
    fn grid_is_long_format_time_major() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("g.csv");
        let times = [0.0, 0.5];
        let grid = [-1.0, 0.0, 1.0];
        let density = vec![vec![0.1, 0.2, 0.3], vec![0.4, f64::NAN, 0.6]];
        write_grid(&path, &times, &grid, &density).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines[0], "time,x,density");
        assert_eq!(lines.len(), 1 + 6);
        assert_eq!(lines[1], "0,-1,0.1");
        assert_eq!(lines[5], "0.5,0,nan");
        assert_eq!(lines[6], "0.5,1,0.6");
    }

    #[test]
    fn grid_shape_mismatch_is_an_error() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("g.csv");
        let err = write_grid(&path, &[0.0, 1.0], &[0.0], &[vec![1.0]]).unwrap_err();
        assert!(matches!(err, ReportError::LengthMismatch { .. }));
        let err = write_grid(&path, &[0.0], &[0.0, 1.0], &[vec![1.0]]).unwrap_err();
        assert!(matches!(err, ReportError::LengthMismatch { .. }));
        assert!(!path.exists());
    }
}
