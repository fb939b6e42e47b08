//! What `summary.json` says of a study's run besides its statistics.

use std::collections::BTreeMap;

use crate::fmu::{Fmu, FmuError};
use crate::results::{
    FmuInfo, OutputStats, OutputSummary, RecordLayout, ScalarStats, Summary, Timing, Versions,
};
use crate::spec::{Experiment, Study};
use crate::study::run::instances::instance_name;
use crate::uq::method::MethodSummary;

/// The FMU's String calculated parameters for `summary.json` (`fmu.calculated_strings`),
/// read from an instance of their own in this process (the one writing the summary): the
/// FMU's default parameters, initialized at the start time of `experiment`. Empty when the
/// FMU declares none, and under `--isolate` (`isolated`: the FMU never runs in uq-driver's own
/// process); when that instance fails, a note says why and the field stays empty.
pub(crate) fn calculated_strings(
    fmu: &Fmu,
    experiment: &Experiment,
    isolated: bool,
) -> BTreeMap<String, String> {
    let md = fmu.description();
    if isolated || !md.variables.iter().any(|v| v.is_calculated_string()) {
        return BTreeMap::new();
    }
    let read = || -> Result<Vec<(String, String)>, FmuError> {
        let mut inst = fmu.instantiate(&instance_name(), false)?;
        inst.setup_experiment(None, experiment.start, Some(experiment.stop))?;
        inst.enter_initialization_mode()?;
        inst.exit_initialization_mode()?;
        inst.get_calculated_strings()
    };
    match read() {
        Ok(values) => values.into_iter().collect(),
        Err(e) => {
            crate::study::progress::message(&format!(
                "uq-driver: note: the FMU's String calculated parameters (for summary.json) \
                 could not be read from an instance with its default parameters: {e}"
            ));
            BTreeMap::new()
        }
    }
}

/// What `summary.json` says of the FMU a study ran (`fmu`): its file, its modelDescription's
/// identity, its SHA-256 (`sha256`) and its String calculated parameters
/// ([`calculated_strings`]).
pub(crate) fn fmu_info(
    fmu: &Fmu,
    sha256: String,
    experiment: &Experiment,
    isolated: bool,
) -> FmuInfo {
    let md = fmu.description();
    FmuInfo {
        path: fmu.path().display().to_string(),
        model_name: md.model_name.clone(),
        guid: md.guid.clone(),
        generation_tool: md.generation_tool.clone(),
        sha256,
        calculated_strings: calculated_strings(fmu, experiment, isolated),
    }
}

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
