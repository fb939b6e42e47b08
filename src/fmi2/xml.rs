//! modelDescription.xml, the GUID and documentation/index.html, generated from a model's
//! variable table (pure Rust, no C ABI).

use std::fmt::Write as _;

use super::logger::LOG_CATEGORIES;
use crate::models::{Causality, Initial, ModelInfo, Start, Variability, Variable};

/// SI base-unit exponents (kg, m, s, A, K, mol, cd, rad) of the units models may use.
pub const UNITS: &[(&str, [i32; 8])] = &[
    ("kg", [1, 0, 0, 0, 0, 0, 0, 0]),
    ("m", [0, 1, 0, 0, 0, 0, 0, 0]),
    ("s", [0, 0, 1, 0, 0, 0, 0, 0]),
    ("rad", [0, 0, 0, 0, 0, 0, 0, 1]),
    ("m/s", [0, 1, -1, 0, 0, 0, 0, 0]),
    ("m/s2", [0, 1, -2, 0, 0, 0, 0, 0]),
    ("rad/s", [0, 0, -1, 0, 0, 0, 0, 1]),
    ("rad/s2", [0, 0, -2, 0, 0, 0, 0, 1]),
    ("N", [1, 1, -2, 0, 0, 0, 0, 0]),
    ("N/m", [1, 0, -2, 0, 0, 0, 0, 0]),
    ("N.s/m", [1, 0, -1, 0, 0, 0, 0, 0]),
    ("N.m", [1, 2, -2, 0, 0, 0, 0, 0]),
    ("N.m/rad", [1, 2, -2, 0, 0, 0, 0, -1]),
    ("N.m.s/rad", [1, 2, -1, 0, 0, 0, 0, -1]),
    ("kg.m2", [1, 2, 0, 0, 0, 0, 0, 0]),
    ("kg/m", [1, -1, 0, 0, 0, 0, 0, 0]),
    ("N.m2", [1, 3, -2, 0, 0, 0, 0, 0]),
    ("1/m", [0, -1, 0, 0, 0, 0, 0, 0]),
    ("Pa", [1, -1, -2, 0, 0, 0, 0, 0]),
    ("s2/m", [0, -1, 2, 0, 0, 0, 0, 0]),
    ("m/s2/g", [0, 0, 0, 0, 0, 0, 0, 0]),
    ("1", [0, 0, 0, 0, 0, 0, 0, 0]),
];

const BASE_NAMES: [&str; 8] = ["kg", "m", "s", "A", "K", "mol", "cd", "rad"];

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

fn fmt_f64(v: f64) -> String {
    // Rust's Display is the shortest string that round-trips.
    format!("{v}")
}

fn causality(c: Causality) -> &'static str {
    match c {
        Causality::Parameter => "parameter",
        Causality::CalculatedParameter => "calculatedParameter",
        Causality::Input => "input",
        Causality::Output => "output",
        Causality::Local => "local",
    }
}

fn variability(v: Variability) -> &'static str {
    match v {
        Variability::Constant => "constant",
        Variability::Fixed => "fixed",
        Variability::Tunable => "tunable",
        Variability::Discrete => "discrete",
        Variability::Continuous => "continuous",
    }
}

fn initial(i: Initial) -> &'static str {
    match i {
        Initial::Exact => "exact",
        Initial::Approx => "approx",
        Initial::Calculated => "calculated",
    }
}

/// Canonical text of the interface, hashed into the GUID.
fn interface_text(info: &ModelInfo) -> String {
    let mut s = format!("railuq/{}\n", info.name);
    for v in info.variables {
        let _ = writeln!(
            s,
            "{}|{}|{:?}|{:?}|{:?}|{:?}|{:?}|{:?}",
            v.name, v.vr, v.start, v.causality, v.variability, v.initial, v.unit, v.min
        );
        // Only where declared, so that the GUIDs of models without a maximum stay as they were.
        if let Some(max) = v.max {
            s.pop();
            let _ = writeln!(s, "|max {max:?}");
        }
    }
    s
}

/// The model's GUID: a hash of its interface (names, references, types, start values,
/// causality, variability, units), so it changes exactly when the interface does.
pub fn guid(info: &ModelInfo) -> String {
    let text = interface_text(info);
    let a = super::instance::fnv1a64(text.as_bytes());
    let b = super::instance::fnv1a64(format!("{text}#2").as_bytes());
    format!(
        "{{{:08x}-{:04x}-{:04x}-{:04x}-{:012x}}}",
        (a >> 32) as u32,
        (a >> 16) as u16,
        a as u16,
        (b >> 48) as u16,
        b & 0xffff_ffff_ffff
    )
}

/// Errors in a model's variable table found while generating its description.
#[derive(Debug, thiserror::Error)]
pub enum XmlError {
    /// A variable uses a unit missing from [`UNITS`].
    #[error("model {model}: variable '{var}' uses unit '{unit}' which is not in the unit table")]
    UnknownUnit {
        /// Model name.
        model: &'static str,
        /// Variable name.
        var: &'static str,
        /// Unit name.
        unit: &'static str,
    },
}

fn type_element(v: &Variable) -> String {
    let mut attrs = String::new();
    let tag = match v.start {
        Start::Real(start) => {
            if let Some(u) = v.unit {
                let _ = write!(attrs, " unit=\"{}\"", escape(u));
            }
            if let Some(m) = v.min {
                let _ = write!(attrs, " min=\"{}\"", fmt_f64(m));
            }
            if let Some(m) = v.max {
                let _ = write!(attrs, " max=\"{}\"", fmt_f64(m));
            }
            if let Some(s) = start {
                let _ = write!(attrs, " start=\"{}\"", fmt_f64(s));
            }
            "Real"
        }
        Start::Integer(start) => {
            if let Some(s) = start {
                let _ = write!(attrs, " start=\"{s}\"");
            }
            "Integer"
        }
        Start::Boolean(start) => {
            if let Some(s) = start {
                let _ = write!(attrs, " start=\"{s}\"");
            }
            "Boolean"
        }
        Start::String(start) => {
            if let Some(s) = start {
                let _ = write!(attrs, " start=\"{}\"", escape(s));
            }
            "String"
        }
    };
    format!("<{tag}{attrs}/>")
}

/// Whether the variable belongs to ModelStructure/InitialUnknowns (Co-Simulation: outputs
/// and calculated parameters whose initial is approx or calculated).
fn is_initial_unknown(v: &Variable) -> bool {
    match v.causality {
        Causality::Output => v.initial != Some(Initial::Exact),
        Causality::CalculatedParameter => v.initial != Some(Initial::Exact),
        _ => false,
    }
}

/// The complete modelDescription.xml of a model.
pub fn model_description(info: &ModelInfo) -> Result<String, XmlError> {
    let mut used_units: Vec<&str> = Vec::new();
    for v in info.variables {
        if let Some(u) = v.unit {
            if !UNITS.iter().any(|(n, _)| *n == u) {
                return Err(XmlError::UnknownUnit {
                    model: info.name,
                    var: v.name,
                    unit: u,
                });
            }
            if !used_units.contains(&u) {
                used_units.push(u);
            }
        }
    }
    let mut x = String::new();
    x.push_str("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    let _ = writeln!(
        x,
        "<fmiModelDescription fmiVersion=\"2.0\" modelName=\"{}\" guid=\"{}\" description=\"{}\" generationTool=\"railuq {}\" variableNamingConvention=\"flat\" numberOfEventIndicators=\"0\">",
        info.name,
        guid(info),
        escape(info.description),
        env!("CARGO_PKG_VERSION"),
    );
    let _ = writeln!(
        x,
        "  <CoSimulation modelIdentifier=\"{}\" canHandleVariableCommunicationStepSize=\"true\" canInterpolateInputs=\"false\" maxOutputDerivativeOrder=\"0\" canRunAsynchronuously=\"false\" canBeInstantiatedOnlyOncePerProcess=\"false\" canNotUseMemoryManagementFunctions=\"true\" canGetAndSetFMUstate=\"true\" canSerializeFMUstate=\"true\" providesDirectionalDerivative=\"false\"/>",
        info.name
    );
    if !used_units.is_empty() {
        x.push_str("  <UnitDefinitions>\n");
        for u in &used_units {
            let exps = UNITS
                .iter()
                .find(|(n, _)| n == u)
                .map(|(_, e)| e)
                .expect("checked above");
            let mut attrs = String::new();
            for (name, e) in BASE_NAMES.iter().zip(exps) {
                if *e != 0 {
                    let _ = write!(attrs, " {name}=\"{e}\"");
                }
            }
            let _ = writeln!(
                x,
                "    <Unit name=\"{}\"><BaseUnit{attrs}/></Unit>",
                escape(u)
            );
        }
        x.push_str("  </UnitDefinitions>\n");
    }
    x.push_str("  <LogCategories>\n");
    for (name, desc) in LOG_CATEGORIES {
        let _ = writeln!(
            x,
            "    <Category name=\"{name}\" description=\"{}\"/>",
            escape(desc)
        );
    }
    x.push_str("  </LogCategories>\n");
    let _ = writeln!(
        x,
        "  <DefaultExperiment startTime=\"{}\" stopTime=\"{}\" stepSize=\"{}\"/>",
        fmt_f64(info.default_start),
        fmt_f64(info.default_stop),
        fmt_f64(info.default_step)
    );
    x.push_str("  <ModelVariables>\n");
    for (i, v) in info.variables.iter().enumerate() {
        let mut attrs = format!(
            "name=\"{}\" valueReference=\"{}\" description=\"{}\" causality=\"{}\" variability=\"{}\"",
            escape(v.name),
            v.vr,
            escape(v.description),
            causality(v.causality),
            variability(v.variability)
        );
        if let Some(init) = v.initial {
            let _ = write!(attrs, " initial=\"{}\"", initial(init));
        }
        let _ = writeln!(x, "    <!-- index {} -->", i + 1);
        let _ = writeln!(
            x,
            "    <ScalarVariable {attrs}>{}</ScalarVariable>",
            type_element(v)
        );
    }
    x.push_str("  </ModelVariables>\n  <ModelStructure>\n");
    let outputs: Vec<usize> = info
        .variables
        .iter()
        .enumerate()
        .filter(|(_, v)| v.causality == Causality::Output)
        .map(|(i, _)| i + 1)
        .collect();
    if !outputs.is_empty() {
        x.push_str("    <Outputs>\n");
        for i in &outputs {
            let _ = writeln!(x, "      <Unknown index=\"{i}\"/>");
        }
        x.push_str("    </Outputs>\n");
    }
    let initial_unknowns: Vec<usize> = info
        .variables
        .iter()
        .enumerate()
        .filter(|(_, v)| is_initial_unknown(v))
        .map(|(i, _)| i + 1)
        .collect();
    if !initial_unknowns.is_empty() {
        x.push_str("    <InitialUnknowns>\n");
        for i in &initial_unknowns {
            let _ = writeln!(x, "      <Unknown index=\"{i}\"/>");
        }
        x.push_str("    </InitialUnknowns>\n");
    }
    x.push_str("  </ModelStructure>\n</fmiModelDescription>\n");
    Ok(x)
}

/// documentation/index.html: the model's equations and its variable table.
pub fn documentation(info: &ModelInfo) -> String {
    let mut rows = String::new();
    for v in info.variables {
        let start = match v.start {
            Start::Real(Some(s)) => fmt_f64(s),
            Start::Integer(Some(s)) => s.to_string(),
            Start::Boolean(Some(s)) => s.to_string(),
            Start::String(Some(s)) => escape(s),
            _ => String::new(),
        };
        let _ = writeln!(
            rows,
            "<tr><td><code>{}</code></td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            escape(v.name),
            v.vr,
            causality(v.causality),
            variability(v.variability),
            start,
            v.unit.map(escape).unwrap_or_default(),
            escape(v.description)
        );
    }
    format!(
        r#"<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>{name} — railuq FMU</title>
<style>body{{font-family:sans-serif;max-width:60em;margin:2em auto;line-height:1.4}}
table{{border-collapse:collapse}}td,th{{border:1px solid #ccc;padding:.2em .5em;text-align:left}}
pre{{background:#f6f6f6;padding:.5em}}</style></head><body>
<h1>{name}</h1>
<p>{desc}</p>
<p>FMI 2.0 Co-Simulation FMU generated by railuq {version}. GUID <code>{guid}</code>.</p>
<h2>Model</h2>
{doc}
<h2>Variables</h2>
<table><tr><th>name</th><th>vr</th><th>causality</th><th>variability</th><th>start</th><th>unit</th><th>description</th></tr>
{rows}</table>
<h2>Default experiment</h2>
<p>start {start} s, stop {stop} s, communication step {step} s.</p>
</body></html>
"#,
        name = info.name,
        desc = escape(info.description),
        version = env!("CARGO_PKG_VERSION"),
        guid = guid(info),
        doc = info.documentation_html,
        start = fmt_f64(info.default_start),
        stop = fmt_f64(info.default_stop),
        step = fmt_f64(info.default_step),
    )
}

/// The Markdown table of a model's variables, as the user guide shows it
/// (`docs/src/reference/fmu-variables.md`, between the markers [`readme_markers`]); `make xml`
/// rewrites those blocks.
pub fn markdown_table(info: &ModelInfo) -> String {
    let mut t = String::from(
        "| name | vr | type | causality | variability | start | unit | description |\n\
         |---|---|---|---|---|---|---|---|\n",
    );
    for v in info.variables {
        let (ty, start) = match v.start {
            Start::Real(s) => ("Real", s.map(fmt_f64)),
            Start::Integer(s) => ("Integer", s.map(|x| x.to_string())),
            Start::Boolean(s) => ("Boolean", s.map(|x| x.to_string())),
            Start::String(s) => ("String", s.map(str::to_owned)),
        };
        let _ = writeln!(
            t,
            "| {} | {} | {ty} | {} | {} | {} | {} | {} |",
            v.name,
            v.vr,
            causality(v.causality),
            variability(v.variability),
            start.unwrap_or_default(),
            v.unit.unwrap_or(""),
            v.description.replace('|', "\\|")
        );
    }
    t
}

/// The comment lines that enclose a model's generated table in the guide's variables page.
pub fn readme_markers(info: &ModelInfo) -> (String, String) {
    (
        format!(
            "<!-- variables of {} (generated by `make xml`) -->\n",
            info.name
        ),
        format!("<!-- end of the variables of {} -->\n", info.name),
    )
}

/// `text` with every model's marked variable block replaced by its current table; models
/// without markers are left out. Returns the new text and how many blocks were found.
pub fn update_readme_tables(text: &str, models: &[&ModelInfo]) -> (String, usize) {
    let mut out = text.to_owned();
    let mut found = 0;
    for info in models {
        let (begin, end) = readme_markers(info);
        let Some(b) = out.find(&begin) else { continue };
        let from = b + begin.len();
        let Some(e) = out[from..].find(&end) else {
            continue;
        };
        out.replace_range(from..from + e, &markdown_table(info));
        found += 1;
    }
    (out, found)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::models::registry;

    /// The checked-in modelDescription/*.xml must equal what the variable tables generate.
    #[test]
    fn checked_in_model_descriptions_do_not_drift() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("modelDescription");
        for e in registry() {
            let path = dir.join(format!("{}.xml", e.info.name));
            let on_disk = std::fs::read_to_string(&path)
                .unwrap_or_else(|err| panic!("{}: {err}; run `make xml`", path.display()));
            let generated = model_description(e.info).unwrap();
            assert!(
                on_disk == generated,
                "{} drifted from the variable table of {}: run `make xml` and commit",
                path.display(),
                e.info.name
            );
        }
    }

    #[test]
    fn guid_is_stable_and_distinct() {
        let g = guid(registry()[0].info);
        assert_eq!(g, guid(registry()[0].info));
        assert_eq!(g.len(), 38);
        let all: Vec<_> = registry().iter().map(|e| guid(e.info)).collect();
        let mut d = all.clone();
        d.sort();
        d.dedup();
        assert_eq!(d.len(), all.len());
    }

    #[test]
    fn description_lists_outputs_as_initial_unknowns() {
        let xml = model_description(registry()[0].info).unwrap();
        assert!(xml.contains("<InitialUnknowns>"));
        assert!(xml.contains("fmiVersion=\"2.0\""));
        assert!(xml.contains("<Unit name=\"N/m\"><BaseUnit kg=\"1\" s=\"-2\"/></Unit>"));
    }

    /// The guide's variable tables must equal what the variable tables generate.
    #[test]
    fn guide_variable_tables_do_not_drift() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("docs/src/reference/fmu-variables.md");
        let text = std::fs::read_to_string(&path).unwrap();
        let infos: Vec<&ModelInfo> = registry().iter().map(|e| e.info).collect();
        let (updated, found) = update_readme_tables(&text, &infos);
        assert_eq!(
            found,
            infos.len(),
            "docs/src/reference/fmu-variables.md lacks a marked variable table"
        );
        assert!(
            updated == text,
            "docs/src/reference/fmu-variables.md drifted from the models: run `make xml` and commit"
        );
    }

    #[test]
    fn markdown_table_escapes_pipes_and_lists_every_variable() {
        let info = registry()[0].info;
        let t = markdown_table(info);
        assert_eq!(t.lines().count(), info.variables.len() + 2);
        let (text, n) = update_readme_tables("x\n<!-- variables of Wheel (generated by `make xml`) -->\nold\n<!-- end of the variables of Wheel -->\ny\n", &[info]);
        assert_eq!(n, 1);
        assert!(text.contains(&t) && !text.contains("old"));
    }
}
