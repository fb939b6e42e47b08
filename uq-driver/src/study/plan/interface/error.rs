//! Why a study variable does not fit the FMU: [`InterfaceError`] and its [`VariableProblem`].

use std::path::PathBuf;

/// Why a fixed value does not fit an Integer: a fraction, or a whole number beyond 32 bits.
fn not_whole_why(value: f64) -> &'static str {
    if value.is_finite() && value.fract() == 0.0 {
        "is outside the 32-bit range of an FMI Integer (-2147483648 to 2147483647)"
    } else {
        "is not a whole number"
    }
}

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
    #[error("the FMU ({model}) has no variable named '{name}'")]
    Unknown {
        /// The name.
        name: String,
        /// The FMU's model name.
        model: String,
    },
    /// A random parameter of a type that cannot take a design value.
    #[error(
        "variable '{name}' is a {found}; random parameters must be Real, Integer or Enumeration \
         variables"
    )]
    NotRandomizable {
        /// The variable.
        name: String,
        /// Its type.
        found: &'static str,
    },
    /// A String variable named as an output.
    #[error(
        "variable '{name}' is a {found}; only Real, Integer, Enumeration and Boolean variables \
         can be recorded"
    )]
    NotRecordable {
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
    #[error("'{name}' is an {found}; {value} {}", not_whole_why(*.value))]
    NotWhole {
        /// The variable.
        name: String,
        /// Its type (Integer or Enumeration).
        found: &'static str,
        /// The value.
        value: f64,
    },
    /// A whole number given for a variable (`[fixed]`, `simulate --set`) outside the
    /// `min`/`max` the modelDescription declares.
    #[error(
        "'{name}' is an {found} declared with {} in the modelDescription; the value {value} \
         given for it is outside that range",
        declared_range(*.min, *.max)
    )]
    OutOfRange {
        /// The variable.
        name: String,
        /// Its type (Integer or Enumeration).
        found: &'static str,
        /// The value.
        value: i32,
        /// Declared `min`.
        min: Option<i32>,
        /// Declared `max`.
        max: Option<i32>,
    },
    /// A grid with a shorter last step for an FMU that cannot vary its communication step.
    #[error(
        "the FMU declares canHandleVariableCommunicationStepSize=\"false\", but stop - start is \
         not a whole number of steps of {step} s, so the last step would be {last} s: give a stop \
         time of {whole} or {next} s"
    )]
    FixedStepOnly {
        /// The step (s).
        step: f64,
        /// The shorter last step (s).
        last: f64,
        /// The last whole step's end (s).
        whole: f64,
        /// One step further (s).
        next: f64,
    },
    /// A design value that is not a whole number for an Integer or Enumeration random
    /// parameter.
    #[error(
        "random parameter '{name}' is an {found} variable, but the design has the value {value}, \
         which is not a whole number (32-bit): give it a distribution with whole-number values \
         (e.g. integer_uniform)"
    )]
    RandomNotWhole {
        /// The variable.
        name: String,
        /// Its type (Integer or Enumeration).
        found: &'static str,
        /// The value.
        value: f64,
    },
    /// A value that does not fit the variable's type.
    #[error("'{name}' is a {found}; {value} {why}")]
    WrongValue {
        /// The variable.
        name: String,
        /// Its type.
        found: &'static str,
        /// The value as given.
        value: String,
        /// What was expected.
        why: &'static str,
    },
    /// The input signals do not fit.
    #[error("{0}")]
    Inputs(String),
    /// A random parameter's distribution lies wholly outside its variable's declared range.
    #[error("{0}")]
    SupportOutsideRange(String),
    /// A quantity's settings do not fit the FMU or the study.
    #[error("quantity '{name}': {problem}")]
    Quantity {
        /// The quantity.
        name: String,
        /// What does not fit.
        problem: String,
    },
}

/// "min = 1, max = 4" (or only the bound that is declared).
fn declared_range(min: Option<i32>, max: Option<i32>) -> String {
    match (min, max) {
        (Some(lo), Some(hi)) => format!("min = {lo}, max = {hi}"),
        (Some(lo), None) => format!("min = {lo}"),
        (None, Some(hi)) => format!("max = {hi}"),
        (None, None) => "no range".to_owned(),
    }
}
