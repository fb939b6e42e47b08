//! Tests of the output-file rules: links replaced, devices and pipes written into.

use super::*;
use std::os::unix::fs::symlink;

/// A new temporary folder holding `victim.txt` ("precious\n"), the file a planted link
/// points to; returns the folder and the victim's path.
fn with_victim() -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let victim = dir.path().join("victim.txt");
    std::fs::write(&victim, "precious\n").unwrap();
    (dir, victim)
}

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
    let (dir, victim) = with_victim();
    let d = dir.path();
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
    let (dir, victim) = with_victim();
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
    let (dir, victim) = with_victim();
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

fn make_fifo(path: &Path) {
    let st = std::process::Command::new("mkfifo")
        .arg(path)
        .status()
        .unwrap();
    assert!(st.success(), "mkfifo {}", path.display());
}

fn kind(path: &Path) -> std::fs::FileType {
    std::fs::symlink_metadata(path).unwrap().file_type()
}

/// Reads a FIFO to its end on another thread (the writer's open waits for it).
fn read_fifo(path: &Path) -> std::thread::JoinHandle<Vec<u8>> {
    let path = path.to_path_buf();
    std::thread::spawn(move || std::fs::read(path).unwrap())
}

#[test]
fn a_fifo_named_as_output_receives_the_whole_output_and_stays_a_fifo() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("p");
    make_fifo(&fifo);
    let reader = read_fifo(&fifo);
    let text: String = (0..20_000).map(|i| format!("{i},{}\n", i * i)).collect();
    write(&fifo, text.as_bytes()).unwrap();
    assert_eq!(reader.join().unwrap(), text.as_bytes());
    assert!(kind(&fifo).is_fifo());
    assert!(leftovers(dir.path()).is_empty());

    // Streamed, and committed: the same.
    let reader = read_fifo(&fifo);
    let mut f = OutFile::create(&fifo, 16).unwrap();
    f.write_all(b"a,b\n1,2\n").unwrap();
    f.commit().unwrap();
    assert_eq!(reader.join().unwrap(), b"a,b\n1,2\n");
    assert!(kind(&fifo).is_fifo());
}

#[test]
fn a_format_that_seeks_into_a_fifo_gets_a_clear_error_and_the_fifo_stays() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("p.npz");
    make_fifo(&fifo);
    let reader = read_fifo(&fifo);
    let mut f = OutFile::create(&fifo, 0).unwrap();
    f.write_all(b"x").unwrap();
    let e = f.seek(SeekFrom::Start(0)).unwrap_err().to_string();
    assert!(e.contains("cannot seek") && e.contains("p.npz"), "{e}");
    drop(f);
    reader.join().unwrap();
    assert!(kind(&fifo).is_fifo());
}

#[test]
fn the_null_device_is_written_into_not_replaced() {
    // /dev/null itself: opening it for writing is harmless, and it must stay a device.
    let null = Path::new("/dev/null");
    write(null, b"discarded\n").unwrap();
    let mut f = OutFile::create(null, 4).unwrap();
    f.write_all(b"streamed and discarded\n").unwrap();
    f.commit().unwrap();
    assert!(kind(null).is_char_device());
    assert!(std::fs::read(null).unwrap().is_empty());
}

#[test]
fn a_character_device_made_by_mknod_stays_that_device() {
    // Needs root (CI runs as root); skipped elsewhere.
    let dir = tempfile::tempdir().unwrap();
    let dev = dir.path().join("d");
    // mknod NAME c 1 3: the null device's numbers.
    let made = std::process::Command::new("mknod")
        .arg(&dev)
        .args(["c", "1", "3"])
        .stderr(std::process::Stdio::null())
        .status()
        .unwrap();
    if !made.success() {
        eprintln!("skipped: mknod needs root");
        return;
    }
    write(&dev, b"time,q\n0,1\n").unwrap();
    let m = std::fs::symlink_metadata(&dev).unwrap();
    assert!(m.file_type().is_char_device());
    use std::os::unix::fs::MetadataExt;
    assert_eq!(m.rdev(), libc::makedev(1, 3));
    assert!(leftovers(dir.path()).is_empty());
}

#[test]
fn a_socket_named_as_output_is_refused_and_left_in_place() {
    let dir = tempfile::tempdir().unwrap();
    let sock = dir.path().join("s");
    let _listener = std::os::unix::net::UnixListener::bind(&sock).unwrap();
    let e = write(&sock, b"x").unwrap_err().to_string();
    assert!(e.contains("socket"), "{e}");
    assert!(kind(&sock).is_socket());
    assert!(leftovers(dir.path()).is_empty());
}

#[test]
fn a_folder_named_as_output_is_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    let e = write(dir.path(), b"x").unwrap_err().to_string();
    assert!(e.contains("is a folder"), "{e}");
    assert!(dir.path().is_dir());
}

#[test]
fn a_dash_names_standard_output() {
    assert!(is_stdout(Path::new("-")));
    assert!(!is_stdout(Path::new("./-")));
    assert!(!is_stdout(Path::new("out.csv")));
}
