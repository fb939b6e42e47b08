//! The output folder's lock: one run at a time per folder.
//!
//! `DIR/uq-driver.lock` holds who runs there (pid, host, start time) and is locked with an
//! exclusive `flock` for as long as the run lasts. The operating system releases that lock
//! when the process ends however it ends (a crash, `kill -9`), so a lock file left behind by
//! a dead run is stale by construction: the next run takes it over and says so. A second run
//! while the first is alive is refused with the first one's pid and host.

use std::fs::{File, OpenOptions, TryLockError};
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// The lock file's name inside the output folder.
pub const LOCK_FILE: &str = "uq-driver.lock";

/// Why the folder could not be locked.
#[derive(Debug, thiserror::Error)]
pub enum LockError {
    /// Another run holds the folder.
    #[error(
        "{} is in use by another uq-driver run ({holder}); wait for it to finish, or use \
         another --out folder",
        dir.display()
    )]
    InUse {
        /// The folder.
        dir: PathBuf,
        /// Who holds it, as the lock file says.
        holder: String,
    },
    /// The lock file could not be created or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The lock file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
}

/// A held lock on an output folder; released (and the file removed) on drop.
#[derive(Debug)]
pub struct FolderLock {
    path: PathBuf,
    file: File,
    /// What the lock file said when a stale lock was taken over.
    taken_over: Option<String>,
}

/// This process as the lock file describes it: `pid 1234 on host h since <unix seconds>`.
fn holder_text() -> String {
    let since = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    format!(
        "pid {} on host {} since unix time {since}",
        std::process::id(),
        hostname()
    )
}

/// The host name (from the kernel; `?` if unknown).
pub fn hostname() -> String {
    std::fs::read_to_string("/proc/sys/kernel/hostname")
        .ok()
        .map(|s| s.trim().to_owned())
        .filter(|s| !s.is_empty())
        .or_else(|| std::env::var("HOSTNAME").ok())
        .unwrap_or_else(|| "?".to_owned())
}

impl FolderLock {
    /// Locks `dir` (which must exist) for this process.
    pub fn acquire(dir: &Path) -> Result<FolderLock, LockError> {
        let path = dir.join(LOCK_FILE);
        let io = |source| LockError::Io {
            path: path.clone(),
            source,
        };
        let mut file = OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(&path)
            .map_err(io)?;
        let mut previous = String::new();
        match file.try_lock() {
            Ok(()) => {}
            Err(TryLockError::WouldBlock) => {
                let _ = file.read_to_string(&mut previous);
                let holder = previous.trim();
                return Err(LockError::InUse {
                    dir: dir.to_path_buf(),
                    holder: if holder.is_empty() {
                        "a process that has not written its id yet".to_owned()
                    } else {
                        holder.to_owned()
                    },
                });
            }
            Err(TryLockError::Error(e)) => return Err(io(e)),
        }
        let _ = file.read_to_string(&mut previous);
        let previous = previous.trim().to_owned();
        file.set_len(0).map_err(io)?;
        file.seek(SeekFrom::Start(0)).map_err(io)?;
        file.write_all(format!("{}\n", holder_text()).as_bytes())
            .map_err(io)?;
        file.sync_data().map_err(io)?;
        Ok(FolderLock {
            path,
            file,
            taken_over: (!previous.is_empty()).then_some(previous),
        })
    }

    /// When the folder held a stale lock (its run ended without releasing it, e.g. killed):
    /// who held it.
    pub fn taken_over(&self) -> Option<&str> {
        self.taken_over.as_deref()
    }

    /// The lock file.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Drop for FolderLock {
    fn drop(&mut self) {
        // Removed while still locked: a run starting now creates a new file and locks that.
        let _ = std::fs::remove_file(&self.path);
        let _ = self.file.unlock();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_second_lock_on_a_folder_in_use_names_the_holder() {
        let dir = tempfile::tempdir().unwrap();
        let first = FolderLock::acquire(dir.path()).unwrap();
        assert!(first.taken_over().is_none());
        let err = FolderLock::acquire(dir.path()).unwrap_err();
        let text = err.to_string();
        assert!(matches!(err, LockError::InUse { .. }), "{text}");
        assert!(
            text.contains(&format!("pid {}", std::process::id())),
            "{text}"
        );
        assert!(text.contains(&hostname()), "{text}");
        drop(first);
        assert!(!dir.path().join(LOCK_FILE).exists(), "removed on release");
        FolderLock::acquire(dir.path()).unwrap();
    }

    #[test]
    fn a_stale_lock_file_of_a_dead_run_is_taken_over() {
        let dir = tempfile::tempdir().unwrap();
        let stale = "pid 999999 on host elsewhere since unix time 1";
        std::fs::write(dir.path().join(LOCK_FILE), format!("{stale}\n")).unwrap();
        let lock = FolderLock::acquire(dir.path()).unwrap();
        assert_eq!(lock.taken_over(), Some(stale));
        let text = std::fs::read_to_string(lock.path()).unwrap();
        assert!(
            text.starts_with(&format!("pid {} ", std::process::id())),
            "{text}"
        );
    }
}
