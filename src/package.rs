//! Writes `.fmu` archives: `modelDescription.xml`, `binaries/<platform>/<id>.so`,
//! `documentation/index.html`; zipped with deflate, forward slashes, no links.

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

use crate::fmi2::xml::{documentation, model_description, XmlError};
use crate::models::{registry, ModelInfo};

/// Packaging failures.
#[derive(Debug, thiserror::Error)]
pub enum PackageError {
    /// File system error on a path.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// Zip writer error.
    #[error("{path}: {source}")]
    Zip {
        /// The archive.
        path: PathBuf,
        /// The cause.
        source: zip::result::ZipError,
    },
    /// The variable table is inconsistent.
    #[error(transparent)]
    Xml(#[from] XmlError),
    /// No model of that name.
    #[error("no model named '{0}'")]
    UnknownModel(String),
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> PackageError + '_ {
    move |source| PackageError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// The FMI platform folder of this build, e.g. `linux64`.
pub fn platform_folder() -> &'static str {
    if cfg!(all(target_os = "linux", target_pointer_width = "64")) {
        "linux64"
    } else if cfg!(all(target_os = "windows", target_pointer_width = "64")) {
        "win64"
    } else if cfg!(target_os = "macos") {
        "darwin64"
    } else {
        "linux32"
    }
}

/// Shared-library file extension of this platform.
pub fn library_extension() -> &'static str {
    if cfg!(target_os = "windows") {
        "dll"
    } else if cfg!(target_os = "macos") {
        "dylib"
    } else {
        "so"
    }
}

/// Writes `<dir>/<Model>.xml` for every model.
pub fn write_descriptions(dir: &Path) -> Result<Vec<PathBuf>, PackageError> {
    fs::create_dir_all(dir).map_err(io(dir))?;
    let mut written = Vec::new();
    for e in registry() {
        let path = dir.join(format!("{}.xml", e.info.name));
        fs::write(&path, model_description(e.info)?).map_err(io(&path))?;
        written.push(path);
    }
    Ok(written)
}

/// Finds a model by name.
pub fn model_info(name: &str) -> Result<&'static ModelInfo, PackageError> {
    registry()
        .iter()
        .map(|e| e.info)
        .find(|i| i.name == name)
        .ok_or_else(|| PackageError::UnknownModel(name.to_owned()))
}

/// Writes `<out_dir>/<Model>.fmu` from the cdylib at `library`.
pub fn package(info: &ModelInfo, library: &Path, out_dir: &Path) -> Result<PathBuf, PackageError> {
    fs::create_dir_all(out_dir).map_err(io(out_dir))?;
    let lib_bytes = fs::read(library).map_err(io(library))?;
    let path = out_dir.join(format!("{}.fmu", info.name));
    let tmp = out_dir.join(format!(".{}.fmu.tmp", info.name));
    let file = fs::File::create(&tmp).map_err(io(&tmp))?;
    let zerr = |source| PackageError::Zip {
        path: path.clone(),
        source,
    };
    let mut zip = zip::ZipWriter::new(file);
    let opts = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated)
        .unix_permissions(0o644);
    let entries: [(String, Vec<u8>); 3] = [
        (
            "modelDescription.xml".into(),
            model_description(info)?.into_bytes(),
        ),
        (
            format!(
                "binaries/{}/{}.{}",
                platform_folder(),
                info.name,
                library_extension()
            ),
            lib_bytes,
        ),
        (
            "documentation/index.html".into(),
            documentation(info).into_bytes(),
        ),
    ];
    for (name, data) in entries {
        zip.start_file(name, opts).map_err(zerr)?;
        zip.write_all(&data).map_err(io(&path))?;
    }
    zip.finish().map_err(zerr)?;
    fs::rename(&tmp, &path).map_err(io(&path))?;
    Ok(path)
}
