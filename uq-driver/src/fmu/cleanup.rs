//! The temporary folders of opened FMUs, so that a process ended by a signal (or by an FMU
//! that calls `exit()`) can still remove them: [`remove_all`] is called from those paths, where
//! the `TempDir`s' destructors do not run.

use std::path::{Path, PathBuf};
use std::sync::Mutex;

static FOLDERS: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Remembers a temporary folder to remove if the process ends abnormally.
pub(crate) fn register(path: &Path) {
    let mut f = FOLDERS.lock().unwrap_or_else(|e| e.into_inner());
    f.push(path.to_path_buf());
}

/// Forgets a folder (it is being removed the ordinary way).
pub(crate) fn unregister(path: &Path) {
    let mut f = FOLDERS.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(i) = f.iter().position(|p| p == path) {
        f.swap_remove(i);
    }
}

/// The folders registered now.
pub fn registered() -> Vec<PathBuf> {
    FOLDERS.lock().unwrap_or_else(|e| e.into_inner()).clone()
}

/// Removes every registered folder (best effort; never blocks on the registry: a process on its
/// way out must not wait for a thread that holds it).
pub fn remove_all() {
    let Ok(folders) = FOLDERS.try_lock() else {
        return;
    };
    for p in folders.iter() {
        let _ = std::fs::remove_dir_all(p);
    }
}
