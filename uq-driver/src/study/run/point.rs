//! One model run: an instance started (or reset), its parameters and inputs set, stepped over
//! the communication grid, its signals recorded; where the FMU ends the simulation itself the
//! run ends there.

use std::path::Path;

use super::error::{PointError, RunError};
use super::instances::{first_difference, same_record, InstancePolicy, ResetCheck, Slot};
use crate::fmu::{Fmu, FmuError, Instance, Status, StatusKind};
use crate::qoi::evaluate::evaluate;
use crate::qoi::QoiSpec;
use crate::spec::FixedValue;
use crate::study::plan::inputs::isclose;
use crate::study::plan::interface::{Interface, RandomValueError};

/// What one run recorded.
#[derive(Clone, Debug, PartialEq)]
pub struct Trace {
    /// `values[o * nt + k]` is signal `o` at `times[k]` (nt = the grid's length), for
    /// `k < recorded`; the rest is zero.
    pub values: Vec<f64>,
    /// Grid times recorded: all of them unless the FMU ended the simulation early.
    pub recorded: usize,
    /// When the FMU ended the simulation before the stop time (`fmi2DoStep` returned
    /// fmi2Discard and `fmi2GetBooleanStatus(fmi2Terminated)` was true): the time it ended
    /// at (s, from `fmi2GetRealStatus(fmi2LastSuccessfulTime)`) and, when that is after the
    /// last grid time recorded, the signals there.
    pub ended: Option<(f64, Option<Vec<f64>>)>,
}

/// A grid of at least one finite time, strictly increasing (s).
fn check_times(times: &[f64]) -> Result<(), PointError> {
    if times.is_empty() {
        return Err(PointError::Times(
            "no communication point: give at least one time (s)".into(),
        ));
    }
    if let Some(t) = times.iter().find(|t| !t.is_finite()) {
        return Err(PointError::Times(format!("time {t} is not finite")));
    }
    if let Some(w) = times.windows(2).find(|w| w[1] <= w[0]) {
        return Err(PointError::Times(format!(
            "times must increase, but {} s is followed by {} s",
            w[0], w[1]
        )));
    }
    Ok(())
}

/// Starts `slot`'s instance (fresh, or reset: [`Slot::start`]), sets the parameters (the fixed ones, the random
/// `values`, then the Real `extra` values) and the inputs, initializes and records the signals
/// at `times`, ending early where the FMU ends the simulation. `stop_defined`: whether the
/// FMU is told the stop time (the last of `times`); false lets the run go on after `times`,
/// as a continuation does.
pub(super) fn simulate_point(
    fmu: &Fmu,
    slot: &mut Slot,
    iface: &Interface,
    values: &[f64],
    times: &[f64],
    extra: &[(u32, f64)],
    stop_defined: bool,
) -> Result<Trace, PointError> {
    check_times(times)?;
    let nt = times.len();
    let inst = slot.start(fmu)?;
    iface.fixed.apply(inst)?;
    iface.set_random(inst, values).map_err(|e| match e {
        RandomValueError::Fmu(e) => PointError::Fmu(e),
        RandomValueError::Value(p) => PointError::Value(p.to_string()),
    })?;
    if !extra.is_empty() {
        let (vr, v): (Vec<u32>, Vec<f64>) = extra.iter().copied().unzip();
        inst.set_real(&vr, &v)?;
    }
    let stop = times[nt - 1]; // checked: at least one time
    inst.setup_experiment(None, times[0], stop_defined.then_some(stop))?;
    inst.enter_initialization_mode()?;
    if let Some(inputs) = &iface.inputs {
        inputs.apply(inst, times[0], false)?;
    }
    inst.exit_initialization_mode()?;
    let mut trace = Trace {
        values: vec![0.0; iface.signals.len * nt],
        recorded: 0,
        ended: None,
    };
    let mut buf = vec![0.0; iface.signals.len];
    for k in 0..nt {
        if k > 0 {
            if let Some(inputs) = &iface.inputs {
                inputs.apply(inst, times[k - 1], true)?;
            }
            if let Err(e) = inst.do_step(times[k - 1], times[k] - times[k - 1], true) {
                let Some(end) = ended_by_fmu(inst, &e, times[k - 1]) else {
                    return Err(e.into());
                };
                if isclose(end, times[k]) {
                    // The step completed and the FMU ends there (at `end`, as it says).
                    iface.signals.read(inst, &mut buf)?;
                    store_column(&mut trace.values, &buf, nt, k);
                    trace.recorded = k + 1;
                    if k + 1 < nt {
                        trace.ended = Some((end, None));
                    }
                } else if end > times[k - 1] && !isclose(end, times[k - 1]) {
                    iface.signals.read(inst, &mut buf)?;
                    trace.ended = Some((end, Some(buf.clone())));
                } else {
                    trace.ended = Some((times[k - 1], None));
                }
                return Ok(trace);
            }
        }
        iface.signals.read(inst, &mut buf)?;
        store_column(&mut trace.values, &buf, nt, k);
        trace.recorded = k + 1;
    }
    Ok(trace)
}

/// Writes one time's signals into the signal-major matrix.
fn store_column(values: &mut [f64], column: &[f64], nt: usize, k: usize) {
    for (o, v) in column.iter().enumerate() {
        values[o * nt + k] = *v;
    }
}

/// When `error` from `fmi2DoStep` from `current` means the FMU ended the simulation
/// (fmi2Discard and fmi2Terminated true): the time it ended at (its last successful time, or
/// `current` if it cannot say).
pub(super) fn ended_by_fmu(inst: &mut Instance, error: &FmuError, current: f64) -> Option<f64> {
    let FmuError::Call {
        status: Status::Discard,
        ..
    } = error
    else {
        return None;
    };
    if !inst.get_boolean_status(StatusKind::Terminated).ok()? {
        return None;
    }
    let end = inst
        .get_real_status(StatusKind::LastSuccessfulTime)
        .ok()
        .filter(|t| t.is_finite() && *t >= current)
        .unwrap_or(current);
    Some(end)
}

/// Runs one point on `slot`'s instance (fresh or reset, by its policy). Returns the record
/// values: the stored outputs (output-major: all times of output 0, then output 1, …), then
/// (value, code) of each scalar quantity (a `hunting_speed` entry gives two, from its own
/// constant-speed runs on the same instance after the point's run). A run the FMU ends
/// before the stop time is a failed point ([`PointError::EndedEarly`]), unless every quantity
/// gives its value for such a run (`if_ended`) and no series is stored: then the quantities
/// take those values (code Ok).
pub fn run_point(
    fmu: &Fmu,
    slot: &mut Slot,
    iface: &Interface,
    values: &[f64],
    times: &[f64],
) -> Result<Vec<f64>, PointError> {
    let nt = times.len();
    let trace = simulate_point(fmu, slot, iface, values, times, &[], true).inspect_err(|_| {
        // A failed instance may be in Error state: start the next point on a fresh one.
        slot.discard();
    })?;
    if let Some((time, _)) = trace.ended {
        slot.discard();
        // Every quantity then has its value for such a run and no series is stored (the
        // study was refused otherwise: `ended_value_problem`).
        if iface.n_stored == 0 && !iface.qois.is_empty() {
            let values: Option<Vec<f64>> = iface.qois.iter().map(QoiSpec::if_ended).collect();
            if let Some(values) = values {
                return Ok(values.into_iter().flat_map(|v| [v, 0.0]).collect());
            }
        }
        return Err(PointError::EndedEarly {
            time,
            stop: times[nt - 1],
        });
    }
    let traces = trace.values;
    if let Some(pos) = traces.iter().position(|v| !v.is_finite()) {
        slot.discard();
        return Err(PointError::NonFinite {
            signal: iface.signal_names[pos / nt].clone(),
            time: times[pos % nt],
        });
    }
    let mut out = traces[..iface.n_stored * nt].to_vec();
    let signal = |name: &str| -> &[f64] {
        let i = iface
            .signal_names
            .iter()
            .position(|n| n == name)
            .expect("resolved");
        &traces[i * nt..(i + 1) * nt]
    };
    for (qi, q) in iface.qois.iter().enumerate() {
        if let QoiSpec::HuntingSpeed(h) = q {
            let runs = iface
                .speed_runs
                .iter()
                .find(|r| r.qoi == qi)
                .expect("resolved with the interface");
            out.extend(runs.evaluate(h, fmu, slot, values)?);
            continue;
        }
        let (v, code) = evaluate(q, times, signal).map_err(|error| PointError::Quantity {
            name: q.name().to_owned(),
            error,
        })?;
        out.push(v);
        out.push(code as u8 as f64);
    }
    Ok(out)
}

/// The second half of the reset self-check ([`crate::study::run::instances`]): point `values`, whose run
/// on a fresh instance gave `first`, run again on the same instance (held by `slot`) after
/// `fmi2Reset`. Afterwards `slot` reuses instances if the check passed, else not (and holds
/// none). Also returns the error of the second run when it returned fmi2Fatal (the FMU is then
/// unusable in this process).
pub fn check_reset(
    fmu: &Fmu,
    slot: &mut Slot,
    iface: &Interface,
    values: &[f64],
    times: &[f64],
    first: &[f64],
) -> (ResetCheck, Option<PointError>) {
    slot.set_reuse(true);
    let second = run_point(fmu, slot, iface, values, times);
    let reset_failure = slot.take_reset_failure();
    let (check, fatal) = match (reset_failure, second) {
        (Some(why), _) => (ResetCheck::Failed(format!("fmi2Reset failed: {why}")), None),
        (None, Err(e)) => {
            let check = ResetCheck::Failed(format!(
                "the FMU's run after fmi2Reset failed where a fresh instance's succeeded: {e}"
            ));
            (check, e.returned_fatal().then_some(e))
        }
        (None, Ok(second)) if same_record(first, &second) => (ResetCheck::Passed, None),
        (None, Ok(second)) => (ResetCheck::Failed(first_difference(first, &second)), None),
    };
    if !check.reuse() {
        slot.set_reuse(false);
        slot.discard();
    }
    (check, fatal)
}

/// One deterministic run: its times and, per recorded variable, the series.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct Simulation {
    /// The variables recorded.
    pub names: Vec<String>,
    /// Communication points (s): the grid, cut where the FMU ended the simulation.
    pub times: Vec<f64>,
    /// `series[o][k]`: variable `o` at `times[k]`.
    pub series: Vec<Vec<f64>>,
    /// Outputs not recorded, with the reason (when every output was asked for).
    pub skipped: Vec<(String, String)>,
    /// When the FMU ended the simulation before the stop time, the time (s).
    pub ended_at: Option<f64>,
    /// The FMU's String calculated parameters (name, value) read after the run (see
    /// [`crate::fmu::Instance::get_calculated_strings`]), e.g. the instruction sets a model's
    /// solver ran on; empty when it has none.
    pub calculated_strings: Vec<(String, String)>,
}

/// One deterministic run of `fmu` with `params` set before initialization, `inputs` (a CSV
/// file, as `[inputs]` reads it) applied during the run, recording `outputs` (names; every
/// output that can be recorded when empty) at `times`. Where the FMU ends the simulation
/// early, the run ends there (its last row at the FMU's last successful time), as in fmpy.
pub fn simulate(
    fmu: &Fmu,
    params: &[(String, FixedValue)],
    outputs: &[String],
    inputs: Option<&Path>,
    times: &[f64],
) -> Result<Simulation, RunError> {
    simulate_with(fmu, params, outputs, inputs, times, false)
}

/// [`simulate`], instantiating with `loggingOn = logging_on` (the FMU's messages then echoed
/// to stderr as they come).
pub fn simulate_with(
    fmu: &Fmu,
    params: &[(String, FixedValue)],
    outputs: &[String],
    inputs: Option<&Path>,
    times: &[f64],
    logging_on: bool,
) -> Result<Simulation, RunError> {
    let iface = Interface::for_run(fmu, params, outputs, inputs)?;
    let policy = InstancePolicy {
        reuse: false,
        logging_on,
    };
    let mut slot = Slot::new(policy, logging_on);
    let trace = simulate_point(fmu, &mut slot, &iface, &[], times, &[], true)?;
    let calculated_strings = match slot.current().map(|inst| inst.get_calculated_strings()) {
        Some(Ok(values)) => values,
        Some(Err(e)) => {
            crate::study::progress::message(&format!(
                "uq-driver: note: the FMU's String calculated parameters could not be read \
                 after the run: {e}"
            ));
            Vec::new()
        }
        None => Vec::new(),
    };
    let nt = times.len();
    let mut out_times = times[..trace.recorded].to_vec();
    let mut series: Vec<Vec<f64>> = trace
        .values
        .chunks(nt)
        .map(|s| s[..trace.recorded].to_vec())
        .collect();
    let ended_at = trace.ended.as_ref().map(|(t, _)| *t);
    match trace.ended {
        Some((t, Some(row))) => {
            out_times.push(t);
            for (s, v) in series.iter_mut().zip(row) {
                s.push(v);
            }
        }
        // Ended at (within 1e-9 of) a grid time: the last row is at the FMU's own time, as fmpy
        // writes it.
        Some((t, None)) if trace.recorded > 0 && isclose(t, times[trace.recorded - 1]) => {
            out_times[trace.recorded - 1] = t;
        }
        _ => {}
    }
    Ok(Simulation {
        names: iface.signal_names,
        times: out_times,
        series,
        skipped: iface.skipped,
        ended_at,
        calculated_strings,
    })
}

/// "K = 1.2, C = 3" for messages.
pub(crate) fn describe_values(study: &crate::spec::Study, values: &[f64]) -> String {
    study
        .parameters
        .iter()
        .zip(values)
        .map(|(p, v)| format!("{} = {v}", p.name))
        .collect::<Vec<_>>()
        .join(", ")
}
