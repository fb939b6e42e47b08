//! Inquiry and life cycle: fmi2GetTypesPlatform, fmi2GetVersion, fmi2SetDebugLogging,
//! fmi2Instantiate, fmi2FreeInstance, fmi2SetupExperiment, the initialization mode,
//! fmi2Terminate, fmi2Reset.

use std::ffi::c_char;

use crate::fmi2::instance::{Failure, Instance};
use crate::fmi2::logger::{Category, Logger};
use crate::fmi2::state::Func;
use crate::fmi2::types::*;
use crate::fmi2::uri::file_uri_to_path;
use crate::fmi2::xml::guid;
use crate::models::registry;

use super::*;

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
