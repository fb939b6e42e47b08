//! Reading an input file a user (or a parameter of an FMU) names: only a regular file, never
//! blocking, never more than a cap.
//!
//! The one place that decides how uq-driver (`[inputs] file`, `simulate --input`) and the
//! railuq FMUs (contact tables, measured track profiles) read a data file by name:
//!
//! - Only a regular file is read: a directory, a FIFO (named pipe), a socket or a device is
//!   refused before it is opened for reading. A FIFO opened for reading blocks until a
//!   writer comes (a run that hangs for ever), and `/dev/zero` never ends.
//! - The file is opened non-blocking (`O_NONBLOCK`) and checked again on the open handle, so
//!   that a name swapped for a FIFO in between cannot hang the reader either.
//! - At most a cap of bytes is read: a file larger than the cap is refused before it is
//!   read, and one that grows beyond it while it is read is refused too.
//!
//! The errors ([`ReadError`]) say what is wrong with the file; none of them quotes its
//! contents, and callers that parse the text must not either: a wrong path may name a file
//! that is not theirs to show in a log (`/etc/shadow`).

#![forbid(unsafe_code)]

use std::fs::{File, Metadata, OpenOptions};
use std::io::Read;
use std::path::Path;

/// Why a file could not be read. The messages never quote the file's contents.
#[derive(Debug)]
pub enum ReadError {
    /// The name cannot be looked up (missing, no permission, ...).
    Missing(std::io::Error),
    /// The name is not a regular file: what it is (`"a FIFO (named pipe)"`, ...).
    NotRegular(&'static str),
    /// The file exists but cannot be opened.
    Open(std::io::Error),
    /// The file is larger than the cap (bytes).
    TooLarge {
        /// Its size (bytes).
        size: u64,
        /// The cap (bytes).
        limit: u64,
    },
    /// The file grew beyond the cap (bytes) while it was read.
    Grew {
        /// The cap (bytes).
        limit: u64,
    },
    /// Reading failed.
    Read(std::io::Error),
}

impl std::fmt::Display for ReadError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ReadError::Missing(e) => write!(f, "cannot be read: {e}"),
            ReadError::NotRegular(kind) => write!(f, "is {kind}; a regular file is expected"),
            ReadError::Open(e) => write!(f, "cannot be opened: {e}"),
            ReadError::TooLarge { size, limit } => write!(
                f,
                "has {size} bytes, more than the {} this file may have",
                size_text(*limit)
            ),
            ReadError::Grew { limit } => write!(
                f,
                "grew beyond the {} this file may have while it was read",
                size_text(*limit)
            ),
            ReadError::Read(e) => write!(f, "cannot be read: {e}"),
        }
    }
}

impl std::error::Error for ReadError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            ReadError::Missing(e) | ReadError::Open(e) | ReadError::Read(e) => Some(e),
            _ => None,
        }
    }
}

/// A cap as text: whole MiB where it is a whole number of MiB, else bytes.
pub fn size_text(limit: u64) -> String {
    if limit >= 1 << 20 && limit.is_multiple_of(1 << 20) {
        format!("{} MiB", limit >> 20)
    } else {
        format!("{limit} bytes")
    }
}

/// What kind of file system object `meta` describes, for an error message.
pub fn kind(meta: &Metadata) -> &'static str {
    let t = meta.file_type();
    if t.is_dir() {
        return "a directory";
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() {
            return "a FIFO (named pipe)";
        }
        if t.is_socket() {
            return "a socket";
        }
        if t.is_block_device() || t.is_char_device() {
            return "a device";
        }
    }
    "not a regular file"
}

fn open_non_blocking(path: &Path) -> std::io::Result<File> {
    let mut options = OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        options.custom_flags(libc::O_NONBLOCK);
    }
    options.open(path)
}

/// The bytes of the regular file `path`, at most `limit` of them (see the crate's rules).
pub fn read(path: &Path, limit: u64) -> Result<Vec<u8>, ReadError> {
    let meta = std::fs::metadata(path).map_err(ReadError::Missing)?;
    if !meta.is_file() {
        return Err(ReadError::NotRegular(kind(&meta)));
    }
    let file = open_non_blocking(path).map_err(ReadError::Open)?;
    // The name may have been swapped since it was looked up: check what was opened.
    let meta = file.metadata().map_err(ReadError::Read)?;
    if !meta.is_file() {
        return Err(ReadError::NotRegular(kind(&meta)));
    }
    if meta.len() > limit {
        return Err(ReadError::TooLarge {
            size: meta.len(),
            limit,
        });
    }
    let mut bytes = Vec::with_capacity(usize::try_from(meta.len()).unwrap_or(0));
    file.take(limit.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(ReadError::Read)?;
    if bytes.len() as u64 > limit {
        return Err(ReadError::Grew { limit });
    }
    Ok(bytes)
}

/// The text of the regular file `path` (see [`read`]), or, when it is not UTF-8, the line
/// (1-based) where the first byte that is not UTF-8 is, as `Err(Ok(line))`.
pub fn read_text(path: &Path, limit: u64) -> Result<String, Result<usize, ReadError>> {
    let bytes = read(path, limit).map_err(Err)?;
    String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        Ok(1 + e.as_bytes()[..at].iter().filter(|&&b| b == b'\n').count())
    })
}

#[cfg(test)]
mod tests;
