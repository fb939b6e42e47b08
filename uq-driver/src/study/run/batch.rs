//! The points of a run, in parallel: each on its thread's FMU instance (or in a worker
//! process, `--isolate`), the first one alone as the reset self-check when instances are to
//! be reused, every finished point appended to the results store at once.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

use rayon::prelude::*;

use super::error::{PointError, RunError};
use super::options::RunControl;
use super::point::{describe_values, run_point};
use crate::spec::Study;
use crate::study::plan::interface::Interface;
use crate::study::progress::Progress;
use crate::study::run::guard::StudyGuard;
use crate::study::run::instances::{self, InstancePolicy, ResetCheck, Slot};
use crate::study::run::isolate::{WorkerFailure, WorkerPool};
use crate::study::run::worker_fmu::WorkerFmus;
use crate::study::store::valid::RecordRules;
use crate::study::store::{Entry, Record, Store};

/// Points to run in parallel, each appended to the store as it finishes.
pub(super) struct Batch<'a> {
    /// The FMU of each worker thread.
    pub(super) fmus: &'a WorkerFmus<'a>,
    pub(super) iface: &'a Interface,
    pub(super) study: &'a Study,
    pub(super) times: &'a [f64],
    pub(super) store: &'a Store,
    /// Stop at the first failure (failures not allowed, or a weighted design).
    pub(super) stop_on_failure: bool,
    /// Stop after this many new points (counted over every batch of a study: `started`).
    pub(super) max_new: Option<usize>,
    /// Points started so far by the batches of the study.
    pub(super) started: &'a AtomicUsize,
    /// `--isolate`: the worker processes.
    pub(super) workers: Option<&'a WorkerPool>,
    pub(super) guard: &'a StudyGuard,
    /// How in-process runs get their instance (before the reset self-check: never reused).
    pub(super) policy: InstancePolicy,
    /// Run the first point as the reset self-check, and reuse instances if it passes.
    pub(super) check_reset: bool,
    /// Warnings of the runs, each printed once.
    pub(super) notes: &'a Notes,
    /// What a successful record must hold; one that does not fails its point.
    pub(super) rules: &'a RecordRules,
    /// The host's stop request and progress counter.
    pub(super) control: Option<&'a RunControl>,
}

/// A point of a batch: its index (in the design, or the run index of an adaptive method)
/// and its parameter values.
pub(crate) type Job<'v> = (usize, &'v [f64]);

impl Batch<'_> {
    /// Runs `points`; returns where the result of each finished one is in the store (the
    /// values are not kept), and the instance policy the runs used. With
    /// [`Batch::check_reset`], the first point runs alone first as the reset self-check,
    /// which decides whether the others (and later batches) reuse instances.
    pub(super) fn run(
        &self,
        points: &[Job],
        progress: &Progress,
    ) -> Result<(Vec<(usize, Entry)>, InstancePolicy), RunError> {
        let stop = AtomicBool::new(false);
        let mut first = Vec::new();
        let mut policy = self.policy;
        let mut rest = points;
        if let (true, Some((&(i, values), others))) = (self.check_reset, points.split_first()) {
            let mut check = ResetCheck::NotRun;
            first.extend(self.point(i, values, &stop, progress, || {
                let (outcome, c) = self.run_checked(i, values);
                check = c;
                outcome
            })?);
            if let Some(w) = check.warning(i) {
                self.notes.add(w, progress);
            }
            policy.reuse = check.reuse();
            if let Some(workers) = self.workers {
                workers.set_reuse(policy.reuse);
            }
            rest = others;
        }
        let new: Vec<(usize, Entry)> = rest
            .par_iter()
            .with_min_len(1)
            .map_init(
                || Slot::new(policy, false),
                |slot, &(i, values)| {
                    self.point(i, values, &stop, progress, || {
                        self.run_one(slot, i, values, progress)
                    })
                },
            )
            .filter_map(Result::transpose)
            .collect::<Result<_, _>>()?;
        first.extend(new);
        Ok((first, policy))
    }

    /// Runs point `i` by `run` unless the batch stopped, stores its record and says whether
    /// the batch stops.
    fn point(
        &self,
        i: usize,
        values: &[f64],
        stop: &AtomicBool,
        progress: &Progress,
        run: impl FnOnce() -> Result<Outcome, RunError>,
    ) -> Result<Option<(usize, Entry)>, RunError> {
        if stop.load(Ordering::Relaxed) || self.control.is_some_and(RunControl::stopped) {
            return Ok(None);
        }
        if let Some(max) = self.max_new {
            if self.started.fetch_add(1, Ordering::SeqCst) >= max {
                stop.store(true, Ordering::Relaxed);
                return Ok(None);
            }
        }
        let (rec, fatal) = match run() {
            Ok(Outcome::Done(Record::Ok(v))) => match self.rules.check(v.iter().copied()) {
                Ok(()) => (Record::Ok(v), None),
                Err(problem) => (Record::Failed(format!("the run gave {problem}")), None),
            },
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
        if let Some(c) = self.control {
            c.point_done();
        }
        if let Some(message) = fatal {
            return Err(RunError::Fatal {
                point: i,
                values: describe_values(self.study, values),
                message,
            });
        }
        if let Some(why) = self.workers.and_then(WorkerPool::take_reset_failure) {
            self.notes.reset_failed(&why, progress);
        }
        Ok(Some((i, entry)))
    }

    /// Runs point `i` in-process (on `slot`'s instance) or in a worker process.
    fn run_one(
        &self,
        slot: &mut Slot,
        i: usize,
        values: &[f64],
        progress: &Progress,
    ) -> Result<Outcome, RunError> {
        let _running = self.guard.running(i, describe_values(self.study, values));
        let Some(workers) = self.workers else {
            let fmu = self.fmus.current()?;
            let result = run_point(&fmu, slot, self.iface, values, self.times);
            if let Some(why) = slot.take_reset_failure() {
                self.notes.reset_failed(&why, progress);
            }
            return Ok(in_process(result));
        };
        from_worker(i, workers.run(values))
    }

    /// Runs point `i` as the reset self-check: on a fresh instance (its record is the point's),
    /// then again after `fmi2Reset` of that instance, each run timed on its own.
    fn run_checked(&self, i: usize, values: &[f64]) -> (Result<Outcome, RunError>, ResetCheck) {
        let running = || self.guard.running(i, describe_values(self.study, values));
        let Some(workers) = self.workers else {
            let fmu = match self.fmus.current() {
                Ok(f) => f,
                Err(e) => return (Err(e.into()), ResetCheck::NotRun),
            };
            let mut slot = Slot::new(self.policy, false);
            let first = {
                let _running = running();
                run_point(&fmu, &mut slot, self.iface, values, self.times)
            };
            let Ok(record) = &first else {
                return (Ok(in_process(first)), ResetCheck::NotRun);
            };
            let (check, fatal) = {
                let _running = running();
                crate::study::run::point::check_reset(
                    &fmu, &mut slot, self.iface, values, self.times, record,
                )
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
pub(super) struct Notes {
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

    pub(super) fn into_warnings(self) -> Vec<String> {
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
