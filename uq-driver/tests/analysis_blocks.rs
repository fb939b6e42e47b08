//! The series of the runs are written to the results store as they finish and not held; the
//! analysis reads them back a block of time columns at a time. Pinned here on
//! the wheel FMU: the files do not depend on the block size (`RAILUQ_ANALYSIS_BLOCK_BYTES`),
//! also after a kill and a resume; a study whose series exceed the memory limit
//! (`RAILUQ_MEMORY_LIMIT`) is accepted and runs in far less memory than its series, with a
//! mean that matches the wheel's closed form (`support/wheel.rs`).

use std::path::{Path, PathBuf};
use std::process::Output;

use crate::support::wheel::{self, read_csv};
use crate::support::{assert_contains, driver, run_args, run_killed, stderr, summary};

/// `uq-driver args` with the environment `env`.
fn run(args: &[&str], env: &[(&str, &str)]) -> Output {
    driver()
        .args(args)
        .envs(env.iter().copied())
        .output()
        .expect("uq-driver runs")
}

/// `uq-driver run STUDY --out OUT --no-report` with the environment `env`; must succeed.
fn run_study(study: &Path, out: &Path, env: &[(&str, &str)]) {
    let args = run_args(study, out, &["--no-report"]);
    let o = run(&args, env);
    assert!(
        o.status.success(),
        "uq-driver {args:?} failed:\n{}",
        stderr(&o)
    );
}

/// Every file of an output folder but the store and the lock, with `summary.json` stripped of
/// what describes the invocation (timings, runs resumed).
fn files(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() || p.extension().is_some_and(|x| x == "lock") {
            continue;
        }
        let mut bytes = std::fs::read(&p).unwrap();
        if p.file_name().unwrap() == "summary.json" {
            let mut v: serde_json::Value = serde_json::from_slice(&bytes).unwrap();
            let m = v.as_object_mut().unwrap();
            for k in [
                "timing",
                "wall_time_s",
                "runs_this_invocation",
                "runs_resumed",
            ] {
                m.remove(k);
            }
            bytes = serde_json::to_vec(&v).unwrap();
        }
        out.push((p.strip_prefix(dir).unwrap().to_path_buf(), bytes));
    }
    out.sort();
    out
}

fn assert_same_files(a: &Path, b: &Path) {
    let (fa, fb) = (files(a), files(b));
    assert_eq!(
        fa.iter().map(|f| &f.0).collect::<Vec<_>>(),
        fb.iter().map(|f| &f.0).collect::<Vec<_>>()
    );
    assert!(fa.len() >= 4, "{fa:?}");
    for ((name, x), (_, y)) in fa.iter().zip(&fb) {
        assert!(x == y, "{} differs between {a:?} and {b:?}", name.display());
    }
}

/// Blocks of 32 columns (the least): the wheel's 501 times make 16 blocks.
const TINY: (&str, &str) = ("RAILUQ_ANALYSIS_BLOCK_BYTES", "1");

fn same_files_with_tiny_blocks(tag: &str, method: &str, extra: &str) {
    let dir = tempfile::tempdir().unwrap();
    let study = wheel::write_study(dir.path(), tag, tag, 7, wheel::EXPERIMENT, method, extra);
    let (whole, blocks) = (dir.path().join("whole"), dir.path().join("blocks"));
    run_study(&study, &whole, &[]);
    run_study(&study, &blocks, &[TINY]);
    assert_same_files(&whole, &blocks);
}

#[test]
fn tiny_analysis_blocks_give_the_same_files_scm() {
    same_files_with_tiny_blocks("scm", "kind = \"scm\"\nnodes = 6\norder = 5", "");
}

#[test]
fn tiny_analysis_blocks_give_the_same_files_lhs_with_a_quantity() {
    let q = "[[qoi]]\nkind = \"max_abs\"\nname = \"q_max\"\nsignal = \"q\"\n";
    same_files_with_tiny_blocks("lhs", "kind = \"lhs\"\nsamples = 500", q);
}

#[test]
fn tiny_analysis_blocks_give_the_same_files_sparse_regression_chaos() {
    // LARS chooses a basis per column: the blocks' chaoses have different bases.
    let m = "kind = \"pce_regression\"\ndesign = \"qmc\"\nsamples = 60\norder = 8\nsparse = true";
    same_files_with_tiny_blocks("lars", m, "");
}

#[test]
fn tiny_analysis_blocks_give_the_same_files_sobol_sampling() {
    // With bootstrap intervals (their streams do not depend on the column).
    let m = "kind = \"sobol_sampling\"\nsamples = 256\nbase = \"mc\"\nbootstrap = 50";
    same_files_with_tiny_blocks("sobol", m, "");
}

#[test]
fn tiny_analysis_blocks_give_the_same_files_sobol_sampling_qmc_replicates() {
    // Intervals from the spread of 4 independently scrambled replicates.
    let m = "kind = \"sobol_sampling\"\nsamples = 256\nreplicates = 4";
    same_files_with_tiny_blocks("sobolq", m, "");
}

#[test]
fn a_killed_study_resumed_with_tiny_blocks_gives_the_uninterrupted_files() {
    let dir = tempfile::tempdir().unwrap();
    let method = "kind = \"lhs\"\nsamples = 10000";
    let study = wheel::write_study(dir.path(), "r", "r", 3, wheel::EXPERIMENT, method, "");
    let full = dir.path().join("full");
    run_study(&study, &full, &[]);
    let part = dir.path().join("part");
    // Kill it once a quarter of the records (of 4 037 bytes each) are written.
    run_killed(
        &study,
        &part,
        &["--threads", "1", "--no-report"],
        2_500 * 4_037,
    );
    assert!(!part.join("q.csv").exists(), "killed before the end");
    run_study(&study, &part, &[TINY]);
    assert_same_files(&full, &part);
}

/// Runs `args` and returns the child's peak resident memory (bytes, `ru_maxrss`).
fn peak_memory(args: &[&str], env: &[(&str, &str)]) -> u64 {
    #[allow(clippy::zombie_processes)] // reaped by wait4 below
    let child = driver()
        .args(args)
        .envs(env.iter().copied())
        .spawn()
        .unwrap();
    let mut status = 0;
    // SAFETY: an all-zero rusage is a valid value of this plain C struct.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    // SAFETY: wait4 on our own child's pid with valid pointers to locals.
    let pid = unsafe { libc::wait4(child.id() as i32, &mut status, 0, &mut usage) };
    assert_eq!(pid, child.id() as i32);
    assert!(
        libc::WIFEXITED(status) && libc::WEXITSTATUS(status) == 0,
        "uq-driver {args:?} failed ({status})"
    );
    usage.ru_maxrss as u64 * 1024
}

#[test]
fn series_larger_than_the_memory_limit_are_run_and_analysed_in_blocks() {
    let dir = tempfile::tempdir().unwrap();
    // 400 runs of 100 001 points: 320 MB of series, against a limit of 256 MiB.
    let (n, nt) = (400u64, 100_001u64);
    let series = n * nt * 8;
    let experiment = "start = 0.0\nstop = 50.0\nstep = 0.0005";
    let method = format!("kind = \"lhs\"\nsamples = {n}");
    let study = wheel::write_study(dir.path(), "big", "big", 5, experiment, &method, "");
    let out = dir.path().join("out");
    let args = run_args(&study, &out, &["--no-report"]);
    let limit = ("RAILUQ_MEMORY_LIMIT", "268435456");
    let budget = ("RAILUQ_ANALYSIS_BLOCK_BYTES", "8388608");
    let peak = peak_memory(&args, &[limit, budget]);
    // What the process holds whatever the series (its code, threads, the FMU): the same study
    // with 2 runs. A debug build maps and touches more of its larger binary.
    let small = wheel::write_study(
        dir.path(),
        "small",
        "small",
        5,
        experiment,
        "kind = \"lhs\"\nsamples = 2",
        "",
    );
    let small_out = dir.path().join("small-out");
    let base = peak_memory(
        &run_args(&small, &small_out, &["--no-report"]),
        &[limit, budget],
    );
    eprintln!("peak resident memory {peak} bytes ({base} with 2 runs), series {series} bytes");
    assert!(
        peak.saturating_sub(base) < series / 4,
        "peak {peak} bytes ({base} with 2 runs) for {series} bytes of series"
    );
    assert_eq!(summary(&out)["model_runs"], n);
    // The statistics are those of the runs: the mean within 4 standard errors of the
    // closed form at a few times, the columns of the CSV all there.
    let csv = read_csv(&out.join("q.csv"));
    for t in [0.5, 1.0, 2.0, 5.0] {
        let (mean, se) = (csv.at(t, "mean"), csv.at(t, "std_error_mean"));
        let reference = wheel::reference(t).0;
        assert!(
            (mean - reference).abs() <= 4.0 * se + 1e-12,
            "t = {t}: {mean} vs {reference} ± {se}"
        );
    }
    // Without the blocks the same study is refused under the limit: its series alone exceed
    // it (the refusal gives the estimate and the limit).
    let unblocked = run(
        &args,
        &[limit, ("RAILUQ_ANALYSIS_BLOCK_BYTES", "1000000000000")],
    );
    assert!(!unblocked.status.success());
    let err = stderr(&unblocked);
    assert_contains(&err, "refused");
}

/// Under an address-space limit (`ulimit -v`) a study whose estimate fitted ran all its runs,
/// then aborted in the analysis ("memory allocation failed", status 134): its blocks took
/// 256 MiB whatever the limit. They now take at most an eighth of the memory available, and
/// the runs no longer crawl (every allocation a `mmap` of its own: 254 s for these runs,
/// 5 s without the limit) because the CLI keeps the allocator to 2 arenas there.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
#[test]
fn a_study_under_an_address_space_limit_is_analysed_in_blocks_that_fit_it() {
    let dir = tempfile::tempdir().unwrap();
    let experiment = "start = 0.0\nstop = 5.0\nstep = 0.0001";
    let method = "kind = \"mc\"\nsamples = 400";
    let study = wheel::write_study(dir.path(), "capped", "capped", 5, experiment, method, "");
    let out = dir.path().join("out");
    let started = std::time::Instant::now();
    let o = std::process::Command::new("sh")
        .arg("-c")
        .arg("ulimit -v 250000 && exec \"$0\" \"$@\"")
        .arg(crate::support::DRIVER)
        .args(run_args(&study, &out, &["--no-report", "--threads", "2"]))
        .env("RAILUQ_FMU_DIR", crate::support::fmu_dir())
        .output()
        .unwrap();
    let seconds = started.elapsed().as_secs_f64();
    assert!(o.status.success(), "{:?}: {}", o.status, stderr(&o));
    assert!(seconds < 120.0, "{seconds} s under ulimit -v");
    assert_eq!(summary(&out)["model_runs"], 400);
    let csv = read_csv(&out.join("q.csv"));
    for t in [0.5, 2.0] {
        let (mean, se) = (csv.at(t, "mean"), csv.at(t, "std_error_mean"));
        let reference = wheel::reference(t).0;
        assert!(
            (mean - reference).abs() <= 4.0 * se + 1e-12,
            "t = {t}: {mean} vs {reference} ± {se}"
        );
    }
}
