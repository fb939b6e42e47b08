//! Pure-Rust physics of the railuq models. Nothing here knows about FMI or C: each model is a
//! [`Model`] with a static table of [`Variable`]s (the interface the FMI layer exports) and
//! methods to read and write those variables and to advance time.
#![forbid(unsafe_code)]

pub mod bogie;
pub mod data_file;
pub mod table;
pub mod vehicle;
pub mod vehicle_track;
pub mod wheel;

use std::fmt;
use std::path::PathBuf;

/// What a variable is for (maps one-to-one onto FMI 2.0 causality, but carries no FMI types).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Causality {
    /// Set by the user before a run (or between steps if tunable).
    Parameter,
    /// Computed from parameters during initialization.
    CalculatedParameter,
    /// Set by the environment at every step.
    Input,
    /// Computed by the model.
    Output,
    /// Internal value exposed for inspection.
    Local,
}

/// When a variable may change.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Variability {
    /// Never changes.
    Constant,
    /// Fixed after initialization.
    Fixed,
    /// May change between steps; the model takes it into account at the next step.
    Tunable,
    /// Changes only at discrete instants.
    Discrete,
    /// Changes continuously in time.
    Continuous,
}

/// How the start value is to be understood.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Initial {
    /// The start value is the value.
    Exact,
    /// The start value is a guess.
    Approx,
    /// The value is computed at initialization.
    Calculated,
}

/// The value type and start value of a variable.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Start {
    /// Real value, no start.
    Real(Option<f64>),
    /// Integer value.
    Integer(Option<i32>),
    /// Boolean value.
    Boolean(Option<bool>),
    /// String value.
    String(Option<&'static str>),
}

/// Value type of a variable, without its start value.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VarType {
    /// f64
    Real,
    /// i32
    Integer,
    /// bool
    Boolean,
    /// UTF-8 string
    String,
}

/// One entry of a model's variable table.
#[derive(Clone, Copy, Debug)]
pub struct Variable {
    /// Name as seen by the user (unique within the model).
    pub name: &'static str,
    /// Value reference (unique within the model, across all types).
    pub vr: u32,
    /// Type and start value.
    pub start: Start,
    /// Causality.
    pub causality: Causality,
    /// Variability.
    pub variability: Variability,
    /// Initial attribute (None = the FMI default for the causality/variability pair).
    pub initial: Option<Initial>,
    /// SI unit (a name from the unit table of the FMI layer), if any.
    pub unit: Option<&'static str>,
    /// Lower bound, if any (Real only).
    pub min: Option<f64>,
    /// Upper bound, if any (Real only).
    pub max: Option<f64>,
    /// One-line description.
    pub description: &'static str,
}

impl Variable {
    /// A Real parameter with a start value (initial = exact).
    pub const fn real_parameter(
        name: &'static str,
        vr: u32,
        start: f64,
        variability: Variability,
        unit: Option<&'static str>,
        description: &'static str,
    ) -> Variable {
        Variable {
            name,
            vr,
            start: Start::Real(Some(start)),
            causality: Causality::Parameter,
            variability,
            initial: Some(Initial::Exact),
            unit,
            min: None,
            max: None,
            description,
        }
    }

    /// A fixed Integer parameter with a start value.
    pub const fn integer_parameter(
        name: &'static str,
        vr: u32,
        start: i32,
        description: &'static str,
    ) -> Variable {
        Variable::fixed_parameter(name, vr, Start::Integer(Some(start)), description)
    }

    /// A fixed String parameter with a start value.
    pub const fn string_parameter(
        name: &'static str,
        vr: u32,
        start: &'static str,
        description: &'static str,
    ) -> Variable {
        Variable::fixed_parameter(name, vr, Start::String(Some(start)), description)
    }

    /// A fixed parameter with the start value `start` (of any type), no unit and no bounds.
    const fn fixed_parameter(
        name: &'static str,
        vr: u32,
        start: Start,
        description: &'static str,
    ) -> Variable {
        Variable {
            start,
            ..Variable::real_parameter(name, vr, 0.0, Variability::Fixed, None, description)
        }
    }

    /// A continuous Real output (initial calculated by default).
    pub const fn real_output(
        name: &'static str,
        vr: u32,
        unit: Option<&'static str>,
        description: &'static str,
    ) -> Variable {
        Variable {
            name,
            vr,
            start: Start::Real(None),
            causality: Causality::Output,
            variability: Variability::Continuous,
            initial: None,
            unit,
            min: None,
            max: None,
            description,
        }
    }

    /// A Real calculated parameter (fixed, computed at initialization).
    pub const fn calculated_parameter(
        name: &'static str,
        vr: u32,
        unit: Option<&'static str>,
        description: &'static str,
    ) -> Variable {
        Variable {
            causality: Causality::CalculatedParameter,
            variability: Variability::Fixed,
            initial: Some(Initial::Calculated),
            ..Variable::real_output(name, vr, unit, description)
        }
    }

    /// A String calculated parameter (fixed, computed at initialization, no start value):
    /// what the model found out about the machine it runs on, for the record.
    pub const fn calculated_string(
        name: &'static str,
        vr: u32,
        description: &'static str,
    ) -> Variable {
        Variable {
            start: Start::String(None),
            ..Variable::calculated_parameter(name, vr, None, description)
        }
    }

    /// The same variable with a lower bound.
    pub const fn with_min(self, min: Option<f64>) -> Variable {
        Variable { min, ..self }
    }

    /// The same variable with an upper bound.
    pub const fn with_max(self, max: Option<f64>) -> Variable {
        Variable { max, ..self }
    }

    /// The type of the variable.
    pub fn var_type(&self) -> VarType {
        match self.start {
            Start::Real(_) => VarType::Real,
            Start::Integer(_) => VarType::Integer,
            Start::Boolean(_) => VarType::Boolean,
            Start::String(_) => VarType::String,
        }
    }
}

/// Static description of a model: identity, variables, documentation.
#[derive(Debug)]
pub struct ModelInfo {
    /// Model name and FMU model identifier (binary name), e.g. `Wheel`.
    pub name: &'static str,
    /// One-line description.
    pub description: &'static str,
    /// The variable table, sorted by value reference.
    pub variables: &'static [Variable],
    /// Default experiment: start time (s).
    pub default_start: f64,
    /// Default experiment: stop time (s).
    pub default_stop: f64,
    /// Default experiment: communication step (s).
    pub default_step: f64,
    /// HTML fragment with the equations and notes (goes into `documentation/index.html`).
    pub documentation_html: &'static str,
}

impl ModelInfo {
    /// Looks a variable up by value reference.
    pub fn variable(&self, vr: u32) -> Option<&'static Variable> {
        self.variables
            .binary_search_by_key(&vr, |v| v.vr)
            .ok()
            .map(|i| &self.variables[i])
    }

    /// Looks a variable up by name.
    pub fn variable_by_name(&self, name: &str) -> Option<&'static Variable> {
        self.variables.iter().find(|v| v.name == name)
    }

    /// The error refusing `value` for the variable `vr` (named `?` if unknown) for `reason`.
    pub fn invalid(&self, vr: u32, value: impl ToString, reason: impl Into<String>) -> ModelError {
        ModelError::invalid(self.variable(vr).map_or("?", |v| v.name), value, reason)
    }
}

/// An error reported by a model; the FMI layer turns it into a status and a log line.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ModelError {
    /// A parameter value is outside its legal range.
    #[error("invalid value {value} for '{name}': {reason}")]
    InvalidValue {
        /// Variable name.
        name: &'static str,
        /// Offending value.
        value: String,
        /// Why it is refused.
        reason: String,
    },
    /// The solution became non-finite or otherwise broke down.
    #[error("solver failure at t = {time} s: {reason}")]
    SolverFailure {
        /// Time at which it happened (s).
        time: f64,
        /// What went wrong.
        reason: String,
    },
    /// The value reference is not one the model handles for this type.
    #[error("no {0:?} variable with value reference {1}")]
    NoSuchVariable(VarType, u32),
    /// A step that needs too many internal substeps (refused before any work).
    #[error("{0}")]
    StepTooLong(#[from] crate::solver::TooManySubsteps),
    /// A serialized state could not be read.
    #[error("corrupt model state: {0}")]
    CorruptState(String),
    /// The model cannot take the step and the simulation ends at its current time (fmi2DoStep
    /// returns fmi2Discard, fmi2Terminated becomes true, fmi2LastSuccessfulTime stays the
    /// current time; the outputs there stay valid).
    #[error("the simulation ends at t = {time} s: {reason}")]
    EndOfSimulation {
        /// The last time reached (s).
        time: f64,
        /// Why the model cannot go on.
        reason: String,
    },
    /// Any other failure (file not found, bad resource, …).
    #[error("{0}")]
    Other(String),
}

impl ModelError {
    /// `value` refused for the variable `name`, for `reason`.
    pub fn invalid(name: &'static str, value: impl ToString, reason: impl Into<String>) -> Self {
        ModelError::InvalidValue {
            name,
            value: value.to_string(),
            reason: reason.into(),
        }
    }
}

/// Result of setting a variable: accepted, or accepted with a warning to log.
pub type SetResult = Result<Option<String>, ModelError>;

/// Environment of an initialization.
#[derive(Debug, Clone, Default)]
pub struct InitContext {
    /// Start time (s).
    pub start_time: f64,
    /// Folder of the FMU's resources, if the importer gave one.
    pub resource_dir: Option<PathBuf>,
}

/// A simulation model. Implementations are pure Rust (no FMI types, no unsafe).
///
/// Protocol: the host constructs the model with its default parameters, sets variables,
/// calls [`Model::initialize`] (possibly several times while parameters are still being set),
/// then [`Model::do_step`] repeatedly.
pub trait Model: Send + fmt::Debug + CloneModel {
    /// The static description of this model.
    fn info(&self) -> &'static ModelInfo;
    /// Reads a Real variable (the caller has checked that `vr` is a Real of this model).
    fn get_real(&self, vr: u32) -> Result<f64, ModelError>;
    /// Writes a Real variable; returns an optional warning.
    fn set_real(&mut self, vr: u32, value: f64) -> SetResult;
    /// Reads an Integer variable.
    fn get_integer(&self, vr: u32) -> Result<i32, ModelError> {
        Err(ModelError::NoSuchVariable(VarType::Integer, vr))
    }
    /// Writes an Integer variable.
    fn set_integer(&mut self, vr: u32, _value: i32) -> SetResult {
        Err(ModelError::NoSuchVariable(VarType::Integer, vr))
    }
    /// Reads a Boolean variable.
    fn get_boolean(&self, vr: u32) -> Result<bool, ModelError> {
        Err(ModelError::NoSuchVariable(VarType::Boolean, vr))
    }
    /// Writes a Boolean variable.
    fn set_boolean(&mut self, vr: u32, _value: bool) -> SetResult {
        Err(ModelError::NoSuchVariable(VarType::Boolean, vr))
    }
    /// Reads a String variable.
    fn get_string(&self, vr: u32) -> Result<String, ModelError> {
        Err(ModelError::NoSuchVariable(VarType::String, vr))
    }
    /// Writes a String variable.
    fn set_string(&mut self, vr: u32, _value: &str) -> SetResult {
        Err(ModelError::NoSuchVariable(VarType::String, vr))
    }
    /// Computes the initial state from the parameters at `ctx.start_time`.
    fn initialize(&mut self, ctx: &InitContext) -> Result<(), ModelError>;
    /// Advances the state from `t` (s) by `h` (s) > 0.
    fn do_step(&mut self, t: f64, h: f64) -> Result<(), ModelError>;
    /// Appends the complete model state (parameters and dynamic state) to `out`.
    fn save(&self, out: &mut StateWriter);
    /// Restores what [`Model::save`] wrote.
    fn restore(&mut self, input: &mut StateReader<'_>) -> Result<(), ModelError>;
}

/// A deep copy of a model behind the [`Model`] trait (for FMU state snapshots): every model
/// that is `Clone` has it.
pub trait CloneModel {
    /// A deep copy.
    fn clone_box(&self) -> Box<dyn Model>;
}

impl<M: Model + Clone + 'static> CloneModel for M {
    fn clone_box(&self) -> Box<dyn Model> {
        Box::new(self.clone())
    }
}

/// Little-endian writer for [`Model::save`].
#[derive(Debug, Default)]
pub struct StateWriter {
    /// The bytes written so far.
    pub bytes: Vec<u8>,
}

impl StateWriter {
    /// Appends an f64.
    pub fn f64(&mut self, v: f64) {
        self.bytes.extend_from_slice(&v.to_le_bytes());
    }
    /// Appends a u64.
    pub fn u64(&mut self, v: u64) {
        self.bytes.extend_from_slice(&v.to_le_bytes());
    }
    /// Appends a slice of f64 with its length.
    pub fn f64s(&mut self, v: &[f64]) {
        self.u64(v.len() as u64);
        for x in v {
            self.f64(*x);
        }
    }
    /// Appends a string with its length.
    pub fn str(&mut self, s: &str) {
        self.u64(s.len() as u64);
        self.bytes.extend_from_slice(s.as_bytes());
    }
}

/// Reader matching [`StateWriter`]; every read checks the remaining length.
#[derive(Debug)]
pub struct StateReader<'a> {
    bytes: &'a [u8],
}

impl<'a> StateReader<'a> {
    /// Reads from `bytes`.
    pub fn new(bytes: &'a [u8]) -> Self {
        Self { bytes }
    }
    fn take(&mut self, n: usize) -> Result<&'a [u8], ModelError> {
        if self.bytes.len() < n {
            return Err(ModelError::CorruptState(format!(
                "truncated: wanted {n} bytes, {} left",
                self.bytes.len()
            )));
        }
        let (head, tail) = self.bytes.split_at(n);
        self.bytes = tail;
        Ok(head)
    }
    /// Reads an f64.
    pub fn f64(&mut self) -> Result<f64, ModelError> {
        let b = self.take(8)?;
        Ok(f64::from_le_bytes(b.try_into().expect("8 bytes")))
    }
    /// Reads a u64.
    pub fn u64(&mut self) -> Result<u64, ModelError> {
        let b = self.take(8)?;
        Ok(u64::from_le_bytes(b.try_into().expect("8 bytes")))
    }
    /// Reads a length-prefixed slice of f64 of exactly `expected` elements (if given).
    pub fn f64s(&mut self, expected: Option<usize>) -> Result<Vec<f64>, ModelError> {
        let n = self.u64()? as usize;
        if let Some(e) = expected {
            if n != e {
                return Err(ModelError::CorruptState(format!(
                    "expected {e} values, found {n}"
                )));
            }
        }
        if n > self.bytes.len() / 8 {
            return Err(ModelError::CorruptState("length beyond end of data".into()));
        }
        (0..n).map(|_| self.f64()).collect()
    }
    /// Reads a length-prefixed string.
    pub fn str(&mut self) -> Result<String, ModelError> {
        let n = self.u64()? as usize;
        let b = self.take(n)?;
        String::from_utf8(b.to_vec()).map_err(|e| ModelError::CorruptState(e.to_string()))
    }
    /// Bytes not read yet.
    pub fn remaining(&self) -> usize {
        self.bytes.len()
    }
}

/// A model constructor and its static description.
#[derive(Debug)]
pub struct ModelEntry {
    /// Static description.
    pub info: &'static ModelInfo,
    /// Builds a model with default parameters.
    pub create: fn() -> Box<dyn Model>,
}

/// Every model this library serves.
pub fn registry() -> &'static [ModelEntry] {
    static REGISTRY: [ModelEntry; 4] = [
        ModelEntry {
            info: &wheel::INFO,
            create: wheel::Wheel::boxed,
        },
        ModelEntry {
            info: &bogie::INFO,
            create: bogie::Bogie::boxed,
        },
        ModelEntry {
            info: &vehicle_track::INFO,
            create: vehicle_track::VehicleTrack::boxed,
        },
        ModelEntry {
            info: &vehicle::INFO,
            create: vehicle::Vehicle::boxed,
        },
    ];
    &REGISTRY
}

/// Checks that a parameter value is finite.
pub fn require_finite(name: &'static str, value: f64) -> Result<(), ModelError> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(ModelError::invalid(name, value, "must be finite"))
    }
}

/// Checks that a parameter value is finite and strictly positive.
pub fn require_positive(name: &'static str, value: f64) -> Result<(), ModelError> {
    require_finite(name, value)?;
    if value > 0.0 {
        Ok(())
    } else {
        Err(ModelError::invalid(name, value, "must be > 0"))
    }
}

/// Checks that a parameter value is finite and non-negative.
pub fn require_non_negative(name: &'static str, value: f64) -> Result<(), ModelError> {
    require_finite(name, value)?;
    if value >= 0.0 {
        Ok(())
    } else {
        Err(ModelError::invalid(name, value, "must be >= 0"))
    }
}

/// Asserts that the variable table of `info` is sorted by value reference (each used once)
/// and that no two variables share a name.
#[cfg(test)]
pub(crate) fn assert_table_sorted_and_unique(info: &ModelInfo) {
    let vars = info.variables;
    for w in vars.windows(2) {
        assert!(
            w[0].vr < w[1].vr,
            "{}: vr not sorted at {} / {}",
            info.name,
            w[0].name,
            w[1].name
        );
    }
    let mut names: Vec<_> = vars.iter().map(|v| v.name).collect();
    names.sort_unstable();
    names.dedup();
    assert_eq!(names.len(), vars.len(), "{}: duplicate names", info.name);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_registered_table_is_sorted_and_unique() {
        for entry in registry() {
            assert_table_sorted_and_unique(entry.info);
        }
    }

    #[test]
    fn state_reader_rejects_truncation() {
        let mut w = StateWriter::default();
        w.f64s(&[1.0, 2.0]);
        let mut r = StateReader::new(&w.bytes[..w.bytes.len() - 1]);
        assert!(r.f64s(Some(2)).is_err());
        let mut r = StateReader::new(&w.bytes);
        assert!(r.f64s(Some(3)).is_err());
        let mut r = StateReader::new(&w.bytes);
        assert_eq!(r.f64s(Some(2)).unwrap(), vec![1.0, 2.0]);
    }
}
