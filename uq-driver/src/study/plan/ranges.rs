//! The declared `min`/`max` of the FMU's variables against a study's random parameters: a
//! distribution whose whole support lies outside the declared range is refused; design points
//! outside it are run (never dropped) and reported with their probability weight.

use crate::fmu::{Fmu, VariableKind};
use crate::spec::{FixedValue, Study};
use crate::study::plan::interface::{InterfaceError, VariableProblem};
use crate::uq::method::Design;

/// The declared range of variable `name` (either end may be open), if it declares one.
fn declared_range(fmu: &Fmu, name: &str) -> Option<(f64, f64)> {
    let (min, max) = match &fmu.description().variable(name)?.kind {
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
    let mut warnings = Vec::new();
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
        // Below a minimum <= 0 only: the design's sign warning (a positive-mean input at
        // values <= 0) already reports these points.
        let above = outside.iter().any(|&i| design.values[i][j] > max);
        if !above && min <= 0.0 && p.distribution.mean() > 0.0 {
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
