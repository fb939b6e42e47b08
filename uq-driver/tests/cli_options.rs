//! Command-line consistency pinned: exact quantile column names
//! through a whole study (F6), and `merge` / `slurm` taking `--no-report` as `run` does (F9).

#[path = "support/wheel.rs"]
mod wheel;

use std::path::Path;
use std::process::{Command, Output};

const DRIVER: &str = env!("CARGO_BIN_EXE_uq-driver");
/// A short grid: the files, not the numbers, are under test.
const EXPERIMENT: &str = "start = 0.0\nstop = 0.5\nstep = 0.05";

fn driver(args: &[&str]) -> Output {
    Command::new(DRIVER)
        .args(args)
        .env("RAILUQ_FMU_DIR", wheel::fmu_dir())
        .output()
        .expect("uq-driver runs")
}

fn run_ok(args: &[&str]) -> String {
    let out = driver(args);
    assert!(
        out.status.success(),
        "uq-driver {args:?} failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// F6: `quantiles = [0.0015, 0.002, 0.9951]` gave the columns `q0.2,q0.2,q99.5`; the
/// names are the percentages written out (0.15, 0.2, 99.51), in the CSV and the band plot.
#[test]
fn quantile_columns_of_a_study_name_each_level_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let study = wheel::write_study(
        dir.path(),
        "qq",
        "qq",
        1,
        EXPERIMENT,
        "kind = \"mc\"\nsamples = 16",
        "[analysis]\nquantiles = [0.0015, 0.002, 0.9951]",
    );
    let out = dir.path().join("out");
    run_ok(&["run", s(&study), "--out", s(&out)]);
    let csv = std::fs::read_to_string(out.join("q.csv")).unwrap();
    assert!(
        csv.starts_with("time,mean,std,lower_3sigma,upper_3sigma,q0.15,q0.2,q99.51,"),
        "{}",
        csv.lines().next().unwrap()
    );
    let band = std::fs::read_to_string(out.join("q_band.svg")).unwrap();
    for name in ["q0.15 quantile", "q0.2 quantile", "q99.51 quantile"] {
        assert!(band.contains(name), "{name} not in the band plot");
    }
    // A level given twice is refused before anything runs.
    let twice = wheel::write_study(
        dir.path(),
        "q2",
        "q2",
        1,
        EXPERIMENT,
        "kind = \"mc\"\nsamples = 16",
        "[analysis]\nquantiles = [0.5, 0.99, 0.5]",
    );
    let o = driver(&["run", s(&twice), "--out", s(&dir.path().join("o2"))]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains("quantiles 0.5 and 0.5 both give the column 'q50'"),
        "{err}"
    );
    assert!(!dir.path().join("o2/q.csv").exists());
}

/// F9: `merge` refused `--no-report`, which `run` takes. With it the merge writes the CSV
/// files and summary.json only, the same bytes as a merge with the report; `slurm` passes
/// it to the merge job.
#[test]
fn merge_and_slurm_take_no_report_as_run_does() {
    let dir = tempfile::tempdir().unwrap();
    let study = wheel::write_study(
        dir.path(),
        "nr",
        "nr",
        3,
        EXPERIMENT,
        "kind = \"mc\"\nsamples = 12",
        "",
    );
    let plan = dir.path().join("plan");
    run_ok(&["plan", s(&study), "--shards", "2", "--out", s(&plan)]);
    for k in ["0", "1"] {
        run_ok(&["run-shard", s(&plan), "--shard", k]);
    }
    let bare = dir.path().join("bare");
    let said = run_ok(&["merge", s(&plan), "--out", s(&bare), "--no-report"]);
    assert!(said.contains("no report"), "{said}");
    let full = dir.path().join("full");
    run_ok(&["merge", s(&plan), "--out", s(&full)]);
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
    for f in ["q.csv", "points.csv"] {
        assert_eq!(
            std::fs::read(bare.join(f)).unwrap(),
            std::fs::read(full.join(f)).unwrap(),
            "{f}"
        );
    }
    // slurm --dry-run writes the scripts; the merge job carries the option.
    let sl = dir.path().join("sl");
    run_ok(&[
        "slurm",
        s(&study),
        "--shards",
        "2",
        "--out",
        s(&sl),
        "--dry-run",
        "--no-report",
    ]);
    let merge = std::fs::read_to_string(sl.join("slurm/merge.sbatch")).unwrap();
    let last = merge.lines().last().unwrap();
    assert!(
        last.starts_with("exec ") && last.ends_with(" --no-report"),
        "{last}"
    );
    let sl2 = dir.path().join("sl2");
    run_ok(&[
        "slurm",
        s(&study),
        "--shards",
        "2",
        "--out",
        s(&sl2),
        "--dry-run",
    ]);
    let merge = std::fs::read_to_string(sl2.join("slurm/merge.sbatch")).unwrap();
    assert!(!merge.contains("--no-report"), "{merge}");
}
