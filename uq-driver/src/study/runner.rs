//! The parallel runner: one FMU instance per worker, reused through `fmi2Reset` between
//! points once the reset self-check has passed ([`super::instances`]), every finished point
//! appended to the results store.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use rayon::prelude::*;
use sha2::{Digest, Sha256};

use super::guard::{self, StudyGuard};
use super::instances::{self, InstancePolicy, ResetCheck, Slot};
use super::interface::{Interface, InterfaceError};
use super::isolate::{self, IsolateOptions, WorkerFailure, WorkerPool};
use super::lock::{FolderLock, LockError};
pub use super::point::{run_point, simulate, simulate_with, PointError, Simulation, Trace};
use super::progress::{Progress, ProgressMode};
use super::store::{Entry, Manifest, Record, Store, StoreError, StoredRuns};
use super::worker_fmu::WorkerFmus;
use crate::fmu::{Fmu, FmuError};
use crate::spec::Study;
use crate::uq::method::{ChaosBasis, Design, MethodError, MethodSpec};

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
    /// Run the points that failed in an earlier run again (`--retry-failed`).
    pub retry_failed: bool,
    /// `--isolate`: run each point in a worker process started from this uq-driver executable
    /// (see [`isolate`]); None: in-process.
    pub isolate: Option<PathBuf>,
    /// `--timeout-per-run`: with `isolate` a longer run is killed and fails its point; in-process
    /// the study stops with a message naming the point (an FMU call cannot be interrupted).
    pub timeout_per_run: Option<Duration>,
    /// Start a large study without asking (`--yes`; see [`super::size`]).
    pub yes: bool,
    /// `--fresh-instances`: every run on a fresh FMU instance, never reused through
    /// `fmi2Reset` (and no reset self-check).
    pub fresh_instances: bool,
    /// `--fmu-logging`: instantiate with `loggingOn = true` (the FMU's messages are kept with
    /// failed points, capped, not printed).
    pub fmu_logging: bool,
}

impl RunOptions {
    /// Whether failed points may be left out (the option or the study's `allow_failures`).
    pub fn allow_failures(&self, study: &Study) -> bool {
        self.allow_failures || study.analysis.allow_failures
    }
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
    #[error(
        "{}; first: {first}. After fixing the cause, run again \
         with --retry-failed to re-run the failed points (or --allow-failures, for Monte Carlo \
         and LHS, to analyse the others)",
        failure_count(*.failed, *.total, *.not_run)
    )]
    PointsFailed {
        /// Number of failed points (among those run before the study stopped).
        failed: usize,
        /// Number of points (of this run: a shard's points for a shard).
        total: usize,
        /// Points not run because the study stopped at the first failure: their outcome is
        /// unknown, so `failed` is a lower bound when this is not 0.
        not_run: usize,
        /// The first failed point.
        first: FailedPoint,
    },
    /// A single run failed (`simulate`).
    #[error(transparent)]
    Point(#[from] PointError),
    /// The output path exists and is not a folder.
    #[error("{}: the output path exists and is not a folder", .0.display())]
    NotAFolder(PathBuf),
    /// The output folder is locked by another run.
    #[error(transparent)]
    Lock(#[from] LockError),
    /// A worker process was stopped from outside (`--isolate`): the study stops, the point
    /// has no result.
    #[error("point {point}: {why}; the study stops (the point is run again on a re-run)")]
    Interrupted {
        /// The point.
        point: usize,
        /// What happened.
        why: String,
    },
    /// A call returned fmi2Fatal in-process: FMI 2.0 forbids any further call to the FMU in
    /// this process, so the study stops. The point is stored as failed; points that another
    /// thread was running then are not (they are run by a re-run).
    #[error(
        "point {point} ({values}): {message}. After fmi2Fatal, FMI 2.0 forbids any further call \
         to this FMU in this process, so the study stops here: finished points are kept in the \
         results store, point {point} is recorded as failed, and the points not finished are \
         run by a re-run. Run again with --isolate: there a Fatal fails its point only and the \
         study goes on (add --allow-failures, for Monte Carlo and LHS, to analyse the others)"
    )]
    Fatal {
        /// The point whose call returned fmi2Fatal.
        point: usize,
        /// Its parameter values.
        values: String,
        /// Why it failed, with what the FMU logged.
        message: String,
    },
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
    if let Some(path) = &study.inputs {
        // The signals themselves change the records, not the file's name. An unreadable file
        // is refused before any run (Interface::resolve).
        let content = std::fs::read(path)
            .map(|b| format!("{:x}", Sha256::digest(&b)))
            .unwrap_or_default();
        key["inputs"] = serde_json::json!(content);
    }
    // Likewise the correlation: studies without one keep their hash.
    if let Some(c) = &study.correlation {
        key["correlation"] = serde_json::json!(c.pairs);
    }
    // SCM follows each input's Askey family since `chaos` became one of its keys: where that
    // changes the design (an input with a non-Hermite germ) the hash says so, so that a store
    // of the old Gauss–Hermite design is not resumed; other SCM studies keep their hash.
    if scm_askey(&study.method) && ChaosBasis::some_own_family(&study.parameters) {
        key["scm_germ"] = serde_json::json!("askey");
    }
    format!("{:x}", Sha256::digest(key.to_string().as_bytes()))
}

/// Whether `method` (or a nested study's inner method) is an SCM on the inputs' Askey
/// families.
fn scm_askey(method: &MethodSpec) -> bool {
    match method {
        MethodSpec::Scm(s) => s.chaos == ChaosBasis::Askey,
        MethodSpec::Nested(n) => scm_askey(&n.inner),
        _ => false,
    }
}

/// What a run produced: every point's record, in design order, read in place from the
/// results store (the series of the runs are not held in memory).
#[derive(Debug)]
pub struct RunOutcome {
    /// Records by point index (all present unless stopped early).
    pub runs: StoredRuns,
    /// The output folder's lock, held while the records are read (None: not locked).
    pub lock: Option<FolderLock>,
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
    /// Warnings of the runs (printed when they arose): a failed reset self-check or
    /// `fmi2Reset`, for `summary.json`.
    pub warnings: Vec<String>,
}

impl RunOutcome {
    /// Every record read into memory (small studies and tests: this holds every series).
    pub fn records(&self) -> Result<Vec<Option<Record>>, StoreError> {
        self.runs.records()
    }
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

/// Runs every point of `design` not yet in the store of `out_dir` (with
/// [`RunOptions::retry_failed`], also the points that failed before), holding the folder's
/// lock ([`FolderLock`]) meanwhile.
pub fn run_points(
    study: &Study,
    fmu: &Fmu,
    design: &Design,
    out_dir: &Path,
    opts: &RunOptions,
) -> Result<RunOutcome, RunError> {
    let started = Instant::now();
    let manifest = manifest(study, fmu, design)?;
    prepare_out_dir(out_dir)?;
    let lock = FolderLock::acquire(out_dir)?;
    if let Some(previous) = lock.taken_over() {
        eprintln!(
            "note: {} was locked by a run that is no longer running ({previous}); taking it over",
            out_dir.display()
        );
    }
    let (store, mut runs) = Store::open_in_place(out_dir, &manifest, opts.fresh)?;
    let records = runs.entries();
    if let Some(note) = store.recovery().summary() {
        eprintln!("warning: {note}");
    }
    let wanted: Vec<usize> = match &opts.points {
        Some(p) => p.iter().copied().filter(|&i| i < design.len()).collect(),
        None => (0..design.len()).collect(),
    };
    let failed_before = wanted
        .iter()
        .filter(|&&i| matches!(records[i], Some(Entry::Failed(_))))
        .count();
    if failed_before > 0 && !opts.retry_failed {
        eprintln!(
            "note: {failed_before} point{} failed in an earlier run and {} not run again \
             (--retry-failed runs {} again)",
            if failed_before == 1 { "" } else { "s" },
            if failed_before == 1 { "is" } else { "are" },
            if failed_before == 1 { "it" } else { "them" },
        );
    }
    let missing: Vec<usize> = wanted
        .iter()
        .copied()
        .filter(|&i| match records[i] {
            None => true,
            Some(Entry::Failed(_)) => opts.retry_failed,
            Some(Entry::Ok(_)) => false,
        })
        .collect();
    let threads = opts
        .threads
        .unwrap_or_else(rayon::current_num_threads)
        .max(1);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(RunError::Pool)?;
    let iface = Interface::resolve(study, fmu)?;
    iface.check_design(fmu, &design.values)?;
    let times = study.times();
    super::interface::check_step_sizes(fmu, &times)?;
    let policy = InstancePolicy {
        reuse: false,
        logging_on: opts.fmu_logging,
    };
    let workers = opts.isolate.as_ref().map(|exe| {
        WorkerPool::new(
            IsolateOptions {
                exe: exe.clone(),
                timeout: opts.timeout_per_run,
            },
            &isolate::setup(fmu, &iface, &times, policy),
        )
    });
    let guard = StudyGuard::begin(&study.name, out_dir, workers.is_none());
    let batch = Batch {
        fmus: WorkerFmus::new(fmu, threads),
        iface,
        study,
        design,
        times,
        store: &store,
        stop_on_failure: !opts.allow_failures(study) || design.is_weighted(),
        max_new: opts.max_new_points,
        workers,
        guard: &guard,
        policy,
        check_reset: !opts.fresh_instances && missing.len() >= 2,
        notes: Notes::default(),
    };
    let mode = match (opts.progress, opts.progress_lines) {
        (true, _) => ProgressMode::Bar,
        (false, true) => ProgressMode::Lines,
        _ => ProgressMode::Off,
    };
    let progress = Progress::new(mode, missing.len());
    let done = AtomicBool::new(false);
    let new = std::thread::scope(|scope| {
        if let (Some(limit), None) = (opts.timeout_per_run, &batch.workers) {
            let (guard, done) = (&guard, &done);
            scope.spawn(move || watchdog(guard, limit, done));
        }
        let new = pool.install(|| batch.run(&missing, &progress));
        done.store(true, Ordering::Release);
        new
    })?;
    progress.finish();
    let warnings = batch.notes.into_warnings();
    let n_new = new.len();
    for (i, e) in new {
        runs.set(i, e);
    }
    Ok(RunOutcome {
        runs,
        lock: Some(lock),
        n_new,
        n_resumed: wanted.len() - missing.len(),
        wall_time: started.elapsed().as_secs_f64(),
        threads,
        fmu_sha256: manifest.fmu_sha256,
        warnings,
    })
}

/// Creates the output folder, or checks that the existing path is one.
pub fn prepare_out_dir(dir: &Path) -> Result<(), RunError> {
    if dir.exists() && !dir.is_dir() {
        return Err(RunError::NotAFolder(dir.to_path_buf()));
    }
    std::fs::create_dir_all(dir).map_err(|source| {
        RunError::Store(StoreError::Io {
            path: dir.to_path_buf(),
            source,
        })
    })
}

/// In-process runs cannot be interrupted: when one outlives `limit`, name it and end the
/// process (the store keeps every finished point).
fn watchdog(guard: &StudyGuard, limit: Duration, done: &AtomicBool) {
    let tick = (limit / 10).clamp(Duration::from_millis(10), Duration::from_millis(250));
    while !done.load(Ordering::Acquire) {
        std::thread::sleep(tick);
        let overdue = guard.overdue(limit);
        if overdue.is_empty() {
            continue;
        }
        let points: Vec<String> = overdue
            .iter()
            .map(|(p, v, t)| format!("point {p} ({v}) has run for {:.1} s", t.as_secs_f64()))
            .collect();
        guard::exit_now(
            guard::EXIT_FAILURE,
            &format!(
                "uq-driver: error: {}, longer than --timeout-per-run {} s. An FMU call cannot be \
                 interrupted inside this process, so the study stops here; finished points are \
                 kept in the results store. Run again with --isolate to have such runs killed \
                 and marked failed while the study goes on.",
                points.join("; "),
                limit.as_secs_f64()
            ),
        );
    }
}

/// Points to run in parallel, each appended to the store as it finishes.
struct Batch<'a> {
    /// The FMU of each worker thread.
    fmus: WorkerFmus<'a>,
    iface: Interface,
    study: &'a Study,
    design: &'a Design,
    times: Vec<f64>,
    store: &'a Store,
    /// Stop at the first failure (failures not allowed, or a weighted design).
    stop_on_failure: bool,
    /// Stop after this many new points.
    max_new: Option<usize>,
    /// `--isolate`: the worker processes.
    workers: Option<WorkerPool>,
    guard: &'a StudyGuard,
    /// How in-process runs get their instance (before the reset self-check: never reused).
    policy: InstancePolicy,
    /// Run the first point as the reset self-check, and reuse instances if it passes.
    check_reset: bool,
    /// Warnings of the runs, each printed once.
    notes: Notes,
}

/// Counters shared by the points of a batch.
#[derive(Default)]
struct Shared {
    stop: AtomicBool,
    started: AtomicUsize,
}

impl Batch<'_> {
    /// Runs `points`; returns where the result of each finished one is in the store (the
    /// values are not kept). With [`Batch::check_reset`], the first point runs alone first as
    /// the reset self-check, which decides whether the others reuse instances.
    fn run(&self, points: &[usize], progress: &Progress) -> Result<Vec<(usize, Entry)>, RunError> {
        let shared = Shared::default();
        let mut first = Vec::new();
        let mut policy = self.policy;
        let mut rest = points;
        if let (true, Some((&i, others))) = (self.check_reset, points.split_first()) {
            let mut check = ResetCheck::NotRun;
            first.extend(self.point(i, &shared, progress, || {
                let (outcome, c) = self.run_checked(i);
                check = c;
                outcome
            })?);
            if let Some(w) = check.warning(i) {
                self.notes.add(w, progress);
            }
            policy.reuse = check.reuse();
            if let Some(workers) = &self.workers {
                workers.set_reuse(policy.reuse);
            }
            rest = others;
        }
        let new: Vec<(usize, Entry)> = rest
            .par_iter()
            .with_min_len(1)
            .map_init(
                || Slot::new(policy, false),
                |slot, &i| self.point(i, &shared, progress, || self.run_one(slot, i, progress)),
            )
            .filter_map(Result::transpose)
            .collect::<Result<_, _>>()?;
        first.extend(new);
        Ok(first)
    }

    /// Runs point `i` by `run` unless the batch stopped, stores its record and says whether
    /// the batch stops.
    fn point(
        &self,
        i: usize,
        shared: &Shared,
        progress: &Progress,
        run: impl FnOnce() -> Result<Outcome, RunError>,
    ) -> Result<Option<(usize, Entry)>, RunError> {
        let stop = &shared.stop;
        if stop.load(Ordering::Relaxed) {
            return Ok(None);
        }
        if let Some(max) = self.max_new {
            if shared.started.fetch_add(1, Ordering::SeqCst) >= max {
                stop.store(true, Ordering::Relaxed);
                return Ok(None);
            }
        }
        let (rec, fatal) = match run() {
            Ok(Outcome::Done(rec)) => (rec, None),
            Ok(Outcome::Fatal(rec, message)) => (rec, Some(message)),
            // Refused after another instance's Fatal: not run, not stored.
            Ok(Outcome::Refused) => return Ok(None),
            Err(e) => {
                stop.store(true, Ordering::Relaxed);
                return Err(e);
            }
        };
        if fatal.is_some() || (matches!(rec, Record::Failed(_)) && self.stop_on_failure) {
            stop.store(true, Ordering::Relaxed);
        }
        let entry = self.store.append(i, &rec)?;
        progress.inc();
        if let Some(message) = fatal {
            return Err(RunError::Fatal {
                point: i,
                values: describe_values(self.study, &self.design.values[i]),
                message,
            });
        }
        if let Some(why) = self
            .workers
            .as_ref()
            .and_then(WorkerPool::take_reset_failure)
        {
            self.notes.reset_failed(&why, progress);
        }
        Ok(Some((i, entry)))
    }

    /// Runs point `i` in-process (on `slot`'s instance) or in a worker process.
    fn run_one(&self, slot: &mut Slot, i: usize, progress: &Progress) -> Result<Outcome, RunError> {
        let values = &self.design.values[i];
        let _running = self.guard.running(i, describe_values(self.study, values));
        let Some(workers) = &self.workers else {
            let fmu = self.fmus.current()?;
            let result = run_point(&fmu, slot, &self.iface, values, &self.times);
            if let Some(why) = slot.take_reset_failure() {
                self.notes.reset_failed(&why, progress);
            }
            return Ok(in_process(result));
        };
        from_worker(i, workers.run(values))
    }

    /// Runs point `i` as the reset self-check: on a fresh instance (its record is the point's),
    /// then again after `fmi2Reset` of that instance, each run timed on its own.
    fn run_checked(&self, i: usize) -> (Result<Outcome, RunError>, ResetCheck) {
        let values = &self.design.values[i];
        let running = || self.guard.running(i, describe_values(self.study, values));
        let Some(workers) = &self.workers else {
            let fmu = match self.fmus.current() {
                Ok(f) => f,
                Err(e) => return (Err(e.into()), ResetCheck::NotRun),
            };
            let mut slot = Slot::new(self.policy, false);
            let first = {
                let _running = running();
                run_point(&fmu, &mut slot, &self.iface, values, &self.times)
            };
            let Ok(record) = &first else {
                return (Ok(in_process(first)), ResetCheck::NotRun);
            };
            let (check, fatal) = {
                let _running = running();
                super::point::check_reset(&fmu, &mut slot, &self.iface, values, &self.times, record)
            };
            // Freed before the other points start (an FMU instantiable once per process).
            drop(slot);
            return match (fatal, first) {
                // fmi2Fatal after the reset: no further call in this process. The point's own
                // run (on a fresh instance) succeeded and is kept; the study stops.
                (Some(e), Ok(v)) => (
                    Ok(Outcome::Fatal(
                        Record::Ok(v),
                        format!(
                            "{e} (in the second run of the point, after fmi2Reset, of the reset \
                             self-check; its run on a fresh instance succeeded and is kept; \
                             --fresh-instances never resets)"
                        ),
                    )),
                    check,
                ),
                (_, first) => (Ok(in_process(first)), check),
            };
        };
        let first = {
            let _running = running();
            workers.run(values)
        };
        if first.is_err() {
            return (from_worker(i, first), ResetCheck::NotRun);
        }
        let check = {
            let _running = running();
            workers.check_reset(values)
        };
        match check {
            Ok(check) => (from_worker(i, first), check),
            // Stopped from outside: the study stops, a re-run computes the point.
            Err(why) => (
                Err(RunError::Interrupted { point: i, why }),
                ResetCheck::NotRun,
            ),
        }
    }
}

/// The outcome of an in-process run.
fn in_process(result: Result<Vec<f64>, PointError>) -> Outcome {
    match result {
        Ok(v) => Outcome::Done(Record::Ok(v)),
        Err(e) if e.refused_after_fatal() => Outcome::Refused,
        // This point's own call returned Fatal.
        Err(e) if e.returned_fatal() => {
            Outcome::Fatal(Record::Failed(e.to_string()), e.to_string())
        }
        Err(e) => Outcome::Done(Record::Failed(e.to_string())),
    }
}

/// The outcome of a run in a worker process.
fn from_worker(i: usize, result: Result<Vec<f64>, WorkerFailure>) -> Result<Outcome, RunError> {
    match result {
        Ok(v) => Ok(Outcome::Done(Record::Ok(v))),
        Err(WorkerFailure::Point(m) | WorkerFailure::Died(m)) => {
            Ok(Outcome::Done(Record::Failed(m)))
        }
        Err(WorkerFailure::Interrupted(m)) => Err(RunError::Interrupted { point: i, why: m }),
    }
}

/// Warnings of a batch's runs: printed as they arise, each kind once, and kept.
#[derive(Default)]
struct Notes {
    warnings: std::sync::Mutex<Vec<String>>,
    reset_failed: AtomicBool,
}

impl Notes {
    fn add(&self, warning: String, progress: &Progress) {
        progress.println(&format!("uq-driver: warning: {warning}"));
        self.warnings
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .push(warning);
    }

    /// A `fmi2Reset` failed (the run got a fresh instance): said once.
    fn reset_failed(&self, why: &str, progress: &Progress) {
        if !self.reset_failed.swap(true, Ordering::Relaxed) {
            self.add(instances::reset_failed_warning(why), progress);
        }
    }

    fn into_warnings(self) -> Vec<String> {
        self.warnings
            .into_inner()
            .unwrap_or_else(|e| e.into_inner())
    }
}

/// How a point ended.
enum Outcome {
    /// Run: its record.
    Done(Record),
    /// A call of its run returned fmi2Fatal in-process: the record to keep (failed, or the
    /// successful fresh run of a reset self-check whose second run returned Fatal) and the
    /// message; the study stops.
    Fatal(Record, String),
    /// Refused in-process because another point's call had returned fmi2Fatal: not run.
    Refused,
}

/// What is known of the failures: "3 of 200 points failed" when every point was run, else
/// "stopped after the first 2 failures of 200 points (runs not started: 190; ...)".
fn failure_count(failed: usize, total: usize, not_run: usize) -> String {
    if not_run == 0 {
        return format!("{failed} of {total} points failed");
    }
    let first = if failed == 1 {
        "at the first failure".to_owned()
    } else {
        format!("after the first {failed} failures")
    };
    format!(
        "stopped {first} of {total} points (runs not started: {not_run}; how many of those \
         would fail is not known)"
    )
}

/// "K = 1.2, C = 3" for messages.
fn describe_values(study: &Study, values: &[f64]) -> String {
    study
        .parameters
        .iter()
        .zip(values)
        .map(|(p, v)| format!("{} = {v}", p.name))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The number of failed points; an error naming the first when failures are not allowed
/// (or the design is weighted: dropping a weighted point would bias every moment silently),
/// with how many of the `points` (None: every point) were not run (the study stops at the
/// first failure).
pub fn check_failures(
    study: &Study,
    design: &Design,
    records: &[Option<Entry>],
    allow: bool,
    points: Option<&[usize]>,
) -> Result<usize, RunError> {
    let failed: Vec<(usize, &String)> = records
        .iter()
        .enumerate()
        .filter_map(|(i, r)| match r {
            Some(Entry::Failed(m)) => Some((i, m)),
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
    let wanted: Vec<usize> = match points {
        Some(p) => p.iter().copied().filter(|&i| i < records.len()).collect(),
        None => (0..records.len()).collect(),
    };
    Err(RunError::PointsFailed {
        failed: failed.len(),
        total: wanted.len(),
        not_run: wanted.iter().filter(|&&i| records[i].is_none()).count(),
        first: FailedPoint {
            index,
            parameters,
            message: message.clone(),
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// QA F4: a study stopped at its first failures said "2 of 200 points failed" although
    /// 103 of them fail; the points not started are not counted as successes.
    #[test]
    fn failure_message_says_the_study_stopped_and_how_many_points_were_not_started() {
        let first = FailedPoint {
            index: 4,
            parameters: vec![("K".into(), 1.5)],
            message: "NaN".into(),
        };
        let err = |failed, not_run| {
            RunError::PointsFailed {
                failed,
                total: 200,
                not_run,
                first: first.clone(),
            }
            .to_string()
        };
        let one = err(1, 197);
        assert!(
            one.starts_with(
                "stopped at the first failure of 200 points (runs not started: 197; how many \
                 of those would fail is not known); first: point 4 with K = 1.5: NaN."
            ),
            "{one}"
        );
        let two = err(2, 150);
        assert!(
            two.starts_with(
                "stopped after the first 2 failures of 200 points (runs not started: 150;"
            ),
            "{two}"
        );
        assert!(!two.contains("2 of 200 points failed"));
        // Every point run: the count is the whole truth.
        assert!(err(103, 0).starts_with("103 of 200 points failed; first: point 4"));
    }

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
    fn an_scm_whose_design_follows_the_askey_families_does_not_resume_a_hermite_store() {
        // SCM with a uniform input now runs Gauss–Legendre nodes; a store of the Gauss–Hermite
        // design the same file gave before must not be resumed, so its hash differs from the
        // hash of the same file with `chaos = "hermite"` and from the hash without the key
        // as computed before (the method serialised without `chaos`, no `scm_germ`).
        let text = |dist: &str, chaos: &str| {
            format!(
                "name = \"u\"\nfmu = \"Wheel.fmu\"\n[experiment]\nstop = 1.0\nstep = 0.01\n\
                 [[parameters]]\nname = \"K\"\n{dist}\n\
                 [outputs]\nvariables = [\"q\"]\n[method]\nkind = \"scm\"\nnodes = 3\n{chaos}"
            )
        };
        let study = |t: String| Study::parse(&t, "t.toml", None).unwrap();
        let uniform = "distribution = \"uniform\"\nlow = 90.0\nhigh = 110.0";
        let askey = study(text(uniform, ""));
        let hermite = study(text(uniform, "chaos = \"hermite\""));
        assert_ne!(study_hash(&askey), study_hash(&hermite));
        let mut old_key = serde_json::json!({
            "seed": askey.seed,
            "experiment": askey.experiment,
            "method": askey.method,
            "parameters": askey.parameters,
            "fixed": askey.fixed,
            "outputs": { "variables": askey.outputs },
        });
        let old = format!("{:x}", Sha256::digest(old_key.to_string().as_bytes()));
        assert_ne!(study_hash(&askey), old);
        // A normal input: the design is the Gauss–Hermite one either way, the hash as before.
        let normal = study(text("mean = 100.0\nstd = 10.0", ""));
        old_key["parameters"] = serde_json::json!(normal.parameters);
        old_key["seed"] = serde_json::json!(normal.seed);
        let old = format!("{:x}", Sha256::digest(old_key.to_string().as_bytes()));
        assert_eq!(study_hash(&normal), old);
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
