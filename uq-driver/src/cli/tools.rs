//! `simulate`, `inspect` and `surrogate`.

use std::io::Write;
use std::path::Path;

use anyhow::{Context, Result};

use super::args::*;
use crate::fmu::{Causality, Fmu, VariableKind};
use crate::report::csv::push_shortest;
use crate::spec::{Experiment, FixedValue, InvalidExperiment};
use crate::study::plan::size;
use crate::study::progress::message;
use crate::study::run::{self as runner, guard, Simulation};
use crate::uq::surrogate::Surrogate;

/// The file named by `--out`, or `None` for standard output (no `--out`, or `--out -`).
fn out_path(out: Option<&Path>) -> Option<&Path> {
    out.filter(|p| !out_file::is_stdout(p))
}

/// Writes `text` to `out` (by the rules of the `out-file` crate), or to standard output.
pub(crate) fn emit(text: &str, out: Option<&Path>) -> Result<()> {
    match out_path(out) {
        Some(p) => {
            out_file::write(p, text.as_bytes()).with_context(|| format!("writing {}", p.display()))
        }
        None => Ok(std::io::stdout().lock().write_all(text.as_bytes())?),
    }
}

/// `uq-driver surrogate eval|sample`.
pub(crate) fn surrogate(cmd: SurrogateCommand) -> Result<()> {
    match cmd {
        SurrogateCommand::Eval { dir, at, out } => {
            let s = Surrogate::load(&dir)?;
            let x = s.point(&at)?;
            emit(&s.eval_csv(&x), out.as_deref())
        }
        SurrogateCommand::Sample {
            dir,
            n,
            seed,
            times,
            out,
        } => {
            let s = Surrogate::load(&dir)?;
            // Written as drawn: the memory does not grow with -n.
            match out_path(out.as_deref()) {
                Some(p) => {
                    let mut f = out_file::OutFile::create(p, 1 << 16)
                        .with_context(|| format!("writing {}", p.display()))?;
                    s.write_sample_csv(n, seed, &times, &mut f, &p.display().to_string())?;
                    f.commit()
                        .with_context(|| format!("writing {}", p.display()))?;
                }
                None => {
                    let mut stdout = std::io::stdout().lock();
                    s.write_sample_csv(n, seed, &times, &mut stdout, "standard output")?;
                }
            }
            Ok(())
        }
    }
}

/// `uq-driver simulate`: one run as CSV.
pub(crate) fn simulate(a: SimulateArgs) -> Result<()> {
    let params: Vec<(String, FixedValue)> = a
        .set
        .iter()
        .map(|(n, v)| (n.clone(), FixedValue::Text(v.clone())))
        .collect();
    let to_stdout = out_path(a.out.as_deref()).is_none();
    let (sim, meta) = simulation(&a, &params, to_stdout)?;
    for (name, value) in &sim.calculated_strings {
        message(&format!(
            "uq-driver: note: the FMU reports {name} = \"{value}\""
        ));
    }
    let mut text = String::from("time");
    for n in &sim.names {
        text.push(',');
        crate::report::csv::push_field(&mut text, n);
    }
    text.push('\n');
    for (k, t) in sim.times.iter().enumerate() {
        push_shortest(&mut text, *t);
        for s in &sim.series {
            text.push(',');
            push_shortest(&mut text, s[k]);
        }
        text.push('\n');
    }
    emit(&text, a.out.as_deref())?;
    // Beside a CSV written to a file (not to a device or a pipe): what produced it.
    if let Some(p) = out_path(a.out.as_deref()).filter(|p| p.is_file()) {
        let mut side = p.as_os_str().to_owned();
        side.push(".meta.json");
        let side = std::path::PathBuf::from(side);
        let text = simulation_metadata(&a, &params, &sim, &meta);
        out_file::write(&side, text.as_bytes())
            .with_context(|| format!("writing {}", side.display()))?;
    }
    Ok(())
}

/// What `simulate --out FILE` writes to `FILE.meta.json`: the FMU (path, model name, GUID,
/// SHA-256, its String calculated parameters, e.g. the instruction sets a model's solver ran
/// on), the experiment and the values set (as given on the command line).
fn simulation_metadata(
    a: &SimulateArgs,
    params: &[(String, FixedValue)],
    sim: &Simulation,
    meta: &SimulationMeta,
) -> String {
    let set: serde_json::Map<String, serde_json::Value> = params
        .iter()
        .map(|(n, v)| {
            let text = match v {
                FixedValue::Text(t) => t.clone(),
                other => other.to_string(),
            };
            (n.clone(), serde_json::json!(text))
        })
        .collect();
    let strings: serde_json::Map<String, serde_json::Value> = sim
        .calculated_strings
        .iter()
        .map(|(n, v)| (n.clone(), serde_json::json!(v)))
        .collect();
    let sha256 = crate::study::plan::fingerprint::sha256_file(&a.fmu).unwrap_or_default();
    let json = serde_json::json!({
        "fmu": {
            "path": a.fmu.display().to_string(),
            "model_name": meta.model_name,
            "guid": meta.guid,
            "sha256": sha256,
            "calculated_strings": strings,
        },
        "experiment": {
            "start": meta.experiment.start,
            "stop": meta.experiment.stop,
            "step": meta.experiment.step,
        },
        "set": set,
        "ended_at": sim.ended_at,
        "versions": {"uq_driver": env!("CARGO_PKG_VERSION"), "fmi": "2.0"},
    });
    let mut text = serde_json::to_string_pretty(&json).unwrap_or_default();
    text.push('\n');
    text
}

/// What [`simulation`] used besides its result: the FMU's identity and the experiment.
pub(crate) struct SimulationMeta {
    model_name: String,
    guid: String,
    experiment: Experiment,
}

/// The run of `uq-driver simulate` (and of [`super::simulate`]): `params` set before
/// initialization, the experiment from `a` or the FMU's default experiment; what it notes
/// (values outside a variable's range, outputs not recorded, an early end) goes to the
/// message sink. With `redirect_stdout` what the FMU prints goes to stderr meanwhile (the
/// CSV is written to stdout).
pub(crate) fn simulation(
    a: &SimulateArgs,
    params: &[(String, FixedValue)],
    redirect_stdout: bool,
) -> Result<(Simulation, SimulationMeta)> {
    let fmu = Fmu::open(&a.fmu)?;
    let de = fmu.description().default_experiment.unwrap_or_default();
    let start = a.start.or(de.start_time).unwrap_or(0.0);
    let stop = a
        .stop
        .or(de.stop_time)
        .context("no --stop and no default stop time in the FMU")?;
    let step = match a.step.or(de.step_size) {
        Some(h) => h,
        None => {
            let h = auto_interval(stop - start).context(
                "no --step, no default step size in the FMU, and no time to divide (stop <= \
                 start): give --step",
            )?;
            eprintln!(
                "uq-driver: note: no --step and no default step size in the FMU: communication \
                 step {} s ({} steps from {start} s to {stop} s, chosen as fmpy's simulate_fmu \
                 chooses it: a round step giving 500 to 1000 steps; --step sets another)",
                shortest(h),
                ((stop - start) / h).round()
            );
            h
        }
    };
    let experiment = Experiment { start, stop, step };
    experiment.check().map_err(|e| match e {
        InvalidExperiment::ZeroStep => anyhow::anyhow!(
            "--step 0: the communication step must be positive (s), e.g. --step 0.01"
        ),
        other => other.into(),
    })?;
    // The first column is the time: `--output time` (the FMU's independent variable, or no
    // variable at all) adds no second one.
    let md = fmu.description();
    let is_time = |n: &str| {
        n == "time"
            && md
                .variable("time")
                .is_none_or(|v| v.causality == Causality::Independent)
    };
    let mut outputs: Vec<String> = a.outputs.iter().filter(|n| !is_time(n)).cloned().collect();
    if outputs.len() < a.outputs.len() {
        eprintln!(
            "uq-driver: note: the time is the first column of the CSV; --output time adds no \
             second one"
        );
        if outputs.is_empty() {
            // Only the time asked for: record the FMU's time variable, left out below.
            anyhow::ensure!(
                md.variable("time").is_some(),
                "--output time only: the time is always the first column; name a variable to \
                 record with --output (`uq-driver inspect` lists them)"
            );
            outputs.push("time".into());
        }
    }
    let series = if outputs.is_empty() {
        md.output_variables().count()
    } else {
        outputs.len()
    };
    size::check_simulation(experiment.n_steps() as f64 + 1.0, series)?;
    let times = experiment.times();
    crate::study::plan::interface::check_step_sizes(&fmu, &times)?;
    for (name, value) in params {
        if let Some(w) = crate::study::plan::ranges::value_warning(&fmu, name, value) {
            message(&format!("uq-driver: warning: {w}"));
        }
    }
    let mut sim = {
        // An FMU that calls exit() is reported; what it prints stays out of a CSV on stdout.
        let _exit = guard::SimulationGuard::begin(&a.fmu);
        let _stdout = redirect_stdout.then(guard::StdoutToStderr::begin);
        runner::simulate_with(
            &fmu,
            params,
            &outputs,
            a.input.as_deref(),
            &times,
            a.fmu_logging,
        )?
    };
    for (name, why) in &sim.skipped {
        message(&format!(
            "uq-driver: note: output '{name}' not recorded: {why}"
        ));
    }
    if sim.names.is_empty() {
        message(
            "uq-driver: warning: nothing to record: the FMU has no output that can be written \
             as a number (name variables with --output)",
        );
    }
    if let Some(t) = sim.ended_at {
        message(&format!(
            "uq-driver: note: the FMU ended the simulation at t = {t} s (before the stop time \
             {stop} s); the output ends there"
        ));
    }
    // The time is the CSV's first column (and the host's time axis): a recorded time
    // variable is not a second one.
    let keep: Vec<bool> = sim.names.iter().map(|n| !is_time(n)).collect();
    let mut k = 0;
    sim.names.retain(|_| {
        k += 1;
        keep[k - 1]
    });
    let mut k = 0;
    sim.series.retain(|_| {
        k += 1;
        keep[k - 1]
    });
    let meta = SimulationMeta {
        model_name: md.model_name.clone(),
        guid: md.guid.clone(),
        experiment,
    };
    Ok((sim, meta))
}

/// The communication step fmpy's `simulate_fmu` takes for a Co-Simulation FMU without a
/// default step size (`fmpy.util.auto_interval`, 0.3.32): a power of ten near a thousandth of
/// `t` (s), times 5, 4, 2, 1/2, 1/4 or 1/5, so that `t` takes 500 to 1000 steps (s). `None`
/// for a `t` that is not positive and finite.
pub(crate) fn auto_interval(t: f64) -> Option<f64> {
    if !(t > 0.0 && t.is_finite()) {
        return None;
    }
    // numpy's round: half to even.
    let mut h = 10f64.powf(t.log10().round_ties_even() - 3.0);
    let n = t / h;
    if n >= 2500.0 {
        h *= 5.0;
    } else if n >= 2000.0 {
        h *= 4.0;
    } else if n >= 1000.0 {
        h *= 2.0;
    } else if n <= 200.0 {
        h /= 5.0;
    } else if n <= 250.0 {
        h /= 4.0;
    } else if n <= 500.0 {
        h /= 2.0;
    }
    Some(h)
}

pub(crate) fn inspect(path: &Path) -> Result<()> {
    let fmu = Fmu::open(path)?;
    // Buffered: one write per line would cost a system call per variable.
    let mut o = std::io::BufWriter::new(std::io::stdout().lock());
    let md = fmu.description();
    let cs = &md.co_simulation;
    writeln!(
        o,
        "{} — {}",
        md.model_name,
        md.description.as_deref().unwrap_or("")
    )?;
    writeln!(
        o,
        "  FMI {}  GUID {}  generated by {}",
        md.fmi_version,
        md.guid,
        md.generation_tool.as_deref().unwrap_or("?")
    )?;
    writeln!(
        o,
        "  Co-Simulation: modelIdentifier {}, variable step {}, get/set state {}, serialize state {}, directional derivatives {}",
        cs.model_identifier,
        cs.can_handle_variable_communication_step_size,
        cs.can_get_and_set_fmu_state,
        cs.can_serialize_fmu_state,
        cs.provides_directional_derivative
    )?;
    if cs.needs_execution_tool {
        writeln!(
            o,
            "  needs its execution tool (needsExecutionTool=\"true\"): the exporting tool or \
             runtime must be installed where it runs"
        )?;
    }
    if let Some(de) = &md.default_experiment {
        let plain = |v: Option<f64>| v.map_or_else(|| "–".to_string(), shortest);
        writeln!(
            o,
            "  default experiment: start {} s, stop {} s, step {} s",
            plain(de.start_time),
            plain(de.stop_time),
            plain(de.step_size)
        )?;
    }
    // The name column as wide as the longest name (capped, so that one absurd name does not
    // push every row off the screen).
    let w = md
        .variables
        .iter()
        .map(|v| v.name.chars().count())
        .max()
        .unwrap_or(0)
        .clamp(16, 48);
    writeln!(
        o,
        "  {:<w$} {:>5} {:<8} {:<20} {:<11} {:>12} {:<8} description",
        "name", "vr", "type", "causality", "variability", "start", "unit"
    )?;
    for v in &md.variables {
        let (start, unit) = match &v.kind {
            VariableKind::Real { start, .. } => (
                start.map(shortest),
                crate::report::units::unit_of(md, &v.name),
            ),
            VariableKind::Integer { start, .. } | VariableKind::Enumeration { start, .. } => {
                (start.map(|s| s.to_string()), None)
            }
            VariableKind::Boolean { start } => (start.map(|s| s.to_string()), None),
            VariableKind::String { start } => (start.clone(), None),
        };
        writeln!(
            o,
            "  {:<w$} {:>5} {:<8} {:<20} {:<11} {:>12} {:<8} {}",
            v.name,
            v.value_reference,
            v.kind.type_name(),
            v.causality.as_str(),
            v.variability.as_str(),
            start.unwrap_or_default(),
            unit.unwrap_or_default(),
            described_range(&v.kind, v.description.as_deref().unwrap_or(""))
        )?;
    }
    o.flush()?;
    Ok(())
}

/// A number as the CSV files write it: plain between 1e-4 and 1e16, else in exponent form
/// (`1e300`, not 301 digits).
fn shortest(v: f64) -> String {
    crate::report::csv::shortest(v)
}

/// A variable's description, after its declared `min`/`max` (`range [0.5, 1]`, an open end
/// as `-inf` or `inf`) when it declares either.
fn described_range(kind: &VariableKind, description: &str) -> String {
    let (min, max) = match kind {
        VariableKind::Real { min, max, .. } => (*min, *max),
        VariableKind::Integer { min, max, .. } => (min.map(f64::from), max.map(f64::from)),
        _ => (None, None),
    };
    if min.is_none() && max.is_none() {
        return description.to_owned();
    }
    let lo = min.unwrap_or(f64::NEG_INFINITY);
    let hi = max.unwrap_or(f64::INFINITY);
    format!("range [{}, {}] {description}", shortest(lo), shortest(hi))
        .trim_end()
        .to_owned()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An FMU without a default step could not be simulated without --step; fmpy picks one.
    #[test]
    fn the_step_chosen_without_a_default_is_fmpys() {
        // fmpy.util.auto_interval(t) for these t, from fmpy 0.3.32.
        for (t, h) in [
            (1.0, 0.002),
            (10.0, 0.02),
            (2.0, 0.004),
            (3.0, 0.005),
            (0.5, 0.0005),
            (7.0, 0.01),
            (100.0, 0.2),
        ] {
            let got = auto_interval(t).unwrap();
            assert!((got - h).abs() <= 1e-12 * h, "t = {t}: {got} vs {h}");
            let n = t / got;
            assert!((500.0..=1000.0).contains(&n.round()), "t = {t}: {n} steps");
        }
        assert_eq!(auto_interval(0.0), None);
        assert_eq!(auto_interval(f64::NAN), None);
    }
}
