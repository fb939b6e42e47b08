//! What the integration tests share: the `uq-driver` executable and its runs, the FMUs of the
//! build, output files read back (this file); the wheel and its reference (`wheel`), the
//! analytic benchmarks (`benchmarks`), the C test FMUs (`test_fmus`), CSV files (`csv`) and
//! the check of a refusal (`refusal`). Every helper here is written independently of the code
//! under test: it only runs the executable and reads what it writes.

pub mod benchmarks;
pub mod csv;
pub mod refusal;
pub mod test_fmus;
pub mod wheel;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

/// The `uq-driver` executable of this package.
pub const DRIVER: &str = env!("CARGO_BIN_EXE_uq-driver");

/// The folder of the built FMUs: `$RAILUQ_FMU_DIR`, else `target/fmu`.
pub fn fmu_dir() -> PathBuf {
    std::env::var_os("RAILUQ_FMU_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/fmu"))
}

/// The built FMU `<name>.fmu` ("Wheel", "Bogie", "VehicleTrack"); panics with a hint when it
/// has not been built.
pub fn built_fmu(name: &str) -> PathBuf {
    let p = fmu_dir().join(format!("{name}.fmu"));
    assert!(
        p.is_file(),
        "{} is missing: run `make fmu` first",
        p.display()
    );
    p
}

/// A path as text (the tests' paths are UTF-8).
pub fn utf8(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// `uq-driver`, with `RAILUQ_FMU_DIR` set to [`fmu_dir`] (a study may name the built FMUs
/// without a folder).
pub fn driver() -> Command {
    let mut c = Command::new(DRIVER);
    c.env("RAILUQ_FMU_DIR", fmu_dir());
    c
}

/// Runs `uq-driver args`.
pub fn run(args: &[&str]) -> Output {
    driver().args(args).output().expect("uq-driver runs")
}

/// Standard output of a run, as text.
pub fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// Standard error of a run, as text.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Asserts that the run `o` failed, showing its output if not; returns its standard error.
#[track_caller]
pub fn failed(o: &Output) -> String {
    let err = stderr(o);
    assert!(!o.status.success(), "succeeded:\n{}\n{err}", stdout(o));
    err
}

/// Asserts that `o` (of `uq-driver what`) succeeded, showing its output if not; returns its
/// standard output.
pub fn succeeded(o: &Output, what: &dyn std::fmt::Debug) -> String {
    assert!(
        o.status.success(),
        "uq-driver {what:?} failed ({}):\n{}\n{}",
        o.status,
        stdout(o),
        stderr(o)
    );
    stdout(o)
}

/// Runs `uq-driver args`, which must succeed; returns its standard output.
pub fn run_ok(args: &[&str]) -> String {
    succeeded(&run(args), &args)
}

/// The arguments of `uq-driver run STUDY --out OUT` followed by `extra`.
pub fn run_args<'a>(study: &'a Path, out: &'a Path, extra: &[&'a str]) -> Vec<&'a str> {
    let mut args = vec!["run", utf8(study), "--out", utf8(out)];
    args.extend_from_slice(extra);
    args
}

/// Runs `uq-driver run STUDY --out OUT` with `extra` arguments.
pub fn run_study(study: &Path, out: &Path, extra: &[&str]) -> Output {
    run(&run_args(study, out, extra))
}

/// [`run_study`], which must succeed; returns its standard output.
pub fn run_study_ok(study: &Path, out: &Path, extra: &[&str]) -> String {
    run_ok(&run_args(study, out, extra))
}

/// Runs the built-in study `name` into the folder `<name>` of a new temporary folder, which
/// must succeed; returns the temporary folder (keep it: dropping it removes the files), the
/// output folder and the standard output.
pub fn run_builtin(name: &str) -> (tempfile::TempDir, PathBuf, String) {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join(name);
    let stdout = run_ok(&["run", &format!("builtin:{name}"), "--out", utf8(&out)]);
    (dir, out, stdout)
}

/// `uq-driver plan STUDY --shards N --out PLAN`, then `run-shard` of each of the `shards`.
pub fn plan_and_run_shards(study: &Path, plan: &Path, shards: usize) {
    let n = shards.to_string();
    run_ok(&["plan", utf8(study), "--shards", &n, "--out", utf8(plan)]);
    for k in 0..shards {
        run_ok(&["run-shard", utf8(plan), "--shard", &k.to_string()]);
    }
}

/// `study` planned in `shards` shards into `dir/plan`, each run, and merged into
/// `dir/<merged>`; returns that folder.
pub fn run_sharded(study: &Path, dir: &Path, shards: usize, merged: &str) -> PathBuf {
    let plan = dir.join("plan");
    plan_and_run_shards(study, &plan, shards);
    let out = dir.join(merged);
    run_ok(&["merge", utf8(&plan), "--out", utf8(&out)]);
    out
}

/// Starts `uq-driver run STUDY --out OUT` with `extra` arguments and kills it once its store
/// holds more than `bytes` of records; it must not finish before, and must get there within a
/// minute.
pub fn run_killed(study: &Path, out: &Path, extra: &[&str], bytes: u64) {
    let mut child = driver()
        .args(run_args(study, out, extra))
        .spawn()
        .expect("uq-driver starts");
    let records = out.join("store/records.bin");
    let deadline = Instant::now() + Duration::from_secs(60);
    while std::fs::metadata(&records).map_or(0, |m| m.len()) <= bytes {
        assert!(
            child.try_wait().unwrap().is_none(),
            "finished before it could be killed"
        );
        assert!(Instant::now() < deadline, "no progress");
        std::thread::sleep(Duration::from_millis(10));
    }
    child.kill().unwrap();
    child.wait().unwrap();
}

/// Runs `study` into `<study>.out` with `extra` arguments, which must succeed; returns that
/// folder.
pub fn run_beside(study: &Path, extra: &[&str]) -> PathBuf {
    let out = study.with_extension("out");
    run_study_ok(study, &out, extra);
    out
}

/// The first lines of a study file: its `name`, `fmu` and `seed`, and the `[experiment]` table
/// of the keys `experiment`.
pub fn study_head(name: &str, fmu: &Path, seed: u64, experiment: &str) -> String {
    format!(
        "name = \"{name}\"\nfmu = {:?}\nseed = {seed}\n[experiment]\n{experiment}\n",
        utf8(fmu)
    )
}

/// `[outputs]` with the one variable `signal`, and a quantity `name`: its final value.
pub fn final_quantity(signal: &str, name: &str) -> String {
    format!(
        "[outputs]\nvariables = [\"{signal}\"]\n{}",
        qoi("final", name, signal)
    )
}

/// A `[[qoi]]` table: the quantity `name` of the kind `kind` of the output `signal`.
pub fn qoi(kind: &str, name: &str, signal: &str) -> String {
    format!("[[qoi]]\nkind = \"{kind}\"\nname = \"{name}\"\nsignal = \"{signal}\"\n")
}

/// Random parameters `names`, each uniform on [`low`, `high`] (`[[parameters]]` tables).
pub fn uniform(names: &[&str], low: f64, high: f64) -> String {
    names
        .iter()
        .map(|n| {
            format!(
                "[[parameters]]\nname = \"{n}\"\ndistribution = \"uniform\"\nlow = {low}\nhigh = {high}\n"
            )
        })
        .collect()
}

/// Writes `text` to `dir/<name>.toml`; returns its path.
pub fn write_toml(dir: &Path, name: &str, text: &str) -> PathBuf {
    write_file(dir, &format!("{name}.toml"), text)
}

/// Writes `bytes` to the file `dir/name`; returns its path.
pub fn write_file(dir: &Path, name: &str, bytes: impl AsRef<[u8]>) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    p
}

/// Replaces `from` with `to` in the file `path` (which must contain it).
pub fn edit(path: &Path, from: &str, to: &str) {
    let text = read(path);
    assert!(text.contains(from), "no {from:?} in {}", path.display());
    std::fs::write(path, text.replace(from, to)).unwrap();
}

/// Asserts that `text` contains `needle`, showing the text if not.
#[track_caller]
pub fn assert_contains(text: &str, needle: &str) {
    assert!(text.contains(needle), "no {needle:?} in:\n{text}");
}

/// A text file.
pub fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// A JSON file.
pub fn read_json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&read(path)).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// `summary.json` of the output folder `dir`.
pub fn summary(dir: &Path) -> serde_json::Value {
    read_json(&dir.join("summary.json"))
}

/// Asserts that each of `files` has the same bytes in the folders `a` and `b`.
pub fn assert_same_files(a: &Path, b: &Path, files: &[&str]) {
    for f in files {
        assert_eq!(
            std::fs::read(a.join(f)).unwrap(),
            std::fs::read(b.join(f)).unwrap(),
            "{f} differs between {} and {}",
            a.display(),
            b.display()
        );
    }
}

/// The records of a CSV text (RFC 4180: quoted fields may hold commas, quotes and newlines),
/// such as `points.csv` with the failure messages of its points.
pub fn csv_records(text: &str) -> Vec<Vec<String>> {
    let (mut records, mut record, mut field) = (Vec::new(), Vec::new(), String::new());
    let (mut quoted, mut chars) = (false, text.chars().peekable());
    while let Some(c) = chars.next() {
        match (quoted, c) {
            (true, '"') if chars.peek() == Some(&'"') => {
                chars.next();
                field.push('"');
            }
            (true, '"') => quoted = false,
            (true, c) => field.push(c),
            (false, '"') => quoted = true,
            (false, ',') => record.push(std::mem::take(&mut field)),
            (false, '\n') => {
                record.push(std::mem::take(&mut field));
                records.push(std::mem::take(&mut record));
            }
            (false, c) => field.push(c),
        }
    }
    if !field.is_empty() || !record.is_empty() {
        // A last line without its newline.
        record.push(field);
        records.push(record);
    }
    records
}
