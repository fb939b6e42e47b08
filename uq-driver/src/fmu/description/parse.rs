//! The parsing machinery behind [`ModelDescription::parse`]: one forward pass of quick-xml
//! events; line numbers are tracked incrementally ([`Lines`]), so the time is linear in the
//! size of the file.

use std::borrow::Cow;
use std::collections::{HashMap, HashSet};
use std::str::FromStr;

use quick_xml::events::{BytesStart, Event};
use quick_xml::Reader;

use super::text::{self, line_col, Lines};
use super::{
    Causality, CoSimulation, DefaultExperiment, DescriptionError, Initial, ModelDescription,
    ParseLimits, ScalarVariable, Unit, Variability, VariableKind, VariableNamingConvention,
};

/// Longest attribute value quoted in an error message, in characters.
const QUOTE_MAX: usize = 200;

/// Parses a whole `modelDescription.xml`.
pub(super) fn parse(xml: &[u8], limits: ParseLimits) -> Result<ModelDescription, DescriptionError> {
    let xml = text::check(xml, &limits)?;
    let mut reader = Reader::from_reader(xml);
    let mut lines = Lines::new(xml);
    let mut builder = Builder::default();
    let mut stack: Vec<Elem> = Vec::new();
    let mut root_seen = false;
    loop {
        let pos = to_usize(reader.buffer_position());
        let event = reader
            .read_event()
            .map_err(|e| malformed(xml, to_usize(reader.error_position()), e.to_string()))?;
        match event {
            Event::Start(ref e) | Event::Empty(ref e) => {
                let line = lines.line_at(pos);
                if stack.is_empty() {
                    if root_seen {
                        return Err(malformed(xml, pos, "more than one root element".into()));
                    }
                    root_seen = true;
                }
                if stack.len() >= limits.max_depth {
                    return Err(DescriptionError::TooDeep {
                        line,
                        limit: limits.max_depth,
                    });
                }
                let elem = builder.open(e, stack.last().copied(), line)?;
                if matches!(event, Event::Start(_)) {
                    stack.push(elem);
                } else {
                    builder.close(elem)?;
                }
            }
            Event::End(_) => {
                if let Some(elem) = stack.pop() {
                    builder.close(elem)?;
                }
            }
            Event::Eof => break,
            _ => {}
        }
    }
    if !stack.is_empty() {
        return Err(malformed(
            xml,
            xml.len(),
            "unexpected end of document: an element is not closed".into(),
        ));
    }
    if !root_seen {
        return Err(malformed(xml, xml.len(), "no root element".into()));
    }
    builder.finish()
}

/// The elements whose content matters, as context for their children.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Elem {
    Root,
    UnitDefinitions,
    TypeDefinitions,
    /// A `SimpleType` (its name kept in `Builder::simple_type`).
    SimpleType,
    LogCategories,
    ModelVariables,
    ScalarVariable,
    ModelStructure,
    Outputs,
    /// Anything else (annotations, type definitions, ...): its content is skipped.
    Other,
}

/// A variable whose type element has not been seen yet.
struct PendingVar {
    name: String,
    value_reference: u32,
    description: Option<String>,
    causality: Causality,
    variability: Option<Variability>,
    initial: Option<Initial>,
    kind: Option<VariableKind>,
    type_elements: usize,
    line: usize,
}

#[derive(Default)]
struct Builder {
    fmi_version: String,
    model_name: String,
    guid: String,
    description: Option<String>,
    generation_tool: Option<String>,
    variable_naming_convention: VariableNamingConvention,
    number_of_event_indicators: Option<u32>,
    co_simulation: Option<CoSimulation>,
    model_exchange_present: bool,
    default_experiment: Option<DefaultExperiment>,
    unit_definitions: Vec<Unit>,
    type_units: Vec<(String, String)>,
    simple_type: Option<String>,
    log_categories: Vec<(String, Option<String>)>,
    variables: Vec<ScalarVariable>,
    outputs: Vec<usize>,
    pending: Option<PendingVar>,
}

/// The attributes of one element, unescaped (borrowed from the document where possible).
struct Attrs<'e> {
    element: String,
    line: usize,
    list: Vec<(Cow<'e, str>, Cow<'e, str>)>,
}

impl<'e> Attrs<'e> {
    fn read(e: &'e BytesStart<'_>, element: &str, line: usize) -> Result<Self, DescriptionError> {
        let malformed = |reason: String| DescriptionError::Malformed {
            line,
            column: 1,
            reason,
        };
        let mut list = Vec::new();
        // quick-xml's own duplicate check compares each attribute with all earlier ones
        // (quadratic in the attribute count): check with a hash set below instead.
        for attr in e.attributes().with_checks(false) {
            let attr = attr.map_err(|err| malformed(format!("in <{element}>: {err}")))?;
            let key = String::from_utf8_lossy(attr.key.local_name().into_inner());
            let value = attr
                .unescape_value()
                .map_err(|err| malformed(format!("in <{element}> attribute {key}: {err}")))?;
            list.push((key, value));
        }
        if let Some(key) = first_duplicate(&list) {
            return Err(malformed(format!(
                "<{element}> has the attribute {key} twice"
            )));
        }
        Ok(Attrs {
            element: element.to_string(),
            line,
            list,
        })
    }

    fn get(&self, key: &str) -> Option<&str> {
        self.list
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_ref())
    }

    fn string(&self, key: &str) -> Option<String> {
        self.get(key).map(str::to_string)
    }

    fn required(&self, key: &'static str) -> Result<String, DescriptionError> {
        self.string(key)
            .ok_or_else(|| DescriptionError::MissingAttribute {
                element: self.element.clone(),
                attribute: key,
                line: self.line,
            })
    }

    fn invalid(&self, key: &str, value: &str, expected: &str) -> DescriptionError {
        DescriptionError::InvalidAttribute {
            element: self.element.clone(),
            attribute: key.to_string(),
            value: quote(value),
            expected: expected.to_string(),
            line: self.line,
        }
    }

    fn number<T: FromStr>(&self, key: &str, expected: &str) -> Result<Option<T>, DescriptionError> {
        match self.get(key) {
            None => Ok(None),
            Some(v) => v
                .trim()
                .parse()
                .map(Some)
                .map_err(|_| self.invalid(key, v, expected)),
        }
    }

    fn real(&self, key: &str) -> Result<Option<f64>, DescriptionError> {
        self.number(key, "a real number")
    }

    fn boolean(&self, key: &str) -> Result<Option<bool>, DescriptionError> {
        match self.get(key).map(str::trim) {
            None => Ok(None),
            Some("true" | "1") => Ok(Some(true)),
            Some("false" | "0") => Ok(Some(false)),
            Some(v) => Err(self.invalid(key, v, "true or false")),
        }
    }

    fn flag(&self, key: &str) -> Result<bool, DescriptionError> {
        Ok(self.boolean(key)?.unwrap_or(false))
    }

    fn choice<T: Copy>(
        &self,
        key: &str,
        options: &[(&str, T)],
    ) -> Result<Option<T>, DescriptionError> {
        let Some(v) = self.get(key) else {
            return Ok(None);
        };
        options
            .iter()
            .find(|(name, _)| *name == v)
            .map(|&(_, t)| Some(t))
            .ok_or_else(|| {
                let names: Vec<&str> = options.iter().map(|(n, _)| *n).collect();
                self.invalid(key, v, &format!("one of {}", names.join(", ")))
            })
    }
}

impl Builder {
    fn open(
        &mut self,
        e: &BytesStart<'_>,
        parent: Option<Elem>,
        line: usize,
    ) -> Result<Elem, DescriptionError> {
        let local = e.local_name();
        let name = String::from_utf8_lossy(local.as_ref());
        let attrs = || Attrs::read(e, &name, line);
        let elem = match (parent, name.as_ref()) {
            (None, "fmiModelDescription") => {
                self.root(&attrs()?)?;
                Elem::Root
            }
            (None, other) => {
                return Err(DescriptionError::WrongRoot {
                    found: other.to_string(),
                    line,
                })
            }
            (Some(Elem::Root), "CoSimulation") => {
                if self.co_simulation.is_some() {
                    return Err(DescriptionError::Repeated {
                        element: name.to_string(),
                        line,
                    });
                }
                self.co_simulation = Some(co_simulation(&attrs()?)?);
                Elem::Other
            }
            (Some(Elem::Root), "ModelExchange") => {
                self.model_exchange_present = true;
                Elem::Other
            }
            (Some(Elem::Root), "UnitDefinitions") => Elem::UnitDefinitions,
            (Some(Elem::UnitDefinitions), "Unit") => {
                let name = attrs()?.required("name")?;
                self.unit_definitions.push(Unit { name });
                Elem::Other
            }
            (Some(Elem::Root), "TypeDefinitions") => Elem::TypeDefinitions,
            (Some(Elem::TypeDefinitions), "SimpleType") => {
                self.simple_type = attrs()?.string("name");
                Elem::SimpleType
            }
            (Some(Elem::SimpleType), "Real") => {
                let unit = attrs()?.string("unit").filter(|u| !u.is_empty());
                if let (Some(name), Some(unit)) = (self.simple_type.take(), unit) {
                    self.type_units.push((name, unit));
                }
                Elem::Other
            }
            (Some(Elem::Root), "LogCategories") => Elem::LogCategories,
            (Some(Elem::LogCategories), "Category") => {
                let a = attrs()?;
                self.log_categories
                    .push((a.required("name")?, a.string("description")));
                Elem::Other
            }
            (Some(Elem::Root), "DefaultExperiment") => {
                let a = attrs()?;
                self.default_experiment = Some(DefaultExperiment {
                    start_time: a.real("startTime")?,
                    stop_time: a.real("stopTime")?,
                    tolerance: a.real("tolerance")?,
                    step_size: a.real("stepSize")?,
                });
                Elem::Other
            }
            (Some(Elem::Root), "ModelVariables") => Elem::ModelVariables,
            (Some(Elem::ModelVariables), "ScalarVariable") => {
                self.pending = Some(pending_variable(&attrs()?)?);
                Elem::ScalarVariable
            }
            (
                Some(Elem::ScalarVariable),
                "Real" | "Integer" | "Boolean" | "String" | "Enumeration",
            ) => {
                let kind = variable_kind(&attrs()?)?;
                if let Some(p) = self.pending.as_mut() {
                    p.type_elements += 1;
                    p.kind = Some(kind);
                }
                Elem::Other
            }
            (Some(Elem::Root), "ModelStructure") => Elem::ModelStructure,
            (Some(Elem::ModelStructure), "Outputs") => Elem::Outputs,
            (Some(Elem::Outputs), "Unknown") => {
                let a = attrs()?;
                let index: usize = a.number("index", "a positive integer")?.ok_or_else(|| {
                    DescriptionError::MissingAttribute {
                        element: a.element.clone(),
                        attribute: "index",
                        line,
                    }
                })?;
                self.outputs.push(index);
                Elem::Other
            }
            _ => Elem::Other,
        };
        Ok(elem)
    }

    fn close(&mut self, elem: Elem) -> Result<(), DescriptionError> {
        if elem != Elem::ScalarVariable {
            return Ok(());
        }
        let Some(p) = self.pending.take() else {
            return Ok(());
        };
        let kind = match (p.kind, p.type_elements) {
            (Some(kind), 1) => kind,
            _ => {
                return Err(DescriptionError::BadTypeElement {
                    name: p.name,
                    line: p.line,
                })
            }
        };
        let variability = p.variability.unwrap_or(match kind {
            VariableKind::Real { .. } => Variability::Continuous,
            _ => Variability::Discrete,
        });
        self.variables.push(ScalarVariable {
            name: p.name,
            value_reference: p.value_reference,
            description: p.description,
            causality: p.causality,
            variability,
            initial: p.initial,
            kind,
        });
        Ok(())
    }

    fn root(&mut self, a: &Attrs) -> Result<(), DescriptionError> {
        // The version first: an FMI 1.0 or 3.0 file would fail later checks confusingly.
        let version = a.required("fmiVersion")?;
        if version.trim() != "2.0" {
            return Err(DescriptionError::UnsupportedFmiVersion { found: version });
        }
        self.fmi_version = "2.0".to_string();
        self.model_name = a.required("modelName")?;
        self.guid = a.required("guid")?;
        self.description = a.string("description");
        self.generation_tool = a.string("generationTool");
        self.variable_naming_convention = a
            .choice(
                "variableNamingConvention",
                &[
                    ("flat", VariableNamingConvention::Flat),
                    ("structured", VariableNamingConvention::Structured),
                ],
            )?
            .unwrap_or_default();
        self.number_of_event_indicators =
            a.number("numberOfEventIndicators", "a non-negative integer")?;
        Ok(())
    }

    fn finish(self) -> Result<ModelDescription, DescriptionError> {
        let Some(co_simulation) = self.co_simulation else {
            return Err(DescriptionError::NoCoSimulation {
                model_exchange_present: self.model_exchange_present,
            });
        };
        let mut names: HashMap<&str, ()> = HashMap::with_capacity(self.variables.len());
        // Per (base type, value reference): the first variable with a start value and the first
        // parameter or input of the alias set.
        struct AliasSet {
            with_start: Option<usize>,
            settable: Option<usize>,
        }
        let mut sets: HashMap<(&'static str, u32), AliasSet> = HashMap::new();
        for (i, v) in self.variables.iter().enumerate() {
            if names.insert(v.name.as_str(), ()).is_some() {
                return Err(DescriptionError::DuplicateName {
                    name: v.name.clone(),
                });
            }
            let key = (v.kind.base_type(), v.value_reference);
            let has_start = v.kind.has_start();
            let settable = matches!(v.causality, Causality::Parameter | Causality::Input);
            let set = sets.entry(key).or_insert(AliasSet {
                with_start: None,
                settable: None,
            });
            let conflict =
                |other: usize, reason: &'static str| DescriptionError::DuplicateValueReference {
                    base_type: key.0,
                    value_reference: key.1,
                    first: self.variables[other].name.clone(),
                    second: v.name.clone(),
                    reason,
                };
            if has_start {
                if let Some(other) = set.with_start {
                    return Err(conflict(other, "both have a start value"));
                }
                set.with_start = Some(i);
            }
            if settable {
                if let Some(other) = set.settable {
                    return Err(conflict(other, "both are parameters or inputs"));
                }
                set.settable = Some(i);
            }
        }
        let count = self.variables.len();
        if let Some(&index) = self.outputs.iter().find(|&&i| i == 0 || i > count) {
            return Err(DescriptionError::BadOutputIndex { index, count });
        }
        // FMI 2.0 (2.2.8): ModelStructure/Outputs lists exactly the variables with
        // causality="output"; compared as sets, as fmpy.validation does.
        let mut listed = vec![false; count];
        for &i in &self.outputs {
            listed[i - 1] = true;
        }
        let mismatch = self
            .variables
            .iter()
            .zip(&listed)
            .position(|(v, &l)| (v.causality == Causality::Output) != l);
        if let Some(k) = mismatch {
            let v = &self.variables[k];
            return Err(DescriptionError::OutputsMismatch {
                name: v.name.clone(),
                index: k + 1,
                causality: v.causality.as_str(),
            });
        }
        Ok(ModelDescription {
            fmi_version: self.fmi_version,
            model_name: self.model_name,
            guid: self.guid,
            description: self.description,
            generation_tool: self.generation_tool,
            variable_naming_convention: self.variable_naming_convention,
            number_of_event_indicators: self.number_of_event_indicators,
            co_simulation,
            model_exchange_present: self.model_exchange_present,
            default_experiment: self.default_experiment,
            unit_definitions: self.unit_definitions,
            type_units: self.type_units,
            log_categories: self.log_categories,
            variables: self.variables,
            outputs: self.outputs,
            by_name: Default::default(),
        })
    }
}

fn co_simulation(a: &Attrs) -> Result<CoSimulation, DescriptionError> {
    let model_identifier = a.required("modelIdentifier")?;
    // It names a file inside the FMU: refuse anything that is not a plain file-name stem.
    let plain = !model_identifier.is_empty()
        && model_identifier != "."
        && model_identifier != ".."
        && !model_identifier.contains(['/', '\\', '\0', ':']);
    if !plain {
        return Err(a.invalid(
            "modelIdentifier",
            &model_identifier,
            "a C identifier usable as a file name",
        ));
    }
    Ok(CoSimulation {
        model_identifier,
        needs_execution_tool: a.flag("needsExecutionTool")?,
        can_handle_variable_communication_step_size: a
            .flag("canHandleVariableCommunicationStepSize")?,
        can_interpolate_inputs: a.flag("canInterpolateInputs")?,
        max_output_derivative_order: a
            .number("maxOutputDerivativeOrder", "a non-negative integer")?
            .unwrap_or(0),
        can_run_asynchronuously: a.flag("canRunAsynchronuously")?,
        can_be_instantiated_only_once_per_process: a.flag("canBeInstantiatedOnlyOncePerProcess")?,
        can_not_use_memory_management_functions: a.flag("canNotUseMemoryManagementFunctions")?,
        can_get_and_set_fmu_state: a.flag("canGetAndSetFMUstate")?,
        can_serialize_fmu_state: a.flag("canSerializeFMUstate")?,
        provides_directional_derivative: a.flag("providesDirectionalDerivative")?,
    })
}

fn pending_variable(a: &Attrs) -> Result<PendingVar, DescriptionError> {
    let name = a.required("name")?;
    let value_reference = a
        .number("valueReference", "an unsigned 32-bit integer")?
        .ok_or_else(|| DescriptionError::MissingAttribute {
            element: a.element.clone(),
            attribute: "valueReference",
            line: a.line,
        })?;
    let causality = a
        .choice(
            "causality",
            &[
                ("parameter", Causality::Parameter),
                ("calculatedParameter", Causality::CalculatedParameter),
                ("input", Causality::Input),
                ("output", Causality::Output),
                ("local", Causality::Local),
                ("independent", Causality::Independent),
            ],
        )?
        .unwrap_or_default();
    let variability = a.choice(
        "variability",
        &[
            ("constant", Variability::Constant),
            ("fixed", Variability::Fixed),
            ("tunable", Variability::Tunable),
            ("discrete", Variability::Discrete),
            ("continuous", Variability::Continuous),
        ],
    )?;
    let initial = a.choice(
        "initial",
        &[
            ("exact", Initial::Exact),
            ("approx", Initial::Approx),
            ("calculated", Initial::Calculated),
        ],
    )?;
    Ok(PendingVar {
        name,
        value_reference,
        description: a.string("description"),
        causality,
        variability,
        initial,
        kind: None,
        type_elements: 0,
        line: a.line,
    })
}

fn variable_kind(a: &Attrs) -> Result<VariableKind, DescriptionError> {
    const INT: &str = "a 32-bit integer";
    Ok(match a.element.as_str() {
        "Real" => VariableKind::Real {
            start: a.real("start")?,
            unit: a.string("unit"),
            declared_type: a.string("declaredType"),
            min: a.real("min")?,
            max: a.real("max")?,
            nominal: a.real("nominal")?,
        },
        "Integer" => VariableKind::Integer {
            start: a.number("start", INT)?,
            min: a.number("min", INT)?,
            max: a.number("max", INT)?,
        },
        "Boolean" => VariableKind::Boolean {
            start: a.boolean("start")?,
        },
        "String" => VariableKind::String {
            start: a.string("start"),
        },
        _ => VariableKind::Enumeration {
            start: a.number("start", INT)?,
            declared_type: a.required("declaredType")?,
            min: a.number("min", INT)?,
            max: a.number("max", INT)?,
        },
    })
}

/// The first attribute name that appears twice: pairwise for a few attributes (no allocation),
/// with a hash set for many (linear).
fn first_duplicate<'a>(list: &'a [(Cow<'_, str>, Cow<'_, str>)]) -> Option<&'a str> {
    if list.len() <= 16 {
        return list
            .iter()
            .enumerate()
            .find(|(i, (k, _))| list[..*i].iter().any(|(j, _)| j == k))
            .map(|(_, (k, _))| k.as_ref());
    }
    let mut seen = HashSet::with_capacity(list.len());
    list.iter()
        .map(|(k, _)| k.as_ref())
        .find(|k| !seen.insert(*k))
}

/// `value`, cut to [`QUOTE_MAX`] characters for an error message.
fn quote(value: &str) -> String {
    match value.char_indices().nth(QUOTE_MAX) {
        None => value.to_string(),
        Some((cut, _)) => format!("{}... ({} bytes in all)", &value[..cut], value.len()),
    }
}

fn to_usize(pos: u64) -> usize {
    usize::try_from(pos).unwrap_or(usize::MAX)
}

fn malformed(xml: &[u8], pos: usize, reason: String) -> DescriptionError {
    let (line, column) = line_col(xml, pos);
    DescriptionError::Malformed {
        line,
        column,
        // quick-xml quotes names from the document, which may be huge.
        reason: quote(&reason),
    }
}
