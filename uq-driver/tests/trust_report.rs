//! What a new user's studies showed: `run --seed` / `--set`, the terminal's variance split of a
//! nested study and its convergence over the study's own runs, a page that links summary.json,
//! densities of a non-negative quantity. On the C test FMU `Functions`.

use std::path::{Path, PathBuf};

use crate::study_nested::{nested_text, X1_X2};
use crate::support::csv::Csv;
use crate::support::{
    assert_contains, final_quantity, read, run_study, run_study_ok, stderr, study_head, summary,
    test_fmus, write_toml,
};

/// `name.toml` in `dir`: a study of `Functions` with the function `function` by `method`, x1
/// and x2 ~ N(0, 1), and `y` and its final value `y_end`.
fn functions_study(dir: &Path, fmu: &Path, name: &str, method: &str, function: u32) -> PathBuf {
    let text = format!(
        "{head}[method]\n{method}\n{X1_X2}[fixed]\nfunction = {function}\n{outputs}",
        head = study_head(name, fmu, 3, "stop = 0.2\nstep = 0.1"),
        outputs = final_quantity("y", "y_end")
    );
    write_toml(dir, name, &text)
}

/// `Functions` with function 5 (y = x1 + … + x8), x1 and x2 normal: a Monte Carlo study.
fn linear_study(dir: &Path, fmu: &Path) -> PathBuf {
    functions_study(dir, fmu, "linear", "kind = \"mc\"\nsamples = 8", 5)
}

/// `run` had no `--seed` / `--set`: a changed seed or sample size meant editing the file.
#[test]
fn run_seed_and_set_override_the_study_and_are_kept_with_it() {
    let Some((fmu, dir)) = test_fmus::test_fmu_and_dir("Functions") else {
        return;
    };
    let study = linear_study(dir.path(), &fmu);
    let out = dir.path().join("out");
    let args = [
        "--seed",
        "11",
        "--set",
        "method.samples=12",
        "--set",
        "parameters.x2.std=3",
    ];
    run_study_ok(&study, &out, &args);
    let s = summary(&out);
    assert_eq!(s["seed"], 11);
    assert_eq!(s["model_runs"], 12);
    let x2 = &s["parameters"][1];
    assert_eq!(
        (x2["name"].as_str(), x2["std"].as_f64()),
        (Some("x2"), Some(3.0))
    );
    // The same settings resume; another seed is another study, refused in that folder.
    run_study_ok(&study, &out, &args);
    assert_eq!(summary(&out)["runs_resumed"], 12);
    let other = run_study(
        &study,
        &out,
        &["--seed", "12", "--set", "method.samples=12"],
    );
    assert!(!other.status.success(), "another seed resumed the store");
    // Keys are checked as the study file's own are.
    let e = run_study(&study, &dir.path().join("e1"), &["--set", "method.zzz=1"]);
    let text = stderr(&e);
    assert_contains(&text, "unknown field `zzz`");
    // Named by the setting, not by a line of the rewritten text.
    assert_contains(&text, "linear.toml (with --set method.zzz=1): unknown");
    let e = run_study(
        &study,
        &dir.path().join("e2"),
        &["--set", "parameters.x9.std=1"],
    );
    assert!(
        stderr(&e).contains("--set parameters.x9.std=1") && stderr(&e).contains("'x9'"),
        "{}",
        stderr(&e)
    );
}

/// A nested study's convergence plot counted "runs n" to 4 096 (its pooled draws) for a
/// 256-run study, and the terminal never printed the inner/outer variance split.
#[test]
fn nested_study_prints_its_variance_split_and_converges_over_its_own_runs() {
    let Some((fmu, dir)) = test_fmus::test_fmu_and_dir("Functions") else {
        return;
    };
    // 16 outer samples × 16 inner collocation points (4 × 4 Gauss–Hermite): 256 runs.
    let methods = [
        "{ kind = \"mc\", samples = 16 }",
        "{ kind = \"scm\", nodes = 4 }",
    ];
    let text = nested_text("two-level", &fmu, 3, methods, [X1_X2, ""], "");
    let study = write_toml(dir.path(), "two-level", &text);
    let out = dir.path().join("out");
    let stdout = run_study_ok(&study, &out, &[]);
    assert_eq!(summary(&out)["model_runs"], 256);
    let line = stdout
        .lines()
        .find(|l| l.contains("variance from the inner parameters"))
        .unwrap_or_else(|| panic!("no variance split in:\n{stdout}"));
    assert!(
        line.contains("y_end: variance from the inner parameters (x1, x2)")
            && line.contains("from the outer parameters (seed)")
            && line.contains("16 outer samples"),
        "{line}"
    );
    for file in ["y_end_convergence.csv", "y_convergence.csv"] {
        let runs = Csv::read(&out.join(file)).numeric().col("runs");
        assert_eq!(runs.last(), Some(&256.0), "{file}: {runs:?}");
        assert!(runs.iter().all(|r| r % 16.0 == 0.0), "{file}: {runs:?}");
    }
    // The page links summary.json, it does not paste it.
    let page = read(&out.join("index.html"));
    assert!(page.contains("<a href=\"summary.json\">summary.json</a>"));
    assert!(!page.contains("<pre>") && !page.contains("\"model_runs\""));
}

/// The density of a non-negative quantity spilled below 0.
#[test]
fn the_density_of_a_non_negative_quantity_has_no_mass_below_zero() {
    let Some((fmu, dir)) = test_fmus::test_fmu_and_dir("Functions") else {
        return;
    };
    // Function 6: y = x1² + … + x8², here x1² + x2² (a chi-square with 2 degrees of freedom,
    // density e^(-y/2)/2, 1/2 at 0).
    let study = functions_study(
        dir.path(),
        &fmu,
        "squares",
        "kind = \"lhs\"\nsamples = 4000",
        6,
    );
    let out = dir.path().join("out");
    run_study_ok(&study, &out, &["--no-report"]);
    let pdf = Csv::read(&out.join("y_end_pdf.csv")).numeric();
    let (x, f) = (pdf.col("x"), pdf.col("density"));
    assert!(x[0] >= 0.0, "grid starts at {}", x[0]);
    let mass: f64 = x
        .windows(2)
        .zip(f.windows(2))
        .map(|(x, f)| 0.5 * (x[1] - x[0]) * (f[0] + f[1]))
        .sum();
    assert!((mass - 1.0).abs() < 0.01, "mass {mass}");
    assert!(
        (f[0] - 0.5).abs() < 0.1,
        "density at 0: {} (true 0.5)",
        f[0]
    );
}
