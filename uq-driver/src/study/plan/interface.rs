//! The study's variables resolved against the FMU: which value references the runner sets
//! (random and fixed parameters, input signals) and reads (outputs and the signals of the
//! quantities), each with its FMI type.
//!
//! Setting: a Real takes a number; an Integer or Enumeration a whole number (32-bit); a
//! Boolean `true`/`false` (or 1/0); a String a text. A text given for another type is parsed as
//! that type (`simulate --set NAME=VALUE` gives texts). Random parameters may be Real, Integer
//! or Enumeration variables; a design value that is not a whole number for an Integer one is
//! refused before any run. Reading: Real, Integer, Enumeration and Boolean variables are
//! recorded as numbers (false 0, true 1); String variables cannot be recorded.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::fmu::{Fmu, FmuError, Instance, ScalarVariable, VariableKind};
use crate::qoi::QoiSpec;
use crate::spec::{FixedValue, Study};
use crate::study::plan::inputs::{InputError, InputTable};

mod error;
pub use error::{InterfaceError, VariableProblem};

/// Refuses a grid whose steps differ (a shorter last step) for an FMU that declares
/// `canHandleVariableCommunicationStepSize="false"`: it would get a step it says it cannot take
/// (fmpy ends such a run at the last whole step instead, leaving out the stop time).
pub fn check_step_sizes(fmu: &Fmu, times: &[f64]) -> Result<(), InterfaceError> {
    if fmu
        .description()
        .co_simulation
        .can_handle_variable_communication_step_size
        || times.len() < 3
    {
        return Ok(());
    }
    let (step, n) = (times[1] - times[0], times.len());
    let last = times[n - 1] - times[n - 2];
    if (last - step).abs() <= 1e-6 * step.abs() {
        return Ok(());
    }
    Err(InterfaceError {
        fmu: fmu.path().to_path_buf(),
        problem: VariableProblem::FixedStepOnly {
            step,
            last,
            whole: times[n - 2],
            next: times[n - 2] + step,
        },
    })
}

/// Values set before initialization, by FMI type: (value reference, value).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Settings {
    /// Real variables.
    pub real: Vec<(u32, f64)>,
    /// Integer and Enumeration variables.
    pub integer: Vec<(u32, i32)>,
    /// Boolean variables.
    pub boolean: Vec<(u32, bool)>,
    /// String variables.
    pub string: Vec<(u32, String)>,
}

impl Settings {
    /// Sets every value (one call per type that has any).
    pub fn apply(&self, inst: &mut Instance) -> Result<(), FmuError> {
        if !self.real.is_empty() {
            let (vr, v): (Vec<u32>, Vec<f64>) = self.real.iter().copied().unzip();
            inst.set_real(&vr, &v)?;
        }
        if !self.integer.is_empty() {
            let (vr, v): (Vec<u32>, Vec<i32>) = self.integer.iter().copied().unzip();
            inst.set_integer(&vr, &v)?;
        }
        if !self.boolean.is_empty() {
            let (vr, v): (Vec<u32>, Vec<bool>) = self.boolean.iter().copied().unzip();
            inst.set_boolean(&vr, &v)?;
        }
        if !self.string.is_empty() {
            let vr: Vec<u32> = self.string.iter().map(|(vr, _)| *vr).collect();
            let v: Vec<&str> = self.string.iter().map(|(_, s)| s.as_str()).collect();
            inst.set_string(&vr, &v)?;
        }
        Ok(())
    }
}

/// A random parameter's variable.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RandomTarget {
    /// The variable's name.
    pub name: String,
    /// Its value reference.
    pub vr: u32,
    /// Its type: `Real`, `Integer` or `Enumeration`.
    pub type_name: String,
}

impl RandomTarget {
    fn is_real(&self) -> bool {
        self.type_name == "Real"
    }
}

/// The variables read at every communication point, grouped by FMI type.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Signals {
    /// Real value references and their positions among the signals.
    pub real: (Vec<u32>, Vec<usize>),
    /// Integer and Enumeration ones.
    pub integer: (Vec<u32>, Vec<usize>),
    /// Boolean ones.
    pub boolean: (Vec<u32>, Vec<usize>),
    /// Number of signals.
    pub len: usize,
}

impl Signals {
    /// Reads every signal into `out` (one value per signal, Booleans as 0/1).
    pub fn read(&self, inst: &mut Instance, out: &mut [f64]) -> Result<(), FmuError> {
        let (vrs, pos) = &self.real;
        if !vrs.is_empty() {
            let mut v = vec![0.0; vrs.len()];
            inst.get_real(vrs, &mut v)?;
            for (&p, x) in pos.iter().zip(v) {
                out[p] = x;
            }
        }
        let (vrs, pos) = &self.integer;
        if !vrs.is_empty() {
            let mut v = vec![0; vrs.len()];
            inst.get_integer(vrs, &mut v)?;
            for (&p, x) in pos.iter().zip(v) {
                out[p] = f64::from(x);
            }
        }
        let (vrs, pos) = &self.boolean;
        if !vrs.is_empty() {
            let mut v = vec![false; vrs.len()];
            inst.get_boolean(vrs, &mut v)?;
            for (&p, x) in pos.iter().zip(v) {
                out[p] = f64::from(u8::from(x));
            }
        }
        Ok(())
    }
}

/// A `hunting_speed` quantity's runs, resolved against the FMU.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SpeedRuns {
    /// Index of the quantity among the study's `[[qoi]]`.
    pub qoi: usize,
    /// Value reference of the speed parameter (a Real).
    pub speed: u32,
    /// What each run sets and reads: the random parameters, `[fixed]` merged with `set`, the
    /// inputs; the signal as the only output.
    pub run: Box<Interface>,
    /// The runs' communication points (s): the study's start time to start + duration.
    pub times: Vec<f64>,
}

/// Value references resolved against the FMU.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Interface {
    /// Random parameters, in study order.
    pub random: Vec<RandomTarget>,
    /// Deterministic values, set before initialization.
    pub fixed: Settings,
    /// Every variable read at each communication point: the outputs, then the signals the
    /// quantities of interest need.
    pub signals: Signals,
    /// Their names.
    pub signal_names: Vec<String>,
    /// Number of leading signals that are stored as time series (the study's outputs).
    pub n_stored: usize,
    /// Scalar quantities of interest.
    pub qois: Vec<QoiSpec>,
    /// Time-varying inputs.
    pub inputs: Option<InputTable>,
    /// Outputs left out of a run that records "every output", with the reason.
    pub skipped: Vec<(String, String)>,
    /// The runs of its own of each `hunting_speed` quantity.
    pub speed_runs: Vec<SpeedRuns>,
}

impl Interface {
    /// Values recorded per successful point: stored series, then (value, code) per scalar
    /// quantity (a `hunting_speed` entry yields two).
    pub fn n_values(&self, n_times: usize) -> usize {
        let scalars: usize = self.qois.iter().map(|q| q.quantity_names().len()).sum();
        self.n_stored * n_times + 2 * scalars
    }

    /// Checks the study's variables against the FMU and resolves their value references
    /// (reading the input file, if any); not yet the runs of the `hunting_speed` quantities
    /// ([`super::resolve::interface`] adds them).
    pub(crate) fn resolve_variables(study: &Study, fmu: &Fmu) -> Result<Interface, InterfaceError> {
        let vars = Variables { fmu };
        let random = study
            .parameters
            .iter()
            .map(|p| vars.random(&p.name))
            .collect::<Result<_, InterfaceError>>()?;
        let fixed = vars.settings(study.fixed.iter().map(|(n, v)| (n.as_str(), v)))?;
        let mut signal_names = study.outputs.clone();
        for s in study.qoi.iter().flat_map(QoiSpec::signals) {
            if !signal_names.iter().any(|n| n == s) {
                signal_names.push(s.to_owned());
            }
        }
        let inputs = vars.inputs(study.inputs.as_deref())?;
        if let Some(table) = &inputs {
            let random = study
                .parameters
                .iter()
                .map(|p| (p.name.as_str(), ROLE_RANDOM));
            let fixed = study.fixed.keys().map(|n| (n.as_str(), ROLE_FIXED));
            let speed = study.qoi.iter().flat_map(|q| match q {
                QoiSpec::HuntingSpeed(h) => std::iter::once(h.speed_parameter.as_str())
                    .chain(h.set.keys().map(String::as_str))
                    .collect(),
                _ => Vec::new(),
            });
            let speed = speed.map(|n| (n, ROLE_SPEED));
            vars.check_not_inputs(table, random.chain(fixed).chain(speed))?;
        }
        Ok(Interface {
            random,
            fixed,
            signals: vars.signals(&signal_names)?,
            signal_names,
            n_stored: study.outputs.len(),
            qois: study.qoi.clone(),
            inputs,
            skipped: Vec::new(),
            speed_runs: Vec::new(),
        })
    }

    /// The interface of one deterministic run: `params` set before initialization, `outputs`
    /// read (when empty: every output of the FMU that can be recorded, the others listed in
    /// [`Interface::skipped`]), `inputs` applied during the run.
    pub fn for_run(
        fmu: &Fmu,
        params: &[(String, FixedValue)],
        outputs: &[String],
        inputs: Option<&Path>,
    ) -> Result<Interface, InterfaceError> {
        let vars = Variables { fmu };
        let mut skipped = Vec::new();
        let names: Vec<String> = if outputs.is_empty() {
            let mut names = Vec::new();
            for v in fmu.description().output_variables() {
                match v.kind {
                    VariableKind::String { .. } => skipped.push((
                        v.name.clone(),
                        "a String output cannot be written as a number".to_owned(),
                    )),
                    _ => names.push(v.name.clone()),
                }
            }
            names
        } else {
            outputs.to_vec()
        };
        let fixed = vars.settings(params.iter().map(|(n, v)| (n.as_str(), v)))?;
        let inputs = vars.inputs(inputs)?;
        if let Some(table) = &inputs {
            vars.check_not_inputs(table, params.iter().map(|(n, _)| (n.as_str(), ROLE_SET)))?;
        }
        Ok(Interface {
            random: Vec::new(),
            fixed,
            signals: vars.signals(&names)?,
            n_stored: names.len(),
            signal_names: names,
            qois: Vec::new(),
            inputs,
            skipped,
            speed_runs: Vec::new(),
        })
    }

    /// Refuses a design whose values do not fit the random variables: a value that is not a
    /// whole number for an Integer or Enumeration variable.
    pub fn check_design(&self, fmu: &Fmu, values: &[Vec<f64>]) -> Result<(), InterfaceError> {
        for (j, target) in self.random.iter().enumerate() {
            if target.is_real() {
                continue;
            }
            if let Some(v) = values.iter().map(|p| p[j]).find(|&v| to_i32(v).is_none()) {
                return Err(InterfaceError {
                    fmu: fmu.path().to_path_buf(),
                    problem: not_whole(target, v),
                });
            }
        }
        Ok(())
    }

    /// Sets the random parameters to one design point's `values`.
    pub fn set_random(&self, inst: &mut Instance, values: &[f64]) -> Result<(), RandomValueError> {
        let mut real = (Vec::new(), Vec::new());
        let mut int = (Vec::new(), Vec::new());
        for (target, &v) in self.random.iter().zip(values) {
            if target.is_real() {
                real.0.push(target.vr);
                real.1.push(v);
            } else {
                let i = to_i32(v).ok_or_else(|| RandomValueError::Value(not_whole(target, v)))?;
                int.0.push(target.vr);
                int.1.push(i);
            }
        }
        if !real.0.is_empty() {
            inst.set_real(&real.0, &real.1)?;
        }
        if !int.0.is_empty() {
            inst.set_integer(&int.0, &int.1)?;
        }
        Ok(())
    }
}

/// Why a design point's values could not be set.
#[derive(Debug, thiserror::Error)]
pub enum RandomValueError {
    /// The value does not fit the variable.
    #[error("{0}")]
    Value(VariableProblem),
    /// The FMU refused it.
    #[error(transparent)]
    Fmu(#[from] FmuError),
}

fn not_whole(target: &RandomTarget, value: f64) -> VariableProblem {
    VariableProblem::RandomNotWhole {
        name: target.name.clone(),
        found: if target.type_name == "Enumeration" {
            "Enumeration"
        } else {
            "Integer"
        },
        value,
    }
}

/// A whole number that fits an `fmi2Integer`.
fn to_i32(v: f64) -> Option<i32> {
    (v.fract() == 0.0 && v >= f64::from(i32::MIN) && v <= f64::from(i32::MAX)).then_some(v as i32)
}

/// What a variable given a value before the run is, for [`Variables::check_not_inputs`].
const ROLE_RANDOM: &str = "a random parameter ([[parameters]])";
const ROLE_FIXED: &str = "given a value in [fixed]";
const ROLE_SPEED: &str = "set by a hunting_speed quantity (its speed_parameter or set)";
const ROLE_SET: &str = "given a value (--set)";

/// Lookups of study variables in one FMU, with errors that name it.
pub(super) struct Variables<'a> {
    pub(super) fmu: &'a Fmu,
}

impl<'a> Variables<'a> {
    pub(super) fn error(&self, problem: VariableProblem) -> InterfaceError {
        InterfaceError {
            fmu: self.fmu.path().to_path_buf(),
            problem,
        }
    }

    pub(super) fn any(&self, name: &str) -> Result<&'a ScalarVariable, InterfaceError> {
        let md = self.fmu.description();
        md.variable(name).ok_or_else(|| {
            self.error(VariableProblem::Unknown {
                name: name.to_owned(),
                model: md.model_name.clone(),
            })
        })
    }

    fn random(&self, name: &str) -> Result<RandomTarget, InterfaceError> {
        let var = self.any(name)?;
        match var.kind {
            VariableKind::Real { .. }
            | VariableKind::Integer { .. }
            | VariableKind::Enumeration { .. } => {}
            _ => {
                return Err(self.error(VariableProblem::NotRandomizable {
                    name: name.to_owned(),
                    found: var.kind.type_name(),
                }))
            }
        }
        self.check_settable(var)?;
        Ok(RandomTarget {
            name: name.to_owned(),
            vr: var.value_reference,
            type_name: var.kind.type_name().to_owned(),
        })
    }

    /// The signals `names`, grouped by type.
    pub(super) fn signals(&self, names: &[String]) -> Result<Signals, InterfaceError> {
        let mut s = Signals {
            len: names.len(),
            ..Signals::default()
        };
        for (pos, n) in names.iter().enumerate() {
            let var = self.any(n)?;
            let group = match var.kind {
                VariableKind::Real { .. } => &mut s.real,
                VariableKind::Integer { .. } | VariableKind::Enumeration { .. } => &mut s.integer,
                VariableKind::Boolean { .. } => &mut s.boolean,
                VariableKind::String { .. } => {
                    return Err(self.error(VariableProblem::NotRecordable {
                        name: n.clone(),
                        found: var.kind.type_name(),
                    }))
                }
            };
            group.0.push(var.value_reference);
            group.1.push(pos);
        }
        Ok(s)
    }

    fn inputs(&self, file: Option<&Path>) -> Result<Option<InputTable>, InterfaceError> {
        file.map(|f| InputTable::load(f, self.fmu.description()))
            .transpose()
            .map_err(|e: InputError| self.error(VariableProblem::Inputs(e.to_string())))
    }

    /// Refuses a variable that is given a value before the run (`set`: name and role) and is
    /// also a column of the input file `table`: the file's value would replace it at every
    /// step, silently (every run of a study the same, a Std of 0).
    fn check_not_inputs<'n>(
        &self,
        table: &InputTable,
        set: impl Iterator<Item = (&'n str, &'static str)>,
    ) -> Result<(), InterfaceError> {
        for (name, role) in set {
            if let Some(column) = table.column_for(self.fmu.description(), name) {
                let alias = if column == name {
                    String::new()
                } else {
                    format!(" (as its alias '{column}')")
                };
                return Err(self.error(VariableProblem::Inputs(format!(
                    "'{name}' is {role} and also a column{alias} of the input file {}: the \
                     file's values would replace it at every step of every run. A variable \
                     is either given a value before the run or follows the input file: \
                     remove the column from the file, or '{name}' from the study",
                    table.path.display()
                ))));
            }
        }
        Ok(())
    }

    pub(super) fn check_settable(&self, var: &ScalarVariable) -> Result<(), InterfaceError> {
        if self.fmu.description().settable_before_init(var) {
            return Ok(());
        }
        Err(self.error(VariableProblem::NotSettable {
            name: var.name.clone(),
            causality: var.causality.as_str(),
            variability: var.variability.as_str(),
        }))
    }

    /// Deterministic values by FMI type, each checked against its variable.
    pub(super) fn settings<'n>(
        &self,
        values: impl Iterator<Item = (&'n str, &'n FixedValue)>,
    ) -> Result<Settings, InterfaceError> {
        let mut s = Settings::default();
        for (name, v) in values {
            let var = self.any(name)?;
            self.check_settable(var)?;
            let vr = var.value_reference;
            let found = var.kind.type_name();
            let wrong = |why: &'static str| {
                self.error(VariableProblem::WrongValue {
                    name: name.to_owned(),
                    found,
                    value: v.to_string(),
                    why,
                })
            };
            match (&var.kind, v) {
                (VariableKind::Real { .. }, FixedValue::Number(x)) => s.real.push((vr, *x)),
                (VariableKind::Real { .. }, FixedValue::Text(t)) => {
                    let x: f64 = t.trim().parse().map_err(|_| wrong("is not a number"))?;
                    s.real.push((vr, x));
                }
                (VariableKind::Integer { .. } | VariableKind::Enumeration { .. }, _) => {
                    let x = match v {
                        FixedValue::Number(x) => *x,
                        FixedValue::Text(t) => t
                            .trim()
                            .parse()
                            .map_err(|_| wrong("is not a whole number"))?,
                        FixedValue::Bool(_) => return Err(wrong("is not a whole number")),
                    };
                    let i = to_i32(x).ok_or_else(|| {
                        self.error(VariableProblem::NotWhole {
                            name: name.to_owned(),
                            found,
                            value: x,
                        })
                    })?;
                    let (min, max) = match var.kind {
                        VariableKind::Integer { min, max, .. }
                        | VariableKind::Enumeration { min, max, .. } => (min, max),
                        _ => (None, None),
                    };
                    if min.is_some_and(|lo| i < lo) || max.is_some_and(|hi| i > hi) {
                        return Err(self.error(VariableProblem::OutOfRange {
                            name: name.to_owned(),
                            found,
                            value: i,
                            min,
                            max,
                        }));
                    }
                    s.integer.push((vr, i));
                }
                (VariableKind::Boolean { .. }, _) => {
                    let b = match v {
                        FixedValue::Bool(b) => *b,
                        FixedValue::Number(x) if *x == 0.0 || *x == 1.0 => *x == 1.0,
                        FixedValue::Text(t) => match t.trim().to_ascii_lowercase().as_str() {
                            "true" | "1" => true,
                            "false" | "0" => false,
                            _ => return Err(wrong("is not true/false (or 1/0)")),
                        },
                        _ => return Err(wrong("is not true/false (or 1/0)")),
                    };
                    s.boolean.push((vr, b));
                }
                (VariableKind::String { .. }, FixedValue::Text(t)) => {
                    if t.contains('\0') {
                        return Err(wrong("contains a NUL character"));
                    }
                    s.string.push((vr, t.clone()));
                }
                (VariableKind::String { .. }, _) => {
                    return Err(wrong("is not a text: write it in quotes"))
                }
                (VariableKind::Real { .. }, FixedValue::Bool(_)) => {
                    return Err(wrong("is not a number"))
                }
            }
        }
        Ok(s)
    }
}
