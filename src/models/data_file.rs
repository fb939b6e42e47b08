//! Reading a data file a parameter names (a contact table, a measured track): one function,
//! [`read_data_file`], with the checks every such read needs.
//!
//! - A relative path is resolved in the FMU's resources folder when the importer gave one.
//! - The rest is the `in-file` crate's (shared with uq-driver's input files):
//!   only a regular file is read: a directory, a FIFO, a socket or a device is refused before
//!   it is opened for reading (a FIFO opened for reading would block until a writer comes), and
//!   the file is opened non-blocking and checked again on the open handle, so that a path
//!   swapped for a FIFO in between cannot hang the run either.
//! - At most [`MAX_DATA_FILE_BYTES`] are read.
//! - The text must be UTF-8.
//!
//! Error messages name the parameter and the path and say what was expected; they never
//! quote the file's contents (a wrong path may name a file that is not ours to show in a log).
#![forbid(unsafe_code)]

use std::path::{Path, PathBuf};

/// Largest data file read (bytes): 64 MiB.
pub const MAX_DATA_FILE_BYTES: u64 = 64 << 20;

/// The path a parameter's value names: `value` itself when absolute or when no resources
/// folder is known, else `value` inside `resource_dir`.
pub fn resolve(value: &str, resource_dir: Option<&Path>) -> PathBuf {
    let p = Path::new(value);
    match resource_dir {
        Some(dir) if p.is_relative() => dir.join(p),
        _ => p.to_path_buf(),
    }
}

/// Reads the text of the file parameter `param` names (`value`, resolved by [`resolve`]).
///
/// The error says which parameter, which path and what is wrong with it: missing, not a
/// regular file, larger than [`MAX_DATA_FILE_BYTES`], unreadable or not UTF-8. The rules are
/// the `in-file` crate's, which uq-driver's input files follow too.
pub fn read_data_file(
    param: &str,
    value: &str,
    resource_dir: Option<&Path>,
) -> Result<String, String> {
    let path = resolve(value, resource_dir);
    let shown = path.display();
    let refuse = |what: &str| format!("{param} '{shown}': {what}");
    in_file::read_text(&path, MAX_DATA_FILE_BYTES).map_err(|e| match e {
        Ok(line) => refuse(&format!(
            "line {line} is not UTF-8 text (a text file of numbers is expected)"
        )),
        Err(in_file::ReadError::TooLarge { size, .. }) => refuse(&format!(
            "has {size} bytes, more than the {} MiB a data file may have",
            MAX_DATA_FILE_BYTES >> 20
        )),
        Err(in_file::ReadError::Grew { .. }) => refuse(&format!(
            "grew beyond the {} MiB a data file may have while it was read",
            MAX_DATA_FILE_BYTES >> 20
        )),
        Err(other) => refuse(&other.to_string()),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp_dir(tag: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("railuq-data-file-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn a_relative_path_is_read_from_the_resources_folder() {
        let dir = temp_dir("relative");
        std::fs::write(dir.join("t.csv"), "1,2\n").unwrap();
        assert_eq!(read_data_file("p", "t.csv", Some(&dir)).unwrap(), "1,2\n");
        let abs = dir.join("t.csv");
        assert_eq!(
            read_data_file("p", abs.to_str().unwrap(), Some(Path::new("/nonexistent"))).unwrap(),
            "1,2\n"
        );
        let e = read_data_file("p", "missing.csv", Some(&dir)).unwrap_err();
        assert!(e.starts_with("p '") && e.contains("missing.csv"), "{e}");
        std::fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn a_directory_is_refused() {
        let dir = temp_dir("dir");
        let e = read_data_file("contact_table", dir.to_str().unwrap(), None).unwrap_err();
        assert!(
            e.contains("is a directory; a regular file is expected"),
            "{e}"
        );
        std::fs::remove_dir_all(dir).unwrap();
    }

    #[cfg(unix)]
    #[test]
    fn a_fifo_is_refused_without_blocking() {
        let dir = temp_dir("fifo");
        let fifo = dir.join("pipe");
        let status = std::process::Command::new("mkfifo").arg(&fifo).status();
        if !matches!(status, Ok(s) if s.success()) {
            eprintln!("mkfifo unavailable: skipped");
            return;
        }
        // No writer ever opens the FIFO: a blocking open for reading would hang here.
        let (tx, rx) = std::sync::mpsc::channel();
        let path = fifo.clone();
        std::thread::spawn(move || {
            let _ = tx.send(read_data_file(
                "contact_table",
                path.to_str().unwrap(),
                None,
            ));
        });
        let result = rx
            .recv_timeout(std::time::Duration::from_secs(10))
            .expect("reading a FIFO must not block");
        let e = result.unwrap_err();
        assert!(e.contains("is a FIFO (named pipe)"), "{e}");
        std::fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn a_file_beyond_the_size_cap_is_refused_before_it_is_read() {
        let dir = temp_dir("big");
        let path = dir.join("big.csv");
        let f = std::fs::File::create(&path).unwrap();
        f.set_len(MAX_DATA_FILE_BYTES + 1).unwrap(); // sparse: no disk space used
        let e = read_data_file("p", path.to_str().unwrap(), None).unwrap_err();
        assert!(e.contains("more than the 64 MiB"), "{e}");
        std::fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn binary_content_is_refused_without_being_quoted() {
        let dir = temp_dir("binary");
        let path = dir.join("b.csv");
        std::fs::write(&path, b"1,2\nsecret\xff\xfe tail\n").unwrap();
        let e = read_data_file("p", path.to_str().unwrap(), None).unwrap_err();
        assert!(e.contains("line 2 is not UTF-8"), "{e}");
        assert!(!e.contains("secret") && !e.contains("tail"), "{e}");
        std::fs::remove_dir_all(dir).unwrap();
    }
}
