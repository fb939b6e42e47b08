//! `uq-driver export DIR --runs`: every run's time series of a finished study, read back
//! from its results store, as
//! - `runs.csv`: long format `run,time,<output>...` (one row per run and time; `run` is the
//!   design index of `points.csv`), and
//! - `runs.npz`: NumPy arrays, `time` (times), `run` (design indices of the successful
//!   runs), one `runs × times` array per output, and `<parameter>` (the parameters of each
//!   run) — `np.load("runs.npz")["q"]`.
//!
//! The `.npz` is a zip of `.npy` files (format 1.0: magic, a header dict, little-endian
//! `<f8` / `<i8` data in C order), written here with the zip crate: a dependency on
//! ndarray for this alone is not worth it.

use std::fmt::Write as _;
use std::io::Write as _;
use std::ops::Range;
use std::path::{Path, PathBuf};

use serde_json::Value;

use crate::report::compare::FolderFileError;
use crate::report::ReportError;
use crate::spec::Experiment;
use crate::study::store::format::{self, Slot};
use crate::study::store::lock::{FolderLock, LockError};
use crate::study::store::Manifest;
use crate::text::csv::{push_header, split_line};
use crate::text::file_name::stem;
use out_file::OutFile;

/// Why the runs cannot be exported.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    /// A file of the folder cannot be read, or the folder is not a finished study written by
    /// this version of `uq-driver run`.
    #[error(transparent)]
    File(#[from] FolderFileError),
    /// Writing failed.
    #[error(transparent)]
    Report(#[from] ReportError),
    /// A run holds the folder (or its lock file cannot be written).
    #[error("cannot export {}: cannot take the folder's lock", path.display())]
    Locked {
        /// The study folder.
        path: PathBuf,
        /// Why.
        #[source]
        source: LockError,
    },
    /// Writing the zip failed.
    #[error("cannot write {}", path.display())]
    Zip {
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        source: zip::result::ZipError,
    },
}

/// What was exported.
#[derive(Clone, Debug)]
pub struct Exported {
    /// Successful runs.
    pub runs: usize,
    /// Times per run.
    pub times: usize,
    /// The outputs.
    pub outputs: Vec<String>,
    /// `runs.csv`.
    pub csv: PathBuf,
    /// `runs.npz`.
    pub npz: PathBuf,
}

fn read(path: &Path) -> Result<Vec<u8>, FolderFileError> {
    std::fs::read(path).map_err(|source| FolderFileError::read(path, source))
}

fn invalid(path: &Path, message: impl Into<String>) -> ExportError {
    FolderFileError::invalid(path, message).into()
}

/// When `summary` is a suite's (`suite` and `variants`, no study of its own), what to export
/// instead: the folder holds one study folder per variant, each with its runs, e.g. `a suite's
/// folder (suite wheel): export one of its variants' folders, e.g. `uq-driver export
/// out/scm-3 --runs` (variants with runs: scm-3, lhs)`.
fn suite_folder(dir: &Path, summary: &Value) -> Option<String> {
    let (Some(suite), Some(variants)) = (summary["suite"].as_str(), summary["variants"].as_array())
    else {
        return None;
    };
    // Variants that ran the model: an intrusive method (SGM) runs none (its folder's
    // `summary.json` has no FMU, though its `model_runs` counts its one solve).
    let ran_model = |folder: &str| {
        std::fs::read(dir.join(folder).join("summary.json"))
            .ok()
            .and_then(|b| serde_json::from_slice::<Value>(&b).ok())
            .is_none_or(|v| !v["fmu"].is_null())
    };
    let with_runs: Vec<&str> = variants
        .iter()
        .filter_map(|v| v["folder"].as_str())
        .filter(|f| ran_model(f))
        .collect();
    let Some(first) = with_runs.first() else {
        return Some(format!(
            "a suite's folder (suite {suite}) whose variants made no model runs: nothing to \
             export"
        ));
    };
    Some(format!(
        "a suite's folder (suite {suite}), not a study's: each variant's runs are in its own \
         folder; export one of them, e.g. `uq-driver export {} --runs` (variants with runs: \
         {})",
        dir.join(first).display(),
        with_runs.join(", ")
    ))
}

/// Writes `runs.csv` and `runs.npz` of the study in `dir` into `out`.
pub fn runs(dir: &Path, out: &Path) -> Result<Exported, ExportError> {
    let sp = dir.join("summary.json");
    let summary: Value =
        serde_json::from_slice(&read(&sp)?).map_err(|e| invalid(&sp, format!("not JSON: {e}")))?;
    if let Some(message) = suite_folder(dir, &summary) {
        return Err(invalid(dir, message));
    }
    if summary["fmu"].is_null() && summary["method"]["kind"].is_string() {
        // An intrusive method (SGM) solves its own system once: no runs, no store.
        let kind = summary["method"]["kind"].as_str().unwrap_or_default();
        let what = match crate::uq::method::notes_of_kind(kind).name {
            Some(name) => name.to_string(),
            None => format!("a {kind} study"),
        };
        return Err(invalid(
            dir,
            format!(
                "{what} has no model runs to export (its Galerkin system was solved once, \
                 without an FMU; the results are in the folder's CSV files)"
            ),
        ));
    }
    let outputs: Vec<String> = serde_json::from_value(summary["record_layout"]["outputs"].clone())
        .map_err(|_| {
            invalid(
                &sp,
                "no record_layout: written by an older uq-driver (run the study again)",
            )
        })?;
    let experiment: Experiment = serde_json::from_value(summary["experiment"].clone())
        .map_err(|e| invalid(&sp, format!("experiment: {e}")))?;
    let times = experiment.times();
    let nt = times.len();
    let mp = dir.join("store").join("manifest.json");
    let manifest: Manifest = serde_json::from_slice(&read(&mp)?)
        .map_err(|e| invalid(&mp, format!("not a store manifest: {e}")))?;
    if manifest.n_values < outputs.len() * nt {
        return Err(invalid(
            &mp,
            format!(
                "records hold {} values, fewer than {} outputs × {nt} times",
                manifest.n_values,
                outputs.len()
            ),
        ));
    }
    let rp = dir.join("store").join("records.bin");
    let parameters = read_points(&dir.join("points.csv"))?;
    std::fs::create_dir_all(out).map_err(|source| ReportError::Io {
        path: out.to_path_buf(),
        source,
    })?;
    // A run writing the folder meanwhile could cut the store under the map: take its lock.
    let _lock = FolderLock::acquire(dir).map_err(|source| ExportError::Locked {
        path: dir.to_path_buf(),
        source,
    })?;
    let file = std::fs::File::open(&rp).map_err(|source| FolderFileError::read(&rp, source))?;
    let len = file
        .metadata()
        .map_err(|source| FolderFileError::read(&rp, source))?
        .len();
    let map = if len == 0 {
        None
    } else {
        // This process holds the folder's lock, under which alone `run` appends to, repairs
        // or truncates the file.
        Some(
            crate::sys::map_read_only(&file)
                .map_err(|source| FolderFileError::read(&rp, source))?,
        )
    };
    let bytes: &[u8] = map.as_deref().unwrap_or_default();
    let scanned = format::scan_format(bytes, manifest.n_values, format::detect_format(bytes));
    // A records.bin copied from another study's folder says whose records it holds.
    let foreign = scanned
        .identities
        .iter()
        .any(|(json, _)| serde_json::from_slice::<Manifest>(json).ok().as_ref() != Some(&manifest));
    if foreign {
        return Err(invalid(
            &rp,
            "holds the records of another study or FMU than store/manifest.json says (the file \
             was copied from another folder)",
        ));
    }
    // The first success of each point, in design order; the values stay in the map.
    let mut ok: Vec<(usize, Range<usize>)> = scanned
        .records
        .into_iter()
        .filter_map(|(i, slot, _)| match slot {
            Slot::Ok(r) => Some((i, r)),
            Slot::Failed(_) => None,
        })
        .collect();
    ok.sort_by_key(|(i, _)| *i);
    ok.dedup_by_key(|(i, _)| *i);
    let runs = StoredValues { bytes, ok: &ok, nt };
    let csv = out.join("runs.csv");
    write_csv(&csv, &outputs, &times, &runs)?;
    let npz = out.join("runs.npz");
    write_npz(&npz, &outputs, &times, &runs, &parameters)?;
    Ok(Exported {
        runs: ok.len(),
        times: nt,
        outputs,
        csv,
        npz,
    })
}

/// The successful runs of a store file, read where they lie: `ok` holds each run's design
/// index and the byte range of its values (little-endian f64, output after output, `nt`
/// times each).
struct StoredValues<'a> {
    bytes: &'a [u8],
    ok: &'a [(usize, Range<usize>)],
    nt: usize,
}

impl StoredValues<'_> {
    /// The raw little-endian bytes of output `o` of run `r` (`nt` values).
    fn output_bytes(&self, r: usize, o: usize) -> &[u8] {
        let start = self.ok[r].1.start + 8 * o * self.nt;
        &self.bytes[start..start + 8 * self.nt]
    }

    /// Value `k` of the record of run `r`.
    fn value(&self, r: usize, k: usize) -> f64 {
        let at = self.ok[r].1.start + 8 * k;
        let mut le = [0; 8];
        le.copy_from_slice(&self.bytes[at..at + 8]);
        f64::from_le_bytes(le)
    }
}

/// The parameter columns of `points.csv` by design index: (name, values).
fn read_points(path: &Path) -> Result<Vec<(String, Vec<f64>)>, ExportError> {
    let text = String::from_utf8_lossy(&read(path)?).into_owned();
    let mut lines = text.lines();
    let header = split_line(lines.next().unwrap_or(""));
    let cols: Vec<usize> = (0..header.len())
        .filter(|&j| !matches!(header[j].as_str(), "index" | "weight" | "status"))
        .collect();
    let mut out: Vec<(String, Vec<f64>)> = cols
        .iter()
        .map(|&j| (header[j].clone(), Vec::new()))
        .collect();
    for line in lines {
        let cells = split_line(line);
        for (k, &j) in cols.iter().enumerate() {
            let v = cells
                .get(j)
                .and_then(|c| c.parse().ok())
                .unwrap_or(f64::NAN);
            out[k].1.push(v);
        }
    }
    Ok(out)
}

fn write_csv(
    path: &Path,
    outputs: &[String],
    times: &[f64],
    runs: &StoredValues,
) -> Result<(), ExportError> {
    let io = |source| ReportError::Io {
        path: path.to_path_buf(),
        source,
    };
    let mut w = OutFile::create(path, 1 << 20).map_err(io)?;
    let mut line = String::with_capacity(64);
    let mut header = vec!["run", "time"];
    header.extend(outputs.iter().map(String::as_str));
    push_header(&mut line, &header);
    w.write_all(line.as_bytes()).map_err(io)?;
    let nt = times.len();
    for (r, (i, _)) in runs.ok.iter().enumerate() {
        for (k, t) in times.iter().enumerate() {
            line.clear();
            let _ = write!(line, "{i},{t}");
            for o in 0..outputs.len() {
                let _ = write!(line, ",{}", runs.value(r, o * nt + k));
            }
            line.push('\n');
            w.write_all(line.as_bytes()).map_err(io)?;
        }
    }
    w.commit().map_err(io)?;
    Ok(())
}

/// One `.npy` file (format 1.0) of a C-ordered array with `shape`, of `<f8` or `<i8`.
pub fn npy(shape: &[usize], data: Npy) -> Vec<u8> {
    let descr = match data {
        Npy::F64(_) => "<f8",
        Npy::I64(_) => "<i8",
    };
    let mut out = npy_header(shape, descr);
    out.reserve(8 * data.len());
    match data {
        Npy::F64(v) => v
            .iter()
            .for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
        Npy::I64(v) => v
            .iter()
            .for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
    }
    out
}

/// The magic, version and header of a `.npy` file (format 1.0) of a C-ordered array with
/// `shape` of dtype `descr` (`<f8`, `<i8`): its data follows.
fn npy_header(shape: &[usize], descr: &str) -> Vec<u8> {
    let dims: Vec<String> = shape.iter().map(|d| d.to_string()).collect();
    let shape = if dims.len() == 1 {
        format!("({},)", dims[0])
    } else {
        format!("({})", dims.join(", "))
    };
    let mut header = format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}");
    // Magic (6) + version (2) + length (2) + header, padded with spaces to a multiple of 64
    // and ended by a newline.
    let total = 10 + header.len() + 1;
    header.push_str(&" ".repeat(total.next_multiple_of(64) - total));
    header.push('\n');
    let mut out = Vec::with_capacity(10 + header.len());
    out.extend_from_slice(b"\x93NUMPY\x01\x00");
    out.extend_from_slice(&(header.len() as u16).to_le_bytes());
    out.extend_from_slice(header.as_bytes());
    out
}

/// The data of a `.npy` array.
#[derive(Clone, Copy, Debug)]
pub enum Npy<'a> {
    /// 64-bit floats.
    F64(&'a [f64]),
    /// 64-bit integers.
    I64(&'a [i64]),
}

impl Npy<'_> {
    fn len(&self) -> usize {
        match self {
            Npy::F64(v) => v.len(),
            Npy::I64(v) => v.len(),
        }
    }
}

fn write_npz(
    path: &Path,
    outputs: &[String],
    times: &[f64],
    runs: &StoredValues,
    parameters: &[(String, Vec<f64>)],
) -> Result<(), ExportError> {
    let nt = times.len();
    let n = runs.ok.len();
    let zip_err = |source| ExportError::Zip {
        path: path.to_path_buf(),
        source,
    };
    let io = |source| ReportError::Io {
        path: path.to_path_buf(),
        source,
    };
    let mut z = zip::ZipWriter::new(OutFile::create(path, 1 << 20).map_err(io)?);
    let opts = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Stored)
        .large_file(true);
    let mut add = |name: &str, bytes: Vec<u8>| -> Result<(), ExportError> {
        z.start_file(format!("{}.npy", stem(name)), opts)
            .map_err(zip_err)?;
        z.write_all(&bytes).map_err(io)?;
        Ok(())
    };
    add("time", npy(&[nt], Npy::F64(times)))?;
    let index: Vec<i64> = runs.ok.iter().map(|(i, _)| *i as i64).collect();
    add("run", npy(&[n], Npy::I64(&index)))?;
    // The series, a run at a time straight from the store (already little-endian f64).
    for (o, name) in outputs.iter().enumerate() {
        z.start_file(format!("{}.npy", stem(name)), opts)
            .map_err(zip_err)?;
        z.write_all(&npy_header(&[n, nt], "<f8")).map_err(io)?;
        for r in 0..n {
            z.write_all(runs.output_bytes(r, o)).map_err(io)?;
        }
    }
    for (name, values) in parameters {
        if outputs.contains(name) || name == "time" || name == "run" {
            continue;
        }
        let per_run: Vec<f64> = runs
            .ok
            .iter()
            .map(|(i, _)| values.get(*i).copied().unwrap_or(f64::NAN))
            .collect();
        z.start_file(format!("{}.npy", stem(name)), opts)
            .map_err(zip_err)?;
        z.write_all(&npy(&[n], Npy::F64(&per_run))).map_err(io)?;
    }
    z.finish().map_err(zip_err)?.commit().map_err(io)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_parameter_name_with_a_comma_is_read_back_from_points_csv() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("points.csv");
        std::fs::write(
            &p,
            "index,weight,\"k[2,1]\",x,status\n0,0.5,1.5,2,ok\n1,0.5,3,4,\"failed: a, b\"\n",
        )
        .unwrap();
        let cols = read_points(&p).unwrap();
        assert_eq!(cols.len(), 2);
        assert_eq!(cols[0], ("k[2,1]".to_string(), vec![1.5, 3.0]));
        assert_eq!(cols[1], ("x".to_string(), vec![2.0, 4.0]));
    }

    #[test]
    fn exporting_a_suite_folder_names_its_variant_folders() {
        let dir = tempfile::tempdir().unwrap();
        // The top of a suite's folder, as `run` writes it: no record_layout of its own.
        let summary = serde_json::json!({
            "suite": "wheel",
            "reference": "lhs",
            "variants": [
                { "name": "scm-3", "folder": "scm-3", "model_runs": 9 },
                { "name": "sgm", "folder": "sgm", "model_runs": 1 },
                { "name": "lhs", "folder": "lhs", "model_runs": 500 },
            ],
        });
        std::fs::write(dir.path().join("summary.json"), summary.to_string()).unwrap();
        // SGM's folder: no FMU, no runs to export.
        std::fs::create_dir(dir.path().join("sgm")).unwrap();
        let sgm = serde_json::json!({ "fmu": null, "method": { "kind": "sgm" }, "model_runs": 1 });
        std::fs::write(dir.path().join("sgm/summary.json"), sgm.to_string()).unwrap();
        let e = runs(dir.path(), &dir.path().join("runs"))
            .unwrap_err()
            .to_string();
        assert!(!e.contains("older uq-driver"), "{e}");
        assert!(e.contains("a suite's folder (suite wheel)"), "{e}");
        let example = format!(
            "uq-driver export {} --runs",
            dir.path().join("scm-3").display()
        );
        assert!(e.contains(&example), "{e}");
        assert!(e.contains("(variants with runs: scm-3, lhs)"), "{e}");
        assert!(!dir.path().join("runs").exists());
    }

    #[test]
    fn npy_header_is_aligned_and_parsable() {
        let b = npy(&[2, 3], Npy::F64(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]));
        assert_eq!(&b[..8], b"\x93NUMPY\x01\x00");
        let hlen = u16::from_le_bytes([b[8], b[9]]) as usize;
        assert_eq!((10 + hlen) % 64, 0);
        let header = std::str::from_utf8(&b[10..10 + hlen]).unwrap();
        assert!(header.starts_with("{'descr': '<f8', 'fortran_order': False, 'shape': (2, 3), }"));
        assert!(header.ends_with('\n'));
        assert_eq!(b.len(), 10 + hlen + 48);
        assert_eq!(
            f64::from_le_bytes(b[10 + hlen + 40..].try_into().unwrap()),
            6.0
        );
        let one = npy(&[3], Npy::I64(&[7, 8, 9]));
        let hlen = u16::from_le_bytes([one[8], one[9]]) as usize;
        assert!(std::str::from_utf8(&one[10..10 + hlen])
            .unwrap()
            .contains("'<i8'"));
        assert!(std::str::from_utf8(&one[10..10 + hlen])
            .unwrap()
            .contains("(3,)"));
    }
}
