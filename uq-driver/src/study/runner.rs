//! The parallel runner: one FMU instance per worker, `fmi2Reset` between points, every
//! finished point appended to the results store.

use std::path::Path;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::Instant;

use rayon::prelude::*;
use sha2::{Digest, Sha256};

use super::interface::{Interface, InterfaceError};
use super::progress::{Progress, ProgressMode};
use super::store::{Manifest, Record, Store, StoreError};
use crate::fmu::{Fmu, FmuError, Instance};
use crate::qoi::scalar::{self, QoiError};
use crate::spec::Study;
use crate::uq::method::{Design, MethodError};

/// How to run a study.
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    /// Worker threads (None: all cores).
    pub threads: Option<usize>,
    /// Show a progress bar (on a terminal).
    pub progress: bool,
    /// Print progress lines (when the output is a log file, not a terminal); ignored when
    /// `progress` is set.
    pub progress_lines: bool,
    /// Unweighted designs: continue past failed points (overrides the study file when true).
    pub allow_failures: bool,
    /// Discard earlier results in the output folder.
    pub fresh: bool,
    /// Stop after this many newly finished points (for tests of interruption).
    pub max_new_points: Option<usize>,
    /// Run only these points of the design (a shard); None: all.
    pub points: Option<Vec<usize>>,
    /// Write the CSV files and `summary.json` only: no plots, no `index.html`.
    pub no_report: bool,
}

impl RunOptions {
    /// Whether failed points may be left out (the option or the study's `allow_failures`).
    pub fn allow_failures(&self, study: &Study) -> bool {
        self.allow_failures || study.analysis.allow_failures
    }
}

/// Why one model run failed. Its text is stored with the point, so it is complete on its own.
#[derive(Debug, thiserror::Error)]
pub enum PointError {
    /// An FMI call failed (the message lists what the FMU logged).
    #[error(transparent)]
    Fmu(#[from] FmuError),
    /// An output became NaN or infinite.
    #[error("non-finite value of {signal} at t = {time} s")]
    NonFinite {
        /// The variable.
        signal: String,
        /// When (s).
        time: f64,
    },
    /// A quantity of interest could not be evaluated on the run.
    #[error("quantity '{name}': {error}")]
    Quantity {
        /// The quantity.
        name: String,
        /// Why.
        error: QoiError,
    },
}

/// A point that failed: where and why.
#[derive(Clone, Debug, PartialEq)]
pub struct FailedPoint {
    /// Index in the design.
    pub index: usize,
    /// Its parameter values, by name.
    pub parameters: Vec<(String, f64)>,
    /// Why it failed, with what the FMU logged.
    pub message: String,
}

impl std::fmt::Display for FailedPoint {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "point {} with ", self.index)?;
        for (i, (name, v)) in self.parameters.iter().enumerate() {
            let sep = if i == 0 { "" } else { ", " };
            write!(f, "{sep}{name} = {v}")?;
        }
        write!(f, ": {}", self.message)
    }
}

/// Runner failures.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The FMU could not be opened.
    #[error(transparent)]
    Fmu(#[from] FmuError),
    /// The store could not be used.
    #[error(transparent)]
    Store(#[from] StoreError),
    /// A study variable does not fit the FMU.
    #[error(transparent)]
    Interface(#[from] InterfaceError),
    /// The design could not be built.
    #[error(transparent)]
    Design(#[from] MethodError),
    /// Points failed and failures are not allowed.
    #[error("{failed} of {total} points failed; first: {first}")]
    PointsFailed {
        /// Number of failed points.
        failed: usize,
        /// Number of points.
        total: usize,
        /// The first failed point.
        first: FailedPoint,
    },
    /// A single run failed (`simulate`).
    #[error(transparent)]
    Point(#[from] PointError),
    /// The thread pool could not be built.
    #[error("cannot start the worker threads")]
    Pool(#[source] rayon::ThreadPoolBuildError),
}

/// SHA-256 of an FMU, hex: of the file, or, for an extracted FMU folder, of every file's
/// relative path and content in sorted order.
pub fn sha256_file(path: &Path) -> std::io::Result<String> {
    fn walk(dir: &Path, root: &Path, h: &mut Sha256) -> std::io::Result<()> {
        let mut entries: Vec<_> = std::fs::read_dir(dir)?.collect::<Result<_, _>>()?;
        entries.sort_by_key(|e| e.file_name());
        for e in entries {
            let p = e.path();
            if e.file_type()?.is_dir() {
                walk(&p, root, h)?;
            } else {
                let rel = p
                    .strip_prefix(root)
                    .unwrap_or(&p)
                    .to_string_lossy()
                    .into_owned();
                h.update(rel.as_bytes());
                h.update([0]);
                h.update(std::fs::read(&p)?);
            }
        }
        Ok(())
    }
    if path.is_dir() {
        let mut h = Sha256::new();
        walk(path, path, &mut h)?;
        return Ok(format!("{:x}", h.finalize()));
    }
    let bytes = std::fs::read(path)?;
    Ok(format!("{:x}", Sha256::digest(&bytes)))
}

/// Hash of everything in a study that changes the stored records (not its name, description
/// or analysis settings). The quantities of interest are stored with every run, so their
/// settings are part of it (a study without any keeps the hash it always had).
pub fn study_hash(study: &Study) -> String {
    let mut key = serde_json::json!({
        "seed": study.seed,
        "experiment": study.experiment,
        "method": study.method,
        "parameters": study.parameters,
        "fixed": study.fixed,
        "outputs": { "variables": study.outputs },
    });
    if !study.qoi.is_empty() {
        key["qoi"] = serde_json::json!(study.qoi);
    }
    format!("{:x}", Sha256::digest(key.to_string().as_bytes()))
}

/// Starts (or resets) `slot`'s instance, sets the parameters, initializes and records the
/// signals at `times`: `traces[o * nt + k]` is signal `o` at `times[k]`.
fn simulate_point(
    fmu: &Fmu,
    slot: &mut Option<Instance>,
    iface: &Interface,
    values: &[f64],
    times: &[f64],
) -> Result<Vec<f64>, FmuError> {
    let nt = times.len();
    let inst = match slot {
        Some(inst) => {
            inst.reset()?;
            inst
        }
        None => slot.insert(fmu.instantiate("uq-driver", false)?),
    };
    let (fixed_vr, fixed_v): (Vec<u32>, Vec<f64>) = iface.fixed.iter().copied().unzip();
    inst.set_real(&fixed_vr, &fixed_v)?;
    let (int_vr, int_v): (Vec<u32>, Vec<i32>) = iface.fixed_int.iter().copied().unzip();
    inst.set_integer(&int_vr, &int_v)?;
    inst.set_real(&iface.random, values)?;
    let stop = *times.last().expect("at least one time");
    inst.setup_experiment(None, times[0], Some(stop))?;
    inst.enter_initialization_mode()?;
    inst.exit_initialization_mode()?;
    let mut traces = vec![0.0; iface.signals.len() * nt];
    let mut buf = vec![0.0; iface.signals.len()];
    for k in 0..nt {
        if k > 0 {
            inst.do_step(times[k - 1], times[k] - times[k - 1], true)?;
        }
        inst.get_real(&iface.signals, &mut buf)?;
        for (o, v) in buf.iter().enumerate() {
            traces[o * nt + k] = *v;
        }
    }
    Ok(traces)
}

/// Runs one point on `slot`'s instance (created or reset as needed). Returns the record
/// values: the stored outputs (output-major: all times of output 0, then output 1, …), then
/// (value, code) of each quantity of interest.
pub fn run_point(
    fmu: &Fmu,
    slot: &mut Option<Instance>,
    iface: &Interface,
    values: &[f64],
    times: &[f64],
) -> Result<Vec<f64>, PointError> {
    let nt = times.len();
    let traces = simulate_point(fmu, slot, iface, values, times).inspect_err(|_| {
        // A failed instance may be in Error state: start the next point on a fresh one.
        *slot = None;
    })?;
    if let Some(pos) = traces.iter().position(|v| !v.is_finite()) {
        *slot = None;
        return Err(PointError::NonFinite {
            signal: iface.signal_names[pos / nt].clone(),
            time: times[pos % nt],
        });
    }
    let mut out = traces[..iface.n_stored * nt].to_vec();
    let signal = |name: &str| -> &[f64] {
        let i = iface
            .signal_names
            .iter()
            .position(|n| n == name)
            .expect("resolved");
        &traces[i * nt..(i + 1) * nt]
    };
    for q in &iface.qois {
        let (v, code) =
            scalar::evaluate(q, times, signal).map_err(|error| PointError::Quantity {
                name: q.name().to_owned(),
                error,
            })?;
        out.push(v);
        out.push(code as u8 as f64);
    }
    Ok(out)
}

/// What a run produced: every point's record, in design order.
#[derive(Debug)]
pub struct RunOutcome {
    /// Records by point index (all present unless stopped early).
    pub records: Vec<Option<Record>>,
    /// Points run in this invocation.
    pub n_new: usize,
    /// Points found finished in the store.
    pub n_resumed: usize,
    /// Wall time of this invocation (s).
    pub wall_time: f64,
    /// Threads used.
    pub threads: usize,
    /// SHA-256 of the FMU.
    pub fmu_sha256: String,
}

/// The store manifest of `study` on `fmu` with `design`.
pub fn manifest(study: &Study, fmu: &Fmu, design: &Design) -> Result<Manifest, RunError> {
    let iface = Interface::resolve(study, fmu)?;
    let fmu_sha256 = sha256_file(fmu.path()).map_err(|source| FmuError::Io {
        path: fmu.path().to_path_buf(),
        source,
    })?;
    Ok(Manifest {
        study_hash: study_hash(study),
        fmu_sha256,
        n_points: design.len(),
        n_values: iface.n_values(study.experiment.times().len()),
    })
}

/// Runs every point of `design` not yet in the store of `out_dir`.
pub fn run_points(
    study: &Study,
    fmu: &Fmu,
    design: &Design,
    out_dir: &Path,
    opts: &RunOptions,
) -> Result<RunOutcome, RunError> {
    let started = Instant::now();
    let manifest = manifest(study, fmu, design)?;
    let (store, mut records) = Store::open(out_dir, &manifest, opts.fresh)?;
    if let Some(note) = store.recovery().summary() {
        eprintln!("warning: {note}");
    }
    let wanted: Vec<usize> = match &opts.points {
        Some(p) => p.iter().copied().filter(|&i| i < design.len()).collect(),
        None => (0..design.len()).collect(),
    };
    let missing: Vec<usize> = wanted
        .iter()
        .copied()
        .filter(|&i| records[i].is_none())
        .collect();
    let threads = opts
        .threads
        .unwrap_or_else(rayon::current_num_threads)
        .max(1);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(RunError::Pool)?;
    let batch = Batch {
        fmu,
        iface: Interface::resolve(study, fmu)?,
        design,
        times: study.times(),
        store: &store,
        stop_on_failure: !opts.allow_failures(study) || design.is_weighted(),
        max_new: opts.max_new_points,
    };
    let mode = match (opts.progress, opts.progress_lines) {
        (true, _) => ProgressMode::Bar,
        (false, true) => ProgressMode::Lines,
        _ => ProgressMode::Off,
    };
    let progress = Progress::new(mode, missing.len());
    let new = pool.install(|| batch.run(&missing, &progress))?;
    progress.finish();
    let n_new = new.len();
    for (i, r) in new {
        records[i] = Some(r);
    }
    Ok(RunOutcome {
        records,
        n_new,
        n_resumed: wanted.len() - missing.len(),
        wall_time: started.elapsed().as_secs_f64(),
        threads,
        fmu_sha256: manifest.fmu_sha256,
    })
}

/// Points to run in parallel, each appended to the store as it finishes.
struct Batch<'a> {
    fmu: &'a Fmu,
    iface: Interface,
    design: &'a Design,
    times: Vec<f64>,
    store: &'a Store,
    /// Stop at the first failure (failures not allowed, or a weighted design).
    stop_on_failure: bool,
    /// Stop after this many new points.
    max_new: Option<usize>,
}

impl Batch<'_> {
    fn run(
        &self,
        points: &[usize],
        progress: &Progress,
    ) -> Result<Vec<(usize, Record)>, StoreError> {
        let stop = AtomicBool::new(false);
        let started = AtomicUsize::new(0);
        points
            .par_iter()
            .with_min_len(1)
            .map_init(
                || None::<Instance>,
                |slot, &i| -> Result<Option<(usize, Record)>, StoreError> {
                    if stop.load(Ordering::Relaxed) {
                        return Ok(None);
                    }
                    if let Some(max) = self.max_new {
                        if started.fetch_add(1, Ordering::SeqCst) >= max {
                            stop.store(true, Ordering::Relaxed);
                            return Ok(None);
                        }
                    }
                    let values = &self.design.values[i];
                    let rec = match run_point(self.fmu, slot, &self.iface, values, &self.times) {
                        Ok(v) => Record::Ok(v),
                        Err(e) => {
                            if self.stop_on_failure {
                                stop.store(true, Ordering::Relaxed);
                            }
                            Record::Failed(e.to_string())
                        }
                    };
                    self.store.append(i, &rec)?;
                    progress.inc();
                    Ok(Some((i, rec)))
                },
            )
            .filter_map(Result::transpose)
            .collect()
    }
}

/// The number of failed points; an error naming the first when failures are not allowed
/// (or the design is weighted: dropping a weighted point would bias every moment silently).
pub fn check_failures(
    study: &Study,
    design: &Design,
    records: &[Option<Record>],
    allow: bool,
) -> Result<usize, RunError> {
    let failed: Vec<(usize, &String)> = records
        .iter()
        .enumerate()
        .filter_map(|(i, r)| match r {
            Some(Record::Failed(m)) => Some((i, m)),
            _ => None,
        })
        .collect();
    let Some(&(index, message)) = failed.first() else {
        return Ok(0);
    };
    if allow && !design.is_weighted() {
        return Ok(failed.len());
    }
    let parameters = study
        .parameters
        .iter()
        .zip(&design.values[index])
        .map(|(p, v)| (p.name.clone(), *v))
        .collect();
    Err(RunError::PointsFailed {
        failed: failed.len(),
        total: records.len(),
        first: FailedPoint {
            index,
            parameters,
            message: message.clone(),
        },
    })
}

/// One deterministic run of `fmu` with `params` set before initialization, recording `outputs`
/// (names; all the FMU's outputs when empty) at `times`. Returns the names and, per name,
/// the series.
pub fn simulate(
    fmu: &Fmu,
    params: &[(String, f64)],
    outputs: &[String],
    times: &[f64],
) -> Result<(Vec<String>, Vec<Vec<f64>>), RunError> {
    let iface = Interface::for_run(fmu, params, outputs)?;
    let flat = run_point(fmu, &mut None, &iface, &[], times)?;
    let series = flat.chunks(times.len()).map(<[f64]>::to_vec).collect();
    Ok((iface.signal_names, series))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn changed_quantity_settings_do_not_resume_stale_records() {
        let base = crate::spec::builtin("bogie-lhs-500").unwrap();
        let study = |text: &str| Study::parse(text, "t.toml", None).unwrap();
        let a = study_hash(&study(base));
        let b = study_hash(&study(
            &base.replace("threshold = 1e-4", "threshold = 2e-4"),
        ));
        assert_ne!(a, b, "a record holds v_cr for one threshold only");
        // Name, description and analysis settings do not change the records.
        let renamed = base.replace("name = \"bogie-lhs-500\"", "name = \"renamed\"");
        let c = study_hash(&study(&format!("{renamed}\n[analysis]\npdf_grid = 50\n")));
        assert_eq!(a, c);
    }

    #[test]
    fn studies_without_quantities_keep_their_hash() {
        // The hash of wheel-scm in the store/manifest.json that uq-driver wrote before the
        // restructuring (commit 7b51554): old result folders still resume.
        let s = Study::load("builtin:wheel-scm").unwrap();
        let expected = "9c4270a27263cfdb71ef7669728eefc88c107f891685caf239948c85fa49637a";
        assert_eq!(study_hash(&s), expected);
    }
}
