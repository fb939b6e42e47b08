//! FMI 2.0 C ABI types (fmi2TypesPlatform.h, fmi2FunctionTypes.h), "default" platform.

use std::ffi::{c_char, c_int, c_uint, c_void};

/// `fmi2Component`: pointer to an instance.
pub type Fmi2Component = *mut c_void;
/// `fmi2ComponentEnvironment`: opaque importer pointer handed back to callbacks.
pub type Fmi2ComponentEnvironment = *mut c_void;
/// `fmi2FMUstate`: pointer to a state snapshot.
pub type Fmi2FmuState = *mut c_void;
/// `fmi2ValueReference`.
pub type Fmi2ValueReference = c_uint;
/// `fmi2Real`.
pub type Fmi2Real = f64;
/// `fmi2Integer`.
pub type Fmi2Integer = c_int;
/// `fmi2Boolean` (a C int: 0 false, anything else true).
pub type Fmi2Boolean = c_int;
/// `fmi2String`.
pub type Fmi2String = *const c_char;
/// `fmi2Byte`.
pub type Fmi2Byte = c_char;
/// `fmi2Status` as a C int (we only ever return the constants below).
pub type Fmi2Status = c_int;
/// `fmi2Type` as passed to fmi2Instantiate.
pub type Fmi2Type = c_int;
/// `fmi2StatusKind`.
pub type Fmi2StatusKind = c_int;

/// fmi2OK
pub const FMI2_OK: Fmi2Status = 0;
/// fmi2Warning
pub const FMI2_WARNING: Fmi2Status = 1;
/// fmi2Discard
pub const FMI2_DISCARD: Fmi2Status = 2;
/// fmi2Error
pub const FMI2_ERROR: Fmi2Status = 3;
/// fmi2Fatal
pub const FMI2_FATAL: Fmi2Status = 4;
/// fmi2Pending
pub const FMI2_PENDING: Fmi2Status = 5;

/// fmi2ModelExchange
pub const FMI2_MODEL_EXCHANGE: Fmi2Type = 0;
/// fmi2CoSimulation
pub const FMI2_CO_SIMULATION: Fmi2Type = 1;

/// fmi2DoStepStatus
pub const FMI2_DO_STEP_STATUS: Fmi2StatusKind = 0;
/// fmi2PendingStatus
pub const FMI2_PENDING_STATUS: Fmi2StatusKind = 1;
/// fmi2LastSuccessfulTime
pub const FMI2_LAST_SUCCESSFUL_TIME: Fmi2StatusKind = 2;
/// fmi2Terminated
pub const FMI2_TERMINATED: Fmi2StatusKind = 3;

/// `fmi2CallbackLogger`: variadic in C; we always call it with the format "%s".
pub type Fmi2CallbackLogger = unsafe extern "C" fn(
    Fmi2ComponentEnvironment,
    Fmi2String,
    Fmi2Status,
    Fmi2String,
    Fmi2String,
    ...
);
/// `fmi2CallbackAllocateMemory`.
pub type Fmi2CallbackAllocateMemory = unsafe extern "C" fn(usize, usize) -> *mut c_void;
/// `fmi2CallbackFreeMemory`.
pub type Fmi2CallbackFreeMemory = unsafe extern "C" fn(*mut c_void);
/// `fmi2StepFinished`.
pub type Fmi2StepFinished = unsafe extern "C" fn(Fmi2ComponentEnvironment, Fmi2Status);

/// `fmi2CallbackFunctions`. Function pointers are `Option` so that NULL is representable.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct Fmi2CallbackFunctions {
    /// Logger (may be NULL: we then stay silent).
    pub logger: Option<Fmi2CallbackLogger>,
    /// Allocator (unused: we use Rust's allocator, `canNotUseMemoryManagementFunctions`).
    pub allocate_memory: Option<Fmi2CallbackAllocateMemory>,
    /// Deallocator (unused).
    pub free_memory: Option<Fmi2CallbackFreeMemory>,
    /// Asynchronous step callback (unused: steps are synchronous).
    pub step_finished: Option<Fmi2StepFinished>,
    /// Importer pointer passed back to the logger.
    pub component_environment: Fmi2ComponentEnvironment,
}

/// Human-readable name of a status.
pub fn status_name(s: Fmi2Status) -> &'static str {
    match s {
        FMI2_OK => "fmi2OK",
        FMI2_WARNING => "fmi2Warning",
        FMI2_DISCARD => "fmi2Discard",
        FMI2_ERROR => "fmi2Error",
        FMI2_FATAL => "fmi2Fatal",
        FMI2_PENDING => "fmi2Pending",
        _ => "unknown status",
    }
}
