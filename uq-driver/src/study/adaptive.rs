//! One study of an adaptive method (the reliability methods, Morris screening): the method
//! asks for batches of points, each run in parallel by the study's runner (the same
//! runner, isolation, failure handling and progress as a design) and stored in the results
//! store under its run index; then the probabilities or screening measures, the summary and
//! the report.
//!
//! # Resume
//!
//! The results store's records are indexed by run (its manifest holds the most runs the
//! method may make), and beside them `store/points/` keeps the standard normal point of
//! every run asked for, written before the run starts. A study run again into the folder
//! calls the method again with the same settings and seed: every run found in the store is
//! answered from it (its point checked bit for bit against the one asked for now; a mismatch
//! stops the study), the others are run. The method being a deterministic function of its
//! settings, its seed and the values it receives, the resumed study gives the numbers an
//! uninterrupted one would, on any number of threads. A failed run is answered as failed
//! (FORM then stops again with the same error) unless `--retry-failed` runs it again, which
//! it does only for a run in the last batch the method asked for: once the method has gone
//! on past a failure (a trial step of FORM's line search shortened, a subset level seeded
//! without it), the runs it asked for next depend on that failure, and a value now would
//! send it away from the stored runs. Those failures are kept, with a warning.
//!
//! # Values of the quantities
//!
//! Each run records the study's outputs and quantities as any study does; the method
//! receives every quantity's value. A `hunting_speed` whose disturbance dies out even at the
//! top of the bracket counts as the bracket's `high` (the speed is above it), one that keeps
//! hunting at its bottom as `low`: the side of a limit inside the bracket is right, the
//! value is a bound. A quantity without a value (a `critical_speed` not found) fails the run
//! for the methods that use it.

use std::collections::BTreeSet;
use std::path::Path;
use std::time::Instant;

use crate::fmu::Fmu;
use crate::qoi::evaluate::Code;
use crate::qoi::QoiSpec;
use crate::report::{self, units, StudyReport};
use crate::results::numbers::count;
use crate::results::{LimitProbability, MorrisScreening, PointStatus, PointTable, ScalarStats};
use crate::spec::Study;
use crate::study::facts::{fmu_info, summary, RunFacts};
use crate::study::outcome::{StudyResult, StudyRunError};
use crate::study::plan::{fingerprint, ranges};
use crate::study::progress;
use crate::study::run::{self, Job, RunError, RunOptions, Session};
use crate::study::store::{Entry, Manifest, Record, Store, StoreError};
use crate::uq::distributions::Germ;
use crate::uq::method::adaptive::{AdaptiveResult, BatchModel, Target};
use crate::uq::method::{AdaptiveMethod, MethodError};
use crate::uq::random_inputs::RandomInputs;
use crate::uq::reliability::{Abort, Outcome, Point};

/// Runs an adaptive study into `out_dir`.
pub(crate) fn run_adaptive(
    study: &Study,
    method: AdaptiveMethod,
    out_dir: &Path,
    opts: &RunOptions,
) -> Result<StudyResult, StudyRunError> {
    let fmu = run::open_fmu(study)?;
    ranges::check_supports(study, &fmu).map_err(RunError::from)?;
    let inputs = study.random_inputs();
    let d = inputs.len();
    let quantities: Vec<(String, &QoiSpec)> = study.scalar_quantities().collect();
    let names: Vec<String> = quantities.iter().map(|(n, _)| n.clone()).collect();
    let targets = study
        .adaptive_targets()
        .map_err(|e| StudyRunError::Method(MethodError::Invalid(e)))?;
    let capacity = method.0.max_runs(d, targets.len()).max(1);
    progress::message(&format!(
        "{}: {}{}, at most {} model runs",
        study.name,
        study.method().label(d),
        match targets.len() {
            0 => String::new(),
            1 => " for 1 probability".to_owned(),
            n => format!(" for {n} probabilities"),
        },
        capacity
    ));
    let manifest = fingerprint::manifest_for(study, &fmu, capacity)?;
    let session = Session::open(study, &fmu, manifest.clone(), out_dir, opts, false)?;
    let points_manifest = Manifest {
        n_values: d,
        ..manifest
    };
    let points_dir = out_dir.join("store").join("points");
    let (points, stored) =
        Store::open(&points_dir, &points_manifest, false).map_err(RunError::Store)?;
    let stored_u = stored
        .into_iter()
        .map(|r| match r {
            Some(Record::Ok(u)) => Some(u),
            _ => None,
        })
        .collect();
    let base = study.outputs.len() * study.times().len();
    let mut model = StudyModel {
        session,
        fmu: &fmu,
        inputs: &inputs,
        points,
        stored_u,
        quantities: &quantities,
        base,
        retry_failed: opts.retry_failed,
        retried: BTreeSet::new(),
        kept_failed: BTreeSet::new(),
        resumed: BTreeSet::new(),
        stopped: false,
        error: None,
        capacity,
    };
    let result = method
        .0
        .run(&mut model, &inputs, &targets, &names, study.seed);
    let wall_time = model.session.opened.elapsed().as_secs_f64();
    let result = match result {
        Ok(r) => r,
        Err(e) => {
            if let Some(note) = model.kept_failed_note() {
                progress::message(&format!("uq-driver: note: {note}"));
            }
            if let Some(err) = model.error.take() {
                return Err(err.into());
            }
            let runs = model.runs_done();
            if model.stopped {
                return Err(StudyRunError::Stopped {
                    runs,
                    new: model.session.new,
                });
            }
            let table = model.point_table(study, runs);
            if table
                .status
                .iter()
                .any(|s| matches!(s, PointStatus::Failed(_)))
            {
                let path = out_dir.join("points.csv");
                match report::study::write_points_csv(&path, &table) {
                    Ok(()) => progress::message(&format!(
                        "uq-driver: note: the status and message of every run: {}",
                        path.display()
                    )),
                    Err(w) => progress::message(&format!("uq-driver: warning: {w}")),
                }
            }
            return Err(StudyRunError::Method(e));
        }
    };
    finish(
        study, &fmu, model, result, &targets, wall_time, out_dir, opts,
    )
}

/// The statistics, summary and report of a finished adaptive study.
#[allow(clippy::too_many_arguments)]
fn finish(
    study: &Study,
    fmu: &Fmu,
    model: StudyModel,
    result: AdaptiveResult,
    targets: &[Target],
    wall_time: f64,
    out_dir: &Path,
    opts: &RunOptions,
) -> Result<StudyResult, StudyRunError> {
    let started = Instant::now();
    let runs = result.runs as usize;
    let table = model.point_table(study, runs);
    let failed = table
        .status
        .iter()
        .filter(|s| matches!(s, PointStatus::Failed(_)))
        .count();
    let names: Vec<&str> = study.parameters.iter().map(|p| p.name.as_str()).collect();
    let mut quantities = Vec::new();
    for (k, (name, q)) in model.quantities.iter().enumerate() {
        let values = model.quantity_values(k, runs)?;
        let mut stats = adaptive_stats(name, q, &values);
        let limits: Vec<LimitProbability> = result
            .limits
            .iter()
            .filter(|l| l.target.quantity == k)
            .map(|l| LimitProbability::of(l, &names))
            .collect();
        if !limits.is_empty() {
            stats.reliability = Some(limits);
        }
        stats.morris = result
            .screening
            .iter()
            .find(|s| s.quantity == k)
            .map(|s| MorrisScreening::of(s, &names));
        quantities.push(stats);
    }
    let md = fmu.description();
    let units = units::study_units(study, Some(md));
    units::annotate(&units, &mut [], &mut quantities);
    units::describe_signals(&mut quantities, &study.qoi, md);
    let mut warnings: Vec<String> = result
        .limits
        .iter()
        .flat_map(|l| l.warnings.iter().cloned())
        .collect();
    for s in &result.screening {
        warnings.extend(s.morris.warnings.iter().map(|w| format!("{}: {w}", s.name)));
    }
    warnings.extend(model.kept_failed_note());
    let resumed = model.resumed.len();
    let (runs_store, _lock, notes) = model.session.into_warnings();
    drop(runs_store);
    warnings.splice(0..0, notes);
    let fmu_sha256 = fingerprint::sha256_file(fmu.path()).unwrap_or_default();
    let facts = RunFacts {
        fmu: Some(fmu_info(
            fmu,
            fmu_sha256,
            &study.experiment,
            opts.isolate.is_some(),
        )),
        model_runs: runs,
        runs_new: runs.saturating_sub(resumed),
        runs_resumed: resumed,
        failed,
        wall_time,
        threads: opts.threads.unwrap_or_else(rayon::current_num_threads),
        analysis_time: started.elapsed().as_secs_f64(),
    };
    let mut method_summary = study.method().summary(study.parameters.len());
    method_summary
        .details
        .insert("probabilities".into(), serde_json::json!(targets.len()));
    method_summary
        .details
        .insert("max_runs".into(), serde_json::json!(model.capacity));
    let mut summary = summary(study, facts, method_summary, warnings, &[], &quantities);
    summary.units = units;
    summary.timing.report_s = report::study::write(
        out_dir,
        &StudyReport {
            summary: &summary,
            outputs: &[],
            quantities: &quantities,
            qoi: &study.qoi,
            points: Some(&table),
            extra: &[],
            plots: !opts.no_report,
        },
    )?;
    // The report writes summary.json; the stale surrogate of another method is removed.
    let _ = std::fs::remove_file(out_dir.join("surrogate.json"));
    Ok(StudyResult {
        summary,
        outputs: Vec::new(),
        quantities,
        warnings_shown: 0,
    })
}

/// The statistics of a quantity of an adaptive study: the runs are not samples of the
/// inputs' law, so no moments, quantiles or density (NaN, `null` in `summary.json`); the
/// number of runs with a value and the smallest and largest of them.
fn adaptive_stats(name: &str, q: &QoiSpec, values: &[f64]) -> ScalarStats {
    let (min, max) = values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &x| {
            (lo.min(x), hi.max(x))
        });
    ScalarStats {
        name: name.to_owned(),
        mean: f64::NAN,
        std: f64::NAN,
        std_error_mean: None,
        n_valid: values.len(),
        n_never_hunts: 0,
        n_never_stops: 0,
        quantiles: Vec::new(),
        min,
        max,
        exceedance: Vec::new(),
        exceedance_counts: Vec::new(),
        deterministic: false,
        unit: None,
        definition: q.definition(),
        convergence: None,
        pdf_x: Vec::new(),
        pdf: Vec::new(),
        samples: values.to_vec(),
        density_samples: Vec::new(),
        sobol_first: None,
        sobol_total: None,
        sobol: None,
        draws: crate::uq::method::Draws::Runs,
        chaos_error: None,
        nested: None,
        reliability: None,
        morris: None,
        rank_correlation: None,
        run_inputs: None,
    }
}

/// The study's FMU as an adaptive method's model: runs through the session, answers from
/// the store.
struct StudyModel<'a> {
    session: Session<'a>,
    fmu: &'a Fmu,
    inputs: &'a RandomInputs,
    /// The points of the runs asked for (`store/points/`).
    points: Store,
    stored_u: Vec<Option<Vec<f64>>>,
    /// The scalar quantities in record order.
    quantities: &'a [(String, &'a QoiSpec)],
    /// Values before the quantities in a record (the outputs' series).
    base: usize,
    retry_failed: bool,
    /// Failed runs run again by this invocation (each once).
    retried: BTreeSet<usize>,
    /// Failed runs that `--retry-failed` did not run again: the method asked for later runs
    /// after them.
    kept_failed: BTreeSet<usize>,
    /// Runs answered from the store.
    resumed: BTreeSet<usize>,
    /// `max_new_points` stopped a batch.
    stopped: bool,
    /// A runner error that stopped the method.
    error: Option<RunError>,
    /// The most runs the method may make.
    capacity: usize,
}

impl StudyModel<'_> {
    /// Runs finished so far (the highest run index with a record, plus one).
    fn runs_done(&self) -> usize {
        self.session
            .runs
            .entries()
            .iter()
            .rposition(Option::is_some)
            .map_or(0, |i| i + 1)
    }

    /// Says which failed runs `--retry-failed` left as they were, and why.
    fn kept_failed_note(&self) -> Option<String> {
        let n = self.kept_failed.len();
        if n == 0 {
            return None;
        }
        let runs: Vec<String> = self
            .kept_failed
            .iter()
            .take(8)
            .map(usize::to_string)
            .collect();
        Some(format!(
            "--retry-failed did not run {} again (run {}{}): the method asked for later runs \
             after {}, which depend on the failure; --fresh runs the study anew",
            count(n, "failed run", "failed runs"),
            runs.join(", "),
            if n > 8 { ", ..." } else { "" },
            if n == 1 { "it" } else { "them" }
        ))
    }

    /// Stops the method with a runner error.
    fn fail(&mut self, e: RunError) -> Abort {
        let message = e.to_string();
        self.error = Some(e);
        Abort::Interrupted(message)
    }

    /// The value of every quantity of run `k`.
    fn outcomes(&self, k: usize) -> Result<Vec<Outcome>, StoreError> {
        let nq = self.quantities.len();
        match &self.session.runs.entries()[k] {
            Some(Entry::Failed(m)) => Ok(vec![Err(m.clone()); nq]),
            None => Ok(vec![Err("the run did not finish".to_owned()); nq]),
            Some(Entry::Ok(_)) => {
                let mut pairs = vec![0.0; 2 * nq];
                if let Some(v) = self.session.runs.values(k) {
                    v.try_read_into(self.base..self.base + 2 * nq, &mut pairs)?;
                }
                Ok(self
                    .quantities
                    .iter()
                    .enumerate()
                    .map(|(j, (name, q))| value_of(name, q, pairs[2 * j], pairs[2 * j + 1]))
                    .collect())
            }
        }
    }

    /// The valid values of quantity `k` over the first `runs` runs.
    fn quantity_values(&self, k: usize, runs: usize) -> Result<Vec<f64>, StudyRunError> {
        let mut out = Vec::new();
        for i in 0..runs.min(self.capacity) {
            let o = self.outcomes(i).map_err(RunError::Store)?;
            if let Some(Ok(v)) = o.get(k) {
                out.push(*v);
            }
        }
        Ok(out)
    }

    /// Every run up to `runs` with its physical inputs and status (`points.csv`).
    fn point_table(&self, study: &Study, runs: usize) -> PointTable {
        let n = runs.min(self.capacity);
        let entries = self.session.runs.entries();
        PointTable {
            names: study.parameters.iter().map(|p| p.name.clone()).collect(),
            weights: None,
            values: (0..n)
                .map(|i| match &self.stored_u[i] {
                    Some(u) => self.inputs.to_physical(Germ::Normal, u),
                    None => vec![f64::NAN; self.inputs.len()],
                })
                .collect(),
            status: (0..n)
                .map(|i| match &entries[i] {
                    Some(Entry::Ok(_)) => PointStatus::Ok,
                    Some(Entry::Failed(m)) => PointStatus::Failed(m.clone()),
                    None => PointStatus::Missing,
                })
                .collect(),
        }
    }
}

/// A stored quantity as the methods see it: its value; for a `hunting_speed` beyond its
/// bracket the end of the bracket it lies beyond; otherwise why there is none.
fn value_of(name: &str, q: &QoiSpec, value: f64, code: f64) -> Outcome {
    match (Code::from_f64(code), q) {
        (Code::Ok, _) if value.is_finite() => Ok(value),
        (Code::Ok, _) => Err(format!("{name} = {value}")),
        (Code::NeverHunts, QoiSpec::HuntingSpeed(h)) => Ok(h.high),
        (Code::NeverStops, QoiSpec::HuntingSpeed(h)) => Ok(h.low),
        (Code::NeverHunts, _) => Err(format!(
            "{name}: no value in this run (the signal never exceeds the threshold)"
        )),
        (Code::NeverStops, _) => Err(format!(
            "{name}: no value in this run (the oscillation never dies out)"
        )),
    }
}

impl BatchModel for StudyModel<'_> {
    fn dim(&self) -> usize {
        self.inputs.len()
    }

    fn evaluate(&mut self, batch: &[Point]) -> Result<Vec<Vec<Outcome>>, Abort> {
        let mut jobs: Vec<(usize, Vec<f64>)> = Vec::new();
        // A failed run is run again (`--retry-failed`) only if the method never asked for a
        // run after its batch: once it has, what it asked for next may depend on the failure
        // (a shortened step of FORM's line search, the seeds of a subset level), and a value
        // now would send it elsewhere than the stored runs. Looked up once per batch, and only
        // when a failed run is met (the scan runs over every later run index).
        let last = batch.iter().map(|p| p.run as usize).max().unwrap_or(0);
        let mut went_on = None;
        for p in batch {
            let k = p.run as usize;
            if k >= self.capacity {
                return Err(Abort::Interrupted(format!(
                    "the method asked for run {k}, beyond the {} runs it may make at most \
                     (an error in uq-driver: please report it)",
                    self.capacity
                )));
            }
            if let Some(u) = &self.stored_u[k] {
                let same = u.len() == p.u.len()
                    && u.iter().zip(&p.u).all(|(a, b)| a.to_bits() == b.to_bits());
                if !same {
                    return Err(Abort::ReplayMismatch {
                        run: p.run,
                        stored: u.clone(),
                        requested: p.u.clone(),
                    });
                }
            }
            let run = match &self.session.runs.entries()[k] {
                None => true,
                Some(Entry::Failed(_))
                    if self.retry_failed
                        && *went_on.get_or_insert_with(|| {
                            self.stored_u
                                .get(last + 1..)
                                .is_some_and(|later| later.iter().any(Option::is_some))
                        }) =>
                {
                    self.kept_failed.insert(k);
                    false
                }
                Some(Entry::Failed(_)) => self.retry_failed && self.retried.insert(k),
                Some(Entry::Ok(_)) => false,
            };
            if !run {
                self.resumed.insert(k);
                continue;
            }
            if self.stored_u[k].is_none() {
                if let Err(e) = self.points.append(k, &Record::Ok(p.u.clone())) {
                    return Err(self.fail(RunError::Store(e)));
                }
                self.stored_u[k] = Some(p.u.clone());
            }
            jobs.push((k, self.inputs.to_physical(Germ::Normal, &p.u)));
        }
        if !jobs.is_empty() {
            let values: Vec<Vec<f64>> = jobs.iter().map(|(_, x)| x.clone()).collect();
            if let Err(e) = self.session.iface.check_design(self.fmu, &values) {
                return Err(self.fail(e.into()));
            }
            let list: Vec<Job> = jobs.iter().map(|(k, x)| (*k, x.as_slice())).collect();
            match self.session.run(&list) {
                Ok(done) if done.len() < list.len() => {
                    self.stopped = true;
                    return Err(Abort::Interrupted(format!(
                        "stopped after {} new runs (max_new_points, --max-points)",
                        self.session.new
                    )));
                }
                Ok(_) => {}
                Err(e) => return Err(self.fail(e)),
            }
        }
        let mut out = Vec::with_capacity(batch.len());
        for p in batch {
            match self.outcomes(p.run as usize) {
                Ok(o) => out.push(o),
                Err(e) => return Err(self.fail(RunError::Store(e))),
            }
        }
        Ok(out)
    }
}
