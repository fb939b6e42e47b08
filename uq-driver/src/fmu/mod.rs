//! FMI 2.0 Co-Simulation import.
//!
//! [`Fmu::open`] extracts a `.fmu` archive safely ([`archive`]), parses its
//! `modelDescription.xml` ([`ModelDescription`]) and loads its binary for this platform
//! ([`FmuLibrary`]), resolving every FMI 2.0 Co-Simulation function. [`Fmu::instantiate`] then
//! creates [`Instance`]s, one per worker thread, with a typed API whose errors carry the FMU's
//! log messages.
//!
//! ```no_run
//! # fn main() -> Result<(), uq_driver::fmu::FmuError> {
//! use uq_driver::fmu::Fmu;
//! // railuq's Wheel: a damped oscillator with parameters m, K, C (kg, N/m, N.s/m) and
//! // outputs q, v, a (m, m/s, m/s2). Variable names are case-sensitive.
//! let fmu = Fmu::open("target/fmu/Wheel.fmu".as_ref())?;
//! let mut inst = fmu.instantiate("w0", false)?;
//! inst.set_real_by_name("K", 150.0)?;
//! inst.setup_experiment(None, 0.0, Some(1.0))?;
//! inst.enter_initialization_mode()?;
//! inst.exit_initialization_mode()?;
//! let step = 0.01; // communication step (s)
//! for i in 0..100 {
//!     inst.do_step(i as f64 * step, step, true)?;
//! }
//! let q = inst.get_real_by_name("q")?; // displacement at t = 1 s (m)
//! inst.terminate()?;
//! println!("q(1 s) = {q} m");
//! # Ok(()) }
//! ```
//!
//! [`crate::study::run::simulate`] does all of this for one parameter point and a time grid.
//!
//! Every `Fmu::open` extracts and loads its own copy of the binary, and
//! [`Fmu::private_copy`] loads another copy of an opened FMU's binary, so an FMU that keeps
//! global state (`canBeInstantiatedOnlyOncePerProcess`) can still run in parallel with one
//! copy per worker.

pub mod archive;
mod binary;
pub mod cleanup;
pub mod description;
mod error;
mod instance;
mod logger;
mod value;

use std::fs;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize};
use std::sync::Arc;

pub use archive::ExtractLimits;
pub use binary::{binary_path_in_fmu, platform, FmuLibrary};
pub use description::{
    Causality, CoSimulation, DefaultExperiment, DescriptionError, Initial, ModelDescription,
    ScalarVariable, Unit, Variability, VariableKind, VariableNamingConvention,
};
pub use error::{FmuError, LogMessage, Status};
pub use instance::{FmuState, Instance, InstanceState, StatusKind};
pub use value::FixedValue;

/// An opened FMU: extracted, described and loaded, ready to instantiate.
///
/// Cloning is cheap and shares the extraction and the library; `Fmu` is `Send + Sync`, so one
/// `Fmu` can serve instances on many threads. The extracted folder is deleted and the library
/// unloaded when the last `Fmu` clone and the last [`Instance`] are gone.
#[derive(Clone, Debug)]
pub struct Fmu {
    inner: Arc<FmuInner>,
}

/// What instances share with their `Fmu`.
#[derive(Debug)]
pub(crate) struct FmuInner {
    /// The `.fmu` file (or folder) as given by the user.
    pub(crate) path: PathBuf,
    pub(crate) description: ModelDescription,
    /// Declared before `extracted`: the library is unloaded before its folder is deleted.
    pub(crate) library: FmuLibrary,
    /// `file:///...resources/` of the extracted folder.
    pub(crate) resource_uri: String,
    root: PathBuf,
    binary: PathBuf,
    pub(crate) live_instances: AtomicUsize,
    /// Set when a call returned fmi2Fatal: no function of this FMU may be called again.
    pub(crate) fatal: AtomicBool,
    _extracted: Option<Extracted>,
    /// For a [`Fmu::private_copy`]: the FMU it copies (its extraction holds the resources).
    _parent: Option<Arc<FmuInner>>,
}

/// A temporary extraction folder, known to [`cleanup`] until it is removed.
#[derive(Debug)]
struct Extracted(Option<tempfile::TempDir>);

impl Extracted {
    fn path(&self) -> &Path {
        self.0.as_ref().expect("present until dropped").path()
    }
}

impl Drop for Extracted {
    fn drop(&mut self) {
        if let Some(dir) = self.0.take() {
            let path = dir.path().to_path_buf();
            // Removed first, forgotten after: a signal meanwhile still finds it registered.
            let _ = dir.close();
            cleanup::unregister(&path);
        }
    }
}

impl Fmu {
    /// Opens an FMU: a `.fmu` archive (extracted into a temporary folder, deleted on drop) or
    /// an already extracted FMU folder (used in place).
    pub fn open(path: &Path) -> Result<Fmu, FmuError> {
        let io = |source| FmuError::Io {
            path: path.to_path_buf(),
            source,
        };
        let metadata = fs::metadata(path).map_err(io)?;
        if metadata.is_dir() {
            return Self::load(path, path, None, None);
        }
        // Registered as it is created: a signal during a long extraction still removes it.
        let dir = cleanup::temp_dir("uq-fmu-").map_err(|source| FmuError::Io {
            path: std::env::temp_dir(),
            source,
        })?;
        let dir = Extracted(Some(dir));
        let archived_platforms = {
            let _filling = cleanup::filling();
            match binary::platform() {
                Ok((host, _)) => Some(archive::extract_for_host(path, dir.path(), host)?),
                // No binary folder is this host's: extract all, loading reports it.
                Err(_) => {
                    archive::extract(path, dir.path())?;
                    None
                }
            }
        };
        let root = dir.path().to_path_buf();
        Self::load(path, &root, Some(dir), archived_platforms)
    }

    /// Opens the FMU extracted in the folder `root` (used in place), naming it `shown` in
    /// messages and in [`Fmu::path`] (e.g. the `.fmu` another process extracted it from).
    pub fn open_extracted(root: &Path, shown: &Path) -> Result<Fmu, FmuError> {
        Self::load(shown, root, None, None)
    }

    /// Loads the FMU extracted in `root`; `path` is what the user gave; `archived_platforms`,
    /// the platform folders of its archive's binaries when not all were unpacked.
    fn load(
        path: &Path,
        root: &Path,
        extracted: Option<Extracted>,
        archived_platforms: Option<Vec<String>>,
    ) -> Result<Fmu, FmuError> {
        let io = |source| FmuError::Io {
            path: path.to_path_buf(),
            source,
        };
        let root = fs::canonicalize(root).map_err(io)?;

        let md_path = root.join("modelDescription.xml");
        if !md_path.is_file() {
            return Err(FmuError::MissingModelDescription {
                path: path.to_path_buf(),
            });
        }
        // The size first: an extracted folder is not bounded by the archive's limits.
        let limit = description::ParseLimits::DEFAULT_MAX_BYTES;
        let size = fs::metadata(&md_path).map_err(io)?.len();
        if size > limit as u64 {
            return Err(FmuError::from_description(
                path,
                DescriptionError::TooLarge {
                    size: usize::try_from(size).unwrap_or(usize::MAX),
                    limit,
                },
            ));
        }
        let xml = fs::read(&md_path).map_err(|source| FmuError::Io {
            path: md_path.clone(),
            source,
        })?;
        let description =
            ModelDescription::parse(&xml).map_err(|e| FmuError::from_description(path, e))?;

        let relative = binary_path_in_fmu(&description.co_simulation.model_identifier)?;
        let binary = root.join(&relative);
        if !binary.is_file() {
            return Err(FmuError::MissingBinary {
                path: path.to_path_buf(),
                expected: relative,
                available: archived_platforms.unwrap_or_else(|| platform_folders(&root)),
            });
        }
        // Name the binary by its place in the FMU, not in the temporary folder.
        let library = load_library(&binary, &path.join(&relative))?;

        let resource_uri = format!("{}/", file_uri(&root.join("resources")));
        Ok(Fmu {
            inner: Arc::new(FmuInner {
                path: path.to_path_buf(),
                description,
                library,
                resource_uri,
                root,
                binary,
                live_instances: AtomicUsize::new(0),
                fatal: AtomicBool::new(false),
                _extracted: extracted,
                _parent: None,
            }),
        })
    }

    /// Loads another copy of this FMU's binary, with globals of its own: the files of the
    /// binary's platform folder are copied into a new temporary folder (deleted on drop) and
    /// the copy is loaded from there. The copy shares the description and the resources, and
    /// counts its instances apart, so an FMU that declares
    /// `canBeInstantiatedOnlyOncePerProcess="true"` can have one live instance per copy.
    pub fn private_copy(&self) -> Result<Fmu, FmuError> {
        let inner = &self.inner;
        let dir = cleanup::temp_dir("uq-fmu-").map_err(|source| FmuError::Io {
            path: std::env::temp_dir(),
            source,
        })?;
        let dir = Extracted(Some(dir));
        let folder = inner.binary.parent().unwrap_or(&inner.root);
        let io = |path: &Path| {
            let path = path.to_path_buf();
            move |source| FmuError::Io { path, source }
        };
        {
            let _filling = cleanup::filling();
            for entry in fs::read_dir(folder).map_err(io(folder))? {
                let from = entry.map_err(io(folder))?.path();
                if fs::metadata(&from).map_err(io(&from))?.is_file() {
                    let name = from.file_name().expect("a folder entry has a name");
                    fs::copy(&from, dir.path().join(name)).map_err(io(&from))?;
                }
            }
        }
        let name = inner.binary.file_name().expect("the binary has a name");
        let binary = dir.path().join(name);
        let relative = binary_path_in_fmu(&inner.description.co_simulation.model_identifier)?;
        let library = load_library(&binary, &inner.path.join(relative))?;
        Ok(Fmu {
            inner: Arc::new(FmuInner {
                path: inner.path.clone(),
                description: inner.description.clone(),
                library,
                resource_uri: inner.resource_uri.clone(),
                root: inner.root.clone(),
                binary,
                live_instances: AtomicUsize::new(0),
                fatal: AtomicBool::new(false),
                _extracted: Some(dir),
                _parent: Some(Arc::clone(inner)),
            }),
        })
    }

    /// Whether a call returned fmi2Fatal: no function of this FMU may be called again (open it
    /// again, in another process, for a usable copy).
    pub fn is_unusable(&self) -> bool {
        self.inner.fatal.load(std::sync::atomic::Ordering::Acquire)
    }

    /// The parsed `modelDescription.xml`.
    pub fn description(&self) -> &ModelDescription {
        &self.inner.description
    }

    /// The path given to [`Fmu::open`].
    pub fn path(&self) -> &Path {
        &self.inner.path
    }

    /// The folder holding the extracted FMU.
    pub fn root(&self) -> &Path {
        &self.inner.root
    }

    /// The loaded shared library's path (inside [`Fmu::root`]).
    pub fn binary_path(&self) -> &Path {
        &self.inner.binary
    }

    /// The loaded library.
    pub fn library(&self) -> &FmuLibrary {
        &self.inner.library
    }

    /// The `fmuResourceLocation` passed to `fmi2Instantiate`: a percent-encoded `file:///` URI
    /// of the extracted `resources/` folder, ending with `/`.
    pub fn resource_uri(&self) -> &str {
        &self.inner.resource_uri
    }

    /// Creates a Co-Simulation instance (`fmi2Instantiate` with this FMU's GUID, not visible).
    /// `logging_on` asks the FMU for debug logging and echoes its messages to stderr; errors
    /// are logged and kept whatever it is.
    pub fn instantiate(&self, instance_name: &str, logging_on: bool) -> Result<Instance, FmuError> {
        Instance::new(
            Arc::clone(&self.inner),
            instance_name,
            logging_on,
            logging_on,
        )
    }

    /// As [`Fmu::instantiate`], with the echo of the FMU's messages to stderr chosen apart from
    /// `logging_on`: a study asks its FMU to log (`--fmu-logging`) but keeps the messages with
    /// the failing points (capped) instead of flooding the terminal.
    pub fn instantiate_with(
        &self,
        instance_name: &str,
        logging_on: bool,
        echo: bool,
    ) -> Result<Instance, FmuError> {
        Instance::new(Arc::clone(&self.inner), instance_name, logging_on, echo)
    }
}

/// Loads the library at `binary`, naming it `shown` (its place in the FMU) in errors.
fn load_library(binary: &Path, shown: &Path) -> Result<FmuLibrary, FmuError> {
    FmuLibrary::load(binary).map_err(|e| match e {
        FmuError::Load { reason, .. } => FmuError::Load {
            path: shown.to_path_buf(),
            reason,
        },
        FmuError::MissingSymbol { symbol, .. } => FmuError::MissingSymbol {
            path: shown.to_path_buf(),
            symbol,
        },
        FmuError::IncompatibleBinary { reason, .. } => FmuError::IncompatibleBinary {
            path: shown.to_path_buf(),
            reason,
        },
        other => other,
    })
}

/// The folders under `root/binaries`, for error messages.
fn platform_folders(root: &Path) -> Vec<String> {
    let mut names: Vec<String> = fs::read_dir(root.join("binaries"))
        .map(|entries| {
            entries
                .filter_map(Result::ok)
                .filter(|e| e.path().is_dir())
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .collect()
        })
        .unwrap_or_default();
    names.sort();
    names
}

/// A `file:///` URI for an absolute path, percent-encoding all but unreserved characters,
/// `/` and `:`.
pub fn file_uri(path: &Path) -> String {
    #[cfg(unix)]
    let bytes: Vec<u8> = {
        use std::os::unix::ffi::OsStrExt;
        path.as_os_str().as_bytes().to_vec()
    };
    #[cfg(windows)]
    let bytes: Vec<u8> = {
        let text = path.to_string_lossy().replace('\\', "/");
        let text = text.strip_prefix("//?/").unwrap_or(&text);
        format!("/{text}").into_bytes()
    };
    #[cfg(not(any(unix, windows)))]
    let bytes: Vec<u8> = path.to_string_lossy().as_bytes().to_vec();
    let mut uri = String::from("file://");
    for b in bytes {
        if b.is_ascii_alphanumeric() || b"-._~/:".contains(&b) {
            uri.push(char::from(b));
        } else {
            uri.push_str(&format!("%{b:02X}"));
        }
    }
    uri
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn file_uri_percent_encodes() {
        #[cfg(unix)]
        assert_eq!(
            file_uri(Path::new("/tmp/a b/ü%/resources")),
            "file:///tmp/a%20b/%C3%BC%25/resources"
        );
    }

    #[test]
    fn fmu_is_send_and_sync_and_instance_is_send() {
        fn send_sync<T: Send + Sync>() {}
        fn send<T: Send>() {}
        send_sync::<Fmu>();
        send::<Instance>();
        send::<FmuError>();
    }

    #[test]
    fn open_reports_missing_file() {
        let err = Fmu::open(Path::new("/nonexistent/M.fmu")).unwrap_err();
        assert!(matches!(err, FmuError::Io { .. }), "{err}");
        assert!(err.to_string().starts_with("/nonexistent/M.fmu: "), "{err}");
    }
}
