//! Writing output files safely: never through a symbolic link, never half-written.
//!
//! uq-driver often runs as root in shared folders (cluster plan folders), where anyone may
//! have planted a symbolic link (or a hard link) under the name of a file it writes. Opening
//! such a name for writing would overwrite whatever the link points at (found by QA: a
//! `summary.json` link to `/etc/passwd`). Every output file is therefore written to a new
//! temporary file in the same folder (created exclusively, so no link can be in the way) and
//! then renamed over its name: `rename` replaces a link itself, never its target. A write
//! that fails (a full disk) leaves the previous file, or none, and no half-written one.
//!
//! [`write()`] writes a file from memory; [`OutFile`] streams a large one (e.g. `export`'s
//! `runs.csv`) and is committed with [`OutFile::commit`]; dropped without it, the
//! temporary file is removed and the target is left as it was.
//!
//! The new file gets the usual permissions (0666 less the umask), as `File::create` would
//! give it.

use std::fs::{File, Permissions};
use std::io::{self, BufWriter, Seek, SeekFrom, Write};
use std::os::unix::fs::PermissionsExt;
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
/// `slurm/` → `/etc/cron.d`) would otherwise put uq-driver's files wherever it points.
pub fn sub_folder(path: &Path) -> io::Result<()> {
    if std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_symlink()) {
        return Err(io::Error::other(
            "is a symbolic link; uq-driver does not write through it (remove it)",
        ));
    }
    std::fs::create_dir_all(path)
}

/// Writes `bytes` to `path` through a temporary file renamed over it (see the module docs).
pub fn write(path: &Path, bytes: &[u8]) -> io::Result<()> {
    let mut tmp = temp_beside(path)?;
    tmp.as_file_mut().write_all(bytes)?;
    tmp.persist(path).map_err(|e| e.error)?;
    Ok(())
}

/// A file being written: buffered writes go to a temporary file beside `path`, which
/// [`commit`](OutFile::commit) renames over `path`.
#[derive(Debug)]
pub struct OutFile {
    path: PathBuf,
    writer: BufWriter<NamedTempFile>,
}

impl OutFile {
    /// Starts writing `path` (with a write buffer of `capacity` bytes).
    pub fn create(path: &Path, capacity: usize) -> io::Result<OutFile> {
        Ok(OutFile {
            path: path.to_path_buf(),
            writer: BufWriter::with_capacity(capacity, temp_beside(path)?),
        })
    }

    /// Flushes the buffer and renames the file over its target.
    pub fn commit(self) -> io::Result<()> {
        let tmp = self.writer.into_inner().map_err(|e| e.into_error())?;
        tmp.persist(&self.path).map_err(|e| e.error)?;
        Ok(())
    }

    /// The unbuffered temporary file (e.g. for its length).
    pub fn file(&self) -> &File {
        self.writer.get_ref().as_file()
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
mod tests {
    use super::*;
    use std::os::unix::fs::symlink;

    fn leftovers(dir: &Path) -> Vec<String> {
        std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.starts_with(TEMP_PREFIX))
            .collect()
    }

    #[test]
    fn a_symlink_planted_as_a_sub_folder_is_refused_not_written_through() {
        let dir = tempfile::tempdir().unwrap();
        let elsewhere = dir.path().join("elsewhere");
        std::fs::create_dir(&elsewhere).unwrap();
        let planted = dir.path().join("slurm");
        symlink(&elsewhere, &planted).unwrap();
        let err = sub_folder(&planted).unwrap_err();
        assert!(err.to_string().contains("symbolic link"), "{err}");
        let made = dir.path().join("a").join("b");
        sub_folder(&made).unwrap();
        assert!(made.is_dir());
        sub_folder(&made).unwrap();
    }

    #[test]
    fn temporary_files_left_by_a_killed_run_are_removed_and_nothing_else() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let victim = d.join("victim.txt");
        std::fs::write(&victim, "precious\n").unwrap();
        std::fs::write(d.join(format!("{TEMP_PREFIX}abc.part")), "half").unwrap();
        symlink(&victim, d.join(format!("{TEMP_PREFIX}link.part"))).unwrap();
        std::fs::create_dir(d.join(format!("{TEMP_PREFIX}dir.part"))).unwrap();
        std::fs::write(d.join(format!("{TEMP_PREFIX}abc.csv")), "other").unwrap();
        std::fs::write(d.join("summary.json"), "{}").unwrap();
        assert_eq!(remove_leftovers(d), 2);
        let mut left: Vec<String> = std::fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        left.sort();
        assert_eq!(
            left,
            [
                format!("{TEMP_PREFIX}abc.csv"),
                format!("{TEMP_PREFIX}dir.part"),
                "summary.json".to_owned(),
                "victim.txt".to_owned()
            ]
        );
        assert_eq!(std::fs::read_to_string(&victim).unwrap(), "precious\n");
    }

    #[test]
    fn a_symlink_planted_as_an_output_file_is_replaced_not_written_through() {
        let dir = tempfile::tempdir().unwrap();
        let victim = dir.path().join("victim.txt");
        std::fs::write(&victim, "precious\n").unwrap();
        let out = dir.path().join("out");
        std::fs::create_dir(&out).unwrap();
        let planted = out.join("summary.json");
        symlink(&victim, &planted).unwrap();
        write(&planted, b"{}\n").unwrap();
        assert_eq!(std::fs::read_to_string(&victim).unwrap(), "precious\n");
        assert!(!std::fs::symlink_metadata(&planted)
            .unwrap()
            .file_type()
            .is_symlink());
        assert_eq!(std::fs::read_to_string(&planted).unwrap(), "{}\n");
        assert!(leftovers(&out).is_empty());
    }

    #[test]
    fn a_hard_link_planted_as_an_output_file_keeps_its_other_name_unchanged() {
        let dir = tempfile::tempdir().unwrap();
        let victim = dir.path().join("victim.txt");
        std::fs::write(&victim, "precious\n").unwrap();
        let planted = dir.path().join("points.csv");
        std::fs::hard_link(&victim, &planted).unwrap();
        let mut f = OutFile::create(&planted, 16).unwrap();
        f.write_all(b"index,status\n0,ok\n").unwrap();
        f.commit().unwrap();
        assert_eq!(std::fs::read_to_string(&victim).unwrap(), "precious\n");
        assert_eq!(
            std::fs::read_to_string(&planted).unwrap(),
            "index,status\n0,ok\n"
        );
    }

    #[test]
    fn an_uncommitted_stream_leaves_the_old_file_and_no_temporary() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("runs.csv");
        std::fs::write(&path, "old\n").unwrap();
        let mut f = OutFile::create(&path, 4).unwrap();
        f.write_all(b"new content that is never committed").unwrap();
        drop(f);
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "old\n");
        assert!(leftovers(dir.path()).is_empty());
    }

    #[test]
    fn new_files_get_the_usual_permissions_and_a_bare_name_is_written_in_the_cwd_folder() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.csv");
        write(&path, b"x\n").unwrap();
        let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
        let plain = dir.path().join("plain.csv");
        File::create(&plain).unwrap();
        assert_eq!(mode(&path), mode(&plain));
        assert_eq!(folder_of(Path::new("x.csv")), Path::new("."));
    }

    #[test]
    fn writing_into_a_missing_folder_is_an_error() {
        let dir = tempfile::tempdir().unwrap();
        assert!(write(&dir.path().join("missing/x.csv"), b"x").is_err());
    }
}
