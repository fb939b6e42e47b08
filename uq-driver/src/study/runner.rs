//! The parallel runner: one FMU instance per worker, `fmi2Reset` between points, every
//! finished point appended to the results store.

use std::path::Path;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::Instant;

use rayon::prelude::*;
use sha2::{Digest, Sha256};

use super::design::Design;
use super::spec::{QoiSpec, Study};
use super::store::{Manifest, Record, Store, StoreError};
use crate::fmu::{Fmu, FmuError, Instance, ScalarVariable, VariableKind};
use crate::qoi::scalar;

/// How to run a study.
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    /// Worker threads (None: all cores).
    pub threads: Option<usize>,
    /// Show a progress bar (on a terminal).
    pub progress: bool,
    /// MC/LHS: continue past failed points (overrides the study file when true).
    pub allow_failures: bool,
    /// Discard earlier results in the output folder.
    pub fresh: bool,
    /// Stop after this many newly finished points (for tests of interruption).
    pub max_new_points: Option<usize>,
    /// Run only these points of the design (a shard); None: all.
    pub points: Option<Vec<usize>>,
}

/// Runner failures.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The FMU could not be opened or does not fit the study.
    #[error(transparent)]
    Fmu(#[from] FmuError),
    /// The store could not be used.
    #[error(transparent)]
    Store(#[from] StoreError),
    /// A study variable does not fit the FMU.
    #[error("{fmu}: {message}")]
    Interface {
        /// FMU path.
        fmu: String,
        /// What does not fit.
        message: String,
    },
    /// The design could not be built.
    #[error("{0}")]
    Design(String),
    /// Points failed and failures are not allowed.
    #[error("{failed} of {total} points failed; first: point {index} with {params}: {message}")]
    PointsFailed {
        /// Number of failed points.
        failed: usize,
        /// Number of points.
        total: usize,
        /// First failed point.
        index: usize,
        /// Its parameter values.
        params: String,
        /// Why it failed.
        message: String,
    },
    /// Thread pool could not be built.
    #[error("thread pool: {0}")]
    Pool(String),
}

/// Value references resolved against the FMU.
#[derive(Clone, Debug)]
pub struct Interface {
    /// Random parameters, in study order.
    pub random: Vec<u32>,
    /// Fixed Real parameters (name order) and values.
    pub fixed: Vec<(u32, f64)>,
    /// Fixed Integer parameters (e.g. a spectrum or seed number).
    pub fixed_int: Vec<(u32, i32)>,
    /// Every variable read at each communication point: the outputs, then the signals the
    /// quantities of interest need.
    pub signals: Vec<u32>,
    /// Their names.
    pub signal_names: Vec<String>,
    /// Number of leading signals that are stored as time series (the study's outputs).
    pub n_stored: usize,
    /// Scalar quantities of interest.
    pub qois: Vec<QoiSpec>,
}

impl Interface {
    /// Values recorded per successful point: stored series, then (value, code) per quantity.
    pub fn n_values(&self, n_times: usize) -> usize {
        self.n_stored * n_times + 2 * self.qois.len()
    }
}

/// A variable of the FMU by name, or an error naming it.
fn any_var<'a>(fmu: &'a Fmu, name: &str) -> Result<&'a ScalarVariable, RunError> {
    fmu.description()
        .variable(name)
        .ok_or_else(|| RunError::Interface {
            fmu: fmu.path().display().to_string(),
            message: format!(
                "the study names variable '{name}', which the FMU ({}) does not have",
                fmu.description().model_name
            ),
        })
}

fn real_var<'a>(fmu: &'a Fmu, name: &str) -> Result<&'a ScalarVariable, RunError> {
    let var = any_var(fmu, name)?;
    if !matches!(var.kind, VariableKind::Real { .. }) {
        return Err(RunError::Interface {
            fmu: fmu.path().display().to_string(),
            message: format!(
                "variable '{name}' is a {}, not a Real",
                var.kind.type_name()
            ),
        });
    }
    Ok(var)
}

fn check_settable(fmu: &Fmu, var: &ScalarVariable) -> Result<(), RunError> {
    if fmu.description().settable_before_init(var) {
        return Ok(());
    }
    Err(RunError::Interface {
        fmu: fmu.path().display().to_string(),
        message: format!(
            "variable '{}' (causality {}, variability {}) may not be set before initialization, \
             so a study cannot set it",
            var.name,
            var.causality.as_str(),
            var.variability.as_str()
        ),
    })
}

/// Deterministic settings: (value reference, value) for Reals and for Integers.
type FixedValues = (Vec<(u32, f64)>, Vec<(u32, i32)>);

/// Splits deterministic values into Real and Integer settings, checking each variable.
fn fixed_values<'a>(
    fmu: &Fmu,
    values: impl Iterator<Item = (&'a str, f64)>,
) -> Result<FixedValues, RunError> {
    let mut reals = Vec::new();
    let mut ints = Vec::new();
    for (name, v) in values {
        let var = any_var(fmu, name)?;
        check_settable(fmu, var)?;
        match var.kind {
            VariableKind::Real { .. } => reals.push((var.value_reference, v)),
            VariableKind::Integer { .. } | VariableKind::Enumeration { .. } => {
                if v.fract() != 0.0 || v.abs() > f64::from(i32::MAX) {
                    return Err(RunError::Interface {
                        fmu: fmu.path().display().to_string(),
                        message: format!("'{name}' is an Integer; {v} is not a whole number"),
                    });
                }
                ints.push((var.value_reference, v as i32));
            }
            _ => {
                return Err(RunError::Interface {
                    fmu: fmu.path().display().to_string(),
                    message: format!(
                        "'{name}' is a {}; only Real and Integer values can be set",
                        var.kind.type_name()
                    ),
                })
            }
        }
    }
    Ok((reals, ints))
}

/// Checks the study's variables against the FMU and resolves their value references.
pub fn resolve_interface(study: &Study, fmu: &Fmu) -> Result<Interface, RunError> {
    let settable = |name: &str| -> Result<u32, RunError> {
        let var = real_var(fmu, name)?;
        check_settable(fmu, var)?;
        Ok(var.value_reference)
    };
    let random = study
        .parameters
        .iter()
        .map(|p| settable(&p.name))
        .collect::<Result<_, _>>()?;
    let (fixed, fixed_int) =
        fixed_values(fmu, study.file.fixed.iter().map(|(n, v)| (n.as_str(), *v)))?;
    let mut signal_names: Vec<String> = study.file.outputs.variables.clone();
    for q in &study.file.qoi {
        for s in q.signals() {
            if !signal_names.iter().any(|n| n == s) {
                signal_names.push(s.to_owned());
            }
        }
    }
    let signals = signal_names
        .iter()
        .map(|n| Ok(real_var(fmu, n)?.value_reference))
        .collect::<Result<_, RunError>>()?;
    Ok(Interface {
        random,
        fixed,
        fixed_int,
        signals,
        signal_names,
        n_stored: study.file.outputs.variables.len(),
        qois: study.file.qoi.clone(),
    })
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

/// Hash of everything in a study that changes its numbers (not its name or description).
pub fn study_hash(study: &Study) -> String {
    let f = &study.file;
    let key = serde_json::json!({
        "seed": f.seed,
        "experiment": f.experiment,
        "method": f.method,
        "parameters": study.parameters,
        "fixed": f.fixed,
        "outputs": f.outputs,
    });
    format!("{:x}", Sha256::digest(key.to_string().as_bytes()))
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
) -> Result<Vec<f64>, String> {
    let nt = times.len();
    let ns = iface.signals.len();
    let result = (|| -> Result<Vec<f64>, FmuError> {
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
        let start = times[0];
        let stop = *times.last().expect("at least one time");
        inst.setup_experiment(None, start, Some(stop))?;
        inst.enter_initialization_mode()?;
        inst.exit_initialization_mode()?;
        let mut traces = vec![0.0; ns * nt];
        let mut buf = vec![0.0; ns];
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
    })();
    let traces = match result {
        Ok(t) => t,
        Err(e) => {
            // A failed instance may be in Error state: start the next point on a fresh one.
            *slot = None;
            return Err(e.to_string());
        }
    };
    if let Some(pos) = traces.iter().position(|v| !v.is_finite()) {
        *slot = None;
        return Err(format!(
            "non-finite value of {} at t = {} s",
            iface.signal_names[pos / nt],
            times[pos % nt]
        ));
    }
    let mut out = traces[..iface.n_stored * nt].to_vec();
    for q in &iface.qois {
        let signal = |name: &str| -> &[f64] {
            let i = iface
                .signal_names
                .iter()
                .position(|n| n == name)
                .expect("resolved");
            &traces[i * nt..(i + 1) * nt]
        };
        let (v, code) = scalar::evaluate(q, times, signal)
            .map_err(|e| format!("quantity '{}': {e}", q.name()))?;
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

/// Runs every point of `design` not yet in the store of `out_dir`.
pub fn run_points(
    study: &Study,
    fmu: &Fmu,
    design: &Design,
    out_dir: &Path,
    opts: &RunOptions,
) -> Result<RunOutcome, RunError> {
    let started = Instant::now();
    let iface = resolve_interface(study, fmu)?;
    let times = study.file.experiment.times();
    let fmu_sha256 = sha256_file(fmu.path()).map_err(|source| FmuError::Io {
        path: fmu.path().to_path_buf(),
        source,
    })?;
    let manifest = Manifest {
        study_hash: study_hash(study),
        fmu_sha256: fmu_sha256.clone(),
        n_points: design.len(),
        n_values: iface.n_values(times.len()),
    };
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
    let n_resumed = wanted.len() - missing.len();
    let threads = opts
        .threads
        .unwrap_or_else(rayon::current_num_threads)
        .max(1);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| RunError::Pool(e.to_string()))?;
    let allow_failures = opts.allow_failures || study.file.analysis.allow_failures;
    let stop = AtomicBool::new(false);
    let finished = AtomicUsize::new(0);
    let bar = if opts.progress && !missing.is_empty() {
        let b = indicatif::ProgressBar::new(missing.len() as u64);
        b.set_style(
            indicatif::ProgressStyle::with_template(
                "{bar:40} {pos}/{len} points  {elapsed} elapsed, ~{eta} left",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        Some(b)
    } else {
        None
    };
    let new: Vec<(usize, Record)> = pool.install(|| {
        missing
            .par_iter()
            .with_min_len(1)
            .map_init(
                || None::<Instance>,
                |slot, &i| -> Result<Option<(usize, Record)>, StoreError> {
                    if stop.load(Ordering::Relaxed) {
                        return Ok(None);
                    }
                    if let Some(max) = opts.max_new_points {
                        if finished.fetch_add(1, Ordering::SeqCst) >= max {
                            stop.store(true, Ordering::Relaxed);
                            return Ok(None);
                        }
                    }
                    let rec = match run_point(fmu, slot, &iface, &design.values[i], &times) {
                        Ok(v) => Record::Ok(v),
                        Err(m) => {
                            if !allow_failures || design.weights.is_some() {
                                stop.store(true, Ordering::Relaxed);
                            }
                            Record::Failed(m)
                        }
                    };
                    store.append(i, &rec)?;
                    if let Some(b) = &bar {
                        b.inc(1);
                    }
                    Ok(Some((i, rec)))
                },
            )
            .filter_map(Result::transpose)
            .collect::<Result<Vec<_>, StoreError>>()
    })?;
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    let n_new = new.len();
    for (i, r) in new {
        records[i] = Some(r);
    }
    Ok(RunOutcome {
        records,
        n_new,
        n_resumed,
        wall_time: started.elapsed().as_secs_f64(),
        threads,
        fmu_sha256,
    })
}

/// Fails with a clear message when points failed and that is not allowed.
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
    if failed.is_empty() {
        return Ok(0);
    }
    // Collocation nodes carry weights: dropping one would bias every moment silently.
    if !allow || design.weights.is_some() {
        let (index, message) = failed[0];
        let params = study
            .parameters
            .iter()
            .zip(&design.values[index])
            .map(|(p, v)| format!("{} = {v}", p.name))
            .collect::<Vec<_>>()
            .join(", ");
        return Err(RunError::PointsFailed {
            failed: failed.len(),
            total: records.len(),
            index,
            params,
            message: message.clone(),
        });
    }
    Ok(failed.len())
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
    let md = fmu.description();
    let names: Vec<String> = if outputs.is_empty() {
        md.output_variables()
            .filter(|v| matches!(v.kind, VariableKind::Real { .. }))
            .map(|v| v.name.clone())
            .collect()
    } else {
        outputs.to_vec()
    };
    let (fixed, fixed_int) = fixed_values(fmu, params.iter().map(|(n, v)| (n.as_str(), *v)))?;
    let signals = names
        .iter()
        .map(|n| Ok(real_var(fmu, n)?.value_reference))
        .collect::<Result<Vec<_>, RunError>>()?;
    let iface = Interface {
        random: Vec::new(),
        fixed,
        fixed_int,
        signals,
        signal_names: names.clone(),
        n_stored: names.len(),
        qois: Vec::new(),
    };
    let mut slot = None;
    let flat =
        run_point(fmu, &mut slot, &iface, &[], times).map_err(|message| RunError::Interface {
            fmu: fmu.path().display().to_string(),
            message,
        })?;
    let nt = times.len();
    Ok((names, flat.chunks(nt).map(<[f64]>::to_vec).collect()))
}
