//! The wheel studies against an independent reference: the closed-form response integrated
//! over (K, C) on a 40 × 40 Gauss–Hermite grid whose nodes are computed in the tests
//! (`support/wheel.rs`, Golub–Welsch), separately from the code under test. Also: thread-count independence, resume after a kill,
//! failed points, and clear errors for bad inputs.

#[path = "support/wheel.rs"]
mod wheel;

use std::path::{Path, PathBuf};
use std::process::Command;

use wheel::{fmu_dir, read_csv, reference, wheel_fmu};

const DRIVER: &str = env!("CARGO_BIN_EXE_uq-driver");

fn run(args: &[&str]) -> std::process::Output {
    let out = Command::new(DRIVER)
        .args(args)
        .env("RAILUQ_FMU_DIR", fmu_dir())
        .output()
        .expect("uq-driver runs");
    out
}

fn run_ok(args: &[&str]) {
    let out = run(args);
    assert!(
        out.status.success(),
        "uq-driver {args:?} failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

fn study_file(dir: &Path, name: &str, method: &str, extra: &str) -> PathBuf {
    wheel::write_study(dir, name, name, 7, wheel::EXPERIMENT, method, extra)
}

const TIMES: [f64; 5] = [0.5, 1.0, 2.0, 3.0, 5.0];

#[test]
fn scm_6x6_matches_the_reference() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("scm");
    run_ok(&["run", "builtin:wheel-scm", "--out", out.to_str().unwrap()]);
    let csv = read_csv(&out.join("q.csv"));
    for t in TIMES {
        let (m, s) = reference(t);
        let (dm, ds) = (csv.at(t, "mean") - m, csv.at(t, "std") - s);
        assert!(dm.abs() < 1e-9, "t = {t}: mean error {dm:e}");
        assert!(ds.abs() < 1e-6, "t = {t}: std error {ds:e}");
        // The chaos (order 5) gives nearly the same Std.
        assert!((csv.at(t, "std_pce") - s).abs() < 1e-6, "t = {t}: std_pce");
        assert!((csv.at(t, "upper_3sigma") - (m + 3.0 * s)).abs() < 1e-6);
    }
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["model_runs"], 36);
    assert_eq!(summary["method"]["kind"], "scm");
    for f in [
        "index.html",
        "q_band.svg",
        "q_pdf.svg",
        "q_pdf.png",
        "q_pdf.csv",
        "points.csv",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
}

fn check_sampling(kind: &str, n: usize) {
    let dir = tempfile::tempdir().unwrap();
    let study = study_file(
        dir.path(),
        kind,
        &format!("kind = \"{kind}\"\nsamples = {n}"),
        "",
    );
    let out = dir.path().join("out");
    run_ok(&[
        "run",
        study.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let csv = read_csv(&out.join("q.csv"));
    for t in TIMES {
        let (m, s) = reference(t);
        let se_mean = s / (n as f64).sqrt();
        let se_std = s / (2.0 * (n as f64 - 1.0)).sqrt();
        let (dm, ds) = (csv.at(t, "mean") - m, csv.at(t, "std") - s);
        assert!(
            dm.abs() < 4.0 * se_mean,
            "{kind} t = {t}: mean off by {dm:e} (4 SE = {:e})",
            4.0 * se_mean
        );
        assert!(
            ds.abs() < 4.0 * se_std,
            "{kind} t = {t}: std off by {ds:e} (4 SE = {:e})",
            4.0 * se_std
        );
    }
}

#[test]
fn lhs_matches_the_reference_within_4_standard_errors() {
    check_sampling("lhs", 1000);
}

#[test]
fn mc_matches_the_reference_within_4_standard_errors() {
    check_sampling("mc", 2000);
}

#[test]
fn one_and_two_threads_give_identical_files() {
    let dir = tempfile::tempdir().unwrap();
    let study = study_file(dir.path(), "t", "kind = \"lhs\"\nsamples = 300", "");
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    run_ok(&[
        "run",
        study.to_str().unwrap(),
        "--out",
        a.to_str().unwrap(),
        "--threads",
        "1",
    ]);
    run_ok(&[
        "run",
        study.to_str().unwrap(),
        "--out",
        b.to_str().unwrap(),
        "--threads",
        "2",
    ]);
    for f in ["q.csv", "q_pdf.csv", "points.csv"] {
        assert_eq!(
            std::fs::read(a.join(f)).unwrap(),
            std::fs::read(b.join(f)).unwrap(),
            "{f}"
        );
    }
}

#[test]
fn a_killed_study_resumes_to_the_uninterrupted_result() {
    let dir = tempfile::tempdir().unwrap();
    let study = study_file(dir.path(), "r", "kind = \"lhs\"\nsamples = 40000", "");
    let full = dir.path().join("full");
    run_ok(&[
        "run",
        study.to_str().unwrap(),
        "--out",
        full.to_str().unwrap(),
    ]);
    let part = dir.path().join("part");
    let mut child = Command::new(DRIVER)
        .args([
            "run",
            study.to_str().unwrap(),
            "--out",
            part.to_str().unwrap(),
            "--threads",
            "1",
        ])
        .spawn()
        .unwrap();
    let records = part.join("store/records.bin");
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(60);
    // Kill it once a good part (but not all) of the records are written.
    loop {
        let len = std::fs::metadata(&records).map(|m| m.len()).unwrap_or(0);
        if len > 10_000 * 4_037 {
            break;
        }
        assert!(
            child.try_wait().unwrap().is_none(),
            "finished before it could be killed"
        );
        assert!(std::time::Instant::now() < deadline, "no progress");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(!part.join("q.csv").exists(), "killed before the end");
    let out = run(&[
        "run",
        study.to_str().unwrap(),
        "--out",
        part.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(part.join("summary.json")).unwrap()).unwrap();
    let resumed = summary["runs_resumed"].as_u64().unwrap();
    assert!((10_000..40_000).contains(&resumed), "resumed {resumed}");
    assert_eq!(
        summary["runs_this_invocation"].as_u64().unwrap() + resumed,
        40_000
    );
    for f in ["q.csv", "q_pdf.csv", "points.csv"] {
        assert_eq!(
            std::fs::read(full.join(f)).unwrap(),
            std::fs::read(part.join(f)).unwrap(),
            "{f}"
        );
    }
}

#[test]
fn failed_points_stop_the_study_or_are_counted_when_allowed() {
    let dir = tempfile::tempdir().unwrap();
    // m ~ N(1, 1): about 16 % of the samples have m <= 0, which the FMU refuses.
    let text = std::fs::read_to_string(study_file(
        dir.path(),
        "f",
        "kind = \"lhs\"\nsamples = 200",
        "",
    ))
    .unwrap()
    .replace(
        "name = \"C\"\nmean = 20.0\ncov = 0.1",
        "name = \"m\"\nmean = 1.0\nstd = 1.0",
    );
    let study = dir.path().join("fail.toml");
    std::fs::write(&study, text).unwrap();
    let out = run(&[
        "run",
        study.to_str().unwrap(),
        "--out",
        dir.path().join("a").to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        // "N of M points failed", or, when the study stopped before running every point,
        // "stopped at the first failure of M points (runs not started: K; ...)".
        (err.contains("points failed") || err.contains("runs not started: "))
            && err.contains("m = -"),
        "{err}"
    );
    assert!(
        err.contains("fmi2SetReal"),
        "the FMU's reason is shown: {err}"
    );
    let out = run(&[
        "run",
        study.to_str().unwrap(),
        "--out",
        dir.path().join("b").to_str().unwrap(),
        "--allow-failures",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("b/summary.json")).unwrap())
            .unwrap();
    let failed = summary["failed_runs"].as_u64().unwrap();
    assert!((15..60).contains(&failed), "failed {failed}");
    let points = std::fs::read_to_string(dir.path().join("b/points.csv")).unwrap();
    assert_eq!(points.matches("failed").count() as u64, failed);
}

#[test]
fn bad_inputs_give_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    let bad_fmu = dir.path().join("bad.fmu");
    std::fs::write(&bad_fmu, b"this is not a zip").unwrap();
    let text = std::fs::read_to_string(study_file(
        dir.path(),
        "x",
        "kind = \"lhs\"\nsamples = 10",
        "",
    ))
    .unwrap();
    let cases = [
        (
            text.replace(
                &wheel_fmu().display().to_string(),
                &bad_fmu.display().to_string(),
            ),
            "not a zip archive",
        ),
        (text.replace("name = \"K\"", "name = \"Kx\""), "'Kx'"),
        (
            text.replace("variables = [\"q\"]", "variables = [\"nope\"]"),
            "'nope'",
        ),
        (
            text.replace("name = \"K\"", "name = \"q\""),
            "may not be set",
        ),
        (
            text.replace("samples = 10", "samples = 10\ncolour = 3"),
            "unknown field",
        ),
    ];
    for (i, (t, needle)) in cases.iter().enumerate() {
        let p = dir.path().join(format!("case{i}.toml"));
        std::fs::write(&p, t).unwrap();
        let out = run(&[
            "run",
            p.to_str().unwrap(),
            "--out",
            dir.path().join(format!("o{i}")).to_str().unwrap(),
        ]);
        assert!(!out.status.success());
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(needle), "case {i}: {err}");
        assert!(!err.contains("panicked"), "case {i}: {err}");
    }
    let out = run(&[
        "run",
        "builtin:nope",
        "--out",
        dir.path().join("n").to_str().unwrap(),
    ]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("no built-in study 'nope'"));
}

#[test]
fn a_folder_of_another_study_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let a = study_file(dir.path(), "a", "kind = \"lhs\"\nsamples = 20", "");
    let b = study_file(dir.path(), "b", "kind = \"lhs\"\nsamples = 30", "");
    let out = dir.path().join("o");
    run_ok(&["run", a.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    let r = run(&["run", b.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert!(!r.status.success());
    assert!(String::from_utf8_lossy(&r.stderr).contains("different study"));
    run_ok(&[
        "run",
        b.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--fresh",
    ]);
}

#[test]
fn sgm_order_6_matches_the_reference() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("sgm");
    run_ok(&["run", "builtin:wheel-sgm", "--out", out.to_str().unwrap()]);
    let csv = read_csv(&out.join("q.csv"));
    for t in TIMES {
        let (m, s) = reference(t);
        let (dm, ds) = (csv.at(t, "mean") - m, csv.at(t, "std") - s);
        assert!(dm.abs() < 1e-9, "t = {t}: mean error {dm:e}");
        assert!(ds.abs() < 1e-7, "t = {t}: std error {ds:e}");
    }
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["method"]["terms"], 28, "C(6 + 2, 2)");
    assert!(
        summary["method"]["definiteness"]["min_eig_stiffness"]
            .as_f64()
            .unwrap()
            > 0.0
    );
}

#[test]
fn a_suite_compares_its_variants_against_the_reference() {
    let dir = tempfile::tempdir().unwrap();
    // The paper-wheel suite with a small LHS, so the test stays fast.
    let text = Command::new(DRIVER)
        .args(["show", "paper-wheel"])
        .output()
        .unwrap()
        .stdout;
    let text = String::from_utf8(text).unwrap();
    let cut = text.find("[[variants]]").unwrap();
    let small = format!(
        "{}{}",
        &text[..cut].replace(
            "fmu = \"Wheel.fmu\"",
            &format!("fmu = \"{}\"", wheel_fmu().display())
        ),
        r#"[[variants]]
name = "sgm"
method = { kind = "sgm", order = 6 }

[[variants]]
name = "scm"
method = { kind = "scm", nodes = 6, order = 5 }

[[variants]]
name = "lhs-200"
method = { kind = "lhs", samples = 200 }
"#
    );
    let study = dir.path().join("suite.toml");
    std::fs::write(&study, small).unwrap();
    let out = dir.path().join("o");
    run_ok(&[
        "run",
        study.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let cmp = read_csv(&out.join("q_compare.csv"));
    for t in TIMES {
        // SCM − SGM: both within 1e-9 (mean) / 1e-6 (Std) of the reference.
        assert!(cmp.at(t, "dmean_scm").abs() < 2e-9);
        assert!(cmp.at(t, "dstd_scm").abs() < 2e-6);
        let (_, s) = reference(t);
        assert!(cmp.at(t, "dmean_lhs-200").abs() < 4.0 * s / 200f64.sqrt());
    }
    for f in [
        "index.html",
        "summary.json",
        "q_mean_diff.svg",
        "q_std_diff.svg",
        "sgm/q.csv",
        "scm/q.csv",
        "lhs-200/q.csv",
    ] {
        assert!(out.join(f).is_file(), "{f}");
    }
}

#[test]
fn sparse_grid_level_3_matches_the_reference() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("sparse");
    run_ok(&[
        "run",
        "builtin:wheel-sparse",
        "--out",
        out.to_str().unwrap(),
    ]);
    let csv = read_csv(&out.join("q.csv"));
    for t in TIMES {
        let (m, s) = reference(t);
        let (dm, ds) = (csv.at(t, "mean") - m, csv.at(t, "std") - s);
        assert!(dm.abs() < 1e-9, "t = {t}: mean error {dm:e}");
        assert!(ds.abs() < 1e-6, "t = {t}: std error {ds:e}");
        // The level-2/level-3 difference is reported and small.
        assert!(csv.at(t, "level_difference") < 0.05, "t = {t}");
    }
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["model_runs"], 65);
    assert_eq!(summary["method"]["kind"], "sparse_grid");
    assert!(out.join("surrogate.json").is_file());
}

#[test]
fn sparse_regression_chaos_on_100_runs_matches_the_reference() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("lars");
    run_ok(&[
        "run",
        "builtin:wheel-pce-lars",
        "--out",
        out.to_str().unwrap(),
    ]);
    let csv = read_csv(&out.join("q.csv"));
    for t in TIMES {
        let (m, s) = reference(t);
        let (dm, ds) = (csv.at(t, "mean") - m, csv.at(t, "std") - s);
        assert!(
            dm.abs() < 1e-3 * s,
            "t = {t}: mean error {dm:e} (std {s:e})"
        );
        assert!(ds.abs() < 1e-2 * s, "t = {t}: std error {ds:e} (std {s:e})");
        let loo = csv.at(t, "loo");
        assert!((0.0..0.05).contains(&loo), "t = {t}: loo {loo}");
    }
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["model_runs"], 100);
}
