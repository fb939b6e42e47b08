//! The wheel studies against an independent reference: the closed-form response integrated
//! over (K, C) on a 40 × 40 Gauss–Hermite grid whose nodes are computed in the tests
//! (`support/wheel.rs`, Golub–Welsch), separately from the code under test. Also:
//! thread-count independence, resume after a kill, failed points, and clear errors for bad
//! inputs.

use std::path::{Path, PathBuf};

use crate::support::csv::Csv;
use crate::support::wheel::{self, read_csv, reference, wheel_fmu};
use crate::support::{
    assert_same_files, run, run_builtin, run_killed, run_ok, run_study, run_study_ok, stderr,
    summary, utf8, write_file,
};

fn study_file(dir: &Path, name: &str, method: &str, extra: &str) -> PathBuf {
    wheel::write_study(dir, name, name, 7, wheel::EXPERIMENT, method, extra)
}

const TIMES: [f64; 5] = [0.5, 1.0, 2.0, 3.0, 5.0];

/// Checks q.csv of the output folder `out` against the reference at TIMES: the mean and the
/// Std within the tolerances `tol` gives for the reference Std; `row` checks more of the row
/// of each time (given the time, the reference mean and Std).
fn check_reference(out: &Path, tol: impl Fn(f64) -> (f64, f64), row: impl Fn(&Csv, f64, f64, f64)) {
    let csv = read_csv(&out.join("q.csv"));
    for t in TIMES {
        let (m, s) = reference(t);
        let (dm, ds) = (csv.at(t, "mean") - m, csv.at(t, "std") - s);
        let (tol_mean, tol_std) = tol(s);
        assert!(
            dm.abs() < tol_mean,
            "t = {t}: mean error {dm:e}, more than {tol_mean:e} (std {s:e})"
        );
        assert!(
            ds.abs() < tol_std,
            "t = {t}: std error {ds:e}, more than {tol_std:e} (std {s:e})"
        );
        row(&csv, t, m, s);
    }
}

#[test]
fn scm_6x6_matches_the_reference() {
    let (_dir, out, _) = run_builtin("wheel-scm");
    check_reference(
        &out,
        |_| (1e-9, 1e-6),
        |csv, t, m, s| {
            // The chaos (order 5) gives nearly the same Std.
            assert!((csv.at(t, "std_pce") - s).abs() < 1e-6, "t = {t}: std_pce");
            assert!((csv.at(t, "upper_3sigma") - (m + 3.0 * s)).abs() < 1e-6);
        },
    );
    let summary = summary(&out);
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
    run_study_ok(&study, &out, &[]);
    // Within 4 standard errors of the mean and of the Std.
    let se = |s: f64| (s / (n as f64).sqrt(), s / (2.0 * (n as f64 - 1.0)).sqrt());
    check_reference(&out, |s| (4.0 * se(s).0, 4.0 * se(s).1), |_, _, _, _| {});
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
    run_study_ok(&study, &a, &["--threads", "1"]);
    run_study_ok(&study, &b, &["--threads", "2"]);
    assert_same_files(&a, &b, &["q.csv", "q_pdf.csv", "points.csv"]);
}

#[test]
fn a_killed_study_resumes_to_the_uninterrupted_result() {
    let dir = tempfile::tempdir().unwrap();
    let study = study_file(dir.path(), "r", "kind = \"lhs\"\nsamples = 10000", "");
    let full = dir.path().join("full");
    run_study_ok(&study, &full, &[]);
    let part = dir.path().join("part");
    // Kill it once a good part (but not all) of the records are written: a quarter of them,
    // about half a second into a single-threaded run of two seconds.
    run_killed(&study, &part, &["--threads", "1"], 2_500 * 4_037);
    assert!(!part.join("q.csv").exists(), "killed before the end");
    run_study_ok(&study, &part, &[]);
    let summary = summary(&part);
    let resumed = summary["runs_resumed"].as_u64().unwrap();
    assert!((2_500..10_000).contains(&resumed), "resumed {resumed}");
    assert_eq!(
        summary["runs_this_invocation"].as_u64().unwrap() + resumed,
        10_000
    );
    assert_same_files(&full, &part, &["q.csv", "q_pdf.csv", "points.csv"]);
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
    let study = write_file(dir.path(), "fail.toml", text);
    let out = run_study(&study, &dir.path().join("a"), &[]);
    assert!(!out.status.success());
    let err = stderr(&out);
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
    run_study_ok(&study, &dir.path().join("b"), &["--allow-failures"]);
    let summary = summary(&dir.path().join("b"));
    let failed = summary["failed_runs"].as_u64().unwrap();
    assert!((15..60).contains(&failed), "failed {failed}");
    let points = std::fs::read_to_string(dir.path().join("b/points.csv")).unwrap();
    assert_eq!(points.matches("failed").count() as u64, failed);
}

#[test]
fn bad_inputs_give_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    let bad_fmu = write_file(dir.path(), "bad.fmu", b"this is not a zip");
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
        let out = run_study(&p, &dir.path().join(format!("o{i}")), &[]);
        assert!(!out.status.success());
        let err = stderr(&out);
        assert!(err.contains(needle), "case {i}: {err}");
        assert!(!err.contains("panicked"), "case {i}: {err}");
    }
    let out = run(&["run", "builtin:nope", "--out", utf8(&dir.path().join("n"))]);
    assert!(stderr(&out).contains("no built-in study 'nope'"));
}

#[test]
fn a_folder_of_another_study_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let a = study_file(dir.path(), "a", "kind = \"lhs\"\nsamples = 20", "");
    let b = study_file(dir.path(), "b", "kind = \"lhs\"\nsamples = 30", "");
    let out = dir.path().join("o");
    run_study_ok(&a, &out, &[]);
    let r = run_study(&b, &out, &[]);
    assert!(!r.status.success());
    assert!(stderr(&r).contains("different study"));
    run_study_ok(&b, &out, &["--fresh"]);
}

#[test]
fn sgm_order_6_matches_the_reference() {
    let (_dir, out, _) = run_builtin("wheel-sgm");
    check_reference(&out, |_| (1e-9, 1e-7), |_, _, _, _| {});
    let summary = summary(&out);
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
    let text = run_ok(&["show", "paper-wheel"]);
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
    let study = write_file(dir.path(), "suite.toml", small);
    let out = dir.path().join("o");
    run_study_ok(&study, &out, &[]);
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
    let (_dir, out, _) = run_builtin("wheel-sparse");
    check_reference(
        &out,
        |_| (1e-9, 1e-6),
        |csv, t, _, _| {
            // The level-2/level-3 difference is reported and small.
            assert!(csv.at(t, "level_difference") < 0.05, "t = {t}");
        },
    );
    let summary = summary(&out);
    assert_eq!(summary["model_runs"], 65);
    assert_eq!(summary["method"]["kind"], "sparse_grid");
    assert!(out.join("surrogate.json").is_file());
}

#[test]
fn sparse_regression_chaos_on_100_runs_matches_the_reference() {
    // As shipped: the series fitted on its principal components. Its mean is within 0.2 % of
    // the Std of the reference (0.13 % at 5 s, where the fit of every column has 0.015 %).
    let (dir, out, _) = run_builtin("wheel-pce-lars");
    let loo_below_5_percent = |csv: &Csv, t: f64, _: f64, _: f64| {
        let loo = csv.at(t, "loo");
        assert!((0.0..0.05).contains(&loo), "t = {t}: loo {loo}");
    };
    check_reference(&out, |s| (2e-3 * s, 1e-2 * s), loo_below_5_percent);
    let s = summary(&out);
    assert_eq!(s["model_runs"], 100);
    assert_eq!(s["outputs"]["q"]["functional"]["method"], "pca");
    // Every column fitted on its own: within 0.1 % of the Std.
    let text = uq_driver::spec::builtin("wheel-pce-lars").unwrap().replace(
        "fmu = \"Wheel.fmu\"",
        &format!("fmu = {:?}", utf8(&wheel_fmu())),
    );
    let file = write_file(
        dir.path(),
        "columns.toml",
        format!("{text}\n[analysis]\nfunctional = \"columns\"\n"),
    );
    let columns = dir.path().join("columns");
    run_study_ok(&file, &columns, &[]);
    check_reference(&columns, |s| (1e-3 * s, 1e-2 * s), loo_below_5_percent);
    assert_eq!(
        summary(&columns)["outputs"]["q"]["functional"]["method"],
        "columns"
    );
}
