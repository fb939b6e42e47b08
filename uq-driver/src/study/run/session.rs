//! An output folder open for runs, kept over the batches of a study: the folder's lock, the
//! results store, the thread pool, the FMU's interface, the worker processes (`--isolate`),
//! the guard and the instance policy decided by the reset self-check. A design runs as one
//! batch ([`super::run_points`]); an adaptive method runs batch after batch, each asked for
//! once the one before has finished.

use std::path::Path;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::Instant;

use super::batch::{Batch, Job, Notes};
use super::error::RunError;
use super::guard::StudyGuard;
use super::instances::InstancePolicy;
use super::isolate::{self, IsolateOptions, WorkerPool};
use super::options::RunOptions;
use super::worker_fmu::WorkerFmus;
use super::{prepare_out_dir, watchdog};
use crate::fmu::Fmu;
use crate::spec::Study;
use crate::study::plan::interface::Interface;
use crate::study::progress::{Progress, ProgressMode};
use crate::study::store::lock::FolderLock;
use crate::study::store::valid::RecordRules;
use crate::study::store::{Entry, Manifest, Store, StoredRuns};

/// An output folder open for runs.
pub(crate) struct Session<'a> {
    study: &'a Study,
    opts: &'a RunOptions,
    /// The folder's lock, held while the session lives (and its records are read).
    pub(crate) lock: FolderLock,
    store: Store,
    /// Every point's record so far (the store's, and those run by this session).
    pub(crate) runs: StoredRuns,
    /// The store's manifest.
    pub(crate) manifest: Manifest,
    pool: rayon::ThreadPool,
    /// The FMU's interface of the study.
    pub(crate) iface: Interface,
    times: Vec<f64>,
    /// What a successful record must hold.
    rules: RecordRules,
    fmus: WorkerFmus<'a>,
    workers: Option<WorkerPool>,
    guard: StudyGuard,
    notes: Notes,
    started: AtomicUsize,
    policy: InstancePolicy,
    reset_checked: bool,
    stop_on_failure: bool,
    /// Worker threads.
    pub(crate) threads: usize,
    /// Points run by this session.
    pub(crate) new: usize,
    /// When the session opened.
    pub(crate) opened: Instant,
}

impl<'a> Session<'a> {
    /// Opens `out_dir` (its lock, its store for `manifest`) to run points of `study` on
    /// `fmu`; `stop_on_failure`: a batch stops at its first failed point.
    pub(crate) fn open(
        study: &'a Study,
        fmu: &'a Fmu,
        manifest: Manifest,
        out_dir: &Path,
        opts: &'a RunOptions,
        stop_on_failure: bool,
    ) -> Result<Session<'a>, RunError> {
        let opened = Instant::now();
        prepare_out_dir(out_dir)?;
        let lock = FolderLock::acquire(out_dir)?;
        if let Some(previous) = lock.taken_over() {
            crate::study::progress::message(&format!(
                "note: {} was locked by a run that is no longer running ({previous}); taking it \
                 over",
                out_dir.display()
            ));
        }
        let iface = crate::study::plan::resolve::interface(study, fmu)?;
        let times = study.times();
        let rules = super::record_rules(&iface, &times);
        let (store, runs) = Store::open_checked(out_dir, &manifest, opts.fresh, Some(&rules))?;
        if let Some(note) = store.recovery().summary() {
            crate::study::progress::message(&format!("warning: {note}"));
        }
        let threads = opts.threads.unwrap_or_else(rayon::current_num_threads);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .map_err(RunError::Pool)?;
        crate::study::plan::interface::check_step_sizes(fmu, &times)?;
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
        Ok(Session {
            study,
            opts,
            lock,
            store,
            runs,
            manifest,
            pool,
            iface,
            times,
            rules,
            fmus: WorkerFmus::new(fmu, threads),
            workers,
            guard,
            notes: Notes::default(),
            started: AtomicUsize::new(0),
            policy,
            reset_checked: opts.fresh_instances,
            stop_on_failure,
            threads,
            new: 0,
            opened,
        })
    }

    /// Runs `jobs` in parallel (each appended to the store as it finishes) and records them
    /// in [`Session::runs`]; returns the points that finished (fewer than `jobs` when a
    /// failure or `max_new_points` stopped the batch). The first batch of two points or more
    /// begins with the reset self-check.
    pub(crate) fn run(&mut self, jobs: &[Job]) -> Result<Vec<(usize, Entry)>, RunError> {
        if jobs.is_empty() {
            return Ok(Vec::new());
        }
        let check_reset = !self.reset_checked && jobs.len() >= 2;
        let mode = match (self.opts.progress, self.opts.progress_lines) {
            (true, _) => ProgressMode::Bar,
            (false, true) => ProgressMode::Lines,
            _ => ProgressMode::Off,
        };
        let progress = Progress::new(mode, jobs.len());
        let batch = Batch {
            fmus: &self.fmus,
            iface: &self.iface,
            study: self.study,
            times: &self.times,
            store: &self.store,
            stop_on_failure: self.stop_on_failure,
            max_new: self.opts.max_new_points,
            started: &self.started,
            workers: self.workers.as_ref(),
            guard: &self.guard,
            policy: self.policy,
            check_reset,
            notes: &self.notes,
            rules: &self.rules,
            control: self.opts.control.as_deref(),
        };
        let done = AtomicBool::new(false);
        let (guard, pool) = (&self.guard, &self.pool);
        let timeout = self.opts.timeout_per_run;
        let in_process = self.workers.is_none();
        let result = std::thread::scope(|scope| {
            // In-process, only with the process guards (checked by `RunOptions::check`).
            if let (Some(limit), true) = (timeout, in_process) {
                let done = &done;
                scope.spawn(move || watchdog(guard, limit, done));
            }
            let r = pool.install(|| batch.run(jobs, &progress));
            done.store(true, Ordering::Release);
            r
        });
        progress.finish();
        let (new, policy) = result?;
        if check_reset {
            self.reset_checked = true;
            self.policy = policy;
        }
        self.new += new.len();
        for (i, e) in &new {
            self.runs.set(*i, e.clone());
        }
        Ok(new)
    }

    /// The warnings of the runs so far (printed as they arose).
    pub(crate) fn into_warnings(self) -> (StoredRuns, FolderLock, Vec<String>) {
        (self.runs, self.lock, self.notes.into_warnings())
    }
}
