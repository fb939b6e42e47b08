//! The data files of a study's folder: `<V>.csv`, `<V>_pdf.csv`, `<V>_sobol.csv`,
//! `<q>_pdf.csv`, `<q>_samples.csv`, `<q>_convergence.csv`, `points.csv` and the units
//! sidecar `units.csv`.

use crate::report::file_name::stem;
use std::fmt::Write as _;
use std::path::Path;

use super::super::csv::{push_field, push_shortest};
use super::super::{write_bytes, write_columns, write_grid, ReportError};
use super::quantile_column;
use crate::results::{Convergence, OutputStats, PointStatus, PointTable, ScalarStats};
use crate::uq::method::Sobol;

/// `<V>_pdf.csv`: the PDF evolution in long format (empty for a deterministic output).
pub(super) fn pdf_csv(dir: &Path, s: &OutputStats) -> Result<(), ReportError> {
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
/// intervals, `S_<p>_lo,S_<p>_hi...,ST_<p>_lo,ST_<p>_hi...`.
pub(super) fn sobol_csv(dir: &Path, s: &OutputStats, names: &[&str]) -> Result<(), ReportError> {
    let Some(Sobol {
        first,
        total,
        intervals,
    }) = &s.sobol
    else {
        return Ok(());
    };
    let mut header = vec!["time".to_string()];
    header.extend(names.iter().map(|n| format!("S_{n}")));
    header.extend(names.iter().map(|n| format!("ST_{n}")));
    let mut data: Vec<Vec<f64>> = (0..names.len())
        .map(|j| column(first, j))
        .chain((0..names.len()).map(|j| column(total, j)))
        .collect();
    if let Some(ci) = intervals {
        for (label, rows) in [("S", &ci.first), ("ST", &ci.total)] {
            for (j, n) in names.iter().enumerate() {
                header.push(format!("{label}_{n}_lo"));
                header.push(format!("{label}_{n}_hi"));
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
    let header: Vec<String> = names
        .iter()
        .map(|n| format!("S_{n}"))
        .chain(names.iter().map(|n| format!("ST_{n}")))
        .collect();
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

/// `<q>_pdf.csv`: `x,density` (header only for a deterministic quantity).
pub(super) fn scalar_pdf_csv(dir: &Path, q: &ScalarStats) -> Result<(), ReportError> {
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
    if c.axis == "runs" {
        write_columns(&path, &["runs", "mean", "std"], &[&c.x, &c.mean, &c.std])
    } else {
        write_columns(
            &path,
            &["order", "mean", "std", "std_of_order"],
            &[&c.x, &c.mean, &c.std, &c.std_of_order],
        )
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
/// without a declared unit are left out; dimensionless ones have unit `1`.
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
    for s in outputs {
        let file = format!("{}.csv", stem(&s.name));
        let u = s.unit.as_deref();
        for col in output_columns(s).0 {
            push(&file, &col, if col == "time" { Some("s") } else { u });
        }
        let file = format!("{}_pdf.csv", stem(&s.name));
        push(&file, "time", Some("s"));
        push(&file, "x", u);
        push(&file, "density", super::super::units::per(u).as_deref());
        if s.sobol.is_some() {
            let file = format!("{}_sobol.csv", stem(&s.name));
            push(&file, "time", Some("s"));
            for n in names {
                push(&file, &format!("S_{n}"), Some("1"));
                push(&file, &format!("ST_{n}"), Some("1"));
            }
        }
        if overall_sobol(s).is_some() {
            let file = format!("{}_sobol_overall.csv", stem(&s.name));
            for n in names {
                push(&file, &format!("S_{n}"), Some("1"));
                push(&file, &format!("ST_{n}"), Some("1"));
            }
        }
    }
    for q in quantities {
        let u = q.unit.as_deref();
        let file = format!("{}_pdf.csv", stem(&q.name));
        push(&file, "x", u);
        push(&file, "density", super::super::units::per(u).as_deref());
        push(&format!("{}_samples.csv", stem(&q.name)), &q.name, u);
        let file = format!("{}_convergence.csv", stem(&q.name));
        push(&file, "mean", u);
        push(&file, "std", u);
        push(&file, "std_of_order", u);
    }
    if let Some(t) = points {
        if t.weights.is_some() {
            push("points.csv", "weight", Some("1"));
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
