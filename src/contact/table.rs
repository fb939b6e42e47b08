//! The contact table: for each lateral displacement y of a wheelset, the contact of its **left**
//! wheel (the right wheel uses the row at −y, mirrored), as a tool such as RSGEO writes it.
//!
//! File format (CSV, SI units, a header line naming the columns, rows ascending in y with equal
//! steps; extra columns are ignored):
//!
//! ```text
//! y, N0, delta, a, b, aw, r, c11, c22, c23, zc, q0
//! ```
//!
//! | column | unit | meaning |
//! |---|---|---|
//! | y | m | wheelset lateral displacement |
//! | N0 | N | static normal force on the wheel |
//! | delta | rad | contact angle |
//! | a, b | m | contact-ellipse semi-axes (a along the rolling direction) |
//! | aw | m | lateral position of the contact point on the wheel, from the wheelset centre |
//! | r | m | rolling radius |
//! | c11, c22, c23 | 1 | Kalker's linear creep coefficients |
//! | zc | m | vertical position of the contact point |
//! | q0 | m | static penetration |

use std::fmt;

/// One row of a contact table: the left wheel's contact at wheelset displacement `y`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TableRow {
    /// Wheelset lateral displacement (m).
    pub y: f64,
    /// Static normal force on the wheel (N).
    pub n0: f64,
    /// Contact angle (rad).
    pub delta: f64,
    /// Contact-ellipse semi-axis along the rolling direction (m).
    pub a: f64,
    /// Contact-ellipse semi-axis across the rolling direction (m).
    pub b: f64,
    /// Lateral position of the contact point on the wheel, from the wheelset centre (m).
    pub aw: f64,
    /// Rolling radius (m).
    pub r: f64,
    /// Kalker's coefficient C11 (1).
    pub c11: f64,
    /// Kalker's coefficient C22 (1).
    pub c22: f64,
    /// Kalker's coefficient C23 (1).
    pub c23: f64,
    /// Vertical position of the contact point (m).
    pub zc: f64,
    /// Static penetration (m).
    pub q0: f64,
}

/// The column names of a table file, in order.
pub const COLUMNS: [&str; 12] = [
    "y", "N0", "delta", "a", "b", "aw", "r", "c11", "c22", "c23", "zc", "q0",
];

impl TableRow {
    /// The values in the order of [`COLUMNS`].
    pub fn values(&self) -> [f64; 12] {
        [
            self.y, self.n0, self.delta, self.a, self.b, self.aw, self.r, self.c11, self.c22,
            self.c23, self.zc, self.q0,
        ]
    }

    /// A row from values in the order of [`COLUMNS`].
    pub fn from_values(v: [f64; 12]) -> TableRow {
        TableRow {
            y: v[0],
            n0: v[1],
            delta: v[2],
            a: v[3],
            b: v[4],
            aw: v[5],
            r: v[6],
            c11: v[7],
            c22: v[8],
            c23: v[9],
            zc: v[10],
            q0: v[11],
        }
    }

    /// The first of the columns that must be positive (N0, a, b, r, q0) that is not, with its
    /// value (N for N0, m for the others).
    fn not_positive(&self) -> Option<(&'static str, f64)> {
        [
            ("N0", self.n0),
            ("a", self.a),
            ("b", self.b),
            ("r", self.r),
            ("q0", self.q0),
        ]
        .into_iter()
        .find(|&(_, v)| v <= 0.0)
    }
}

/// Why a contact table is refused.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum TableError {
    /// The table's contents are not usable (too few rows, y not ascending in equal steps,
    /// non-finite or non-physical values).
    #[error("{0}")]
    Invalid(String),
    /// A line of a table file is not what the format expects (the message says what was
    /// expected; it never quotes the line).
    #[error("line {line}: {reason}")]
    Line {
        /// Line number in the file (1 = first line).
        line: usize,
        /// What was expected there.
        reason: String,
    },
}

/// A contact table: rows ascending in y with equal steps.
#[derive(Clone, Debug, PartialEq)]
pub struct ContactTable {
    rows: Vec<TableRow>,
}

impl ContactTable {
    /// A table from rows, checked: at least 4 rows, y ascending in equal steps (to 1e-6 of
    /// the step), every value finite, N0, a, b, r, q0 > 0.
    pub fn from_rows(rows: Vec<TableRow>) -> Result<ContactTable, TableError> {
        if rows.len() < 4 {
            return Err(TableError::Invalid(format!(
                "a contact table needs at least 4 rows, found {}",
                rows.len()
            )));
        }
        let step = rows[1].y - rows[0].y;
        for (i, row) in rows.iter().enumerate() {
            if let Some(k) = row.values().iter().position(|v| !v.is_finite()) {
                return Err(TableError::Invalid(format!(
                    "row {} (y = {}): {} is not finite",
                    i + 1,
                    row.y,
                    COLUMNS[k]
                )));
            }
            if let Some((name, v)) = row.not_positive() {
                return Err(TableError::Invalid(format!(
                    "row {} (y = {}): {name} = {v} must be > 0",
                    i + 1,
                    row.y
                )));
            }
            if i > 0 {
                let d = row.y - rows[i - 1].y;
                if !(step > 0.0 && (d - step).abs() <= 1e-6 * step) {
                    return Err(TableError::Invalid(format!(
                        "row {} (y = {}): y must ascend in equal steps ({} m after the first two rows)",
                        i + 1,
                        row.y,
                        step
                    )));
                }
            }
        }
        Ok(ContactTable { rows })
    }

    /// The rows, ascending in y.
    pub fn rows(&self) -> &[TableRow] {
        &self.rows
    }

    /// The range of y covered (m).
    pub fn range(&self) -> (f64, f64) {
        (self.rows[0].y, self.rows[self.rows.len() - 1].y)
    }
}

/// Splits a line of a data file (a contact table, a profile, a measured track or track
/// irregularity) into fields: commas, semicolons, tabs or spaces separate them.
pub(crate) fn fields(line: &str) -> Vec<&str> {
    line.split(|c: char| c == ',' || c == ';' || c.is_whitespace())
        .filter(|s| !s.is_empty())
        .collect()
}

impl ContactTable {
    /// Parses the text of a table file (format in the module documentation).
    ///
    /// Blank lines and lines starting with `#` are skipped. The first other line is a header
    /// when any of its fields is not a number: it must name each of [`COLUMNS`] once (in any
    /// order; other names are extra columns, ignored). Without a header the first twelve
    /// fields of a line are the columns in the order of [`COLUMNS`]. Fields are separated by
    /// commas (semicolons, tabs and spaces are accepted too). Every row passes the checks of
    /// [`ContactTable::from_rows`], reported with its line number. No message quotes the text.
    pub fn parse_csv(text: &str) -> Result<ContactTable, TableError> {
        let line_err = |line: usize, reason: String| TableError::Line { line, reason };
        let mut index: Option<[usize; 12]> = None;
        let mut rows: Vec<TableRow> = Vec::new();
        let mut first_line = 0;
        let mut step = 0.0;
        for (no, raw) in text.lines().enumerate() {
            let line = no + 1;
            let trimmed = raw.trim();
            if trimmed.is_empty() || trimmed.starts_with('#') {
                continue;
            }
            let f = fields(trimmed);
            if index.is_none() {
                if f.iter().any(|s| s.parse::<f64>().is_err()) {
                    let mut idx = [usize::MAX; 12];
                    for (k, name) in f.iter().enumerate() {
                        if let Some(c) = COLUMNS.iter().position(|c| c.eq_ignore_ascii_case(name)) {
                            if idx[c] != usize::MAX {
                                return Err(line_err(
                                    line,
                                    format!("the header names column '{}' twice", COLUMNS[c]),
                                ));
                            }
                            idx[c] = k;
                        }
                    }
                    if let Some(c) = idx.iter().position(|&k| k == usize::MAX) {
                        return Err(line_err(
                            line,
                            format!(
                                "the header must name the columns {} (column '{}' is missing)",
                                COLUMNS.join(", "),
                                COLUMNS[c]
                            ),
                        ));
                    }
                    index = Some(idx);
                    continue;
                }
                index = Some(std::array::from_fn(|k| k));
            }
            let idx = index.expect("set above");
            let needed = idx.iter().max().expect("12 columns") + 1;
            if f.len() < needed {
                return Err(line_err(
                    line,
                    format!(
                        "expected {needed} fields ({}), found {}",
                        COLUMNS.join(", "),
                        f.len()
                    ),
                ));
            }
            let mut v = [0.0; 12];
            for (c, &k) in idx.iter().enumerate() {
                let x: f64 = f[k].parse().map_err(|_| {
                    line_err(line, format!("column '{}' is not a number", COLUMNS[c]))
                })?;
                if !x.is_finite() {
                    return Err(line_err(
                        line,
                        format!("column '{}' is not a finite number", COLUMNS[c]),
                    ));
                }
                v[c] = x;
            }
            let row = TableRow::from_values(v);
            if let Some((name, _)) = row.not_positive() {
                return Err(line_err(line, format!("column '{name}' must be > 0")));
            }
            match rows.len() {
                0 => first_line = line,
                1 => {
                    step = row.y - rows[0].y;
                    if step <= 0.0 {
                        return Err(line_err(
                            line,
                            format!("y must ascend (it does not from line {first_line} on)"),
                        ));
                    }
                }
                n => {
                    let d = row.y - rows[n - 1].y;
                    if (d - step).abs() > 1e-6 * step {
                        return Err(line_err(
                            line,
                            "y must ascend in equal steps (the step of the first two rows)".into(),
                        ));
                    }
                }
            }
            rows.push(row);
        }
        if rows.len() < 4 {
            return Err(TableError::Invalid(format!(
                "a contact table needs at least 4 rows of {}, found {}",
                COLUMNS.join(", "),
                rows.len()
            )));
        }
        ContactTable::from_rows(rows)
            .map_err(|_| TableError::Invalid("the rows are not a valid contact table".into()))
    }
}

/// Number of interpolated columns: every column but y.
const NCOL: usize = 11;

/// A row from `y` and the other columns in the order of [`COLUMNS`].
#[inline]
fn row_of(y: f64, v: &[f64; NCOL]) -> TableRow {
    TableRow {
        y,
        n0: v[0],
        delta: v[1],
        a: v[2],
        b: v[3],
        aw: v[4],
        r: v[5],
        c11: v[6],
        c22: v[7],
        c23: v[8],
        zc: v[9],
        q0: v[10],
    }
}

/// The table interpolated in y by natural cubic splines (second derivative zero at both ends),
/// one per column, as the reference implementation does (GSL's `cspline`).
///
/// [`ContactSpline::left`] gives the left wheel's contact at wheelset displacement `y`;
/// [`ContactSpline::right`] the right wheel's, which is the left wheel's row at `−y` (profiles
/// symmetric about the track centre line): its values are magnitudes to be read mirrored,
/// i.e. the contact point lies at lateral position `−aw` and the contact plane is tilted by
/// `δ` the other way.
#[derive(Clone, Debug, PartialEq)]
pub struct ContactSpline {
    y0: f64,
    step: f64,
    /// Column values at the nodes (every column but y).
    values: Vec<[f64; NCOL]>,
    /// Second derivatives at the nodes (d²/dy², per column).
    second: Vec<[f64; NCOL]>,
}

impl ContactSpline {
    /// The splines of `table` (natural end conditions; one tridiagonal solve per column).
    pub fn new(table: &ContactTable) -> ContactSpline {
        let rows = table.rows();
        let n = rows.len();
        let (y0, y_last) = table.range();
        let step = (y_last - y0) / (n - 1) as f64;
        let values: Vec<[f64; NCOL]> = rows
            .iter()
            .map(|r| {
                let v = r.values();
                std::array::from_fn(|c| v[c + 1])
            })
            .collect();
        // M[i-1] + 4 M[i] + M[i+1] = 6 (f[i+1] - 2 f[i] + f[i-1]) / h², M[0] = M[n-1] = 0:
        // forward elimination (diagonal 4, off-diagonals 1), then back substitution.
        let mut second = vec![[0.0; NCOL]; n];
        let mut diag = vec![0.0; n];
        let mut rhs = vec![[0.0; NCOL]; n];
        let scale = 6.0 / (step * step);
        for i in 1..n - 1 {
            let d = if i == 1 { 4.0 } else { 4.0 - 1.0 / diag[i - 1] };
            diag[i] = d;
            for c in 0..NCOL {
                let r = scale * (values[i + 1][c] - 2.0 * values[i][c] + values[i - 1][c]);
                rhs[i][c] = if i == 1 {
                    r
                } else {
                    r - rhs[i - 1][c] / diag[i - 1]
                };
            }
        }
        for i in (1..n - 1).rev() {
            for c in 0..NCOL {
                second[i][c] = (rhs[i][c] - second[i + 1][c]) / diag[i];
            }
        }
        ContactSpline {
            y0,
            step,
            values,
            second,
        }
    }

    /// The range of y covered (m).
    pub fn range(&self) -> (f64, f64) {
        (
            self.y0,
            self.y0 + self.step * (self.values.len() - 1) as f64,
        )
    }

    /// Largest |y| (m) at which both wheels are inside the table: `y` and `−y` in its range.
    pub fn limit(&self) -> f64 {
        let (lo, hi) = self.range();
        (-lo).min(hi)
    }

    /// The interpolated row at `y` (m), or `None` outside the table's range.
    #[inline]
    pub fn left(&self, y: f64) -> Option<TableRow> {
        let (lo, hi) = self.range();
        if !(y >= lo && y <= hi) {
            return None;
        }
        let n = self.values.len();
        let s = (y - self.y0) / self.step;
        let i = (s.floor() as usize).min(n - 2);
        let b = s - i as f64;
        let a = 1.0 - b;
        let h2 = self.step * self.step / 6.0;
        let (ca, cb) = ((a * a * a - a) * h2, (b * b * b - b) * h2);
        let (f0, f1) = (&self.values[i], &self.values[i + 1]);
        let (m0, m1) = (&self.second[i], &self.second[i + 1]);
        let v: [f64; NCOL] =
            std::array::from_fn(|c| a * f0[c] + b * f1[c] + ca * m0[c] + cb * m1[c]);
        Some(row_of(y, &v))
    }

    /// The right wheel's contact at wheelset displacement `y` (m): the left wheel's row at
    /// `−y` (its `y` field is `−y`), or `None` outside the table's range.
    #[inline]
    pub fn right(&self, y: f64) -> Option<TableRow> {
        self.left(-y)
    }

    /// Largest value of `f(row)` over the table's nodes (for bounds on the model's rates).
    pub fn node_max(&self, f: impl Fn(&TableRow) -> f64) -> f64 {
        let (lo, _) = self.range();
        (0..self.values.len())
            .map(|i| f(&row_of(lo + i as f64 * self.step, &self.values[i])))
            .fold(f64::NEG_INFINITY, f64::max)
    }
}

impl fmt::Display for ContactTable {
    /// The table as a file: the header line and one line per row (shortest round-trip numbers).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "{}", COLUMNS.join(","))?;
        for row in &self.rows {
            let line: Vec<String> = row.values().iter().map(|v| format!("{v:e}")).collect();
            writeln!(f, "{}", line.join(","))?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(y: f64) -> TableRow {
        TableRow {
            y,
            n0: 66_600.0,
            delta: 0.025,
            a: 6e-3,
            b: 4e-3,
            aw: 0.75,
            r: 0.425,
            c11: 4.0,
            c22: 3.5,
            c23: 1.5,
            zc: 0.0,
            q0: 1e-4,
        }
    }

    /// The RSGEO table of the reference study (S1002 on UIC60, 1:40), as a table file.
    const RSGEO: &str = include_str!("../../tests/data/rsgeo_s1002_uic60_1in40.csv");

    fn csv(rows: &[TableRow]) -> String {
        ContactTable::from_rows(rows.to_vec()).unwrap().to_string()
    }

    #[test]
    fn the_rsgeo_file_parses_to_its_3402_rows() {
        let t = ContactTable::parse_csv(RSGEO).unwrap();
        assert_eq!(t.rows().len(), 3402);
        assert_eq!(t.range(), (-0.017, 0.01701));
        let first = t.rows()[0];
        assert_eq!((first.n0, first.q0), (6.6604470702e+04, 1.1849300000e-04));
        // What Display writes parses back to the same table.
        assert_eq!(ContactTable::parse_csv(&t.to_string()).unwrap(), t);
    }

    #[test]
    fn a_header_may_order_the_columns_and_add_others() {
        let rows: Vec<_> = (0..5).map(|i| row(-2e-5 + i as f64 * 1e-5)).collect();
        let mut text = String::from("# comment\nq0;extra;zc;c23;c22;c11;r;aw;b;a;delta;N0;y\n");
        for r in &rows {
            let v = r.values();
            text += &format!(
                "{};7;{};{};{};{};{};{};{};{};{};{};{}\n\n",
                v[11], v[10], v[9], v[8], v[7], v[6], v[5], v[4], v[3], v[2], v[1], v[0]
            );
        }
        let t = ContactTable::parse_csv(&text).unwrap();
        assert_eq!(t.rows(), &rows[..]);
        // Without a header the first twelve fields are the columns in order.
        let plain: String = csv(&rows)
            .lines()
            .skip(1)
            .map(|l| format!("{l}, 99\n"))
            .collect();
        assert_eq!(ContactTable::parse_csv(&plain).unwrap().rows(), &rows[..]);
    }

    #[test]
    fn bad_files_are_refused_by_line_without_quoting_them() {
        let rows: Vec<_> = (0..5).map(|i| row(-2e-5 + i as f64 * 1e-5)).collect();
        let good = csv(&rows);
        let lines: Vec<&str> = good.lines().collect();
        let with = |k: usize, new: &str| {
            let mut l = lines.clone();
            l[k] = new;
            l.join("\n")
        };
        let secret = "SECRET-TOKEN";
        let cases = [
            (
                with(0, "y,N0,delta,a,b,aw,r,c11,c22,c23,zc,SECRET-TOKEN"),
                "line 1: the header must name the columns",
                "'q0' is missing",
            ),
            (
                with(2, &lines[2].replacen("6.66e4", "SECRET-TOKEN", 1)),
                "line 3: column 'N0' is not a number",
                "",
            ),
            (
                with(2, &lines[2].replacen("6.66e4", "NaN", 1)),
                "line 3: column 'N0' is not a finite number",
                "",
            ),
            (
                with(2, &lines[2].replacen("6.66e4", "-1", 1)),
                "line 3: column 'N0' must be > 0",
                "",
            ),
            (
                with(3, "0.5,1,SECRET-TOKEN"),
                "line 4: expected 12 fields",
                "found 3",
            ),
            (
                with(4, lines[2]),
                "line 5: y must ascend in equal steps",
                "",
            ),
            (with(2, lines[1]), "line 3: y must ascend", ""),
        ];
        for (text, expected, also) in cases {
            let e = ContactTable::parse_csv(&text).unwrap_err().to_string();
            assert!(e.starts_with(expected) && e.contains(also), "{e}");
            assert!(!e.contains(secret), "{e}");
        }
        let e = ContactTable::parse_csv("# nothing\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("at least 4 rows"), "{e}");
    }

    fn spline_of(f: impl Fn(f64) -> f64, n: usize, h: f64) -> ContactSpline {
        let rows: Vec<_> = (0..n)
            .map(|i| {
                let y = -h * (n / 2) as f64 + i as f64 * h;
                TableRow { n0: f(y), ..row(y) }
            })
            .collect();
        ContactSpline::new(&ContactTable::from_rows(rows).unwrap())
    }

    #[test]
    fn the_spline_is_the_natural_cubic_interpolant() {
        let f = |y: f64| 1.0 + (300.0 * y).sin() + 40.0 * y * y;
        let (n, h) = (41, 1e-3);
        let s = spline_of(f, n, h);
        let (lo, hi) = s.range();
        let at = |y: f64| s.left(y).unwrap().n0;
        // Interpolates at the nodes.
        for i in 0..n {
            let y = lo + i as f64 * h;
            assert!((at(y) - f(y)).abs() < 1e-12, "node {i}");
        }
        // First and second derivatives continuous at interior nodes; second derivative zero
        // at both ends (these determine the natural cubic spline).
        // One-sided differences within one spline piece, exact for cubics.
        let e = 1e-5;
        let p = |y: f64, side: f64| [0.0, 1.0, 2.0, 3.0].map(|k| at(y + side * k * e));
        let d1 = |y: f64, side: f64| {
            let f = p(y, side);
            side * (-11.0 * f[0] + 18.0 * f[1] - 9.0 * f[2] + 2.0 * f[3]) / (6.0 * e)
        };
        let d2 = |y: f64, side: f64| {
            let f = p(y, side);
            (2.0 * f[0] - 5.0 * f[1] + 4.0 * f[2] - f[3]) / (e * e)
        };
        for i in 1..n - 1 {
            let y = lo + i as f64 * h;
            assert!(
                (d1(y, 1.0) - d1(y, -1.0)).abs() < 1e-6,
                "slope jumps at node {i}"
            );
            assert!(
                (d2(y, 1.0) - d2(y, -1.0)).abs() < 1e-2,
                "curvature jumps at node {i}"
            );
        }
        assert!(
            d2(lo, 1.0).abs() < 1e-2 && d2(hi, -1.0).abs() < 1e-2,
            "natural ends"
        );
        // Accurate inside: fourth order away from the ends.
        for k in 0..200 {
            let y = -0.01 + k as f64 * 1e-4 + 3.3e-6;
            assert!((at(y) - f(y)).abs() < 1e-4, "y = {y}");
        }
        // Outside the range there is no value; the right wheel reads the row at -y.
        assert!(s.left(hi + 1e-12).is_none() && s.left(f64::NAN).is_none());
        assert_eq!(s.right(0.003).unwrap().n0, at(-0.003));
        assert_eq!(s.limit(), 0.02);
    }

    #[test]
    fn rows_must_ascend_in_equal_steps() {
        let ok: Vec<_> = (0..5).map(|i| row(-2e-5 + i as f64 * 1e-5)).collect();
        assert!(ContactTable::from_rows(ok.clone()).is_ok());
        let mut bad = ok.clone();
        bad[3].y += 3e-6;
        let e = ContactTable::from_rows(bad).unwrap_err().to_string();
        assert!(e.contains("row 4") && e.contains("equal steps"), "{e}");
        let mut bad = ok;
        bad[2].q0 = 0.0;
        let e = ContactTable::from_rows(bad).unwrap_err().to_string();
        assert!(e.contains("q0"), "{e}");
    }
}
