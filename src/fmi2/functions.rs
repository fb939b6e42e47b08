//! The 34 exported FMI 2.0 Co-Simulation functions. This is the only file with
//! `extern "C"` entry points: each one null-checks its pointers, catches panics (a panic
//! becomes fmi2Fatal or a NULL instance, never an abort of the host) and hands safe Rust
//! values to [`Instance`].
#![allow(non_snake_case)]

use std::ffi::{c_char, CStr, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};

use super::instance::{Failure, Instance, Outcome, Snapshot, INSTANCE_MAGIC, SNAPSHOT_MAGIC};
use super::logger::{Category, Logger};
use super::state::{Func, State};
use super::types::*;
use super::uri::file_uri_to_path;
use super::xml::guid;
use crate::models::{registry, Model, VarType};

/// With the `test-panic` feature, setting any Real to this value panics inside the FMU.
#[cfg(feature = "test-panic")]
pub const TEST_PANIC_VALUE: f64 = -7.0e77;

fn guard<R>(on_panic: R, f: impl FnOnce() -> R) -> R {
    catch_unwind(AssertUnwindSafe(f)).unwrap_or(on_panic)
}

fn panic_message(p: &(dyn std::any::Any + Send)) -> String {
    p.downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| p.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "unknown panic".into())
}

/// Turns an `fmi2Component` into the instance it points to.
///
/// # Safety
/// `c` must be NULL or a pointer returned by [`fmi2Instantiate`] and not yet freed.
unsafe fn instance_mut<'a>(c: Fmi2Component) -> Option<&'a mut Instance> {
    if c.is_null() || !(c as usize).is_multiple_of(std::mem::align_of::<Instance>()) {
        return None;
    }
    // SAFETY: `Instance` is repr(C) with the magic first: reading one u64 at a non-NULL, aligned
    // pointer from the importer checks it is ours before any reference is made.
    if unsafe { std::ptr::read(c as *const u64) } != INSTANCE_MAGIC {
        return None;
    }
    // SAFETY: the magic matches, so `c` is a live Box<Instance> made by fmi2Instantiate.
    Some(unsafe { &mut *(c as *mut Instance) })
}

/// A slice from a C array, or None when the pointer is NULL.
///
/// # Safety
/// If non-NULL, `p` must point to `n` valid, initialized values.
unsafe fn slice<'a, T>(p: *const T, n: usize) -> Option<&'a [T]> {
    if p.is_null() {
        None
    } else {
        // SAFETY: non-NULL and, by the caller's contract, `n` valid elements.
        Some(unsafe { std::slice::from_raw_parts(p, n) })
    }
}

/// A mutable slice from a C array, or None when the pointer is NULL.
///
/// # Safety
/// If non-NULL, `p` must point to `n` writable values.
unsafe fn slice_mut<'a, T>(p: *mut T, n: usize) -> Option<&'a mut [T]> {
    if p.is_null() {
        None
    } else {
        // SAFETY: non-NULL and, by the caller's contract, `n` writable elements.
        Some(unsafe { std::slice::from_raw_parts_mut(p, n) })
    }
}

/// A Rust string from a C string, or None when NULL or not UTF-8.
///
/// # Safety
/// If non-NULL, `p` must be a NUL-terminated string.
unsafe fn c_str<'a>(p: *const c_char) -> Option<&'a str> {
    if p.is_null() {
        None
    } else {
        // SAFETY: non-NULL and NUL-terminated by the caller's contract.
        unsafe { CStr::from_ptr(p) }.to_str().ok()
    }
}

fn null_arg(name: &str) -> Failure {
    Failure::error(format!("argument '{name}' is NULL"))
}

/// Runs `body` on the instance behind `c` after the state-table check, inside a panic
/// boundary. Failures are logged and move the instance to Error or Fatal.
fn with_instance(
    c: Fmi2Component,
    func: Func,
    fname: &'static str,
    body: impl FnOnce(&mut Instance) -> Outcome,
) -> Fmi2Status {
    guard(FMI2_FATAL, || {
        // SAFETY: the FMI standard requires `c` to be an instance returned by fmi2Instantiate;
        // NULL, misaligned and freed (magic cleared) pointers are rejected inside.
        let Some(inst) = (unsafe { instance_mut(c) }) else {
            return FMI2_ERROR;
        };
        if let Err(f) = inst.check_state(func, fname) {
            return inst.fail(fname, f);
        }
        match catch_unwind(AssertUnwindSafe(|| body(&mut *inst))) {
            Ok(Ok(status)) => {
                if inst.logger.would_log(FMI2_OK, Category::Calls) {
                    inst.logger
                        .log(FMI2_OK, Category::Calls, &format!("{fname}: ok"));
                }
                status
            }
            Ok(Err(f)) => inst.fail(fname, f),
            Err(p) => {
                let msg = format!("internal error (panic): {}", panic_message(p.as_ref()));
                inst.fail(
                    fname,
                    Failure {
                        status: FMI2_FATAL,
                        message: msg,
                    },
                )
            }
        }
    })
}

// ---------------------------------------------------------------- inquiry

/// fmi2GetTypesPlatform: "default".
#[no_mangle]
pub extern "C" fn fmi2GetTypesPlatform() -> *const c_char {
    c"default".as_ptr()
}

/// fmi2GetVersion: "2.0".
#[no_mangle]
pub extern "C" fn fmi2GetVersion() -> *const c_char {
    c"2.0".as_ptr()
}

/// fmi2SetDebugLogging.
///
/// # Safety
/// FMI 2.0 contract: `c` from fmi2Instantiate; `categories` holds `n` C strings.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetDebugLogging(
    c: Fmi2Component,
    logging_on: Fmi2Boolean,
    n: usize,
    categories: *const Fmi2String,
) -> Fmi2Status {
    with_instance(c, Func::SetDebugLogging, "fmi2SetDebugLogging", |inst| {
        let cats: Vec<String> = if n == 0 {
            Vec::new()
        } else {
            // SAFETY: FMI contract: `categories` points to `n` strings.
            let ptrs = unsafe { slice(categories, n) }.ok_or_else(|| null_arg("categories"))?;
            ptrs.iter()
                .map(|&p| {
                    // SAFETY: each entry is a NUL-terminated string (FMI contract).
                    let s = unsafe { c_str(p) };
                    s.map(str::to_owned)
                        .ok_or_else(|| null_arg("categories[i]"))
                })
                .collect::<Result<_, _>>()?
        };
        inst.logger
            .set_debug_logging(logging_on != 0, &cats)
            .map_err(Failure::error)?;
        Ok(FMI2_OK)
    })
}

// ---------------------------------------------------------------- life cycle

/// fmi2Instantiate: checks the type (Co-Simulation only) and the GUID, which selects the model.
///
/// # Safety
/// FMI 2.0 contract: string arguments NULL or NUL-terminated; `functions` NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn fmi2Instantiate(
    instance_name: Fmi2String,
    fmu_type: Fmi2Type,
    fmu_guid: Fmi2String,
    fmu_resource_location: Fmi2String,
    functions: *const Fmi2CallbackFunctions,
    _visible: Fmi2Boolean,
    logging_on: Fmi2Boolean,
) -> Fmi2Component {
    guard(std::ptr::null_mut(), || {
        let callbacks = if functions.is_null() {
            None
        } else {
            // SAFETY: non-NULL, points to the importer's callback struct (FMI contract); we copy it.
            Some(unsafe { *functions })
        };
        // SAFETY: NULL or NUL-terminated (FMI contract).
        let name = unsafe { c_str(instance_name) }.unwrap_or("");
        let logger = Logger::new(
            callbacks,
            if name.is_empty() { "?" } else { name },
            logging_on != 0,
        );
        let fail = |msg: String| {
            logger.log(
                FMI2_ERROR,
                Category::Error,
                &format!("fmi2Instantiate: {msg}"),
            );
            std::ptr::null_mut()
        };
        if name.is_empty() {
            return fail("instanceName is NULL or empty".into());
        }
        if fmu_type != FMI2_CO_SIMULATION {
            return fail(format!(
                "fmuType {fmu_type} requested, but this FMU supports Co-Simulation (fmi2CoSimulation = 1) only"
            ));
        }
        // SAFETY: NULL or NUL-terminated (FMI contract).
        let Some(g) = (unsafe { c_str(fmu_guid) }) else {
            return fail("fmuGUID is NULL".into());
        };
        let Some(entry) = registry().iter().find(|e| guid(e.info) == g) else {
            let known: Vec<String> = registry()
                .iter()
                .map(|e| format!("{} {}", e.info.name, guid(e.info)))
                .collect();
            return fail(format!(
                "GUID {g} matches no model of this binary (known: {})",
                known.join(", ")
            ));
        };
        // SAFETY: NULL or NUL-terminated (FMI contract).
        let resource_dir = match unsafe { c_str(fmu_resource_location) } {
            None | Some("") => None,
            Some(uri) => {
                match file_uri_to_path(uri) {
                    Some(p) => Some(p),
                    None => {
                        logger.log(
                        FMI2_WARNING,
                        Category::Warning,
                        &format!("fmi2Instantiate: ignoring resource location '{uri}' (not a file: URI)"),
                    );
                        None
                    }
                }
            }
        };
        let inst = Box::new(Instance::new(entry, name.to_owned(), logger, resource_dir));
        Box::into_raw(inst) as Fmi2Component
    })
}

/// fmi2FreeInstance.
///
/// # Safety
/// FMI 2.0 contract: `c` from fmi2Instantiate, not used afterwards.
#[no_mangle]
pub unsafe extern "C" fn fmi2FreeInstance(c: Fmi2Component) {
    guard((), || {
        // SAFETY: FMI contract (see instance_mut).
        let Some(inst) = (unsafe { instance_mut(c) }) else {
            return;
        };
        if let Err(f) = inst.check_state(Func::FreeInstance, "fmi2FreeInstance") {
            inst.fail("fmi2FreeInstance", f);
            return;
        }
        inst.magic = 0;
        // SAFETY: `c` was created by Box::into_raw in fmi2Instantiate and is freed once.
        drop(unsafe { Box::from_raw(c as *mut Instance) });
    })
}

/// fmi2SetupExperiment.
///
/// # Safety
/// FMI 2.0 contract: `c` from fmi2Instantiate.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetupExperiment(
    c: Fmi2Component,
    _tolerance_defined: Fmi2Boolean,
    _tolerance: Fmi2Real,
    start_time: Fmi2Real,
    stop_time_defined: Fmi2Boolean,
    stop_time: Fmi2Real,
) -> Fmi2Status {
    with_instance(c, Func::SetupExperiment, "fmi2SetupExperiment", |inst| {
        inst.setup_experiment(start_time, (stop_time_defined != 0).then_some(stop_time))
    })
}

/// fmi2EnterInitializationMode.
///
/// # Safety
/// FMI 2.0 contract: `c` from fmi2Instantiate.
#[no_mangle]
pub unsafe extern "C" fn fmi2EnterInitializationMode(c: Fmi2Component) -> Fmi2Status {
    with_instance(
        c,
        Func::EnterInitializationMode,
        "fmi2EnterInitializationMode",
        Instance::enter_initialization_mode,
    )
}

/// fmi2ExitInitializationMode.
///
/// # Safety
/// FMI 2.0 contract: `c` from fmi2Instantiate.
#[no_mangle]
pub unsafe extern "C" fn fmi2ExitInitializationMode(c: Fmi2Component) -> Fmi2Status {
    with_instance(
        c,
        Func::ExitInitializationMode,
        "fmi2ExitInitializationMode",
        Instance::exit_initialization_mode,
    )
}

/// fmi2Terminate.
///
/// # Safety
/// FMI 2.0 contract: `c` from fmi2Instantiate.
#[no_mangle]
pub unsafe extern "C" fn fmi2Terminate(c: Fmi2Component) -> Fmi2Status {
    with_instance(c, Func::Terminate, "fmi2Terminate", Instance::terminate)
}

/// fmi2Reset.
///
/// # Safety
/// FMI 2.0 contract: `c` from fmi2Instantiate.
#[no_mangle]
pub unsafe extern "C" fn fmi2Reset(c: Fmi2Component) -> Fmi2Status {
    with_instance(c, Func::Reset, "fmi2Reset", Instance::reset)
}

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
    #[cfg(feature = "test-panic")]
    if vals.contains(&TEST_PANIC_VALUE) {
        panic!("forced panic (test-panic feature)");
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

// ---------------------------------------------------------------- FMU state

/// fmi2GetFMUstate: allocates a snapshot, or overwrites `*state` if it is one.
///
/// # Safety
/// FMI 2.0 contract: `c` from fmi2Instantiate; `state` points to NULL or a snapshot of ours.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetFMUstate(c: Fmi2Component, state: *mut Fmi2FmuState) -> Fmi2Status {
    with_instance(c, Func::FmuState, "fmi2GetFMUstate", |inst| {
        if state.is_null() {
            return Err(null_arg("FMUstate"));
        }
        let snap = inst.snapshot();
        // SAFETY: `state` is non-NULL and points to a writable fmi2FMUstate (FMI contract).
        let slot = unsafe { &mut *state };
        // SAFETY: `*slot` is NULL or a snapshot we allocated (checked by its magic).
        match unsafe { snapshot_mut(*slot) } {
            Some(existing) => *existing = snap,
            None if slot.is_null() => *slot = Box::into_raw(Box::new(snap)) as Fmi2FmuState,
            None => return Err(Failure::error("*FMUstate is not an FMU state of this FMU")),
        }
        Ok(FMI2_OK)
    })
}

/// Turns an fmi2FMUstate into our snapshot.
///
/// # Safety
/// `s` must be NULL or a pointer we returned from fmi2GetFMUstate/fmi2DeSerializeFMUstate.
unsafe fn snapshot_mut<'a>(s: Fmi2FmuState) -> Option<&'a mut Snapshot> {
    if s.is_null() || !(s as usize).is_multiple_of(std::mem::align_of::<Snapshot>()) {
        return None;
    }
    // SAFETY: `Snapshot` is repr(C) with the magic first; read it before making a reference.
    if unsafe { std::ptr::read(s as *const u64) } != SNAPSHOT_MAGIC {
        return None;
    }
    // SAFETY: the magic matches, so `s` is a live Box<Snapshot> we allocated.
    Some(unsafe { &mut *(s as *mut Snapshot) })
}

/// fmi2SetFMUstate.
///
/// # Safety
/// FMI 2.0 contract: `c` from fmi2Instantiate; `state` from fmi2GetFMUstate.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetFMUstate(c: Fmi2Component, state: Fmi2FmuState) -> Fmi2Status {
    with_instance(c, Func::FmuState, "fmi2SetFMUstate", |inst| {
        // SAFETY: FMI contract; foreign pointers are rejected by the magic check.
        let snap = unsafe { snapshot_mut(state) }
            .ok_or_else(|| Failure::error("FMUstate is NULL or not an FMU state of this FMU"))?;
        inst.restore(snap)
    })
}

/// fmi2FreeFMUstate: frees `*state` and sets it to NULL.
///
/// # Safety
/// FMI 2.0 contract: `c` from fmi2Instantiate; `state` points to a snapshot pointer or NULL.
#[no_mangle]
pub unsafe extern "C" fn fmi2FreeFMUstate(
    c: Fmi2Component,
    state: *mut Fmi2FmuState,
) -> Fmi2Status {
    with_instance(c, Func::FmuState, "fmi2FreeFMUstate", |_inst| {
        if state.is_null() {
            return Ok(FMI2_OK);
        }
        // SAFETY: non-NULL pointer to the importer's fmi2FMUstate variable.
        let slot = unsafe { &mut *state };
        if slot.is_null() {
            return Ok(FMI2_OK);
        }
        // SAFETY: checked by magic; allocated by Box::into_raw in fmi2GetFMUstate.
        let snap = unsafe { snapshot_mut(*slot) }
            .ok_or_else(|| Failure::error("*FMUstate is not an FMU state of this FMU"))?;
        snap.magic = 0;
        // SAFETY: a Box<Snapshot> we created, freed exactly once (the slot is cleared).
        drop(unsafe { Box::from_raw(*slot as *mut Snapshot) });
        *slot = std::ptr::null_mut();
        Ok(FMI2_OK)
    })
}

/// fmi2SerializedFMUstateSize.
///
/// # Safety
/// FMI 2.0 contract: `c` from fmi2Instantiate; `state` a snapshot; `size` writable.
#[no_mangle]
pub unsafe extern "C" fn fmi2SerializedFMUstateSize(
    c: Fmi2Component,
    state: Fmi2FmuState,
    size: *mut usize,
) -> Fmi2Status {
    with_instance(c, Func::FmuState, "fmi2SerializedFMUstateSize", |inst| {
        // SAFETY: FMI contract; checked by magic.
        let snap = unsafe { snapshot_mut(state) }
            .ok_or_else(|| Failure::error("FMUstate is NULL or not an FMU state of this FMU"))?;
        if size.is_null() {
            return Err(null_arg("size"));
        }
        let n = inst.serialize(snap).len();
        // SAFETY: non-NULL writable size_t (FMI contract).
        unsafe { *size = n };
        Ok(FMI2_OK)
    })
}

/// fmi2SerializeFMUstate.
///
/// # Safety
/// FMI 2.0 contract: `bytes` has room for `size` bytes.
#[no_mangle]
pub unsafe extern "C" fn fmi2SerializeFMUstate(
    c: Fmi2Component,
    state: Fmi2FmuState,
    bytes: *mut Fmi2Byte,
    size: usize,
) -> Fmi2Status {
    with_instance(c, Func::FmuState, "fmi2SerializeFMUstate", |inst| {
        // SAFETY: FMI contract; checked by magic.
        let snap = unsafe { snapshot_mut(state) }
            .ok_or_else(|| Failure::error("FMUstate is NULL or not an FMU state of this FMU"))?;
        let data = inst.serialize(snap);
        if data.len() != size {
            return Err(Failure::error(format!(
                "size {size} given, the serialized state has {} bytes",
                data.len()
            )));
        }
        // SAFETY: FMI contract: `bytes` has room for `size` bytes.
        let out = unsafe { slice_mut(bytes as *mut u8, size) }
            .ok_or_else(|| null_arg("serializedState"))?;
        out.copy_from_slice(&data);
        Ok(FMI2_OK)
    })
}

/// fmi2DeSerializeFMUstate: checks magic, version, model and checksum.
///
/// # Safety
/// FMI 2.0 contract: `bytes` holds `size` bytes; `state` writable.
#[no_mangle]
pub unsafe extern "C" fn fmi2DeSerializeFMUstate(
    c: Fmi2Component,
    bytes: *const Fmi2Byte,
    size: usize,
    state: *mut Fmi2FmuState,
) -> Fmi2Status {
    with_instance(c, Func::FmuState, "fmi2DeSerializeFMUstate", |inst| {
        // SAFETY: FMI contract: `size` readable bytes.
        let data = unsafe { slice(bytes as *const u8, size) }
            .ok_or_else(|| null_arg("serializedState"))?;
        if state.is_null() {
            return Err(null_arg("FMUstate"));
        }
        let snap = inst.deserialize(data)?;
        // SAFETY: non-NULL pointer to the importer's fmi2FMUstate variable.
        let slot = unsafe { &mut *state };
        // SAFETY: NULL or one of our snapshots (checked by magic).
        match unsafe { snapshot_mut(*slot) } {
            Some(existing) => *existing = snap,
            None => *slot = Box::into_raw(Box::new(snap)) as Fmi2FmuState,
        }
        Ok(FMI2_OK)
    })
}

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

/// fmi2GetBooleanStatus: fmi2Terminated is always false (the slave never asks to stop).
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
            Ok(Fmi2Boolean::from(inst.state == State::Terminated))
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
