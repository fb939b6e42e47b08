//! The FMI 2.0 Co-Simulation C ABI of the *built* shared library, driven exactly as an
//! importer drives it: `dlopen` the cdylib, look the `fmi2*` symbols up, and call them through
//! C function pointers with C data (NUL-terminated strings, raw arrays, a C callbacks struct).
//!
//! ```text
//! cargo test -p railuq --test fmi_abi             # target/debug/librailuq.so
//! cargo test --release -p railuq --test fmi_abi   # target/release/librailuq.so, the shipped one
//! ```
//!
//! The library is `target/<profile>/librailuq.so` of the profile the test is built in (or under
//! `$CARGO_TARGET_DIR`), or the file named by the environment variable `RAILUQ_SO`. The panic
//! boundary is proven on that same library: the test arms its test hook
//! (`RAILUQ_FMU_TEST_PANIC=1`) in a child process of its own.
//!
//! Everything ABI-related is defined here from the FMI 2.0 headers, not imported from the
//! crate: the only things taken from `railuq` are the GUID, the serialized-state checksum (to
//! forge a well-formed but hostile state) and the test-panic value.
//!
//! # The logger and C varargs
//!
//! `fmi2CallbackLogger` is variadic in C:
//! `void logger(env, instanceName, status, category, const char* message, ...)`. Stable Rust
//! cannot *define* a variadic function. The FMU, however, always calls it as
//! `logger(env, name, status, category, "%s", msg)`, so the receiver below is a plain
//! six-argument `extern "C"` function that takes the single variadic argument as a sixth
//! `*const c_char`. This is sound for this call pattern on the System V x86_64 ABI (and on
//! AAPCS64 outside Apple platforms), where the first six integer/pointer arguments of a variadic
//! call travel in the same registers as for a non-variadic call. The receiver reads the sixth
//! argument only when the format is exactly `"%s"`, and records anything else as a failure.
//! Hence the `cfg` below.
#![cfg(all(
    target_os = "linux",
    any(target_arch = "x86_64", target_arch = "aarch64")
))]

use std::ffi::{c_char, c_int, c_void, CStr, CString};
use std::path::{Path, PathBuf};
use std::ptr::{null, null_mut};
use std::sync::{Barrier, Mutex, OnceLock, PoisonError};
use std::thread;

use libloading::Library;

// ---------------------------------------------------------------- C ABI (fmi2FunctionTypes.h)

#[allow(dead_code)] // the constants and types this test does not use
#[path = "common/fmi2.rs"]
mod fmi2;
use fmi2::*;

// ---------------------------------------------------------------- the Wheel model

const VR_M: Vr = 0;
const VR_K: Vr = 1;
const VR_C: Vr = 2;
const VR_Q: Vr = 10;
const VR_V: Vr = 11;
const VR_A: Vr = 12;
const OUTPUTS: [Vr; 3] = [VR_Q, VR_V, VR_A];

/// (q, v, a) after each communication step.
type Traj = Vec<[f64; 3]>;

/// The paper's nominal response (m = 10, K = 100, C = 20, q0 = 0.1, v0 = 0), in m.
fn nominal_q(t: f64) -> f64 {
    0.1 * (-t).exp() * ((3.0 * t).cos() + (3.0 * t).sin() / 3.0)
}

/// Underdamped free response of m q'' + c q' + k q = 0 at time `t` after (q0, v0).
fn free_response(m: f64, k: f64, c: f64, q0: f64, v0: f64, t: f64) -> f64 {
    let a = -c / (2.0 * m);
    let wd = (k / m - a * a).sqrt();
    (a * t).exp() * (q0 * (wd * t).cos() + (v0 - a * q0) / wd * (wd * t).sin())
}

/// For bitwise comparisons of trajectories.
fn bits(t: &[[f64; 3]]) -> Vec<[u64; 3]> {
    t.iter().map(|y| y.map(f64::to_bits)).collect()
}

fn wheel_guid() -> String {
    railuq::fmi2::xml::guid(&railuq::models::wheel::INFO)
}

// ---------------------------------------------------------------- logger

/// One call of the logger callback.
#[derive(Clone, Debug)]
struct Entry {
    instance: String,
    status: Status,
    category: String,
    format: String,
    message: String,
}

/// Reached by the logger through `componentEnvironment`.
#[derive(Default)]
struct Log {
    entries: Mutex<Vec<Entry>>,
}

impl Log {
    fn entries(&self) -> Vec<Entry> {
        let entries = self
            .entries
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .clone();
        for e in &entries {
            assert_eq!(
                e.format, "%s",
                "logger called with a format other than \"%s\": {e:?}"
            );
        }
        entries
    }

    fn clear(&self) {
        self.entries
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .clear();
    }
}

/// A C string as an owned `String` ("<NULL>" for NULL).
///
/// # Safety
/// `p` must be NULL or a NUL-terminated string.
unsafe fn lossy(p: CStrPtr) -> String {
    if p.is_null() {
        "<NULL>".into()
    } else {
        // SAFETY: non-NULL and NUL-terminated by the caller's contract.
        unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned()
    }
}

/// The `fmi2CallbackLogger` handed to the FMU (non-variadic, see the module documentation).
/// Never unwinds: nothing here panics (a poisoned lock is recovered).
unsafe extern "C" fn logger(
    env: ComponentEnvironment,
    instance: CStrPtr,
    status: Status,
    category: CStrPtr,
    format: CStrPtr,
    arg: CStrPtr,
) {
    if env.is_null() {
        return;
    }
    // SAFETY: `env` is the `Log` we stored in componentEnvironment; `Inst` keeps it alive
    // until after fmi2FreeInstance, and the FMU has no other copy of it.
    let log = unsafe { &*(env as *const Log) };
    // SAFETY: the FMU passes NUL-terminated strings (NULL is handled by `lossy`).
    let (instance, category, format) = unsafe { (lossy(instance), lossy(category), lossy(format)) };
    let message = if format == "%s" {
        // SAFETY: with format "%s" the single variadic argument is a C string, which on the
        // supported ABIs arrives as this sixth argument.
        unsafe { lossy(arg) }
    } else {
        String::new()
    };
    log.entries
        .lock()
        .unwrap_or_else(PoisonError::into_inner)
        .push(Entry {
            instance,
            status,
            category,
            format,
            message,
        });
}

/// `allocateMemory` with C `calloc` semantics.
unsafe extern "C" fn allocate_memory(n: usize, size: usize) -> *mut c_void {
    // SAFETY: calloc has no preconditions.
    unsafe { libc::calloc(n, size) }
}

/// `freeMemory`.
unsafe extern "C" fn free_memory(p: *mut c_void) {
    // SAFETY: the FMI contract: `p` is NULL or came from `allocate_memory` (calloc).
    unsafe { libc::free(p) }
}

// ---------------------------------------------------------------- the loaded library

/// The dlopen'ed library and its 34 functions as typed C function pointers.
struct Fmu {
    path: PathBuf,
    get_types_platform: GetStrFn,
    get_version: GetStrFn,
    set_debug_logging: SetDebugLoggingFn,
    instantiate: InstantiateFn,
    free_instance: FreeInstanceFn,
    setup_experiment: SetupExperimentFn,
    enter_initialization_mode: ComponentFn,
    exit_initialization_mode: ComponentFn,
    terminate: ComponentFn,
    reset: ComponentFn,
    get_real: GetRealFn,
    get_integer: GetIntFn,
    get_boolean: GetIntFn,
    get_string: GetStringFn,
    set_real: SetRealFn,
    set_integer: SetIntFn,
    set_boolean: SetIntFn,
    set_string: SetStringFn,
    get_fmu_state: StateSlotFn,
    set_fmu_state: SetStateFn,
    free_fmu_state: StateSlotFn,
    serialized_fmu_state_size: StateSizeFn,
    serialize_fmu_state: SerializeFn,
    deserialize_fmu_state: DeserializeFn,
    get_directional_derivative: DirectionalDerivativeFn,
    set_real_input_derivatives: SetInputDerivativesFn,
    get_real_output_derivatives: GetOutputDerivativesFn,
    do_step: DoStepFn,
    cancel_step: ComponentFn,
    get_status: GetIntStatusFn,
    get_real_status: GetRealStatusFn,
    get_integer_status: GetIntStatusFn,
    get_boolean_status: GetIntStatusFn,
    get_string_status: GetStringStatusFn,
    /// Last field: the function pointers above are valid while it is loaded.
    lib: Library,
}

/// Copies a symbol's value (a function pointer) out of the library.
///
/// # Safety
/// `T` must be the C type of the symbol `name`.
unsafe fn sym<T: Copy>(lib: &Library, path: &Path, name: &str) -> T {
    let cname = CString::new(name).expect("symbol name");
    // SAFETY: the caller guarantees that `T` is the symbol's type.
    match unsafe { lib.get::<T>(cname.as_bytes_with_nul()) } {
        Ok(s) => *s,
        Err(e) => panic!("{}: symbol {name} is not exported: {e}", path.display()),
    }
}

impl Fmu {
    fn load() -> Fmu {
        let profile = if cfg!(debug_assertions) {
            "debug"
        } else {
            "release"
        };
        let path = fmi2::library_path(profile);
        assert!(
            path.is_file(),
            "{} does not exist: build it first with `cargo build -p railuq --lib` (in the \
             profile of this test), or set RAILUQ_SO",
            path.display()
        );
        use libloading::os::unix::{Library as UnixLibrary, RTLD_LOCAL, RTLD_NOW};
        // SAFETY: loading runs the library's initialisers; a Rust cdylib has none that
        // matter. RTLD_NOW resolves every symbol up front, as a strict importer would.
        let lib: Library = unsafe { UnixLibrary::open(Some(&path), RTLD_NOW | RTLD_LOCAL) }
            .unwrap_or_else(|e| panic!("dlopen {}: {e}", path.display()))
            .into();
        let p = path.as_path();
        // SAFETY: each field's type is the fmi2FunctionTypes.h type of its symbol for the
        // "default" types platform; the pointers are used only while `lib`, stored in the same
        // struct, stays loaded (the struct lives in a static and is never dropped).
        unsafe {
            Fmu {
                get_types_platform: sym(&lib, p, "fmi2GetTypesPlatform"),
                get_version: sym(&lib, p, "fmi2GetVersion"),
                set_debug_logging: sym(&lib, p, "fmi2SetDebugLogging"),
                instantiate: sym(&lib, p, "fmi2Instantiate"),
                free_instance: sym(&lib, p, "fmi2FreeInstance"),
                setup_experiment: sym(&lib, p, "fmi2SetupExperiment"),
                enter_initialization_mode: sym(&lib, p, "fmi2EnterInitializationMode"),
                exit_initialization_mode: sym(&lib, p, "fmi2ExitInitializationMode"),
                terminate: sym(&lib, p, "fmi2Terminate"),
                reset: sym(&lib, p, "fmi2Reset"),
                get_real: sym(&lib, p, "fmi2GetReal"),
                get_integer: sym(&lib, p, "fmi2GetInteger"),
                get_boolean: sym(&lib, p, "fmi2GetBoolean"),
                get_string: sym(&lib, p, "fmi2GetString"),
                set_real: sym(&lib, p, "fmi2SetReal"),
                set_integer: sym(&lib, p, "fmi2SetInteger"),
                set_boolean: sym(&lib, p, "fmi2SetBoolean"),
                set_string: sym(&lib, p, "fmi2SetString"),
                get_fmu_state: sym(&lib, p, "fmi2GetFMUstate"),
                set_fmu_state: sym(&lib, p, "fmi2SetFMUstate"),
                free_fmu_state: sym(&lib, p, "fmi2FreeFMUstate"),
                serialized_fmu_state_size: sym(&lib, p, "fmi2SerializedFMUstateSize"),
                serialize_fmu_state: sym(&lib, p, "fmi2SerializeFMUstate"),
                deserialize_fmu_state: sym(&lib, p, "fmi2DeSerializeFMUstate"),
                get_directional_derivative: sym(&lib, p, "fmi2GetDirectionalDerivative"),
                set_real_input_derivatives: sym(&lib, p, "fmi2SetRealInputDerivatives"),
                get_real_output_derivatives: sym(&lib, p, "fmi2GetRealOutputDerivatives"),
                do_step: sym(&lib, p, "fmi2DoStep"),
                cancel_step: sym(&lib, p, "fmi2CancelStep"),
                get_status: sym(&lib, p, "fmi2GetStatus"),
                get_real_status: sym(&lib, p, "fmi2GetRealStatus"),
                get_integer_status: sym(&lib, p, "fmi2GetIntegerStatus"),
                get_boolean_status: sym(&lib, p, "fmi2GetBooleanStatus"),
                get_string_status: sym(&lib, p, "fmi2GetStringStatus"),
                path: path.clone(),
                lib,
            }
        }
    }
}

/// The library, loaded once per test process (tests run on several threads).
fn fmu() -> &'static Fmu {
    static FMU: OnceLock<Fmu> = OnceLock::new();
    FMU.get_or_init(Fmu::load)
}

// ---------------------------------------------------------------- instances

/// What to pass for `functions` in fmi2Instantiate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Callbacks {
    /// A full struct with our logger.
    Full,
    /// A struct whose logger is NULL.
    NullLogger,
    /// `functions == NULL`.
    NullStruct,
}

/// The arguments of fmi2Instantiate (defaults: a Co-Simulation Wheel, logging on).
#[derive(Clone, Debug)]
struct Spec {
    name: Option<CString>,
    fmu_type: c_int,
    guid: Option<CString>,
    resource: Option<CString>,
    callbacks: Callbacks,
    logging_on: bool,
}

impl Spec {
    fn new(name: &str) -> Spec {
        Spec {
            name: Some(CString::new(name).expect("name")),
            fmu_type: CO_SIMULATION,
            guid: Some(CString::new(wheel_guid()).expect("guid")),
            resource: None,
            callbacks: Callbacks::Full,
            logging_on: true,
        }
    }
    fn no_name(mut self) -> Spec {
        self.name = None;
        self
    }
    fn fmu_type(mut self, t: c_int) -> Spec {
        self.fmu_type = t;
        self
    }
    fn guid(mut self, g: Option<&str>) -> Spec {
        self.guid = g.map(|g| CString::new(g).expect("guid"));
        self
    }
    fn resource(mut self, uri: &str) -> Spec {
        self.resource = Some(CString::new(uri).expect("uri"));
        self
    }
    fn callbacks(mut self, c: Callbacks) -> Spec {
        self.callbacks = c;
        self
    }
    fn logging(mut self, on: bool) -> Spec {
        self.logging_on = on;
        self
    }

    /// fmi2Instantiate; on NULL, the messages logged meanwhile.
    fn instantiate(self) -> Result<Inst, Vec<Entry>> {
        let fmu = fmu();
        let log = Box::new(Log::default());
        let callbacks = CallbackFunctions {
            logger: (self.callbacks == Callbacks::Full).then_some(logger as LoggerFn),
            allocate_memory: Some(allocate_memory),
            free_memory: Some(free_memory),
            step_finished: None,
            component_environment: &*log as *const Log as *mut c_void,
        };
        let functions: *const CallbackFunctions = match self.callbacks {
            Callbacks::NullStruct => null(),
            _ => &callbacks,
        };
        let ptr = |s: &Option<CString>| s.as_ref().map_or(null(), |s| s.as_ptr());
        // SAFETY: strings are NULL or NUL-terminated and outlive the call; `functions` is NULL
        // or a valid struct (the FMU copies it); the logger environment `log` is boxed and
        // outlives the instance (see `Inst`).
        let c = unsafe {
            (fmu.instantiate)(
                ptr(&self.name),
                self.fmu_type,
                ptr(&self.guid),
                ptr(&self.resource),
                functions,
                0,
                c_int::from(self.logging_on),
            )
        };
        if c.is_null() {
            Err(log.entries())
        } else {
            Ok(Inst { fmu, c, log })
        }
    }
}

/// One live instance. Methods return the raw fmi2Status; `Drop` frees the instance.
struct Inst {
    fmu: &'static Fmu,
    c: Component,
    /// Dropped after the instance is freed (fields drop after `Drop::drop`).
    log: Box<Log>,
}

impl Drop for Inst {
    fn drop(&mut self) {
        if !self.c.is_null() {
            // SAFETY: `c` came from fmi2Instantiate and is freed exactly once.
            unsafe { (self.fmu.free_instance)(self.c) };
        }
    }
}

impl Inst {
    fn new(name: &str) -> Inst {
        Spec::new(name)
            .instantiate()
            .unwrap_or_else(|log| panic!("fmi2Instantiate returned NULL; log: {log:#?}"))
    }

    /// fmi2FreeInstance; returns what was logged over the instance's life.
    fn free(mut self) -> Vec<Entry> {
        // SAFETY: `c` came from fmi2Instantiate; it is cleared so that Drop does not free it.
        unsafe { (self.fmu.free_instance)(self.c) };
        self.c = null_mut();
        self.log.entries()
    }

    fn log(&self) -> Vec<Entry> {
        self.log.entries()
    }

    fn clear_log(&self) {
        self.log.clear();
    }

    /// Whether an entry of `status` contains every one of `parts`.
    fn logged(&self, status: Status, parts: &[&str]) -> bool {
        self.log()
            .iter()
            .any(|e| e.status == status && parts.iter().all(|p| e.message.contains(p)))
    }

    #[track_caller]
    fn assert_logged(&self, status: Status, parts: &[&str]) {
        assert!(
            self.logged(status, parts),
            "no log entry with status {status} containing {parts:?}; log: {:#?}",
            self.log()
        );
    }

    fn setup(&self, start: f64, stop: Option<f64>) -> Status {
        // SAFETY: `c` is live.
        unsafe {
            (self.fmu.setup_experiment)(
                self.c,
                0,
                0.0,
                start,
                c_int::from(stop.is_some()),
                stop.unwrap_or(0.0),
            )
        }
    }

    fn enter(&self) -> Status {
        // SAFETY: `c` is live.
        unsafe { (self.fmu.enter_initialization_mode)(self.c) }
    }

    fn exit(&self) -> Status {
        // SAFETY: `c` is live.
        unsafe { (self.fmu.exit_initialization_mode)(self.c) }
    }

    fn terminate(&self) -> Status {
        // SAFETY: `c` is live.
        unsafe { (self.fmu.terminate)(self.c) }
    }

    fn reset(&self) -> Status {
        // SAFETY: `c` is live.
        unsafe { (self.fmu.reset)(self.c) }
    }

    /// Setup, enter and exit initialization mode, each asserted OK.
    #[track_caller]
    fn init(&self, start: f64, stop: Option<f64>) {
        assert_eq!(self.setup(start, stop), OK, "setup; log {:#?}", self.log());
        assert_eq!(self.enter(), OK, "enter; log {:#?}", self.log());
        assert_eq!(self.exit(), OK, "exit; log {:#?}", self.log());
    }

    fn step(&self, t: f64, h: f64) -> Status {
        // SAFETY: `c` is live.
        unsafe { (self.fmu.do_step)(self.c, t, h, 1) }
    }

    fn get_reals(&self, vrs: &[Vr]) -> (Status, Vec<f64>) {
        let mut out = vec![f64::NAN; vrs.len()];
        // SAFETY: `c` is live; both arrays hold `vrs.len()` elements.
        let s = unsafe { (self.fmu.get_real)(self.c, vrs.as_ptr(), vrs.len(), out.as_mut_ptr()) };
        (s, out)
    }

    #[track_caller]
    fn get(&self, vr: Vr) -> f64 {
        let (s, v) = self.get_reals(&[vr]);
        assert_eq!(s, OK, "fmi2GetReal({vr}); log {:#?}", self.log());
        v[0]
    }

    #[track_caller]
    fn outputs(&self) -> [f64; 3] {
        let (s, v) = self.get_reals(&OUTPUTS);
        assert_eq!(s, OK, "fmi2GetReal(outputs); log {:#?}", self.log());
        [v[0], v[1], v[2]]
    }

    fn set_reals(&self, vrs: &[Vr], values: &[f64]) -> Status {
        assert_eq!(vrs.len(), values.len());
        // SAFETY: `c` is live; both arrays hold `vrs.len()` elements.
        unsafe { (self.fmu.set_real)(self.c, vrs.as_ptr(), vrs.len(), values.as_ptr()) }
    }

    fn set(&self, vr: Vr, value: f64) -> Status {
        self.set_reals(&[vr], &[value])
    }

    fn set_debug_logging(&self, on: bool, categories: &[&str]) -> Status {
        let owned: Vec<CString> = categories
            .iter()
            .map(|c| CString::new(*c).expect("category"))
            .collect();
        let ptrs: Vec<CStrPtr> = owned.iter().map(|c| c.as_ptr()).collect();
        let p = if ptrs.is_empty() {
            null()
        } else {
            ptrs.as_ptr()
        };
        // SAFETY: `c` is live; `p` is NULL (n = 0) or holds `ptrs.len()` live C strings.
        unsafe { (self.fmu.set_debug_logging)(self.c, c_int::from(on), ptrs.len(), p) }
    }

    /// `n` steps of `h` from `t0` (points `t0 + i h`), each asserted OK; outputs after each.
    #[track_caller]
    fn run(&self, t0: f64, h: f64, n: usize) -> Traj {
        (0..n)
            .map(|i| {
                let t = t0 + i as f64 * h;
                let s = self.step(t, h);
                assert_eq!(s, OK, "fmi2DoStep({t}, {h}); log {:#?}", self.log());
                self.outputs()
            })
            .collect()
    }

    fn get_state(&self, state: &mut FmuState) -> Status {
        // SAFETY: `c` is live; `state` is a valid fmi2FMUstate variable.
        unsafe { (self.fmu.get_fmu_state)(self.c, state) }
    }

    fn set_state(&self, state: FmuState) -> Status {
        // SAFETY: `c` is live; `state` came from this FMU (or is NULL).
        unsafe { (self.fmu.set_fmu_state)(self.c, state) }
    }

    fn free_state(&self, state: &mut FmuState) -> Status {
        // SAFETY: `c` is live; `state` is a valid fmi2FMUstate variable.
        unsafe { (self.fmu.free_fmu_state)(self.c, state) }
    }

    fn state_size(&self, state: FmuState) -> (Status, usize) {
        let mut n = usize::MAX;
        // SAFETY: `c` is live; `state` came from this FMU; `n` is writable.
        let s = unsafe { (self.fmu.serialized_fmu_state_size)(self.c, state, &mut n) };
        (s, n)
    }

    fn serialize_into(&self, state: FmuState, buf: &mut [u8]) -> Status {
        // SAFETY: `c` is live; `buf` has room for `buf.len()` bytes.
        unsafe { (self.fmu.serialize_fmu_state)(self.c, state, buf.as_mut_ptr().cast(), buf.len()) }
    }

    #[track_caller]
    fn serialize(&self, state: FmuState) -> Vec<u8> {
        let (s, n) = self.state_size(state);
        assert_eq!(s, OK, "fmi2SerializedFMUstateSize; log {:#?}", self.log());
        let mut buf = vec![0u8; n];
        let s = self.serialize_into(state, &mut buf);
        assert_eq!(s, OK, "fmi2SerializeFMUstate; log {:#?}", self.log());
        buf
    }

    fn deserialize(&self, bytes: &[u8], state: &mut FmuState) -> Status {
        // SAFETY: `c` is live; `bytes` holds `bytes.len()` bytes; `state` is writable.
        unsafe {
            (self.fmu.deserialize_fmu_state)(self.c, bytes.as_ptr().cast(), bytes.len(), state)
        }
    }
}

/// A fresh run of the Wheel: `params` set before initialization, then `n` steps of `h`.
fn simulate(params: &[(Vr, f64)], h: f64, n: usize) -> Traj {
    let inst = Inst::new("reference");
    for &(vr, v) in params {
        let s = inst.set(vr, v);
        assert!(s == OK || s == WARNING, "set {vr} = {v}: {s}");
    }
    inst.init(0.0, None);
    inst.run(0.0, h, n)
}

// ================================================================ 1. symbols, version

#[test]
fn all_34_fmi2_cs_symbols_are_exported() {
    let fmu = fmu();
    let mut unique = FMI2_CS_SYMBOLS.to_vec();
    unique.sort_unstable();
    unique.dedup();
    assert_eq!(unique.len(), 34, "the list itself has duplicates");
    let missing: Vec<&str> = FMI2_CS_SYMBOLS
        .iter()
        .copied()
        .filter(|name| {
            let cname = CString::new(*name).expect("name");
            // SAFETY: only the address is read; nothing is called through it.
            let found = unsafe { fmu.lib.get::<*const c_void>(cname.as_bytes_with_nul()) };
            !matches!(found, Ok(p) if !(*p).is_null())
        })
        .collect();
    assert!(
        missing.is_empty(),
        "{} does not export {missing:?}",
        fmu.path.display()
    );
}

#[test]
fn version_and_types_platform() {
    let fmu = fmu();
    // SAFETY: both functions take nothing and return static C strings.
    let (version, platform) = unsafe {
        (
            CStr::from_ptr((fmu.get_version)()),
            CStr::from_ptr((fmu.get_types_platform)()),
        )
    };
    assert_eq!(version.to_str(), Ok("2.0"));
    assert_eq!(platform.to_str(), Ok("default"));
}

// ================================================================ 2. fmi2Instantiate

#[test]
fn guid_in_model_description_matches_the_computed_one() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("modelDescription/Wheel.xml");
    let xml = std::fs::read_to_string(&path).expect("modelDescription/Wheel.xml");
    let start = xml.find("guid=\"").expect("guid attribute") + "guid=\"".len();
    let end = start + xml[start..].find('"').expect("closing quote");
    assert_eq!(&xml[start..end], wheel_guid());
}

#[test]
fn wrong_guid_is_refused_and_the_log_names_it() {
    let bad = "{00000000-dead-beef-0000-000000000000}";
    let log = Spec::new("w")
        .guid(Some(bad))
        .instantiate()
        .err()
        .expect("a wrong GUID must give NULL");
    assert!(
        log.iter()
            .any(|e| e.status == ERROR && e.message.contains(bad)),
        "no error naming {bad}: {log:#?}"
    );
    let log = Spec::new("w")
        .guid(None)
        .instantiate()
        .err()
        .expect("a NULL GUID must give NULL");
    assert!(log.iter().any(|e| e.status == ERROR), "{log:#?}");
}

#[test]
fn model_exchange_and_null_instance_name_are_refused() {
    let log = Spec::new("me")
        .fmu_type(MODEL_EXCHANGE)
        .instantiate()
        .err()
        .expect("fmi2ModelExchange must give NULL");
    assert!(log.iter().any(|e| e.status == ERROR), "{log:#?}");
    let log = Spec::new("x")
        .no_name()
        .instantiate()
        .err()
        .expect("a NULL instanceName must give NULL");
    assert!(log.iter().any(|e| e.status == ERROR), "{log:#?}");
}

#[test]
fn null_logger_and_null_callbacks_do_not_crash() {
    let inst = Spec::new("silent")
        .callbacks(Callbacks::NullLogger)
        .instantiate()
        .expect("a NULL logger in the callbacks struct is fine");
    // An error that would be logged, with nowhere to log it.
    assert_eq!(inst.step(0.0, 0.01), ERROR);
    assert_eq!(inst.reset(), OK);
    inst.init(0.0, None);
    let traj = inst.run(0.0, 0.01, 10);
    assert!((traj[9][0] - nominal_q(0.1)).abs() < 1e-9);
    inst.free();

    // Whether NULL callbacks are accepted is the FMU's choice; it must not crash either way.
    if let Ok(inst) = Spec::new("nocallbacks")
        .callbacks(Callbacks::NullStruct)
        .instantiate()
    {
        assert_eq!(inst.step(0.0, 0.01), ERROR);
        assert_eq!(inst.reset(), OK);
        inst.init(0.0, None);
        assert_eq!(inst.step(0.0, 0.01), OK);
        inst.free();
    }
    // Refusals with NULL callbacks must not crash either.
    let refused = Spec::new("x")
        .guid(Some("{nope}"))
        .callbacks(Callbacks::NullStruct)
        .instantiate();
    assert!(refused.is_err());
}

#[test]
fn file_uri_resource_locations_are_accepted() {
    for uri in ["file:///tmp/a%20b", "file:/tmp/x", "file://localhost/tmp/x"] {
        let inst = Spec::new("res")
            .resource(uri)
            .instantiate()
            .unwrap_or_else(|log| panic!("{uri} refused: {log:#?}"));
        assert!(
            !inst.log().iter().any(|e| e.message.contains("resource")),
            "{uri}: {:#?}",
            inst.log()
        );
        inst.init(0.0, None);
        assert_eq!(inst.step(0.0, 0.01), OK);
    }
    // Control: a non-file URI is reported (so the checks above can fail).
    let inst = Spec::new("res")
        .resource("http://example.com/r")
        .instantiate()
        .expect("instance");
    inst.assert_logged(WARNING, &["resource location"]);
}

// ================================================================ 3. state machine

/// Drives a fresh instance into a state, then makes a call that is illegal there.
type IllegalCall = Box<dyn Fn(&Inst) -> Status>;

/// (function, state, the call).
fn illegal_calls() -> Vec<(&'static str, &'static str, IllegalCall)> {
    vec![
        (
            "fmi2DoStep",
            "Instantiated",
            Box::new(|i: &Inst| i.step(0.0, 0.01)),
        ),
        (
            "fmi2GetReal",
            "Instantiated",
            Box::new(|i: &Inst| i.get_reals(&[VR_Q]).0),
        ),
        (
            "fmi2ExitInitializationMode",
            "Instantiated",
            Box::new(|i: &Inst| i.exit()),
        ),
        (
            "fmi2SetupExperiment",
            "StepComplete",
            Box::new(|i: &Inst| {
                i.init(0.0, None);
                i.setup(0.0, None)
            }),
        ),
        (
            "fmi2EnterInitializationMode",
            "InitializationMode",
            Box::new(|i: &Inst| {
                assert_eq!(i.setup(0.0, None), OK);
                assert_eq!(i.enter(), OK);
                i.enter()
            }),
        ),
        (
            "fmi2DoStep",
            "Terminated",
            Box::new(|i: &Inst| {
                i.init(0.0, None);
                assert_eq!(i.step(0.0, 0.01), OK);
                assert_eq!(i.terminate(), OK);
                i.step(0.01, 0.01)
            }),
        ),
        (
            "fmi2Terminate",
            "Terminated",
            Box::new(|i: &Inst| {
                i.init(0.0, None);
                assert_eq!(i.terminate(), OK);
                i.terminate()
            }),
        ),
    ]
}

#[test]
fn calls_in_a_wrong_state_are_refused_then_reset_recovers() {
    for (fname, state, call) in illegal_calls() {
        let inst = Inst::new("states");
        let s = call(&inst);
        assert_eq!(s, ERROR, "{fname} in {state} returned {s}");
        // Names the function, and the state outside the function's own name.
        let named = |e: &Entry| {
            e.status == ERROR
                && e.message.contains(fname)
                && e.message.replace(fname, "").contains(state)
        };
        assert!(
            inst.log().iter().any(named),
            "{fname}/{state}: {:#?}",
            inst.log()
        );

        // Now in Error: stepping is still refused, and the log says so.
        inst.clear_log();
        assert_eq!(
            inst.step(0.0, 0.01),
            ERROR,
            "{fname}/{state}: step in Error"
        );
        inst.assert_logged(ERROR, &["fmi2DoStep", "Error"]);

        // fmi2Reset recovers; a full run is possible again.
        assert_eq!(
            inst.reset(),
            OK,
            "{fname}/{state}: reset; log {:#?}",
            inst.log()
        );
        inst.init(0.0, None);
        let traj = inst.run(0.0, 0.01, 100);
        for (i, y) in traj.iter().enumerate() {
            let t = (i + 1) as f64 * 0.01;
            assert!((y[0] - nominal_q(t)).abs() < 1e-9, "after reset, t={t}");
        }
        let log = inst.free();
        assert!(
            !log.iter()
                .any(|e| e.status >= ERROR && e.message.contains("fmi2FreeInstance")),
            "{log:#?}"
        );
    }
}

#[test]
fn free_instance_works_in_every_state() {
    /// A state and how to reach it from Instantiated.
    type Drive = (&'static str, fn(&Inst));
    let drive: [Drive; 6] = [
        ("Instantiated", |_| {}),
        ("InitializationMode", |i| {
            assert_eq!(i.setup(0.0, None), OK);
            assert_eq!(i.enter(), OK);
        }),
        ("StepComplete", |i| {
            i.init(0.0, None);
            assert_eq!(i.step(0.0, 0.01), OK);
        }),
        ("Terminated", |i| {
            i.init(0.0, None);
            assert_eq!(i.terminate(), OK);
        }),
        ("Error", |i| {
            assert_eq!(i.step(0.0, 0.01), ERROR);
        }),
        ("Error after init", |i| {
            i.init(0.0, None);
            assert_eq!(i.step(0.5, 0.01), ERROR);
        }),
    ];
    for (state, f) in drive {
        let inst = Inst::new("free");
        f(&inst);
        let log = inst.free();
        assert!(
            !log.iter().any(|e| e.message.contains("fmi2FreeInstance")),
            "free in {state}: {log:#?}"
        );
    }
    // The library is still healthy.
    assert_eq!(simulate(&[], 0.01, 3).len(), 3);
}

// ================================================================ 4. NULL pointers

#[test]
fn null_instance_is_refused_by_every_function() {
    let fmu = fmu();
    let c: Component = null_mut();
    let vr: [Vr; 1] = [VR_Q];
    let mut r = [0.0f64; 1];
    let mut i = [0 as c_int; 1];
    let mut s: [CStrPtr; 1] = [null()];
    let order = [1 as c_int];
    let mut state: FmuState = null_mut();
    let mut size = 0usize;
    let mut bytes = [0 as c_char; 16];
    let mut st: Status = 0;
    let mut rs = 0.0f64;
    let mut is: c_int = 0;
    let mut ss: CStrPtr = null();
    let cat = [c"logCalls".as_ptr()];
    // SAFETY: every call gets c = NULL (which the FMU must reject) and otherwise valid
    // pointers to arrays of the stated lengths.
    let results: Vec<(&str, Status)> = unsafe {
        (fmu.free_instance)(c);
        vec![
            (
                "fmi2SetDebugLogging",
                (fmu.set_debug_logging)(c, 1, 1, cat.as_ptr()),
            ),
            (
                "fmi2SetupExperiment",
                (fmu.setup_experiment)(c, 0, 0.0, 0.0, 0, 0.0),
            ),
            (
                "fmi2EnterInitializationMode",
                (fmu.enter_initialization_mode)(c),
            ),
            (
                "fmi2ExitInitializationMode",
                (fmu.exit_initialization_mode)(c),
            ),
            ("fmi2Terminate", (fmu.terminate)(c)),
            ("fmi2Reset", (fmu.reset)(c)),
            (
                "fmi2GetReal",
                (fmu.get_real)(c, vr.as_ptr(), 1, r.as_mut_ptr()),
            ),
            (
                "fmi2GetInteger",
                (fmu.get_integer)(c, vr.as_ptr(), 1, i.as_mut_ptr()),
            ),
            (
                "fmi2GetBoolean",
                (fmu.get_boolean)(c, vr.as_ptr(), 1, i.as_mut_ptr()),
            ),
            (
                "fmi2GetString",
                (fmu.get_string)(c, vr.as_ptr(), 1, s.as_mut_ptr()),
            ),
            ("fmi2SetReal", (fmu.set_real)(c, vr.as_ptr(), 1, r.as_ptr())),
            (
                "fmi2SetInteger",
                (fmu.set_integer)(c, vr.as_ptr(), 1, i.as_ptr()),
            ),
            (
                "fmi2SetBoolean",
                (fmu.set_boolean)(c, vr.as_ptr(), 1, i.as_ptr()),
            ),
            (
                "fmi2SetString",
                (fmu.set_string)(c, vr.as_ptr(), 1, cat.as_ptr()),
            ),
            ("fmi2GetFMUstate", (fmu.get_fmu_state)(c, &mut state)),
            ("fmi2SetFMUstate", (fmu.set_fmu_state)(c, state)),
            ("fmi2FreeFMUstate", (fmu.free_fmu_state)(c, &mut state)),
            (
                "fmi2SerializedFMUstateSize",
                (fmu.serialized_fmu_state_size)(c, state, &mut size),
            ),
            (
                "fmi2SerializeFMUstate",
                (fmu.serialize_fmu_state)(c, state, bytes.as_mut_ptr(), bytes.len()),
            ),
            (
                "fmi2DeSerializeFMUstate",
                (fmu.deserialize_fmu_state)(c, bytes.as_ptr(), bytes.len(), &mut state),
            ),
            (
                "fmi2GetDirectionalDerivative",
                (fmu.get_directional_derivative)(
                    c,
                    vr.as_ptr(),
                    1,
                    vr.as_ptr(),
                    1,
                    r.as_ptr(),
                    r.as_mut_ptr(),
                ),
            ),
            (
                "fmi2SetRealInputDerivatives",
                (fmu.set_real_input_derivatives)(c, vr.as_ptr(), 1, order.as_ptr(), r.as_ptr()),
            ),
            (
                "fmi2GetRealOutputDerivatives",
                (fmu.get_real_output_derivatives)(
                    c,
                    vr.as_ptr(),
                    1,
                    order.as_ptr(),
                    r.as_mut_ptr(),
                ),
            ),
            ("fmi2DoStep", (fmu.do_step)(c, 0.0, 0.01, 1)),
            ("fmi2CancelStep", (fmu.cancel_step)(c)),
            (
                "fmi2GetStatus",
                (fmu.get_status)(c, DO_STEP_STATUS, &mut st),
            ),
            (
                "fmi2GetRealStatus",
                (fmu.get_real_status)(c, LAST_SUCCESSFUL_TIME, &mut rs),
            ),
            (
                "fmi2GetIntegerStatus",
                (fmu.get_integer_status)(c, DO_STEP_STATUS, &mut is),
            ),
            (
                "fmi2GetBooleanStatus",
                (fmu.get_boolean_status)(c, TERMINATED, &mut is),
            ),
            (
                "fmi2GetStringStatus",
                (fmu.get_string_status)(c, DO_STEP_STATUS, &mut ss),
            ),
        ]
    };
    assert_eq!(
        results.len(),
        30,
        "31 instance functions, fmi2FreeInstance above"
    );
    let wrong: Vec<_> = results.iter().filter(|(_, s)| *s != ERROR).collect();
    assert!(wrong.is_empty(), "not fmi2Error for c = NULL: {wrong:?}");
    assert!(state.is_null(), "no state may be produced for c = NULL");
}

#[test]
fn null_arrays_with_nonzero_length_are_errors() {
    let fmu = fmu();
    let vr = [VR_K];
    let val = [1.0f64];
    let mut out = [0.0f64];
    let out_ptr = out.as_mut_ptr();
    type Call = Box<dyn Fn(Component) -> Status>;
    // (what, the name the log must give, needs an initialized instance, the call)
    let cases: Vec<(&str, &str, bool, Call)> = vec![
        // For every closure below: `c` is a live instance; the non-NULL arrays hold one element.
        ("fmi2GetReal vr", "'vr'", true, {
            // SAFETY: `c` is live; non-NULL arrays hold one element (see above).
            Box::new(move |c| unsafe { (fmu.get_real)(c, null(), 1, out_ptr) })
        }),
        ("fmi2GetReal value", "'value'", true, {
            // SAFETY: `c` is live; non-NULL arrays hold one element (see above).
            Box::new(move |c| unsafe { (fmu.get_real)(c, vr.as_ptr(), 1, null_mut()) })
        }),
        ("fmi2SetReal vr", "'vr'", false, {
            // SAFETY: `c` is live; non-NULL arrays hold one element (see above).
            Box::new(move |c| unsafe { (fmu.set_real)(c, null(), 1, val.as_ptr()) })
        }),
        ("fmi2SetReal value", "'value'", false, {
            // SAFETY: `c` is live; non-NULL arrays hold one element (see above).
            Box::new(move |c| unsafe { (fmu.set_real)(c, vr.as_ptr(), 1, null()) })
        }),
        ("fmi2GetInteger vr", "'vr'", true, {
            // SAFETY: `c` is live; non-NULL arrays hold one element (see above).
            Box::new(move |c| unsafe { (fmu.get_integer)(c, null(), 1, null_mut()) })
        }),
        ("fmi2SetBoolean value", "'value'", false, {
            // SAFETY: `c` is live; non-NULL arrays hold one element (see above).
            Box::new(move |c| unsafe { (fmu.set_boolean)(c, vr.as_ptr(), 1, null()) })
        }),
        ("fmi2GetString value", "'value'", true, {
            // SAFETY: `c` is live; non-NULL arrays hold one element (see above).
            Box::new(move |c| unsafe { (fmu.get_string)(c, vr.as_ptr(), 1, null_mut()) })
        }),
        ("fmi2SetDebugLogging categories", "'categories'", false, {
            // SAFETY: `c` is live; non-NULL arrays hold one element (see above).
            Box::new(move |c| unsafe { (fmu.set_debug_logging)(c, 1, 2, null()) })
        }),
        ("fmi2GetFMUstate slot", "FMUstate", true, {
            // SAFETY: `c` is live; non-NULL arrays hold one element (see above).
            Box::new(move |c| unsafe { (fmu.get_fmu_state)(c, null_mut()) })
        }),
        ("fmi2DeSerializeFMUstate bytes", "serializedState", true, {
            Box::new(move |c| {
                let mut s: FmuState = null_mut();
                // SAFETY: `c` is live; non-NULL arrays hold one element (see above).
                unsafe { (fmu.deserialize_fmu_state)(c, null(), 10, &mut s) }
            })
        }),
        ("fmi2GetRealStatus value", "'value'", true, {
            // SAFETY: `c` is live; non-NULL arrays hold one element (see above).
            Box::new(move |c| unsafe { (fmu.get_real_status)(c, LAST_SUCCESSFUL_TIME, null_mut()) })
        }),
    ];
    for (what, names, initialized, call) in cases {
        let inst = Inst::new("nulls");
        if initialized {
            inst.init(0.0, None);
        }
        assert_eq!(call(inst.c), ERROR, "{what}");
        // The message names the argument, so the refusal is not a state-table one.
        inst.assert_logged(ERROR, &[names]);
    }
}

#[test]
fn zero_length_get_and_set_with_null_pointers_are_ok() {
    let fmu = fmu();
    let inst = Inst::new("empty");
    inst.init(0.0, None);
    let c = inst.c;
    // SAFETY: `c` is live; nvr = 0, so no array is touched.
    let statuses = unsafe {
        [
            (fmu.get_real)(c, null(), 0, null_mut()),
            (fmu.get_integer)(c, null(), 0, null_mut()),
            (fmu.get_boolean)(c, null(), 0, null_mut()),
            (fmu.get_string)(c, null(), 0, null_mut()),
            (fmu.set_real)(c, null(), 0, null()),
            (fmu.set_integer)(c, null(), 0, null()),
            (fmu.set_boolean)(c, null(), 0, null()),
            (fmu.set_string)(c, null(), 0, null()),
        ]
    };
    assert_eq!(statuses, [OK; 8]);
    assert_eq!(inst.step(0.0, 0.01), OK, "still usable");
}

// ================================================================ 5. value references

#[test]
fn unknown_references_and_wrong_types_are_errors_naming_the_reference() {
    let inst = Inst::new("vr");
    inst.init(0.0, None);
    assert_eq!(inst.get_reals(&[VR_Q, 999]).0, ERROR);
    inst.assert_logged(ERROR, &["fmi2GetReal", "999"]);

    let inst = Inst::new("vr");
    assert_eq!(inst.set(999, 1.0), ERROR);
    inst.assert_logged(ERROR, &["fmi2SetReal", "999"]);

    let fmu = fmu();
    let inst = Inst::new("vr");
    inst.init(0.0, None);
    let mut v: c_int = 0;
    // SAFETY: live instance; one reference, one output slot.
    let s = unsafe { (fmu.get_integer)(inst.c, [VR_M].as_ptr(), 1, &mut v) };
    assert_eq!(s, ERROR, "fmi2GetInteger on the Real m");
    inst.assert_logged(ERROR, &["fmi2GetInteger", "reference 0"]);

    let inst = Inst::new("vr");
    // SAFETY: live instance; one reference, one value.
    let s = unsafe { (fmu.set_boolean)(inst.c, [VR_K].as_ptr(), 1, &1) };
    assert_eq!(s, ERROR, "fmi2SetBoolean on the Real K");
    inst.assert_logged(ERROR, &["fmi2SetBoolean", "reference 1"]);
}

#[test]
fn outputs_and_fixed_parameters_after_init_cannot_be_set() {
    let inst = Inst::new("causality");
    assert_eq!(inst.set(VR_Q, 0.5), ERROR, "output q before init");
    inst.assert_logged(ERROR, &["'q'"]);

    let inst = Inst::new("causality");
    inst.init(0.0, None);
    assert_eq!(inst.set(VR_V, 0.5), ERROR, "output v after init");
    inst.assert_logged(ERROR, &["'v'"]);

    let inst = Inst::new("fixed");
    assert_eq!(inst.setup(0.0, None), OK);
    assert_eq!(inst.enter(), OK);
    assert_eq!(inst.set(VR_M, 12.0), OK, "m in InitializationMode");
    assert_eq!(inst.exit(), OK);
    assert_eq!(inst.get(VR_M), 12.0);
    assert_eq!(inst.set(VR_M, 11.0), ERROR, "m after initialization");
    inst.assert_logged(ERROR, &["'m'", "fixed"]);
    assert_eq!(inst.get(VR_M), 12.0, "refused value must not be applied");
}

#[test]
fn tunable_k_set_after_init_acts_from_the_next_step() {
    let h = 0.01;
    let inst = Inst::new("tunable");
    inst.init(0.0, None);
    let mut switched = inst.run(0.0, h, 100);
    assert_eq!(inst.set(VR_K, 150.0), OK, "log {:#?}", inst.log());
    assert_eq!(inst.get(VR_K), 150.0);
    switched.extend(inst.run(1.0, h, 100));

    // The same run with K = 100 set from the start: equal up to the switch, different after.
    let unchanged = simulate(&[(VR_K, 100.0)], h, 200);
    assert_eq!(bits(&switched[..100]), bits(&unchanged[..100]));
    for i in 100..200 {
        assert_ne!(
            switched[i][0], unchanged[i][0],
            "step {i} ignores the new K"
        );
    }
    // After the switch: the free response with K = 150 from the state reached at t = 1.
    let [q1, v1, _] = switched[99];
    for (i, y) in switched[100..].iter().enumerate() {
        let tau = (i + 1) as f64 * h;
        let r = free_response(10.0, 150.0, 20.0, q1, v1, tau);
        assert!(
            (y[0] - r).abs() < 1e-9,
            "t = {}: {} vs {r}",
            1.0 + tau,
            y[0]
        );
    }
    // And not the run with K = 150 from the start.
    let from_start = simulate(&[(VR_K, 150.0)], h, 200);
    assert_ne!(switched[150][0], from_start[150][0]);
}

// ================================================================ 6. values

#[test]
fn non_finite_values_and_non_positive_mass_are_errors() {
    let inst = Inst::new("values");
    let cases = [
        (VR_K, f64::NAN, "'K'"),
        (VR_K, f64::INFINITY, "'K'"),
        (VR_C, f64::NEG_INFINITY, "'C'"),
        (VR_M, 0.0, "'m'"),
        (VR_M, -1.0, "'m'"),
        (VR_C, -1.0, "'C'"),
    ];
    for (vr, v, name) in cases {
        inst.clear_log();
        assert_eq!(inst.set(vr, v), ERROR, "{name} = {v}");
        inst.assert_logged(ERROR, &[name]);
        assert_eq!(inst.reset(), OK);
    }
    // None of the refused values was kept.
    inst.init(0.0, None);
    let (s, p) = inst.get_reals(&[VR_M, VR_K, VR_C]);
    assert_eq!((s, p), (OK, vec![10.0, 100.0, 20.0]));
}

#[test]
fn negative_stiffness_is_a_warning_and_logged() {
    let inst = Inst::new("warn");
    assert_eq!(inst.set(VR_K, -5.0), WARNING);
    assert!(
        inst.log().iter().any(|e| e.status == WARNING
            && e.category == "logStatusWarning"
            && e.message.contains("K")),
        "{:#?}",
        inst.log()
    );
    inst.init(0.0, None);
    assert_eq!(inst.get(VR_K), -5.0, "the value is applied");
    assert_eq!(inst.step(0.0, 0.01), OK, "and the model runs");
}

// ================================================================ 7. stepping

#[test]
fn fixed_steps_match_the_closed_form() {
    let inst = Inst::new("fixed");
    inst.init(0.0, None);
    assert_eq!(inst.get(VR_Q), 0.1);
    let h = 0.01;
    let traj = inst.run(0.0, h, 500);
    let worst = traj
        .iter()
        .enumerate()
        .map(|(i, y)| (y[0] - nominal_q((i + 1) as f64 * h)).abs())
        .fold(0.0, f64::max);
    assert!(worst < 1e-9, "max |q - closed form| = {worst:e}");
    let mut last = 0.0;
    // SAFETY: live instance; `last` is writable.
    let s = unsafe { (inst.fmu.get_real_status)(inst.c, LAST_SUCCESSFUL_TIME, &mut last) };
    assert_eq!(s, OK);
    assert!((last - 5.0).abs() < 1e-9, "lastSuccessfulTime {last}");
}

#[test]
fn variable_steps_and_a_sloppy_communication_point_match_the_closed_form() {
    let sloppy = 0.010000000000000009f64;
    assert_ne!(sloppy, 0.01, "the point must differ from the FMU time");
    let inst = Inst::new("variable");
    inst.init(0.0, None);
    let pattern: [f64; 6] = [0.01, 0.003, 0.017, 0.0005, 0.02, 0.0095];
    let (mut t, mut k, mut n) = (0.0f64, 0usize, 0usize);
    let mut worst = 0.0f64;
    while t < 5.0 - 1e-12 {
        let h = pattern[k % pattern.len()].min(5.0 - t);
        let point = if k == 1 { sloppy } else { t };
        let s = inst.step(point, h);
        assert_eq!(s, OK, "fmi2DoStep({point}, {h}); log {:#?}", inst.log());
        t = point + h;
        worst = worst.max((inst.get(VR_Q) - nominal_q(t)).abs());
        k += 1;
        n += 1;
    }
    assert!(n > 300, "{n} steps");
    assert!(worst < 1e-9, "max |q - closed form| = {worst:e}");
}

#[test]
fn a_communication_point_off_the_fmu_time_is_an_error() {
    let inst = Inst::new("point");
    inst.init(0.0, None);
    assert_eq!(inst.step(0.0, 0.01), OK);
    assert_eq!(inst.step(0.5, 0.01), ERROR);
    inst.assert_logged(ERROR, &["fmi2DoStep", "0.5"]);

    // A point off by much more than rounding, but less than a step.
    let inst = Inst::new("point");
    inst.init(0.0, None);
    assert_eq!(inst.step(0.0, 0.01), OK);
    assert_eq!(inst.step(0.01 + 1e-6, 0.01), ERROR);
}

#[test]
fn an_absurd_step_is_an_error_not_a_hang() {
    // fmi2DoStep with h = 1e300 (or 1e6) never returned: the substep count overflowed.
    let inst = Inst::new("absurd");
    inst.init(0.0, None);
    for h in [1e300, 1e6] {
        assert_eq!(inst.step(0.0, h), ERROR, "h = {h}");
        inst.assert_logged(
            ERROR,
            &["fmi2DoStep", "substeps", "use shorter communication steps"],
        );
        assert_eq!(inst.reset(), OK);
        inst.init(0.0, None);
    }
    assert_eq!(inst.step(0.0, 0.01), OK, "normal steps after a reset");

    // VehicleTrack (no irregularity, a short window: quick to initialise in a debug build).
    let guid = railuq::fmi2::xml::guid(&railuq::models::vehicle_track::INFO);
    let vt = Spec::new("absurd-vt")
        .guid(Some(&guid))
        .instantiate()
        .unwrap_or_else(|log| panic!("VehicleTrack: {log:#?}"));
    use railuq::models::vehicle_track::{VR_IRREGULARITY, VR_N_MODES, VR_N_SLEEPERS};
    for (vr, v) in [(VR_N_SLEEPERS, 63), (VR_N_MODES, 32), (VR_IRREGULARITY, 0)] {
        // SAFETY: live instance; one value reference and one value.
        let s = unsafe { (fmu().set_integer)(vt.c, &vr, 1, &v) };
        assert_eq!(s, OK);
    }
    vt.init(0.0, None);
    assert_eq!(vt.step(0.0, 1e300), ERROR);
    vt.assert_logged(ERROR, &["fmi2DoStep", "substeps"]);
}

#[test]
fn a_step_past_the_stop_time_is_an_error() {
    let inst = Inst::new("stop");
    inst.init(0.0, Some(1.0));
    inst.run(0.0, 0.01, 100); // lands on 1.0 within rounding
    assert_eq!(inst.step(1.0, 0.01), ERROR);
    inst.assert_logged(ERROR, &["stop time"]);

    let inst = Inst::new("stop");
    inst.init(0.0, Some(1.0));
    inst.run(0.0, 0.01, 95);
    assert_eq!(
        inst.step(0.95, 0.1),
        ERROR,
        "a step ending beyond the stop time"
    );

    // stopTimeDefined = false: the stop time value is ignored.
    let inst = Inst::new("stop");
    let fmu = fmu();
    // SAFETY: live instance.
    let s = unsafe { (fmu.setup_experiment)(inst.c, 0, 0.0, 0.0, 0, 1.0) };
    assert_eq!(s, OK);
    assert_eq!(inst.enter(), OK);
    assert_eq!(inst.exit(), OK);
    inst.run(0.0, 0.01, 150);
}

#[test]
fn a_non_zero_start_time_shifts_the_solution() {
    let inst = Inst::new("start");
    inst.init(2.0, Some(3.0));
    assert_eq!(inst.step(0.0, 0.01), ERROR, "the FMU starts at 2.0");
    let inst = Inst::new("start");
    inst.init(2.0, Some(3.0));
    let traj = inst.run(2.0, 0.01, 100);
    for (i, y) in traj.iter().enumerate() {
        let tau = (i + 1) as f64 * 0.01;
        assert!((y[0] - nominal_q(tau)).abs() < 1e-9, "t = {}", 2.0 + tau);
    }
    let mut last = 0.0;
    // SAFETY: live instance; `last` is writable.
    let s = unsafe { (inst.fmu.get_real_status)(inst.c, LAST_SUCCESSFUL_TIME, &mut last) };
    assert_eq!(s, OK);
    assert!((last - 3.0).abs() < 1e-9, "lastSuccessfulTime {last}");
}

#[test]
fn values_set_in_initialization_mode_reach_the_outputs_and_the_run() {
    const VR_Q0: Vr = 3;
    let inst = Inst::new("initmode");
    assert_eq!(inst.setup(0.0, None), OK);
    assert_eq!(inst.enter(), OK);
    assert_eq!(inst.get(VR_Q), 0.1);
    assert_eq!(inst.set(VR_Q0, 0.2), OK);
    assert_eq!(inst.get(VR_Q), 0.2, "q follows q0 during initialization");
    assert_eq!(inst.exit(), OK);
    let traj = inst.run(0.0, 0.01, 100);
    for (i, y) in traj.iter().enumerate() {
        let t = (i + 1) as f64 * 0.01;
        assert!((y[0] - 2.0 * nominal_q(t)).abs() < 2e-9, "t = {t}");
    }
}

// ================================================================ 8. reset

#[test]
fn reset_gives_a_bitwise_equal_trajectory() {
    let params = [(VR_K, 120.0), (VR_C, 15.0)];
    let inst = Inst::new("reset");
    for (vr, v) in params {
        assert_eq!(inst.set(vr, v), OK);
    }
    inst.init(0.0, None);
    let first = inst.run(0.0, 0.01, 200);

    assert_eq!(inst.reset(), OK);
    // Reset restores the start values.
    assert_eq!(inst.setup(0.0, None), OK);
    assert_eq!(inst.enter(), OK);
    assert_eq!(inst.get_reals(&[VR_K, VR_C]), (OK, vec![100.0, 20.0]));
    assert_eq!(inst.reset(), OK, "reset from InitializationMode");

    for (vr, v) in params {
        assert_eq!(inst.set(vr, v), OK);
    }
    inst.init(0.0, None);
    let second = inst.run(0.0, 0.01, 200);
    assert_eq!(bits(&first), bits(&second));
    assert_ne!(
        bits(&first),
        bits(&simulate(&[], 0.01, 200)),
        "params mattered"
    );
}

// ================================================================ 9. FMU state

#[test]
fn get_set_and_serialized_fmu_state_replay_bitwise() {
    let h = 0.01;
    let inst = Inst::new("state");
    inst.init(0.0, None);
    inst.run(0.0, h, 100);
    let mut s: FmuState = null_mut();
    assert_eq!(inst.get_state(&mut s), OK);
    assert!(!s.is_null());
    let first = inst.run(1.0, h, 100);

    assert_eq!(inst.set_state(s), OK);
    let second = inst.run(1.0, h, 100);
    assert_eq!(bits(&first), bits(&second), "set state");

    let bytes = inst.serialize(s);
    assert_eq!(bytes, inst.serialize(s), "serialization is deterministic");
    let mut s2: FmuState = null_mut();
    assert_eq!(inst.deserialize(&bytes, &mut s2), OK);
    assert!(!s2.is_null() && s2 != s);
    assert_eq!(inst.set_state(s2), OK);
    let third = inst.run(1.0, h, 100);
    assert_eq!(bits(&first), bits(&third), "serialized state");

    // Deserialize into an existing state, then a second instance can use the bytes too.
    assert_eq!(inst.deserialize(&bytes, &mut s), OK);
    assert_eq!(inst.set_state(s), OK);
    assert_eq!(bits(&first), bits(&inst.run(1.0, h, 100)));
    let other = Inst::new("other");
    let mut s3: FmuState = null_mut();
    assert_eq!(other.deserialize(&bytes, &mut s3), OK);
    assert_eq!(other.set_state(s3), OK);
    assert_eq!(
        bits(&first),
        bits(&other.run(1.0, h, 100)),
        "other instance"
    );
    assert_eq!(other.free_state(&mut s3), OK);
    assert!(s3.is_null());

    assert_eq!(inst.free_state(&mut s), OK);
    assert!(s.is_null(), "fmi2FreeFMUstate sets the pointer to NULL");
    assert_eq!(inst.free_state(&mut s2), OK);
    assert!(s2.is_null());
    assert_eq!(inst.free_state(&mut s), OK, "freeing NULL is a no-op");
}

/// Deterministic pseudo-random bytes (xorshift64).
fn noise(n: usize, mut x: u64) -> Vec<u8> {
    (0..n)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x as u8
        })
        .collect()
}

#[test]
fn foreign_truncated_and_corrupted_states_are_refused() {
    let h = 0.01;
    let inst = Inst::new("corrupt");
    inst.init(0.0, None);
    inst.run(0.0, h, 100);
    let mut good: FmuState = null_mut();
    assert_eq!(inst.get_state(&mut good), OK);
    let reference = inst.run(1.0, h, 100);
    let bytes = inst.serialize(good);

    let flip = |i: usize| {
        let mut b = bytes.clone();
        b[i] ^= 0x10;
        b
    };
    let mut forged_magic = noise(bytes.len(), 7);
    forged_magic[..8].copy_from_slice(&bytes[..8]);
    let bad: Vec<(&str, Vec<u8>)> = vec![
        ("random bytes", noise(bytes.len(), 0x9e37_79b9_7f4a_7c15)),
        ("random bytes with our magic", forged_magic),
        ("empty", Vec::new()),
        ("truncated by one", bytes[..bytes.len() - 1].to_vec()),
        ("truncated to half", bytes[..bytes.len() / 2].to_vec()),
        ("extended by one", [bytes.as_slice(), &[0]].concat()),
        ("flipped byte in the magic", flip(2)),
        ("flipped byte in the middle", flip(bytes.len() / 2)),
        ("flipped byte in the checksum", flip(bytes.len() - 1)),
    ];
    for (what, b) in bad {
        inst.clear_log();
        let mut s: FmuState = null_mut();
        assert_eq!(inst.deserialize(&b, &mut s), ERROR, "{what}");
        assert!(s.is_null(), "{what}: a state was produced");
        inst.assert_logged(ERROR, &["fmi2DeSerializeFMUstate"]);
        // Not crashed, and recoverable with the good state.
        assert_eq!(inst.set_state(good), OK, "{what}: {:#?}", inst.log());
        assert_eq!(bits(&reference), bits(&inst.run(1.0, h, 100)), "{what}");
    }

    // A wrong buffer size for serialization is refused too.
    let (s, n) = inst.state_size(good);
    assert_eq!(s, OK);
    let mut small = vec![0u8; n - 1];
    assert_eq!(inst.serialize_into(good, &mut small), ERROR);
    assert_eq!(inst.free_state(&mut good), OK);
}

// ================================================================ 10. panic boundary

#[test]
fn a_panic_inside_the_fmu_is_fatal_not_an_abort() {
    let panic_value = railuq::fmi2::TEST_PANIC_VALUE;
    assert_eq!(panic_value, -7.0e77);
    let armed = std::env::var_os(railuq::fmi2::TEST_PANIC_ENV).is_some_and(|v| v == "1");
    if !armed && !cfg!(feature = "test-panic") {
        // Unarmed, the value is an ordinary number to the shipped library.
        let inst = Inst::new("unarmed");
        let s = inst.set(VR_K, panic_value);
        assert_ne!(s, FATAL, "unarmed: {:#?}", inst.log());
        assert!(
            !inst.log().iter().any(|e| e.message.contains("panic")),
            "{:#?}",
            inst.log()
        );
        // The hook is armed by the environment of the process that loads the library: this
        // test runs again, alone, in a child process that has it.
        let name = "a_panic_inside_the_fmu_is_fatal_not_an_abort";
        let out = std::process::Command::new(std::env::current_exe().expect("test executable"))
            .args(["--exact", name, "--test-threads=1", "--nocapture"])
            .env(railuq::fmi2::TEST_PANIC_ENV, "1")
            .output()
            .expect("run the test again with the hook armed");
        let text = format!(
            "{}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(
            out.status.success() && text.contains("1 passed"),
            "the armed run failed ({}):\n{text}",
            out.status
        );
        return;
    }
    let fmu = fmu();
    let inst = Inst::new("panic");
    inst.init(0.0, None);
    inst.run(0.0, 0.01, 50);
    let s = inst.set(VR_K, panic_value);
    assert_eq!(
        s,
        FATAL,
        "fmi2SetReal({panic_value}) returned {s}, not fmi2Fatal with the test hook armed \
         ({}): log {:#?}",
        fmu.path.display(),
        inst.log()
    );
    // We are still here: the panic did not abort the process.
    assert!(
        inst.log()
            .iter()
            .any(|e| e.status == FATAL && e.message.contains("panic")),
        "{:#?}",
        inst.log()
    );

    let mut state: FmuState = null_mut();
    let refused = [
        ("fmi2DoStep", inst.step(0.5, 0.01)),
        ("fmi2GetReal", inst.get_reals(&[VR_Q]).0),
        ("fmi2SetReal", inst.set(VR_K, 100.0)),
        ("fmi2Terminate", inst.terminate()),
        ("fmi2Reset", inst.reset()),
        ("fmi2SetupExperiment", inst.setup(0.0, None)),
        ("fmi2EnterInitializationMode", inst.enter()),
        ("fmi2GetFMUstate", inst.get_state(&mut state)),
        ("fmi2SetDebugLogging", inst.set_debug_logging(true, &[])),
    ];
    let accepted: Vec<_> = refused.iter().filter(|(_, s)| *s == OK).collect();
    assert!(
        accepted.is_empty(),
        "accepted after fmi2Fatal: {accepted:?}"
    );
    assert!(state.is_null());
    inst.free();

    // The library still works for new instances.
    let traj = simulate(&[], 0.01, 100);
    assert!((traj[99][0] - nominal_q(1.0)).abs() < 1e-9);
}

// ================================================================ 11. threads

#[test]
fn two_instances_on_two_threads_match_sequential_runs() {
    let ks = [80.0, 140.0];
    let barrier = Barrier::new(ks.len());
    let parallel: Vec<Traj> = thread::scope(|scope| {
        let handles: Vec<_> = ks
            .iter()
            .map(|&k| {
                let barrier = &barrier;
                scope.spawn(move || {
                    let inst = Inst::new(&format!("thread K={k}"));
                    assert_eq!(inst.set(VR_K, k), OK);
                    inst.init(0.0, None);
                    barrier.wait(); // both instances alive before either steps
                    inst.run(0.0, 0.01, 500)
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("thread"))
            .collect()
    });
    for (&k, p) in ks.iter().zip(&parallel) {
        assert_eq!(bits(p), bits(&simulate(&[(VR_K, k)], 0.01, 500)), "K = {k}");
    }
    assert_ne!(bits(&parallel[0]), bits(&parallel[1]));
}

#[test]
fn eight_instances_alive_at_once() {
    let ks: Vec<f64> = (0..8).map(|i| 60.0 + 15.0 * i as f64).collect();
    let insts: Vec<Inst> = ks
        .iter()
        .enumerate()
        .map(|(i, &k)| {
            let inst = Inst::new(&format!("inst{i}"));
            assert_eq!(inst.set(VR_K, k), OK);
            inst.init(0.0, None);
            inst
        })
        .collect();
    let h = 0.01;
    let mut trajs: Vec<Traj> = vec![Vec::new(); insts.len()];
    for step in 0..300 {
        for (inst, traj) in insts.iter().zip(&mut trajs) {
            traj.extend(inst.run(step as f64 * h, h, 1));
        }
    }
    for ((inst, traj), &k) in insts.iter().zip(&trajs).zip(&ks) {
        assert_eq!(bits(traj), bits(&simulate(&[(VR_K, k)], h, 300)), "K = {k}");
        assert!(
            inst.log().iter().all(|e| e.category == "logCalls"),
            "{:#?}",
            inst.log()
        );
    }
    for w in trajs.windows(2) {
        assert_ne!(bits(&w[0]), bits(&w[1]));
    }
}

// ================================================================ 12. debug logging

#[test]
fn unknown_log_category_is_an_error() {
    let inst = Inst::new("cats");
    assert_eq!(inst.set_debug_logging(true, &["logNonsense"]), ERROR);
    inst.assert_logged(ERROR, &["logNonsense"]);
    let inst = Inst::new("cats");
    assert_eq!(
        inst.set_debug_logging(true, &["logStatusWarning", "logCalls"]),
        OK
    );
}

#[test]
fn log_calls_gives_one_line_per_call() {
    let inst = Spec::new("calls")
        .logging(false)
        .instantiate()
        .expect("instance");
    assert_eq!(inst.set_debug_logging(true, &["logCalls"]), OK);
    inst.clear_log();

    assert_eq!(inst.set(VR_K, 120.0), OK);
    inst.init(0.0, None);
    inst.run(0.0, 0.01, 3); // 3 steps, 3 gets
    let log = inst.log();
    let expected = [
        ("fmi2SetReal", 1),
        ("fmi2SetupExperiment", 1),
        ("fmi2EnterInitializationMode", 1),
        ("fmi2ExitInitializationMode", 1),
        ("fmi2DoStep", 3),
        ("fmi2GetReal", 3),
    ];
    for (fname, n) in expected {
        let got = log
            .iter()
            .filter(|e| e.category == "logCalls" && e.message.starts_with(fname))
            .count();
        assert_eq!(got, n, "{fname}: {log:#?}");
    }
    assert_eq!(log.len(), 10, "one line per call: {log:#?}");
    assert!(log
        .iter()
        .all(|e| e.status == OK && e.instance == "calls" && e.category == "logCalls"));

    assert_eq!(inst.set_debug_logging(false, &["logCalls"]), OK);
    inst.clear_log();
    assert_eq!(inst.step(0.03, 0.01), OK);
    assert!(inst.log().is_empty(), "{:#?}", inst.log());
}

/// fmi2SetDebugLogging(on, ["logCalls"]) on an instance created with loggingOn = false
/// enables logCalls only (as the FMI fmuTemplate does: listed categories are enabled, the
/// others stay off), so a K < 0 warning must not be logged.
#[test]
fn enabling_log_calls_alone_does_not_enable_warnings() {
    let inst = Spec::new("calls")
        .logging(false)
        .instantiate()
        .expect("instance");
    assert_eq!(inst.set_debug_logging(true, &["logCalls"]), OK);
    inst.clear_log();
    assert_eq!(inst.set(VR_K, -1.0), WARNING);
    let log = inst.log();
    assert!(
        log.iter().all(|e| e.category == "logCalls"),
        "only logCalls was enabled: {log:#?}"
    );
}

#[test]
fn logging_off_silences_warnings_but_not_errors() {
    let off_at_instantiation = Spec::new("quiet")
        .logging(false)
        .instantiate()
        .expect("instance");
    let off_later = Inst::new("quieted");
    assert_eq!(off_later.set_debug_logging(false, &[]), OK);
    for inst in [off_at_instantiation, off_later] {
        inst.clear_log();
        assert_eq!(inst.set(VR_K, -3.0), WARNING);
        assert!(
            inst.log().iter().all(|e| e.category == "logCalls"),
            "{:#?}",
            inst.log()
        );
        assert_eq!(inst.set(999, 1.0), ERROR);
        inst.assert_logged(ERROR, &["999"]);
        assert!(inst.log().iter().all(|e| e.status == ERROR));
    }
}

// ================================================================ unsupported functions

#[test]
fn unsupported_and_status_functions() {
    let fmu = fmu();
    let inst = Inst::new("status");
    inst.init(0.0, None);
    assert_eq!(inst.step(0.0, 0.01), OK);
    let mut st: Status = -1;
    let mut b: c_int = -1;
    // SAFETY: live instance; writable outputs.
    let (s1, s2) = unsafe {
        (
            (fmu.get_status)(inst.c, DO_STEP_STATUS, &mut st),
            (fmu.get_boolean_status)(inst.c, TERMINATED, &mut b),
        )
    };
    assert_eq!(s1, DISCARD, "nothing is ever pending");
    assert_eq!((s2, b), (OK, 0), "fmi2Terminated is false");
    // SAFETY: live instance.
    assert_eq!(unsafe { (fmu.cancel_step)(inst.c) }, ERROR);
    inst.assert_logged(ERROR, &["fmi2CancelStep"]);
}

// ================================================================ Vehicle

#[test]
fn the_vehicle_continues_through_fmu_states_and_a_new_speed_and_discards_on_derailment() {
    use railuq::models::vehicle::{self, VR_R, VR_SPEED, VR_V, VR_Y0_W3, VR_Y_W3};
    let guid = railuq::fmi2::xml::guid(&vehicle::INFO);
    let car = Spec::new("vehicle")
        .guid(Some(&guid))
        .instantiate()
        .unwrap_or_else(|log| panic!("Vehicle: {log:#?}"));
    assert_eq!(car.set(VR_V, 60.0), OK);
    car.init(0.0, None);
    let h = 0.01;
    let run = |n: usize| -> Vec<u64> {
        (0..n)
            .map(|_| {
                let now = {
                    let mut v = 0.0;
                    // SAFETY: live instance, writable value.
                    let s =
                        unsafe { (car.fmu.get_real_status)(car.c, LAST_SUCCESSFUL_TIME, &mut v) };
                    assert_eq!(s, OK);
                    v
                };
                assert_eq!(car.step(now, h), OK, "{:#?}", car.log());
                car.get(VR_Y_W3).to_bits()
            })
            .collect()
    };
    run(20);
    let mut s: FmuState = null_mut();
    assert_eq!(car.get_state(&mut s), OK);
    let first = run(10);
    assert_eq!(car.set_state(s), OK);
    assert_eq!(
        run(10),
        first,
        "the run from an FMU state repeats bit for bit"
    );
    // The speed is tunable: a new one between steps, a fixed parameter is refused.
    assert_eq!(car.set(VR_V, 55.0), OK);
    run(1);
    assert_eq!(car.get(VR_SPEED), 55.0);
    assert_eq!(car.set(VR_R, 1000.0), ERROR);
    assert_eq!(car.free_state(&mut s), OK);

    // A curve far too tight for the speed: the car derails, fmi2DoStep discards and the
    // simulation ends where the last step ended.
    let car = Spec::new("derail")
        .guid(Some(&guid))
        .instantiate()
        .unwrap_or_else(|log| panic!("Vehicle: {log:#?}"));
    for (vr, v) in [(VR_V, 45.0), (VR_R, 300.0), (VR_Y0_W3, 0.0)] {
        assert_eq!(car.set(vr, v), OK);
    }
    car.init(0.0, None);
    let mut t = 0.0;
    let status = loop {
        let s = car.step(t, h);
        if s != OK || t > 5.0 {
            break s;
        }
        t += h;
    };
    assert_eq!(status, DISCARD, "{:#?}", car.log());
    car.assert_logged(DISCARD, &["fmi2DoStep", "derailment: wheelset"]);
    let (mut terminated, mut last) = (0, -1.0);
    // SAFETY: live instance, writable values.
    let (s1, s2) = unsafe {
        (
            (car.fmu.get_boolean_status)(car.c, TERMINATED, &mut terminated),
            (car.fmu.get_real_status)(car.c, LAST_SUCCESSFUL_TIME, &mut last),
        )
    };
    assert_eq!((s1, terminated), (OK, 1));
    assert_eq!(s2, OK);
    assert!((last - t).abs() < 1e-9, "{last} vs {t}");
}
