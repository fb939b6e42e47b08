//! Result folders that were tampered with or mixed up: a results store or a shard holds the
//! identity of its study and FMU (in `records.bin` itself, not only in `manifest.json`), a
//! plan's study is checked against the fingerprint it was planned with, and a stored record
//! of non-finite values fails its point instead of making every statistic NaN.

use std::fs;
use std::path::Path;

use crate::support::wheel::{self, read_csv};
use crate::support::{
    assert_contains, failed, plan_and_run_shards, run, run_ok, run_study, stderr, utf8,
};
use uq_driver::internals::store::{decode, encode, Record};

/// A small MC study of the wheel with seed `seed`.
fn wheel_mc(dir: &Path, file: &str, seed: u64) -> std::path::PathBuf {
    wheel::write_study(
        dir,
        file,
        "tamper",
        seed,
        "start = 0.0\nstop = 1.0\nstep = 0.05",
        "kind = \"mc\"\nsamples = 8",
        "",
    )
}

fn records(dir: &Path) -> std::path::PathBuf {
    dir.join("store").join("records.bin")
}

/// `records.bin` of another study's shard copied into a shard folder was merged: the other
/// design's outputs paired with this design's inputs, exit status 0.
#[test]
fn a_records_file_of_another_study_in_a_shard_folder_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    plan_and_run_shards(&wheel_mc(dir.path(), "a", 42), &a, 2);
    plan_and_run_shards(&wheel_mc(dir.path(), "b", 43), &b, 2);
    let shard0 = |p: &Path| p.join("shards").join("0");
    fs::copy(records(&shard0(&b)), records(&shard0(&a))).unwrap();
    let o = run(&["merge", utf8(&a), "--no-report"]);
    let err = stderr(&o);
    assert!(!o.status.success(), "merged: {err}");
    assert!(
        err.contains("shard 0") && err.contains("does not belong to this plan"),
        "{err}"
    );
    assert_contains(&err, "records of another study or FMU");
    // run-shard does not resume it either.
    let o = run(&["run-shard", utf8(&a), "--shard", "0"]);
    assert_contains(&failed(&o), "records of another study");

    // The same in a study folder: the run is not resumed from another study's records.
    let (x, y) = (dir.path().join("x"), dir.path().join("y"));
    let (sa, sb) = (wheel_mc(dir.path(), "a", 42), wheel_mc(dir.path(), "b", 43));
    run_ok(&["run", utf8(&sa), "--out", utf8(&x), "--no-report"]);
    run_ok(&["run", utf8(&sb), "--out", utf8(&y), "--no-report"]);
    fs::copy(records(&y), records(&x)).unwrap();
    let o = run_study(&sa, &x, &["--no-report"]);
    assert_contains(&failed(&o), "copied from another folder");
}

/// plan.json's study edited after planning (seed 42 → 43) was merged without a word: the
/// merge built the seed-43 design and paired it with the shards' seed-42 outputs.
#[test]
fn an_edited_study_in_plan_json_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let plan = dir.path().join("plan");
    plan_and_run_shards(&wheel_mc(dir.path(), "s", 42), &plan, 2);
    let path = plan.join("plan.json");
    let text = fs::read_to_string(&path).unwrap();
    assert!(text.contains("seed = 42"));
    fs::write(&path, text.replace("seed = 42", "seed = 43")).unwrap();
    for args in [
        vec!["merge", utf8(&plan), "--no-report"],
        vec!["run-shard", utf8(&plan), "--shard", "1"],
    ] {
        let o = run(&args);
        let err = stderr(&o);
        assert!(!o.status.success(), "{args:?}: {err}");
        assert!(
            err.contains("the study in plan.json is not the one that was planned"),
            "{args:?}: {err}"
        );
    }
}

/// A forged record of NaNs for point 0 (valid checksums) gave a NaN mean in q.csv and exit
/// status 0. It now fails point 0, saying why; with --allow-failures (MC) the statistics
/// leave it out and stay finite.
#[test]
fn a_forged_record_of_nans_fails_its_point_instead_of_a_nan_mean() {
    let dir = tempfile::tempdir().unwrap();
    let study = wheel_mc(dir.path(), "s", 42);
    let out = dir.path().join("out");
    run_ok(&["run", utf8(&study), "--out", utf8(&out), "--no-report"]);
    let bytes = fs::read(records(&out)).unwrap();
    let n_values = 21;
    let (_, d) = decode(&bytes, n_values);
    let mut forged: Vec<u8> = d
        .identities
        .first()
        .map(|(_, r)| bytes[r.clone()].to_vec())
        .unwrap_or_default();
    for (i, rec, _) in &d.records {
        let rec = match (i, rec) {
            (0, Record::Ok(v)) => Record::Ok(vec![f64::NAN; v.len()]),
            (_, r) => r.clone(),
        };
        forged.extend(encode(*i, &rec));
    }
    assert_eq!(d.records.len(), 8);
    fs::write(records(&out), forged).unwrap();
    let o = run_study(&study, &out, &["--no-report"]);
    let err = stderr(&o);
    assert!(!o.status.success(), "a NaN record was analysed: {err}");
    assert!(
        err.contains("point 0")
            && err.contains("non-finite value (NaN) of output 'q' at t = 0 s")
            && err.contains("damaged or edited"),
        "{err}"
    );
    let o = run_study(&study, &out, &["--no-report", "--allow-failures"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let csv = read_csv(&out.join("q.csv"));
    assert!(csv.col("mean").iter().all(|m| m.is_finite()));
}
