//! Oversized designs: `samples = 1000000000000`,
//! `step = 1e-12` and `stop = 1e15` with `step = 1` used to end in an out-of-memory abort
//! (exit 134) and an empty output folder. They must end in a clear refusal with the estimate
//! and the limit, whatever `--yes` says, before anything is allocated, with the output folder
//! as it was. A study of more than 100 000 runs starts only with `--yes`.

use std::path::{Path, PathBuf};

use crate::support::refusal::assert_refused;
use crate::support::wheel::{self, wheel_fmu};
use crate::support::{
    driver, plan_and_run_shards, run, run_ok, run_study, stderr, utf8, write_file,
};

fn study(dir: &Path, name: &str, experiment: &str, method: &str) -> PathBuf {
    wheel::write_study(dir, name, name, 42, experiment, method, "")
}

const WHEEL_GRID: &str = "stop = 5.0\nstep = 0.01";

/// Every file under `dir` with its bytes, sorted by path.
fn snapshot(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                out.push((p.clone(), std::fs::read(&p).unwrap()));
            }
        }
    }
    out.sort();
    out
}

#[test]
fn huge_samples_are_refused_with_the_estimate_and_the_limit_even_with_yes() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    // A finished study in the folder first: the refusal must leave it as it is.
    let small = study(
        dir.path(),
        "small",
        WHEEL_GRID,
        "kind = \"lhs\"\nsamples = 20",
    );
    assert!(run_study(&small, &out, &[]).status.success());
    let before = snapshot(&out);
    for method in [
        "kind = \"lhs\"\nsamples = 1000000000000",
        "kind = \"mc\"\nsamples = 1000000000000",
        "kind = \"lhs\"\nsamples = 1000000000\nreplicates = 1000",
        "kind = \"sobol_sampling\"\nsamples = 1000000000\nbase = \"lhs\"",
    ] {
        let huge = study(dir.path(), "huge", WHEEL_GRID, method);
        for extra in [&[][..], &["--yes"][..], &["--yes", "--fresh"][..]] {
            let o = run_study(&huge, &out, extra);
            assert_refused(
                &o,
                &[
                    "model runs",
                    "of memory",
                    "available",
                    "refused even with --yes",
                    "sparse_grid",
                    "pce_regression",
                ],
            );
            assert_eq!(snapshot(&out), before, "{method} {extra:?}: folder changed");
        }
    }
    let h = study(
        dir.path(),
        "h",
        WHEEL_GRID,
        "kind = \"lhs\"\nsamples = 1000000000000",
    );
    let o = run_study(&h, &dir.path().join("new"), &[]);
    assert!(stderr(&o).contains("1000000000000 model runs"));
    assert!(!dir.path().join("new").exists(), "nothing is created");
    // A quasi-Monte Carlo design beyond 2^32 points per sequence is refused at load time.
    let qmc = study(
        dir.path(),
        "q",
        WHEEL_GRID,
        "kind = \"qmc\"\nsamples = 1000000000000",
    );
    let o = run_study(&qmc, &out, &["--yes"]);
    assert_refused(&o, &["2^32"]);
    // Planning refuses too.
    let huge = study(
        dir.path(),
        "p",
        WHEEL_GRID,
        "kind = \"lhs\"\nsamples = 1000000000000",
    );
    let plan = dir.path().join("plan");
    let o = run(&[
        "plan",
        utf8(&huge),
        "--shards",
        "4",
        "--out",
        utf8(&plan),
        "--yes",
    ]);
    assert_refused(&o, &["refused even with --yes"]);
    assert!(!plan.exists());
}

/// Runs a study of the wheel with the `[experiment]` keys `experiment` and `--yes`: refused,
/// with `needles` in the message and no output folder. Returns the temporary folder.
fn refused_grid(experiment: &str, needles: &[&str]) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let p = study(
        dir.path(),
        "grid",
        experiment,
        "kind = \"lhs\"\nsamples = 10",
    );
    let out = dir.path().join("out");
    let o = run_study(&p, &out, &["--yes"]);
    assert_refused(&o, needles);
    assert!(!out.exists());
    dir
}

#[test]
fn a_tiny_step_is_refused_before_the_grid_is_allocated() {
    refused_grid(
        "stop = 5.0\nstep = 1e-12",
        &[
            "5.000e12 communication points",
            "limit of 1e8",
            "coarser step",
        ],
    );
}

#[test]
fn a_huge_stop_is_refused_before_the_grid_is_allocated() {
    let dir = refused_grid(
        "stop = 1e15\nstep = 1.0",
        &["1.000e15 communication points", "limit of 1e8"],
    );
    let out = dir.path().join("out");
    // One run with such a grid (`simulate`) too.
    let csv = dir.path().join("y.csv");
    let o = run(&[
        "simulate",
        wheel_fmu().to_str().unwrap(),
        "--stop",
        "1e15",
        "--step",
        "1",
        "--out",
        utf8(&csv),
    ]);
    assert_refused(&o, &["communication points", "limit of 1e8"]);
    assert!(!csv.exists());
    // Under the grid limit but beyond what the whole study could hold: refused by the memory
    // estimate (2e7 points per run, 2 000 runs: 320 GB of records).
    let p = study(
        dir.path(),
        "long2",
        "stop = 2e7\nstep = 1.0",
        "kind = \"lhs\"\nsamples = 2000",
    );
    let o = run_study(&p, &out, &["--yes"]);
    assert_refused(&o, &["2000 model runs", "refused even with --yes"]);
    assert!(!out.exists());
}

#[test]
fn more_than_100000_runs_need_yes() {
    let dir = tempfile::tempdir().unwrap();
    let p = study(
        dir.path(),
        "big",
        WHEEL_GRID,
        "kind = \"lhs\"\nsamples = 100001",
    );
    let out = dir.path().join("out");
    let o = run_study(&p, &out, &[]);
    assert_refused(
        &o,
        &[
            "100001 model runs, more than 100000",
            "--yes",
            "sparse_grid",
            "per run, measured",
        ],
    );
    assert!(!out.exists());
    // With --yes it starts (stopped after a few points here; it would resume).
    let o = run_study(&p, &out, &["--yes", "--max-points", "4"]);
    assert!(
        stderr(&o).contains("stopped after 4 of 100001 points"),
        "{}",
        stderr(&o)
    );
    // 100 000 runs start without asking (stopped at once here).
    let p = study(
        dir.path(),
        "edge",
        WHEEL_GRID,
        "kind = \"qmc\"\nsamples = 12500\nreplicates = 8",
    );
    let o = run(&[
        "run",
        utf8(&p),
        "--out",
        utf8(&dir.path().join("edge")),
        "--max-points",
        "1",
    ]);
    assert!(
        stderr(&o).contains("stopped after 1 of 100000 points"),
        "{}",
        stderr(&o)
    );
}

/// A study of fewer than 100 000 runs that takes hours (VehicleTrack over 60 s, about 1.5 s a
/// run here, 99 000 runs on one thread): timed on a short run, it needs --yes.
#[test]
fn a_long_study_needs_yes() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("studies/vehicle-track-nominal.toml"),
    )
    .unwrap()
    .replace("kind = \"nominal\"", "kind = \"lhs\"\nsamples = 99000")
    .replace("stop = 6.0", "stop = 60.0")
    .replace("variables = [\"Zc_acc\", \"P1\"]", "variables = []");
    let p = write_file(dir.path(), "long.toml", text);
    let out = dir.path().join("out");
    let o = run_study(&p, &out, &["--threads", "1"]);
    assert_refused(
        &o,
        &[
            "more than 60 min",
            "on 1 thread",
            "per run, measured",
            "--yes",
        ],
    );
    let err = stderr(&o);
    assert!(!err.contains("model runs, more than"), "{err}");
    assert!(!err.contains("of memory, more than"), "{err}");
    assert!(!out.exists());
}

#[test]
fn merge_checks_the_memory_of_the_analysis_as_run_does() {
    // `merge` analysed a study `run` refuses, and aborted (SIGABRT) on a failed
    // allocation after reading every shard. It is now refused first, with the estimate.
    let dir = tempfile::tempdir().unwrap();
    let path = study(
        dir.path(),
        "merge_mem",
        WHEEL_GRID,
        "kind = \"lhs\"\nsamples = 20",
    );
    let plan = dir.path().join("plan");
    let p = utf8(&plan);
    plan_and_run_shards(&path, &plan, 1);
    let merged = dir.path().join("merged");
    let m = utf8(&merged);
    let o = driver()
        .args(["merge", p, "--out", m, "--yes"])
        .env("RAILUQ_MEMORY_LIMIT", "1000")
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(
        e.contains("20 model runs") && e.contains("refused even with --yes"),
        "{e}"
    );
    assert!(!e.contains("panicked"), "{e}");
    // Within the memory it merges, as before.
    run_ok(&["merge", p, "--out", m, "--no-report"]);
    assert!(merged.join("summary.json").exists());
}
