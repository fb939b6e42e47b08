//! The `if_ended` rule: which studies can give a run the FMU ends early (the Vehicle's
//! derailment) a value beyond the limit instead of a failed point.

use crate::qoi::scalar::QoiSpec;

/// Why `qois` cannot take their `if_ended` values (`None`: they can, or none is set). A run the
/// FMU ended early has no series after the end and no value of the other quantities, so when
/// one quantity sets `if_ended` every quantity must (and none may be a `hunting_speed`, whose
/// runs are its own), and the study may store no series (`outputs`: statistics over time need
/// every run on the whole grid).
pub(crate) fn ended_value_problem(qois: &[QoiSpec], outputs: &[String]) -> Option<String> {
    let set = qois.iter().find(|q| q.if_ended().is_some())?;
    if let Some(q) = qois.iter().find(|q| q.if_ended().is_none()) {
        return Some(format!(
            "quantity '{}' sets if_ended but '{}' does not: a run the FMU ends early has no \
             value of '{}'; set if_ended on every quantity (max_abs, min, max and range have it)",
            set.name(),
            q.name(),
            q.name()
        ));
    }
    (!outputs.is_empty()).then(|| {
        format!(
            "quantity '{}' sets if_ended, but the study stores output series ([outputs] \
             variables = {outputs:?}), which a run the FMU ends early does not cover; leave them \
             out (the quantities' signals are read without being stored)",
            set.name()
        )
    })
}
