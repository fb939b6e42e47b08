//! Suites: a study with `[[variants]]` runs each variant into `DIR/<variant>/` (each one
//! resumable on its own) and then compares them against the reference variant; the pages and
//! plots of the comparison are written by [`crate::report::suite`].

use std::path::Path;

use crate::report::{self, suite::VariantResults};
use crate::results::{SuiteSummary, VariantOutput, VariantSummary};
use crate::spec::{Study, Suite};
use crate::study::outcome::{StudyResult, StudyRunError, SuiteResult};
use crate::study::run::RunOptions;
use crate::study::single::run_single;

/// Largest |a − b| over paired entries.
pub fn max_abs_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// Runs every variant of `suite` and writes the comparison into `out_dir`.
pub fn run(
    study: &Study,
    suite: &Suite,
    out_dir: &Path,
    opts: &RunOptions,
) -> Result<SuiteResult, StudyRunError> {
    let mut results = Vec::new();
    for v in &suite.variants {
        crate::study::progress::message(&format!(
            "{}: variant {} ({}) …",
            study.name,
            v.name,
            v.method().label(v.parameters.len())
        ));
        let folder = out_dir.join(&v.name);
        out_file::sub_folder(&folder).map_err(|source| report::ReportError::Io {
            path: folder.clone(),
            source,
        })?;
        results.push(run_single(v, &folder, opts)?);
    }
    let summary = summarize(study, suite, &results);
    std::fs::create_dir_all(out_dir).map_err(|source| report::ReportError::Io {
        path: out_dir.to_path_buf(),
        source,
    })?;
    let variants: Vec<VariantResults> = results
        .iter()
        .map(|r| VariantResults {
            summary: &r.summary,
            outputs: &r.outputs,
            quantities: &r.quantities,
        })
        .collect();
    report::suite::write(out_dir, &summary, &variants)?;
    Ok(SuiteResult {
        summary,
        variants: results,
    })
}

/// The suite's summary: every variant against the reference.
fn summarize(study: &Study, suite: &Suite, results: &[StudyResult]) -> SuiteSummary {
    let reference = &results[suite.reference];
    let variants = suite
        .variants
        .iter()
        .zip(results)
        .map(|(v, r)| VariantSummary {
            name: v.name.clone(),
            method: v.method().label(v.parameters.len()),
            model_runs: r.summary.model_runs,
            wall_time_s: r.summary.wall_time_s,
            folder: v.name.clone(),
            outputs: r
                .outputs
                .iter()
                .map(|s| {
                    let rs = reference.outputs.iter().find(|x| x.name == s.name);
                    VariantOutput {
                        name: s.name.clone(),
                        max_abs_mean_diff_vs_reference: max_abs_diff(
                            &s.mean,
                            rs.map_or(&[][..], |x| &x.mean),
                        ),
                        max_abs_std_diff_vs_reference: max_abs_diff(
                            &s.std,
                            rs.map_or(&[][..], |x| &x.std),
                        ),
                    }
                })
                .collect(),
            quantities: r.quantities.clone(),
        })
        .collect();
    SuiteSummary {
        suite: study.name.clone(),
        description: study.description.clone(),
        origin: study.origin.clone(),
        reference: suite.variants[suite.reference].name.clone(),
        variants,
        paper: suite.paper.clone(),
        wall_time_s: results.iter().map(|r| r.summary.wall_time_s).sum(),
    }
}
