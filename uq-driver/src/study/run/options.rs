//! How to run a study: the options of `run`, `run-shard` and `merge` as a library takes them.

use std::path::PathBuf;
use std::time::Duration;

use super::error::RunError;
use super::guard;
use crate::spec::Study;

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
