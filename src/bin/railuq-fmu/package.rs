//! Writes `.fmu` archives: `modelDescription.xml`, `model.png`, one
//! `binaries/<platform>/<id>.<ext>` per shared library (stripped of symbols and debug info),
//! `documentation/index.html` and the licence under `documentation/licenses/`; zipped with
//! deflate, forward slashes, no links.

mod binary;
mod icon;

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

pub use binary::Platform;
pub use icon::model_png;

use railuq::fmi2::xml::{documentation, model_description, XmlError};
use railuq::models::{registry, ModelInfo};

/// The MIT licence text of the repository (`LICENSE-MIT`).
pub const LICENSE_MIT: &str = include_str!("../../../LICENSE-MIT");
/// The Apache 2.0 licence text of the repository (`LICENSE-APACHE`).
pub const LICENSE_APACHE: &str = include_str!("../../../LICENSE-APACHE");

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
    /// A file given as a shared library is not one of an FMI platform.
    #[error("{path}: {reason}")]
    NotALibrary {
        /// The file.
        path: PathBuf,
        /// What it is instead.
        reason: String,
    },
    /// Stripping a library failed.
    #[error("{path}: cannot strip symbols and debug info ({reason}); install binutils, set STRIP to a strip program, or package with --keep-debug")]
    Strip {
        /// The library.
        path: PathBuf,
        /// What each strip program said.
        reason: String,
    },
    /// Two libraries for one platform folder, or none at all.
    #[error("{0}")]
    Libraries(String),
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> PackageError + '_ {
    move |source| PackageError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// A shared library ready to be packaged.
#[derive(Clone, Debug)]
pub struct Library {
    /// Its FMI platform, read from its header.
    pub platform: Platform,
    /// The bytes that go into the FMU.
    pub bytes: Vec<u8>,
}

impl Library {
    /// Reads the library at `path` and finds its platform. With `strip`, symbols and debug info
    /// are removed first (a scratch copy is written in `scratch_dir` and deleted); without, the
    /// bytes are packaged as they are.
    pub fn load(path: &Path, strip: bool, scratch_dir: &Path) -> Result<Library, PackageError> {
        let not_lib = |reason| PackageError::NotALibrary {
            path: path.to_path_buf(),
            reason,
        };
        let bytes = fs::read(path).map_err(io(path))?;
        let platform = Platform::of_library(&bytes).map_err(not_lib)?;
        if !strip {
            return Ok(Library { platform, bytes });
        }
        fs::create_dir_all(scratch_dir).map_err(io(scratch_dir))?;
        let file_name = path.file_name().unwrap_or_default().to_string_lossy();
        let tmp = scratch_dir.join(format!(".{file_name}.stripped.tmp"));
        binary::strip(path, &tmp, platform).map_err(|reason| PackageError::Strip {
            path: path.to_path_buf(),
            reason,
        })?;
        let bytes = fs::read(&tmp).map_err(io(&tmp));
        let _ = fs::remove_file(&tmp);
        let bytes = bytes?;
        match Platform::of_library(&bytes) {
            Ok(p) if p == platform => Ok(Library { platform, bytes }),
            other => Err(not_lib(format!(
                "stripping changed the library's header ({other:?})"
            ))),
        }
    }
}

/// Writes `<dir>/<Model>.xml` for every model.
pub fn write_descriptions(dir: &Path) -> Result<Vec<PathBuf>, PackageError> {
    fs::create_dir_all(dir).map_err(io(dir))?;
    let mut written = Vec::new();
    for e in registry() {
        let path = dir.join(format!("{}.xml", e.info.name));
        out_file::write(&path, model_description(e.info)?.as_bytes()).map_err(io(&path))?;
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

/// `documentation/licenses/license.txt`: the entry point of the licence information.
fn license_notice(info: &ModelInfo) -> String {
    format!(
        "{name}.fmu is part of railuq {version}.\n\
         \n\
         Licensed under either of\n\
         \n\
         - the Apache License, Version 2.0 (LICENSE-APACHE.txt beside this file), or\n\
         - the MIT License (LICENSE-MIT.txt beside this file)\n\
         \n\
         at your option (SPDX: MIT OR Apache-2.0).\n\
         \n\
         The binaries under binaries/ also contain the Rust standard library and Rust crates\n\
         from crates.io, each under its own permissive licence (MIT, Apache-2.0 or both, for\n\
         most); `cargo tree -p railuq -e normal --format '{{p}} {{l}}'` lists them.\n",
        name = info.name,
        version = env!("CARGO_PKG_VERSION"),
    )
}

/// Every entry of the archive of model `info` with `libraries`, in archive order.
fn entries(
    info: &ModelInfo,
    libraries: &[Library],
) -> Result<Vec<(String, Vec<u8>)>, PackageError> {
    if libraries.is_empty() {
        return Err(PackageError::Libraries(
            "no shared library to package".into(),
        ));
    }
    let mut out = vec![
        (
            "modelDescription.xml".to_owned(),
            model_description(info)?.into_bytes(),
        ),
        ("model.png".to_owned(), model_png(info.name)),
    ];
    for (i, lib) in libraries.iter().enumerate() {
        if libraries[..i].iter().any(|l| l.platform == lib.platform) {
            return Err(PackageError::Libraries(format!(
                "two libraries for binaries/{}",
                lib.platform.folder()
            )));
        }
        let p = lib.platform;
        let name = format!("binaries/{}/{}.{}", p.folder(), info.name, p.extension());
        out.push((name, lib.bytes.clone()));
    }
    out.extend([
        (
            "documentation/index.html".to_owned(),
            documentation(info).into_bytes(),
        ),
        (
            "documentation/licenses/license.txt".to_owned(),
            license_notice(info).into_bytes(),
        ),
        (
            "documentation/licenses/LICENSE-APACHE.txt".to_owned(),
            LICENSE_APACHE.as_bytes().to_vec(),
        ),
        (
            "documentation/licenses/LICENSE-MIT.txt".to_owned(),
            LICENSE_MIT.as_bytes().to_vec(),
        ),
    ]);
    Ok(out)
}

/// Writes `<out_dir>/<Model>.fmu` with one binary per library (at most one per platform).
pub fn package(
    info: &ModelInfo,
    libraries: &[Library],
    out_dir: &Path,
) -> Result<PathBuf, PackageError> {
    let entries = entries(info, libraries)?;
    fs::create_dir_all(out_dir).map_err(io(out_dir))?;
    let path = out_dir.join(format!("{}.fmu", info.name));
    // Through a temporary file renamed over the name (a device or pipe is written into).
    let file = out_file::OutFile::create(&path, 1 << 16).map_err(io(&path))?;
    let zerr = |source| PackageError::Zip {
        path: path.clone(),
        source,
    };
    let mut zip = zip::ZipWriter::new(file);
    let deflated = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated)
        .unix_permissions(0o644);
    // The binaries are stored, not deflated (an FMU may use either method): an
    // importer then copies them out instead of inflating megabytes on every load (about
    // 10 ms per opening of the FMU), for an FMU about twice the size.
    let stored = deflated.compression_method(zip::CompressionMethod::Stored);
    for (name, data) in entries {
        let opts = if name.starts_with("binaries/") {
            stored
        } else {
            deflated
        };
        zip.start_file(name, opts).map_err(zerr)?;
        zip.write_all(&data).map_err(io(&path))?;
    }
    zip.finish().map_err(zerr)?.commit().map_err(io(&path))?;
    Ok(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fake(platform: Platform) -> Library {
        Library {
            platform,
            bytes: vec![1, 2, 3],
        }
    }

    #[test]
    fn archive_lists_every_binary_the_icon_and_the_licence() {
        let info = model_info("Wheel").unwrap();
        let libs = [fake(Platform::Linux64), fake(Platform::Win64)];
        let names: Vec<String> = entries(info, &libs)
            .unwrap()
            .into_iter()
            .map(|(n, _)| n)
            .collect();
        assert_eq!(
            names,
            [
                "modelDescription.xml",
                "model.png",
                "binaries/linux64/Wheel.so",
                "binaries/win64/Wheel.dll",
                "documentation/index.html",
                "documentation/licenses/license.txt",
                "documentation/licenses/LICENSE-APACHE.txt",
                "documentation/licenses/LICENSE-MIT.txt",
            ]
        );
    }

    #[test]
    fn two_libraries_for_one_platform_or_none_are_refused() {
        let info = model_info("Wheel").unwrap();
        let libs = [fake(Platform::Win64), fake(Platform::Win64)];
        let err = entries(info, &libs).unwrap_err().to_string();
        assert!(err.contains("two libraries for binaries/win64"), "{err}");
        assert!(entries(info, &[]).is_err());
    }

    #[test]
    fn licence_texts_are_the_repository_files() {
        assert!(LICENSE_MIT.starts_with("MIT License"));
        assert!(LICENSE_MIT.contains("Permission is hereby granted, free of charge"));
        assert!(LICENSE_APACHE.contains("Apache License"));
        assert!(LICENSE_APACHE.contains("Version 2.0, January 2004"));
        assert!(LICENSE_APACHE.contains("END OF TERMS AND CONDITIONS"));
        let notice = license_notice(model_info("Bogie").unwrap());
        assert!(notice.contains("MIT OR Apache-2.0") && notice.contains("Bogie.fmu"));
    }

    #[test]
    fn a_text_file_is_not_a_library() {
        let dir = std::env::temp_dir().join(format!("railuq-pkg-{}", std::process::id()));
        fs::create_dir_all(&dir).unwrap();
        let f = dir.join("not-a-lib.so");
        fs::write(&f, "hello").unwrap();
        let err = Library::load(&f, false, &dir).unwrap_err().to_string();
        assert!(err.contains("not a shared library"), "{err}");
        fs::remove_dir_all(&dir).unwrap();
    }
}
