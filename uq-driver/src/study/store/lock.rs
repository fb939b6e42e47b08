//! The output folder's lock: one run at a time per folder.
//!
//! `DIR/uq-driver.lock` holds who runs there (pid, host, start time) and is locked with an
//! exclusive `flock` for as long as the run lasts. The operating system releases that lock
//! when the process ends however it ends (a crash, `kill -9`), so a lock file left behind by
//! a dead run is stale by construction: the next run takes it over and says so. A second run
//! while the first is alive is refused with the first one's pid and host.
//!
//! The folder may be shared (a cluster plan folder) and the run may be root's: the lock file
//! is opened without following a symbolic link (`O_NOFOLLOW`) and must be a regular file
//! with no other name (a planted link to `/etc/passwd` is refused, never written), and what
//! a previous lock file said is repeated only when it reads as a lock record.

use std::fs::{File, OpenOptions, TryLockError};
use std::io::{Read, Seek, SeekFrom, Write};
use std::os::unix::fs::{MetadataExt, OpenOptionsExt};
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
    /// The lock file's name is taken by something else than a lock file of ours.
    #[error(
        "{} is {what}, not a lock file; uq-driver does not write through it: remove it (or \
         use another --out folder)",
        path.display()
    )]
    NotALockFile {
        /// The lock file's path.
        path: PathBuf,
        /// What is there (`a symbolic link to /etc/passwd`, `a directory`, ...).
        what: String,
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

/// Whether `text` reads as a lock record of [`holder_text`]'s form
/// (`pid <n> on host <h> since unix time <s>`).
fn is_lock_record(text: &str) -> bool {
    let Some(rest) = text.strip_prefix("pid ") else {
        return false;
    };
    let Some((pid, rest)) = rest.split_once(" on host ") else {
        return false;
    };
    let Some((host, since)) = rest.rsplit_once(" since unix time ") else {
        return false;
    };
    let digits = |s: &str| !s.is_empty() && s.len() <= 20 && s.bytes().all(|b| b.is_ascii_digit());
    digits(pid)
        && digits(since)
        && !host.is_empty()
        && host.len() <= 255
        && !host.chars().any(char::is_control)
}

/// Opens the lock file at `path`: created new if absent, else the existing one, never
/// through a symbolic link (`O_NOFOLLOW`), and only if it is a regular file with no other
/// name (a hard link to a file elsewhere would be overwritten too).
fn open_lock_file(path: &Path) -> Result<File, LockError> {
    let io = |source| LockError::Io {
        path: path.to_path_buf(),
        source,
    };
    let open = |create: bool| {
        OpenOptions::new()
            .read(true)
            .write(true)
            .create_new(create)
            // O_NONBLOCK: opening a planted FIFO or device must not wait.
            .custom_flags(libc::O_NOFOLLOW | libc::O_NONBLOCK)
            .open(path)
    };
    // A lock file removed between the two opens (its run ended) is created anew.
    let mut attempts = 0;
    let file = loop {
        attempts += 1;
        break match open(true) {
            Ok(f) => f,
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => match open(false) {
                Ok(f) => f,
                Err(e) if e.kind() == std::io::ErrorKind::NotFound && attempts < 5 => continue,
                Err(e) => {
                    // ELOOP from O_NOFOLLOW (or a link planted meanwhile): say what is there.
                    let meta = std::fs::symlink_metadata(path);
                    if let Ok(m) = &meta {
                        if m.file_type().is_symlink() {
                            let target = std::fs::read_link(path)
                                .map(|t| format!(" to {}", t.display()))
                                .unwrap_or_default();
                            return Err(LockError::NotALockFile {
                                path: path.to_path_buf(),
                                what: format!("a symbolic link{target}"),
                            });
                        }
                        if m.is_dir() {
                            return Err(LockError::NotALockFile {
                                path: path.to_path_buf(),
                                what: "a directory".into(),
                            });
                        }
                    }
                    return Err(io(e));
                }
            },
            Err(e) => return Err(io(e)),
        };
    };
    let meta = file.metadata().map_err(io)?;
    let what = if !meta.is_file() {
        Some("not a regular file (a device, FIFO or socket)".to_owned())
    } else if meta.nlink() > 1 {
        Some(format!("a file with {} names (hard links)", meta.nlink()))
    } else {
        None
    };
    match what {
        Some(what) => Err(LockError::NotALockFile {
            path: path.to_path_buf(),
            what,
        }),
        None => Ok(file),
    }
}

/// Up to 4 KiB of the lock file's text, trimmed (empty when unreadable).
fn read_record(file: &mut File) -> String {
    let mut bytes = Vec::new();
    let _ = file.take(4096).read_to_end(&mut bytes);
    String::from_utf8_lossy(&bytes).trim().to_owned()
}

impl FolderLock {
    /// Locks `dir` (which must exist) for this process.
    pub fn acquire(dir: &Path) -> Result<FolderLock, LockError> {
        let path = dir.join(LOCK_FILE);
        let io = |source| LockError::Io {
            path: path.clone(),
            source,
        };
        let mut file = open_lock_file(&path)?;
        match file.try_lock() {
            Ok(()) => {}
            Err(TryLockError::WouldBlock) => {
                let holder = read_record(&mut file);
                return Err(LockError::InUse {
                    dir: dir.to_path_buf(),
                    holder: if is_lock_record(&holder) {
                        holder
                    } else {
                        "a process that has not written its id yet".to_owned()
                    },
                });
            }
            Err(TryLockError::Error(e)) => return Err(io(e)),
        }
        let previous = read_record(&mut file);
        let previous = if previous.is_empty() || is_lock_record(&previous) {
            previous
        } else {
            "a lock file that does not read as one of uq-driver's".to_owned()
        };
        file.set_len(0).map_err(io)?;
        file.seek(SeekFrom::Start(0)).map_err(io)?;
        file.write_all(format!("{}\n", holder_text()).as_bytes())
            .map_err(io)?;
        file.sync_data().map_err(io)?;
        // Only this process writes in the folder now: temporary files there are a killed
        // run's leftovers.
        out_file::remove_leftovers(dir);
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
        let text = std::fs::read_to_string(&lock.path).unwrap();
        assert!(
            text.starts_with(&format!("pid {} ", std::process::id())),
            "{text}"
        );
    }

    #[test]
    fn a_symlink_planted_as_the_lock_file_is_refused_and_its_target_untouched() {
        let dir = tempfile::tempdir().unwrap();
        let victim = dir.path().join("passwd");
        let secret = "root:x:0:0:secret gecos:/root:/bin/bash\n";
        std::fs::write(&victim, secret).unwrap();
        let out = dir.path().join("out");
        std::fs::create_dir(&out).unwrap();
        std::os::unix::fs::symlink(&victim, out.join(LOCK_FILE)).unwrap();
        let err = FolderLock::acquire(&out).unwrap_err();
        let text = err.to_string();
        assert!(matches!(err, LockError::NotALockFile { .. }), "{text}");
        assert!(text.contains("symbolic link"), "{text}");
        assert!(!text.contains("secret"), "{text}");
        assert_eq!(std::fs::read_to_string(&victim).unwrap(), secret);
        // A dangling link (whose target would be created) is refused too.
        let dangling = tempfile::tempdir().unwrap();
        let target = dir.path().join("created-through-link");
        std::os::unix::fs::symlink(&target, dangling.path().join(LOCK_FILE)).unwrap();
        assert!(FolderLock::acquire(dangling.path()).is_err());
        assert!(!target.exists());
    }

    #[test]
    fn a_hard_link_planted_as_the_lock_file_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let victim = dir.path().join("victim");
        std::fs::write(&victim, "keep\n").unwrap();
        std::fs::hard_link(&victim, dir.path().join(LOCK_FILE)).unwrap();
        let err = FolderLock::acquire(dir.path()).unwrap_err();
        assert!(err.to_string().contains("hard links"), "{err}");
        assert_eq!(std::fs::read_to_string(&victim).unwrap(), "keep\n");
    }

    #[test]
    fn a_stale_lock_file_that_is_not_a_lock_record_is_not_echoed() {
        let dir = tempfile::tempdir().unwrap();
        let garbage = "VICTIM lock original content";
        std::fs::write(dir.path().join(LOCK_FILE), garbage).unwrap();
        let lock = FolderLock::acquire(dir.path()).unwrap();
        let said = lock.taken_over().unwrap();
        assert!(!said.contains("VICTIM"), "{said}");
        assert!(is_lock_record(&holder_text()));
        for bad in [
            "pid x on host h since unix time 1",
            "pid 1 on host  since unix time 1",
            "pid 1 on host h since unix time",
            "avahi:x:107:115:Avahi mDNS daemon,,,:/run/avahi-daemon:/usr/sbin/nologin",
        ] {
            assert!(!is_lock_record(bad), "{bad}");
        }
    }
}
