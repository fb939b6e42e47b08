//! The FMU's shared library: loading it and resolving the FMI 2.0 Co-Simulation functions.
//!
//! Every function a Co-Simulation FMU must export is resolved once, at load time, into a typed
//! function pointer; a binary that lacks one is refused with the name of the missing function.
//! The pointers stay valid as long as the [`FmuLibrary`] (which owns the `Library`) is alive;
//! instances hold it in an `Arc`, so the library is unloaded after the last instance is freed.

use std::ffi::{c_char, c_int, c_uint, c_void, CStr};
use std::path::{Path, PathBuf};

use libloading::Library;

use super::error::FmuError;
use super::logger::CallbackFunctions;

/// `fmi2Component`.
pub(crate) type Component = *mut c_void;
/// `fmi2FMUstate`.
pub(crate) type StatePtr = *mut c_void;
/// `fmi2Status` as returned by the C functions.
pub(crate) type RawStatus = c_int;
/// `fmi2ValueReference`.
pub(crate) type Vr = c_uint;

/// `fmi2CoSimulation`, the `fmi2Type` passed to `fmi2Instantiate`.
pub(crate) const FMI2_CO_SIMULATION: c_int = 1;

/// The FMI 2.0 functions used for Co-Simulation, as C function pointers.
pub(crate) struct Functions {
    pub get_types_platform: unsafe extern "C" fn() -> *const c_char,
    pub get_version: unsafe extern "C" fn() -> *const c_char,
    pub set_debug_logging:
        unsafe extern "C" fn(Component, c_int, usize, *const *const c_char) -> RawStatus,
    pub instantiate: unsafe extern "C" fn(
        *const c_char,
        c_int,
        *const c_char,
        *const c_char,
        *const CallbackFunctions,
        c_int,
        c_int,
    ) -> Component,
    pub free_instance: unsafe extern "C" fn(Component),
    pub setup_experiment: unsafe extern "C" fn(Component, c_int, f64, f64, c_int, f64) -> RawStatus,
    pub enter_initialization_mode: unsafe extern "C" fn(Component) -> RawStatus,
    pub exit_initialization_mode: unsafe extern "C" fn(Component) -> RawStatus,
    pub terminate: unsafe extern "C" fn(Component) -> RawStatus,
    pub reset: unsafe extern "C" fn(Component) -> RawStatus,
    pub get_real: unsafe extern "C" fn(Component, *const Vr, usize, *mut f64) -> RawStatus,
    pub get_integer: unsafe extern "C" fn(Component, *const Vr, usize, *mut c_int) -> RawStatus,
    pub get_boolean: unsafe extern "C" fn(Component, *const Vr, usize, *mut c_int) -> RawStatus,
    pub get_string:
        unsafe extern "C" fn(Component, *const Vr, usize, *mut *const c_char) -> RawStatus,
    pub set_real: unsafe extern "C" fn(Component, *const Vr, usize, *const f64) -> RawStatus,
    pub set_integer: unsafe extern "C" fn(Component, *const Vr, usize, *const c_int) -> RawStatus,
    pub set_boolean: unsafe extern "C" fn(Component, *const Vr, usize, *const c_int) -> RawStatus,
    pub set_string:
        unsafe extern "C" fn(Component, *const Vr, usize, *const *const c_char) -> RawStatus,
    pub get_fmu_state: unsafe extern "C" fn(Component, *mut StatePtr) -> RawStatus,
    pub set_fmu_state: unsafe extern "C" fn(Component, StatePtr) -> RawStatus,
    pub free_fmu_state: unsafe extern "C" fn(Component, *mut StatePtr) -> RawStatus,
    pub serialized_fmu_state_size:
        unsafe extern "C" fn(Component, StatePtr, *mut usize) -> RawStatus,
    pub serialize_fmu_state:
        unsafe extern "C" fn(Component, StatePtr, *mut c_char, usize) -> RawStatus,
    pub deserialize_fmu_state:
        unsafe extern "C" fn(Component, *const c_char, usize, *mut StatePtr) -> RawStatus,
    pub get_directional_derivative: unsafe extern "C" fn(
        Component,
        *const Vr,
        usize,
        *const Vr,
        usize,
        *const f64,
        *mut f64,
    ) -> RawStatus,
    pub set_real_input_derivatives:
        unsafe extern "C" fn(Component, *const Vr, usize, *const c_int, *const f64) -> RawStatus,
    pub get_real_output_derivatives:
        unsafe extern "C" fn(Component, *const Vr, usize, *const c_int, *mut f64) -> RawStatus,
    pub do_step: unsafe extern "C" fn(Component, f64, f64, c_int) -> RawStatus,
    pub cancel_step: unsafe extern "C" fn(Component) -> RawStatus,
    pub get_status: unsafe extern "C" fn(Component, c_int, *mut RawStatus) -> RawStatus,
    pub get_real_status: unsafe extern "C" fn(Component, c_int, *mut f64) -> RawStatus,
    pub get_integer_status: unsafe extern "C" fn(Component, c_int, *mut c_int) -> RawStatus,
    pub get_boolean_status: unsafe extern "C" fn(Component, c_int, *mut c_int) -> RawStatus,
    pub get_string_status: unsafe extern "C" fn(Component, c_int, *mut *const c_char) -> RawStatus,
}

/// A loaded FMU shared library with all FMI 2.0 Co-Simulation functions resolved.
pub struct FmuLibrary {
    path: PathBuf,
    version: String,
    types_platform: String,
    pub(crate) api: Functions,
    // Declared last: dropped (unloaded) after nothing else here needs it.
    _library: Library,
}

impl std::fmt::Debug for FmuLibrary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FmuLibrary")
            .field("path", &self.path)
            .field("version", &self.version)
            .finish_non_exhaustive()
    }
}

/// The FMI 2.0 platform folder and library extension of the host, e.g. `("linux64", "so")`.
pub fn platform() -> Result<(&'static str, &'static str), FmuError> {
    let folder = if cfg!(all(target_os = "linux", target_arch = "x86_64")) {
        Some("linux64")
    } else if cfg!(all(target_os = "linux", target_arch = "x86")) {
        Some("linux32")
    } else if cfg!(all(target_os = "windows", target_arch = "x86_64")) {
        Some("win64")
    } else if cfg!(all(target_os = "windows", target_arch = "x86")) {
        Some("win32")
    } else if cfg!(all(target_os = "macos", target_arch = "x86_64")) {
        Some("darwin64")
    } else {
        None
    };
    let extension = if cfg!(target_os = "windows") {
        "dll"
    } else if cfg!(target_os = "macos") {
        "dylib"
    } else {
        "so"
    };
    folder
        .map(|f| (f, extension))
        .ok_or(FmuError::UnsupportedPlatform {
            os: std::env::consts::OS,
            arch: std::env::consts::ARCH,
        })
}

/// The binary's path inside an FMU, e.g. `binaries/linux64/Wheel.so`.
pub fn binary_path_in_fmu(model_identifier: &str) -> Result<String, FmuError> {
    let (folder, extension) = platform()?;
    Ok(format!("binaries/{folder}/{model_identifier}.{extension}"))
}

/// Resolves `name` in `lib` as a function pointer of the type the context expects.
macro_rules! resolve {
    ($lib:expr, $path:expr, $name:literal) => {{
        // SAFETY: the symbol is an FMI 2.0 function, whose C signature is fixed by the standard
        // and matches the field type it is assigned to; the pointer is used only while the
        // library is loaded (the library is stored next to it in `FmuLibrary`).
        let symbol = unsafe { $lib.get(concat!($name, "\0").as_bytes()) };
        match symbol {
            Ok(symbol) => *symbol,
            Err(_) => {
                return Err(FmuError::MissingSymbol {
                    path: $path.to_path_buf(),
                    symbol: $name,
                })
            }
        }
    }};
}

/// The dynamic loader's `reason`, with a hint where it names a symbol of the Python runtime:
/// FMUs with embedded Python (e.g. made with pythonfmu) may expect the host to provide it.
fn with_load_hint(reason: String) -> String {
    let python = reason
        .split_once("undefined symbol: ")
        .is_some_and(|(_, symbol)| symbol.starts_with("_Py") || symbol.starts_with("Py"));
    if !python {
        return reason;
    }
    format!(
        "{reason} (the FMU's library needs the Python runtime, which it does not link itself: an \
         FMU with embedded Python, e.g. made with pythonfmu. Start uq-driver with the libpython it \
         was built for preloaded, e.g. LD_PRELOAD=/usr/lib/x86_64-linux-gnu/libpython3.11.so.1.0, \
         and PYTHONHOME/PYTHONPATH pointing at that Python and the modules the FMU imports)"
    )
}

impl FmuLibrary {
    /// Loads the shared library at `path`, resolves the FMI 2.0 Co-Simulation functions and
    /// checks that `fmi2GetVersion()` is `"2.0"` and `fmi2GetTypesPlatform()` is `"default"`.
    pub fn load(path: &Path) -> Result<FmuLibrary, FmuError> {
        if !path.is_file() {
            return Err(FmuError::Load {
                path: path.to_path_buf(),
                reason: "no such file".to_string(),
            });
        }
        let library = open_library(path).map_err(|e| FmuError::Load {
            path: path.to_path_buf(),
            reason: with_load_hint(e.to_string()),
        })?;
        let api = Functions {
            get_types_platform: resolve!(library, path, "fmi2GetTypesPlatform"),
            get_version: resolve!(library, path, "fmi2GetVersion"),
            set_debug_logging: resolve!(library, path, "fmi2SetDebugLogging"),
            instantiate: resolve!(library, path, "fmi2Instantiate"),
            free_instance: resolve!(library, path, "fmi2FreeInstance"),
            setup_experiment: resolve!(library, path, "fmi2SetupExperiment"),
            enter_initialization_mode: resolve!(library, path, "fmi2EnterInitializationMode"),
            exit_initialization_mode: resolve!(library, path, "fmi2ExitInitializationMode"),
            terminate: resolve!(library, path, "fmi2Terminate"),
            reset: resolve!(library, path, "fmi2Reset"),
            get_real: resolve!(library, path, "fmi2GetReal"),
            get_integer: resolve!(library, path, "fmi2GetInteger"),
            get_boolean: resolve!(library, path, "fmi2GetBoolean"),
            get_string: resolve!(library, path, "fmi2GetString"),
            set_real: resolve!(library, path, "fmi2SetReal"),
            set_integer: resolve!(library, path, "fmi2SetInteger"),
            set_boolean: resolve!(library, path, "fmi2SetBoolean"),
            set_string: resolve!(library, path, "fmi2SetString"),
            get_fmu_state: resolve!(library, path, "fmi2GetFMUstate"),
            set_fmu_state: resolve!(library, path, "fmi2SetFMUstate"),
            free_fmu_state: resolve!(library, path, "fmi2FreeFMUstate"),
            serialized_fmu_state_size: resolve!(library, path, "fmi2SerializedFMUstateSize"),
            serialize_fmu_state: resolve!(library, path, "fmi2SerializeFMUstate"),
            deserialize_fmu_state: resolve!(library, path, "fmi2DeSerializeFMUstate"),
            get_directional_derivative: resolve!(library, path, "fmi2GetDirectionalDerivative"),
            set_real_input_derivatives: resolve!(library, path, "fmi2SetRealInputDerivatives"),
            get_real_output_derivatives: resolve!(library, path, "fmi2GetRealOutputDerivatives"),
            do_step: resolve!(library, path, "fmi2DoStep"),
            cancel_step: resolve!(library, path, "fmi2CancelStep"),
            get_status: resolve!(library, path, "fmi2GetStatus"),
            get_real_status: resolve!(library, path, "fmi2GetRealStatus"),
            get_integer_status: resolve!(library, path, "fmi2GetIntegerStatus"),
            get_boolean_status: resolve!(library, path, "fmi2GetBooleanStatus"),
            get_string_status: resolve!(library, path, "fmi2GetStringStatus"),
        };

        // SAFETY: fmi2GetVersion takes no argument and returns a static C string (or, from a
        // broken FMU, null, which `c_string` handles).
        let version = unsafe { c_string((api.get_version)()) };
        // SAFETY: as above, for fmi2GetTypesPlatform.
        let types_platform = unsafe { c_string((api.get_types_platform)()) };
        expect_string(path, "fmi2GetVersion", version.as_deref(), "2.0")?;
        expect_string(
            path,
            "fmi2GetTypesPlatform",
            types_platform.as_deref(),
            "default",
        )?;
        Ok(FmuLibrary {
            path: path.to_path_buf(),
            version: version.unwrap_or_default(),
            types_platform: types_platform.unwrap_or_default(),
            api,
            _library: library,
        })
    }

    /// The path of the loaded shared library.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// What `fmi2GetVersion()` returned (always `"2.0"`).
    pub fn version(&self) -> &str {
        &self.version
    }

    /// What `fmi2GetTypesPlatform()` returned (always `"default"`).
    pub fn types_platform(&self) -> &str {
        &self.types_platform
    }
}

/// Refuses a binary whose `function()` did not return `expected`.
fn expect_string(
    path: &Path,
    function: &str,
    got: Option<&str>,
    expected: &str,
) -> Result<(), FmuError> {
    let reason = match got {
        Some(v) if v == expected => return Ok(()),
        Some(v) => format!("{function}() returned \"{v}\", expected \"{expected}\""),
        None => format!("{function}() returned null"),
    };
    Err(FmuError::IncompatibleBinary {
        path: path.to_path_buf(),
        reason,
    })
}

#[cfg(unix)]
fn open_library(path: &Path) -> Result<Library, libloading::Error> {
    use libloading::os::unix::{Library as UnixLibrary, RTLD_LOCAL, RTLD_NOW};
    // SAFETY: loading runs the library's initialisers. Running the FMU's code is the purpose of
    // an importer; RTLD_NOW makes unresolved dependencies fail here rather than mid-run, and
    // RTLD_LOCAL keeps its fmi2* symbols from clashing with other FMUs.
    let library = unsafe { UnixLibrary::open(Some(path), RTLD_NOW | RTLD_LOCAL) }?;
    Ok(library.into())
}

#[cfg(not(unix))]
fn open_library(path: &Path) -> Result<Library, libloading::Error> {
    // SAFETY: loading runs the library's initialisers; running the FMU's code is the purpose of
    // an importer.
    unsafe { Library::new(path) }
}

/// Copies a C string returned by the FMU, `None` if null.
///
/// # Safety
/// `ptr` must be null or point to a NUL-terminated string valid for the duration of the call.
pub(crate) unsafe fn c_string(ptr: *const c_char) -> Option<String> {
    if ptr.is_null() {
        return None;
    }
    // SAFETY: non-null, and NUL-terminated and valid per this function's contract.
    let s = unsafe { CStr::from_ptr(ptr) };
    Some(s.to_string_lossy().into_owned())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn binary_path_names_platform_folder() {
        let p = binary_path_in_fmu("Wheel").unwrap();
        if cfg!(all(target_os = "linux", target_arch = "x86_64")) {
            assert_eq!(p, "binaries/linux64/Wheel.so");
        }
    }

    #[test]
    fn missing_library_is_a_load_error() {
        let err = FmuLibrary::load(Path::new("/nonexistent/x.so")).unwrap_err();
        assert!(matches!(err, FmuError::Load { .. }), "{err}");
        assert!(err.to_string().starts_with("/nonexistent/x.so: "), "{err}");
    }

    #[test]
    fn an_fmu_needing_the_python_runtime_gets_a_hint_to_preload_it() {
        // A pythonfmu 0.7.0 FMU's library does not link libpython.
        let reason = "/tmp/x/Osc.so: undefined symbol: _Py_NoneStruct".to_owned();
        let hinted = with_load_hint(reason.clone());
        assert!(
            hinted.starts_with(&reason) && hinted.contains("LD_PRELOAD"),
            "{hinted}"
        );
        let other = "/tmp/x/A.so: undefined symbol: cblas_dgemm".to_owned();
        assert_eq!(with_load_hint(other.clone()), other);
    }
}
