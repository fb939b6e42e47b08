//! Regression tests for hostile or huge `modelDescription.xml` files:
//! big descriptions parse in one linear pass, and nesting, size and encoding are refused with
//! errors that name the problem. Speed is measured in `make bench`, not asserted here.

use std::fmt::Write as _;

use uq_driver::fmu::description::ParseLimits;
use uq_driver::fmu::{Causality, DescriptionError, ModelDescription, VariableKind};

use crate::support::assert_contains;

/// A valid description with `n` Real variables `v0..v{n-1}` (every tenth a tunable parameter
/// with a start value, the others outputs), one per line, listed as outputs.
fn many_variables(n: usize) -> String {
    let mut xml = String::from(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<fmiModelDescription fmiVersion=\"2.0\" \
         modelName=\"Big\" guid=\"{big}\">\n<CoSimulation modelIdentifier=\"Big\"/>\n\
         <ModelVariables>\n",
    );
    for i in 0..n {
        if i % 10 == 0 {
            writeln!(
                xml,
                "  <ScalarVariable name=\"a.b[{i}].p\" valueReference=\"{i}\" \
                 causality=\"parameter\" variability=\"tunable\" description=\"param {i}\">\
                 <Real start=\"{i}.5\" unit=\"m\"/></ScalarVariable>"
            )
            .unwrap();
        } else {
            writeln!(
                xml,
                "  <ScalarVariable name=\"a.b[{i}].y\" valueReference=\"{i}\" \
                 causality=\"output\"><Real/></ScalarVariable>"
            )
            .unwrap();
        }
    }
    xml.push_str("</ModelVariables>\n<ModelStructure><Outputs>\n");
    for i in (0..n).filter(|i| i % 10 != 0) {
        writeln!(xml, "<Unknown index=\"{}\"/>", i + 1).unwrap();
    }
    xml.push_str("</Outputs></ModelStructure>\n</fmiModelDescription>\n");
    xml
}

#[test]
fn quadratic_parsing_of_many_variables_is_gone_50000_variables_parse() {
    // Before the fix each element's line was found by rescanning from the start: 20 000
    // variables took 35 s, 50 000 would take about 220 s.
    let n = 50_000;
    let xml = many_variables(n);
    let md = ModelDescription::parse(xml.as_bytes()).unwrap();
    assert_eq!(md.variables.len(), n);
    assert_eq!(md.outputs.len(), n - n.div_ceil(10));
    let p = md.variable("a.b[49990].p").unwrap();
    assert_eq!(p.causality, Causality::Parameter);
    assert!(matches!(p.kind, VariableKind::Real { start: Some(s), .. } if s == 49990.5));
    // Line numbers are still right at the end of a big file: break the last variable.
    let broken = xml.replace(
        "name=\"a.b[49999].y\" valueReference=\"49999\"",
        "name=\"a.b[49999].y\" valueReference=\"-1\"",
    );
    let err = ModelDescription::parse(broken.as_bytes()).unwrap_err();
    assert!(
        matches!(err, DescriptionError::InvalidAttribute { line, .. } if line == 4 + 49_999 + 1),
        "{err}"
    );
}

#[test]
fn deep_nesting_bomb_is_refused_naming_the_limit() {
    // 200 000 nested elements (a few KB once zipped) did not finish parsing in 120 s.
    let depth = 200_000;
    let mut xml = String::from(
        "<fmiModelDescription fmiVersion=\"2.0\" modelName=\"M\" guid=\"g\">\n\
         <CoSimulation modelIdentifier=\"M\"/>\n",
    );
    xml.push_str(&"<a>".repeat(depth));
    xml.push_str(&"</a>".repeat(depth));
    xml.push_str("</fmiModelDescription>");
    let err = ModelDescription::parse(xml.as_bytes()).unwrap_err();
    assert_eq!(
        err,
        DescriptionError::TooDeep {
            line: 3,
            limit: ParseLimits::DEFAULT_MAX_DEPTH
        }
    );
    let text = err.to_string();
    assert_contains(&text, "nested more than 256 deep");
    // Exactly at the limit is fine; one more level is not.
    let nest = |levels: usize| {
        let inner = levels - 2; // below the root and <x>
        format!(
            "<fmiModelDescription fmiVersion=\"2.0\" modelName=\"M\" guid=\"g\">\
             <CoSimulation modelIdentifier=\"M\"/><x>{}{}</x></fmiModelDescription>",
            "<a>".repeat(inner),
            "</a>".repeat(inner)
        )
    };
    let limits = ParseLimits {
        max_depth: 10,
        ..ParseLimits::default()
    };
    assert!(ModelDescription::parse_with_limits(nest(10).as_bytes(), limits).is_ok());
    assert!(matches!(
        ModelDescription::parse_with_limits(nest(11).as_bytes(), limits),
        Err(DescriptionError::TooDeep { limit: 10, .. })
    ));
}

#[test]
fn oversized_description_is_refused_before_parsing_naming_the_limit() {
    // A 300 MB attribute used 884 MB of memory; the limit is checked on the byte count first.
    let xml = many_variables(10);
    let limits = ParseLimits {
        max_bytes: xml.len() - 1,
        ..ParseLimits::default()
    };
    let err = ModelDescription::parse_with_limits(xml.as_bytes(), limits).unwrap_err();
    assert_eq!(
        err,
        DescriptionError::TooLarge {
            size: xml.len(),
            limit: xml.len() - 1
        }
    );
    assert!(
        err.to_string().contains(&format!(
            "more than the limit of {} bytes for modelDescription.xml",
            xml.len() - 1
        )),
        "{err}"
    );
    let limits = ParseLimits {
        max_bytes: xml.len(),
        ..ParseLimits::default()
    };
    assert!(ModelDescription::parse_with_limits(xml.as_bytes(), limits).is_ok());
    assert_eq!(ParseLimits::default().max_bytes, 256 << 20);
}

#[test]
fn huge_invalid_attribute_is_quoted_briefly_in_the_error() {
    let big = "x".repeat(1 << 20);
    let xml =
        many_variables(3).replace("valueReference=\"1\"", &format!("valueReference=\"{big}\""));
    let err = ModelDescription::parse(xml.as_bytes()).unwrap_err();
    let text = err.to_string();
    assert!(text.len() < 1000, "{} bytes", text.len());
    assert_contains(&text, &format!("({} bytes in all)", big.len()));
}

#[test]
fn many_attributes_on_one_element_parse_in_linear_time_and_duplicates_are_refused() {
    // quick-xml's duplicate check is quadratic in the attribute count; ours is not.
    let extra: String = (0..100_000).map(|i| format!(" x{i}=\"1\"")).collect();
    let xml = many_variables(2).replace(
        "<ScalarVariable name=\"a.b[1].y\"",
        &format!("<ScalarVariable{extra} name=\"a.b[1].y\""),
    );
    assert_eq!(
        ModelDescription::parse(xml.as_bytes())
            .unwrap()
            .variables
            .len(),
        2
    );
    let dup = xml.replace(" x99999=\"1\"", " x5=\"2\"");
    let err = ModelDescription::parse(dup.as_bytes()).unwrap_err();
    assert!(
        err.to_string().contains("has the attribute x5 twice"),
        "{err}"
    );
}

fn utf16(text: &str, big_endian: bool, bom: bool) -> Vec<u8> {
    let mut out = Vec::new();
    let units = (bom.then_some(0xFEFF_u16))
        .into_iter()
        .chain(text.encode_utf16());
    for u in units {
        out.extend_from_slice(&if big_endian {
            u.to_be_bytes()
        } else {
            u.to_le_bytes()
        });
    }
    out
}

#[test]
fn utf16_description_says_fmi_requires_utf8() {
    // It used to get a confusing message about the root element.
    let xml = many_variables(3).replace("encoding=\"UTF-8\"", "encoding=\"UTF-16\"");
    for (big_endian, bom, what) in [
        (false, true, "UTF-16 (little-endian byte-order mark)"),
        (true, true, "UTF-16 (big-endian byte-order mark)"),
        (false, false, "UTF-16 little-endian"),
        (true, false, "UTF-16 big-endian"),
    ] {
        let err = ModelDescription::parse(&utf16(&xml, big_endian, bom)).unwrap_err();
        assert!(matches!(err, DescriptionError::NotUtf8 { .. }), "{err:?}");
        let text = err.to_string();
        assert_contains(&text, what);
        assert_contains(&text, "FMI 2.0 requires modelDescription.xml in UTF-8");
    }
    let mut utf32 = vec![0xFF, 0xFE, 0, 0];
    utf32.extend(xml.chars().flat_map(|c| (c as u32).to_le_bytes()));
    assert!(ModelDescription::parse(&utf32)
        .unwrap_err()
        .to_string()
        .contains("UTF-32"));
}

#[test]
fn latin1_description_is_refused_with_the_position_of_the_first_bad_byte() {
    let xml = many_variables(3)
        .replace("encoding=\"UTF-8\"", "encoding=\"ISO-8859-1\"")
        .replace("description=\"param 0\"", "description=\"param \u{e9}\"");
    // As Latin-1: é is the single byte 0xE9, which is not UTF-8.
    let latin1: Vec<u8> = xml.chars().map(|c| c as u32 as u8).collect();
    let err = ModelDescription::parse(&latin1).unwrap_err();
    let text = err.to_string();
    assert_contains(&text, "byte 0xE9 at line 5");
    // Valid UTF-8 bytes, but declared as Latin-1: ambiguous, refused.
    let err = ModelDescription::parse(xml.as_bytes()).unwrap_err();
    assert!(text_has(&err, "declares encoding=\"ISO-8859-1\""), "{err}");
    // ASCII-only under another declaration reads the same either way: accepted.
    let ascii = many_variables(3).replace("encoding=\"UTF-8\"", "encoding=\"ISO-8859-1\"");
    assert!(ModelDescription::parse(ascii.as_bytes()).is_ok());
    // UTF-8 with non-ASCII text as declared: accepted.
    let utf8 = xml.replace("encoding=\"ISO-8859-1\"", "encoding=\"utf-8\"");
    let md = ModelDescription::parse(utf8.as_bytes()).unwrap();
    assert_eq!(md.variables[0].description.as_deref(), Some("param \u{e9}"));
}

fn text_has(err: &DescriptionError, needle: &str) -> bool {
    err.to_string().contains(needle)
}

#[test]
fn nul_byte_in_a_variable_name_is_refused() {
    let xml = many_variables(3).replace("name=\"a.b[1].y\"", "name=\"a.b[1]\0.y\"");
    let err = ModelDescription::parse(xml.as_bytes()).unwrap_err();
    assert!(
        matches!(err, DescriptionError::Malformed { line: 6, .. }),
        "{err:?}"
    );
    assert!(text_has(&err, "NUL byte"), "{err}");
    // As a character reference too (XML 1.0 forbids &#0;).
    let xml = many_variables(3).replace("name=\"a.b[1].y\"", "name=\"a.b[1]&#0;.y\"");
    assert!(matches!(
        ModelDescription::parse(xml.as_bytes()),
        Err(DescriptionError::Malformed { line: 6, .. })
    ));
}
