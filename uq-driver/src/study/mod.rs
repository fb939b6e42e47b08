//! Running a study: the parallel runner, the resumable results store, the statistics and
//! the files in the output folder.
//!
//! [`run_study`] is the whole pipeline: study → the method's design → runs (parallel,
//! resumable) → the method's estimates → statistics → report. An intrusive method solves its
//! own system instead of running an FMU. A suite (a study with `[[variants]]`) runs each
//! variant into a sub-folder and then writes a comparison.

#![forbid(unsafe_code)]

mod adaptive;
pub(crate) mod analysis;
mod facts;
mod outcome;
pub(crate) mod plan;
pub(crate) mod progress;
pub(crate) mod run;
pub(crate) mod shard;
mod single;
pub(crate) mod store;
pub(crate) mod suite;

use std::path::Path;

pub use analysis::AnalysisError;
pub use outcome::{Outcome, StudyResult, StudyRunError, SuiteResult};
pub use plan::interface::{InterfaceError, VariableProblem};
pub use plan::size::SizeError;
pub use progress::{set_message_sink, Sink};
pub use run::guard::install_process_guards;
pub use run::{
    simulate, simulate_with, FailedPoint, PointError, RunControl, RunError, RunOptions, Simulation,
};
pub use store::lock::LockError;
pub use store::StoreError;

use crate::spec::Study;

/// Runs a study into `out_dir` (resuming what a previous run there finished). A suite runs
/// every variant into `out_dir/<variant>/` and writes the comparison into `out_dir`.
///
/// Nothing is allocated, run or written (`out_dir` is not even created) before the study
/// passes [`Study::check`] (the fields of a [`Study`] are public: they are checked again) and
/// the size check: too large to run, it is refused; large, it needs `opts.yes`. An empty
/// `out_dir` is refused ([`RunError::NoOutDir`]), as are options that do not fit together
/// ([`RunError::Options`]) and a folder that cannot be created or written
/// ([`RunError::OutDirNotWritable`]; the test makes a hidden folder in it, or in the
/// nearest existing folder above it, and removes it at once).
pub fn run_study(
    study: &Study,
    out_dir: &Path,
    opts: &RunOptions,
) -> Result<Outcome, StudyRunError> {
    study.check()?;
    if out_dir.as_os_str().is_empty() {
        return Err(RunError::NoOutDir.into());
    }
    opts.check()?;
    run::check_out_dir(out_dir)?;
    plan::size::check(study, out_dir, opts)?;
    run::prepare_out_dir(out_dir)?;
    match &study.suite {
        Some(s) => suite::run(study, s, out_dir, opts).map(Outcome::Suite),
        None => single::run_single(study, out_dir, opts).map(|r| Outcome::Study(Box::new(r))),
    }
}
