//! What running a study returns, and how it fails.

use crate::report::ReportError;
use crate::results::{OutputStats, ScalarStats, SuiteSummary, Summary};
use crate::study::analysis::AnalysisError;
use crate::study::plan::size::SizeError;
use crate::study::run::RunError;
use crate::uq::method::MethodError;

/// Errors of a whole study run.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum StudyRunError {
    /// The study is not valid (its public fields were changed after [`Study::parse`]).
    ///
    /// [`Study::parse`]: crate::spec::Study::parse
    #[error(transparent)]
    Study(#[from] crate::spec::StudyError),
    /// Running the points failed.
    #[error(transparent)]
    Run(#[from] RunError),
    /// The study is too large to start (or to start without `--yes`).
    #[error(transparent)]
    Size(#[from] SizeError),
    /// An intrusive method failed.
    #[error(transparent)]
    Method(#[from] MethodError),
    /// The statistics could not be computed.
    #[error(transparent)]
    Analysis(#[from] AnalysisError),
    /// Writing results failed.
    #[error(transparent)]
    Report(#[from] ReportError),
    /// The study stopped before every point was run (see `max_new_points`).
    #[error(
        "stopped after {done} of {total} points; run again with the same --out (output folder) \
         to resume"
    )]
    Incomplete {
        /// Points finished.
        done: usize,
        /// Points of the design.
        total: usize,
    },
    /// An adaptive study (a reliability method) stopped before it finished (see
    /// `max_new_points`): its runs are kept and replayed by the next run into the folder.
    #[error(
        "stopped after {runs} model runs ({new} new in this run) before the method finished; \
         run again with the same --out (output folder) to resume"
    )]
    Stopped {
        /// Runs in the results store.
        runs: usize,
        /// Runs made by this invocation.
        new: usize,
    },
}

/// What a finished study returns.
#[derive(Clone, Debug)]
#[non_exhaustive]
pub struct StudyResult {
    /// The summary written to `summary.json`.
    pub summary: Summary,
    /// Statistics per output.
    pub outputs: Vec<OutputStats>,
    /// Statistics per scalar quantity of interest.
    pub quantities: Vec<ScalarStats>,
    /// How many of `summary.warnings`, from the first, were already printed before the runs
    /// (the declared-range warnings), so that `run` does not print them again at the end.
    pub warnings_shown: usize,
}

/// What a finished suite returns.
#[derive(Clone, Debug)]
#[non_exhaustive]
pub struct SuiteResult {
    /// The summary written to the suite's `summary.json`.
    pub summary: SuiteSummary,
    /// Each variant's result, in file order.
    pub variants: Vec<StudyResult>,
}

/// A study's or a suite's result.
#[derive(Clone, Debug)]
#[non_exhaustive]
pub enum Outcome {
    /// One study.
    Study(Box<StudyResult>),
    /// A suite of variants.
    Suite(SuiteResult),
}
