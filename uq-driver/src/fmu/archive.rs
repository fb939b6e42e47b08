//! Safe extraction of `.fmu` archives (zip files).
//!
//! An FMU is an untrusted zip archive. Extraction refuses every entry that could write outside
//! the target folder (`..` components, absolute paths, NUL bytes: [`zip::read::ZipFile::enclosed_name`]),
//! symbolic links and other non-regular files, duplicate names (read from the central directory
//! itself: the zip crate keeps only the last of two equal names), archives whose entry count or
//! total declared size exceeds [`ExtractLimits`] (checked before anything is written), and a
//! `modelDescription.xml` larger than the parser accepts. While streaming, an entry is cut off
//! one byte past its declared size (and past the remaining budget): a lying size is refused
//! without writing more than was declared.

use std::collections::HashSet;
use std::fs::{self, File, OpenOptions};
use std::io::{self, BufReader, Read, Seek, SeekFrom, Write};
use std::path::Path;

use zip::result::ZipError;
use zip::ZipArchive;

use super::description::ParseLimits;
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

/// Extracts what this host needs to run the `.fmu` archive `archive` into the existing folder
/// `dest`, with the default limits. Every entry is checked as by [`extract`], but these are
/// not written: the binaries of other platforms (`binaries/<folder>/…` for a folder other
/// than `host_folder`, e.g. the `win64` DLL on Linux), `documentation/`, `sources/` and the
/// icon `model.png`, which no importer runs. That saves unpacking megabytes, and creating
/// and deleting folders (slow on some file systems), on every opening of the FMU.
///
/// Returns the platform folders the archive has binaries in (`binaries/<folder>/…`), sorted,
/// for a message when this host's binary is missing.
pub fn extract_for_host(
    archive: &Path,
    dest: &Path,
    host_folder: &str,
) -> Result<Vec<String>, FmuError> {
    let mut platforms = std::collections::BTreeSet::new();
    extract_filtered(archive, dest, ExtractLimits::default(), &mut |relative| {
        let mut parts = relative.components().map(|c| c.as_os_str());
        let top = parts.next().and_then(|t| t.to_str());
        let second = parts.next();
        let nested = parts.next().is_some();
        match (top, second) {
            // binaries/<folder>/…: kept for this host only.
            (Some("binaries"), Some(folder)) if nested => {
                platforms.insert(folder.to_string_lossy().into_owned());
                folder == host_folder
            }
            (Some("documentation" | "sources"), Some(_)) => false,
            (Some("model.png"), None) => false,
            _ => true,
        }
    })?;
    Ok(platforms.into_iter().collect())
}

/// Extracts `archive` into the existing folder `dest`, refusing unsafe entries and archives that
/// exceed `limits`. On error, `dest` may hold part of the archive.
pub fn extract_with_limits(
    archive: &Path,
    dest: &Path,
    limits: ExtractLimits,
) -> Result<(), FmuError> {
    extract_filtered(archive, dest, limits, &mut |_| true)
}

/// [`extract_with_limits`], writing only the entries whose relative path `keep` accepts (all
/// are checked).
fn extract_filtered(
    archive: &Path,
    dest: &Path,
    limits: ExtractLimits,
    keep: &mut dyn FnMut(&Path) -> bool,
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

    check_central_directory(archive, &mut zip, &limits)?;
    check_declared_sizes(archive, &mut zip, &limits)?;

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
        if !keep(&relative) {
            continue;
        }

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
        let declared = entry.size();
        let budget = limits.max_total_bytes.saturating_sub(total);
        if declared > budget {
            return Err(too_large(total.saturating_add(declared)));
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
        // Read at most one byte beyond the declared size (which is within the budget): the
        // declared size may lie, and then no more than it is written.
        let written =
            copy_limited(&mut entry, &mut out, declared.saturating_add(1)).map_err(|e| {
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
        if written > declared {
            return Err(FmuError::Archive {
                path: archive.to_path_buf(),
                entry: name.clone(),
                reason: format!("it holds more data than its declared size of {declared} bytes"),
            });
        }
    }
    Ok(())
}

/// Signature of a central directory file header.
const CENTRAL_HEADER_SIGNATURE: u32 = 0x0201_4b50;
/// Fixed part of a central directory file header, in bytes.
const CENTRAL_HEADER_LEN: usize = 46;

/// Reads the central directory as stored (the zip crate merges entries of the same name,
/// keeping the last): refuses duplicate names and more entries than the limit.
fn check_central_directory(
    archive: &Path,
    zip: &mut ZipArchive<File>,
    limits: &ExtractLimits,
) -> Result<(), FmuError> {
    let io_err = |source| FmuError::Io {
        path: archive.to_path_buf(),
        source,
    };
    let mut file = BufReader::new(File::open(archive).map_err(io_err)?);
    file.seek(SeekFrom::Start(zip.central_directory_start()))
        .map_err(io_err)?;
    let mut names: HashSet<Vec<u8>> = HashSet::with_capacity(zip.len());
    let mut header = [0u8; CENTRAL_HEADER_LEN];
    let mut count = 0usize;
    // The zip crate has read these headers already; anything unreadable ends the walk.
    while file.read_exact(&mut header).is_ok() {
        let field = |at: usize| u16::from_le_bytes([header[at], header[at + 1]]);
        if u32::from_le_bytes([header[0], header[1], header[2], header[3]])
            != CENTRAL_HEADER_SIGNATURE
        {
            break;
        }
        count += 1;
        if count > limits.max_entries {
            return Err(FmuError::ArchiveTooLarge {
                path: archive.to_path_buf(),
                reason: format!(
                    "more than {} entries in its central directory",
                    limits.max_entries
                ),
            });
        }
        let mut name = vec![0u8; usize::from(field(28))];
        if file.read_exact(&mut name).is_err() {
            break;
        }
        let skip = i64::from(field(30)) + i64::from(field(32));
        if file.seek_relative(skip).is_err() {
            break;
        }
        if names.contains(&name) {
            return Err(FmuError::UnsafeEntry {
                path: archive.to_path_buf(),
                entry: String::from_utf8_lossy(&name).into_owned(),
                reason: "duplicate entry (two entries of this name: which one would win?)".into(),
            });
        }
        names.insert(name);
    }
    Ok(())
}

/// Checks the sizes the archive declares before anything is written: their total, and the
/// size of `modelDescription.xml` against what the parser accepts.
fn check_declared_sizes(
    archive: &Path,
    zip: &mut ZipArchive<File>,
    limits: &ExtractLimits,
) -> Result<(), FmuError> {
    let mut total: u64 = 0;
    let description_limit = ParseLimits::default().max_bytes as u64;
    for index in 0..zip.len() {
        let name = zip.name_for_index(index).unwrap_or("<unnamed>").to_string();
        let size = zip
            .by_index_raw(index)
            .map_err(|e| FmuError::Archive {
                path: archive.to_path_buf(),
                entry: name.clone(),
                reason: e.to_string(),
            })?
            .size();
        if name == "modelDescription.xml" && size > description_limit {
            return Err(FmuError::ArchiveTooLarge {
                path: archive.to_path_buf(),
                reason: format!(
                    "modelDescription.xml declares {size} bytes, more than the limit of \
                     {description_limit} bytes"
                ),
            });
        }
        total = total.saturating_add(size);
        if total > limits.max_total_bytes {
            return Err(FmuError::ArchiveTooLarge {
                path: archive.to_path_buf(),
                reason: format!(
                    "its entries declare more than {} bytes uncompressed in all (at entry \
                     '{name}', {total} bytes so far); nothing was extracted",
                    limits.max_total_bytes,
                ),
            });
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
    fn what_no_importer_runs_is_not_unpacked() {
        let dir = tempfile::tempdir().unwrap();
        let fmu = dir.path().join("a.fmu");
        write_zip(
            &fmu,
            &[
                ("modelDescription.xml", b"<x/>"),
                ("binaries/linux64/m.so", b"so"),
                ("binaries/win64/m.dll", b"dll"),
                ("binaries/darwin64/sub/m.dylib", b"dylib"),
                ("binaries/notes.txt", b"n"),
                ("resources/win64/data.txt", b"r"),
                ("resources/documentation/d.txt", b"r"),
                ("documentation/index.html", b"d"),
                ("sources/m.c", b"c"),
                ("model.png", b"p"),
                ("extra/x.txt", b"x"),
            ],
        );
        let out = tempfile::tempdir().unwrap();
        let platforms = extract_for_host(&fmu, out.path(), "linux64").unwrap();
        assert_eq!(platforms, ["darwin64", "linux64", "win64"]);
        let has = |p: &str| out.path().join(p).exists();
        assert!(has("modelDescription.xml") && has("binaries/linux64/m.so"));
        assert!(has("binaries/notes.txt") && has("resources/win64/data.txt"));
        assert!(has("resources/documentation/d.txt") && has("extra/x.txt"));
        assert!(!has("binaries/win64") && !has("binaries/darwin64"));
        assert!(!has("documentation") && !has("sources") && !has("model.png"));
        // Entries that are not unpacked are still checked.
        let bad = dir.path().join("bad.fmu");
        write_zip(&bad, &[("binaries/win64/../../../evil.dll", b"x")]);
        let out = tempfile::tempdir().unwrap();
        let err = extract_for_host(&bad, out.path(), "linux64").unwrap_err();
        assert!(matches!(err, FmuError::UnsafeEntry { .. }), "{err}");
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

    /// Offsets of every occurrence of `needle` in `hay`.
    fn find_all(hay: &[u8], needle: &[u8]) -> Vec<usize> {
        hay.windows(needle.len())
            .enumerate()
            .filter(|(_, w)| *w == needle)
            .map(|(i, _)| i)
            .collect()
    }

    fn zip_bytes(entries: &[(&str, &[u8])]) -> Vec<u8> {
        let mut w = zip::ZipWriter::new(Cursor::new(Vec::new()));
        for (name, data) in entries {
            w.start_file(*name, SimpleFileOptions::default()).unwrap();
            w.write_all(data).unwrap();
        }
        w.finish().unwrap().into_inner()
    }

    fn files_under(dir: &Path) -> Vec<(String, u64)> {
        let mut out = Vec::new();
        for e in fs::read_dir(dir).unwrap() {
            let e = e.unwrap();
            if e.path().is_dir() {
                out.extend(files_under(&e.path()));
            } else {
                out.push((e.path().display().to_string(), e.metadata().unwrap().len()));
            }
        }
        out
    }

    #[test]
    fn exact_duplicate_entry_names_are_refused() {
        // The zip crate keeps only the last of two equal names, so the last copy used to win
        // silently. The writer refuses duplicates: write two names of one length, then rename
        // the second in its local and central headers.
        let mut bytes = zip_bytes(&[
            ("modelDescription.xml", b"<first/>"),
            ("modelDescriptioX.xml", b"<second/>"),
        ]);
        let spots = find_all(&bytes, b"modelDescriptioX.xml");
        assert_eq!(spots.len(), 2, "local and central header");
        for at in spots {
            bytes[at..at + 20].copy_from_slice(b"modelDescription.xml");
        }
        let dir = tempfile::tempdir().unwrap();
        let fmu = dir.path().join("dup.fmu");
        fs::write(&fmu, &bytes).unwrap();
        assert_eq!(
            ZipArchive::new(File::open(&fmu).unwrap()).unwrap().len(),
            1,
            "the zip crate merges the two"
        );
        let out = tempfile::tempdir().unwrap();
        let err = extract(&fmu, out.path()).unwrap_err();
        assert!(
            matches!(&err, FmuError::UnsafeEntry { entry, reason, .. }
                if entry == "modelDescription.xml" && reason.starts_with("duplicate entry")),
            "{err}"
        );
        assert!(files_under(out.path()).is_empty(), "nothing extracted");
    }

    #[test]
    fn honest_sizes_over_the_limit_are_refused_before_anything_is_written() {
        // Each entry declares its size honestly; together they exceed the limit. Entry by entry,
        // the first ones used to be written in full before the total was found too large.
        let mb = vec![0u8; 1 << 20];
        let bytes = zip_bytes(&[("a.bin", &mb), ("b.bin", &mb), ("c.bin", &mb)]);
        assert!(bytes.len() < 50_000, "compresses well: {}", bytes.len());
        let dir = tempfile::tempdir().unwrap();
        let fmu = dir.path().join("bomb.fmu");
        fs::write(&fmu, &bytes).unwrap();
        let out = tempfile::tempdir().unwrap();
        let limits = ExtractLimits {
            max_total_bytes: (5 << 20) / 2,
            max_entries: 10,
        };
        let err = extract_with_limits(&fmu, out.path(), limits).unwrap_err();
        assert!(matches!(err, FmuError::ArchiveTooLarge { .. }), "{err}");
        assert!(err.to_string().contains("at entry 'c.bin'"), "{err}");
        assert!(err.to_string().contains("nothing was extracted"), "{err}");
        assert_eq!(files_under(out.path()), vec![], "nothing written");
    }

    #[test]
    fn lying_entry_size_stops_one_byte_past_the_declared_size() {
        let data = vec![7u8; 100_000];
        let mut bytes = zip_bytes(&[("resources/big.bin", &data)]);
        // Declare 100 bytes in the local header (uncompressed size at offset 22) and in the
        // central directory header (offset 24).
        let local = find_all(&bytes, &0x0403_4b50u32.to_le_bytes())[0];
        let central = find_all(&bytes, &0x0201_4b50u32.to_le_bytes())[0];
        bytes[local + 22..local + 26].copy_from_slice(&100u32.to_le_bytes());
        bytes[central + 24..central + 28].copy_from_slice(&100u32.to_le_bytes());
        let dir = tempfile::tempdir().unwrap();
        let fmu = dir.path().join("liar.fmu");
        fs::write(&fmu, &bytes).unwrap();
        let out = tempfile::tempdir().unwrap();
        let err = extract(&fmu, out.path()).unwrap_err();
        assert!(
            err.to_string()
                .contains("more data than its declared size of 100 bytes"),
            "{err}"
        );
        let written = files_under(out.path());
        assert_eq!(written.len(), 1);
        assert!(written[0].1 <= 101, "{written:?}");
    }

    #[test]
    fn oversized_model_description_is_refused_before_extraction() {
        let dir = tempfile::tempdir().unwrap();
        let fmu = dir.path().join("big-md.fmu");
        let mut bytes = zip_bytes(&[("modelDescription.xml", b"<x/>")]);
        let too_big = ParseLimits::default().max_bytes as u32 + 1;
        let local = find_all(&bytes, &0x0403_4b50u32.to_le_bytes())[0];
        let central = find_all(&bytes, &0x0201_4b50u32.to_le_bytes())[0];
        bytes[local + 22..local + 26].copy_from_slice(&too_big.to_le_bytes());
        bytes[central + 24..central + 28].copy_from_slice(&too_big.to_le_bytes());
        fs::write(&fmu, &bytes).unwrap();
        let out = tempfile::tempdir().unwrap();
        let err = extract(&fmu, out.path()).unwrap_err();
        assert!(
            err.to_string().contains(&format!(
                "modelDescription.xml declares {too_big} bytes, more than the limit of {} bytes",
                too_big - 1
            )),
            "{err}"
        );
    }
}
