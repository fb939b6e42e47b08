//! fmi2Get* / fmi2Set* of Real, Integer, Boolean and String values.

use std::ffi::CString;

use crate::fmi2::instance::{Failure, Instance};
use crate::fmi2::state::Func;
use crate::fmi2::types::*;
use crate::models::{Model, VarType};

use super::*;

// ---------------------------------------------------------------- get / set

macro_rules! getter {
    ($fname:ident, $cty:ty, $vt:expr, $get:expr) => {
        /// Reads variables (FMI 2.0).
        ///
        /// # Safety
        /// FMI 2.0 contract: `c` from fmi2Instantiate; `vr` and `value` hold `nvr` elements.
        #[no_mangle]
        pub unsafe extern "C" fn $fname(
            c: Fmi2Component,
            vr: *const Fmi2ValueReference,
            nvr: usize,
            value: *mut $cty,
        ) -> Fmi2Status {
            with_instance(c, Func::GetValues, stringify!($fname), |inst| {
                if nvr == 0 {
                    return Ok(FMI2_OK);
                }
                // SAFETY: FMI contract: `nvr` value references.
                let vrs = unsafe { slice(vr, nvr) }.ok_or_else(|| null_arg("vr"))?;
                // SAFETY: FMI contract: room for `nvr` values.
                let out = unsafe { slice_mut(value, nvr) }.ok_or_else(|| null_arg("value"))?;
                inst.get_values(vrs, out, $vt, $get)
            })
        }
    };
}

macro_rules! setter {
    ($fname:ident, $cty:ty, $vt:expr, $check:expr, $set:expr) => {
        /// Writes variables (FMI 2.0).
        ///
        /// # Safety
        /// FMI 2.0 contract: `c` from fmi2Instantiate; `vr` and `value` hold `nvr` elements.
        #[no_mangle]
        pub unsafe extern "C" fn $fname(
            c: Fmi2Component,
            vr: *const Fmi2ValueReference,
            nvr: usize,
            value: *const $cty,
        ) -> Fmi2Status {
            with_instance(c, Func::SetValues, stringify!($fname), |inst| {
                if nvr == 0 {
                    return Ok(FMI2_OK);
                }
                // SAFETY: FMI contract: `nvr` value references.
                let vrs = unsafe { slice(vr, nvr) }.ok_or_else(|| null_arg("vr"))?;
                // SAFETY: FMI contract: `nvr` values.
                let vals = unsafe { slice(value, nvr) }.ok_or_else(|| null_arg("value"))?;
                #[allow(clippy::redundant_closure_call)]
                ($check)(inst, vrs, vals)?;
                inst.set_values(vrs, vals, $vt, $set)
            })
        }
    };
}

fn no_check<T>(_: &mut Instance, _: &[u32], _: &[T]) -> Result<(), Failure> {
    Ok(())
}

fn check_finite(inst: &mut Instance, vrs: &[u32], vals: &[f64]) -> Result<(), Failure> {
    if vals.contains(&TEST_PANIC_VALUE) && test_panic_armed() {
        panic!("forced panic (test hook)");
    }
    for (&vr, &v) in vrs.iter().zip(vals) {
        if !v.is_finite() {
            let name = inst
                .lookup(vr, VarType::Real)
                .map(|v| v.name)
                .unwrap_or("?");
            return Err(Failure::error(format!(
                "non-finite value {v} for '{name}' (value reference {vr})"
            )));
        }
    }
    Ok(())
}

getter!(fmi2GetReal, Fmi2Real, VarType::Real, |m: &dyn Model, vr| m
    .get_real(vr));
getter!(
    fmi2GetInteger,
    Fmi2Integer,
    VarType::Integer,
    |m: &dyn Model, vr| m.get_integer(vr)
);
getter!(
    fmi2GetBoolean,
    Fmi2Boolean,
    VarType::Boolean,
    |m: &dyn Model, vr| m.get_boolean(vr).map(Fmi2Boolean::from)
);
setter!(
    fmi2SetReal,
    Fmi2Real,
    VarType::Real,
    check_finite,
    |m: &mut dyn Model, vr, v| m.set_real(vr, v)
);
setter!(
    fmi2SetInteger,
    Fmi2Integer,
    VarType::Integer,
    no_check,
    |m: &mut dyn Model, vr, v| m.set_integer(vr, v)
);
setter!(
    fmi2SetBoolean,
    Fmi2Boolean,
    VarType::Boolean,
    no_check,
    |m: &mut dyn Model, vr, v: Fmi2Boolean| m.set_boolean(vr, v != 0)
);

/// fmi2GetString: the returned pointers stay valid until the next call on this instance.
///
/// # Safety
/// FMI 2.0 contract: `c` from fmi2Instantiate; `vr` and `value` hold `nvr` elements.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetString(
    c: Fmi2Component,
    vr: *const Fmi2ValueReference,
    nvr: usize,
    value: *mut Fmi2String,
) -> Fmi2Status {
    with_instance(c, Func::GetValues, "fmi2GetString", |inst| {
        if nvr == 0 {
            return Ok(FMI2_OK);
        }
        // SAFETY: FMI contract: `nvr` value references.
        let vrs = unsafe { slice(vr, nvr) }.ok_or_else(|| null_arg("vr"))?;
        // SAFETY: FMI contract: room for `nvr` pointers.
        let out = unsafe { slice_mut(value, nvr) }.ok_or_else(|| null_arg("value"))?;
        let strings = inst.get_strings(vrs)?;
        inst.strings = strings
            .into_iter()
            .map(|s| CString::new(s.replace('\0', "?")).unwrap_or_default())
            .collect();
        for (o, s) in out.iter_mut().zip(&inst.strings) {
            *o = s.as_ptr();
        }
        Ok(FMI2_OK)
    })
}

/// fmi2SetString.
///
/// # Safety
/// FMI 2.0 contract: `c` from fmi2Instantiate; `vr` and `value` hold `nvr` elements.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetString(
    c: Fmi2Component,
    vr: *const Fmi2ValueReference,
    nvr: usize,
    value: *const Fmi2String,
) -> Fmi2Status {
    with_instance(c, Func::SetValues, "fmi2SetString", |inst| {
        if nvr == 0 {
            return Ok(FMI2_OK);
        }
        // SAFETY: FMI contract: `nvr` value references.
        let vrs = unsafe { slice(vr, nvr) }.ok_or_else(|| null_arg("vr"))?;
        // SAFETY: FMI contract: `nvr` string pointers.
        let ptrs = unsafe { slice(value, nvr) }.ok_or_else(|| null_arg("value"))?;
        let owned: Vec<String> = ptrs
            .iter()
            .map(|&p| {
                // SAFETY: each entry is a NUL-terminated string (FMI contract).
                let s = unsafe { c_str(p) };
                s.map(str::to_owned).ok_or_else(|| null_arg("value[i]"))
            })
            .collect::<Result<_, _>>()?;
        let idx: Vec<usize> = (0..owned.len()).collect();
        inst.set_values(
            vrs,
            &idx,
            VarType::String,
            |m: &mut dyn Model, vr, i: usize| m.set_string(vr, &owned[i]),
        )
    })
}
