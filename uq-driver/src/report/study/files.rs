//! The data files of a study's folder: `<V>.csv`, `<V>_pdf.csv`, `<V>_sobol.csv`,
//! `<q>_pdf.csv`, `<q>_samples.csv`, `<q>_convergence.csv`, `points.csv` and the units
//! sidecar `units.csv`.

use crate::report::file_name::stem;
use std::fmt::Write as _;
use std::path::Path;

use super::super::csv::{push_field, push_shortest};
use super::super::units::DIMENSIONLESS;
use super::super::{write_bytes, write_columns, write_grid, ReportError};
use super::quantile_column;
use crate::results::{Convergence, OutputStats, PointStatus, PointTable, ScalarStats};
use crate::uq::method::Sobol;

/// `<V>_pdf.csv`: the PDF evolution in long format; none for a deterministic output (the
/// same in every run: no density).
pub(super) fn pdf_csv(dir: &Path, s: &OutputStats) -> Result<(), ReportError> {
    if s.deterministic {
        return Ok(());
    }
    write_grid(
        &dir.join(format!("{}_pdf.csv", stem(&s.name))),
        &s.pdf_times,
        &s.pdf_grid,
        &s.pdf,
    )
}

/// `<V>.csv`: time, mean, std, the ±3σ band, the quantiles and (collocation) `std_pce`.
pub(super) fn output_csv(dir: &Path, s: &OutputStats) -> Result<(), ReportError> {
    let (header, cols) = output_columns(s);
    let hdr: Vec<&str> = header.iter().map(String::as_str).collect();
    write_columns(&dir.join(format!("{}.csv", stem(&s.name))), &hdr, &cols)
}

fn output_columns(s: &OutputStats) -> (Vec<String>, Vec<&[f64]>) {
    let mut header: Vec<String> = ["time", "mean", "std", "lower_3sigma", "upper_3sigma"]
        .iter()
        .map(|x| x.to_string())
        .collect();
    let mut cols: Vec<&[f64]> = vec![&s.times, &s.mean, &s.std, &s.lower_3sigma, &s.upper_3sigma];
    for (p, q) in &s.quantiles {
        header.push(quantile_column(*p));
        cols.push(q);
    }
    if let Some(sp) = &s.std_pce {
        header.push("std_pce".into());
        cols.push(sp);
    }
    if let Some(se) = &s.std_error_mean {
        header.push("std_error_mean".into());
        cols.push(se);
    }
    if let Some(e) = &s.chaos_error {
        header.push(e.kind.name().into());
        cols.push(&e.values);
    }
    (header, cols)
}

/// Index `j` of every row.
pub(super) fn column(rows: &[Vec<f64>], j: usize) -> Vec<f64> {
    rows.iter().map(|r| r[j]).collect()
}

/// `<V>_sobol.csv`: `time,S_<p>...,ST_<p>...`, then, where the method gives confidence
/// intervals, `S_<p>_lo,S_<p>_hi...,ST_<p>_lo,ST_<p>_hi...` (first-order indices from given
/// data: `time,S_<p>...` only).
pub(super) fn sobol_csv(dir: &Path, s: &OutputStats, names: &[&str]) -> Result<(), ReportError> {
    let Some(Sobol {
        first,
        total,
        intervals,
        given_data,
    }) = &s.sobol
    else {
        return Ok(());
    };
    let mut header = vec!["time".to_string()];
    header.extend(sobol_columns(names, intervals.is_some(), !given_data));
    let totals = if *given_data { 0 } else { names.len() };
    let mut data: Vec<Vec<f64>> = (0..names.len())
        .map(|j| column(first, j))
        .chain((0..totals).map(|j| column(total, j)))
        .collect();
    if let Some(ci) = intervals {
        for rows in [&ci.first, &ci.total] {
            for j in 0..names.len() {
                data.push(rows.iter().map(|r| r[j].0).collect());
                data.push(rows.iter().map(|r| r[j].1).collect());
            }
        }
    }
    let mut cols: Vec<&[f64]> = vec![&s.times];
    cols.extend(data.iter().map(Vec::as_slice));
    let hdr: Vec<&str> = header.iter().map(String::as_str).collect();
    write_columns(
        &dir.join(format!("{}_sobol.csv", stem(&s.name))),
        &hdr,
        &cols,
    )
}

/// What `<V>_sobol.csv` holds, for the page's paragraph on the Sobol' indices over time: the
/// total indices beside the first-order ones, or, for indices from given data (`mc`, `lhs`,
/// `qmc`: the runs binned by each parameter), the first-order ones only.
pub(super) fn sobol_csv_sentence(s: &OutputStats) -> &'static str {
    match &s.sobol {
        Some(sobol) if sobol.given_data => {
            "The indices are estimated from the runs themselves (given data): the CSV file \
             has the first-order indices only; the method gives no total indices (sobol_sampling \
             or a chaos method gives them)."
        }
        _ => "The total indices are in the CSV file.",
    }
}

/// The index columns of `<V>_sobol.csv` after `time`: `S_<p>...,ST_<p>...`, then with
/// intervals `S_<p>_lo,S_<p>_hi...,ST_<p>_lo,ST_<p>_hi...`.
fn sobol_columns(names: &[&str], intervals: bool, total: bool) -> Vec<String> {
    let mut header: Vec<String> = names.iter().map(|n| format!("S_{n}")).collect();
    if !total {
        return header;
    }
    header.extend(names.iter().map(|n| format!("ST_{n}")));
    if intervals {
        for label in ["S", "ST"] {
            for n in names {
                header.push(format!("{label}_{n}_lo"));
                header.push(format!("{label}_{n}_hi"));
            }
        }
    }
    header
}

/// `<V>_sobol_overall.csv`: one row, `S_<p>...,ST_<p>...`, the Sobol' indices of the whole
/// series ([`Sobol::integrated`]); not written where the output has no indices or no spread.
pub(super) fn sobol_overall_csv(
    dir: &Path,
    s: &OutputStats,
    names: &[&str],
) -> Result<(), ReportError> {
    let Some((first, total)) = overall_sobol(s) else {
        return Ok(());
    };
    let header = sobol_columns(names, false, true);
    let values: Vec<[f64; 1]> = first.iter().chain(&total).map(|&v| [v]).collect();
    let cols: Vec<&[f64]> = values.iter().map(|v| &v[..]).collect();
    let hdr: Vec<&str> = header.iter().map(String::as_str).collect();
    write_columns(
        &dir.join(format!("{}_sobol_overall.csv", stem(&s.name))),
        &hdr,
        &cols,
    )
}

/// The Sobol' indices of the whole series of `s` (variance-weighted over time), where it has
/// indices over time and some spread.
pub(super) fn overall_sobol(s: &OutputStats) -> Option<(Vec<f64>, Vec<f64>)> {
    s.sobol
        .as_ref()
        .filter(|_| !s.deterministic)?
        .integrated(&s.times, &s.std)
}

/// `<q>_pdf.csv`: `x,density`; none for a deterministic quantity, nor for one without a
/// density (an adaptive study's: its runs are not samples of the inputs' law).
pub(super) fn scalar_pdf_csv(dir: &Path, q: &ScalarStats) -> Result<(), ReportError> {
    if q.deterministic || q.pdf.is_empty() {
        return Ok(());
    }
    write_columns(
        &dir.join(format!("{}_pdf.csv", stem(&q.name))),
        &["x", "density"],
        &[&q.pdf_x, &q.pdf],
    )
}

/// `<q>_samples.csv`: `run,<q>`, the valid values of the runs.
pub(super) fn scalar_samples(dir: &Path, q: &ScalarStats) -> Result<(), ReportError> {
    let idx: Vec<f64> = (0..q.samples.len()).map(|i| i as f64).collect();
    write_columns(
        &dir.join(format!("{}_samples.csv", stem(&q.name))),
        &["run", &q.name],
        &[&idx, &q.samples],
    )
}

/// `<name>_convergence.csv`: `runs,mean,std` (running estimates over the first n runs), or
/// `order,mean,std,std_of_order` (the chaos truncated at each total order, and the Std of
/// the terms of that order alone).
pub(super) fn convergence_csv(dir: &Path, name: &str, c: &Convergence) -> Result<(), ReportError> {
    let path = dir.join(format!("{}_convergence.csv", stem(name)));
    let header = convergence_columns(c);
    let cols: [&[f64]; 4] = [&c.x, &c.mean, &c.std, &c.std_of_order];
    write_columns(&path, header, &cols[..header.len()])
}

/// The columns of `<name>_convergence.csv`: `runs,mean,std` or `order,mean,std,std_of_order`.
fn convergence_columns(c: &Convergence) -> &'static [&'static str] {
    if c.axis == "runs" {
        &["runs", "mean", "std"]
    } else {
        &["order", "mean", "std", "std_of_order"]
    }
}

/// `points.csv`: `index[,weight],<parameters>,status`.
pub fn points_csv(path: &Path, t: &PointTable) -> Result<(), ReportError> {
    let mut text = String::from("index");
    if t.weights.is_some() {
        text.push_str(",weight");
    }
    for n in &t.names {
        text.push(',');
        push_field(&mut text, n);
    }
    text.push_str(",status\n");
    for (i, vals) in t.values.iter().enumerate() {
        let _ = write!(text, "{i}");
        if let Some(w) = &t.weights {
            text.push(',');
            push_shortest(&mut text, w[i]);
        }
        for v in vals {
            text.push(',');
            push_shortest(&mut text, *v);
        }
        let status = match &t.status[i] {
            PointStatus::Ok => "ok".to_string(),
            PointStatus::Failed(m) => format!("\"failed: {}\"", m.replace('"', "'")),
            PointStatus::Missing => "missing".into(),
        };
        let _ = writeln!(text, ",{status}");
    }
    write_bytes(path, text.as_bytes())
}

/// `units.csv`: `file,column,unit` for every numeric column of the CSV files written (the
/// files keep their column names; this says what each number is measured in). Columns
/// without a declared unit (and counts: `runs`, `order`, `run`, `index`) are left out;
/// dimensionless ones (Sobol' indices and their intervals, the chaos truncation-error
/// estimates `order_difference` / `level_difference` / `loo`, which are shares of the
/// variance, and weights) have unit `1`. The columns are those the writers above write.
pub(super) fn units_csv(
    dir: &Path,
    outputs: &[OutputStats],
    quantities: &[ScalarStats],
    names: &[&str],
    units: &std::collections::BTreeMap<String, String>,
    points: Option<&PointTable>,
) -> Result<(), ReportError> {
    let mut rows: Vec<(String, String, String)> = Vec::new();
    let mut push = |file: &str, col: &str, unit: Option<&str>| {
        if let Some(u) = unit {
            rows.push((file.to_owned(), col.to_owned(), u.to_owned()));
        }
    };
    let per = |u: Option<&str>| super::super::units::per(u);
    for s in outputs {
        let file = format!("{}.csv", stem(&s.name));
        let u = s.unit.as_deref();
        let error = s.chaos_error.as_ref().map(|e| e.kind.name());
        for col in output_columns(s).0 {
            let unit = match col.as_str() {
                "time" => Some("s"),
                c if Some(c) == error => Some(DIMENSIONLESS),
                _ => u,
            };
            push(&file, &col, unit);
        }
        if !s.deterministic {
            let file = format!("{}_pdf.csv", stem(&s.name));
            push(&file, "time", Some("s"));
            push(&file, "x", u);
            push(&file, "density", per(u).as_deref());
        }
        if let Some(sobol) = &s.sobol {
            let file = format!("{}_sobol.csv", stem(&s.name));
            push(&file, "time", Some("s"));
            for col in sobol_columns(names, sobol.intervals.is_some(), !sobol.given_data) {
                push(&file, &col, Some(DIMENSIONLESS));
            }
        }
        if overall_sobol(s).is_some() {
            let file = format!("{}_sobol_overall.csv", stem(&s.name));
            for col in sobol_columns(names, false, true) {
                push(&file, &col, Some(DIMENSIONLESS));
            }
        }
        if let Some(c) = &s.convergence {
            let file = format!("{}_convergence.csv", stem(&s.name));
            for col in &convergence_columns(c)[1..] {
                push(&file, col, u);
            }
        }
    }
    for q in quantities {
        let u = q.unit.as_deref();
        if !q.deterministic && !q.pdf.is_empty() {
            let file = format!("{}_pdf.csv", stem(&q.name));
            push(&file, "x", u);
            push(&file, "density", per(u).as_deref());
        }
        push(&format!("{}_samples.csv", stem(&q.name)), &q.name, u);
        if let Some(c) = &q.convergence {
            let file = format!("{}_convergence.csv", stem(&q.name));
            for col in &convergence_columns(c)[1..] {
                push(&file, col, u);
            }
        }
    }
    if let Some(t) = points {
        if t.weights.is_some() {
            push("points.csv", "weight", Some(DIMENSIONLESS));
        }
        for n in &t.names {
            push("points.csv", n, units.get(n).map(String::as_str));
        }
    }
    let mut text = String::from("file,column,unit\n");
    for (f, c, u) in rows {
        let _ = writeln!(text, "{},{},{}", csv_cell(&f), csv_cell(&c), csv_cell(&u));
    }
    write_bytes(&dir.join("units.csv"), text.as_bytes())
}

fn csv_cell(s: &str) -> String {
    let mut out = String::new();
    push_field(&mut out, s);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_page_promises_no_total_indices_for_given_data_sobol() {
        let sobol = |given_data| Sobol {
            first: vec![vec![0.25, 0.75]],
            total: if given_data {
                Vec::new()
            } else {
                vec![vec![0.25, 0.75]]
            },
            intervals: None,
            given_data,
        };
        let mut s = OutputStats::constant("y", vec![0.0], 1.0, 0.5);
        s.sobol = Some(sobol(true));
        let given = sobol_csv_sentence(&s);
        assert!(!given.contains("total indices are in"), "{given}");
        assert!(given.contains("first-order indices only"), "{given}");
        // The CSV file written for given data has no ST_ column, as the sentence says.
        let dir = tempfile::tempdir().unwrap();
        sobol_csv(dir.path(), &s, &["a", "b"]).unwrap();
        let csv = std::fs::read_to_string(dir.path().join("y_sobol.csv")).unwrap();
        assert_eq!(csv.lines().next(), Some("time,S_a,S_b"));
        s.sobol = Some(sobol(false));
        assert_eq!(
            sobol_csv_sentence(&s),
            "The total indices are in the CSV file."
        );
    }
}
