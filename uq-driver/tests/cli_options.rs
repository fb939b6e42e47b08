//! Command-line consistency pinned: exact quantile column names through a whole study, and
//! `merge` / `slurm` taking `--no-report` as `run` does.

use std::path::{Path, PathBuf};

use crate::support::wheel;
use crate::support::{
    assert_contains, assert_same_files, driver, failed, plan_and_run_shards, read, run_ok,
    run_study, stderr, utf8, write_file,
};

/// A short grid: the files, not the numbers, are under test.
const EXPERIMENT: &str = "start = 0.0\nstop = 0.5\nstep = 0.05";

/// `name.toml` in `dir`: the wheel study `name` with the seed `seed` over [`EXPERIMENT`] by
/// `method`, with `rest` appended.
fn mc_study(dir: &Path, name: &str, seed: u64, method: &str, rest: &str) -> PathBuf {
    wheel::write_study(dir, name, name, seed, EXPERIMENT, method, rest)
}

/// `quantiles = [0.0015, 0.002, 0.9951]` gave the columns `q0.2,q0.2,q99.5`; the
/// names are the percentages written out (0.15, 0.2, 99.51), in the CSV and the band plot.
#[test]
fn quantile_columns_of_a_study_name_each_level_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let study = mc_study(
        dir.path(),
        "qq",
        1,
        "kind = \"mc\"\nsamples = 16",
        "[analysis]\nquantiles = [0.0015, 0.002, 0.9951]",
    );
    let out = dir.path().join("out");
    run_ok(&["run", utf8(&study), "--out", utf8(&out)]);
    let csv = read(&out.join("q.csv"));
    assert!(
        csv.starts_with("time,mean,std,lower_3sigma,upper_3sigma,q0.15,q0.2,q99.51,"),
        "{}",
        csv.lines().next().unwrap()
    );
    let band = read(&out.join("q_band.svg"));
    for name in ["q0.15 quantile", "q0.2 quantile", "q99.51 quantile"] {
        assert!(band.contains(name), "{name} not in the band plot");
    }
    // A level given twice is refused before anything runs.
    let twice = mc_study(
        dir.path(),
        "q2",
        1,
        "kind = \"mc\"\nsamples = 16",
        "[analysis]\nquantiles = [0.5, 0.99, 0.5]",
    );
    let o = run_study(&twice, &dir.path().join("o2"), &[]);
    let err = failed(&o);
    assert_contains(&err, "quantiles 0.5 and 0.5 both give the column 'q50'");
    assert!(!dir.path().join("o2/q.csv").exists());
}

/// `merge` refused `--no-report`, which `run` takes. With it the merge writes the CSV
/// files and summary.json only, the same bytes as a merge with the report; `slurm` passes
/// it to the merge job.
#[test]
fn merge_and_slurm_take_no_report_as_run_does() {
    let dir = tempfile::tempdir().unwrap();
    let study = mc_study(dir.path(), "nr", 3, "kind = \"mc\"\nsamples = 12", "");
    let plan = dir.path().join("plan");
    plan_and_run_shards(&study, &plan, 2);
    let bare = dir.path().join("bare");
    let said = run_ok(&["merge", utf8(&plan), "--out", utf8(&bare), "--no-report"]);
    assert_contains(&said, "no report");
    let full = dir.path().join("full");
    run_ok(&["merge", utf8(&plan), "--out", utf8(&full)]);
    assert!(full.join("index.html").exists());
    assert!(!bare.join("index.html").exists());
    let svgs = std::fs::read_dir(&bare)
        .unwrap()
        .filter(|e| {
            e.as_ref()
                .unwrap()
                .path()
                .extension()
                .is_some_and(|x| x == "svg")
        })
        .count();
    assert_eq!(svgs, 0, "plots written with --no-report");
    assert_same_files(&bare, &full, &["q.csv", "points.csv"]);
    // slurm --dry-run writes the scripts; the merge job carries the option.
    // The merge job's script of `slurm --dry-run` into `name` with the arguments `extra`.
    let merge_job = |name: &str, extra: &[&str]| {
        let sl = dir.path().join(name);
        let dry = [
            "slurm",
            utf8(&study),
            "--shards",
            "2",
            "--out",
            utf8(&sl),
            "--dry-run",
        ];
        run_ok(&[&dry[..], extra].concat());
        read(&sl.join("slurm/merge.sbatch"))
    };
    let merge = merge_job("sl", &["--no-report"]);
    let last = merge.lines().last().unwrap();
    assert!(
        last.starts_with("exec ") && last.ends_with(" --no-report"),
        "{last}"
    );
    let merge = merge_job("sl2", &[]);
    assert!(!merge.contains("--no-report"), "{merge}");
}

/// A mistyped subcommand with swapped letters (`rnu`) got no "did you mean": clap's own
/// similarity misses it.
#[test]
fn a_mistyped_subcommand_gets_a_did_you_mean() {
    for (wrong, right) in [("rnu", "run"), ("simulte", "simulate"), ("mrege", "merge")] {
        let o = crate::support::run(&[wrong, "x"]);
        let err = crate::support::stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(
            err.contains(&format!("unrecognized subcommand '{wrong}'"))
                && err.contains(&format!("a similar subcommand exists: '{right}'")),
            "{err}"
        );
    }
    let err = crate::support::stderr(&crate::support::run(&["zzzz"]));
    assert!(!err.contains("similar"), "{err}");
}

/// `--threads 0` was refused naming a Rust type's field.
#[test]
fn threads_0_is_refused_in_the_command_s_terms() {
    let o = crate::support::run(&["run", "x.toml", "--out", "o", "--threads", "0"]);
    let err = crate::support::stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert_contains(
        &err,
        "0 threads cannot run anything: give at least 1, or leave --threads out",
    );
    assert!(!err.contains("NonZero") && !err.contains("usize"), "{err}");
}

/// `uq-driver list` printed lines of up to 842 characters (whole descriptions).
#[test]
fn list_lines_fit_in_100_characters() {
    let out = run_ok(&["list"]);
    for line in out.lines() {
        let n = line.chars().count();
        assert!(n <= 100, "{n} chars: {line}");
    }
    for name in ["wheel-scm", "wheel-sgm", "wheel-mc"] {
        assert!(out.lines().any(|l| l == format!("builtin:{name}")), "{out}");
    }
    // The descriptions are whole, wrapped between words.
    let words = out.split_whitespace().collect::<Vec<_>>().join(" ");
    assert!(
        words.contains("stochastic Galerkin method with Hermite chaos of total order 6 (28 terms)"),
        "{out}"
    );
}

/// A study in the working folder named its misspelt FMU twice ("Whel.fmu", "Whel.fmu": the
/// study's folder and the working folder) and did not point at the `Wheel.fmu` beside it.
#[test]
fn a_misspelt_fmu_is_listed_once_per_place_with_the_fmu_it_may_mean() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("Wheel.fmu"), b"").unwrap();
    write_file(
        dir.path(),
        "s.toml",
        "name = \"s\"\nfmu = \"Whel.fmu\"\n[experiment]\nstop = 1.0\nstep = 0.1\n\
         [method]\nkind = \"scm\"\nnodes = 2\n[[parameters]]\nname = \"K\"\nmean = 1.0\nstd = 0.1\n\
         [outputs]\nvariables = [\"q\"]\n",
    );
    let out = driver()
        .current_dir(dir.path())
        .args(["run", "s.toml", "--out", "o"])
        .output()
        .unwrap();
    let err = stderr(&out);
    let listed: Vec<&str> = err.lines().filter(|l| l.starts_with("  ")).collect();
    let mut unique = listed.clone();
    unique.sort();
    unique.dedup();
    assert_eq!(listed.len(), unique.len(), "{err}");
    let here = dir.path().join("Whel.fmu");
    assert!(
        listed
            .iter()
            .any(|l| l.trim() == here.display().to_string()),
        "{err}"
    );
    let wheel = dir.path().join("Wheel.fmu").display().to_string();
    assert_contains(&err, &format!("did you mean {wheel}?"));
}

/// A misspelt key given by `--set` got the list of expected keys but no "did you mean", which
/// the same key in the study file gets.
#[test]
fn a_misspelt_key_of_set_gets_a_did_you_mean() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("o");
    let o = crate::support::run(&[
        "run",
        "builtin:wheel-scm",
        "--out",
        utf8(&out),
        "--set",
        "method.node=3",
    ]);
    let err = failed(&o);
    assert_contains(&err, "with --set method.node=3");
    assert_contains(&err, "hint: did you mean `nodes`?");
}
