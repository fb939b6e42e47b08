//! One study (not a suite): the method's design run on the FMU (or its own solve), the
//! statistics, the summary and the report.

use std::collections::BTreeMap;
use std::path::Path;
use std::time::Instant;

use crate::fmu::Fmu;
use crate::report::units;
use crate::report::{self, ReportError, StudyReport};
use crate::results::{OutputSplit, PointStatus, PointTable};
use crate::spec::Study;
use crate::study::analysis::{self, Analysed, AnalysisError};
use crate::study::facts::{fmu_info, summary, RunFacts};
use crate::study::outcome::{StudyResult, StudyRunError};
use crate::study::plan::ranges;
use crate::study::plan::size;
use crate::study::progress;
use crate::study::run::{self, RunError, RunOptions, RunOutcome};
use crate::study::store::{Entry, StoredRuns};
use crate::uq::distributions::{Distribution, Germ};
use crate::uq::method::{ChaosBasis, Design, Draws, Evaluation, Intrusive, Sampling};
use crate::uq::random_inputs::RandomInputs;
use crate::uq::surrogate::{NamedChaos, SurrogateFile};

/// Runs a study that is not a suite.
pub(crate) fn run_single(
    study: &Study,
    out_dir: &Path,
    opts: &RunOptions,
) -> Result<StudyResult, StudyRunError> {
    std::fs::create_dir_all(out_dir).map_err(|source| ReportError::Io {
        path: out_dir.to_path_buf(),
        source,
    })?;
    match study.method().evaluation() {
        Evaluation::Intrusive(method) => solve(study, method, out_dir, opts),
        Evaluation::Adaptive(method) => {
            crate::study::adaptive::run_adaptive(study, method, out_dir, opts)
        }
        Evaluation::Sampling(method) => {
            let fmu = run::open_fmu(study)?;
            ranges::check_supports(study, &fmu).map_err(RunError::from)?;
            let design = method.design(&study.random_inputs(), study.seed)?;
            if method.planned_runs_for(&study.parameters).is_none() {
                // Only the design knew its size: check it before it runs.
                size::check_runs(study, design.len(), opts)?;
            }
            progress::message(&format!(
                "{}: {} with {}",
                study.name,
                study.method().label(study.parameters.len()),
                match design.len() {
                    1 => "1 model run".to_owned(),
                    n => format!("{n} model runs"),
                }
            ));
            let early = ranges::range_warnings(study, &fmu, &design);
            for w in &early {
                progress::message(&format!("uq-driver: warning: {w}"));
            }
            let outcome = run::run_points(study, &fmu, &design, out_dir, opts)?;
            let noted = outcome.warnings.len();
            let mut result = finish(study, method, &fmu, &design, outcome, out_dir, opts)?;
            // finish puts the same range warnings first in the summary's list, then those the
            // runs printed.
            result.warnings_shown = early.len() + noted;
            Ok(result)
        }
    }
}

/// Statistics and files of a study whose points have all been run (`outcome.records`).
pub(crate) fn finish(
    study: &Study,
    method: &dyn Sampling,
    fmu: &Fmu,
    design: &Design,
    outcome: RunOutcome,
    out_dir: &Path,
    opts: &RunOptions,
) -> Result<StudyResult, StudyRunError> {
    let entries = outcome.runs.entries();
    let done = entries.iter().filter(|r| r.is_some()).count();
    let failed = run::check_failures(
        study,
        design,
        entries,
        opts.allow_failures(study),
        opts.points.as_deref(),
    )
    .map_err(|e| with_points_csv(study, design, entries, out_dir, e.into()))?;
    if done < design.len() {
        return Err(StudyRunError::Incomplete {
            done,
            total: design.len(),
        });
    }
    let started = Instant::now();
    let md = fmu.description();
    let units = units::study_units(study, Some(md));
    let (analysed, splits, mut warnings) = analyse(study, method, design, &outcome.runs, &units)
        .map_err(|e| with_points_csv(study, design, entries, out_dir, e.into()))?;
    let (mut outputs, mut quantities) = (analysed.outputs, analysed.quantities);
    units::annotate(&units, &mut outputs, &mut quantities);
    units::describe_signals(&mut quantities, &study.qoi, md);
    let analysis_time = started.elapsed().as_secs_f64();
    let facts = RunFacts {
        fmu: Some(fmu_info(
            fmu,
            outcome.fmu_sha256.clone(),
            &study.experiment,
            opts.isolate.is_some(),
        )),
        model_runs: design.len(),
        runs_new: outcome.n_new,
        runs_resumed: outcome.n_resumed,
        failed,
        wall_time: outcome.wall_time,
        threads: outcome.threads,
        analysis_time,
    };
    let method_summary = study.method().summary(study.parameters.len());
    warnings.splice(0..0, design.warnings.iter().cloned());
    // What the runs noted (a failed fmi2Reset, the reset self-check), printed as they happened.
    warnings.splice(0..0, outcome.warnings.iter().cloned());
    warnings.splice(0..0, ranges::range_warnings(study, fmu, design));
    let mut summary = summary(
        study,
        facts,
        method_summary,
        warnings,
        &outputs,
        &quantities,
    );
    write_surrogate(
        study,
        design.germ,
        &design.inputs,
        &analysed.output_chaos,
        &analysed.quantity_chaos,
        out_dir,
    )?;
    summary.units = units;
    let points = point_table(study, design, entries);
    let extra = report::nested::write(out_dir, &quantities, &splits, !opts.no_report)?;
    summary.timing.report_s = report::study::write(
        out_dir,
        &StudyReport {
            summary: &summary,
            outputs: &outputs,
            quantities: &quantities,
            qoi: &study.qoi,
            points: Some(&points),
            extra: &extra,
            plots: !opts.no_report,
        },
    )?;
    Ok(StudyResult {
        summary,
        outputs,
        quantities,
        warnings_shown: 0,
    })
}

/// The statistics of every output and quantity; a nested study adds the split of each output
/// over time and its notes.
fn analyse(
    study: &Study,
    method: &dyn Sampling,
    design: &Design,
    records: &StoredRuns,
    units: &BTreeMap<String, String>,
) -> Result<(Analysed, Vec<OutputSplit>, Vec<String>), AnalysisError> {
    Ok(match study.method.nested() {
        Some(nested) => {
            let n = crate::study::analysis::nested::analyse(study, nested, design, records)?;
            (n.analysed, n.splits, n.warnings)
        }
        None => {
            let mut analysed = analysis::analyse_runs(study, method, design, records)?;
            analysis::guide_tails(&mut analysed, &design.inputs, design.germ);
            // Inputs with an Askey family of their own that the design maps through the normal.
            let askey_hint =
                design.germ == Germ::Normal && ChaosBasis::some_own_family(&design.inputs);
            let mut warnings = analysis::chaos_gap_warnings(&analysed, askey_hint, units);
            warnings.extend(analysis::chaos_error_warnings(
                &analysed,
                method.no_error_estimate(),
            ));
            warnings.extend(correlated_sobol_warning(study, &analysed));
            warnings.extend(correlated_chaos_warning(study, &analysed));
            (analysed, Vec::new(), warnings)
        }
    })
}

/// With correlated inputs the Sobol' indices are those of the independent germs in study
/// order (the Cholesky factor of the copula): the index of a parameter counts only its part
/// independent of the parameters listed before it, so it changes with their order (S of
/// one input was 0.0006 in file order and 0.116 listed first). Said where indices are given.
fn correlated_sobol_warning(study: &Study, a: &Analysed) -> Option<String> {
    let correlated = study.correlation.is_some();
    let indices = a.outputs.iter().any(|o| o.sobol.is_some())
        || a.quantities.iter().any(|q| q.sobol.is_some());
    let given_data = a
        .outputs
        .iter()
        .filter_map(|o| o.sobol.as_ref())
        .all(|s| s.given_data)
        && a.quantities
            .iter()
            .filter_map(|q| q.sobol.as_ref())
            .all(|s| s.estimator.is_some());
    if correlated && indices && given_data {
        // Estimated from the runs: indices of the physical parameters, whatever their order.
        return Some(
            "the inputs are correlated: the first-order Sobol' indices estimated from the runs \
             are those of the physical parameters, Var(E[Y | X_i]) / Var(Y): each includes what \
             the parameter carries of the parameters it is correlated with, so they may add up \
             to more than 1 and do not depend on the order of [[parameters]]"
                .into(),
        );
    }
    (correlated && indices).then(|| {
        let order: Vec<&str> = study.parameters.iter().map(|p| p.name.as_str()).collect();
        format!(
            "the inputs are correlated: the Sobol' indices are those of the independent germs \
             in the order of [[parameters]] ({}): each parameter's index counts only its part \
             independent of the parameters listed before it, and changes with that order; list \
             a parameter first to see its whole share (its first-order index then includes what \
             it carries of the others)",
            order.join(", ")
        )
    })
}

/// A chaos of correlated inputs that are not all normal expands the model composed with the
/// Gaussian copula's map (each input `F⁻¹(Φ(·))` of a mix of germs), which can be far from a
/// polynomial although the model is smooth; its own error estimate then understates its
/// error (a lognormal and a gamma input at ρ = −0.5, LARS on 400 runs: Std +7.7 %
/// with a leave-one-out error of 0.55 %). Said where a chaos gives the statistics.
fn correlated_chaos_warning(study: &Study, a: &Analysed) -> Option<String> {
    let correlation = study.correlation.as_ref()?;
    let chaos = a.outputs.iter().any(|o| o.draws == Draws::Chaos)
        || a.quantities.iter().any(|q| q.draws == Draws::Chaos);
    let non_normal: Vec<&str> = study
        .parameters
        .iter()
        .zip(&correlation.correlated)
        .filter(|(p, &c)| c && !matches!(p.distribution, Distribution::Normal { .. }))
        .map(|(p, _)| p.name.as_str())
        .collect();
    (chaos && !non_normal.is_empty()).then(|| {
        format!(
            "correlated inputs that are not normal ({}): the chaos expands the model through \
             the Gaussian copula's transform, which can be far from a polynomial; its own \
             truncation-error estimate can then understate the error several-fold, so check \
             the mean and Std with a sampling method (`lhs`, `qmc`)",
            non_normal.join(", ")
        )
    })
}

/// An intrusive study: one solve, then statistics and files.
fn solve(
    study: &Study,
    method: &dyn Intrusive,
    out_dir: &Path,
    opts: &RunOptions,
) -> Result<StudyResult, StudyRunError> {
    let started = Instant::now();
    let times = study.times();
    let solution = method.solve(&study.problem(&times))?;
    let wall_time = started.elapsed().as_secs_f64();
    let started = Instant::now();
    let outputs = analysis::analyse_solution(study, &solution)?;
    let chaos: Vec<NamedChaos> = study
        .outputs
        .iter()
        .zip(&solution.outputs)
        .filter_map(|(name, e)| {
            e.chaos.as_ref().map(|pce| NamedChaos {
                name: name.clone(),
                times: Some(times.clone()),
                pce: pce.clone(),
                error: e.chaos_error.clone(),
            })
        })
        .collect();
    write_surrogate(
        study,
        Germ::Normal,
        &study.random_inputs(),
        &chaos,
        &[],
        out_dir,
    )?;
    let analysis_time = started.elapsed().as_secs_f64();
    let mut method_summary = study.method().summary(study.parameters.len());
    method_summary.details.extend(solution.details);
    let facts = RunFacts {
        fmu: None,
        model_runs: 1,
        runs_new: 1,
        runs_resumed: 0,
        failed: 0,
        wall_time,
        threads: 1,
        analysis_time,
    };
    let mut summary = summary(
        study,
        facts,
        method_summary,
        solution.warnings,
        &outputs,
        &[],
    );
    summary.units = units::study_units(study, None);
    // The page shows the system that was solved.
    let system: Vec<report::Section> = study
        .system
        .iter()
        .map(report::study::system_section)
        .collect();
    summary.timing.report_s = report::study::write(
        out_dir,
        &StudyReport {
            summary: &summary,
            outputs: &outputs,
            quantities: &[],
            qoi: &study.qoi,
            points: None,
            extra: &system,
            plots: !opts.no_report,
        },
    )?;
    Ok(StudyResult {
        summary,
        outputs,
        quantities: Vec::new(),
        warnings_shown: 0,
    })
}

/// Writes `surrogate.json` when the method gave a chaos (and removes a stale one otherwise).
fn write_surrogate(
    study: &Study,
    germ: Germ,
    inputs: &RandomInputs,
    outputs: &[NamedChaos],
    quantities: &[NamedChaos],
    out_dir: &Path,
) -> Result<(), ReportError> {
    let path = out_dir.join("surrogate.json");
    if outputs.is_empty() && quantities.is_empty() {
        let _ = std::fs::remove_file(&path);
        return Ok(());
    }
    let file = SurrogateFile::new(
        &study.name,
        study.method().kind(),
        germ,
        inputs,
        outputs,
        quantities,
    );
    let text = serde_json::to_string(&file).expect("surrogates serialize");
    crate::report::write_bytes(&path, text.as_bytes())
}

/// The design with the status of each point.
/// `error`, after writing `points.csv` (every point's status and message) when points failed:
/// a study that stops on its failures, or has too few successful runs to analyse, still says
/// what happened to each point (before, only the store held the messages).
fn with_points_csv(
    study: &Study,
    design: &Design,
    records: &[Option<Entry>],
    out_dir: &Path,
    error: StudyRunError,
) -> StudyRunError {
    if !records.iter().any(|r| matches!(r, Some(Entry::Failed(_)))) {
        return error;
    }
    let path = out_dir.join("points.csv");
    match report::study::write_points_csv(&path, &point_table(study, design, records)) {
        Ok(()) => progress::message(&format!(
            "uq-driver: note: the status and message of every point: {}",
            path.display()
        )),
        Err(e) => progress::message(&format!("uq-driver: warning: {e}")),
    }
    error
}

fn point_table(study: &Study, design: &Design, records: &[Option<Entry>]) -> PointTable {
    PointTable {
        names: study.parameters.iter().map(|p| p.name.clone()).collect(),
        weights: design.weights.clone(),
        values: design.values.clone(),
        status: records
            .iter()
            .map(|r| match r {
                Some(Entry::Ok(_)) => PointStatus::Ok,
                Some(Entry::Failed(m)) => PointStatus::Failed(m.clone()),
                None => PointStatus::Missing,
            })
            .collect(),
    }
}
