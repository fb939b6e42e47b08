//! Writing output files safely: never through a symbolic link, never half-written, never
//! over a device or a pipe.
//!
//! The one place that decides how uq-driver and railuq-fmu write a file by name.
//!
//! **Regular files.** uq-driver often runs as root in shared folders (cluster plan folders),
//! where anyone may have planted a symbolic link (or a hard link) under the name of a file it
//! writes. Opening such a name for writing would overwrite whatever the link points at (a
//! `summary.json` link to `/etc/passwd`). A file whose name is free, a regular file or a link
//! is therefore written to a new temporary file in the same folder (created exclusively, so
//! no link can be in the way) and then renamed over its name: `rename` replaces a link
//! itself, never its target. A write that fails (a full disk) leaves the previous file, or
//! none, and no half-written one.
//!
//! **Devices, pipes and sockets.** A name that exists and is a character or block device, a
//! named pipe (FIFO) or a socket is never renamed over or removed: renaming over
//! `/dev/null` would replace the system's null device with a regular file. Such a name is
//! opened for writing and written into (`--out /dev/null` discards, `--out /dev/stdout` and a
//! pipe another program reads receive the whole output). A socket cannot be opened as a
//! file: that is an error, and the socket is left as it is.
//!
//! **Standard output.** The name `-` writes to standard output.
//!
//! **Folders.** A folder given where a file is expected is an error that says so.
//!
//! [`write()`] writes a file from memory; [`OutFile`] streams a large one and is committed
//! with [`OutFile::commit`]; dropped without it, the temporary file is removed and the target
//! is left as it was (what went into a device or pipe cannot be taken back).
//!
//! A new file gets the usual permissions (0666 less the umask), as `File::create` would
//! give it.

use std::fs::{File, OpenOptions, Permissions};
use std::io::{self, BufWriter, Seek, SeekFrom, Write};
use std::os::unix::fs::{FileTypeExt, OpenOptionsExt, PermissionsExt};
use std::path::{Path, PathBuf};

use tempfile::NamedTempFile;

/// Prefix of the temporary files (hidden; a run killed while writing may leave one behind).
pub const TEMP_PREFIX: &str = ".uq-driver-tmp-";

/// The folder a file named `path` lives in (`.` for a bare file name).
fn folder_of(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

fn temp_beside(path: &Path) -> io::Result<NamedTempFile> {
    tempfile::Builder::new()
        .prefix(TEMP_PREFIX)
        .suffix(".part")
        .permissions(Permissions::from_mode(0o666))
        .tempfile_in(folder_of(path))
}

/// Whether `path` names standard output (`-`).
pub fn is_stdout(path: &Path) -> bool {
    path.as_os_str() == "-"
}

/// Where the bytes for a name go.
enum Target {
    /// A temporary file renamed over the name (the name is free, a regular file or a link).
    Replace,
    /// An existing device or pipe, opened for writing.
    Into(File),
    /// Standard output.
    Stdout,
}

/// Decides how `path` is written (see the module docs).
fn target(path: &Path) -> io::Result<Target> {
    if is_stdout(path) {
        return Ok(Target::Stdout);
    }
    let kind = match std::fs::symlink_metadata(path) {
        Ok(m) => m.file_type(),
        Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(Target::Replace),
        Err(e) => return Err(e),
    };
    if kind.is_file() || kind.is_symlink() {
        return Ok(Target::Replace);
    }
    if kind.is_dir() {
        return Err(io::Error::new(
            io::ErrorKind::IsADirectory,
            "is a folder, not a file: give the name of a file to write",
        ));
    }
    if kind.is_socket() {
        return Err(io::Error::other(
            "is a socket: uq-driver writes neither into it nor over it (give a file, a pipe or a device)",
        ));
    }
    // A device or a FIFO: written into. O_NOFOLLOW: a link swapped in since the check above
    // is not followed. Opening a FIFO waits for its reader, as a shell redirection does.
    let file = OpenOptions::new()
        .write(true)
        .custom_flags(libc::O_NOFOLLOW)
        .open(path)?;
    let now = file.metadata()?.file_type();
    if now.is_file() {
        // Replaced by a regular file since the check: write it the usual way, untouched.
        return Ok(Target::Replace);
    }
    Ok(Target::Into(file))
}

/// Removes the temporary files a killed run left in `dir` (not in its sub-folders): regular
/// files and links named `.uq-driver-tmp-*.part`, never followed. Called by the holder of the
/// folder's lock, while no other run writes there. Returns how many were removed; a file that
/// cannot be removed is left (it is only clutter).
pub fn remove_leftovers(dir: &Path) -> usize {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return 0;
    };
    let mut removed = 0;
    for entry in entries.flatten() {
        let name = entry.file_name();
        let name = name.to_string_lossy();
        if !(name.starts_with(TEMP_PREFIX) && name.ends_with(".part")) {
            continue;
        }
        // file_type() does not follow a link: a directory of that name is left alone.
        let Ok(kind) = entry.file_type() else {
            continue;
        };
        if (kind.is_file() || kind.is_symlink()) && std::fs::remove_file(entry.path()).is_ok() {
            removed += 1;
        }
    }
    removed
}

/// Creates the sub-folder `path` of an output folder (with its parents) unless it exists,
/// and refuses it when it is a symbolic link: a link planted in a shared folder (e.g.
/// `slurm/` → `/etc/cron.d`) would otherwise put the files wherever it points.
pub fn sub_folder(path: &Path) -> io::Result<()> {
    if std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_symlink()) {
        return Err(io::Error::other(
            "is a symbolic link; uq-driver does not write through it (remove it)",
        ));
    }
    std::fs::create_dir_all(path)
}

/// Writes `bytes` to `path` (see the module docs for what each kind of name gets).
pub fn write(path: &Path, bytes: &[u8]) -> io::Result<()> {
    let mut f = OutFile::create(path, 0)?;
    f.write_all(bytes)?;
    f.commit()
}

/// Where an [`OutFile`]'s bytes go.
#[derive(Debug)]
enum Sink {
    Temp(NamedTempFile),
    Into(File, PathBuf),
    Stdout(io::Stdout),
}

impl Write for Sink {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        match self {
            Sink::Temp(f) => f.write(buf),
            Sink::Into(f, _) => f.write(buf),
            Sink::Stdout(s) => s.write(buf),
        }
    }

    fn flush(&mut self) -> io::Result<()> {
        match self {
            Sink::Temp(f) => f.flush(),
            Sink::Into(f, _) => f.flush(),
            Sink::Stdout(s) => s.flush(),
        }
    }
}

impl Seek for Sink {
    fn seek(&mut self, pos: SeekFrom) -> io::Result<u64> {
        let cannot = |what: &str| {
            io::Error::new(
                io::ErrorKind::Unsupported,
                format!(
                    "{what} cannot seek, and this file format needs to (write it to a regular \
                     file instead)"
                ),
            )
        };
        match self {
            Sink::Temp(f) => f.seek(pos),
            Sink::Into(f, path) => f.seek(pos).map_err(|e| {
                if e.raw_os_error() == Some(libc::ESPIPE) {
                    cannot(&path.display().to_string())
                } else {
                    e
                }
            }),
            Sink::Stdout(_) => Err(cannot("standard output")),
        }
    }
}

/// A file being written: buffered writes go to a temporary file beside `path`, which
/// [`commit`](OutFile::commit) renames over `path` — or straight into `path` when it is a
/// device or a pipe, or to standard output for `-`.
#[derive(Debug)]
pub struct OutFile {
    path: PathBuf,
    writer: BufWriter<Sink>,
}

impl OutFile {
    /// Starts writing `path` (with a write buffer of `capacity` bytes).
    pub fn create(path: &Path, capacity: usize) -> io::Result<OutFile> {
        let sink = match target(path)? {
            Target::Replace => Sink::Temp(temp_beside(path)?),
            Target::Into(file) => Sink::Into(file, path.to_path_buf()),
            Target::Stdout => Sink::Stdout(io::stdout()),
        };
        Ok(OutFile {
            path: path.to_path_buf(),
            writer: BufWriter::with_capacity(capacity, sink),
        })
    }

    /// Flushes the buffer and renames the file over its target (a device, a pipe or standard
    /// output: flushes only).
    pub fn commit(self) -> io::Result<()> {
        match self.writer.into_inner().map_err(|e| e.into_error())? {
            Sink::Temp(tmp) => {
                tmp.persist(&self.path).map_err(|e| e.error)?;
            }
            Sink::Into(mut f, _) => f.flush()?,
            Sink::Stdout(mut s) => s.flush()?,
        }
        Ok(())
    }
}

impl Write for OutFile {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.writer.write(buf)
    }

    fn write_all(&mut self, buf: &[u8]) -> io::Result<()> {
        self.writer.write_all(buf)
    }

    fn flush(&mut self) -> io::Result<()> {
        self.writer.flush()
    }
}

impl Seek for OutFile {
    fn seek(&mut self, pos: SeekFrom) -> io::Result<u64> {
        self.writer.seek(pos)
    }
}

#[cfg(test)]
mod tests;
