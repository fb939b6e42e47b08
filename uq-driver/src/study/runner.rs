//! Running a study's points: the options, the errors, the output folder (its lock, its store
//! and the in-process time limit) and the failure policy. The points themselves run in
//! `batch.rs` (one FMU instance per worker, reused through `fmi2Reset` once the reset
//! self-check has passed: [`super::instances`]); what identifies the records is in
//! `fingerprint.rs` (re-exported here).

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use super::batch::{Batch, Notes};
pub use super::fingerprint::{manifest, sha256_file, study_hash};
use super::guard::{self, StudyGuard};
use super::instances::InstancePolicy;
use super::interface::{Interface, InterfaceError};
use super::isolate::{self, IsolateOptions, WorkerPool};
use super::lock::{FolderLock, LockError};
pub use super::point::{run_point, simulate, simulate_with, PointError, Simulation, Trace};
use super::progress::{Progress, ProgressMode};
use super::store::{Entry, Record, Store, StoreError, StoredRuns};
use super::worker_fmu::WorkerFmus;
use crate::fmu::{Fmu, FmuError};
use crate::spec::Study;
use crate::uq::method::{Design, MethodError};

/// How to run a study.
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    /// Worker threads of the model runs (None: all cores; 0 is refused).
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
    /// Run only these points of the design (a shard); None: all. A point outside the design
    /// is refused ([`RunError::Options`]).
    pub points: Option<Vec<usize>>,
    /// Write the CSV files and `summary.json` only: no plots, no `index.html`.
    pub no_report: bool,
    /// Run the points that failed in an earlier run again (`--retry-failed`).
    pub retry_failed: bool,
    /// `--isolate`: run each point in a worker process started from this uq-driver executable
    /// (see [`isolate`]); None: in-process.
    pub isolate: Option<PathBuf>,
    /// `--timeout-per-run`: with `isolate` a longer run is killed and fails its point.
    /// In-process an FMU call cannot be interrupted, so a longer run ends the whole process
    /// after naming the point: allowed only after [`guard::install_process_guards`] (the
    /// command line's choice), refused with [`RunError::Options`] otherwise.
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
    /// Checks that the options fit together: `threads` at least 1, and `timeout_per_run`
    /// either with `isolate` (a longer run is killed) or in a process that opted in to
    /// [`guard::install_process_guards`] (in-process, a longer run ends the whole process,
    /// which a library host must ask for).
    pub fn check(&self) -> Result<(), RunError> {
        if self.threads == Some(0) {
            return Err(RunError::Options(
                "threads = 0: give at least 1 worker thread (RunOptions::threads = None: \
                 all cores)"
                    .into(),
            ));
        }
        if let (Some(limit), None) = (self.timeout_per_run, &self.isolate) {
            if !guard::process_guards() {
                return Err(RunError::Options(format!(
                    "timeout_per_run = {} s without isolate: an FMU call cannot be interrupted \
                     inside this process, so an overrun could only be stopped by ending the \
                     whole process, which a library caller has not asked for. Set \
                     RunOptions::isolate (each run in a worker process that is killed after \
                     the limit; the --isolate of the command line), or call \
                     uq_driver::study::guard::install_process_guards() first if this program \
                     owns its process and may end on an overrun",
                    limit.as_secs_f64()
                )));
            }
        }
        Ok(())
    }

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
         with --retry-failed (RunOptions::retry_failed) to re-run the failed points (or \
         --allow-failures, RunOptions::allow_failures, for Monte Carlo and LHS, to analyse the \
         others)",
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
    /// No output folder was given (an empty path would write into the current folder).
    #[error("no output folder: the output path is empty (give a folder for the results store and the result files)")]
    NoOutDir,
    /// The run options do not fit together (e.g. `timeout_per_run` in-process without the
    /// process guards).
    #[error("{0}")]
    Options(String),
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
         run by a re-run. Run again with --isolate (RunOptions::isolate): there a Fatal fails \
         its point only and the study goes on (add --allow-failures, RunOptions::allow_failures, \
         for Monte Carlo and LHS, to analyse the others)"
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
    opts.check()?;
    if let Some(&bad) = opts
        .points
        .as_ref()
        .and_then(|p| p.iter().find(|&&i| i >= design.len()))
    {
        return Err(RunError::Options(format!(
            "RunOptions::points names point {bad}, but the design has {} points (0 to {})",
            design.len(),
            design.len().saturating_sub(1)
        )));
    }
    let started = Instant::now();
    let manifest = manifest(study, fmu, design)?;
    prepare_out_dir(out_dir)?;
    let lock = FolderLock::acquire(out_dir)?;
    if let Some(previous) = lock.taken_over() {
        super::progress::message(&format!(
            "note: {} was locked by a run that is no longer running ({previous}); taking it over",
            out_dir.display()
        ));
    }
    let (store, mut runs) = Store::open_in_place(out_dir, &manifest, opts.fresh)?;
    let records = runs.entries();
    if let Some(note) = store.recovery().summary() {
        super::progress::message(&format!("warning: {note}"));
    }
    let wanted: Vec<usize> = match &opts.points {
        Some(p) => p.clone(),
        None => (0..design.len()).collect(),
    };
    let failed_before = wanted
        .iter()
        .filter(|&&i| matches!(records[i], Some(Entry::Failed(_))))
        .count();
    if failed_before > 0 && !opts.retry_failed {
        super::progress::message(&format!(
            "note: {failed_before} point{} failed in an earlier run and {} not run again \
             (--retry-failed, RunOptions::retry_failed, runs {} again)",
            if failed_before == 1 { "" } else { "s" },
            if failed_before == 1 { "is" } else { "are" },
            if failed_before == 1 { "it" } else { "them" },
        ));
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
    let threads = opts.threads.unwrap_or_else(rayon::current_num_threads);
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
        // In-process, only with the process guards (checked by `opts.check()` above).
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
    if dir.as_os_str().is_empty() {
        return Err(RunError::NoOutDir);
    }
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
pub(super) fn describe_values(study: &Study, values: &[f64]) -> String {
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

    /// A study stopped at its first failures said "2 of 200 points failed" although
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
}
