//! The results store against the free disk space: the series of the runs go to the store as
//! they finish (not to memory), so the disk is what a study with long series can run out of.

use std::path::Path;

/// The store's size and the room for it (bytes).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Disk {
    /// The results store of the whole study.
    pub store: f64,
    /// Free space for it: what an unprivileged user may still write on the output folder's
    /// file system, plus the store already there (a resumed study).
    pub free: f64,
}

/// Bytes of a results store of `runs` records of `values` values each (format 2: 29 bytes of
/// framing per record).
pub fn store_bytes(runs: f64, values: f64) -> f64 {
    runs * (8.0 * values + 29.0)
}

/// The room for the store of `dir` (which need not exist yet: its nearest existing folder's
/// file system counts), or `None` where the system does not say.
pub fn free_bytes(dir: &Path) -> Option<f64> {
    let existing = std::fs::metadata(dir.join("store").join("records.bin")).map_or(0, |m| m.len());
    let mut p = if dir.as_os_str().is_empty() {
        Path::new(".")
    } else {
        dir
    };
    while !p.exists() {
        p = match p.parent() {
            Some(q) if !q.as_os_str().is_empty() => q,
            _ => Path::new("."),
        };
        if p == Path::new(".") {
            break;
        }
    }
    crate::sys::available_bytes(p).map(|free| free + existing as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn free_space_is_known_for_a_folder_not_yet_created() {
        let dir = tempfile::tempdir().unwrap();
        let free = free_bytes(&dir.path().join("a/b/c")).unwrap();
        assert!(free > 0.0 && free.is_finite());
        // The wheel's record: 501 values and the frame.
        assert_eq!(store_bytes(1.0, 501.0), 4037.0);
    }
}
