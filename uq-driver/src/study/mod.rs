//! Study files, the parallel runner, the resumable results store and the result writers.
//!
//! [`run_study`] is the whole pipeline: study → design → runs (parallel, resumable) →
//! statistics → files in the output folder. SGM studies solve their Galerkin system instead
//! of running an FMU; suites (studies with `[[variants]]`) run each variant into a
//! sub-folder and then write a comparison ([`compare`]).

pub mod analysis;
pub mod compare;
pub mod design;
pub mod output;
pub mod runner;
pub mod sgm;
pub mod shard;
pub mod spec;
pub mod store;

use std::path::Path;
use std::time::Instant;

pub use design::Design;
pub use runner::{RunError, RunOptions, RunOutcome};
pub use spec::{MethodKind, Study, StudyError, BUILTINS};

use crate::fmu::Fmu;
use store::Record;

/// Errors of a whole study run.
#[derive(Debug, thiserror::Error)]
pub enum StudyRunError {
    /// Running the points failed.
    #[error(transparent)]
    Run(#[from] RunError),
    /// Writing results failed.
    #[error(transparent)]
    Report(#[from] crate::report::ReportError),
    /// A variant could not be built.
    #[error(transparent)]
    Study(#[from] StudyError),
    /// The statistics could not be computed.
    #[error("analysis: {0}")]
    Analysis(String),
    /// The study stopped before every point was run (see `max_new_points`).
    #[error("stopped after {done} of {total} points; run again with the same --out to resume")]
    Incomplete {
        /// Points finished.
        done: usize,
        /// Points of the design.
        total: usize,
    },
}

/// What a finished study returns.
#[derive(Debug)]
pub struct StudyResult {
    /// The summary written to `summary.json`.
    pub summary: serde_json::Value,
    /// Statistics per output.
    pub stats: Vec<analysis::OutputStats>,
    /// Statistics per scalar quantity of interest.
    pub scalars: Vec<analysis::ScalarStats>,
    /// Model runs (points; 1 for SGM).
    pub model_runs: usize,
    /// Failed points (MC/LHS with failures allowed).
    pub n_failed: usize,
    /// Warnings for the user.
    pub warnings: Vec<String>,
    /// Wall time (s).
    pub wall_time: f64,
}

fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> crate::report::ReportError + '_ {
    move |source| crate::report::ReportError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Runs a study into `out_dir` (resuming what a previous run there finished). A suite runs
/// every variant into `out_dir/<variant>/` and writes the comparison into `out_dir`.
pub fn run_study(
    study: &Study,
    out_dir: &Path,
    opts: &RunOptions,
) -> Result<StudyResult, StudyRunError> {
    std::fs::create_dir_all(out_dir).map_err(io_err(out_dir))?;
    if study.is_suite() {
        return compare::run_suite(study, out_dir, opts);
    }
    if study.file.method.kind == MethodKind::Sgm {
        return run_sgm(study, out_dir, opts);
    }
    let fmu = Fmu::open(&study.fmu_path).map_err(RunError::from)?;
    let design = Design::build(study).map_err(|e| RunError::Design(e.to_string()))?;
    let outcome = runner::run_points(study, &fmu, &design, out_dir, opts)?;
    finish(study, &fmu, design, outcome, out_dir, opts)
}

/// Statistics and files of a study whose points have all been run (`outcome.records`).
pub(crate) fn finish(
    study: &Study,
    fmu: &Fmu,
    design: Design,
    outcome: RunOutcome,
    out_dir: &Path,
    opts: &RunOptions,
) -> Result<StudyResult, StudyRunError> {
    let done = outcome.records.iter().filter(|r| r.is_some()).count();
    let allow = opts.allow_failures || study.file.analysis.allow_failures;
    let n_failed = runner::check_failures(study, &design, &outcome.records, allow)?;
    if done < design.len() {
        return Err(StudyRunError::Incomplete {
            done,
            total: design.len(),
        });
    }
    let stats =
        analysis::analyse(study, &design, &outcome.records).map_err(StudyRunError::Analysis)?;
    let scalars = analysis::analyse_scalars(study, &design, &outcome.records)
        .map_err(StudyRunError::Analysis)?;
    let md = fmu.description();
    let m = &study.file.method;
    let ctx = output::RunContext {
        model_runs: design.len(),
        runs_new: outcome.n_new,
        runs_resumed: outcome.n_resumed,
        failed: n_failed,
        wall_time: outcome.wall_time,
        threads: outcome.threads,
        fmu: serde_json::json!({
            "path": study.fmu_path.display().to_string(),
            "model_name": md.model_name,
            "guid": md.guid,
            "generation_tool": md.generation_tool,
            "sha256": outcome.fmu_sha256,
        }),
        method: serde_json::json!({
            "kind": m.kind.as_str(),
            "samples": m.samples,
            "nodes_per_dimension": m.nodes,
            "order": (m.kind == MethodKind::Scm).then_some(design.order),
        }),
        warnings: design.warnings.clone(),
        points_csv: Some(points_csv(study, &design, &outcome.records)),
        density_source: if m.kind == MethodKind::Scm {
            "kernel density of a large sample of the chaos surrogate"
        } else {
            "kernel density of the runs"
        },
    };
    let summary = output::write_all(out_dir, study, &ctx, &stats, &scalars)?;
    Ok(StudyResult {
        summary,
        stats,
        scalars,
        model_runs: design.len(),
        n_failed,
        warnings: design.warnings,
        wall_time: outcome.wall_time,
    })
}

/// `points.csv`: the design with the status of each point.
fn points_csv(study: &Study, design: &Design, records: &[Option<Record>]) -> String {
    let mut lines = String::from("index");
    if design.weights.is_some() {
        lines.push_str(",weight");
    }
    for p in &study.parameters {
        lines.push(',');
        lines.push_str(&p.name);
    }
    lines.push_str(",status\n");
    for (i, vals) in design.values.iter().enumerate() {
        lines.push_str(&i.to_string());
        if let Some(w) = &design.weights {
            lines.push_str(&format!(",{}", w[i]));
        }
        for v in vals {
            lines.push_str(&format!(",{v}"));
        }
        let status = match &records[i] {
            Some(Record::Ok(_)) => "ok".to_string(),
            Some(Record::Failed(m)) => format!("\"failed: {}\"", m.replace('"', "'")),
            None => "missing".into(),
        };
        lines.push_str(&format!(",{status}\n"));
    }
    lines
}

fn run_sgm(
    study: &Study,
    out_dir: &Path,
    _opts: &RunOptions,
) -> Result<StudyResult, StudyRunError> {
    let started = Instant::now();
    let (gs, coeffs) = sgm::solve(study).map_err(StudyRunError::Analysis)?;
    let wall_time = started.elapsed().as_secs_f64();
    let definiteness = gs.check_definiteness();
    let stats: Vec<analysis::OutputStats> = study
        .file
        .outputs
        .variables
        .iter()
        .zip(coeffs)
        .map(|(name, c)| analysis::stats_from_pce(study, name, &gs.pce(c)))
        .collect();
    let m = &study.file.method;
    let ctx = output::RunContext {
        model_runs: 1,
        runs_new: 1,
        runs_resumed: 0,
        failed: 0,
        wall_time,
        threads: 1,
        fmu: serde_json::Value::Null,
        method: serde_json::json!({
            "kind": "sgm",
            "order": m.order,
            "terms": gs.basis.len(),
            "galerkin_size": gs.mm.nrows(),
            "definiteness": definiteness,
        }),
        warnings: definiteness.warnings.clone(),
        points_csv: None,
        density_source: "kernel density of a large sample of the Galerkin chaos",
    };
    let summary = output::write_all(out_dir, study, &ctx, &stats, &[])?;
    Ok(StudyResult {
        summary,
        stats,
        scalars: Vec::new(),
        model_runs: 1,
        n_failed: 0,
        warnings: definiteness.warnings,
        wall_time,
    })
}
