//! Tests of `description`.

use super::*;

const MINIMAL: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription fmiVersion="2.0" modelName="M" guid="{abc}">
  <CoSimulation modelIdentifier="M"/>
  <ModelVariables>
<ScalarVariable name="x" valueReference="0"><Real/></ScalarVariable>
  </ModelVariables>
  <ModelStructure/>
</fmiModelDescription>"#;

fn parse(s: &str) -> Result<ModelDescription, DescriptionError> {
    ModelDescription::parse(s.as_bytes())
}

#[test]
fn minimal_description_gets_fmi_defaults() {
    let md = parse(MINIMAL).unwrap();
    assert_eq!(md.fmi_version, "2.0");
    assert_eq!(md.guid, "{abc}");
    assert_eq!(md.co_simulation.model_identifier, "M");
    assert!(!md.co_simulation.can_get_and_set_fmu_state);
    assert_eq!(md.co_simulation.max_output_derivative_order, 0);
    assert!(!md.model_exchange_present);
    assert_eq!(md.default_experiment, None);
    assert_eq!(
        md.variable_naming_convention,
        VariableNamingConvention::Flat
    );
    let x = md.variable("x").unwrap();
    assert_eq!(x.causality, Causality::Local);
    assert_eq!(x.variability, Variability::Continuous);
    assert_eq!(x.initial, None);
    assert_eq!(x.effective_initial(), Some(Initial::Calculated));
    assert!(md.variable("y").is_none());
}

#[test]
fn full_description_is_parsed() {
    let xml = r#"<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription fmiVersion="2.0" modelName="Wheel" guid="g-1" description="a &amp; b"
generationTool="railuq" variableNamingConvention="structured" numberOfEventIndicators="0">
  <ModelExchange modelIdentifier="Wheel"/>
  <CoSimulation modelIdentifier="Wheel" canHandleVariableCommunicationStepSize="true"
  canGetAndSetFMUstate="true" canSerializeFMUstate="false" maxOutputDerivativeOrder="1"/>
  <UnitDefinitions><Unit name="m"><BaseUnit m="1"/></Unit><Unit name="s"/></UnitDefinitions>
  <TypeDefinitions>
<SimpleType name="Mode"><Enumeration><Item name="a" value="1"/></Enumeration></SimpleType>
<SimpleType name="Length"><Real unit="m"/></SimpleType>
  </TypeDefinitions>
  <LogCategories><Category name="logAll" description="everything"/><Category name="x"/></LogCategories>
  <DefaultExperiment startTime="0" stopTime="2.5" tolerance="1e-6" stepSize="0.001"/>
  <ModelVariables>
<ScalarVariable name="time" valueReference="0" causality="independent"><Real unit="s"/></ScalarVariable>
<ScalarVariable name="k" valueReference="1" causality="parameter" variability="tunable" description="stiffness">
  <Real start="2.5e6" unit="N/m" min="0" max="INF" nominal="1e6"/>
</ScalarVariable>
<ScalarVariable name="n" valueReference="0" causality="parameter" variability="fixed"><Integer start="-3" min="-10" max="10"/></ScalarVariable>
<ScalarVariable name="on" valueReference="0" causality="input"><Boolean start="true"/></ScalarVariable>
<ScalarVariable name="label" valueReference="0" causality="parameter" variability="fixed"><String start="a&lt;b"/></ScalarVariable>
<ScalarVariable name="mode" valueReference="7" causality="parameter" variability="fixed"><Enumeration declaredType="Mode" start="1"/></ScalarVariable>
<ScalarVariable name="y" valueReference="2" causality="output" initial="exact">
  <Real declaredType="Length" start="0"/><Annotations><Tool name="t"/></Annotations>
</ScalarVariable>
  </ModelVariables>
  <ModelStructure>
<Outputs><Unknown index="7" dependencies=""/></Outputs>
<InitialUnknowns><Unknown index="1"/></InitialUnknowns>
  </ModelStructure>
</fmiModelDescription>"#;
    let md = parse(xml).unwrap();
    assert_eq!(md.model_name, "Wheel");
    assert_eq!(md.description.as_deref(), Some("a & b"));
    assert_eq!(md.generation_tool.as_deref(), Some("railuq"));
    assert_eq!(
        md.variable_naming_convention,
        VariableNamingConvention::Structured
    );
    assert_eq!(md.number_of_event_indicators, Some(0));
    assert!(md.model_exchange_present);
    let cs = &md.co_simulation;
    assert!(cs.can_handle_variable_communication_step_size && cs.can_get_and_set_fmu_state);
    assert!(!cs.can_serialize_fmu_state);
    assert_eq!(cs.max_output_derivative_order, 1);
    assert_eq!(
        md.unit_definitions,
        vec![Unit { name: "m".into() }, Unit { name: "s".into() }]
    );
    assert_eq!(
        md.log_categories,
        vec![
            ("logAll".to_string(), Some("everything".to_string())),
            ("x".to_string(), None)
        ]
    );
    let de = md.default_experiment.unwrap();
    assert_eq!(
        (de.start_time, de.stop_time, de.tolerance, de.step_size),
        (Some(0.0), Some(2.5), Some(1e-6), Some(0.001))
    );
    assert_eq!(md.variables.len(), 7);
    let k = md.variable("k").unwrap();
    assert_eq!(k.description.as_deref(), Some("stiffness"));
    assert_eq!(
        k.kind,
        VariableKind::Real {
            start: Some(2.5e6),
            unit: Some("N/m".into()),
            declared_type: None,
            min: Some(0.0),
            max: Some(f64::INFINITY),
            nominal: Some(1e6)
        }
    );
    assert_eq!(
        md.variable("n").unwrap().kind,
        VariableKind::Integer {
            start: Some(-3),
            min: Some(-10),
            max: Some(10)
        }
    );
    let on = md.variable("on").unwrap();
    assert_eq!(on.kind, VariableKind::Boolean { start: Some(true) });
    assert_eq!(on.variability, Variability::Discrete);
    assert_eq!(
        md.variable("label").unwrap().kind,
        VariableKind::String {
            start: Some("a<b".into())
        }
    );
    assert_eq!(
        md.variable("mode").unwrap().kind,
        VariableKind::Enumeration {
            start: Some(1),
            declared_type: "Mode".into(),
            min: None,
            max: None,
        }
    );
    let y = md.variable("y").unwrap();
    assert_eq!(y.initial, Some(Initial::Exact));
    assert!(matches!(
        &y.kind,
        VariableKind::Real { declared_type: Some(t), .. } if t == "Length"
    ));
    assert_eq!(md.outputs, vec![7]);
    assert_eq!(
        md.output_variables()
            .map(|v| v.name.as_str())
            .collect::<Vec<_>>(),
        vec!["y"]
    );
}

fn var(causality: Causality, variability: Variability, initial: Option<Initial>) -> ScalarVariable {
    ScalarVariable {
        name: "v".into(),
        value_reference: 0,
        description: None,
        causality,
        variability,
        initial,
        kind: VariableKind::Real {
            start: Some(1.0),
            unit: None,
            declared_type: None,
            min: None,
            max: None,
            nominal: None,
        },
    }
}

#[test]
fn settable_rules_follow_fmi_2_0() {
    use Causality::*;
    use Variability::*;
    let cases = [
        // causality, variability, initial, before init, in init mode, after init
        (Parameter, Fixed, None, true, true, false),
        (Parameter, Tunable, None, true, true, true),
        (Input, Continuous, None, true, true, true),
        (Input, Discrete, None, true, true, true),
        (Output, Continuous, None, false, false, false),
        (Output, Continuous, Some(Initial::Exact), true, true, false),
        (Local, Continuous, Some(Initial::Approx), true, false, false),
        (Local, Constant, None, false, false, false),
        (CalculatedParameter, Fixed, None, false, false, false),
        (Independent, Continuous, None, false, false, false),
    ];
    for (c, v, i, before, init, after) in cases {
        let sv = var(c, v, i);
        assert_eq!(sv.settable_before_init(), before, "{c:?} {v:?} {i:?}");
        assert_eq!(
            sv.settable_in_initialization_mode(),
            init,
            "{c:?} {v:?} {i:?}"
        );
        assert_eq!(sv.settable_after_init(), after, "{c:?} {v:?} {i:?}");
    }
}

#[test]
fn malformed_xml_reports_line_and_column() {
    let xml = "<fmiModelDescription fmiVersion=\"2.0\" modelName=\"M\" guid=\"g\">\n  <CoSimulation modelIdentifier=\"M\"/>\n  <ModelVariables>\n  </ModelVariablez>\n</fmiModelDescription>";
    let err = parse(xml).unwrap_err();
    let DescriptionError::Malformed { line, .. } = &err else {
        panic!("{err:?}")
    };
    assert_eq!(*line, 4, "{err}");
    assert!(matches!(
        parse("<fmiModelDescription fmiVersion=\"2.0\""),
        Err(DescriptionError::Malformed { .. })
    ));
    assert!(matches!(parse(""), Err(DescriptionError::Malformed { .. })));
    let unclosed = "<fmiModelDescription fmiVersion=\"2.0\" modelName=\"M\" guid=\"g\"><CoSimulation modelIdentifier=\"M\"/>";
    assert!(matches!(
        parse(unclosed),
        Err(DescriptionError::Malformed { .. })
    ));
}

#[test]
fn other_fmi_versions_are_refused_by_name() {
    let xml = MINIMAL.replace("fmiVersion=\"2.0\"", "fmiVersion=\"1.0\"");
    let err = parse(&xml).unwrap_err();
    assert_eq!(
        err,
        DescriptionError::UnsupportedFmiVersion {
            found: "1.0".into()
        }
    );
    assert!(err.to_string().contains("\"1.0\""));
    let xml = MINIMAL.replace("fmiVersion=\"2.0\"", "fmiVersion=\"3.0\"");
    assert!(matches!(
        parse(&xml),
        Err(DescriptionError::UnsupportedFmiVersion { found }) if found == "3.0"
    ));
}

#[test]
fn model_exchange_only_is_refused() {
    let xml = MINIMAL.replace("CoSimulation", "ModelExchange");
    assert_eq!(
        parse(&xml).unwrap_err(),
        DescriptionError::NoCoSimulation {
            model_exchange_present: true
        }
    );
}

#[test]
fn missing_guid_and_model_identifier_are_named() {
    let err = parse(&MINIMAL.replace(" guid=\"{abc}\"", "")).unwrap_err();
    assert!(
        matches!(
            &err,
            DescriptionError::MissingAttribute {
                attribute: "guid",
                line: 2,
                ..
            }
        ),
        "{err:?}"
    );
    let err = parse(&MINIMAL.replace(" modelIdentifier=\"M\"", "")).unwrap_err();
    assert!(
        matches!(
            &err,
            DescriptionError::MissingAttribute {
                attribute: "modelIdentifier",
                ..
            }
        ),
        "{err:?}"
    );
    let err =
        parse(&MINIMAL.replace("modelIdentifier=\"M\"", "modelIdentifier=\"../x\"")).unwrap_err();
    assert!(
        matches!(err, DescriptionError::InvalidAttribute { .. }),
        "{err:?}"
    );
}

fn with_variables(vars: &str) -> String {
    MINIMAL.replace(
        r#"<ScalarVariable name="x" valueReference="0"><Real/></ScalarVariable>"#,
        vars,
    )
}

#[test]
fn duplicate_value_references_within_a_type_are_refused() {
    let xml = with_variables(
        r#"<ScalarVariable name="a" valueReference="3" causality="parameter" variability="fixed"><Real start="1"/></ScalarVariable>
           <ScalarVariable name="b" valueReference="3" causality="parameter" variability="fixed"><Real start="2"/></ScalarVariable>"#,
    );
    let err = parse(&xml).unwrap_err();
    assert_eq!(
        err,
        DescriptionError::DuplicateValueReference {
            base_type: "Real",
            value_reference: 3,
            first: "a".into(),
            second: "b".into(),
            reason: "both have a start value",
        }
    );
    let xml = with_variables(
        r#"<ScalarVariable name="a" valueReference="3" causality="input"><Real/></ScalarVariable>
           <ScalarVariable name="b" valueReference="3" causality="parameter" variability="tunable"><Real start="2"/></ScalarVariable>"#,
    );
    assert!(matches!(
        parse(&xml),
        Err(DescriptionError::DuplicateValueReference {
            reason: "both are parameters or inputs",
            ..
        })
    ));
    // Integer and Enumeration share fmi2Integer.
    let xml = with_variables(
        r#"<ScalarVariable name="a" valueReference="3" causality="parameter" variability="fixed"><Integer start="1"/></ScalarVariable>
           <ScalarVariable name="b" valueReference="3" causality="parameter" variability="fixed"><Enumeration declaredType="E" start="2"/></ScalarVariable>"#,
    );
    assert!(matches!(
        parse(&xml),
        Err(DescriptionError::DuplicateValueReference {
            base_type: "Integer",
            ..
        })
    ));
}

#[test]
fn same_value_reference_in_other_types_and_aliases_are_accepted() {
    let xml = with_variables(
        r#"<ScalarVariable name="a" valueReference="3"><Real/></ScalarVariable>
           <ScalarVariable name="b" valueReference="3"><Integer/></ScalarVariable>
           <ScalarVariable name="c" valueReference="3"><Boolean/></ScalarVariable>
           <ScalarVariable name="d" valueReference="3"><String/></ScalarVariable>
           <ScalarVariable name="e" valueReference="4" causality="output"><Real/></ScalarVariable>
           <ScalarVariable name="e_alias" valueReference="4"><Real/></ScalarVariable>"#,
    )
    .replace(
        "<ModelStructure/>",
        "<ModelStructure><Outputs><Unknown index=\"5\"/></Outputs></ModelStructure>",
    );
    assert_eq!(parse(&xml).unwrap().variables.len(), 6);
}

#[test]
fn structural_errors_are_typed() {
    let dup = with_variables(
        r#"<ScalarVariable name="a" valueReference="1"><Real/></ScalarVariable>
           <ScalarVariable name="a" valueReference="2"><Real/></ScalarVariable>"#,
    );
    assert!(matches!(
        parse(&dup),
        Err(DescriptionError::DuplicateName { .. })
    ));
    let untyped = with_variables(r#"<ScalarVariable name="a" valueReference="1"/>"#);
    assert!(matches!(
        parse(&untyped),
        Err(DescriptionError::BadTypeElement { .. })
    ));
    let bad_causality = with_variables(
        r#"<ScalarVariable name="a" valueReference="1" causality="inout"><Real/></ScalarVariable>"#,
    );
    let err = parse(&bad_causality).unwrap_err();
    assert!(err.to_string().contains("causality=\"inout\""), "{err}");
    let bad_start = with_variables(
        r#"<ScalarVariable name="a" valueReference="1"><Integer start="1.5"/></ScalarVariable>"#,
    );
    assert!(matches!(
        parse(&bad_start),
        Err(DescriptionError::InvalidAttribute { .. })
    ));
    let no_vr = with_variables(r#"<ScalarVariable name="a"><Real/></ScalarVariable>"#);
    assert!(matches!(
        parse(&no_vr),
        Err(DescriptionError::MissingAttribute {
            attribute: "valueReference",
            ..
        })
    ));
    let bad_output = MINIMAL.replace(
        "<ModelStructure/>",
        "<ModelStructure><Outputs><Unknown index=\"2\"/></Outputs></ModelStructure>",
    );
    assert_eq!(
        parse(&bad_output).unwrap_err(),
        DescriptionError::BadOutputIndex { index: 2, count: 1 }
    );
    assert!(matches!(
        parse("<fmiModelDescriptio fmiVersion=\"2.0\"/>"),
        Err(DescriptionError::WrongRoot { .. })
    ));
}

#[test]
fn byte_order_mark_is_accepted() {
    let mut bytes = b"\xEF\xBB\xBF".to_vec();
    bytes.extend_from_slice(MINIMAL.as_bytes());
    assert!(ModelDescription::parse(&bytes).is_ok());
}

/// The `min`/`max` of an Enumeration variable are read, so that a fixed value outside
/// them is refused before any run (as for an Integer).
#[test]
fn enumeration_min_and_max_are_read() {
    let xml = MINIMAL.replace(
        "<ScalarVariable name=\"x\" valueReference=\"0\"><Real/></ScalarVariable>",
        "<ScalarVariable name=\"e\" valueReference=\"0\" causality=\"parameter\" \
         variability=\"fixed\"><Enumeration declaredType=\"T\" start=\"2\" min=\"1\" max=\"3\"/>\
         </ScalarVariable>",
    );
    let md = parse(&xml).unwrap();
    assert_eq!(
        md.variable("e").unwrap().kind,
        VariableKind::Enumeration {
            start: Some(2),
            declared_type: "T".into(),
            min: Some(1),
            max: Some(3),
        }
    );
}

/// An FMU with an empty `<ModelStructure/>` but an output variable was accepted, and
/// `simulate` said "the FMU has no output" and exited 0; fmpy's validation refuses it.
#[test]
fn outputs_missing_from_model_structure_make_an_invalid_description() {
    let output = MINIMAL.replace(
        "<ScalarVariable name=\"x\" valueReference=\"0\">",
        "<ScalarVariable name=\"x\" valueReference=\"0\" causality=\"output\">",
    );
    let err = parse(&output).unwrap_err();
    assert_eq!(
        err,
        DescriptionError::OutputsMismatch {
            name: "x".into(),
            index: 1,
            causality: "output"
        }
    );
    assert!(
        err.to_string().starts_with(
            "variable 'x' (index 1) has causality=\"output\", but ModelStructure/Outputs does \
             not list it; FMI 2.0 requires"
        ),
        "{err}"
    );
    let listed = output.replace(
        "<ModelStructure/>",
        "<ModelStructure><Outputs><Unknown index=\"1\"/></Outputs></ModelStructure>",
    );
    assert!(parse(&listed).is_ok());
    // A listed variable that is not an output (x is local by default).
    let not_output = MINIMAL.replace(
        "<ModelStructure/>",
        "<ModelStructure><Outputs><Unknown index=\"1\"/></Outputs></ModelStructure>",
    );
    let err = parse(&not_output).unwrap_err().to_string();
    assert!(
        err.starts_with(
            "ModelStructure/Outputs lists variable 'x' (index 1), whose causality is \"local\""
        ),
        "{err}"
    );
}
