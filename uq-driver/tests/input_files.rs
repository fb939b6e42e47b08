//! Files a study or a run reads by name: the `[inputs]` CSV and the data files of the FMUs'
//! parameters (VehicleTrack's `profile_file`). A variable given a value before the run is
//! never also a column of the input file (the file would silently replace it); a FIFO or a
//! device is refused without blocking, and no error quotes a file's contents.

use std::path::Path;
use std::process::Output;
use std::time::Duration;

use crate::support::refusal::assert_refused;
use crate::support::wheel::{wheel_fmu, write_study};
use crate::support::{
    assert_contains, built_fmu, driver, run, run_study, stderr, utf8, write_file,
};

/// Runs `uq-driver args`, failing the test if it has not ended within 60 s (a FIFO opened
/// for reading blocks for ever).
fn run_within(args: &[&str]) -> Output {
    let mut child = driver()
        .args(args)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let start = std::time::Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > Duration::from_secs(60) {
            child.kill().unwrap();
            panic!("uq-driver {args:?} hung");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.wait_with_output().unwrap()
}

fn mkfifo(path: &Path) -> bool {
    let made = std::process::Command::new("mkfifo").arg(path).status();
    matches!(made, Ok(s) if s.success())
}

/// A random parameter that was also a column of the `[inputs]` file: exit 0, every run used
/// the file's values, Std = 0, and points.csv listed the sampled values as if used. A
/// `[fixed]` value or a `--set` that was also a column was accepted silently too.
#[test]
fn a_random_or_fixed_parameter_that_is_also_an_input_column_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("k.csv"), "time,K\n0,100\n5,100\n").unwrap();
    let experiment = "start = 0.0\nstop = 1.0\nstep = 0.05";
    let method = "kind = \"mc\"\nsamples = 8";
    let inputs = "[inputs]\nfile = \"k.csv\"\n";
    let random = write_study(dir.path(), "random", "r", 1, experiment, method, inputs);
    let o = run_study(&random, &dir.path().join("r"), &["--no-report"]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains(
            "'K' is a random parameter ([[parameters]]) and also a column of the input file"
        ) && err.contains("remove the column from the file, or 'K' from the study"),
        "{err}"
    );
    assert!(!dir.path().join("r/q.csv").exists());
    // [fixed]: a study with C random and K fixed.
    let fixed = write_study(
        dir.path(),
        "fixed",
        "f",
        1,
        experiment,
        method,
        &format!("[fixed]\nK = 120.0\n{inputs}"),
    );
    let text = std::fs::read_to_string(&fixed).unwrap().replacen(
        "[[parameters]]\nname = \"K\"\nmean = 100.0\nstd = 10.0\n",
        "",
        1,
    );
    std::fs::write(&fixed, text).unwrap();
    let o = run_study(&fixed, &dir.path().join("f"), &["--no-report"]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert_contains(
        &err,
        "'K' is given a value in [fixed] and also a column of the input file",
    );
    // simulate --set K=... --input k.csv.
    let k_csv = dir.path().join("k.csv");
    let fmu = wheel_fmu();
    let o = run(&[
        "simulate",
        utf8(&fmu),
        "--stop",
        "0.1",
        "--set",
        "K=120",
        "--input",
        utf8(&k_csv),
    ]);
    assert_refused(&o, &["'K' is given a value (--set) and also a column"]);
    // The file alone drives K: accepted.
    let o = run(&[
        "simulate",
        utf8(&fmu),
        "--stop",
        "0.1",
        "--input",
        utf8(&k_csv),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
}

/// A FIFO given as `[inputs] file` or as `profile_file` hung the run; `/dev/zero` grew to
/// ~2 GB before failing.
#[cfg(unix)]
#[test]
fn input_and_profile_files_that_are_fifos_or_devices_are_refused_without_hanging() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("signals.csv");
    if !mkfifo(&fifo) {
        eprintln!("mkfifo unavailable: skipped");
        return;
    }
    let wheel = wheel_fmu();
    for (file, kind) in [
        (utf8(&fifo), "is a FIFO (named pipe)"),
        ("/dev/zero", "is a device"),
    ] {
        let o = run_within(&["simulate", utf8(&wheel), "--stop", "0.1", "--input", file]);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{err}");
        assert!(
            err.contains(&format!(
                "input file {file}: {kind}; a regular file is expected"
            )),
            "{err}"
        );
    }
    // In a study: refused before any run.
    let study = write_study(
        dir.path(),
        "s",
        "s",
        1,
        "start = 0.0\nstop = 1.0\nstep = 0.05",
        "kind = \"mc\"\nsamples = 4",
        &format!("[inputs]\nfile = {:?}\n", utf8(&fifo)),
    );
    let out = dir.path().join("out");
    let o = run_within(&["run", utf8(&study), "--out", utf8(&out), "--no-report"]);
    assert_refused(&o, &["is a FIFO (named pipe)"]);
    // VehicleTrack's measured profile.
    let vt = built_fmu("VehicleTrack");
    for (file, kind) in [
        (utf8(&fifo), "is a FIFO (named pipe)"),
        ("/dev/zero", "is a device"),
    ] {
        let set = format!("profile_file={file}");
        let args = ["simulate", utf8(&vt), "--stop", "0.01", "--set"];
        let o = run_within(&[&args[..], &[&set, "--set", "irregularity=10"]].concat());
        assert_refused(&o, &[&format!("profile_file '{file}': {kind}")]);
    }
}

/// An FMU error about `profile_file = "/etc/shadow"` quoted the file's second line (kept with
/// the failed point in points.csv); an input file's errors quoted its cells.
#[test]
fn errors_about_input_and_profile_files_never_quote_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let secret = write_file(
        dir.path(),
        "shadow",
        "root:$6$SECRETHASH:19000:0:99999:7:::\ndaemon:*:19000:0:99999:7:::\n",
    );
    let vt = built_fmu("VehicleTrack");
    let set = format!("profile_file={}", utf8(&secret));
    let o = run(&[
        "simulate",
        utf8(&vt),
        "--stop",
        "0.01",
        "--set",
        &set,
        "--set",
        "irregularity=10",
    ]);
    let err = assert_refused(&o, &["line 2: expected two numbers"]);
    assert!(!err.contains("SECRET") && !err.contains("daemon"), "{err}");
    // An input file with a header of the wheel's variables, then a secret in a cell.
    // The wheel simulated with the input `text` is refused, the error without the secret.
    let refused = |text: &str, needle: &str| {
        let input = write_file(dir.path(), "in.csv", text);
        let wheel = wheel_fmu();
        let o = run(&[
            "simulate",
            utf8(&wheel),
            "--stop",
            "0.1",
            "--input",
            utf8(&input),
        ]);
        let err = assert_refused(&o, &[needle]);
        assert!(!err.contains("SECRET"), "{err}");
    };
    refused("time,K\n0,100\n1,SECRET-1\n", "line 3, column 2");
    // A header that names no variable: the column's number, not its text.
    refused(
        "time,SECRET-2\n0,1\n",
        "column 2 names no variable of the FMU",
    );
    // A misspelt column: the FMU's own name of the parameter it may mean.
    refused("time,KK\n0,100\n", "them); did you mean `K`?");
}
