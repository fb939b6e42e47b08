//! Time-varying inputs from a CSV file (`[inputs] file = "signal.csv"`, `simulate --input`),
//! applied the way fmpy's `simulate_fmu(input=...)` applies them.
//!
//! The file has a header line: the time column (s) first, whatever its name, then one column
//! per variable, named after an input or a tunable parameter of the FMU. Times must not
//! decrease; a time given twice marks a jump (the row before is the value up to that time, the
//! row after the value from then on). Numbers as Rust or Python write them; Boolean columns
//! also take `true`/`false`. Empty lines and lines starting with `#` are skipped.
//!
//! Only a regular file of at most [`MAX_INPUT_FILE_BYTES`] is read, never blocking (a FIFO,
//! a device or a folder is refused before it is opened for reading), and the errors name a
//! line and a column, never the file's text: a wrong path may name a file that is not the
//! user's to show (`/etc/shadow`).
//!
//! fmpy 0.3.32's convention, reproduced exactly:
//! - continuous Real inputs are interpolated linearly, `w0·v0 + w1·v1` with
//!   `w0 = (t1 − t)/(t1 − t0)`, `w1 = 1 − w0`; Integer, Boolean and Enumeration inputs, and
//!   Real inputs of variability discrete or tunable, are held (the last row at or before t);
//! - before the first time and after the last the first and last rows hold;
//! - in initialization mode the inputs are set at the start time, taking the value *before*
//!   a jump there; before each `fmi2DoStep` from t_n they are set at t_n, taking the value
//!   *after* a jump at t_n. The FMU holds them over the step.
//!
//! Times are compared with fmpy's `math.isclose` (relative 1e-9). Unlike fmpy, uq-driver does
//! not add communication points at the file's jumps (it keeps the study's grid): a jump between
//! two grid points takes effect at the next grid point.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::fmu::{Causality, FmuError, Instance, ModelDescription, Variability, VariableKind};

/// A file of input signals that does not fit.
#[derive(Debug, thiserror::Error)]
pub enum InputError {
    /// The file could not be read.
    #[error("input file {}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The file is malformed or names variables that cannot be inputs.
    #[error("input file {}, {where_}: {message}", path.display())]
    Invalid {
        /// The file.
        path: PathBuf,
        /// Line (and column) or "header".
        where_: String,
        /// What is wrong.
        message: String,
    },
}

/// Input signals resolved against an FMU, ready to apply.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct InputTable {
    /// The file (for messages).
    pub path: PathBuf,
    /// Times (s), non-decreasing.
    pub times: Vec<f64>,
    /// Continuous Real inputs: value reference and values, interpolated.
    pub continuous: Vec<(u32, Vec<f64>)>,
    /// Discrete or tunable Real variables: held.
    pub discrete_real: Vec<(u32, Vec<f64>)>,
    /// Integer and Enumeration inputs: held.
    pub integer: Vec<(u32, Vec<i32>)>,
    /// Boolean inputs: held.
    pub boolean: Vec<(u32, Vec<bool>)>,
    /// The variables' names, in file order.
    pub names: Vec<String>,
}

/// Largest input file read (bytes): 256 MiB (a few million rows of a few signals).
pub const MAX_INPUT_FILE_BYTES: u64 = 256 << 20;

/// The text of the input file `path`: a regular file of at most [`MAX_INPUT_FILE_BYTES`],
/// UTF-8. The error never quotes the file.
pub(crate) fn read_input_file(path: &Path) -> Result<String, InputError> {
    in_file::read_text(path, MAX_INPUT_FILE_BYTES).map_err(|e| match e {
        Ok(line) => InputError::Invalid {
            path: path.to_path_buf(),
            where_: format!("line {line}"),
            message: "not UTF-8 text (a CSV file of numbers is expected)".into(),
        },
        Err(in_file::ReadError::Missing(source) | in_file::ReadError::Open(source)) => {
            InputError::Io {
                path: path.to_path_buf(),
                source,
            }
        }
        // "input file f: is a FIFO (named pipe); a regular file is expected"
        Err(other) => InputError::Io {
            path: path.to_path_buf(),
            source: std::io::Error::other(other.to_string()),
        },
    })
}

/// `math.isclose(a, b)` with Python's defaults (relative 1e-9, absolute 0).
pub fn isclose(a: f64, b: f64) -> bool {
    a == b || (a - b).abs() <= 1e-9 * a.abs().max(b.abs())
}

impl InputTable {
    /// Reads `path` and resolves its columns against `md`. Only a regular file of at most
    /// [`MAX_INPUT_FILE_BYTES`] is read, never blocking (a FIFO or a device is refused before
    /// it is opened for reading: the `in-file` crate's rules).
    pub fn load(path: &Path, md: &ModelDescription) -> Result<InputTable, InputError> {
        let text = read_input_file(path)?;
        Self::parse(&text, path, md)
    }

    /// Parses the text of an input file (named `path` in messages).
    pub fn parse(text: &str, path: &Path, md: &ModelDescription) -> Result<InputTable, InputError> {
        let invalid = |where_: String, message: String| InputError::Invalid {
            path: path.to_path_buf(),
            where_,
            message,
        };
        let mut lines = text
            .lines()
            .enumerate()
            .map(|(i, l)| (i + 1, l.trim()))
            .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
        let (_, header) = lines
            .next()
            .ok_or_else(|| invalid("header".into(), "the file is empty".into()))?;
        let names: Vec<String> = header
            .split(',')
            .map(|s| s.trim().trim_matches('"').to_owned())
            .collect();
        if names.len() < 2 {
            return Err(invalid(
                "header".into(),
                "need a time column and at least one input column".into(),
            ));
        }
        let kinds = names[1..]
            .iter()
            .enumerate()
            .map(|(j, n)| column_kind(md, n, j + 2).map_err(|m| invalid("header".into(), m)))
            .collect::<Result<Vec<_>, _>>()?;
        for (j, n) in names.iter().enumerate().skip(1) {
            if names[1..j].contains(n) {
                return Err(invalid(
                    "header".into(),
                    format!("column '{n}' appears twice"),
                ));
            }
        }
        let mut columns: Vec<Vec<f64>> = vec![Vec::new(); names.len()];
        for (line, l) in lines {
            let cells: Vec<&str> = l.split(',').map(str::trim).collect();
            if cells.len() != names.len() {
                return Err(invalid(
                    format!("line {line}"),
                    format!(
                        "{} values, but the header names {}",
                        cells.len(),
                        names.len()
                    ),
                ));
            }
            for (j, cell) in cells.iter().enumerate() {
                let v = parse_cell(cell).ok_or_else(|| {
                    invalid(
                        format!("line {line}, column {}", j + 1),
                        "not a number (nor true or false)".into(),
                    )
                })?;
                columns[j].push(v);
            }
        }
        let times = std::mem::take(&mut columns[0]);
        if times.is_empty() {
            return Err(invalid("data".into(), "no rows after the header".into()));
        }
        if let Some(k) = times.iter().position(|t| !t.is_finite()) {
            return Err(invalid(
                format!("row {}", k + 1),
                "the time is not finite".into(),
            ));
        }
        if let Some(k) = times.windows(2).position(|w| w[1] < w[0]) {
            return Err(invalid(
                format!("row {}", k + 2),
                "the time is less than the row before's: times must not decrease".into(),
            ));
        }
        let mut table = InputTable {
            path: path.to_path_buf(),
            times,
            continuous: Vec::new(),
            discrete_real: Vec::new(),
            integer: Vec::new(),
            boolean: Vec::new(),
            names: names[1..].to_vec(),
        };
        for ((name, (vr, kind)), values) in names[1..].iter().zip(kinds).zip(columns.drain(1..)) {
            let bad = |k: usize, what: &str| {
                invalid(
                    format!("row {}, column '{name}'", k + 1),
                    format!("the value is not {what}"),
                )
            };
            match kind {
                ColumnKind::Continuous => {
                    if let Some(k) = values.iter().position(|v| !v.is_finite()) {
                        return Err(bad(k, "a finite number"));
                    }
                    table.continuous.push((vr, values));
                }
                ColumnKind::HeldReal => {
                    if let Some(k) = values.iter().position(|v| !v.is_finite()) {
                        return Err(bad(k, "a finite number"));
                    }
                    table.discrete_real.push((vr, values));
                }
                ColumnKind::Integer => {
                    let whole = |v: f64| v.fract() == 0.0 && v.abs() <= f64::from(i32::MAX);
                    if let Some(k) = values.iter().position(|&v| !whole(v)) {
                        return Err(bad(k, "a whole number (32-bit)"));
                    }
                    table
                        .integer
                        .push((vr, values.iter().map(|&v| v as i32).collect()));
                }
                ColumnKind::Boolean => {
                    if let Some(k) = values.iter().position(|&v| v != 0.0 && v != 1.0) {
                        return Err(bad(k, "a Boolean (true/false or 1/0)"));
                    }
                    table
                        .boolean
                        .push((vr, values.iter().map(|&v| v == 1.0).collect()));
                }
            }
        }
        Ok(table)
    }

    /// The column that sets the variable `name` of `md`, if one does: compared by base type
    /// and value reference, so that a column naming an alias of the variable counts too.
    pub fn column_for(&self, md: &ModelDescription, name: &str) -> Option<&str> {
        let key = |n: &str| {
            md.variable(n)
                .map(|v| (v.kind.base_type(), v.value_reference))
        };
        let wanted = key(name)?;
        self.names
            .iter()
            .find(|c| key(c) == Some(wanted))
            .map(String::as_str)
    }

    /// Sets every input at time `t` (s); `after_event` takes the value after a jump at `t`.
    pub fn apply(&self, inst: &mut Instance, t: f64, after_event: bool) -> Result<(), FmuError> {
        if !self.continuous.is_empty() {
            let (vrs, vals): (Vec<u32>, Vec<f64>) = self
                .continuous
                .iter()
                .map(|(vr, v)| (*vr, self.interpolate(v, t, after_event)))
                .unzip();
            inst.set_real(&vrs, &vals)?;
        }
        let i = self.held_index(t, after_event);
        if !self.discrete_real.is_empty() {
            let (vrs, vals): (Vec<u32>, Vec<f64>) =
                self.discrete_real.iter().map(|(vr, v)| (*vr, v[i])).unzip();
            inst.set_real(&vrs, &vals)?;
        }
        if !self.integer.is_empty() {
            let (vrs, vals): (Vec<u32>, Vec<i32>) =
                self.integer.iter().map(|(vr, v)| (*vr, v[i])).unzip();
            inst.set_integer(&vrs, &vals)?;
        }
        if !self.boolean.is_empty() {
            let (vrs, vals): (Vec<u32>, Vec<bool>) =
                self.boolean.iter().map(|(vr, v)| (*vr, v[i])).unzip();
            inst.set_boolean(&vrs, &vals)?;
        }
        Ok(())
    }

    /// The row a held input takes at `t` (fmpy's `interpolate(discrete=True)`).
    pub fn held_index(&self, t: f64, after_event: bool) -> usize {
        let ts = &self.times;
        let n = ts.len();
        if n < 2 {
            return 0;
        }
        let i0 = ts.partition_point(|&x| x < t);
        if i0 == 0 {
            return 0;
        }
        if i0 == n {
            return n - 1;
        }
        let mut i = i0 - 1;
        if after_event {
            while i + 1 < n && (ts[i + 1] < t || isclose(t, ts[i + 1])) {
                i += 1;
            }
        }
        i
    }

    /// A continuous input's value at `t` (fmpy's `interpolate(discrete=False)`).
    pub fn interpolate(&self, values: &[f64], t: f64, after_event: bool) -> f64 {
        let ts = &self.times;
        let n = ts.len();
        if n < 2 {
            return values[0];
        }
        let mut i0 = ts.partition_point(|&x| x < t);
        if i0 == 0 {
            return values[0];
        }
        if i0 == n {
            return values[n - 1];
        }
        if isclose(t, ts[i0]) && i0 < n - 1 && isclose(ts[i0], ts[i0 + 1]) {
            if after_event {
                while i0 < n - 1 && isclose(ts[i0], ts[i0 + 1]) {
                    i0 += 1;
                }
            }
            return values[i0];
        }
        let (t0, t1) = (ts[i0 - 1], ts[i0]);
        let w0 = (t1 - t) / (t1 - t0);
        let w1 = 1.0 - w0;
        w0 * values[i0 - 1] + w1 * values[i0]
    }
}

/// How a column is applied.
enum ColumnKind {
    Continuous,
    HeldReal,
    Integer,
    Boolean,
}

/// The value reference and the kind of the variable column `number` (1-based) names. A name
/// that is no variable of the FMU is not quoted (the file may not be an input file at all,
/// and not ours to show); once it names a variable, the name is the FMU's.
fn column_kind(
    md: &ModelDescription,
    name: &str,
    number: usize,
) -> Result<(u32, ColumnKind), String> {
    let var = md.variable(name).ok_or_else(|| {
        // The FMU's own name of a close input or tunable parameter, if any (the column's
        // name is still not quoted).
        let settable = md.variables.iter().filter(|v| {
            v.causality == Causality::Input
                || (v.causality == Causality::Parameter && v.variability == Variability::Tunable)
        });
        let hint = crate::suggest::closest(name, settable.map(|v| v.name.as_str()))
            .map_or(String::new(), |n| format!("; did you mean `{n}`?"));
        format!(
            "column {number} names no variable of the FMU ({}): the columns after the time \
             must be named after inputs or tunable parameters (`uq-driver inspect` lists \
             them){hint}",
            md.model_name
        )
    })?;
    let is_input = var.causality == Causality::Input;
    let tunable = var.causality == Causality::Parameter && var.variability == Variability::Tunable;
    if !is_input && !tunable {
        return Err(format!(
            "column '{name}': the variable has causality {} and variability {}; only inputs and \
             tunable parameters can change during a run",
            var.causality.as_str(),
            var.variability.as_str()
        ));
    }
    let kind = match &var.kind {
        VariableKind::Real { .. }
            if is_input
                && !matches!(
                    var.variability,
                    Variability::Discrete | Variability::Tunable
                ) =>
        {
            ColumnKind::Continuous
        }
        VariableKind::Real { .. } => ColumnKind::HeldReal,
        VariableKind::Integer { .. } | VariableKind::Enumeration { .. } => ColumnKind::Integer,
        VariableKind::Boolean { .. } => ColumnKind::Boolean,
        VariableKind::String { .. } => {
            return Err(format!(
                "column '{name}': String inputs cannot come from a CSV file"
            ))
        }
    };
    Ok((var.value_reference, kind))
}

/// A number, or `true`/`false` (as 1/0).
fn parse_cell(cell: &str) -> Option<f64> {
    let cell = cell.trim_matches('"');
    match cell {
        "true" | "True" | "TRUE" => Some(1.0),
        "false" | "False" | "FALSE" => Some(0.0),
        _ => cell.parse().ok(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table(times: &[f64]) -> InputTable {
        InputTable {
            path: PathBuf::from("t.csv"),
            times: times.to_vec(),
            continuous: Vec::new(),
            discrete_real: Vec::new(),
            integer: Vec::new(),
            boolean: Vec::new(),
            names: Vec::new(),
        }
    }

    #[test]
    fn interpolation_and_jumps_follow_fmpy() {
        // Values computed by hand from fmpy's Input.interpolate (simulation.py, 0.3.32).
        let t = table(&[0.0, 0.5, 0.5, 1.0]);
        let v = [0.0, 1.0, 3.0, -2.0];
        assert_eq!(t.interpolate(&v, -1.0, true), 0.0);
        assert_eq!(t.interpolate(&v, 0.25, true), 0.5);
        assert_eq!(t.interpolate(&v, 0.5, false), 1.0, "before the jump");
        assert_eq!(t.interpolate(&v, 0.5, true), 3.0, "after the jump");
        assert_eq!(t.interpolate(&v, 0.75, true), 0.5);
        assert_eq!(t.interpolate(&v, 2.0, true), -2.0);
        assert_eq!(
            t.held_index(0.5, false),
            0,
            "held: the row before t at a jump"
        );
        assert_eq!(t.held_index(0.5, true), 2);
        assert_eq!(t.held_index(0.4999999999999, true), 2, "isclose");
        assert_eq!(t.held_index(0.7, false), 2);
        assert_eq!(t.held_index(0.0, false), 0);
        assert_eq!(t.held_index(1.0, true), 3);
        assert_eq!(t.held_index(5.0, true), 3);
    }

    #[test]
    fn exact_grid_times_take_the_row_exactly() {
        let t = table(&[0.0, 0.1, 0.3]);
        let v = [1.0, 0.1, 7.0];
        // w0 = 0 at t = t1: 0·v0 + 1·v1.
        assert_eq!(t.interpolate(&v, 0.1, true), 0.1);
        assert_eq!(t.interpolate(&v, 0.3, true), 7.0);
    }
}
