//! The up-front size checks of the chaos methods.
//!
//! - F2: a 300-run sparse regression chaos (LARS) in 30 inputs of order 5 was estimated at
//!   5 MiB and peaked at 1.5 GB (its candidates at the runs), a 41 601-run sparse grid at
//!   97 MiB and 2.6 GB (the surrogate's basis at its draws); under a memory limit both
//!   aborted on a failed allocation after all their runs. They are refused before any run.
//! - F5: `plan` accepted a sparse grid of 696 321 runs without `--yes` (its run count was
//!   known only to the design), and a sparse grid over the point cap was refused only after
//!   its points were made (32 s, 3.7 GB).
//!
//! Studies on the Functions test FMU (the g-function, `function = 3`), whose parameters
//! `x1..x8`, `a1..a8`, `a`, `b`, `sigma_h`, `rw` are made random here; nothing is run.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use crate::support::refusal::assert_refused;
use crate::support::{
    assert_contains, driver, run_args, stderr, study_head, test_fmus, uniform, utf8, write_toml,
    DRIVER,
};

/// Random parameters the Functions FMU has (the g-function uses the first eight).
const NAMES: [&str; 20] = [
    "x1", "x2", "x3", "x4", "x5", "x6", "x7", "x8", "a1", "a2", "a3", "a4", "a5", "a6", "a7", "a8",
    "a", "b", "sigma_h", "rw",
];

/// A study of `dim` uniform inputs on the Functions FMU with the method `method` (TOML) and
/// the extra `tail` (e.g. an `[analysis]` table).
fn study(dir: &Path, name: &str, dim: usize, method: &str, tail: &str) -> PathBuf {
    let fmu = test_fmus::test_fmu("Functions").expect("the Functions test FMU");
    let parameters: String = NAMES[..dim]
        .iter()
        .map(|n| {
            let (low, high) = if *n == "rw" { (0.05, 0.15) } else { (0.0, 1.0) };
            uniform(&[n], low, high)
        })
        .collect();
    let text = format!(
        r#"{head}[fixed]
function = 3
{parameters}
[outputs]
variables = ["y"]
[method]
{method}
{tail}
"#,
        head = study_head(name, &fmu, 11, "start = 0.0\nstop = 0.1\nstep = 0.1")
    );
    write_toml(dir, name, &text)
}

/// `uq-driver args`, under the memory limit `memory_limit` (bytes) if given.
fn run(args: &[&str], memory_limit: Option<&str>) -> Output {
    let mut c = driver();
    c.args(args);
    if let Some(m) = memory_limit {
        c.env("RAILUQ_MEMORY_LIMIT", m);
    }
    c.output().expect("uq-driver runs")
}

/// `uq-driver plan STUDY --shards N --out PLAN` with `extra` arguments.
fn plan_study(
    study: &Path,
    shards: usize,
    plan: &Path,
    extra: &[&str],
    memory_limit: Option<&str>,
) -> Output {
    let shards = shards.to_string();
    let mut args = vec![
        "plan",
        utf8(study),
        "--shards",
        &shards,
        "--out",
        utf8(plan),
    ];
    args.extend_from_slice(extra);
    run(&args, memory_limit)
}

/// The memory estimate (bytes) in a refusal's text: "about X UNIT of memory".
fn estimate_bytes(err: &str) -> f64 {
    let at = err.find(" of memory").expect("an estimate");
    let words: Vec<&str> = err[..at].rsplit(' ').take(2).collect();
    let value: f64 = words[1].parse().unwrap();
    let unit = match words[0] {
        "KiB" => 1024.0,
        "MiB" => 1024.0 * 1024.0,
        "GiB" => 1024.0 * 1024.0 * 1024.0,
        other => panic!("unit {other}"),
    };
    value * unit
}

/// 300 LHS runs in 18 inputs, order 5: 42 503 candidate terms of degrees 1 to 5, so the
/// candidates at the runs alone take 300 × 42 503 × 8 B = 102 MB, their standardised copies
/// and Gram rows three times that (measured peak of the run: 423 MiB). Under a 200 MB limit
/// it is refused before any run; it used to be estimated at 5 MiB and started.
#[test]
fn a_lars_study_whose_design_matrix_does_not_fit_is_refused_before_any_run() {
    let Some(dir) = test_fmus::dir_if_built() else {
        return;
    };
    let p = study(
        dir.path(),
        "lars",
        18,
        "kind = \"pce_regression\"\nsamples = 300\norder = 5\nsparse = true",
        "",
    );
    let out = dir.path().join("out");
    for extra in [&[][..], &["--yes"][..]] {
        let mut args = run_args(&p, &out, extra);
        // Were it to start, one point and the study stops (no analysis).
        args.extend_from_slice(&["--max-points", "1"]);
        let o = run(&args, Some("200000000"));
        let err = assert_refused(
            &o,
            &[
                "300 model runs",
                "190.7 MiB available",
                "refused even with --yes",
                "a lower `level` or `order`",
            ],
        );
        // Candidates of degrees 1..=5 in 18 inputs: sum_p C(17 + p, p) (independently:
        // C(23, 5) - 1 by the hockey stick), at the runs and three copies per degree.
        let candidates: f64 = (1..=5).map(|p| binomial(17 + p, p)).sum();
        assert_eq!(candidates, binomial(23, 5) - 1.0);
        let matrices = 4.0 * 300.0 * candidates * 8.0;
        assert!(estimate_bytes(&err) > matrices, "{err}");
        assert!(!out.exists(), "nothing is written");
    }
    // `plan` refuses it the same way.
    let plan = dir.path().join("plan");
    let o = plan_study(&p, 2, &plan, &[], Some("200000000"));
    assert_refused(&o, &["refused even with --yes"]);
    assert!(!plan.exists());
}

fn binomial(n: usize, k: usize) -> f64 {
    (0..k).fold(1.0, |acc, i| acc * (n - i) as f64 / (i + 1) as f64)
}

/// A level-3 sparse grid in 18 uniform inputs (9 841 runs): the surrogate's basis at its
/// 4 000 draws of the series has 4 000 × T × 8 B (measured peak of the run 584 MiB). Under a
/// 300 MB limit it is refused before any run; it used to be estimated at 22 MiB.
#[test]
fn a_sparse_grid_whose_surrogate_basis_does_not_fit_is_refused_before_any_run() {
    let Some(dir) = test_fmus::dir_if_built() else {
        return;
    };
    let p = study(
        dir.path(),
        "sg",
        18,
        "kind = \"sparse_grid\"\nlevel = 3",
        "",
    );
    let out = dir.path().join("out");
    let o = run(
        &run_args(&p, &out, &["--yes", "--max-points", "1"]),
        Some("300000000"),
    );
    let err = assert_refused(
        &o,
        &[
            "9841 model runs",
            "286.1 MiB available",
            "refused even with --yes",
        ],
    );
    assert!(estimate_bytes(&err) > 500e6, "{err}");
    assert!(!out.exists());
    // Fewer draws of the series: the same grid fits.
    let p = study(
        dir.path(),
        "sg-few-draws",
        18,
        "kind = \"sparse_grid\"\nlevel = 3",
        "[analysis]\nseries_samples = 100\nsurrogate_samples = 100",
    );
    let o = run(
        &run_args(&p, &out, &["--max-points", "1"]),
        Some("300000000"),
    );
    let err = stderr(&o);
    assert_contains(&err, "stopped after 1 of 9841 points");
}

/// Points of the isotropic Gauss–Patterson grid of `level` in `d` dimensions: nested rules
/// with 1, 2, 4, 8, 16, 32 new nodes per level, summed over the levels with `|l| <= level`.
fn patterson_points(d: usize, level: usize) -> f64 {
    const NEW: [f64; 6] = [1.0, 2.0, 4.0, 8.0, 16.0, 32.0];
    if d == 0 {
        return 1.0;
    }
    (0..=level)
        .map(|j| NEW[j] * patterson_points(d - 1, level - j))
        .sum()
}

/// A level-4 sparse grid in 18 inputs: 105 601 runs (a few hundred MiB). `plan` and
/// `slurm` used to accept it without `--yes` (only the design knew its size); they now ask,
/// as `run` does and as they do for a sampling study of as many runs.
#[test]
fn plan_of_a_large_sparse_grid_needs_yes() {
    let Some(dir) = test_fmus::dir_if_built() else {
        return;
    };
    let runs = patterson_points(18, 4);
    assert_eq!(runs, 105_601.0);
    let p = study(
        dir.path(),
        "big",
        18,
        "kind = \"sparse_grid\"\nlevel = 4",
        "[analysis]\nseries_samples = 2\nsurrogate_samples = 2",
    );
    let needles = ["105601 model runs, more than 100000", "--yes"];
    let plan = dir.path().join("plan");
    let o = plan_study(&p, 4, &plan, &[], None);
    assert_refused(&o, &needles);
    assert!(!plan.exists(), "no plan is written");
    let slurm = dir.path().join("slurm");
    let o = run(
        &[
            "slurm",
            utf8(&p),
            "--shards",
            "4",
            "--out",
            utf8(&slurm),
            "--dry-run",
        ],
        None,
    );
    assert_refused(&o, &needles);
    assert!(!slurm.exists());
    let out = dir.path().join("out");
    let o = run(&run_args(&p, &out, &[]), None);
    assert_refused(&o, &needles);
    assert!(!out.exists(), "refused before the design");
    // With --yes it is planned.
    let o = plan_study(&p, 4, &plan, &["--yes"], None);
    assert!(o.status.success(), "{}", stderr(&o));
    let design = std::fs::read_to_string(plan.join("design.csv")).unwrap();
    assert_eq!(design.lines().count() as f64, runs + 1.0);
}

/// Level 5 in 20 uniform inputs has 1 515 009 points, above the sparse grid's cap of
/// 1 000 000. The count is refused before a point is made: the run is bounded to 500 MB of
/// address space; making the points (the old refusal came after them) took 5 s and 820 MB.
#[test]
fn a_sparse_grid_over_the_point_cap_is_refused_before_its_points_are_made() {
    let Some(dir) = test_fmus::dir_if_built() else {
        return;
    };
    let points = patterson_points(20, 5);
    assert_eq!(points, 1_515_009.0);
    let p = study(
        dir.path(),
        "cap",
        20,
        "kind = \"sparse_grid\"\nlevel = 5",
        "",
    );
    let out = dir.path().join("out");
    let command = format!(
        "ulimit -v 500000 && exec '{DRIVER}' run '{}' --out '{}' --yes",
        p.display(),
        out.display()
    );
    let o = Command::new("sh").args(["-c", &command]).output().unwrap();
    assert_refused(
        &o,
        &[&format!(
            "the level-5 sparse grid has {points} points (more than 1000000)"
        )],
    );
    assert!(!out.exists());
}
