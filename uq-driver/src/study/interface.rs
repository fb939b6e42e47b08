//! The study's variables resolved against the FMU: which value references the runner sets
//! (random and fixed parameters) and reads (outputs and the signals of the quantities).

use std::path::PathBuf;

use crate::fmu::{Fmu, ScalarVariable, VariableKind};
use crate::qoi::QoiSpec;
use crate::spec::Study;

/// A study variable that does not fit the FMU.
#[derive(Debug, thiserror::Error)]
#[error("{}: {problem}", fmu.display())]
pub struct InterfaceError {
    /// The FMU.
    pub fmu: PathBuf,
    /// What does not fit.
    pub problem: VariableProblem,
}

/// What does not fit.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum VariableProblem {
    /// No such variable.
    #[error("the study names variable '{name}', which the FMU ({model}) does not have")]
    Unknown {
        /// The name.
        name: String,
        /// The FMU's model name.
        model: String,
    },
    /// Not a Real.
    #[error("variable '{name}' is a {found}, not a Real")]
    NotReal {
        /// The variable.
        name: String,
        /// Its type.
        found: &'static str,
    },
    /// It may not be set before initialization.
    #[error(
        "variable '{name}' (causality {causality}, variability {variability}) may not be set \
         before initialization, so a study cannot set it"
    )]
    NotSettable {
        /// The variable.
        name: String,
        /// Its causality.
        causality: &'static str,
        /// Its variability.
        variability: &'static str,
    },
    /// A fractional value for an Integer.
    #[error("'{name}' is an Integer; {value} is not a whole number")]
    NotWhole {
        /// The variable.
        name: String,
        /// The value.
        value: f64,
    },
    /// A type that cannot be set from a number.
    #[error("'{name}' is a {found}; only Real and Integer values can be set")]
    NotNumeric {
        /// The variable.
        name: String,
        /// Its type.
        found: &'static str,
    },
}

/// Value references resolved against the FMU.
#[derive(Clone, Debug)]
pub struct Interface {
    /// Random parameters, in study order.
    pub random: Vec<u32>,
    /// Fixed Real parameters (name order) and values.
    pub fixed: Vec<(u32, f64)>,
    /// Fixed Integer parameters (e.g. a spectrum or seed number).
    pub fixed_int: Vec<(u32, i32)>,
    /// Every variable read at each communication point: the outputs, then the signals the
    /// quantities of interest need.
    pub signals: Vec<u32>,
    /// Their names.
    pub signal_names: Vec<String>,
    /// Number of leading signals that are stored as time series (the study's outputs).
    pub n_stored: usize,
    /// Scalar quantities of interest.
    pub qois: Vec<QoiSpec>,
}

impl Interface {
    /// Values recorded per successful point: stored series, then (value, code) per quantity.
    pub fn n_values(&self, n_times: usize) -> usize {
        self.n_stored * n_times + 2 * self.qois.len()
    }

    /// Checks the study's variables against the FMU and resolves their value references.
    pub fn resolve(study: &Study, fmu: &Fmu) -> Result<Interface, InterfaceError> {
        let vars = Variables { fmu };
        let random = study
            .parameters
            .iter()
            .map(|p| {
                let var = vars.real(&p.name)?;
                vars.check_settable(var)?;
                Ok(var.value_reference)
            })
            .collect::<Result<_, InterfaceError>>()?;
        let (fixed, fixed_int) = vars.fixed(study.fixed.iter().map(|(n, v)| (n.as_str(), *v)))?;
        let mut signal_names = study.outputs.clone();
        for s in study.qoi.iter().flat_map(QoiSpec::signals) {
            if !signal_names.iter().any(|n| n == s) {
                signal_names.push(s.to_owned());
            }
        }
        Ok(Interface {
            random,
            fixed,
            fixed_int,
            signals: vars.reals(&signal_names)?,
            signal_names,
            n_stored: study.outputs.len(),
            qois: study.qoi.clone(),
        })
    }

    /// The interface of one deterministic run: `params` set before initialization,
    /// `outputs` read (every Real output of the FMU when empty).
    pub fn for_run(
        fmu: &Fmu,
        params: &[(String, f64)],
        outputs: &[String],
    ) -> Result<Interface, InterfaceError> {
        let vars = Variables { fmu };
        let names: Vec<String> = if outputs.is_empty() {
            fmu.description()
                .output_variables()
                .filter(|v| matches!(v.kind, VariableKind::Real { .. }))
                .map(|v| v.name.clone())
                .collect()
        } else {
            outputs.to_vec()
        };
        let (fixed, fixed_int) = vars.fixed(params.iter().map(|(n, v)| (n.as_str(), *v)))?;
        Ok(Interface {
            random: Vec::new(),
            fixed,
            fixed_int,
            signals: vars.reals(&names)?,
            n_stored: names.len(),
            signal_names: names,
            qois: Vec::new(),
        })
    }
}

/// Lookups of study variables in one FMU, with errors that name it.
struct Variables<'a> {
    fmu: &'a Fmu,
}

impl<'a> Variables<'a> {
    fn error(&self, problem: VariableProblem) -> InterfaceError {
        InterfaceError {
            fmu: self.fmu.path().to_path_buf(),
            problem,
        }
    }

    fn any(&self, name: &str) -> Result<&'a ScalarVariable, InterfaceError> {
        let md = self.fmu.description();
        md.variable(name).ok_or_else(|| {
            self.error(VariableProblem::Unknown {
                name: name.to_owned(),
                model: md.model_name.clone(),
            })
        })
    }

    fn real(&self, name: &str) -> Result<&'a ScalarVariable, InterfaceError> {
        let var = self.any(name)?;
        if !matches!(var.kind, VariableKind::Real { .. }) {
            return Err(self.error(VariableProblem::NotReal {
                name: name.to_owned(),
                found: var.kind.type_name(),
            }));
        }
        Ok(var)
    }

    /// Value references of Real variables.
    fn reals(&self, names: &[String]) -> Result<Vec<u32>, InterfaceError> {
        names
            .iter()
            .map(|n| Ok(self.real(n)?.value_reference))
            .collect()
    }

    fn check_settable(&self, var: &ScalarVariable) -> Result<(), InterfaceError> {
        if self.fmu.description().settable_before_init(var) {
            return Ok(());
        }
        Err(self.error(VariableProblem::NotSettable {
            name: var.name.clone(),
            causality: var.causality.as_str(),
            variability: var.variability.as_str(),
        }))
    }

    /// Splits deterministic values into Real and Integer settings, checking each variable.
    fn fixed<'n>(
        &self,
        values: impl Iterator<Item = (&'n str, f64)>,
    ) -> Result<FixedValues, InterfaceError> {
        let mut reals = Vec::new();
        let mut ints = Vec::new();
        for (name, v) in values {
            let var = self.any(name)?;
            self.check_settable(var)?;
            match var.kind {
                VariableKind::Real { .. } => reals.push((var.value_reference, v)),
                VariableKind::Integer { .. } | VariableKind::Enumeration { .. } => {
                    if v.fract() != 0.0 || v.abs() > f64::from(i32::MAX) {
                        return Err(self.error(VariableProblem::NotWhole {
                            name: name.to_owned(),
                            value: v,
                        }));
                    }
                    ints.push((var.value_reference, v as i32));
                }
                _ => {
                    return Err(self.error(VariableProblem::NotNumeric {
                        name: name.to_owned(),
                        found: var.kind.type_name(),
                    }))
                }
            }
        }
        Ok((reals, ints))
    }
}

/// Deterministic settings: (value reference, value) for Reals and for Integers.
type FixedValues = (Vec<(u32, f64)>, Vec<(u32, i32)>);
