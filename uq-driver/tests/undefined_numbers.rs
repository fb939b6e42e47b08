//! Numbers a method cannot know are not written as exact ones (through the
//! `uq-driver` binary and the Functions / Features test FMUs, `tests/fmus`):
//! - a chaos method has no sampling standard error of the mean: `null`, not 0;
//! - only a positive-mean normal input warns of points at x <= 0;
//! - a study stopped by failures counts only what is known, and a `[fixed]` Integer
//!   outside its declared range is refused before any run;
//! - the Sobol' indices of an output without variance are NaN (0/0), not 0, and its Std
//!   is 0, never −0.
//!
//! Expected values are closed forms of the test functions (function 4: y = x1 + x2²), counts
//! of the design, or the runs' own values recomputed here.

use std::path::{Path, PathBuf};
use std::process::Output;

use crate::support::csv::Csv;
use crate::support::{
    assert_contains, failed, final_quantity, run, run_args, run_beside, run_study, stderr, stdout,
    study_head, summary, test_fmus, write_toml,
};

/// A study on the test FMU `model` (1 s or 0.1 s long), with `body` (fixed values, parameters,
/// outputs, quantities) and the method `method` (TOML).
fn study(dir: &Path, name: &str, model: &str, stop: f64, body: &str, method: &str) -> PathBuf {
    let fmu = test_fmus::test_fmu(model).expect("the test FMU");
    let text = format!(
        "{}[method]\n{method}\n{body}",
        study_head(
            name,
            &fmu,
            5,
            &format!("start = 0.0\nstop = {stop}\nstep = 0.1")
        )
    );
    write_toml(dir, name, &text)
}

/// Function 4 (y = x1 + x2²) of the Functions FMU with x1, x2 fixed (y = 1.3 + 0.49 = 1.79 in
/// every run) or random (`random`: the parameters' TOML), output `y` and quantity `Y`.
fn function4(random: &str, fixed_x: bool) -> String {
    let fixed = if fixed_x { "x1 = 1.3\nx2 = 0.7\n" } else { "" };
    format!(
        "[fixed]\nfunction = 4\nsigma_h = 0.0\nseed = 0\n{fixed}{random}\n{}",
        final_quantity("y", "Y")
    )
}

const X3_X4: &str = "[[parameters]]\nname = \"x3\"\ndistribution = \"normal\"\nmean = 0.0\n\
                     std = 1.0\n[[parameters]]\nname = \"x4\"\ndistribution = \"uniform\"\n\
                     low = 2.0\nhigh = 3.0\n";

const X1_X2: &str = "[[parameters]]\nname = \"x1\"\ndistribution = \"uniform\"\nlow = -1.0\n\
                     high = 2.0\n[[parameters]]\nname = \"x2\"\ndistribution = \"uniform\"\n\
                     low = -1.0\nhigh = 2.0\n";

const NORMAL_X1_X2: &str = "[[parameters]]\nname = \"x1\"\ndistribution = \"normal\"\n\
                            mean = 0.5\nstd = 1.0\n[[parameters]]\nname = \"x2\"\n\
                            distribution = \"normal\"\nmean = 0.5\nstd = 1.0\n";

/// Header and rows of a CSV file, the fields as text.
fn csv(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let c = Csv::read(path);
    (c.header, c.rows)
}

#[test]
fn chaos_methods_write_no_standard_error_of_the_mean_instead_of_zero() {
    let Some(dir) = test_fmus::dir_if_built() else {
        return;
    };
    for (name, method) in [
        ("sg", "kind = \"sparse_grid\"\nlevel = 3"),
        ("scm", "kind = \"scm\"\nnodes = 4"),
        (
            "pce",
            "kind = \"pce_regression\"\ndesign = \"lhs\"\nsamples = 60\norder = 3",
        ),
    ] {
        let s = study(
            dir.path(),
            name,
            "Functions",
            0.1,
            &function4(NORMAL_X1_X2, false),
            method,
        );
        let out = run_beside(&s, &["--no-report"]);
        let sum = summary(&out);
        assert!(sum["method"]["standard_error"].is_null(), "{name}");
        let q = &sum["quantities"]["Y"];
        assert!(
            q["std_error_mean"].is_null(),
            "{name}: {}",
            q["std_error_mean"]
        );
        // The mean of x1 + x2² with x1, x2 ~ N(0.5, 1): 0.5 + (1 + 0.25) = 1.75 (a degree-2
        // polynomial of Gaussians: every one of these chaos methods is exact).
        let mean = q["mean"].as_f64().unwrap();
        assert!((mean - 1.75).abs() < 1e-9, "{name}: mean {mean}");
        let (header, _) = csv(&out.join("y.csv"));
        assert!(
            !header.iter().any(|h| h == "std_error_mean"),
            "{name}: {header:?}"
        );
    }
    // A sampling method still writes it: std / √n of its runs, recomputed here.
    let s = study(
        dir.path(),
        "mc",
        "Functions",
        0.1,
        &function4(X1_X2, false),
        "kind = \"mc\"\nsamples = 200",
    );
    let out = run_beside(&s, &["--no-report"]);
    let (_, rows) = csv(&out.join("Y_samples.csv"));
    let y: Vec<f64> = rows.iter().map(|r| r[1].parse().unwrap()).collect();
    let n = y.len() as f64;
    let m = y.iter().sum::<f64>() / n;
    let sd = (y.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    let se = summary(&out)["quantities"]["Y"]["std_error_mean"]
        .as_f64()
        .unwrap();
    assert!(
        (se - sd / n.sqrt()).abs() < 1e-12 * sd,
        "{se} vs {}",
        sd / n.sqrt()
    );
}

/// The comparison of a suite (`<q>_compare.csv`): `nan` where a variant's method has no
/// standard error of the mean, the number where it has one.
#[test]
fn suite_comparison_writes_nan_for_a_chaos_variant_standard_error() {
    let Some(dir) = test_fmus::dir_if_built() else {
        return;
    };
    let variants =
        "[[variants]]\nname = \"sg\"\nmethod = { kind = \"sparse_grid\", level = 2 }\n\n\
                    [[variants]]\nname = \"mc\"\nmethod = { kind = \"mc\", samples = 100 }\n";
    let body = format!("{}\n{variants}", function4(NORMAL_X1_X2, false));
    let s = study(
        dir.path(),
        "suite",
        "Functions",
        0.1,
        &body,
        "kind = \"mc\"\nsamples = 100",
    );
    let out = run_beside(&s, &[]);
    let (header, rows) = csv(&out.join("Y_compare.csv"));
    let se = header.iter().position(|h| h == "std_error_mean").unwrap();
    assert_eq!(rows.len(), 2, "{rows:?}");
    assert_eq!(rows[0][se], "nan", "sparse grid: {rows:?}");
    let mc_se: f64 = rows[1][se].parse().unwrap();
    let mc = summary(&out.join("mc"))["quantities"]["Y"]["std_error_mean"]
        .as_f64()
        .unwrap();
    assert!(mc_se > 0.0 && mc_se == mc, "{mc_se} vs {mc}");
}

#[test]
fn no_sign_warning_for_a_uniform_input_whose_support_includes_zero() {
    let Some(dir) = test_fmus::dir_if_built() else {
        return;
    };
    // x1, x2 ~ U(−1, 2): a third of the points have x1 <= 0, as the user chose.
    let s = study(
        dir.path(),
        "uq",
        "Functions",
        0.1,
        &function4(X1_X2, false),
        "kind = \"qmc\"\nsamples = 256\nreplicates = 4",
    );
    let out = run_beside(&s, &["--no-report"]);
    let warnings = summary(&out)["warnings"].clone();
    let text = warnings.to_string();
    assert!(!text.contains("<= 0"), "{text}");
}

#[test]
fn study_stopped_by_failures_counts_only_the_failures_it_saw() {
    let Some(dir) = test_fmus::dir_if_built() else {
        return;
    };
    // misbehave = 6: NaN outputs from misbehave_at on: the points with misbehave_at within
    // the 1 s run fail, about 40 % of them.
    let body = "[fixed]\nmisbehave = 6\n[[parameters]]\nname = \"gain\"\n\
                distribution = \"normal\"\nmean = 1.0\nstd = 0.1\n[[parameters]]\n\
                name = \"misbehave_at\"\ndistribution = \"uniform\"\nlow = 0.2\nhigh = 2.2\n\
                [outputs]\nvariables = [\"u_gain\"]\n";
    let s = study(
        dir.path(),
        "nan",
        "Features",
        1.0,
        body,
        "kind = \"mc\"\nsamples = 64",
    );
    let out = dir.path().join("nan.out");
    let args = |threads: &str, extra: &[&'static str]| -> Output {
        let mut a = run_args(&s, &out, &["--fresh", "--no-report", "--threads", threads]);
        a.extend(extra);
        run(&a)
    };
    // The truth: with --allow-failures every point is run; points.csv says which failed.
    let o = args("2", &["--allow-failures"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (_, rows) = csv(&out.join("points.csv"));
    let failed_points: Vec<usize> = rows
        .iter()
        .filter(|r| r[3].contains("failed"))
        .map(|r| r[0].parse().unwrap())
        .collect();
    let n_failed = failed_points.len();
    assert!(n_failed > 2 && n_failed < 64, "{n_failed} failed");
    let stdout = stdout(&o);
    assert_contains(&stdout, &format!("{n_failed} points failed"));
    // One thread: the points run in design order up to the first failure, then the study
    // stops; the message says so instead of "1 of 64 points failed".
    let f = failed_points[0];
    let o = args("1", &[]);
    let err = failed(&o);
    let want = format!(
        "stopped at the first failure of 64 points (runs not started: {}; how many of those \
         would fail is not known); first: point {f} with",
        63 - f
    );
    assert!(err.contains(&want), "{err}\nwanted: {want}");
    assert!(!err.contains("of 64 points failed"), "{err}");
    // Two threads: however many failed before the stop, they are at most the true count and
    // failures + not started <= 64.
    let o = args("2", &[]);
    let err = stderr(&o);
    let (seen, not_started) = if err.contains("stopped at the first failure") {
        (1, number_after(&err, "runs not started: "))
    } else if err.contains("stopped after the first ") {
        (
            number_after(&err, "stopped after the first "),
            number_after(&err, "runs not started: "),
        )
    } else {
        // Every point was run before the stop: the count is the whole truth.
        (number_after(&err, "toml: "), 0)
    };
    assert!(
        seen >= 1 && seen <= n_failed && seen + not_started <= 64,
        "{err}"
    );
}

/// The whole number right after `after` in `text`.
fn number_after(text: &str, after: &str) -> usize {
    let at = text
        .find(after)
        .unwrap_or_else(|| panic!("no {after:?} in {text}"));
    let rest = &text[at + after.len()..];
    rest[..rest
        .find(|c: char| !c.is_ascii_digit())
        .unwrap_or(rest.len())]
        .parse()
        .unwrap_or_else(|_| panic!("no number after {after:?} in {text}"))
}

#[test]
fn fixed_integer_outside_its_declared_range_is_refused_before_any_run() {
    let Some(dir) = test_fmus::dir_if_built() else {
        return;
    };
    // The Functions FMU declares function with min = 1, max = 8.
    let body = function4(X1_X2, false).replace("function = 4", "function = 9");
    let s = study(
        dir.path(),
        "f9",
        "Functions",
        0.1,
        &body,
        "kind = \"mc\"\nsamples = 16",
    );
    let out = dir.path().join("f9.out");
    let o = run_study(&s, &out, &[]);
    let err = failed(&o);
    assert!(
        err.contains("'function' is an Integer declared with min = 1, max = 8")
            && err.contains("the value 9 given for it is outside that range"),
        "{err}"
    );
    assert!(!err.contains("points failed"), "{err}");
    assert!(!out.join("store").exists(), "no run was started");
    // In range, the same study runs.
    let ok = study(
        dir.path(),
        "f4",
        "Functions",
        0.1,
        &function4(X1_X2, false),
        "kind = \"mc\"\nsamples = 16",
    );
    run_beside(&ok, &["--no-report"]);
}

#[test]
fn sobol_indices_of_an_output_without_variance_are_nan_not_zero() {
    let Some(dir) = test_fmus::dir_if_built() else {
        return;
    };
    // y = 1.79 in every run whatever x3, x4: Var = 0, so S = V_i / Var is 0/0.
    for (name, method) in [
        ("sg", "kind = \"sparse_grid\"\nlevel = 4"),
        ("scm", "kind = \"scm\"\nnodes = 6"),
        (
            "pce",
            "kind = \"pce_regression\"\ndesign = \"qmc\"\nsamples = 128\norder = 4",
        ),
        (
            "lars",
            "kind = \"pce_regression\"\ndesign = \"qmc\"\nsamples = 128\norder = 6\nsparse = true",
        ),
        ("sobol", "kind = \"sobol_sampling\"\nsamples = 256"),
        // One run: no variance information at all.
        ("sg0", "kind = \"sparse_grid\"\nlevel = 0"),
    ] {
        let s = study(
            dir.path(),
            name,
            "Functions",
            0.1,
            &function4(X3_X4, true),
            method,
        );
        let out = run_beside(&s, &[]);
        let (header, rows) = csv(&out.join("y_sobol.csv"));
        for row in &rows {
            for (h, v) in header.iter().zip(row).skip(1) {
                assert_eq!(v, "nan", "{name}: {h} = {v}");
            }
        }
        let (header, rows) = csv(&out.join("y.csv"));
        let std = header.iter().position(|h| h == "std").unwrap();
        for row in &rows {
            assert!(!row[std].starts_with('-'), "{name}: Std {}", row[std]);
            assert!(row[std].parse::<f64>().unwrap() < 1e-12, "{name}");
        }
        let q = &summary(&out)["quantities"]["Y"];
        assert!((q["mean"].as_f64().unwrap() - 1.79).abs() < 1e-12, "{name}");
        assert!(q["std"].as_f64().unwrap().is_sign_positive(), "{name}");
        for key in ["sobol_first", "sobol_total"] {
            assert_eq!(q[key], serde_json::json!([null, null]), "{name}: {key}");
        }
        assert!(q["sobol"]["first"]["x3"].is_null(), "{name}");
        assert!(
            !out.join("Y_sobol.svg").exists(),
            "{name}: bars of undefined indices"
        );
        let html = std::fs::read_to_string(out.join("index.html")).unwrap();
        assert!(!html.contains("NaN"), "{name}: NaN in the page");
        // No whole-series indices from columns that have none.
        assert!(!out.join("y_sobol_overall.csv").exists(), "{name}");
    }
}
