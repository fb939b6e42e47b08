//! What `summary.json` says of a study's run besides its statistics.

use std::collections::BTreeMap;

use crate::results::{
    FmuInfo, OutputStats, OutputSummary, RecordLayout, ScalarStats, Summary, Timing, Versions,
};
use crate::spec::Study;
use crate::uq::method::MethodSummary;

/// Facts of a run for the summary.
pub(crate) struct RunFacts {
    pub(crate) fmu: Option<FmuInfo>,
    pub(crate) model_runs: usize,
    pub(crate) runs_new: usize,
    pub(crate) runs_resumed: usize,
    pub(crate) failed: usize,
    pub(crate) wall_time: f64,
    pub(crate) threads: usize,
    pub(crate) analysis_time: f64,
}

/// The summary of `study` (its timing of the report still 0).
pub(crate) fn summary(
    study: &Study,
    facts: RunFacts,
    method: MethodSummary,
    warnings: Vec<String>,
    outputs: &[OutputStats],
    quantities: &[ScalarStats],
) -> Summary {
    Summary {
        study: study.name.clone(),
        description: study.description.clone(),
        origin: study.origin.clone(),
        method,
        seed: study.seed,
        experiment: study.experiment.clone(),
        parameters: study.parameters.clone(),
        correlation: study.correlation.clone(),
        fixed: study.fixed.clone(),
        fmu: facts.fmu,
        model_runs: facts.model_runs,
        runs_this_invocation: facts.runs_new,
        runs_resumed: facts.runs_resumed,
        failed_runs: facts.failed,
        wall_time_s: facts.wall_time,
        threads: facts.threads,
        versions: Versions::default(),
        warnings,
        outputs: outputs
            .iter()
            .map(|s| (s.name.clone(), OutputSummary::of(s)))
            .collect(),
        quantities: quantities
            .iter()
            .map(|q| (q.name.clone(), q.clone()))
            .collect::<BTreeMap<_, _>>(),
        timing: Timing {
            runs_s: facts.wall_time,
            analysis_s: facts.analysis_time,
            report_s: 0.0,
        },
        units: BTreeMap::new(),
        record_layout: RecordLayout {
            outputs: study.outputs.clone(),
            quantities: study.qoi.iter().map(|q| q.name().to_owned()).collect(),
        },
    }
}
