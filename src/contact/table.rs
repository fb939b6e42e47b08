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
}

/// Why a contact table is refused.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum TableError {
    /// The table's contents are not usable (too few rows, y not ascending in equal steps,
    /// non-finite or non-physical values).
    #[error("{0}")]
    Invalid(String),
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
            for (name, v) in [
                ("N0", row.n0),
                ("a", row.a),
                ("b", row.b),
                ("r", row.r),
                ("q0", row.q0),
            ] {
                if v <= 0.0 {
                    return Err(TableError::Invalid(format!(
                        "row {} (y = {}): {name} = {v} must be > 0",
                        i + 1,
                        row.y
                    )));
                }
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
