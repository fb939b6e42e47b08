//! Hardening of the runner, against the Features test FMU's `misbehave` modes
//! (1 error, 2 segfault, 3 abort, 4 exit(0), 5 hang, 6 NaN outputs, 7 fatal, 8 warning, at
//! `misbehave_at`): `--isolate`, `--timeout-per-run`, an in-process `exit()`, `--retry-failed`,
//! the output folder's lock, and the smaller items. Each test is named after the problem it pins.

use std::path::{Path, PathBuf};
use std::process::{Output, Stdio};
use std::time::{Duration, Instant};

use uq_driver::internals as runner;
use uq_driver::spec::Study;
use uq_driver::study::RunOptions;
use uq_driver::uq::method::Design;
use uq_driver::uq::Germ;

use crate::support::refusal::assert_refused;
use crate::support::{
    assert_contains, built_fmu, csv_records, driver, edit, failed, read, run_args, stderr,
    study_head, test_fmus, utf8,
};

/// Eight Monte Carlo points with misbehave_at ~ U(0.3, 1.8) and stop = 1: the points with
/// misbehave_at <= 1 misbehave (by mode `mode`), the others run to the end.
fn study_text(fmu: &Path, mode: i32) -> String {
    format!(
        "{}\
         [method]\nkind = \"mc\"\nsamples = 8\n\
         [[parameters]]\nname = \"misbehave_at\"\ndistribution = \"uniform\"\nlow = 0.3\nhigh = 1.8\n\
         [fixed]\nmisbehave = {mode}\nread_file = \"\"\n\
         [outputs]\nvariables = [\"u_integral\", \"int_out\"]\n\
         [analysis]\nallow_failures = true\n",
        study_head("misbehave", fmu, 1, "stop = 1.0\nstep = 0.1")
    )
}

struct Case {
    dir: tempfile::TempDir,
    study: PathBuf,
    out: PathBuf,
}

fn case(mode: i32) -> Option<Case> {
    let fmu = test_fmus::test_fmu("Features")?;
    let dir = tempfile::tempdir().unwrap();
    let study = crate::support::write_toml(dir.path(), "s", &study_text(&fmu, mode));
    let out = dir.path().join("out");
    Some(Case { dir, study, out })
}

impl Case {
    fn run(&self, extra: &[&str]) -> Output {
        driver()
            .args(run_args(&self.study, &self.out, extra))
            .env("TMPDIR", self.tmp())
            .output()
            .expect("runs")
    }

    /// [`Case::run`], which must succeed.
    #[track_caller]
    fn run_ok(&self, extra: &[&str]) -> Output {
        let o = self.run(extra);
        assert!(o.status.success(), "{}", stderr(&o));
        o
    }

    /// A private temporary folder, to see what the driver leaves behind.
    fn tmp(&self) -> PathBuf {
        let t = self.dir.path().join("tmp");
        std::fs::create_dir_all(&t).unwrap();
        t
    }

    /// `misbehave_at` and the status of each point (`index,misbehave_at,status`; a failure
    /// message may span lines: the FMU's log).
    fn points(&self) -> Vec<(f64, String)> {
        csv_records(&read(&self.out.join("points.csv")))
            .into_iter()
            .skip(1)
            .map(|r| (r[1].parse().unwrap(), r[2].clone()))
            .collect()
    }

    /// Checks that the points that misbehave failed with `needle` in their message and the
    /// others succeeded.
    fn check_failed_with(&self, needle: &str) {
        let points = self.points();
        assert_eq!(points.len(), 8);
        let mut failed = 0;
        for (at, status) in &points {
            if *at <= 1.0 {
                failed += 1;
                assert!(status.contains(needle), "misbehave_at {at}: {status}");
            } else {
                assert_eq!(status, "ok", "misbehave_at {at}");
            }
        }
        assert!(failed >= 2, "the seed gives misbehaving points: {points:?}");
    }

    /// `u_integral.csv` of the output folder.
    fn u_integral(&self) -> String {
        read(&self.out.join("u_integral.csv"))
    }

    fn leftover_temp_folders(&self) -> usize {
        std::fs::read_dir(self.tmp()).unwrap().count()
    }
}

#[test]
fn isolate_a_segfaulting_fmu_fails_its_points_with_the_signal_and_its_last_log_lines() {
    let Some(c) = case(2) else { return };
    c.run_ok(&["--isolate"]);
    c.check_failed_with("killed by signal 11 (SIGSEGV");
    c.check_failed_with("misbehave = 2: segfaulting on purpose");
    assert_eq!(c.leftover_temp_folders(), 0);
}

#[test]
fn isolate_an_aborting_fmu_fails_its_points_with_sigabrt() {
    let Some(c) = case(3) else { return };
    c.run_ok(&["--isolate"]);
    c.check_failed_with("signal 6 (SIGABRT");
}

#[test]
fn isolate_an_fmu_calling_exit_fails_its_points_with_the_exit_status() {
    let Some(c) = case(4) else { return };
    c.run_ok(&["--isolate"]);
    c.check_failed_with("exited with status 0");
}

#[test]
fn isolate_a_hanging_fmu_is_killed_after_the_timeout_and_the_study_goes_on() {
    let Some(c) = case(5) else { return };
    let t0 = Instant::now();
    c.run_ok(&["--isolate", "--timeout-per-run", "0.5", "-t", "2"]);
    c.check_failed_with("longer than --timeout-per-run 0.5 s");
    c.check_failed_with("misbehave = 5: blocking forever");
    assert!(t0.elapsed() < Duration::from_secs(30));
}

#[test]
fn isolate_a_fatal_fmu_fails_only_its_own_points_on_a_fresh_worker() {
    // In one process an fmi2Fatal leaves the FMU unusable for every later point; a worker that
    // saw it is retired, so the points after it run on a fresh copy.
    let Some(c) = case(7) else { return };
    c.run_ok(&["--isolate", "-t", "1"]);
    c.check_failed_with("returned Fatal");
}

#[test]
fn in_process_fatal_stops_the_study_without_failing_the_points_it_made_unrunnable() {
    // After one point's fmi2Fatal in-process, every later point was refused by
    // the FMU layer and stored as *failed*; with --allow-failures the study then analysed the
    // points that happened to finish first (a thread-count-dependent subset), exit 0. Now the
    // study stops at the Fatal, naming the point and --isolate; only that point is stored as
    // failed, and a re-run with --isolate runs the others.
    for threads in ["1", "2"] {
        let Some(c) = case(7) else { return };
        let o = c.run(&["-t", threads]);
        assert!(!o.status.success(), "an in-process Fatal stops the study");
        let err = stderr(&o);
        assert_contains(&err, "After fmi2Fatal");
        assert_contains(&err, "--isolate");
        assert!(!err.contains("an earlier call returned Fatal"), "{err}");
        c.run_ok(&["--isolate", "-t", threads]);
        // Every point at or below 1 failed by its own Fatal, every other one is ok.
        c.check_failed_with("returned Fatal");
    }
}

#[test]
fn isolate_errors_nan_and_warnings_behave_as_in_process() {
    for (mode, needle) in [(1, "returned Error"), (6, "non-finite value")] {
        let Some(c) = case(mode) else { return };
        c.run_ok(&["--isolate"]);
        c.check_failed_with(needle);
        // In-process gives the same statuses and the same numbers.
        let isolated = c.u_integral();
        c.run_ok(&["--fresh"]);
        c.check_failed_with(needle);
        let in_process = c.u_integral();
        assert_eq!(isolated, in_process);
    }
    let Some(c) = case(8) else { return };
    assert!(c.run(&["--isolate"]).status.success());
    assert!(c.points().iter().all(|(_, s)| s == "ok"));
}

#[test]
fn isolate_gives_the_in_process_records_bit_for_bit() {
    // 101 communication points of 0.01 s (times like 0.41000000000000003 reach the worker
    // exactly: its setup is JSON, parsed with exact float round trips) and a Real input.
    let Some(c) = case(0) else { return };
    edit(&c.study, "step = 0.1", "step = 0.01");
    edit(&c.study, "read_file = \"\"", "read_file = \"\"\nu = 0.7");
    assert!(c.run(&["--isolate", "-t", "2"]).status.success());
    let a = c.u_integral();
    assert!(c.run(&["--fresh", "-t", "1"]).status.success());
    let b = c.u_integral();
    assert_eq!(a, b);
}

#[test]
fn in_process_exit_during_a_study_is_reported_with_a_non_zero_status() {
    // An FMU calling exit(0) made `uq-driver run` exit 0 with no output and no
    // message. Two threads: two instances may call exit() at the same moment.
    let Some(c) = case(4) else { return };
    for threads in ["1", "2"] {
        let o = c.run(&["-t", threads, "--fresh"]);
        assert_refused(
            &o,
            &["ended by a call to exit()", "running point ", "--isolate"],
        );
        assert_eq!(c.leftover_temp_folders(), 0);
    }
    // The finished points are in the store: --isolate resumes and completes the study.
    c.run_ok(&["--isolate"]);
    c.check_failed_with("exited with status 0");
}

#[test]
fn in_process_timeout_stops_the_study_naming_the_point_and_keeps_the_store() {
    // An FMU that blocks hung uq-driver forever.
    let Some(c) = case(5) else { return };
    let t0 = Instant::now();
    let o = c.run(&["--timeout-per-run", "0.5", "-t", "1"]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(t0.elapsed() < Duration::from_secs(30));
    assert!(
        err.contains("longer than --timeout-per-run 0.5 s") && err.contains("point "),
        "{err}"
    );
    assert!(
        err.contains("misbehave_at = "),
        "names the point's values: {err}"
    );
    assert_eq!(c.leftover_temp_folders(), 0);
    // The points finished before the hang are kept: --isolate resumes from them.
    let o = c.run(&["--isolate", "--timeout-per-run", "0.5"]);
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("note") || !err.contains("error"), "{err}");
    c.check_failed_with("longer than --timeout-per-run");
}

#[test]
fn failed_points_are_retried_with_retry_failed_and_the_message_names_it() {
    // Failed points were never retried on a re-run; only --fresh helped, and the
    // message did not say so.
    let Some(c) = case(1) else { return };
    // Failures not allowed: the study stops and names --retry-failed.
    edit(&c.study, "allow_failures = true", "allow_failures = false");
    let o = c.run(&["-t", "1"]);
    assert_contains(&failed(&o), "--retry-failed");
    // The FMU is "fixed" (misbehave = 0 is a different study, so the fix is simulated by the
    // same study with failures allowed): a plain re-run keeps the failures and says so ...
    edit(&c.study, "allow_failures = false", "allow_failures = true");
    let o = c.run_ok(&[]);
    assert!(
        stderr(&o).contains("not run again (--retry-failed"),
        "{}",
        stderr(&o)
    );
    let failed_before = c.points().iter().filter(|(_, s)| s != "ok").count();
    assert!(failed_before >= 2);
    // ... and --retry-failed runs them again (they fail again here: same FMU), with no point
    // counted twice in the store.
    let o = c.run_ok(&["--retry-failed"]);
    assert!(
        String::from_utf8_lossy(&o.stdout).contains(&format!("({} resumed)", 8 - failed_before)),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );
    c.check_failed_with("returned Error");
}

#[test]
fn a_retried_point_that_now_succeeds_replaces_its_failure_in_the_store() {
    use uq_driver::internals::store::{Manifest, Record, Store};
    let dir = tempfile::tempdir().unwrap();
    let m = Manifest {
        study_hash: "s".into(),
        fmu_sha256: "f".into(),
        n_points: 2,
        n_values: 1,
    };
    let (s, _) = Store::open(dir.path(), &m, false).unwrap();
    s.append(0, &Record::Failed("first".into())).unwrap();
    s.append(1, &Record::Ok(vec![1.0])).unwrap();
    s.append(0, &Record::Ok(vec![2.0])).unwrap();
    s.append(1, &Record::Failed("later".into())).unwrap();
    drop(s);
    let (_, done) = Store::open(dir.path(), &m, false).unwrap();
    assert_eq!(
        done[0],
        Some(Record::Ok(vec![2.0])),
        "a success replaces a failure"
    );
    assert_eq!(
        done[1],
        Some(Record::Ok(vec![1.0])),
        "a success is never replaced"
    );
}

#[test]
fn two_runs_in_one_output_folder_the_second_is_refused_naming_the_first() {
    // Two runs in one folder both computed every point and doubled the store.
    let Some(c) = case(5) else { return };
    let mut first = driver()
        .args(run_args(&c.study, &c.out, &["-t", "1"]))
        .env("TMPDIR", c.tmp())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    // Wait until the first run holds the lock (it then hangs in the FMU).
    let lock = c.out.join("uq-driver.lock");
    let t0 = Instant::now();
    while !std::fs::read_to_string(&lock).is_ok_and(|t| t.starts_with("pid")) {
        assert!(t0.elapsed() < Duration::from_secs(20), "no lock file");
        std::thread::sleep(Duration::from_millis(20));
    }
    let o = c.run(&["--isolate"]);
    let err = failed(&o);
    assert!(
        err.contains("is in use by another uq-driver run")
            && err.contains(&format!("pid {}", first.id())),
        "{err}"
    );
    // The first one dies without releasing anything: its lock is stale and taken over.
    first.kill().unwrap();
    first.wait().unwrap();
    let o = c.run(&["--isolate", "--timeout-per-run", "0.5"]);
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    assert_contains(&err, "no longer running");
    assert!(!lock.exists(), "released at the end");
}

#[test]
fn an_output_path_that_is_a_file_is_said_to_be_not_a_folder() {
    // Reported as "File exists".
    let Some(c) = case(0) else { return };
    std::fs::write(&c.out, "x").unwrap();
    let o = c.run(&[]);
    let err = failed(&o);
    assert_contains(&err, "exists and is not a folder");
    assert!(!err.contains("File exists"), "{err}");
}

#[test]
fn error_causes_are_printed_once() {
    // Error causes were printed twice.
    let Some(c) = case(1) else { return };
    edit(&c.study, "allow_failures = true", "allow_failures = false");
    let o = c.run(&["-t", "1"]);
    let err = failed(&o);
    assert_eq!(err.matches("fails on purpose").count(), 1, "{err}");
    let o = crate::support::run(&["inspect", "/nonexistent/M.fmu"]);
    let err = stderr(&o);
    assert_eq!(err.matches("No such file").count(), 1, "{err}");
}

#[test]
fn inspect_stopped_by_sigterm_leaves_no_temporary_folder() {
    // A temp folder was left behind when `inspect` was stopped by SIGTERM.
    let vt = built_fmu("VehicleTrack");
    let tmp = tempfile::tempdir().unwrap();
    for delay_ms in [0, 2, 5, 10, 20] {
        let child = driver()
            .args(["inspect", utf8(&vt)])
            .env("TMPDIR", tmp.path())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        std::thread::sleep(Duration::from_millis(delay_ms));
        // SAFETY: kill(2) on the child's own pid with a valid signal.
        unsafe { libc::kill(child.id() as i32, libc::SIGTERM) };
        let o = child.wait_with_output().unwrap();
        let left: Vec<_> = std::fs::read_dir(tmp.path()).unwrap().collect();
        assert!(
            left.is_empty(),
            "after {delay_ms} ms ({:?}): {left:?}",
            o.status
        );
    }
}

#[test]
fn integral_design_values_set_an_integer_random_parameter() {
    // A design for an Integer variable (as integer_uniform gives): each point's int_param is
    // read back by int_out.
    let Some(fmu_path) = test_fmus::test_fmu("Features") else {
        return;
    };
    let text = format!(
        "name = \"int\"\nfmu = {:?}\n[experiment]\nstop = 0.2\nstep = 0.1\n\
         [method]\nkind = \"mc\"\nsamples = 3\n\
         [[parameters]]\nname = \"int_param\"\ndistribution = \"uniform\"\nlow = -10\nhigh = 10\n\
         [outputs]\nvariables = [\"int_out\"]\n",
        utf8(&fmu_path)
    );
    let study = Study::parse(&text, "int.toml", None).unwrap();
    let fmu = uq_driver::fmu::Fmu::open(&fmu_path).unwrap();
    let values = vec![vec![-7.0], vec![0.0], vec![2147483647.0]];
    let design = Design {
        germ: Germ::Uniform,
        points: values.clone(),
        values,
        weights: None,
        warnings: Vec::new(),
        inputs: study.random_inputs(),
    };
    let dir = tempfile::tempdir().unwrap();
    let outcome =
        runner::run_points(&study, &fmu, &design, dir.path(), &RunOptions::default()).unwrap();
    let got: Vec<Vec<f64>> = outcome
        .runs
        .records()
        .unwrap()
        .iter()
        .map(|r| match r {
            Some(uq_driver::internals::store::Record::Ok(v)) => v.clone(),
            other => panic!("{other:?}"),
        })
        .collect();
    assert_eq!(
        got,
        vec![vec![-7.0; 3], vec![0.0; 3], vec![2147483647.0; 3]]
    );
    // A fractional value is refused before any run.
    let bad = Design {
        values: vec![vec![1.5]],
        points: vec![vec![0.5]],
        ..design
    };
    let err = runner::run_points(
        &study,
        &fmu,
        &bad,
        &dir.path().join("b"),
        &RunOptions::default(),
    )
    .unwrap_err()
    .to_string();
    assert_contains(&err, "not a whole number");
}

#[test]
fn model_description_of_an_extracted_folder_is_refused_by_size_before_it_is_read() {
    let dir = tempfile::tempdir().unwrap();
    let md = dir.path().join("modelDescription.xml");
    // A sparse file just over the limit: refused without reading 256 MiB.
    let f = std::fs::File::create(&md).unwrap();
    let limit = uq_driver::fmu::description::ParseLimits::DEFAULT_MAX_BYTES as u64;
    f.set_len(limit + 1).unwrap();
    drop(f);
    let err = uq_driver::fmu::Fmu::open(dir.path())
        .unwrap_err()
        .to_string();
    assert_contains(&err, "more than the limit");
}

/// Runs uq-driver with `args` (and `TMPDIR` = `tmp`), killing it after `limit`: a regression
/// must fail the test, never hang the suite. `None` when it had to be killed.
fn run_limited(args: &[&str], tmp: &Path, limit: Duration) -> Option<Output> {
    let mut child = driver()
        .args(args)
        .env("TMPDIR", tmp)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("runs");
    let t0 = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if t0.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            return None;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    Some(child.wait_with_output().unwrap())
}

impl Case {
    fn run_limited(&self, extra: &[&str], limit: Duration) -> Option<Output> {
        run_limited(&run_args(&self.study, &self.out, extra), &self.tmp(), limit)
    }
}

#[test]
fn isolate_an_fmu_writing_garbage_to_fd_3_neither_hangs_nor_garbles_the_answers() {
    // Fd 3 of a worker was its answer pipe; 12 stray bytes there hung the driver
    // forever, --timeout-per-run or not. The pipes now sit at high descriptors.
    let Some(c) = case(9) else { return };
    let o = c
        .run_limited(
            &["--isolate", "-t", "1", "--timeout-per-run", "5"],
            Duration::from_secs(60),
        )
        .expect("the study must not hang");
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        c.points().iter().all(|(_, s)| s == "ok"),
        "{:?}",
        c.points()
    );
    // The same numbers as in-process with a well-behaved FMU (mode 9 changes no value).
    let isolated = c.u_integral();
    edit(&c.study, "misbehave = 9", "misbehave = 0");
    c.run_ok(&["--fresh", "-t", "1"]);
    let in_process = c.u_integral();
    assert_eq!(isolated, in_process);
}

#[test]
fn isolate_a_crashed_worker_is_noticed_at_once_though_a_helper_it_started_holds_its_pipes() {
    // The driver noticed a crashed worker only when its pipes closed, i.e. when
    // a helper process the FMU had started (here one that lives 20 s) ended.
    let Some(c) = case(10) else { return };
    let t0 = Instant::now();
    let o = c
        .run_limited(&["--isolate", "-t", "1"], Duration::from_secs(60))
        .expect("the study must not hang");
    assert!(o.status.success(), "{}", stderr(&o));
    c.check_failed_with("killed by signal 11 (SIGSEGV");
    c.check_failed_with("misbehave = 10: starting a helper");
    // At least two crashed points: waiting for the helpers would take 40 s.
    assert!(t0.elapsed() < Duration::from_secs(15), "{:?}", t0.elapsed());
}

#[test]
fn isolate_an_fmu_raising_sigterm_on_itself_fails_its_points_and_the_study_finishes() {
    // A worker dead of SIGTERM was taken for a driver being stopped from
    // outside, so the study stopped at that point on every re-run and could never finish.
    let Some(c) = case(11) else { return };
    let o = c
        .run_limited(&["--isolate", "-t", "1"], Duration::from_secs(60))
        .expect("the study must not hang");
    assert!(o.status.success(), "{}", stderr(&o));
    c.check_failed_with("SIGTERM");
    c.check_failed_with("misbehave = 11: raising SIGTERM");
}

#[test]
fn in_process_crash_says_which_point_crashed_and_keeps_the_signal_as_exit_status() {
    // An FMU crashing in-process killed the driver printing only the plan line.
    use std::os::unix::process::ExitStatusExt;
    for (mode, sig, name) in [(2, 11, "SIGSEGV"), (3, 6, "SIGABRT")] {
        let Some(c) = case(mode) else { return };
        for threads in ["1", "2"] {
            let o = c
                .run_limited(&["-t", threads, "--fresh"], Duration::from_secs(60))
                .expect("ends");
            let err = stderr(&o);
            assert_eq!(o.status.signal(), Some(sig), "{err}");
            assert_contains(&err, &format!("killed by {name}"));
            assert_contains(&err, "running point ");
            assert_contains(&err, "misbehave_at = ");
            assert_contains(&err, "--isolate");
        }
        // The finished points are kept: --isolate resumes and completes the study.
        c.run_ok(&["--isolate"]);
        c.check_failed_with(name);
    }
}

#[test]
fn simulate_an_fmu_calling_exit_fails_with_a_message_and_a_non_zero_status() {
    // `simulate` exited 0 with no CSV and no message.
    let Some((fmu, dir)) = test_fmus::test_fmu_and_dir("Features") else {
        return;
    };
    let csv = dir.path().join("f4.csv");
    let o = run_limited(
        &[
            "simulate",
            utf8(&fmu),
            "--set",
            "misbehave=4",
            "--out",
            utf8(&csv),
        ],
        dir.path(),
        Duration::from_secs(60),
    )
    .expect("ends");
    assert_refused(&o, &["called exit()", "Features.fmu"]);
}

#[test]
fn simulate_to_stdout_keeps_what_the_fmu_prints_out_of_the_csv() {
    // The FMU's printf output was interleaved with the CSV rows on stdout.
    let Some((fmu, dir)) = test_fmus::test_fmu_and_dir("Features") else {
        return;
    };
    let o = run_limited(
        &[
            "simulate",
            utf8(&fmu),
            "--set",
            "misbehave=12",
            "--output",
            "u_integral",
        ],
        dir.path(),
        Duration::from_secs(60),
    )
    .expect("ends");
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8(o.stdout.clone()).unwrap();
    assert!(out.starts_with("time,u_integral\n"), "{out}");
    assert_eq!(out.lines().count(), 12, "{out}");
    assert!(!out.contains("prints to stdout"), "{out}");
    assert!(stderr(&o).contains("misbehave = 12 prints to stdout"));
}
