//! The temporary folders of opened FMUs, so that a process ended by a signal (or by an FMU
//! that calls `exit()`) can still remove them: [`remove_all`] is called from those paths, where
//! the `TempDir`s' destructors do not run.

use std::path::{Path, PathBuf};
use std::sync::{Mutex, RwLock, RwLockReadGuard};

/// Held (shared) while a folder is being filled, taken (exclusive) by [`remove_all`]: a
/// removal while another thread extracts would race with it (the extraction recreates the
/// folder as it creates its subfolders), so the removal waits for the extraction to finish.
static FILLING: RwLock<()> = RwLock::new(());

/// Held while an FMU is extracted into a registered folder.
pub(crate) fn filling() -> RwLockReadGuard<'static, ()> {
    FILLING.read().unwrap_or_else(|e| e.into_inner())
}

/// The folders, and whether the process is ending (no new folder may then live).
static FOLDERS: Mutex<(Vec<PathBuf>, bool)> = Mutex::new((Vec::new(), false));

fn folders() -> std::sync::MutexGuard<'static, (Vec<PathBuf>, bool)> {
    FOLDERS.lock().unwrap_or_else(|e| e.into_inner())
}

/// Creates a temporary folder (`<prefix>XXXXXX` in the system's temporary folder) and
/// remembers it, in one step with respect to [`remove_all`]: a process being ended never keeps
/// a folder created meanwhile. When the process is already ending, the calling thread waits
/// for the end instead of creating anything.
pub(crate) fn temp_dir(prefix: &str) -> std::io::Result<tempfile::TempDir> {
    let mut f = folders();
    if f.1 {
        drop(f);
        loop {
            std::thread::park();
        }
    }
    let dir = tempfile::Builder::new().prefix(prefix).tempdir()?;
    f.0.push(dir.path().to_path_buf());
    Ok(dir)
}

/// Forgets a folder (it is being removed the ordinary way).
pub(crate) fn unregister(path: &Path) {
    let mut f = folders();
    if let Some(i) = f.0.iter().position(|p| p == path) {
        f.0.swap_remove(i);
    }
}

/// The folders registered now.
pub fn registered() -> Vec<PathBuf> {
    folders().0.clone()
}

/// Removes every registered folder; from then on a new folder is removed as it is registered
/// (the process is ending). The lock is held only for short bookkeeping elsewhere, so waiting
/// for it cannot deadlock.
pub fn remove_all() {
    // Never released: the process is ending.
    std::mem::forget(FILLING.write().unwrap_or_else(|e| e.into_inner()));
    let mut f = folders();
    f.1 = true;
    for p in f.0.drain(..) {
        // Renamed first: another thread still extracting into it (by its old path) can add no
        // entry after this, so the removal below is complete.
        let mut gone = p.clone().into_os_string();
        gone.push(".removing");
        let gone = PathBuf::from(gone);
        let target = if std::fs::rename(&p, &gone).is_ok() {
            gone
        } else {
            p
        };
        for _ in 0..3 {
            if std::fs::remove_dir_all(&target).is_ok() || !target.exists() {
                break;
            }
        }
    }
}
