//! Robustness of the importer and the runner against FMUs that are legal but awkward: FMUs with global state, each expectation computed here from the
//! test FMU's documented behaviour (`tests/fmus/README.md`).

#[path = "support/test_fmus.rs"]
mod test_fmus;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use uq_driver::fmu::Fmu;

const DRIVER: &str = env!("CARGO_BIN_EXE_uq-driver");

fn driver(args: &[&str]) -> Output {
    Command::new(DRIVER).args(args).output().expect("runs")
}

/// A Monte Carlo study of the Once FMU: x ~ U(0, 2), y recorded on [0, 1] by 0.1.
fn once_study(dir: &Path, fmu: &Path) -> std::path::PathBuf {
    let study = dir.join("once.toml");
    std::fs::write(
        &study,
        format!(
            "name = \"once\"\nfmu = {:?}\nseed = 3\n[experiment]\nstop = 1.0\nstep = 0.1\n\
             [method]\nkind = \"mc\"\nsamples = 24\n\
             [[parameters]]\nname = \"x\"\ndistribution = \"uniform\"\nlow = 0\nhigh = 2\n\
             [fixed]\nstep_delay = 0.002\n\
             [outputs]\nvariables = [\"y\"]\n",
            fmu.to_str().unwrap()
        ),
    )
    .unwrap();
    study
}

#[test]
fn an_fmu_instantiable_once_per_process_runs_on_every_thread_with_a_library_copy_each() {
    let Some(fmu) = test_fmus::test_fmu("Once") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let study = once_study(dir.path(), &fmu);
    let mut files = Vec::new();
    for threads in ["1", "4"] {
        let out = dir.path().join(format!("t{threads}"));
        let o = driver(&[
            "run",
            study.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--threads",
            threads,
            "--no-report",
        ]);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{threads} threads: {stderr}");
        let points = std::fs::read_to_string(out.join("points.csv")).unwrap();
        assert_eq!(points.lines().count(), 25, "{points}");
        assert!(
            points.lines().skip(1).all(|l| l.ends_with(",ok")),
            "{points}"
        );
        // y(1) = x: the mean at t = 1 is the mean of the design's x.
        let xs: Vec<f64> = points
            .lines()
            .skip(1)
            .map(|l| l.split(',').nth(1).unwrap().parse().unwrap())
            .collect();
        let mean_x = xs.iter().sum::<f64>() / xs.len() as f64;
        let y = std::fs::read_to_string(out.join("y.csv")).unwrap();
        let last = y.lines().last().unwrap();
        let fields: Vec<&str> = last.split(',').collect();
        assert_eq!(fields[0].parse::<f64>().unwrap(), 1.0, "{y}");
        let mean_y: f64 = fields[1].parse().unwrap();
        assert!((mean_y - mean_x).abs() < 1e-12, "{mean_y} vs {mean_x}");
        files.push((points, y));
    }
    assert_eq!(files[0], files[1], "1 thread and 4 threads differ");
}

#[test]
fn private_copies_of_a_library_keep_globals_apart() {
    let Some(path) = test_fmus::test_fmu("Once") else {
        return;
    };
    let fmu = Fmu::open(&path).unwrap();
    let copy = fmu.private_copy().unwrap();
    assert_ne!(fmu.binary_path(), copy.binary_path());
    // Two live instances of one copy are refused before the FMU is called.
    let a = fmu.instantiate("a", false).unwrap();
    let err = fmu.instantiate("a2", false).unwrap_err();
    assert!(
        err.to_string()
            .contains("canBeInstantiatedOnlyOncePerProcess"),
        "{err}"
    );
    // One instance per copy, stepped in turns: each integrates its own x (y = x t).
    let b = copy.instantiate("b", false).unwrap();
    let mut insts = [a, b];
    for (inst, x) in insts.iter_mut().zip([2.0, -3.0]) {
        inst.set_real_by_name("x", x).unwrap();
        inst.setup_experiment(None, 0.0, Some(1.0)).unwrap();
        inst.enter_initialization_mode().unwrap();
        inst.exit_initialization_mode().unwrap();
    }
    for k in 0..10 {
        for inst in insts.iter_mut() {
            inst.do_step(k as f64 * 0.1, 0.1, true).unwrap();
        }
    }
    for (inst, x) in insts.iter_mut().zip([2.0, -3.0]) {
        let y = inst.get_real_by_name("y").unwrap();
        assert!((y - x).abs() < 1e-12, "y = {y}, x = {x}");
    }
}

/// Writes a study of the Once FMU with `parameter` (a `[[parameters]]` body for x) and
/// `fixed` (the `[fixed]` body).
fn study_of_once(dir: &Path, fmu: &Path, method: &str, parameter: &str, fixed: &str) -> PathBuf {
    let study = dir.join("s.toml");
    std::fs::write(
        &study,
        format!(
            "name = \"s\"\nfmu = {:?}\nseed = 7\n[experiment]\nstop = 0.3\nstep = 0.1\n\
             [method]\n{method}\n[[parameters]]\nname = \"x\"\n{parameter}\n\
             [fixed]\n{fixed}\n[outputs]\nvariables = [\"y\"]\n",
            fmu.to_str().unwrap()
        ),
    )
    .unwrap();
    study
}

fn run(study: &Path, out: &Path, extra: &[&str]) -> Output {
    let mut args = vec![
        "run",
        study.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--no-report",
    ];
    args.extend_from_slice(extra);
    driver(&args)
}

#[test]
fn design_points_outside_the_declared_min_max_are_warned_with_their_weight() {
    let Some(fmu) = test_fmus::test_fmu("Once") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    // x declares [-10, 10]; N(0, 6) puts about 10 % of the draws outside.
    let study = study_of_once(
        dir.path(),
        &fmu,
        "kind = \"mc\"\nsamples = 200",
        "distribution = \"normal\"\nmean = 0\nstd = 6",
        "step_delay = 0",
    );
    let out = dir.path().join("out");
    let o = run(&study, &out, &[]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    let points = std::fs::read_to_string(out.join("points.csv")).unwrap();
    let outside = points
        .lines()
        .skip(1)
        .filter(|l| {
            let x: f64 = l.split(',').nth(1).unwrap().parse().unwrap();
            !(-10.0..=10.0).contains(&x)
        })
        .count();
    assert!(outside > 0, "{points}");
    let want = format!(
        "{outside} of 200 points have x outside the range [-10, 10] the FMU declares for it \
         (min/max; probability weight {:.3e})",
        outside as f64 / 200.0
    );
    assert!(stderr.contains(&want), "{stderr}\nwant: {want}");
    // Printed before the runs, and not a second time with the final warnings.
    assert_eq!(stderr.matches(&want).count(), 1, "{stderr}");
    let summary = std::fs::read_to_string(out.join("summary.json")).unwrap();
    assert!(summary.contains(&want), "{summary}");
}

#[test]
fn a_distribution_wholly_outside_the_declared_min_max_is_refused_before_any_run() {
    let Some(fmu) = test_fmus::test_fmu("Once") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let study = study_of_once(
        dir.path(),
        &fmu,
        "kind = \"mc\"\nsamples = 4",
        "distribution = \"uniform\"\nlow = 20\nhigh = 30",
        "step_delay = 0",
    );
    let out = dir.path().join("out");
    let o = run(&study, &out, &[]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{stderr}");
    assert!(
        stderr.contains(
            "random parameter 'x' takes values in [20, 30], wholly outside the range [-10, 10]"
        ),
        "{stderr}"
    );
    assert!(!out.join("store").exists());
    // simulate --set outside the range: a warning, and the run.
    let o = driver(&["simulate", fmu.to_str().unwrap(), "--set", "x=12"]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    assert!(
        stderr.contains("x = 12 is outside the range [-10, 10]"),
        "{stderr}"
    );
    let o = driver(&["inspect", fmu.to_str().unwrap()]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("range [-10, 10] slope"), "{stdout}");
}

#[test]
fn huge_and_escaped_fmu_log_messages_are_cut_before_reaching_points_csv_and_the_store() {
    let Some(fmu) = test_fmus::test_fmu("Once") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    // Every step logs 1 MB (a colour escape first); points with x > 1 fail with such a message.
    let study = study_of_once(
        dir.path(),
        &fmu,
        "kind = \"mc\"\nsamples = 12",
        "distribution = \"uniform\"\nlow = 0\nhigh = 2",
        "log_bytes = 1000000\nfail_above = 1",
    );
    let out = dir.path().join("out");
    let o = run(&study, &out, &["--allow-failures"]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    let points = std::fs::read_to_string(out.join("points.csv")).unwrap();
    let records = csv_records(&points);
    let failed: Vec<&String> = records[1..]
        .iter()
        .map(|r| r.last().unwrap())
        .filter(|s| *s != "ok")
        .collect();
    assert!(!failed.is_empty(), "{points}");
    for l in &failed {
        assert!(l.len() < 80 * 1024, "a failure line of {} bytes", l.len());
        assert!(l.contains("bytes cut)"), "{}", &l[..l.len().min(500)]);
        assert!(!l.contains('\u{1b}'), "a raw escape in points.csv");
        assert!(l.contains("\\u{1b}[31m"), "{}", &l[..l.len().min(500)]);
    }
    let store: u64 = std::fs::read_dir(out.join("store"))
        .unwrap()
        .map(|e| e.unwrap().metadata().unwrap().len())
        .sum();
    assert!(store < 2_000_000, "store of {store} bytes");
}

/// The records of a CSV text (RFC 4180: quoted fields may hold commas, quotes and newlines).
fn csv_records(text: &str) -> Vec<Vec<String>> {
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
    records
}

#[test]
fn inspect_prints_a_huge_start_value_in_exponent_form() {
    // README audit F13: Once's `fail_above` (start 1e300) was printed as 301 digits.
    let Some(fmu) = test_fmus::test_fmu("Once") else {
        return;
    };
    let o = driver(&["inspect", fmu.to_str().unwrap()]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{stdout}");
    let line = stdout
        .lines()
        .find(|l| l.trim_start().starts_with("fail_above"))
        .expect("fail_above listed");
    assert!(line.contains(" 1e300 "), "{line}");
    assert!(line.len() < 200, "{line}");
}

#[test]
fn simulate_set_of_an_integer_outside_its_range_is_refused_as_a_fixed_one_is() {
    // README audit F10: the README promised a warning for any `simulate --set` outside the
    // range; an Integer is refused (as a `[fixed]` one is by `run`), and the message no longer
    // calls a `--set` value "the fixed value".
    let Some(fmu) = test_fmus::test_fmu("Features") else {
        return;
    };
    let o = driver(&[
        "simulate",
        fmu.to_str().unwrap(),
        "--set",
        "misbehave=13",
        "--stop",
        "0.1",
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{err}");
    assert!(
        err.contains("'misbehave' is an Integer declared with min = 0, max = 12")
            && err.contains("the value 13 given for it is outside that range"),
        "{err}"
    );
}
