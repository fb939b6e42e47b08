//! How to run a study: the options of `run`, `run-shard` and `merge` as a library takes them.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::Duration;

use super::error::RunError;
use super::guard;
use crate::spec::Study;

/// How to run a study. Built from [`RunOptions::default`] (all cores, resume, a report) with
/// the `with_*` methods, or by setting fields on a default value:
///
/// ```
/// use uq_driver::study::RunOptions;
/// let opts = RunOptions::default().with_threads(2).with_no_report(true).with_fresh(true);
/// assert_eq!(opts.threads, Some(2));
/// ```
#[derive(Clone, Debug, Default)]
#[non_exhaustive]
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
    /// (the `uq-driver worker` protocol); None: in-process.
    pub isolate: Option<PathBuf>,
    /// `--timeout-per-run`: with `isolate` a longer run is killed and fails its point.
    /// In-process an FMU call cannot be interrupted, so a longer run ends the whole process
    /// after naming the point: allowed only after [`guard::install_process_guards`] (the
    /// command line's choice), refused with [`RunError::Options`] otherwise.
    pub timeout_per_run: Option<Duration>,
    /// Start a large study without asking (`--yes`; see the size checks of a study).
    pub yes: bool,
    /// `--fresh-instances`: every run on a fresh FMU instance, never reused through
    /// `fmi2Reset` (and no reset self-check).
    pub fresh_instances: bool,
    /// `--fmu-logging`: instantiate with `loggingOn = true` (the FMU's messages are kept with
    /// failed points, capped, not printed).
    pub fmu_logging: bool,
    /// A host's hand on the run from another thread: stop it, read its progress (None: the
    /// run goes to its end, or to a signal of the process guards).
    pub control: Option<Arc<RunControl>>,
}

/// A host's hand on a running study from another thread (a GUI, the Python package): ask it
/// to stop, and read how many points are done. Shared through [`RunOptions::control`].
///
/// [`RunControl::stop`] is the library's Ctrl-C: no point starts after it, the points
/// running finish and are stored, and [`crate::study::run_study`] returns
/// [`crate::study::StudyRunError::Incomplete`]; a later run into the same folder resumes
/// (as after Ctrl-C on the command line). An FMU call is never interrupted, and a study
/// whose points were all done before the stop completes. A control serves one run at a
/// time; [`RunControl::progress`] counts the points of the variant running now (a suite runs
/// its variants one after another).
///
/// ```
/// use std::sync::Arc;
/// use uq_driver::study::{RunControl, RunOptions};
/// let control = Arc::new(RunControl::default());
/// let opts = RunOptions::default().with_control(Arc::clone(&control));
/// // ... run_study(&study, out, &opts) on one thread; on another:
/// let (done, total) = control.progress();
/// assert_eq!((done, total), (0, 0));
/// control.stop();
/// assert!(control.stopped());
/// # drop(opts);
/// ```
#[derive(Debug, Default)]
pub struct RunControl {
    stop: AtomicBool,
    done: AtomicUsize,
    total: AtomicUsize,
}

impl RunControl {
    /// Asks the run to stop: no new point starts (see the type).
    pub fn stop(&self) {
        self.stop.store(true, Ordering::Release);
    }

    /// Whether [`RunControl::stop`] was called.
    pub fn stopped(&self) -> bool {
        self.stop.load(Ordering::Acquire)
    }

    /// `(done, total)`: points finished in this invocation and points it has to run (those
    /// not found finished in the results store) of the batch running now; `(0, 0)` before
    /// the points start.
    pub fn progress(&self) -> (usize, usize) {
        (
            self.done.load(Ordering::Acquire),
            self.total.load(Ordering::Acquire),
        )
    }

    /// A batch of `total` points starts.
    pub(crate) fn begin(&self, total: usize) {
        self.done.store(0, Ordering::Release);
        self.total.store(total, Ordering::Release);
    }

    /// One more point finished.
    pub(crate) fn point_done(&self) {
        self.done.fetch_add(1, Ordering::AcqRel);
    }
}

/// Builder methods of [`RunOptions`]: `with_x: x = (T);` sets the field `x` to the argument,
/// `with_x: x = Some(T);` to `Some` of it.
macro_rules! setters {
    ($($(#[$doc:meta])* $name:ident: $field:ident = $($some:ident)?($t:ty);)*) => {
        $(
            $(#[$doc])*
            pub fn $name(mut self, v: $t) -> Self {
                self.$field = $($some)?(v);
                self
            }
        )*
    };
}

impl RunOptions {
    setters! {
        /// Worker threads of the model runs (at least 1; the default is all cores).
        with_threads: threads = Some(usize);
        /// Shows a progress bar (on a terminal).
        with_progress: progress = (bool);
        /// Prints progress lines (for a log file).
        with_progress_lines: progress_lines = (bool);
        /// Unweighted designs: continues past failed points.
        with_allow_failures: allow_failures = (bool);
        /// Discards earlier results in the output folder.
        with_fresh: fresh = (bool);
        /// Stops after this many newly finished points (the study resumes later).
        with_max_new_points: max_new_points = Some(usize);
        /// Runs only these points of the design (a shard).
        with_points: points = Some(Vec<usize>);
        /// Writes the CSV files and `summary.json` only.
        with_no_report: no_report = (bool);
        /// Runs the points that failed in an earlier run again.
        with_retry_failed: retry_failed = (bool);
        /// Runs each point in a worker process started from this executable (see the field).
        with_isolate: isolate = Some(PathBuf);
        /// The time limit of one run (see the field).
        with_timeout_per_run: timeout_per_run = Some(Duration);
        /// Starts a large study without asking.
        with_yes: yes = (bool);
        /// Runs every point on a fresh FMU instance.
        with_fresh_instances: fresh_instances = (bool);
        /// Instantiates the FMU with `loggingOn = true`.
        with_fmu_logging: fmu_logging = (bool);
        /// Shares `v` with the run: stop it or read its progress from another thread.
        with_control: control = Some(Arc<RunControl>);
    }

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
                     uq_driver::study::run::guard::install_process_guards() first if this program \
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
