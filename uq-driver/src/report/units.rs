//! Units of a study's variables and quantities, from the FMU's modelDescription, and how
//! the report prints them.
//!
//! The CSV files keep their column names; their units are in `summary.json` (`units`, and
//! `unit` of every output and quantity) and in the sidecar `units.csv` (`file,column,unit`).

use std::collections::BTreeMap;

use crate::fmu::{ModelDescription, VariableKind};
use crate::qoi::scalar::Words;
use crate::qoi::QoiSpec;
use crate::results::{OutputStats, ScalarStats};
use crate::spec::Study;

/// The unit of a dimensionless quantity (FMI writes no unit, or `"1"`).
pub const DIMENSIONLESS: &str = "1";

/// The declared unit of variable `name`, if it is a Real with a `unit` attribute, or with a
/// `declaredType` whose `SimpleType` has one (the variable's own unit wins, as FMI 2.0 says).
pub fn unit_of(md: &ModelDescription, name: &str) -> Option<String> {
    match &md.variable(name)?.kind {
        VariableKind::Real {
            unit,
            declared_type,
            ..
        } => unit.clone().filter(|u| !u.is_empty()).or_else(|| {
            let t = declared_type.as_deref()?;
            md.type_units
                .iter()
                .find(|(name, _)| name == t)
                .map(|(_, u)| u.clone())
        }),
        _ => None,
    }
}

/// The unit of every variable `study` names (random and fixed parameters, outputs, the
/// signals of its quantities) and of every quantity, where the FMU declares one; `time` is
/// always `s`.
pub fn study_units(study: &Study, md: Option<&ModelDescription>) -> BTreeMap<String, String> {
    let mut units = BTreeMap::from([("time".to_string(), "s".to_string())]);
    let Some(md) = md else {
        return units;
    };
    let names = study
        .parameters
        .iter()
        .map(|p| p.name.as_str())
        .chain(study.fixed.keys().map(String::as_str))
        .chain(study.outputs.iter().map(String::as_str))
        .chain(study.qoi.iter().flat_map(QoiSpec::signals));
    for n in names {
        if let Some(u) = unit_of(md, n) {
            units.insert(n.to_owned(), u);
        }
    }
    for q in &study.qoi {
        if let Some(u) = quantity_unit(q, md) {
            for name in q.quantity_names() {
                units.insert(name, u.clone());
            }
        }
    }
    units
}

/// The unit of a quantity: that of the signal it is measured in, or
/// [`DIMENSIONLESS`] for an index.
pub fn quantity_unit(q: &QoiSpec, md: &ModelDescription) -> Option<String> {
    match q.unit_signal() {
        Some(s) => unit_of(md, s),
        None => Some(DIMENSIONLESS.to_owned()),
    }
}

/// Sets the `unit` of every output and quantity from `units`.
pub fn annotate(
    units: &BTreeMap<String, String>,
    outputs: &mut [OutputStats],
    quantities: &mut [ScalarStats],
) {
    for o in outputs {
        o.unit = units.get(&o.name).cloned();
    }
    for q in quantities {
        q.unit = units.get(&q.name).cloned();
    }
}

/// Writes each quantity's definition again with what the FMU says of its variables: the
/// description of the signal it is computed from (`settings.signal_description`, and in the
/// text after the signal's name; for a Sperling index, where on the carbody the acceleration
/// is taken: `Zc_acc_front`, "above the front bogie centre") and the declared units of its
/// thresholds and speeds. The text is built anew from the quantity's parts
/// ([`QoiSpec::definition_with`]), never by searching the old text for the signal's name.
pub fn describe_signals(quantities: &mut [ScalarStats], qoi: &[QoiSpec], md: &ModelDescription) {
    let unit = |name: &str| unit_of(md, name);
    for q in quantities.iter_mut() {
        let Some(spec) = qoi.iter().find(|s| s.quantity_names().contains(&q.name)) else {
            continue;
        };
        let signal = spec.signals().first().map(|s| s.to_string());
        let description = signal.as_deref().and_then(|s| {
            md.variable(s)
                .and_then(|v| v.description.clone())
                .filter(|d| !d.is_empty())
                .map(|d| (s, d))
        });
        if let Some((_, text)) = &description {
            q.definition
                .settings
                .insert("signal_description".into(), text.clone().into());
        }
        let words = Words {
            description: description.as_ref().map(|(s, d)| (*s, d.as_str())),
            unit: Some(&unit),
        };
        q.definition.text = spec.definition_with(&words).text;
    }
}

/// `name [unit]` for an axis label: `q [m]`, `W [-]` for a dimensionless index, or the
/// name alone when the unit is unknown.
pub fn label(name: &str, unit: Option<&str>) -> String {
    match unit {
        Some(u) if u == DIMENSIONLESS => format!("{name} [-]"),
        Some(u) => format!("{name} [{u}]"),
        None => name.to_owned(),
    }
}

/// The unit of a density of a variable in `unit`: `1/m`, `s/m` for `m/s`, `1/(N.s/m)`.
pub fn per(unit: Option<&str>) -> Option<String> {
    match unit {
        None => None,
        Some(u) if u == DIMENSIONLESS => Some(DIMENSIONLESS.to_owned()),
        Some(u) => match u.split_once('/') {
            Some((num, den)) if !num.contains(['.', '*', ' ']) && !den.contains(['.', '*']) => {
                Some(if num == "1" {
                    den.to_owned()
                } else {
                    format!("{den}/{num}")
                })
            }
            _ if u.contains(['.', '*', '/', ' ']) => Some(format!("1/({u})")),
            _ => Some(format!("1/{u}")),
        },
    }
}

/// A number with its unit for text: `64.9 m/s`, `2.31` (dimensionless or unknown).
pub fn with_unit(value: &str, unit: Option<&str>) -> String {
    match unit {
        Some(u) if u != DIMENSIONLESS => format!("{value} {u}"),
        _ => value.to_owned(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_and_density_units() {
        assert_eq!(label("q", Some("m")), "q [m]");
        assert_eq!(label("W", Some(DIMENSIONLESS)), "W [-]");
        assert_eq!(label("x", None), "x");
        assert_eq!(per(Some("m")).as_deref(), Some("1/m"));
        assert_eq!(per(Some("m/s")).as_deref(), Some("s/m"));
        assert_eq!(per(Some("m/s2")).as_deref(), Some("s2/m"));
        assert_eq!(per(Some("N.s/m")).as_deref(), Some("1/(N.s/m)"));
        assert_eq!(per(Some("1/s")).as_deref(), Some("s"));
        assert_eq!(per(Some("1")).as_deref(), Some("1"));
        assert_eq!(per(None), None);
        assert_eq!(with_unit("64.9", Some("m/s")), "64.9 m/s");
        assert_eq!(with_unit("2.31", Some("1")), "2.31");
    }

    #[test]
    fn units_given_through_a_declared_type_are_resolved() {
        // Modelica tools give most units through TypeDefinitions (e.g. the
        // Reference FMU BouncingBall's `v` with declaredType "Velocity"); they were not shown.
        let xml = r#"<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription fmiVersion="2.0" modelName="M" guid="g">
  <CoSimulation modelIdentifier="M"/>
  <TypeDefinitions>
    <SimpleType name="Mode"><Enumeration><Item name="a" value="1"/></Enumeration></SimpleType>
    <SimpleType name="Velocity"><Real quantity="Velocity" unit="m/s"/></SimpleType>
    <SimpleType name="Plain"><Real/></SimpleType>
  </TypeDefinitions>
  <ModelVariables>
    <ScalarVariable name="v" valueReference="0" causality="output"><Real declaredType="Velocity"/></ScalarVariable>
    <ScalarVariable name="w" valueReference="1" causality="output"><Real declaredType="Velocity" unit="km/h"/></ScalarVariable>
    <ScalarVariable name="p" valueReference="2" causality="output"><Real declaredType="Plain"/></ScalarVariable>
    <ScalarVariable name="x" valueReference="3" causality="output"><Real declaredType="Unknown"/></ScalarVariable>
  </ModelVariables>
  <ModelStructure><Outputs><Unknown index="1"/><Unknown index="2"/><Unknown index="3"/><Unknown index="4"/></Outputs></ModelStructure>
</fmiModelDescription>"#;
        let md = ModelDescription::parse(xml.as_bytes()).unwrap();
        assert_eq!(unit_of(&md, "v").as_deref(), Some("m/s"));
        assert_eq!(
            unit_of(&md, "w").as_deref(),
            Some("km/h"),
            "its own unit wins"
        );
        assert_eq!(unit_of(&md, "p"), None);
        assert_eq!(unit_of(&md, "x"), None);
    }
}
