//! The declared `min`/`max` of the FMU's variables against a study's random parameters: a
//! distribution whose whole support lies outside the declared range is refused; design points
//! outside it are run (never dropped) and reported with their probability weight. A normal
//! input with a positive mean whose variable must stay positive (a declared `min >= 0`, or a
//! unit of a positive physical quantity, [`POSITIVE_UNITS`]) is reported when it reaches
//! values <= 0, unless the study says `allow_negative = true`.

use crate::fmu::{Fmu, ModelDescription, VariableKind};
use crate::report::units::unit_of;
use crate::spec::{FixedValue, Study};
use crate::study::plan::interface::{InterfaceError, VariableProblem};
use crate::uq::method::Design;
use crate::uq::Distribution;

/// The declared range of variable `name` (either end may be open), if it declares one.
fn declared_range(fmu: &Fmu, name: &str) -> Option<(f64, f64)> {
    declared_range_in(fmu.description(), name)
}

/// [`declared_range`] in a modelDescription.
fn declared_range_in(md: &ModelDescription, name: &str) -> Option<(f64, f64)> {
    let (min, max) = match &md.variable(name)?.kind {
        VariableKind::Real { min, max, .. } => (*min, *max),
        VariableKind::Integer { min, max, .. } => (min.map(f64::from), max.map(f64::from)),
        _ => return None,
    };
    (min.is_some() || max.is_some()).then(|| {
        (
            min.unwrap_or(f64::NEG_INFINITY),
            max.unwrap_or(f64::INFINITY),
        )
    })
}

/// Units of quantities that are positive by their physics, as FMI `unit` strings (SI, `.`
/// for a product; `·`, `*` and spaces are read as `.`): mass, moment of inertia, linear and
/// rotational stiffness, linear and rotational damping. A variable with one of these units
/// (or a declared `min >= 0`) must stay positive.
pub const POSITIVE_UNITS: &[&str] = &[
    "kg",
    "t",
    "kg.m2",
    "N/m",
    "kN/m",
    "MN/m",
    "N.m/rad",
    "N.s/m",
    "kN.s/m",
    "N.m.s/rad",
];

/// Whether `unit` is one of [`POSITIVE_UNITS`] (`·`, `*`, spaces and `^2`/`²` normalised).
fn positive_unit(unit: &str) -> bool {
    let u: String = unit
        .trim()
        .replace(['·', '*'], ".")
        .replace(' ', ".")
        .replace("^2", "2")
        .replace('²', "2");
    POSITIVE_UNITS.contains(&u.as_str())
}

/// Whether each random parameter must stay positive: not `allow_negative`, and its variable
/// declares `min >= 0` or has a unit of [`POSITIVE_UNITS`].
fn positive_inputs(study: &Study, md: &ModelDescription) -> Vec<bool> {
    study
        .parameters
        .iter()
        .map(|p| {
            let name = p.name.as_str();
            let min_ok = declared_range_in(md, name).is_some_and(|(min, _)| min >= 0.0);
            !study.allow_negative.iter().any(|n| n == name)
                && (min_ok || unit_of(md, name).is_some_and(|u| positive_unit(&u)))
        })
        .collect()
}

/// The design's sign warnings ([`Design::sign_warnings`]) for the parameters that must stay
/// positive ([`positive_inputs`]).
fn sign_warnings(study: &Study, md: &ModelDescription, design: &Design) -> Vec<String> {
    let positive = positive_inputs(study, md);
    design.sign_warnings(|j| positive.get(j).copied().unwrap_or(false))
}

/// Refuses a random parameter whose distribution lies wholly outside the range its variable
/// declares.
pub fn check_supports(study: &Study, fmu: &Fmu) -> Result<(), InterfaceError> {
    for p in &study.parameters {
        let Some((min, max)) = declared_range(fmu, &p.name) else {
            continue;
        };
        let (lo, hi) = p.distribution.support();
        if hi < min || lo > max {
            return Err(InterfaceError {
                fmu: fmu.path().to_path_buf(),
                problem: VariableProblem::SupportOutsideRange(format!(
                    "random parameter '{}' takes values in [{lo}, {hi}], wholly outside the range \
                     [{min}, {max}] the FMU declares for it (min/max)",
                    p.name
                )),
            });
        }
    }
    Ok(())
}

/// One warning per random parameter with design points outside its variable's declared range:
/// how many and their probability weight (points only below a minimum <= 0 of a positive-mean
/// input are left to the design's sign warning).
pub fn range_warnings(study: &Study, fmu: &Fmu, design: &Design) -> Vec<String> {
    let positive = positive_inputs(study, fmu.description());
    let mut warnings = sign_warnings(study, fmu.description(), design);
    for (j, p) in study.parameters.iter().enumerate() {
        let Some((min, max)) = declared_range(fmu, &p.name) else {
            continue;
        };
        let outside: Vec<usize> = (0..design.len())
            .filter(|&i| {
                let v = design.values[i][j];
                v < min || v > max
            })
            .collect();
        if outside.is_empty() {
            continue;
        }
        // Below a minimum <= 0 only: the sign warning (a positive-mean normal input that must
        // stay positive, at values <= 0) already reports these points.
        let above = outside.iter().any(|&i| design.values[i][j] > max);
        let signed = matches!(p.distribution, Distribution::Normal { .. }) && positive[j];
        if !above && min <= 0.0 && p.distribution.mean() > 0.0 && signed {
            continue;
        }
        let weight: f64 = match &design.weights {
            Some(w) => outside.iter().map(|&i| w[i].abs()).sum(),
            None => outside.len() as f64 / design.len() as f64,
        };
        warnings.push(format!(
            "{} of {} points have {} outside the range [{min}, {max}] the FMU declares for it \
             (min/max; probability weight {weight:.3e}); they are run, not dropped — the model \
             may not be valid there: consider a truncated_normal or a narrower input",
            outside.len(),
            design.len(),
            p.name,
        ));
    }
    warnings.extend(declaration_warnings(study, fmu));
    warnings
}

/// What the modelDescription says against the study's settings: a `[fixed]` Real outside its
/// declared range (as `simulate --set` warns; the FMU may refuse it too), a Sperling
/// `direction` that contradicts its signal's description.
fn declaration_warnings(study: &Study, fmu: &Fmu) -> Vec<String> {
    let fixed = study
        .fixed
        .iter()
        .filter_map(|(name, value)| value_warning(fmu, name, value));
    let describe = |s: &str| fmu.description().variable(s)?.description.clone();
    let directions = study
        .qoi
        .iter()
        .filter_map(|q| q.direction_warning(&describe));
    fixed.chain(directions).collect()
}

/// A warning when the value `value` given for variable `name` (e.g. `simulate --set`) is a
/// number outside the range the FMU declares for it.
pub fn value_warning(fmu: &Fmu, name: &str, value: &FixedValue) -> Option<String> {
    // A fixed Integer outside its declared range is refused, not warned about (and not both).
    if !matches!(
        fmu.description().variable(name)?.kind,
        VariableKind::Real { .. }
    ) {
        return None;
    }
    let (min, max) = declared_range(fmu, name)?;
    let v = match value {
        FixedValue::Number(v) => *v,
        FixedValue::Text(t) => t.trim().parse::<f64>().ok()?,
        _ => return None,
    };
    (v < min || v > max).then(|| {
        format!(
            "{name} = {v} is outside the range [{min}, {max}] the FMU declares for it (min/max); \
             the model may not be valid there"
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::uq::method::Design;
    use crate::uq::Germ;

    /// `free` declares nothing, `floor` min = 0, `stiff` the unit N/m, `damp` a declared type
    /// in N·s/m, `above` min = -1 (values <= 0 allowed by the FMU).
    const XML: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription fmiVersion="2.0" modelName="M" guid="{abc}">
  <CoSimulation modelIdentifier="M"/>
  <UnitDefinitions><Unit name="N/m"/><Unit name="N.s/m"/></UnitDefinitions>
  <TypeDefinitions><SimpleType name="Damping"><Real unit="N.s/m"/></SimpleType></TypeDefinitions>
  <ModelVariables>
<ScalarVariable name="free" valueReference="0" causality="parameter" variability="fixed"><Real start="1"/></ScalarVariable>
<ScalarVariable name="floor" valueReference="1" causality="parameter" variability="fixed"><Real start="1" min="0"/></ScalarVariable>
<ScalarVariable name="stiff" valueReference="2" causality="parameter" variability="fixed"><Real start="1" unit="N/m"/></ScalarVariable>
<ScalarVariable name="damp" valueReference="3" causality="parameter" variability="fixed"><Real start="1" declaredType="Damping"/></ScalarVariable>
<ScalarVariable name="above" valueReference="4" causality="parameter" variability="fixed"><Real start="1" min="-1"/></ScalarVariable>
<ScalarVariable name="y" valueReference="5" causality="output"><Real/></ScalarVariable>
  </ModelVariables>
  <ModelStructure><Outputs><Unknown index="6"/></Outputs></ModelStructure>
</fmiModelDescription>"#;

    fn study(extra: &str) -> Study {
        let mut text = String::from(
            "name = \"s\"\nfmu = \"M.fmu\"\n[experiment]\nstart = 0.0\nstop = 1.0\nstep = 0.5\n\
             [outputs]\nvariables = [\"y\"]\n[method]\nkind = \"mc\"\nsamples = 3\n",
        );
        for name in ["free", "floor", "stiff", "damp", "above"] {
            text += &format!("[[parameters]]\nname = \"{name}\"\nmean = 1.0\nstd = 1.0\n");
            if extra.contains(name) {
                text += "allow_negative = true\n";
            }
        }
        Study::parse(&text, "test", None).unwrap()
    }

    /// Unit-cube points 0.05, 0.5, 0.95: N(1, 1) reaches 1 - 1.645 < 0 at the first.
    fn flagged(study: &Study) -> Vec<String> {
        let md = ModelDescription::parse(XML.as_bytes()).unwrap();
        let cube: Vec<Vec<f64>> = [0.05, 0.5, 0.95].iter().map(|&u| vec![u; 5]).collect();
        let design = Design::mapped(Germ::Uniform, cube, None, &study.random_inputs());
        assert!(
            design.values[0].iter().all(|&v| v < 0.0),
            "{:?}",
            design.values
        );
        sign_warnings(study, &md, &design)
            .iter()
            .map(|w| {
                w.split(" <= 0")
                    .next()
                    .unwrap()
                    .rsplit(' ')
                    .next()
                    .unwrap()
                    .to_owned()
            })
            .collect()
    }

    /// Every normal input with a positive mean warned about values <= 0, even where the FMU
    /// declares no minimum, and nothing could say that a value may be negative.
    #[test]
    fn non_positive_values_warn_only_for_inputs_the_fmu_declares_positive_unless_allowed() {
        assert_eq!(flagged(&study("")), ["floor", "stiff", "damp"]);
        assert_eq!(flagged(&study("stiff floor")), ["damp"]);
        assert!(positive_unit("N·s/m") && positive_unit(" kg*m^2 ") && !positive_unit("m"));
    }
}
