//! uq-driver used as a library: bad studies and options give typed errors
//! instead of panics, wrong results or files in the current folder, and a study leaves the
//! host's process alone (no `atexit` handler, no signal handlers, no `_exit`) unless the host
//! opts in with `install_process_guards`.
//!
//! No test of this test binary calls `install_process_guards` (it would change every test of
//! the process, see `main.rs`): the opted-in behaviour is the command line's, tested in
//! `isolation.rs`.

use std::path::Path;
use std::time::Duration;

use uq_driver::spec::{Experiment, Study, StudyError};
use uq_driver::study::{run_study, Outcome, RunError, RunOptions, StudyRunError};
use uq_driver::study::{simulate, PointError};

use crate::support::{assert_contains, wheel};

fn study(method: &str) -> Study {
    let experiment = "start = 0.0\nstop = 1.0\nstep = 0.01";
    let text = wheel::study_text("lib", 1, experiment, method, "");
    Study::parse(&text, "inline", None).unwrap()
}

fn opts() -> RunOptions {
    RunOptions::default()
        .with_threads(2)
        .with_no_report(true)
        .with_fresh(true)
}

fn invalid_message(r: Result<Outcome, StudyRunError>) -> String {
    match r {
        Err(StudyRunError::Study(e @ StudyError::Invalid { .. })) => e.to_string(),
        Err(e) => panic!("expected an invalid-study error, got {e}"),
        Ok(_) => panic!("expected an invalid-study error, got Ok"),
    }
}

/// `run_study` did not validate a `Study` whose public fields were changed
/// after `Study::parse`: stop < start returned `Ok` with the initial state as the result, no
/// parameters ran 50 identical runs, no outputs analysed nothing, and step 0 or NaN gave a
/// misleading "inf B of memory" size error.
#[test]
fn run_study_refuses_a_study_changed_into_an_invalid_one() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let base = study("kind = \"lhs\"\nsamples = 20");

    let mut s = base.clone();
    s.experiment = Experiment {
        start: 1.0,
        stop: 0.0,
        step: 0.1,
    };
    let m = invalid_message(run_study(&s, &out, &opts()));
    assert_contains(&m, "start < stop");

    for step in [0.0, f64::NAN] {
        let mut s = base.clone();
        s.experiment.step = step;
        let m = invalid_message(run_study(&s, &out, &opts()));
        assert_contains(&m, "step");
        assert!(!m.contains("memory"), "{m}");
    }

    let mut s = base.clone();
    s.parameters.clear();
    let m = invalid_message(run_study(&s, &out, &opts()));
    assert_contains(&m, "no random parameters");

    let mut s = base.clone();
    s.outputs.clear();
    let m = invalid_message(run_study(&s, &out, &opts()));
    assert_contains(&m, "nothing to analyse");

    let mut s = base.clone();
    s.parameters[1].name = "K".into();
    let m = invalid_message(run_study(&s, &out, &opts()));
    assert_contains(&m, "listed twice");

    // Nothing was written for any of them.
    assert!(!out.exists());
    // The unchanged study runs.
    let Outcome::Study(r) = run_study(&base, &out, &opts()).unwrap() else {
        panic!("a study");
    };
    assert_eq!(r.outputs[0].times.len(), 101);
}

/// `run_study(&study, Path::new(""), …)` wrote `store/`, `points.csv`, `q.csv`
/// … into the host's current folder.
#[test]
fn an_empty_output_folder_is_refused() {
    let s = study("kind = \"lhs\"\nsamples = 10");
    match run_study(&s, Path::new(""), &opts()) {
        Err(StudyRunError::Run(RunError::NoOutDir)) => {}
        Err(e) => panic!("{e}"),
        Ok(_) => panic!("an empty output path was accepted"),
    }
}

/// `timeout_per_run` without `isolate` ended the host process with
/// `_exit(1)` when a run overran; a library caller now gets a typed error before anything
/// runs, saying why and what to use instead.
#[test]
fn timeout_per_run_in_process_is_refused_without_the_process_guards() {
    let dir = tempfile::tempdir().unwrap();
    let s = study("kind = \"lhs\"\nsamples = 50");
    let o = opts().with_timeout_per_run(Duration::from_millis(1));
    match run_study(&s, &dir.path().join("out"), &o) {
        Err(StudyRunError::Run(RunError::Options(m))) => {
            assert!(
                m.contains("isolate") && m.contains("install_process_guards"),
                "{m}"
            );
        }
        Err(e) => panic!("{e}"),
        Ok(_) => panic!("timeout_per_run in-process was accepted"),
    }
    // threads = 0 was silently made 1 ; points outside the design were dropped.
    let o = opts().with_threads(0);
    assert!(matches!(
        run_study(&s, &dir.path().join("out0"), &o),
        Err(StudyRunError::Run(RunError::Options(_)))
    ));
    let o = opts().with_points(vec![1_000_000]);
    match run_study(&s, &dir.path().join("out1"), &o) {
        Err(StudyRunError::Run(RunError::Options(m))) => assert!(m.contains("1000000"), "{m}"),
        Err(e) => panic!("{e}"),
        Ok(_) => panic!("a point outside the design was accepted"),
    }
}

/// `simulate` with an empty time grid panicked ("at least one time"), and
/// `Experiment::times()` of a 1e21-point grid panicked with "capacity overflow".
#[test]
fn an_empty_or_invalid_time_grid_is_a_typed_error() {
    let fmu = uq_driver::fmu::Fmu::open(&wheel::wheel_fmu()).unwrap();
    let q = ["q".to_owned()];
    for times in [vec![], vec![0.0, 0.5, 0.5], vec![0.0, f64::NAN]] {
        match simulate(&fmu, &[], &q, None, &times) {
            Err(RunError::Point(PointError::Times(_))) => {}
            other => panic!("{times:?}: {other:?}"),
        }
    }
    let huge = Experiment {
        start: 0.0,
        stop: 1e12,
        step: 1e-9,
    };
    assert!(huge.times().is_empty());
    assert!(huge.try_times().is_err());
    let bad = Experiment {
        start: 1.0,
        stop: 0.0,
        step: 0.1,
    };
    assert!(bad.times().is_empty());
    let good = Experiment {
        start: 0.0,
        stop: 1.0,
        step: 0.25,
    };
    assert_eq!(good.times(), vec![0.0, 0.25, 0.5, 0.75, 1.0]);
}

/// The handler of `sig` now (its address).
fn handler_of(sig: i32) -> usize {
    // SAFETY: sigaction with a null new action only reads the current one into `old`.
    unsafe {
        let mut old: libc::sigaction = std::mem::zeroed();
        assert_eq!(libc::sigaction(sig, std::ptr::null(), &mut old), 0);
        old.sa_sigaction
    }
}

/// An in-process study installed SIGSEGV, SIGBUS, SIGILL, SIGFPE and SIGABRT
/// handlers for the rest of the host's process.
#[test]
fn an_in_process_study_leaves_the_signal_handlers_alone() {
    let signals = [
        libc::SIGSEGV,
        libc::SIGBUS,
        libc::SIGILL,
        libc::SIGFPE,
        libc::SIGABRT,
        libc::SIGINT,
        libc::SIGTERM,
    ];
    let before: Vec<usize> = signals.iter().map(|&s| handler_of(s)).collect();
    let dir = tempfile::tempdir().unwrap();
    run_study(
        &study("kind = \"lhs\"\nsamples = 10"),
        &dir.path().join("out"),
        &opts(),
    )
    .unwrap();
    let after: Vec<usize> = signals.iter().map(|&s| handler_of(s)).collect();
    assert_eq!(before, after);
}

/// Set in the child process of the next test.
const HOST_EXIT_CHILD: &str = "UQ_DRIVER_TEST_HOST_EXIT_CHILD";

/// The name the test harness knows the test function `name` of this module by
/// (`library::name`), to run it alone in a child process.
fn test_name(name: &str) -> String {
    let module = module_path!().split_once("::").map_or("", |m| m.1);
    format!("{module}::{name}")
}

/// While a study ran in a background thread, the host's own
/// `std::process::exit(0)` became exit status 1 with a message blaming an FMU (an `atexit`
/// handler registered by the study). The host (this test binary, run again as a child)
/// exits with its own status and no such message.
#[test]
fn the_hosts_own_exit_during_a_study_keeps_its_status() {
    if let Some(out) = std::env::var_os(HOST_EXIT_CHILD) {
        let out = std::path::PathBuf::from(out);
        let mut s = study("kind = \"lhs\"\nsamples = 5000");
        s.experiment.stop = 5.0;
        let dir = out.clone();
        std::thread::spawn(move || {
            let _ = run_study(&s, &dir, &opts());
        });
        // Wait until the runs have started (the store exists), then end the process.
        for _ in 0..2000 {
            if out.join("store").exists() {
                break;
            }
            std::thread::sleep(Duration::from_millis(5));
        }
        std::thread::sleep(Duration::from_millis(20));
        if !out.join("summary.json").exists() {
            eprintln!("host: exit(0) while the study runs");
        }
        std::process::exit(0);
    }
    let dir = tempfile::tempdir().unwrap();
    let child = std::process::Command::new(std::env::current_exe().unwrap())
        .args([
            "--exact",
            &test_name("the_hosts_own_exit_during_a_study_keeps_its_status"),
            "--nocapture",
        ])
        .env(HOST_EXIT_CHILD, dir.path().join("out"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&child.stderr);
    assert!(
        dir.path().join("out").join("store").exists(),
        "the study did not start"
    );
    assert!(
        stderr.contains("host: exit(0) while the study runs"),
        "the study was not running at exit: {stderr}"
    );
    assert_eq!(child.status.code(), Some(0), "{stderr}");
    assert!(!stderr.contains("called exit()"), "{stderr}");
}
