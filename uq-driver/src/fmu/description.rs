//! `modelDescription.xml` of an FMI 2.0 Co-Simulation FMU, parsed into typed structs.
//!
//! Only what an importer needs is kept: the header attributes, the Co-Simulation capabilities,
//! the default experiment, units, log categories, the scalar variables and the list of outputs.
//! Defaults follow the FMI 2.0 standard (causality `local`, variability `continuous` for Real
//! variables; see [`ScalarVariable`] for the others).

mod parse;
mod text;

/// Why a `modelDescription.xml` could not be accepted. Lines and columns are 1-based.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum DescriptionError {
    /// The document is not well-formed XML.
    #[error("malformed XML at line {line}, column {column}: {reason}")]
    Malformed {
        /// Line of the error.
        line: usize,
        /// Column (in bytes) of the error.
        column: usize,
        /// What is wrong.
        reason: String,
    },
    /// `fmiVersion` is not `"2.0"`.
    #[error("unsupported FMI version \"{found}\" (expected \"2.0\")")]
    UnsupportedFmiVersion {
        /// The `fmiVersion` attribute found.
        found: String,
    },
    /// The description has no `CoSimulation` element.
    #[error("no CoSimulation element{}", if *.model_exchange_present { " (Model Exchange only)" } else { "" })]
    NoCoSimulation {
        /// Whether a `ModelExchange` element is present.
        model_exchange_present: bool,
    },
    /// The root element is not `fmiModelDescription`.
    #[error("line {line}: the root element is <{found}>, expected <fmiModelDescription>")]
    WrongRoot {
        /// The root element found.
        found: String,
        /// Its line.
        line: usize,
    },
    /// A required attribute is missing.
    #[error("line {line}: <{element}> has no {attribute} attribute")]
    MissingAttribute {
        /// The element.
        element: String,
        /// The attribute.
        attribute: &'static str,
        /// The element's line.
        line: usize,
    },
    /// An attribute has a value that FMI 2.0 does not allow.
    #[error("line {line}: <{element}> has invalid {attribute}=\"{value}\" ({expected})")]
    InvalidAttribute {
        /// The element.
        element: String,
        /// The attribute.
        attribute: String,
        /// The value found.
        value: String,
        /// What was expected.
        expected: String,
        /// The element's line.
        line: usize,
    },
    /// An element that may appear once appears again.
    #[error("line {line}: more than one <{element}> element")]
    Repeated {
        /// The element.
        element: String,
        /// The line of the second one.
        line: usize,
    },
    /// A `ScalarVariable` has no type element (`Real`, `Integer`, ...), or more than one.
    #[error("line {line}: variable '{name}' must have exactly one type element (Real, Integer, Boolean, String or Enumeration)")]
    BadTypeElement {
        /// The variable.
        name: String,
        /// The variable's line.
        line: usize,
    },
    /// Two variables have the same name.
    #[error("duplicate variable name '{name}'")]
    DuplicateName {
        /// The name.
        name: String,
    },
    /// Two variables of the same base type share a value reference but are not valid aliases
    /// (FMI 2.0 allows aliases, but at most one per alias set may have a start value, and at
    /// most one may be a parameter or an input).
    #[error(
        "variables '{first}' and '{second}' share the {base_type} value reference \
         {value_reference} but cannot be aliases: {reason}"
    )]
    DuplicateValueReference {
        /// The base type (Real, Integer, Boolean or String; Enumeration counts as Integer).
        base_type: &'static str,
        /// The shared value reference.
        value_reference: u32,
        /// The first variable.
        first: String,
        /// The second variable.
        second: String,
        /// Why they cannot be aliases.
        reason: &'static str,
    },
    /// `ModelStructure/Outputs/Unknown` refers to a variable that does not exist.
    #[error(
        "ModelStructure/Outputs refers to variable index {index}, but there are {count} variables"
    )]
    BadOutputIndex {
        /// The 1-based index found.
        index: usize,
        /// The number of variables.
        count: usize,
    },
    /// `ModelStructure/Outputs` does not list exactly the variables with causality
    /// `"output"` (FMI 2.0, section 2.2.8): this one is an output it does not list, or it
    /// lists this one, which is not an output.
    #[error("{}", outputs_mismatch(name, *.index, causality))]
    OutputsMismatch {
        /// The variable.
        name: String,
        /// Its 1-based index among the variables.
        index: usize,
        /// Its causality.
        causality: &'static str,
    },
    /// The file is larger than [`ParseLimits::max_bytes`].
    #[error(
        "the file is {size} bytes, more than the limit of {limit} bytes for modelDescription.xml"
    )]
    TooLarge {
        /// Size of the file, in bytes.
        size: usize,
        /// The limit, in bytes.
        limit: usize,
    },
    /// Elements are nested deeper than [`ParseLimits::max_depth`].
    #[error(
        "line {line}: elements nested more than {limit} deep (the limit on the nesting depth \
         of modelDescription.xml)"
    )]
    TooDeep {
        /// Line of the first element beyond the limit.
        line: usize,
        /// The limit (the root element is at depth 1).
        limit: usize,
    },
    /// The file is not UTF-8 (FMI 2.0 requires UTF-8).
    #[error("the file is not UTF-8: {found}; FMI 2.0 requires modelDescription.xml in UTF-8")]
    NotUtf8 {
        /// What was found instead, e.g. `it is UTF-16 (little-endian byte-order mark)`.
        found: String,
    },
}

/// The message of [`DescriptionError::OutputsMismatch`].
fn outputs_mismatch(name: &str, index: usize, causality: &str) -> String {
    let rule = "FMI 2.0 requires ModelStructure/Outputs to list exactly the variables with \
                causality=\"output\"";
    if causality == "output" {
        format!(
            "variable '{name}' (index {index}) has causality=\"output\", but \
             ModelStructure/Outputs does not list it; {rule}"
        )
    } else {
        format!(
            "ModelStructure/Outputs lists variable '{name}' (index {index}), whose causality \
             is \"{causality}\", not \"output\"; {rule}"
        )
    }
}

/// Limits that protect parsing against hostile or broken files.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ParseLimits {
    /// Largest accepted file, in bytes.
    pub max_bytes: usize,
    /// Deepest accepted element nesting (the root element is at depth 1).
    pub max_depth: usize,
}

impl ParseLimits {
    /// Default [`ParseLimits::max_bytes`]: 256 MiB, far above the tens of MB of FMUs with
    /// 10^5 variables.
    pub const DEFAULT_MAX_BYTES: usize = 256 << 20;
    /// Default [`ParseLimits::max_depth`]: 256, as libxml2 without `XML_PARSE_HUGE` (fmpy,
    /// through lxml, also accepts 256 levels and refuses 257); FMI 2.0 itself nests 5 levels,
    /// tool annotations a few more.
    pub const DEFAULT_MAX_DEPTH: usize = 256;
}

impl Default for ParseLimits {
    /// [`ParseLimits::DEFAULT_MAX_BYTES`] and [`ParseLimits::DEFAULT_MAX_DEPTH`].
    fn default() -> Self {
        ParseLimits {
            max_bytes: Self::DEFAULT_MAX_BYTES,
            max_depth: Self::DEFAULT_MAX_DEPTH,
        }
    }
}

/// The parsed `modelDescription.xml` of an FMI 2.0 Co-Simulation FMU.
#[derive(Clone, Debug, PartialEq)]
pub struct ModelDescription {
    /// Always `"2.0"`.
    pub fmi_version: String,
    /// `modelName`.
    pub model_name: String,
    /// `guid`, passed to `fmi2Instantiate`.
    pub guid: String,
    /// `description`.
    pub description: Option<String>,
    /// `generationTool`.
    pub generation_tool: Option<String>,
    /// `variableNamingConvention` (default flat).
    pub variable_naming_convention: VariableNamingConvention,
    /// `numberOfEventIndicators`.
    pub number_of_event_indicators: Option<u32>,
    /// The Co-Simulation capabilities. Always present: [`ModelDescription::parse`] refuses a
    /// description without a `CoSimulation` element.
    pub co_simulation: CoSimulation,
    /// Whether the FMU also implements Model Exchange.
    pub model_exchange_present: bool,
    /// `DefaultExperiment`, if any.
    pub default_experiment: Option<DefaultExperiment>,
    /// `UnitDefinitions`.
    pub unit_definitions: Vec<Unit>,
    /// The `unit` of each Real `SimpleType` of `TypeDefinitions` that has one: (type name,
    /// unit). A Real variable with this `declaredType` and no `unit` of its own has this unit.
    pub type_units: Vec<(String, String)>,
    /// `LogCategories`: (name, description).
    pub log_categories: Vec<(String, Option<String>)>,
    /// `ModelVariables`, in document order (index `i` is the variable `i + 1` of `ModelStructure`).
    pub variables: Vec<ScalarVariable>,
    /// 1-based indices into `variables` from `ModelStructure/Outputs`.
    pub outputs: Vec<usize>,
    /// Variable positions by name, built on the first [`ModelDescription::variable`] call.
    pub(crate) by_name: NameIndex,
}

/// A cache of variable positions by name: looking up every variable of a large FMU by name
/// is linear, not quadratic. Equal, cloned and shown as nothing (it is derived data).
#[derive(Default)]
pub(crate) struct NameIndex(std::sync::OnceLock<std::collections::HashMap<String, usize>>);

impl Clone for NameIndex {
    fn clone(&self) -> Self {
        NameIndex::default()
    }
}

impl PartialEq for NameIndex {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

impl std::fmt::Debug for NameIndex {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("NameIndex")
    }
}

/// `variableNamingConvention`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum VariableNamingConvention {
    /// Any string (the default).
    #[default]
    Flat,
    /// Hierarchical names such as `a.b[2].c`.
    Structured,
}

/// The attributes of the `CoSimulation` element. Flags default to `false`.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct CoSimulation {
    /// Prefix of the binary's file name (`binaries/<platform>/<modelIdentifier>.so`).
    pub model_identifier: String,
    /// `needsExecutionTool`.
    pub needs_execution_tool: bool,
    /// `canHandleVariableCommunicationStepSize`.
    pub can_handle_variable_communication_step_size: bool,
    /// `canInterpolateInputs`.
    pub can_interpolate_inputs: bool,
    /// `maxOutputDerivativeOrder` (default 0).
    pub max_output_derivative_order: u32,
    /// `canRunAsynchronuously` (sic, as spelled by FMI 2.0).
    pub can_run_asynchronuously: bool,
    /// `canBeInstantiatedOnlyOncePerProcess`.
    pub can_be_instantiated_only_once_per_process: bool,
    /// `canNotUseMemoryManagementFunctions`.
    pub can_not_use_memory_management_functions: bool,
    /// `canGetAndSetFMUstate`.
    pub can_get_and_set_fmu_state: bool,
    /// `canSerializeFMUstate`.
    pub can_serialize_fmu_state: bool,
    /// `providesDirectionalDerivative`.
    pub provides_directional_derivative: bool,
}

/// `DefaultExperiment`: times in seconds.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DefaultExperiment {
    /// `startTime` (s).
    pub start_time: Option<f64>,
    /// `stopTime` (s).
    pub stop_time: Option<f64>,
    /// `tolerance` (relative).
    pub tolerance: Option<f64>,
    /// `stepSize` (s): the suggested communication step.
    pub step_size: Option<f64>,
}

/// A unit of `UnitDefinitions`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Unit {
    /// The unit's name, e.g. `m/s2`.
    pub name: String,
}

/// `causality` of a variable (default `local`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Causality {
    /// Set by the environment before initialization (and during the run if tunable).
    Parameter,
    /// Computed from parameters during initialization.
    CalculatedParameter,
    /// Set by the environment at communication points.
    Input,
    /// Read by the environment.
    Output,
    /// Internal.
    #[default]
    Local,
    /// The independent variable (time).
    Independent,
}

/// `variability` of a variable (default `continuous`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Variability {
    /// Never changes.
    Constant,
    /// Fixed after initialization.
    Fixed,
    /// Changes only at communication points (or events), when set by the environment.
    Tunable,
    /// Changes only at events.
    Discrete,
    /// May change at any time (Real variables only).
    #[default]
    Continuous,
}

/// `initial` of a variable.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Initial {
    /// Initialized with the start value.
    Exact,
    /// The start value is a guess for an iteration.
    Approx,
    /// Computed during initialization.
    Calculated,
}

/// A `ScalarVariable`.
#[derive(Clone, Debug, PartialEq)]
pub struct ScalarVariable {
    /// Unique name.
    pub name: String,
    /// Handle used by `fmi2Get*`/`fmi2Set*`; unique per base type except for aliases.
    pub value_reference: u32,
    /// `description`.
    pub description: Option<String>,
    /// `causality`.
    pub causality: Causality,
    /// `variability`. If the attribute is absent: continuous for Real, discrete for the others
    /// (FMI 2.0 allows continuous only for Real).
    pub variability: Variability,
    /// `initial` as written; see [`ScalarVariable::effective_initial`] for the default.
    pub initial: Option<Initial>,
    /// Type and type-specific attributes.
    pub kind: VariableKind,
}

/// The type element of a variable, with its attributes.
#[derive(Clone, Debug, PartialEq)]
pub enum VariableKind {
    /// `Real` (`fmi2Real`, a C `double`).
    Real {
        /// `start`.
        start: Option<f64>,
        /// `unit`.
        unit: Option<String>,
        /// `declaredType`.
        declared_type: Option<String>,
        /// `min`.
        min: Option<f64>,
        /// `max`.
        max: Option<f64>,
        /// `nominal`.
        nominal: Option<f64>,
    },
    /// `Integer` (`fmi2Integer`, a C `int`).
    Integer {
        /// `start`.
        start: Option<i32>,
        /// `min`.
        min: Option<i32>,
        /// `max`.
        max: Option<i32>,
    },
    /// `Boolean` (`fmi2Boolean`, a C `int`).
    Boolean {
        /// `start`.
        start: Option<bool>,
    },
    /// `String` (`fmi2String`).
    String {
        /// `start`.
        start: Option<String>,
    },
    /// `Enumeration` (accessed as `fmi2Integer`).
    Enumeration {
        /// `start`.
        start: Option<i32>,
        /// `declaredType` (required by FMI 2.0).
        declared_type: String,
        /// `min` (on the variable; the type's item range is not read).
        min: Option<i32>,
        /// `max` (on the variable).
        max: Option<i32>,
    },
}

impl VariableKind {
    /// The type element's name: `Real`, `Integer`, `Boolean`, `String` or `Enumeration`.
    pub fn type_name(&self) -> &'static str {
        match self {
            VariableKind::Real { .. } => "Real",
            VariableKind::Integer { .. } => "Integer",
            VariableKind::Boolean { .. } => "Boolean",
            VariableKind::String { .. } => "String",
            VariableKind::Enumeration { .. } => "Enumeration",
        }
    }

    /// The FMI base type used to get and set it (`Enumeration` is accessed as `Integer`).
    pub fn base_type(&self) -> &'static str {
        match self {
            VariableKind::Enumeration { .. } => "Integer",
            other => other.type_name(),
        }
    }

    /// Whether a `start` attribute is present.
    pub fn has_start(&self) -> bool {
        match self {
            VariableKind::Real { start, .. } => start.is_some(),
            VariableKind::Integer { start, .. } | VariableKind::Enumeration { start, .. } => {
                start.is_some()
            }
            VariableKind::Boolean { start } => start.is_some(),
            VariableKind::String { start } => start.is_some(),
        }
    }
}

impl Causality {
    /// The attribute value as written in modelDescription.xml, e.g. `calculatedParameter`.
    pub fn as_str(self) -> &'static str {
        match self {
            Causality::Parameter => "parameter",
            Causality::CalculatedParameter => "calculatedParameter",
            Causality::Input => "input",
            Causality::Output => "output",
            Causality::Local => "local",
            Causality::Independent => "independent",
        }
    }
}

impl Variability {
    /// The attribute value as written in modelDescription.xml, e.g. `tunable`.
    pub fn as_str(self) -> &'static str {
        match self {
            Variability::Constant => "constant",
            Variability::Fixed => "fixed",
            Variability::Tunable => "tunable",
            Variability::Discrete => "discrete",
            Variability::Continuous => "continuous",
        }
    }
}

impl Initial {
    /// The attribute value as written in modelDescription.xml, e.g. `exact`.
    pub fn as_str(self) -> &'static str {
        match self {
            Initial::Exact => "exact",
            Initial::Approx => "approx",
            Initial::Calculated => "calculated",
        }
    }
}

impl ScalarVariable {
    /// `initial`, or its FMI 2.0 default from causality and variability when absent
    /// (`None` for inputs and the independent variable, which have no `initial`).
    pub fn effective_initial(&self) -> Option<Initial> {
        if self.initial.is_some() {
            return self.initial;
        }
        match (self.causality, self.variability) {
            (Causality::Input | Causality::Independent, _) => None,
            (Causality::Parameter, _) => Some(Initial::Exact),
            (Causality::CalculatedParameter, _) => Some(Initial::Calculated),
            (Causality::Output | Causality::Local, Variability::Constant) => Some(Initial::Exact),
            (Causality::Output | Causality::Local, _) => Some(Initial::Calculated),
        }
    }

    /// Whether `fmi2Set*` may set this variable after instantiation, before
    /// `fmi2EnterInitializationMode` (FMI 2.0: variability not constant and initial exact or
    /// approx; this covers fixed and tunable parameters and inputs).
    pub fn settable_before_init(&self) -> bool {
        self.variability != Variability::Constant
            && (self.causality == Causality::Input
                || matches!(
                    self.effective_initial(),
                    Some(Initial::Exact | Initial::Approx)
                ))
    }

    /// Whether `fmi2Set*` may set this variable in initialization mode (FMI 2.0: variability not
    /// constant and initial exact, or an input).
    pub fn settable_in_initialization_mode(&self) -> bool {
        self.variability != Variability::Constant
            && (self.causality == Causality::Input
                || self.effective_initial() == Some(Initial::Exact))
    }

    /// A String of causality `calculatedParameter`: a text the FMU computes at initialization
    /// (summary.json and `simulate` record these, see [`super::Instance::get_calculated_strings`]).
    pub fn is_calculated_string(&self) -> bool {
        self.causality == Causality::CalculatedParameter
            && matches!(self.kind, VariableKind::String { .. })
    }

    /// Whether `fmi2Set*` may set this variable after initialization, at communication points
    /// (FMI 2.0: inputs and tunable parameters only).
    pub fn settable_after_init(&self) -> bool {
        self.causality == Causality::Input
            || (self.causality == Causality::Parameter && self.variability == Variability::Tunable)
    }
}

impl ModelDescription {
    /// Parses `modelDescription.xml` from its bytes (UTF-8, an optional byte-order mark allowed),
    /// with the default [`ParseLimits`]. Time and memory are linear in the size of the file.
    pub fn parse(xml: &[u8]) -> Result<ModelDescription, DescriptionError> {
        Self::parse_with_limits(xml, ParseLimits::default())
    }

    /// Parses `modelDescription.xml` from its bytes, refusing files larger or more deeply
    /// nested than `limits`.
    pub fn parse_with_limits(
        xml: &[u8],
        limits: ParseLimits,
    ) -> Result<ModelDescription, DescriptionError> {
        parse::parse(xml, limits)
    }

    /// The variable with this name, if any.
    pub fn variable(&self, name: &str) -> Option<&ScalarVariable> {
        let index = self.by_name.0.get_or_init(|| {
            let mut index = std::collections::HashMap::with_capacity(self.variables.len());
            for (i, v) in self.variables.iter().enumerate() {
                index.entry(v.name.clone()).or_insert(i);
            }
            index
        });
        match index.get(name).and_then(|&i| self.variables.get(i)) {
            Some(v) if v.name == name => Some(v),
            // The variables were changed after the index was built.
            _ => self.variables.iter().find(|v| v.name == name),
        }
    }

    /// The variables listed in `ModelStructure/Outputs`, in that order.
    pub fn output_variables(&self) -> impl Iterator<Item = &ScalarVariable> + '_ {
        self.outputs
            .iter()
            .filter_map(|&i| self.variables.get(i.wrapping_sub(1)))
    }

    /// Whether `var` may be set before initialization; see [`ScalarVariable::settable_before_init`].
    pub fn settable_before_init(&self, var: &ScalarVariable) -> bool {
        var.settable_before_init()
    }

    /// Whether `var` may be set after initialization; see [`ScalarVariable::settable_after_init`].
    pub fn settable_after_init(&self, var: &ScalarVariable) -> bool {
        var.settable_after_init()
    }
}

#[cfg(test)]
mod tests;
