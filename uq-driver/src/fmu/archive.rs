//! Safe extraction of `.fmu` archives (zip files).
//!
//! An FMU is an untrusted zip archive. Extraction refuses every entry that could write outside
//! the target folder (`..` components, absolute paths, NUL bytes: [`zip::read::ZipFile::enclosed_name`]),
//! symbolic links and other non-regular files, duplicate names, and archives whose entry count or
//! total uncompressed size exceeds [`ExtractLimits`] (zip bombs). Sizes are checked on the bytes
//! actually decompressed, not only on the sizes the archive declares.

use std::fs::{self, File, OpenOptions};
use std::io::{self, Read, Write};
use std::path::Path;

use zip::result::ZipError;
use zip::ZipArchive;

use super::error::FmuError;

/// Unix file-type bits of an entry's mode (`S_IFMT`).
const S_IFMT: u32 = 0o170_000;
/// Regular file.
const S_IFREG: u32 = 0o100_000;
/// Directory.
const S_IFDIR: u32 = 0o040_000;
/// Symbolic link.
const S_IFLNK: u32 = 0o120_000;

/// Limits that protect extraction against zip bombs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ExtractLimits {
    /// Maximum total uncompressed size of all entries, in bytes.
    pub max_total_bytes: u64,
    /// Maximum number of entries (files and folders).
    pub max_entries: usize,
}

impl Default for ExtractLimits {
    /// 2 GiB in at most 100 000 entries.
    fn default() -> Self {
        ExtractLimits {
            max_total_bytes: 2 << 30,
            max_entries: 100_000,
        }
    }
}

/// Extracts the `.fmu` archive `archive` into the existing folder `dest`, with the default limits.
pub fn extract(archive: &Path, dest: &Path) -> Result<(), FmuError> {
    extract_with_limits(archive, dest, ExtractLimits::default())
}

/// Extracts `archive` into a new temporary folder, deleted when the returned handle drops.
pub fn extract_to_temp(archive: &Path) -> Result<tempfile::TempDir, FmuError> {
    let dir = tempfile::Builder::new()
        .prefix("uq-fmu-")
        .tempdir()
        .map_err(|source| FmuError::Io {
            path: std::env::temp_dir(),
            source,
        })?;
    extract(archive, dir.path())?;
    Ok(dir)
}

/// Extracts `archive` into the existing folder `dest`, refusing unsafe entries and archives that
/// exceed `limits`. On error, `dest` may hold part of the archive.
pub fn extract_with_limits(
    archive: &Path,
    dest: &Path,
    limits: ExtractLimits,
) -> Result<(), FmuError> {
    let io_err = |path: &Path| {
        let path = path.to_path_buf();
        move |source| FmuError::Io { path, source }
    };
    let file = File::open(archive).map_err(io_err(archive))?;
    let mut zip = ZipArchive::new(file).map_err(|e| match e {
        ZipError::Io(source) => FmuError::Io {
            path: archive.to_path_buf(),
            source,
        },
        other => FmuError::NotAZip {
            path: archive.to_path_buf(),
            reason: other.to_string(),
        },
    })?;
    if zip.len() > limits.max_entries {
        return Err(FmuError::ArchiveTooLarge {
            path: archive.to_path_buf(),
            reason: format!(
                "{} entries, more than the limit of {}",
                zip.len(),
                limits.max_entries
            ),
        });
    }

    let mut total: u64 = 0;
    for index in 0..zip.len() {
        let stored_name = zip.name_for_index(index).unwrap_or("<unnamed>").to_string();
        let mut entry = zip.by_index(index).map_err(|e| FmuError::Archive {
            path: archive.to_path_buf(),
            entry: stored_name,
            reason: e.to_string(),
        })?;
        let name = entry.name().to_string();
        let unsafe_entry = |reason: &str| FmuError::UnsafeEntry {
            path: archive.to_path_buf(),
            entry: name.clone(),
            reason: reason.to_string(),
        };

        let raw = entry.name_raw();
        if raw.first().is_some_and(|&b| b == b'/' || b == b'\\')
            || (raw.len() >= 2 && raw[0].is_ascii_alphabetic() && raw[1] == b':')
        {
            return Err(unsafe_entry("absolute path"));
        }
        let Some(relative) = entry.enclosed_name() else {
            return Err(unsafe_entry("path escapes the extraction folder"));
        };
        let kind = entry.unix_mode().map(|mode| mode & S_IFMT).unwrap_or(0);
        if kind == S_IFLNK {
            return Err(unsafe_entry("symbolic link"));
        }
        if kind != 0 && kind != S_IFREG && kind != S_IFDIR {
            return Err(unsafe_entry("not a regular file or folder"));
        }
        let target = dest.join(&relative);

        if entry.is_dir() {
            fs::create_dir_all(&target).map_err(io_err(&target))?;
            continue;
        }

        let too_large = |total: u64| FmuError::ArchiveTooLarge {
            path: archive.to_path_buf(),
            reason: format!(
                "more than {} bytes uncompressed (at entry '{name}', {total} bytes so far)",
                limits.max_total_bytes
            ),
        };
        let budget = limits.max_total_bytes.saturating_sub(total);
        if entry.size() > budget {
            return Err(too_large(total.saturating_add(entry.size())));
        }
        if let Some(parent) = target.parent() {
            fs::create_dir_all(parent).map_err(io_err(parent))?;
        }
        // `create_new` refuses duplicate entries and never follows a link planted at `target`.
        let mut out = OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&target)
            .map_err(|e| {
                if e.kind() == io::ErrorKind::AlreadyExists {
                    unsafe_entry("duplicate entry")
                } else {
                    FmuError::Io {
                        path: target.clone(),
                        source: e,
                    }
                }
            })?;
        // Read at most one byte beyond the budget: the declared size may lie.
        let written =
            copy_limited(&mut entry, &mut out, budget.saturating_add(1)).map_err(|e| {
                if e.kind() == io::ErrorKind::InvalidData || e.kind() == io::ErrorKind::Other {
                    FmuError::Archive {
                        path: archive.to_path_buf(),
                        entry: name.clone(),
                        reason: e.to_string(),
                    }
                } else {
                    FmuError::Io {
                        path: target.clone(),
                        source: e,
                    }
                }
            })?;
        total = total.saturating_add(written);
        if written > budget {
            return Err(too_large(total));
        }
    }
    Ok(())
}

/// Copies at most `limit` bytes from `reader` to `writer`, returning the number copied.
fn copy_limited(reader: &mut impl Read, writer: &mut impl Write, limit: u64) -> io::Result<u64> {
    io::copy(&mut reader.take(limit), writer)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Cursor;
    use zip::write::SimpleFileOptions;

    fn write_zip(path: &Path, entries: &[(&str, &[u8])]) {
        let mut w = zip::ZipWriter::new(Cursor::new(Vec::new()));
        for (name, data) in entries {
            w.start_file(*name, SimpleFileOptions::default()).unwrap();
            w.write_all(data).unwrap();
        }
        let bytes = w.finish().unwrap().into_inner();
        fs::write(path, bytes).unwrap();
    }

    #[test]
    fn extracts_nested_files() {
        let dir = tempfile::tempdir().unwrap();
        let fmu = dir.path().join("a.fmu");
        write_zip(
            &fmu,
            &[
                ("modelDescription.xml", b"<x/>"),
                ("resources/a/b.txt", b"hi"),
            ],
        );
        let out = extract_to_temp(&fmu).unwrap();
        assert_eq!(
            fs::read(out.path().join("resources/a/b.txt")).unwrap(),
            b"hi"
        );
    }

    #[test]
    fn zip_bomb_is_refused_on_actual_size() {
        let dir = tempfile::tempdir().unwrap();
        let fmu = dir.path().join("bomb.fmu");
        let zeros = vec![0u8; 10_000];
        write_zip(&fmu, &[("a.bin", &zeros), ("b.bin", &zeros)]);
        let out = tempfile::tempdir().unwrap();
        let limits = ExtractLimits {
            max_total_bytes: 15_000,
            max_entries: 10,
        };
        let err = extract_with_limits(&fmu, out.path(), limits).unwrap_err();
        assert!(matches!(err, FmuError::ArchiveTooLarge { .. }), "{err}");
        let limits = ExtractLimits {
            max_total_bytes: 1 << 20,
            max_entries: 1,
        };
        let out = tempfile::tempdir().unwrap();
        let err = extract_with_limits(&fmu, out.path(), limits).unwrap_err();
        assert!(err.to_string().contains("2 entries"), "{err}");
    }

    #[test]
    fn duplicate_entries_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let fmu = dir.path().join("dup.fmu");
        // The zip writer refuses duplicates, so use two spellings of one path.
        write_zip(&fmu, &[("a/b.txt", b"1"), ("a/./b.txt", b"2")]);
        let out = tempfile::tempdir().unwrap();
        let err = extract(&fmu, out.path()).unwrap_err();
        assert!(err.to_string().contains("duplicate entry"), "{err}");
    }
}
