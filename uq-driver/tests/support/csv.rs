//! CSV files as the driver writes them (no quoted fields; `points.csv` with failure messages
//! is read with [`super::csv_records`]): the header and the rows' fields, read back as text
//! and as numbers.

use std::path::Path;

/// A CSV file: the column names and the fields of each row.
pub struct Csv {
    /// Column names.
    pub header: Vec<String>,
    /// The fields of each row, as written.
    pub rows: Vec<Vec<String>>,
}

impl Csv {
    /// Splits `text` at newlines and commas; the first line is the header.
    pub fn parse(text: &str) -> Csv {
        let mut lines = text.lines();
        let header = lines
            .next()
            .unwrap_or("")
            .split(',')
            .map(str::to_owned)
            .collect();
        let rows = lines
            .map(|l| l.split(',').map(str::to_owned).collect())
            .collect();
        Csv { header, rows }
    }

    /// The file `path`.
    pub fn read(path: &Path) -> Csv {
        Csv::parse(&super::read(path))
    }

    /// Checks that every field is a number ("nan" and "inf" included); returns the file.
    pub fn numeric(self) -> Csv {
        self.numbers();
        self
    }

    /// Checks that every row has as many fields as the header; returns the file.
    pub fn rectangular(self) -> Csv {
        for (i, r) in self.rows.iter().enumerate() {
            assert_eq!(
                r.len(),
                self.header.len(),
                "row {i} has {} fields under a header of {}: {:?}",
                r.len(),
                self.header.len(),
                self.header
            );
        }
        self
    }

    /// Every row as numbers (each field must be one).
    pub fn numbers(&self) -> Vec<Vec<f64>> {
        self.rows
            .iter()
            .map(|r| r.iter().map(|f| number(f, r)).collect())
            .collect()
    }

    /// The position of column `name`.
    pub fn index(&self, name: &str) -> usize {
        self.header
            .iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("no column {name} in {:?}", self.header))
    }

    /// Column `name` as numbers.
    pub fn col(&self, name: &str) -> Vec<f64> {
        let c = self.index(name);
        self.rows.iter().map(|r| number(&r[c], r)).collect()
    }

    /// Column `name` in the last row.
    pub fn last(&self, name: &str) -> f64 {
        *self.col(name).last().expect("a row")
    }

    /// Column `name` in the row whose first column is the time `t`.
    pub fn at(&self, t: f64, name: &str) -> f64 {
        let c = self.index(name);
        let r = self
            .rows
            .iter()
            .find(|r| (number(&r[0], r) - t).abs() < 1e-9)
            .unwrap_or_else(|| panic!("no row at t = {t}"));
        number(&r[c], r)
    }
}

fn number(field: &str, row: &[String]) -> f64 {
    field
        .parse()
        .unwrap_or_else(|_| panic!("{field} in {}", row.join(",")))
}
