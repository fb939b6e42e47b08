//! Tests of `in-file`.

use super::*;

#[test]
fn a_regular_file_is_read() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("t.csv");
    std::fs::write(&p, "time,u\n0,1\n").unwrap();
    assert_eq!(read(&p, 100).unwrap(), b"time,u\n0,1\n");
    assert_eq!(read_text(&p, 100).unwrap(), "time,u\n0,1\n");
}

#[test]
fn a_directory_and_a_missing_file_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let e = read(dir.path(), 100).unwrap_err();
    assert_eq!(e.to_string(), "is a directory; a regular file is expected");
    let e = read(&dir.path().join("nope"), 100).unwrap_err();
    assert!(matches!(e, ReadError::Missing(_)), "{e}");
}

#[cfg(unix)]
#[test]
fn a_fifo_is_refused_without_blocking() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("pipe");
    let status = std::process::Command::new("mkfifo").arg(&fifo).status();
    if !matches!(status, Ok(s) if s.success()) {
        eprintln!("mkfifo unavailable: skipped");
        return;
    }
    // No writer ever opens the FIFO: a blocking open for reading would hang here.
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(read(&fifo, 100).map_err(|e| e.to_string()));
    });
    let result = rx
        .recv_timeout(std::time::Duration::from_secs(10))
        .expect("reading a FIFO must not block");
    assert_eq!(
        result.unwrap_err(),
        "is a FIFO (named pipe); a regular file is expected"
    );
}

#[cfg(unix)]
#[test]
fn dev_zero_is_refused_before_anything_is_read() {
    // /dev/zero never ends: read to the end it grew until memory ran out.
    let e = read(Path::new("/dev/zero"), 100).unwrap_err();
    assert_eq!(e.to_string(), "is a device; a regular file is expected");
}

#[test]
fn a_file_beyond_the_cap_is_refused_before_it_is_read() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("big.csv");
    let f = File::create(&p).unwrap();
    f.set_len((3 << 20) + 1).unwrap(); // sparse: no disk space used
    let e = read(&p, 3 << 20).unwrap_err();
    assert_eq!(
        e.to_string(),
        "has 3145729 bytes, more than the 3 MiB this file may have"
    );
    assert!(read(&p, 4 << 20).is_ok());
}

#[test]
fn text_that_is_not_utf8_names_its_line_only() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("b.csv");
    std::fs::write(&p, b"1,2\nsecret\xff\xfe tail\n").unwrap();
    assert!(matches!(read_text(&p, 100), Err(Ok(2))));
}
