//! The FMI 2.0 Co-Simulation C ABI (fmi2FunctionTypes.h), written from the standard's headers
//! and not taken from the crate, for the programs that drive a built FMU binary through it:
//! the ABI test (`tests/fmi_abi.rs`), the stepping benchmark (`benches/fmi_step.rs`) and
//! uq-driver's check of its C test FMUs (`uq-driver/tests/test_fmus.rs`, the function names).
//! Each includes this file as a module with `#[path]`, allowing what it does not use.

use std::ffi::{c_char, c_int, c_uint, c_void};
use std::path::{Path, PathBuf};

pub type Component = *mut c_void;
pub type ComponentEnvironment = *mut c_void;
pub type FmuState = *mut c_void;
pub type Vr = c_uint;
pub type Status = c_int;
pub type CStrPtr = *const c_char;

pub const OK: Status = 0;
pub const WARNING: Status = 1;
pub const DISCARD: Status = 2;
pub const ERROR: Status = 3;
pub const FATAL: Status = 4;

pub const MODEL_EXCHANGE: c_int = 0;
pub const CO_SIMULATION: c_int = 1;
pub const FMI2_TRUE: c_int = 1;
pub const FMI2_FALSE: c_int = 0;

pub const DO_STEP_STATUS: c_int = 0;
pub const LAST_SUCCESSFUL_TIME: c_int = 2;
pub const TERMINATED: c_int = 3;

/// The logger as the ABI test receives it (see `tests/fmi_abi.rs` on C varargs).
pub type LoggerFn =
    unsafe extern "C" fn(ComponentEnvironment, CStrPtr, Status, CStrPtr, CStrPtr, CStrPtr);
pub type AllocateMemoryFn = unsafe extern "C" fn(usize, usize) -> *mut c_void;
pub type FreeMemoryFn = unsafe extern "C" fn(*mut c_void);
pub type StepFinishedFn = unsafe extern "C" fn(ComponentEnvironment, Status);

/// `fmi2CallbackFunctions`; `Option<fn>` has the layout of a nullable C function pointer.
#[repr(C)]
pub struct CallbackFunctions {
    pub logger: Option<LoggerFn>,
    pub allocate_memory: Option<AllocateMemoryFn>,
    pub free_memory: Option<FreeMemoryFn>,
    pub step_finished: Option<StepFinishedFn>,
    pub component_environment: ComponentEnvironment,
}

pub type GetStrFn = unsafe extern "C" fn() -> CStrPtr;
pub type SetDebugLoggingFn =
    unsafe extern "C" fn(Component, c_int, usize, *const CStrPtr) -> Status;
pub type InstantiateFn = unsafe extern "C" fn(
    CStrPtr,
    c_int,
    CStrPtr,
    CStrPtr,
    *const CallbackFunctions,
    c_int,
    c_int,
) -> Component;
pub type FreeInstanceFn = unsafe extern "C" fn(Component);
pub type SetupExperimentFn = unsafe extern "C" fn(Component, c_int, f64, f64, c_int, f64) -> Status;
pub type ComponentFn = unsafe extern "C" fn(Component) -> Status;
pub type GetRealFn = unsafe extern "C" fn(Component, *const Vr, usize, *mut f64) -> Status;
pub type GetIntFn = unsafe extern "C" fn(Component, *const Vr, usize, *mut c_int) -> Status;
pub type GetStringFn = unsafe extern "C" fn(Component, *const Vr, usize, *mut CStrPtr) -> Status;
pub type SetRealFn = unsafe extern "C" fn(Component, *const Vr, usize, *const f64) -> Status;
pub type SetIntFn = unsafe extern "C" fn(Component, *const Vr, usize, *const c_int) -> Status;
pub type SetStringFn = unsafe extern "C" fn(Component, *const Vr, usize, *const CStrPtr) -> Status;
pub type StateSlotFn = unsafe extern "C" fn(Component, *mut FmuState) -> Status;
pub type SetStateFn = unsafe extern "C" fn(Component, FmuState) -> Status;
pub type StateSizeFn = unsafe extern "C" fn(Component, FmuState, *mut usize) -> Status;
pub type SerializeFn = unsafe extern "C" fn(Component, FmuState, *mut c_char, usize) -> Status;
pub type DeserializeFn =
    unsafe extern "C" fn(Component, *const c_char, usize, *mut FmuState) -> Status;
pub type DirectionalDerivativeFn = unsafe extern "C" fn(
    Component,
    *const Vr,
    usize,
    *const Vr,
    usize,
    *const f64,
    *mut f64,
) -> Status;
pub type SetInputDerivativesFn =
    unsafe extern "C" fn(Component, *const Vr, usize, *const c_int, *const f64) -> Status;
pub type GetOutputDerivativesFn =
    unsafe extern "C" fn(Component, *const Vr, usize, *const c_int, *mut f64) -> Status;
pub type DoStepFn = unsafe extern "C" fn(Component, f64, f64, c_int) -> Status;
pub type GetIntStatusFn = unsafe extern "C" fn(Component, c_int, *mut c_int) -> Status;
pub type GetRealStatusFn = unsafe extern "C" fn(Component, c_int, *mut f64) -> Status;
pub type GetStringStatusFn = unsafe extern "C" fn(Component, c_int, *mut CStrPtr) -> Status;

/// The 25 common and 9 Co-Simulation functions of FMI 2.0, as listed in the standard.
pub const FMI2_CS_SYMBOLS: [&str; 34] = [
    "fmi2GetTypesPlatform",
    "fmi2GetVersion",
    "fmi2SetDebugLogging",
    "fmi2Instantiate",
    "fmi2FreeInstance",
    "fmi2SetupExperiment",
    "fmi2EnterInitializationMode",
    "fmi2ExitInitializationMode",
    "fmi2Terminate",
    "fmi2Reset",
    "fmi2GetReal",
    "fmi2GetInteger",
    "fmi2GetBoolean",
    "fmi2GetString",
    "fmi2SetReal",
    "fmi2SetInteger",
    "fmi2SetBoolean",
    "fmi2SetString",
    "fmi2GetFMUstate",
    "fmi2SetFMUstate",
    "fmi2FreeFMUstate",
    "fmi2SerializedFMUstateSize",
    "fmi2SerializeFMUstate",
    "fmi2DeSerializeFMUstate",
    "fmi2GetDirectionalDerivative",
    // Co-Simulation only.
    "fmi2SetRealInputDerivatives",
    "fmi2GetRealOutputDerivatives",
    "fmi2DoStep",
    "fmi2CancelStep",
    "fmi2GetStatus",
    "fmi2GetRealStatus",
    "fmi2GetIntegerStatus",
    "fmi2GetBooleanStatus",
    "fmi2GetStringStatus",
];

/// The railuq shared library of the `profile` ("debug", "release") build: `$RAILUQ_SO`, else
/// `librailuq.so` in `$CARGO_TARGET_DIR/<profile>` (default `target/`).
pub fn library_path(profile: &str) -> PathBuf {
    if let Some(p) = std::env::var_os("RAILUQ_SO") {
        return PathBuf::from(p);
    }
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("target"));
    target.join(profile).join("librailuq.so")
}
