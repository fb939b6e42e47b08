//! One page comparing finished study folders (`uq-driver compare DIR... --out DIR`; `make
//! run` writes `out/index.html` this way): a table of the studies (method, runs, wall time
//! of each stage, the outputs at the stop time, the scalar quantities), and for every output
//! and quantity that several studies share, their bands, Std and PDFs in one plot each.
//! Everything is read back from the folders' `summary.json` and CSV files.

use crate::report::file_name::stem;
use std::path::{Component, Path, PathBuf};

use serde_json::Value;

use super::units::label;
use super::{
    palette, write_columns, Band, DensityPlot, LinePlot, ReportError, ReportPage, Section, Series,
    Table,
};
use crate::results::numbers::count;
use crate::results::sig;

/// A file of a study folder that cannot be read, or is not what `uq-driver run` writes.
#[derive(Debug, thiserror::Error)]
pub enum FolderFileError {
    /// A file could not be read.
    #[error("cannot read {}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// A file is not what `uq-driver run` writes (for an export: not a finished study written
    /// by this version).
    #[error("{}: {message}", path.display())]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
}

impl FolderFileError {
    /// `path` could not be read.
    pub(crate) fn read(path: &Path, source: std::io::Error) -> FolderFileError {
        FolderFileError::Read {
            path: path.to_path_buf(),
            source,
        }
    }

    /// `path` is not what `uq-driver run` writes.
    pub(crate) fn invalid(path: &Path, message: impl Into<String>) -> FolderFileError {
        FolderFileError::Invalid {
            path: path.to_path_buf(),
            message: message.into(),
        }
    }
}

/// Why a folder cannot be compared.
#[derive(Debug, thiserror::Error)]
pub enum CompareError {
    /// A file cannot be read, or is not what `uq-driver run` writes.
    #[error(transparent)]
    File(#[from] FolderFileError),
    /// Writing the page failed.
    #[error(transparent)]
    Report(#[from] ReportError),
}

/// A study folder as read back.
struct Folder {
    dir: PathBuf,
    summary: Value,
    /// How the page, its plots and CSV columns call the study: unique among the folders
    /// compared ([`labels`]).
    label: String,
}

impl Folder {
    fn study(&self) -> &str {
        self.summary["study"].as_str().unwrap_or("?")
    }

    fn name(&self) -> String {
        self.label.clone()
    }

    fn unit(&self, var: &str) -> Option<String> {
        self.summary["units"][var].as_str().map(str::to_owned)
    }
}

fn read(path: &Path) -> Result<String, FolderFileError> {
    std::fs::read_to_string(path).map_err(|source| FolderFileError::read(path, source))
}

/// The study folders in `dirs`; a suite's folder stands for its variants' folders.
fn folders(dirs: &[PathBuf]) -> Result<Vec<Folder>, CompareError> {
    let mut out = Vec::new();
    for dir in dirs {
        let path = dir.join("summary.json");
        let summary: Value = serde_json::from_str(&read(&path)?)
            .map_err(|e| FolderFileError::invalid(&path, format!("not JSON: {e}")))?;
        if let Some(variants) = summary["variants"]
            .as_array()
            .filter(|_| summary["suite"].is_string())
        {
            let subs: Vec<PathBuf> = variants
                .iter()
                .filter_map(|v| v["folder"].as_str())
                .map(|f| dir.join(f))
                .collect();
            out.extend(folders(&subs)?);
        } else if summary["study"].is_string() {
            out.push(Folder {
                dir: dir.clone(),
                summary,
                label: String::new(),
            });
        } else {
            return Err(FolderFileError::invalid(
                &path,
                "not the summary of a study or suite written by uq-driver",
            )
            .into());
        }
    }
    Ok(out)
}

/// Columns of a CSV file written by uq-driver (a header, then numbers).
struct Csv {
    header: Vec<String>,
    columns: Vec<Vec<f64>>,
}

impl Csv {
    fn read(path: &Path) -> Result<Csv, CompareError> {
        let text = read(path)?;
        let mut lines = text.lines();
        let header: Vec<String> = lines
            .next()
            .unwrap_or("")
            .split(',')
            .map(str::to_owned)
            .collect();
        let mut columns = vec![Vec::new(); header.len()];
        for (i, line) in lines.enumerate() {
            for (j, cell) in line.split(',').enumerate().take(header.len()) {
                let v: f64 = cell.trim().parse().map_err(|_| {
                    FolderFileError::invalid(
                        path,
                        format!("line {}: '{cell}' is not a number", i + 2),
                    )
                })?;
                columns[j].push(v);
            }
        }
        Ok(Csv { header, columns })
    }

    fn column(&self, name: &str) -> Option<&[f64]> {
        let j = self.header.iter().position(|h| h == name)?;
        Some(&self.columns[j])
    }
}

/// `target` relative to the folder `from` (both made absolute), for links.
fn relative(target: &Path, from: &Path) -> PathBuf {
    let abs = |p: &Path| {
        std::fs::canonicalize(p).unwrap_or_else(|_| {
            std::env::current_dir()
                .map(|c| c.join(p))
                .unwrap_or_else(|_| p.to_path_buf())
        })
    };
    let (t, f) = (abs(target), abs(from));
    let tc: Vec<Component> = t.components().collect();
    let fc: Vec<Component> = f.components().collect();
    let common = tc.iter().zip(&fc).take_while(|(a, b)| a == b).count();
    let mut out = PathBuf::new();
    for _ in common..fc.len() {
        out.push("..");
    }
    for c in &tc[common..] {
        out.push(c.as_os_str());
    }
    out
}

/// Names of the outputs (or quantities, `key`) of a summary.
fn names(f: &Folder, key: &str) -> Vec<String> {
    f.summary[key]
        .as_object()
        .map(|m| m.keys().cloned().collect())
        .unwrap_or_default()
}

/// The label of each study (`(study name, folder)`, in the order given): its name where no
/// other study compared has that name (today's labels); otherwise its folder's name (the last
/// part of the path); a label that is still taken gets `-2`, `-3`, … (the first free one).
fn labels(studies: &[(String, &Path)]) -> Vec<String> {
    let folder = |d: &Path| {
        std::fs::canonicalize(d)
            .unwrap_or_else(|_| d.to_path_buf())
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
    };
    let unique = |name: &String| studies.iter().filter(|(n, _)| n == name).count() == 1;
    let wanted: Vec<String> = studies
        .iter()
        .map(|(name, dir)| match unique(name) {
            true => name.clone(),
            false => folder(dir).unwrap_or_else(|| name.clone()),
        })
        .collect();
    // The unique names are kept as they are; the others take what is left, in order.
    let mut out: Vec<Option<String>> = studies
        .iter()
        .map(|(name, _)| unique(name).then(|| name.clone()))
        .collect();
    for i in 0..studies.len() {
        if out[i].is_some() {
            continue;
        }
        let free = |l: &String, out: &[Option<String>]| {
            !out.iter().flatten().any(|o| o == l)
                && (l == &wanted[i] || !wanted.iter().any(|w| w == l))
        };
        let mut label = wanted[i].clone();
        let mut k = 2;
        while !free(&label, &out) {
            label = format!("{}-{k}", wanted[i]);
            k += 1;
        }
        out[i] = Some(label);
    }
    out.into_iter().flatten().collect()
}

/// Writes `out/index.html` (and its plots and `compare.csv`) comparing the study folders
/// `dirs`.
pub fn write(dirs: &[PathBuf], out: &Path) -> Result<(), CompareError> {
    let mut studies = folders(dirs)?;
    let named: Vec<(String, &Path)> = studies
        .iter()
        .map(|f| (f.study().to_owned(), f.dir.as_path()))
        .collect();
    for (label, f) in labels(&named).into_iter().zip(&mut studies) {
        f.label = label;
    }
    std::fs::create_dir_all(out).map_err(|source| ReportError::Io {
        path: out.to_path_buf(),
        source,
    })?;
    let mut sections = vec![table_section(&studies, out)];
    let mut outputs: Vec<String> = Vec::new();
    let mut quantities: Vec<String> = Vec::new();
    for f in &studies {
        for n in names(f, "outputs") {
            if !outputs.contains(&n) {
                outputs.push(n);
            }
        }
        for n in names(f, "quantities") {
            if !quantities.contains(&n) {
                quantities.push(n);
            }
        }
    }
    for v in &outputs {
        sections.push(output_section(&studies, v, out)?);
    }
    for q in &quantities {
        sections.push(quantity_section(&studies, q, out)?);
    }
    ReportPage {
        title: "railuq: studies compared".into(),
        summary_json: String::new(),
        sections,
    }
    .write(&out.join("index.html"))?;
    Ok(())
}

fn num(v: &Value) -> String {
    match (v.as_u64(), v.as_f64()) {
        (Some(i), _) => i.to_string(),
        (None, Some(x)) => sig(x),
        _ => "–".into(),
    }
}

/// The table of the studies, with links to their reports.
fn table_section(studies: &[Folder], out: &Path) -> Section {
    let header: Vec<String> = [
        "study",
        "method",
        "model runs",
        "runs [s]",
        "analysis [s]",
        "report [s]",
        "outputs at the stop time: mean / Std",
        "quantities: mean / Std",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let rows = studies
        .iter()
        .map(|f| {
            let s = &f.summary;
            let outputs: Vec<String> = names(f, "outputs")
                .iter()
                .map(|n| {
                    let o = &s["outputs"][n];
                    format!(
                        "{n}: {} / {}",
                        num(&o["mean_at_stop"]),
                        num(&o["std_at_stop"])
                    )
                })
                .collect();
            let quantities: Vec<String> = names(f, "quantities")
                .iter()
                .map(|n| {
                    let q = &s["quantities"][n];
                    format!("{n}: {} / {}", num(&q["mean"]), num(&q["std"]))
                })
                .collect();
            vec![
                f.name(),
                s["method"]["kind"].as_str().unwrap_or("?").to_owned(),
                num(&s["model_runs"]),
                num(&s["timing"]["runs_s"]),
                num(&s["timing"]["analysis_s"]),
                num(&s["timing"]["report_s"]),
                outputs.join("; "),
                quantities.join("; "),
            ]
        })
        .collect();
    Section {
        heading: "Studies".into(),
        text: "Each study's own report is linked below; the plots further down put the studies \
               side by side (outputs and quantities that several studies share)."
            .into(),
        images: studies
            .iter()
            .map(|f| {
                relative(&f.dir.join("index.html"), out)
                    .display()
                    .to_string()
            })
            .collect(),
        table: Some(Table { header, rows }),
    }
}

/// Bands and Std of output `v` in every study that has it, and `<v>_compare.csv` when the
/// studies share a time grid.
fn output_section(studies: &[Folder], v: &str, out: &Path) -> Result<Section, CompareError> {
    let have: Vec<(&Folder, Csv)> = studies
        .iter()
        .filter(|f| !f.summary["outputs"][v].is_null())
        .map(|f| Csv::read(&f.dir.join(format!("{}.csv", stem(v)))).map(|c| (f, c)))
        .collect::<Result<_, _>>()?;
    let unit = have.first().and_then(|(f, _)| f.unit(v));
    let unit = unit.as_deref();
    let mut bands = LinePlot::new(
        format!("{v}: mean ± 3σ of every study"),
        "time [s]",
        label(v, unit),
    );
    let mut std = LinePlot::new(
        format!("Std of {v} in every study"),
        "time [s]",
        label(&format!("Std {v}"), unit),
    );
    // The studies whose output varies; a deterministic one (a nominal run: Std 0 at every time)
    // is drawn as its value only, and has no Std curve.
    let varies = |c: &Csv| c.column("std").is_some_and(|s| s.iter().any(|&x| x > 0.0));
    let mut deterministic = Vec::new();
    let mut edges = Vec::new();
    for (i, (f, c)) in have.iter().enumerate() {
        let (Some(t), Some(m), Some(s)) = (c.column("time"), c.column("mean"), c.column("std"))
        else {
            continue;
        };
        let name = f.name();
        if !varies(c) {
            deterministic.push(name.clone());
            bands.series.push(Series::new(
                format!("{name} (deterministic)"),
                t.to_vec(),
                m.to_vec(),
                palette(i),
            ));
            continue;
        }
        let (lo, hi) = crate::results::OutputStats::band(m, s, 3.0);
        if bands.bands.is_empty() {
            // The first study that varies: a filled band; the others as outlines, so that
            // overlapping bands do not blend into a colour no legend entry has.
            bands.bands.push(Band::new(
                format!("{name} ±3σ"),
                t.to_vec(),
                lo,
                hi,
                palette(i),
            ));
        } else {
            edges.push(
                Series::new(format!("{name} ±3σ (outline)"), t.to_vec(), hi, palette(i)).dashed(),
            );
            edges.push(Series::new("", t.to_vec(), lo, palette(i)).dashed());
        }
        bands.series.push(Series::new(
            format!("{name} mean"),
            t.to_vec(),
            m.to_vec(),
            palette(i),
        ));
        let line = Series::new(name, t.to_vec(), s.to_vec(), palette(i));
        std.series.push(if std.series.is_empty() {
            line
        } else {
            line.dashed()
        });
    }
    bands.series.splice(0..0, edges);
    bands.write(&out.join(format!("{}_bands.svg", stem(v))))?;
    let mut images = vec![format!("{}_bands.svg", stem(v))];
    if !std.series.is_empty() {
        std.write(&out.join(format!("{}_std.svg", stem(v))))?;
        images.push(format!("{}_std.svg", stem(v)));
    }
    let mut text = format!(
        "{v} in {}: their μ ± 3σ bands (the first filled, the others outlined) and Std over \
         time.",
        count(have.len(), "study", "studies")
    );
    if !deterministic.is_empty() {
        text.push_str(&format!(
            " {} {} the same value in every run (deterministic): drawn as {} value only, \
             without a band or a Std.",
            deterministic.join(", "),
            if deterministic.len() == 1 {
                "has"
            } else {
                "have"
            },
            if deterministic.len() == 1 {
                "its"
            } else {
                "their"
            },
        ));
    }
    // Differences against the first study that varies, where the time grids agree.
    let varying: Vec<&(&Folder, Csv)> = have.iter().filter(|(_, c)| varies(c)).collect();
    if let Some((f0, c0)) = varying.first() {
        let t0 = c0.column("time").unwrap_or(&[]);
        let mut diff = LinePlot::new(
            format!("|Std − Std({})| of {v} (log axis)", f0.name()),
            "time [s]",
            label(&format!("|Δ Std {v}|"), unit),
        );
        diff.log_y = true;
        let mut header = vec!["time".to_string()];
        let mut cols: Vec<Vec<f64>> = vec![t0.to_vec()];
        let mut largest = 0.0f64;
        for (i, (f, c)) in have.iter().enumerate() {
            if c.column("time") != Some(t0) {
                continue;
            }
            header.push(format!("mean_{}", f.name()));
            cols.push(c.column("mean").unwrap_or(&[]).to_vec());
            header.push(format!("std_{}", f.name()));
            cols.push(c.column("std").unwrap_or(&[]).to_vec());
            if f.dir != f0.dir && varies(c) {
                let d: Vec<f64> = c
                    .column("std")
                    .unwrap_or(&[])
                    .iter()
                    .zip(c0.column("std").unwrap_or(&[]))
                    .map(|(a, b)| (a - b).abs())
                    .collect();
                largest = d
                    .iter()
                    .copied()
                    .filter(|x| x.is_finite())
                    .fold(largest, f64::max);
                diff.series
                    .push(Series::new(f.name(), t0.to_vec(), d, palette(i)));
            }
        }
        // One near-zero difference (e.g. at the first time step) must not stretch the log axis
        // over decades where no curve lies: the axis starts 6 decades below the largest.
        let floor = largest * 1e-6;
        for s in &mut diff.series {
            for y in &mut s.y {
                if *y < floor {
                    *y = f64::NAN;
                }
            }
        }
        if cols.len() > 3 {
            let hdr: Vec<&str> = header.iter().map(String::as_str).collect();
            let refs: Vec<&[f64]> = cols.iter().map(Vec::as_slice).collect();
            write_columns(&out.join(format!("{}_compare.csv", stem(v))), &hdr, &refs)?;
            if !diff.series.is_empty() && largest > 0.0 {
                diff.write(&out.join(format!("{}_std_diff.svg", stem(v))))?;
                images.push(format!("{}_std_diff.svg", stem(v)));
                text.push_str(&format!(
                    " The difference of each Std from that of {} is on a log axis (it spans \
                     decades between methods; differences below 1e-6 of the largest are not \
                     drawn).",
                    f0.name()
                ));
            }
            images.push(format!("{}_compare.csv", stem(v)));
        }
    }
    Ok(Section {
        heading: format!("Output {v}"),
        text,
        images,
        table: None,
    })
}

/// PDFs of quantity `q` in every study that has one, and a table of its statistics.
fn quantity_section(studies: &[Folder], q: &str, out: &Path) -> Result<Section, CompareError> {
    let have: Vec<&Folder> = studies
        .iter()
        .filter(|f| !f.summary["quantities"][q].is_null())
        .collect();
    let unit = have.first().and_then(|f| f.unit(q));
    let mut plot = DensityPlot {
        title: format!("PDF of {q} in every study"),
        x_label: label(q, unit.as_deref()),
        ..DensityPlot::default()
    };
    let mut rows = Vec::new();
    let mut limits: Vec<f64> = Vec::new();
    let mut fixed = Vec::new();
    for (i, f) in have.iter().enumerate() {
        let s = &f.summary["quantities"][q];
        let deterministic = s["deterministic"].as_bool().unwrap_or(false);
        if deterministic {
            // No density: its value as a marker line.
            if let Some(x) = s["mean"].as_f64() {
                plot.markers
                    .push((x, format!("{} (deterministic): {}", f.name(), sig(x))));
            }
            fixed.push(f.name());
        } else {
            let c = Csv::read(&f.dir.join(format!("{}_pdf.csv", stem(q))))?;
            if let (Some(x), Some(d)) = (c.column("x"), c.column("density")) {
                plot.curves
                    .push(Series::new(f.name(), x.to_vec(), d.to_vec(), palette(i)));
            }
        }
        for e in s["exceedance_counts"].as_array().into_iter().flatten() {
            if let Some(l) = e["limit"].as_f64() {
                if !limits.contains(&l) {
                    limits.push(l);
                }
            }
        }
        let exceed: Vec<String> = s["exceedance_counts"]
            .as_array()
            .into_iter()
            .flatten()
            .map(|e| {
                format!(
                    "P(> {}): {} of {}",
                    num(&e["limit"]),
                    num(&e["exceeded"]),
                    num(&e["of"])
                )
            })
            .collect();
        rows.push(vec![
            f.name(),
            num(&s["mean"]),
            num(&s["std"]),
            if deterministic {
                format!("{} (deterministic)", num(&s["n_valid"]))
            } else {
                num(&s["n_valid"])
            },
            exceed.join("; "),
        ]);
    }
    for l in limits {
        plot.markers.push((l, format!("limit {q} = {}", sig(l))));
    }
    let mut images = Vec::new();
    if !plot.curves.is_empty() {
        plot.write(&out.join(format!("{}_pdf_compare.svg", stem(q))))?;
        images.push(format!("{}_pdf_compare.svg", stem(q)));
    }
    Ok(Section {
        heading: format!("Quantity {q}"),
        text: if fixed.is_empty() {
            format!("{q} in {}.", count(have.len(), "study", "studies"))
        } else {
            format!(
                "{q} in {}; {} deterministic (its value is marked by a line, without a \
                 density). The limits of the studies are marked.",
                count(have.len(), "study", "studies"),
                fixed.join(", ")
            )
        },
        images,
        table: Some(Table::new(
            &["study", "mean", "Std", "valid runs", "exceedance"],
            rows,
        )),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_links() {
        let d = tempfile::tempdir().unwrap();
        let a = d.path().join("out/wheel-scm");
        let b = d.path().join("out");
        std::fs::create_dir_all(&a).unwrap();
        assert_eq!(
            relative(&a.join("index.html"), &b),
            PathBuf::from("wheel-scm/index.html")
        );
        let c = d.path().join("other/x");
        std::fs::create_dir_all(&c).unwrap();
        assert_eq!(
            relative(&a.join("index.html"), &c),
            PathBuf::from("../../out/wheel-scm/index.html")
        );
    }

    /// A study folder with output `y` on the times 0, 1: `summary.json` and `y.csv`.
    fn study_folder(dir: &Path, name: &str, mean: f64) {
        std::fs::create_dir_all(dir).unwrap();
        let summary = serde_json::json!({
            "study": name,
            "method": {"kind": "mc"},
            "outputs": {"y": {"mean_at_stop": mean, "std_at_stop": 1.0}},
            "quantities": {},
        });
        std::fs::write(dir.join("summary.json"), summary.to_string()).unwrap();
        let csv = format!("time,mean,std\n0,{mean},1\n1,{mean},2\n");
        std::fs::write(dir.join("y.csv"), csv).unwrap();
    }

    /// F7: `compare` of folders whose studies share a `name` wrote `mean_ishi,std_ishi`
    /// once per folder; the columns are now told apart by the folders' names, and unique
    /// study names stay the labels.
    #[test]
    fn compare_of_studies_with_the_same_name_writes_distinct_columns() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path();
        study_folder(&p.join("ishi_qmc"), "ishi", 1.0);
        study_folder(&p.join("ishi_sg5"), "ishi", 2.0);
        study_folder(&p.join("other"), "borehole", 3.0);
        study_folder(&p.join("a/ishi_pce"), "ishi", 4.0);
        // The same folder name under another parent: numbered.
        study_folder(&p.join("b/ishi_pce"), "ishi", 5.0);
        let dirs: Vec<PathBuf> = ["ishi_qmc", "ishi_sg5", "other", "a/ishi_pce", "b/ishi_pce"]
            .iter()
            .map(|f| p.join(f))
            .collect();
        write(&dirs, &p.join("cmp")).unwrap();
        let text = std::fs::read_to_string(p.join("cmp/y_compare.csv")).unwrap();
        assert_eq!(
            text.lines().next().unwrap(),
            "time,mean_ishi_qmc,std_ishi_qmc,mean_ishi_sg5,std_ishi_sg5,mean_borehole,\
             std_borehole,mean_ishi_pce,std_ishi_pce,mean_ishi_pce-2,std_ishi_pce-2"
        );
        assert_eq!(text.lines().nth(1).unwrap(), "0,1,1,2,1,3,1,4,1,5,1");
        // Unique names: the labels are the study names, as before.
        write(&dirs[1..3], &p.join("c2")).unwrap();
        let text = std::fs::read_to_string(p.join("c2/y_compare.csv")).unwrap();
        assert_eq!(
            text.lines().next().unwrap(),
            "time,mean_ishi,std_ishi,mean_borehole,std_borehole"
        );
    }

    #[test]
    fn labels_stay_unique_when_a_folder_is_named_like_another_study() {
        let s = |n: &str| n.to_string();
        let (a, b, c) = (
            Path::new("x/borehole"),
            Path::new("y/borehole"),
            Path::new("z/q"),
        );
        // Two studies "ishi" in folders named like the third study: that one keeps its name.
        let got = labels(&[(s("ishi"), a), (s("borehole"), c), (s("ishi"), b)]);
        assert_eq!(got, ["borehole-2", "borehole", "borehole-3"]);
        // The same folder twice.
        let got = labels(&[(s("ishi"), a), (s("ishi"), a)]);
        assert_eq!(got, ["borehole", "borehole-2"]);
    }

    #[test]
    fn a_deterministic_study_is_compared_by_its_value_without_a_std_or_density() {
        // A nominal study got a "±3σ" entry, a flat Std curve on a
        // −1…1 axis, and its W dropped out of the PDF plot, which also left out the limits.
        let d = tempfile::tempdir().unwrap();
        let p = d.path();
        study_folder(&p.join("a"), "a", 1.0);
        study_folder(&p.join("b"), "b", 1.5);
        let nominal = p.join("nominal");
        std::fs::create_dir_all(&nominal).unwrap();
        let quantity = |mean: f64, deterministic: bool| {
            serde_json::json!({"mean": mean, "std": if deterministic { 0.0 } else { 0.1 },
                "n_valid": 1, "deterministic": deterministic,
                "exceedance_counts": [{"limit": 2.5, "exceeded": 0, "of": 1}]})
        };
        let summary = serde_json::json!({
            "study": "nominal", "method": {"kind": "nominal"},
            "outputs": {"y": {"mean_at_stop": 1.2, "std_at_stop": 0.0}},
            "quantities": {"W": quantity(2.31, true)},
        });
        std::fs::write(nominal.join("summary.json"), summary.to_string()).unwrap();
        std::fs::write(nominal.join("y.csv"), "time,mean,std\n0,1.2,0\n1,1.2,0\n").unwrap();
        for f in ["a", "b"] {
            let path = p.join(f).join("summary.json");
            let mut s: Value =
                serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
            s["quantities"]["W"] = quantity(2.3, false);
            std::fs::write(&path, s.to_string()).unwrap();
            std::fs::write(
                p.join(f).join("W_pdf.csv"),
                "x,density\n2.2,1\n2.3,3\n2.4,1\n",
            )
            .unwrap();
        }
        let out = p.join("cmp");
        write(&[p.join("a"), nominal.clone(), p.join("b")], &out).unwrap();
        let std_svg = std::fs::read_to_string(out.join("y_std.svg")).unwrap();
        assert!(
            !std_svg.contains("nominal"),
            "no Std curve for the deterministic study"
        );
        let bands = std::fs::read_to_string(out.join("y_bands.svg")).unwrap();
        assert!(bands.contains("nominal (deterministic)") && !bands.contains("nominal ±3σ"));
        let pdf = std::fs::read_to_string(out.join("W_pdf_compare.svg")).unwrap();
        assert!(
            pdf.contains("nominal (deterministic): 2.31"),
            "its value is marked"
        );
        assert!(pdf.contains("limit W = 2.5"), "the limits are marked");
        let page = std::fs::read_to_string(out.join("index.html")).unwrap();
        assert!(page.contains("deterministic"), "said in words");
        // Only the deterministic study: no Std plot at all.
        let only = p.join("only");
        write(std::slice::from_ref(&nominal), &only).unwrap();
        assert!(!only.join("y_std.svg").exists());
    }

    #[test]
    fn a_folder_without_a_summary_is_named() {
        let d = tempfile::tempdir().unwrap();
        let e = write(&[d.path().to_path_buf()], &d.path().join("o")).unwrap_err();
        assert!(e.to_string().contains("summary.json"), "{e}");
    }
}
