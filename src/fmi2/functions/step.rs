//! Stepping (fmi2DoStep, status queries) and the functions this FMU does not support.

use crate::fmi2::instance::{Failure, Instance};
use crate::fmi2::state::{Func, State};
use crate::fmi2::types::*;

use super::*;

// ---------------------------------------------------------------- unsupported

fn unsupported(c: Fmi2Component, func: Func, fname: &'static str, why: &'static str) -> Fmi2Status {
    with_instance(c, func, fname, |_| {
        Err(Failure::error(format!("not supported: {why}")))
    })
}

/// fmi2GetDirectionalDerivative: not supported (providesDirectionalDerivative = false).
///
/// # Safety
/// FMI 2.0 contract: `c` from fmi2Instantiate.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetDirectionalDerivative(
    c: Fmi2Component,
    _v_unknown: *const Fmi2ValueReference,
    _n_unknown: usize,
    _v_known: *const Fmi2ValueReference,
    _n_known: usize,
    _dv_known: *const Fmi2Real,
    _dv_unknown: *mut Fmi2Real,
) -> Fmi2Status {
    unsupported(
        c,
        Func::GetDirectionalDerivative,
        "fmi2GetDirectionalDerivative",
        "this FMU declares providesDirectionalDerivative=\"false\"",
    )
}

/// fmi2SetRealInputDerivatives: not supported (canInterpolateInputs = false).
///
/// # Safety
/// FMI 2.0 contract: `c` from fmi2Instantiate.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetRealInputDerivatives(
    c: Fmi2Component,
    _vr: *const Fmi2ValueReference,
    _nvr: usize,
    _order: *const Fmi2Integer,
    _value: *const Fmi2Real,
) -> Fmi2Status {
    unsupported(
        c,
        Func::SetRealInputDerivatives,
        "fmi2SetRealInputDerivatives",
        "this FMU declares canInterpolateInputs=\"false\"",
    )
}

/// fmi2GetRealOutputDerivatives: not supported (maxOutputDerivativeOrder = 0).
///
/// # Safety
/// FMI 2.0 contract: `c` from fmi2Instantiate.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetRealOutputDerivatives(
    c: Fmi2Component,
    _vr: *const Fmi2ValueReference,
    _nvr: usize,
    _order: *const Fmi2Integer,
    _value: *mut Fmi2Real,
) -> Fmi2Status {
    unsupported(
        c,
        Func::GetRealOutputDerivatives,
        "fmi2GetRealOutputDerivatives",
        "this FMU declares maxOutputDerivativeOrder=\"0\"",
    )
}

/// fmi2CancelStep: not supported (steps are synchronous; never in StepInProgress).
///
/// # Safety
/// FMI 2.0 contract: `c` from fmi2Instantiate.
#[no_mangle]
pub unsafe extern "C" fn fmi2CancelStep(c: Fmi2Component) -> Fmi2Status {
    unsupported(
        c,
        Func::CancelStep,
        "fmi2CancelStep",
        "fmi2DoStep always completes synchronously",
    )
}

// ---------------------------------------------------------------- stepping

/// fmi2DoStep.
///
/// # Safety
/// FMI 2.0 contract: `c` from fmi2Instantiate.
#[no_mangle]
pub unsafe extern "C" fn fmi2DoStep(
    c: Fmi2Component,
    current_communication_point: Fmi2Real,
    communication_step_size: Fmi2Real,
    _no_set_fmu_state_prior: Fmi2Boolean,
) -> Fmi2Status {
    with_instance(c, Func::DoStep, "fmi2DoStep", |inst| {
        inst.do_step(current_communication_point, communication_step_size)
    })
}

fn status_query<T>(
    c: Fmi2Component,
    fname: &'static str,
    value: *mut T,
    get: impl FnOnce(&Instance) -> Result<T, Failure>,
) -> Fmi2Status {
    with_instance(c, Func::GetStatus, fname, |inst| {
        if value.is_null() {
            return Err(null_arg("value"));
        }
        let v = get(inst)?;
        // SAFETY: non-NULL writable value (FMI contract).
        unsafe { value.write(v) };
        Ok(FMI2_OK)
    })
}

fn no_such_status(kind: Fmi2StatusKind) -> Failure {
    Failure::discard(format!(
        "status kind {kind} is not available: fmi2DoStep is synchronous, nothing is ever pending"
    ))
}

/// fmi2GetStatus: nothing is ever pending (fmi2Discard).
///
/// # Safety
/// FMI 2.0 contract: `c` from fmi2Instantiate; `value` writable.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetStatus(
    c: Fmi2Component,
    kind: Fmi2StatusKind,
    value: *mut Fmi2Status,
) -> Fmi2Status {
    status_query(c, "fmi2GetStatus", value, |_| Err(no_such_status(kind)))
}

/// fmi2GetRealStatus: fmi2LastSuccessfulTime gives the current time.
///
/// # Safety
/// FMI 2.0 contract: `c` from fmi2Instantiate; `value` writable.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetRealStatus(
    c: Fmi2Component,
    kind: Fmi2StatusKind,
    value: *mut Fmi2Real,
) -> Fmi2Status {
    status_query(c, "fmi2GetRealStatus", value, |inst| {
        if kind == FMI2_LAST_SUCCESSFUL_TIME {
            Ok(inst.time())
        } else {
            Err(no_such_status(kind))
        }
    })
}

/// fmi2GetIntegerStatus: no integer status exists (fmi2Discard).
///
/// # Safety
/// FMI 2.0 contract: `c` from fmi2Instantiate; `value` writable.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetIntegerStatus(
    c: Fmi2Component,
    kind: Fmi2StatusKind,
    value: *mut Fmi2Integer,
) -> Fmi2Status {
    status_query(c, "fmi2GetIntegerStatus", value, |_| {
        Err(no_such_status(kind))
    })
}

/// fmi2GetBooleanStatus: fmi2Terminated is true after fmi2Terminate, and after a step the model
/// could not take (fmi2Discard: the simulation ends at the current time, e.g. the bogie's speed
/// ramp reaching 1 m/s).
///
/// # Safety
/// FMI 2.0 contract: `c` from fmi2Instantiate; `value` writable.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetBooleanStatus(
    c: Fmi2Component,
    kind: Fmi2StatusKind,
    value: *mut Fmi2Boolean,
) -> Fmi2Status {
    status_query(c, "fmi2GetBooleanStatus", value, |inst| {
        if kind == FMI2_TERMINATED {
            Ok(Fmi2Boolean::from(matches!(
                inst.state,
                State::Terminated | State::StepFailed
            )))
        } else {
            Err(no_such_status(kind))
        }
    })
}

/// fmi2GetStringStatus: nothing is ever pending (fmi2Discard).
///
/// # Safety
/// FMI 2.0 contract: `c` from fmi2Instantiate; `value` writable.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetStringStatus(
    c: Fmi2Component,
    kind: Fmi2StatusKind,
    value: *mut Fmi2String,
) -> Fmi2Status {
    status_query(c, "fmi2GetStringStatus", value, |_| {
        Err(no_such_status(kind))
    })
}
