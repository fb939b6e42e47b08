//! A study resolved against its FMU: the [`Interface`] of its runs, including the runs of its
//! own of each `hunting_speed` quantity ([`crate::qoi::hunting_speed`]): at each design point,
//! runs at constant speeds with the point's random values, the study's `[fixed]` values, the
//! quantity's `set` values and the speed parameter, bisected (or continued stage by stage) on
//! the same FMU instance as the point's run (`run::point`). They are part of the point's evaluation, so their results are
//! stored in the point's record (resumable, shardable, and the same in a `--isolate` worker).

use crate::fmu::{Fmu, Variability, VariableKind};
use crate::qoi::hunting_speed::{HuntingSpeedSpec, SearchMode};
use crate::qoi::QoiSpec;
use crate::spec::{Experiment, Study};
use crate::study::plan::interface::{
    Interface, InterfaceError, Settings, SpeedRuns, VariableProblem, Variables,
};

/// Checks the study's variables against the FMU and resolves their value references (reading
/// the input file, if any), with the runs of each `hunting_speed` quantity.
pub fn interface(study: &Study, fmu: &Fmu) -> Result<Interface, InterfaceError> {
    let mut iface = Interface::resolve_variables(study, fmu)?;
    iface.speed_runs = SpeedRuns::resolve_all(study, &iface, &Variables { fmu })?;
    Ok(iface)
}

impl SpeedRuns {
    /// The runs of every `hunting_speed` quantity of `study`, whose other variables `base`
    /// holds.
    pub(super) fn resolve_all(
        study: &Study,
        base: &Interface,
        vars: &Variables,
    ) -> Result<Vec<SpeedRuns>, InterfaceError> {
        study
            .qoi
            .iter()
            .enumerate()
            .filter_map(|(i, q)| match q {
                QoiSpec::HuntingSpeed(h) => Some(Self::resolve(i, h, study, base, vars)),
                _ => None,
            })
            .collect()
    }

    fn resolve(
        qoi: usize,
        h: &HuntingSpeedSpec,
        study: &Study,
        base: &Interface,
        vars: &Variables,
    ) -> Result<SpeedRuns, InterfaceError> {
        let problem = |problem: String| {
            vars.error(VariableProblem::Quantity {
                name: h.name.clone(),
                problem,
            })
        };
        let random = |n: &str| study.parameters.iter().any(|p| p.name == n);
        if random(&h.speed_parameter) {
            return Err(problem(format!(
                "the speed parameter '{}' is a random parameter; the bisection sets it",
                h.speed_parameter
            )));
        }
        if let Some(k) = h.set.keys().find(|k| random(k)) {
            return Err(problem(format!(
                "`set` names '{k}', a random parameter (each point sets its own value)"
            )));
        }
        let var = vars.any(&h.speed_parameter)?;
        if !matches!(var.kind, VariableKind::Real { .. }) {
            return Err(problem(format!(
                "the speed parameter '{}' is a {}; it must be a Real",
                h.speed_parameter,
                var.kind.type_name()
            )));
        }
        vars.check_settable(var)?;
        if h.mode == SearchMode::Continuation {
            if var.variability != Variability::Tunable {
                return Err(problem(format!(
                    "mode = \"continuation\" changes the speed between steps, but the speed \
                     parameter '{}' is {}, not tunable",
                    h.speed_parameter,
                    var.variability.as_str()
                )));
            }
            if h.needs_fmu_state()
                && !vars
                    .fmu
                    .description()
                    .co_simulation
                    .can_get_and_set_fmu_state
            {
                return Err(problem(format!(
                    "mode = \"continuation\" with a tolerance ({}) below speed_step ({}) goes \
                     back to the last hunting state (fmi2GetFMUstate, fmi2SetFMUstate), but the \
                     FMU declares canGetAndSetFMUstate=\"false\"; set tolerance = speed_step to \
                     run without refinement",
                    h.tolerance,
                    h.speed_step.unwrap_or(f64::NAN)
                )));
            }
        }
        let speed = var.value_reference;
        let set = vars.settings(h.set.iter().map(|(n, v)| (n.as_str(), v)))?;
        let mut run = base.clone();
        run.fixed = merged(&base.fixed, &set, speed);
        run.signal_names = vec![h.signal.clone()];
        run.signals = vars.signals(&run.signal_names)?;
        run.n_stored = 1;
        run.qois = Vec::new();
        run.skipped = Vec::new();
        run.speed_runs = Vec::new();
        let e = &study.experiment;
        let times = Experiment {
            start: e.start,
            stop: e.start + h.duration,
            step: h.step.unwrap_or(e.step),
        }
        .times();
        if times.len() < 2 {
            return Err(problem("the runs have no time step".into()));
        }
        Ok(SpeedRuns {
            qoi,
            speed,
            run: Box::new(run),
            times,
        })
    }
}

/// `base` with `over`'s values (and the speed, set per run) replacing its values of the same
/// variables, so that each variable is set once.
fn merged(base: &Settings, over: &Settings, speed: u32) -> Settings {
    // Value references are unique per type only: merge type by type.
    fn merge<T: Clone>(a: &[(u32, T)], b: &[(u32, T)]) -> Vec<(u32, T)> {
        a.iter()
            .filter(|(vr, _)| !b.iter().any(|(w, _)| w == vr))
            .chain(b)
            .cloned()
            .collect()
    }
    let mut real = merge(&base.real, &over.real);
    real.retain(|(vr, _)| *vr != speed);
    Settings {
        real,
        integer: merge(&base.integer, &over.integer),
        boolean: merge(&base.boolean, &over.boolean),
        string: merge(&base.string, &over.string),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn merged_settings_set_each_variable_once() {
        let base = Settings {
            real: vec![(1, 1.0), (2, 2.0), (15, 100.0)],
            integer: vec![(7, 3), (15, 4)],
            ..Settings::default()
        };
        let over = Settings {
            real: vec![(2, 20.0), (16, 0.0)],
            ..Settings::default()
        };
        let m = merged(&base, &over, 15);
        assert_eq!(m.real, vec![(1, 1.0), (2, 20.0), (16, 0.0)]);
        // An Integer may have the speed's value reference: it stays.
        assert_eq!(m.integer, vec![(7, 3), (15, 4)]);
    }
}
