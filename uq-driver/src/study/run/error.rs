//! How running points fails: a study's runs ([`RunError`]), one point ([`PointError`]).

use std::path::PathBuf;

use crate::fmu::{FmuError, Status};
use crate::qoi::QoiError;
use crate::study::plan::interface::InterfaceError;
use crate::study::store::lock::LockError;
use crate::study::store::StoreError;
use crate::uq::method::MethodError;

/// A point that failed: where and why.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
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
#[non_exhaustive]
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
         with --retry-failed to re-run the failed points{}",
        failure_count(*.failed, *.total, *.not_run),
        allow_failures_hint(*.allow_failures_applies)
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
        /// Whether `--allow-failures` (`RunOptions::allow_failures`) would let the study
        /// analyse the other points: true for an unweighted design (`mc`, `lhs`, `qmc`,
        /// `pce_regression`, `sobol_sampling`), false for a weighted one (collocation, sparse
        /// grids, a nominal run), which cannot leave a point out.
        allow_failures_applies: bool,
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
    /// The output folder cannot be created (or written): no folder can be made in it, or in
    /// the nearest existing folder above it.
    #[error(
        "{}: the output folder cannot be created or written: no folder can be made in {} ({source}); \
         give an output folder where you can write",
        path.display(),
        existing.display()
    )]
    OutDirNotWritable {
        /// The output folder.
        path: PathBuf,
        /// The nearest existing folder at or above it, where the test failed.
        existing: PathBuf,
        /// Why.
        source: std::io::Error,
    },
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
         to analyse the others: mc, lhs, qmc, pce_regression and sobol_sampling; collocation \
         and sparse grids cannot leave a point out)"
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

/// Why one model run failed. Its text is stored with the point, so it is complete on its own.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
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
    /// A design value does not fit its variable.
    #[error("{0}")]
    Value(String),
    /// The time grid cannot be run: empty, not finite or not increasing.
    #[error("time grid: {0}")]
    Times(String),
    /// The FMU ended the simulation before the stop time. Statistics over time need every run
    /// on the whole grid (a mean at t over the runs that reached t would be conditioned on
    /// reaching it), so such a run is a failed point.
    #[error(
        "the FMU ended the simulation at t = {time} s, before the stop time {stop} s \
         (fmi2DoStep returned fmi2Discard and fmi2Terminated is true); statistics over time \
         need every run on the whole grid, so the point counts as failed (a stop time of at \
         most {time} s keeps such runs)"
    )]
    EndedEarly {
        /// When the FMU ended it (s).
        time: f64,
        /// The study's stop time (s).
        stop: f64,
    },
    /// A quantity of interest could not be evaluated on the run.
    #[error("quantity '{name}': {error}")]
    Quantity {
        /// The quantity.
        name: String,
        /// Why.
        error: QoiError,
    },
    /// A constant-speed run of a `hunting_speed` quantity failed.
    #[error("quantity '{name}': the constant-speed run at {parameter} = {speed}: {source}")]
    SpeedRun {
        /// The quantity.
        name: String,
        /// The speed parameter.
        parameter: String,
        /// Its value in the failed run.
        speed: f64,
        /// Why the run failed.
        source: Box<PointError>,
    },
}

impl PointError {
    /// The FMI error behind this failure, if any.
    fn fmu_error(&self) -> Option<&FmuError> {
        match self {
            PointError::Fmu(e) => Some(e),
            PointError::SpeedRun { source, .. } => source.fmu_error(),
            _ => None,
        }
    }

    /// Whether a call of this run was refused because a call (of this run or of another
    /// instance of the same library) had returned fmi2Fatal: the point itself is not at fault.
    pub fn refused_after_fatal(&self) -> bool {
        matches!(self.fmu_error(), Some(FmuError::Unusable { .. }))
    }

    /// Whether a call of this run returned fmi2Fatal.
    pub fn returned_fatal(&self) -> bool {
        matches!(
            self.fmu_error(),
            Some(FmuError::Call {
                status: Status::Fatal,
                ..
            })
        )
    }
}

/// The end of [`RunError::PointsFailed`]'s message: `--allow-failures` offered only where it
/// applies (an unweighted design); a weighted design is said to need every point, so that a
/// study that already ran with the flag is not told to add it.
fn allow_failures_hint(applies: bool) -> &'static str {
    if applies {
        " (or --allow-failures to analyse the others)"
    } else {
        "; --allow-failures does not apply: this method's design is weighted (collocation, a \
         sparse grid, a nominal run), and no point can be left out of it"
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
