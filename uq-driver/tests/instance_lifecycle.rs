//! The instance lifecycle of a study, against the Features test FMU's `reset_bug`
//! (a broken `fmi2Reset`), `name_dir` (working files keyed on the instance name) and `quiet`
//! (messages only with logging on): instances reused through a broken `fmi2Reset` gave
//! failures or silently wrong numbers, every instance was named `uq-driver`, and FMUs were
//! always instantiated with `loggingOn = false`. Each test is named after the problem it
//! pins. Reference values are in closed form: with `u` = 0.7 held, `u_integral`(t) = 0.7 t and
//! `u_gain` = 0.7 gain.

use std::path::{Path, PathBuf};
use std::process::Output;

use crate::support::csv::Csv;
use crate::support::{
    assert_contains, csv_records, failed, read, run, run_args, run_ok, stderr, study_head,
    test_fmus, utf8, write_toml,
};

/// Eight Monte Carlo points with gain ~ U(1, 2), u = 0.7, stop 1 s, step 0.1 s; `fixed`
/// extra `[fixed]` lines.
fn study_text(fmu: &Path, fixed: &str) -> String {
    format!(
        "{}\
         [method]\nkind = \"mc\"\nsamples = 8\n\
         [[parameters]]\nname = \"gain\"\ndistribution = \"uniform\"\nlow = 1.0\nhigh = 2.0\n\
         [fixed]\nread_file = \"\"\nu = 0.7\n{fixed}\n\
         [outputs]\nvariables = [\"u_integral\", \"u_gain\", \"file_value\"]\n\
         [analysis]\nallow_failures = true\n",
        study_head("lifecycle", fmu, 1, "stop = 1.0\nstep = 0.1")
    )
}

struct Case {
    dir: tempfile::TempDir,
    study: PathBuf,
}

fn case(fixed: &str) -> Option<Case> {
    let fmu = test_fmus::test_fmu("Features")?;
    let dir = tempfile::tempdir().unwrap();
    let study = write_toml(dir.path(), "s", &study_text(&fmu, fixed));
    Some(Case { dir, study })
}

impl Case {
    fn out(&self, name: &str) -> PathBuf {
        self.dir.path().join(name)
    }

    /// `run` into folder `name` with `extra` options; must succeed.
    fn run(&self, name: &str, extra: &[&str]) -> Output {
        let o = self.try_run(name, extra);
        assert!(o.status.success(), "{extra:?}: {}", stderr(&o));
        o
    }

    /// `run` into folder `name` with `extra` options.
    fn try_run(&self, name: &str, extra: &[&str]) -> Output {
        let out = self.out(name);
        let mut args = run_args(&self.study, &out, &["--no-report"]);
        args.extend_from_slice(extra);
        run(&args)
    }

    fn csv(&self, name: &str, file: &str) -> String {
        read(&self.out(name).join(file))
    }

    /// The statuses of points.csv (`index,<parameter>,status`), in point order.
    fn statuses(&self, name: &str) -> Vec<String> {
        csv_records(&self.csv(name, "points.csv"))
            .into_iter()
            .skip(1)
            .map(|r| r[2].clone())
            .collect()
    }
}

/// The gain of each point, from points.csv (`index,gain,status`).
fn gains(points: &str) -> Vec<f64> {
    points
        .lines()
        .skip(1)
        .filter_map(|l| l.split(',').nth(1)?.parse().ok())
        .collect()
}

/// Every run's series of output `name`, from `export --runs`: (run, time, value).
fn runs(dir: &Path, name: &str) -> Vec<(usize, f64, f64)> {
    run_ok(&["export", utf8(dir), "--runs"]);
    let csv = Csv::read(&dir.join("runs/runs.csv"));
    let col = csv.index(name);
    csv.numbers()
        .into_iter()
        .map(|r| (r[0] as usize, r[1], r[col]))
        .collect()
}

/// Checks `u_integral` = 0.7 t and `u_gain` = 0.7 gain (the design's gain of each run, read
/// from `file_value` when `name_dir` is set, else only its range) in every run.
fn check_closed_form(dir: &Path) {
    let integral = runs(dir, "u_integral");
    assert_eq!(integral.len(), 8 * 11);
    for (run, t, v) in &integral {
        assert!((v - 0.7 * t).abs() < 1e-12, "run {run} at t = {t}: {v}");
    }
    for (run, _, v) in runs(dir, "u_gain") {
        assert!((0.7..=1.4).contains(&v), "run {run}: u_gain {v}");
    }
}

#[test]
fn a_reset_that_returns_error_fails_no_point_in_process_or_in_workers() {
    // Every second point failed (every point under --isolate).
    let Some(c) = case("reset_bug = 1") else {
        return;
    };
    let mut csvs = Vec::new();
    for (name, extra) in [
        ("t1", &["-t", "1"][..]),
        ("t2", &["-t", "2"]),
        ("iso", &["--isolate", "-t", "2"]),
    ] {
        let o = c.run(name, extra);
        assert!(c.statuses(name).iter().all(|s| s == "ok"), "{name}");
        let err = stderr(&o);
        assert_eq!(err.matches("warning: fmi2Reset failed").count(), 1, "{err}");
        assert_contains(&err, "reset_bug = 1: fmi2Reset fails on purpose");
        assert_contains(&err, "every point now runs on a fresh instance");
        check_closed_form(&c.out(name));
        csvs.push(c.csv(name, "u_integral.csv") + &c.csv(name, "u_gain.csv"));
    }
    assert!(csvs.iter().all(|s| *s == csvs[0]));
}

#[test]
fn a_reset_that_forgets_start_values_gives_the_numbers_of_fresh_instances() {
    // Silently wrong numbers, different per thread count and under --isolate.
    let Some(c) = case("reset_bug = 2") else {
        return;
    };
    let mut csvs = Vec::new();
    for (name, extra) in [
        ("t1", &["-t", "1"][..]),
        ("t2", &["-t", "2"]),
        ("iso", &["--isolate"]),
    ] {
        let o = c.run(name, extra);
        let err = stderr(&o);
        assert_eq!(
            err.matches("the FMU's results after fmi2Reset differ from a fresh instance's")
                .count(),
            1,
            "{err}"
        );
        check_closed_form(&c.out(name));
        csvs.push(c.csv(name, "u_integral.csv"));
        // Kept in summary.json too (printed once, during the run).
        let summary = c.csv(name, "summary.json");
        assert_contains(&summary, "differ from a fresh instance");
    }
    assert!(csvs.iter().all(|s| *s == csvs[0]));
}

#[test]
fn a_reset_that_fails_after_some_runs_only_gives_a_fresh_instance_and_one_warning() {
    // A reset that fails after the self-check passed (here after runs with gain < 1.5):
    // the point runs on a fresh instance, never fails, and the warning comes once.
    let Some(c) = case("reset_bug = 3") else {
        return;
    };
    let design = |name: &str| gains(&c.csv(name, "points.csv"));
    for (name, extra) in [("t1", &["-t", "1"][..]), ("iso", &["--isolate", "-t", "1"])] {
        let o = c.run(name, extra);
        let gains = design(name);
        // The seed puts point 0 above 1.5 (the check passes) and later points below.
        assert!(
            gains[0] >= 1.5 && gains.iter().any(|g| *g < 1.5),
            "{gains:?}"
        );
        assert!(c.statuses(name).iter().all(|s| s == "ok"), "{name}");
        let err = stderr(&o);
        assert!(!err.contains("differ from a fresh"), "{err}");
        assert_eq!(err.matches("warning: fmi2Reset failed").count(), 1, "{err}");
        assert_contains(&err, "reset_bug = 3");
        check_closed_form(&c.out(name));
    }
    assert_eq!(
        c.csv("t1", "u_integral.csv"),
        c.csv("iso", "u_integral.csv")
    );
}

/// The instance files the Features FMU wrote in `dir` (`<instanceName>.txt`), by name.
fn instance_files(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// Whether `file` is `uq-driver-<pid>-<n>.txt`.
fn is_unique_name(file: &str) -> bool {
    let Some(rest) = file
        .strip_prefix("uq-driver-")
        .and_then(|r| r.strip_suffix(".txt"))
    else {
        return false;
    };
    let parts: Vec<&str> = rest.split('-').collect();
    parts.len() == 2 && parts.iter().all(|p| p.parse::<u64>().is_ok())
}

#[test]
fn concurrent_instances_have_names_of_their_own() {
    // Every instance was named `uq-driver`; an FMU that keys its files on the instance
    // name read another run's file (61 of 120 rows wrong with two threads).
    let Some(c) = case("") else { return };
    let base = std::fs::read_to_string(&c.study).unwrap();
    // Names: fresh instances, one per run (8). Reused: the self-check's instance, then one
    // per rayon job that runs points; with one thread that is one or two jobs (at most 3 names),
    // with two a busy machine may steal and split down to one point a job (up to 8).
    for (name, extra, names_expected) in [
        ("reused", &["-t", "2"][..], 2..=8),
        ("reused-one-thread", &["-t", "1"], 2..=3),
        ("fresh", &["-t", "2", "--fresh-instances"], 8..=8),
        ("iso", &["--isolate", "-t", "2", "--fresh-instances"], 8..=8),
    ] {
        let files = c.dir.path().join(format!("names-{name}"));
        std::fs::create_dir(&files).unwrap();
        let text = base.replace(
            "u = 0.7\n",
            &format!("u = 0.7\nname_dir = {:?}\n", utf8(&files)),
        );
        std::fs::write(&c.study, text).unwrap();
        c.run(name, extra);
        let names = instance_files(&files);
        assert!(names.iter().all(|n| is_unique_name(n)), "{names:?}");
        assert!(names_expected.contains(&names.len()), "{name}: {names:?}");
        // Each run read back its own gain.
        let gains = gains(&c.csv(name, "points.csv"));
        for (run, _, v) in runs(&c.out(name), "file_value") {
            assert_eq!(v, gains[run], "{name}: run {run}");
        }
        check_closed_form(&c.out(name));
    }
}

#[test]
fn a_study_with_a_single_point_to_run_makes_no_reset_self_check() {
    // The self-check costs one extra run per study, none when one point is left: a broken
    // reset is then never called, and nothing warns.
    let Some(c) = case("reset_bug = 1") else {
        return;
    };
    // Seven points first (the self-check warns), then the one left.
    let seven = c.try_run("one", &["--max-points", "7"]);
    assert!(
        stderr(&seven).contains("fmi2Reset failed"),
        "{}",
        stderr(&seven)
    );
    let one = c.run("one", &[]);
    assert!(!stderr(&one).contains("fmi2Reset"), "{}", stderr(&one));
    assert!(c.statuses("one").iter().all(|s| s == "ok"));
}

#[test]
fn fresh_instances_and_fmu_logging_change_no_result_of_a_well_behaved_fmu() {
    let Some(c) = case("") else { return };
    let o = c.run("base", &["-t", "2"]);
    assert!(!stderr(&o).contains("warning"), "{}", stderr(&o));
    for (name, extra) in [
        ("fresh", &["--fresh-instances", "-t", "2"][..]),
        ("logging", &["--fmu-logging", "-t", "1"]),
        ("iso-logging", &["--fmu-logging", "--isolate"]),
    ] {
        let o = c.run(name, extra);
        // Logging on: the FMU's info messages are kept, not printed.
        assert!(!stderr(&o).contains("[fmu "), "{}", stderr(&o));
        for file in [
            "u_integral.csv",
            "u_gain.csv",
            "file_value.csv",
            "points.csv",
        ] {
            assert_eq!(c.csv("base", file), c.csv(name, file), "{name}: {file}");
        }
    }
}

#[test]
fn fmu_logging_brings_the_messages_of_an_fmu_that_logs_only_when_asked() {
    // Instances were always made with loggingOn = false, so an FMU that logs only when
    // asked (pythonfmu) gave "the FMU logged nothing", even for its errors.
    let Some(c) = case("misbehave = 1\nquiet = true") else {
        return;
    };
    // misbehave_at ~ U(0.3, 1.8): the runs with misbehave_at <= 1 fail.
    let text = std::fs::read_to_string(&c.study).unwrap().replace(
        "name = \"gain\"\ndistribution = \"uniform\"\nlow = 1.0\nhigh = 2.0",
        "name = \"misbehave_at\"\ndistribution = \"uniform\"\nlow = 0.3\nhigh = 1.8",
    );
    std::fs::write(&c.study, text).unwrap();
    let said = "misbehave = 1: fmi2DoStep fails on purpose at t = ";
    c.run("quiet", &[]);
    let statuses = c.statuses("quiet");
    assert!(
        statuses.iter().filter(|s| *s != "ok").count() >= 2,
        "{statuses:?}"
    );
    for s in statuses.iter().filter(|s| *s != "ok") {
        assert_contains(s, "the FMU logged nothing");
        assert_contains(s, "--fmu-logging");
        assert!(!s.contains(said), "{s}");
    }
    for (name, extra) in [
        ("logging", &["--fmu-logging"][..]),
        ("iso", &["--fmu-logging", "--isolate"]),
    ] {
        c.run(name, extra);
        let now = c.statuses(name);
        for (before, s) in statuses.iter().zip(&now) {
            assert_eq!(before == "ok", s == "ok", "{name}");
            if s != "ok" {
                assert!(s.contains(said), "{name}: {s}");
                assert!(!s.contains("logged nothing"), "{name}: {s}");
            }
        }
    }
    // simulate: the message in the error, and on stderr as it comes.
    let fmu = test_fmus::test_fmu("Features").unwrap();
    let sim = |extra: &[&str]| {
        let mut args = vec![
            "simulate",
            utf8(&fmu),
            "--set",
            "misbehave=1",
            "--set",
            "quiet=true",
        ];
        args.extend_from_slice(extra);
        run(&args)
    };
    let quiet = sim(&[]);
    assert!(!quiet.status.success());
    assert!(
        stderr(&quiet).contains("--fmu-logging"),
        "{}",
        stderr(&quiet)
    );
    let loud = sim(&["--fmu-logging"]);
    assert!(!loud.status.success());
    assert!(stderr(&loud).contains(said), "{}", stderr(&loud));
}

#[test]
fn a_fatal_reset_in_the_self_check_keeps_the_fresh_run_and_stops_the_study() {
    // The reset self-check's second run found fmi2Reset returning fmi2Fatal: the point's own
    // run on a fresh instance had succeeded but was stored as failed. Now it is kept, the
    // study stops (no further call in this process), and a re-run with --isolate finishes
    // with the numbers of fresh instances.
    let Some(c) = case("reset_bug = 4") else {
        return;
    };
    let o = c.try_run("t1", &["-t", "1"]);
    let err = failed(&o);
    assert!(
        err.contains("reset self-check") && err.contains("After fmi2Fatal"),
        "{err}"
    );
    let o = c.run("t1", &["--isolate"]);
    let all = format!("{}{}", String::from_utf8_lossy(&o.stdout), stderr(&o));
    assert!(
        all.contains("(1 resumed)"),
        "the fresh run of the first point was kept: {all}"
    );
    assert!(c.statuses("t1").iter().all(|s| s == "ok"));
    check_closed_form(&c.out("t1"));
    c.run("fresh", &["--fresh-instances"]);
    assert_eq!(
        c.csv("t1", "u_integral.csv"),
        c.csv("fresh", "u_integral.csv")
    );
}
