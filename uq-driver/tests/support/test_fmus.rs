//! The C test FMUs of `uq-driver/tests/fmus/` (Functions, Features, Once; see the README there),
//! built for the Rust integration tests:
//!
//! ```ignore
//! let Some(fmu) = test_fmus::test_fmu("Functions") else { return }; // printed SKIPPED
//! ```
//!
//! Each folder of `tests/fmus/` with a `modelDescription.xml` is one FMU: its `*.c` files and
//! `common/*.c` are compiled with `$CC` (default `cc`) against the FMI 2.0 headers that fmpy ships
//! (`$FMI2_HEADERS`, else `../.venv/lib/python3*/site-packages/fmpy/c-code`), and packed with the
//! zip crate as `<CARGO_TARGET_TMPDIR>/test-fmus/<modelName>.fmu`
//! (`binaries/linux64/<modelIdentifier>.so`, `resources/`), the same way as
//! `tests/fmus/build.py` does for pytest. Built once per test process; files are written under a
//! private name and renamed, so concurrent test processes never see a partial file.
//!
//! Without a compiler or headers, `test_fmu` prints why and returns `None`, unless `CI` is set:
//! then it panics.

use std::collections::BTreeMap;
use std::fs;
use std::io::{Cursor, Write};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

use zip::write::SimpleFileOptions;

const MANIFEST_DIR: &str = env!("CARGO_MANIFEST_DIR");

/// The flags of `tests/fmus/build.py`.
const CFLAGS: &[&str] = &[
    "-std=c99",
    "-Wall",
    "-Wextra",
    "-pedantic",
    "-O2",
    "-shared",
    "-fPIC",
    "-fvisibility=hidden",
];

/// The folder of the C sources.
pub fn sources_dir() -> PathBuf {
    Path::new(MANIFEST_DIR).join("tests/fmus")
}

/// The packed test FMU named `model_name` ("Functions", "Features"), or `None` (with a printed
/// reason) when it cannot be built outside CI. Panics for a name that has no folder.
pub fn test_fmu(model_name: &str) -> Option<PathBuf> {
    let built = built()?;
    match built.get(model_name) {
        Some(path) => Some(path.clone()),
        None => panic!(
            "no test FMU named {model_name} in {} (have: {:?})",
            sources_dir().display(),
            built.keys().collect::<Vec<_>>()
        ),
    }
}

/// [`test_fmu`] and a new temporary folder for the test's files.
pub fn test_fmu_and_dir(model_name: &str) -> Option<(PathBuf, tempfile::TempDir)> {
    Some((test_fmu(model_name)?, tempfile::tempdir().unwrap()))
}

/// A new temporary folder for a test of the test FMUs, or `None` when they cannot be built
/// (as for [`built`]).
pub fn dir_if_built() -> Option<tempfile::TempDir> {
    built()?;
    Some(tempfile::tempdir().unwrap())
}

/// Every test FMU by model name, or `None` as for [`test_fmu`].
pub fn built() -> Option<&'static BTreeMap<String, PathBuf>> {
    static BUILT: OnceLock<Result<BTreeMap<String, PathBuf>, String>> = OnceLock::new();
    available("C test FMUs", BUILT.get_or_init(build_all))
}

/// What was built (`what`, for the messages), or `None` with the reason printed when it could
/// not be built outside CI; under CI (`CI` set) that is a failure.
pub fn available<T>(what: &str, built: &'static Result<T, String>) -> Option<&'static T> {
    match built {
        Ok(built) => Some(built),
        Err(reason) if std::env::var_os("CI").is_some() => {
            panic!("the {what} could not be built, and CI requires them: {reason}")
        }
        Err(reason) => {
            eprintln!("SKIPPED ({what} unavailable): {reason}");
            None
        }
    }
}

/// The folder with `fmi2Functions.h`.
pub fn find_headers() -> Result<PathBuf, String> {
    if let Some(dir) = std::env::var_os("FMI2_HEADERS") {
        let dir = PathBuf::from(dir);
        if dir.join("fmi2Functions.h").is_file() {
            return Ok(dir);
        }
        panic!("FMI2_HEADERS={} has no fmi2Functions.h", dir.display());
    }
    let venv_lib = Path::new(MANIFEST_DIR).join("../.venv/lib");
    let mut candidates: Vec<PathBuf> = fs::read_dir(&venv_lib)
        .map(|entries| {
            entries
                .filter_map(Result::ok)
                .filter(|e| e.file_name().to_string_lossy().starts_with("python3"))
                .map(|e| e.path().join("site-packages/fmpy/c-code"))
                .collect()
        })
        .unwrap_or_default();
    candidates.sort();
    candidates
        .into_iter()
        .find(|dir| dir.join("fmi2Functions.h").is_file())
        .ok_or_else(|| {
            format!(
                "no FMI 2.0 headers: set FMI2_HEADERS or install fmpy in {}",
                Path::new(MANIFEST_DIR).join("../.venv").display()
            )
        })
}

fn build_all() -> Result<BTreeMap<String, PathBuf>, String> {
    let headers = find_headers()?;
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("test-fmus");
    fs::create_dir_all(&out).map_err(|e| format!("{}: {e}", out.display()))?;
    let mut built = BTreeMap::new();
    for folder in fmu_folders()? {
        let xml = read(&folder.join("modelDescription.xml"))?;
        let xml = String::from_utf8(xml).map_err(|e| format!("{}: {e}", folder.display()))?;
        let name = attribute(&xml, "modelName")
            .ok_or_else(|| format!("{}: no modelName", folder.display()))?;
        let identifier = attribute(&xml, "modelIdentifier")
            .ok_or_else(|| format!("{}: no modelIdentifier", folder.display()))?;
        let binary = out.join(format!("{identifier}.so.{}", std::process::id()));
        compile(&folder, &headers, &binary)?;
        let fmu = out.join(format!("{name}.fmu"));
        let packed = pack(&folder, &identifier, &binary, &fmu);
        let _ = fs::remove_file(&binary);
        packed?;
        built.insert(name, fmu);
    }
    if built.is_empty() {
        return Err(format!("no test FMU in {}", sources_dir().display()));
    }
    Ok(built)
}

fn read(path: &Path) -> Result<Vec<u8>, String> {
    fs::read(path).map_err(|e| format!("{}: {e}", path.display()))
}

/// The folders of `tests/fmus/` that hold a `modelDescription.xml`, sorted.
fn fmu_folders() -> Result<Vec<PathBuf>, String> {
    let dir = sources_dir();
    let entries = fs::read_dir(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let mut folders: Vec<PathBuf> = entries
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| p.join("modelDescription.xml").is_file())
        .collect();
    folders.sort();
    Ok(folders)
}

/// The value of the first `key="..."` attribute in our own model descriptions.
fn attribute(xml: &str, key: &str) -> Option<String> {
    let pattern = format!(" {key}=\"");
    let pos = xml.find(&pattern)?;
    let rest = &xml[pos + pattern.len()..];
    Some(rest[..rest.find('"')?].to_string())
}

/// The `*.c` files of `dir`, sorted.
fn c_files(dir: &Path) -> Result<Vec<PathBuf>, String> {
    let entries = fs::read_dir(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let mut files: Vec<PathBuf> = entries
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "c"))
        .collect();
    files.sort();
    Ok(files)
}

fn compile(folder: &Path, headers: &Path, out: &Path) -> Result<(), String> {
    let common = sources_dir().join("common");
    let compiler = std::env::var("CC").unwrap_or_else(|_| "cc".to_string());
    let mut cmd = Command::new(&compiler);
    cmd.args(CFLAGS)
        .arg("-I")
        .arg(headers)
        .arg("-I")
        .arg(&common)
        .args(c_files(&common)?)
        .args(c_files(folder)?)
        .arg("-o")
        .arg(out)
        .arg("-lm");
    let output = cmd
        .output()
        .map_err(|e| format!("cannot run the C compiler '{compiler}': {e}"))?;
    let diagnostics = String::from_utf8_lossy(&output.stderr);
    if !output.status.success() {
        return Err(format!(
            "compiling {} failed:\n{diagnostics}",
            folder.display()
        ));
    }
    if !diagnostics.is_empty() {
        eprintln!("warnings compiling {}:\n{diagnostics}", folder.display());
    }
    Ok(())
}

/// Every file under `dir` with its path relative to `dir` ('/'-separated), sorted.
fn files_under(dir: &Path, prefix: &str, out: &mut Vec<(String, PathBuf)>) -> Result<(), String> {
    let entries = fs::read_dir(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let mut paths: Vec<PathBuf> = entries.filter_map(Result::ok).map(|e| e.path()).collect();
    paths.sort();
    for path in paths {
        let name = format!("{prefix}{}", path.file_name().unwrap().to_string_lossy());
        if path.is_dir() {
            files_under(&path, &format!("{name}/"), out)?;
        } else if path.is_file() {
            out.push((name, path));
        }
    }
    Ok(())
}

/// Writes the .fmu: deflate, forward slashes, files only; under a private name, then renamed.
fn pack(folder: &Path, identifier: &str, binary: &Path, fmu: &Path) -> Result<(), String> {
    let mut entries = vec![
        (
            "modelDescription.xml".to_string(),
            folder.join("modelDescription.xml"),
        ),
        (
            format!("binaries/linux64/{identifier}.so"),
            binary.to_path_buf(),
        ),
    ];
    let resources = folder.join("resources");
    if resources.is_dir() {
        files_under(&resources, "resources/", &mut entries)?;
    }
    let options = SimpleFileOptions::default().compression_method(zip::CompressionMethod::Deflated);
    let mut w = zip::ZipWriter::new(Cursor::new(Vec::new()));
    for (name, path) in &entries {
        w.start_file(name.as_str(), options)
            .map_err(|e| format!("{name}: {e}"))?;
        w.write_all(&read(path)?)
            .map_err(|e| format!("{name}: {e}"))?;
    }
    let bytes = w.finish().map_err(|e| e.to_string())?.into_inner();
    let partial = fmu.with_extension(format!("fmu.{}", std::process::id()));
    fs::write(&partial, bytes).map_err(|e| format!("{}: {e}", partial.display()))?;
    fs::rename(&partial, fmu).map_err(|e| format!("{}: {e}", fmu.display()))
}
