//! Robustness of the importer and the runner against FMUs that are legal but awkward: FMUs
//! with global state, each expectation computed here from the test FMU's documented behaviour
//! (`tests/fmus/README.md`).

use std::path::{Path, PathBuf};
use std::process::Output;

use uq_driver::fmu::Fmu;

use crate::support::{
    assert_contains, csv_records, failed, read, run, run_args, stderr, stdout, study_head,
    test_fmus, utf8, write_toml,
};

/// A Monte Carlo study of the Once FMU: x ~ U(0, 2), y recorded on [0, 1] by 0.1.
fn once_study(dir: &Path, fmu: &Path) -> PathBuf {
    write_toml(
        dir,
        "once",
        &format!(
            "{}\
             [method]\nkind = \"mc\"\nsamples = 24\n\
             [[parameters]]\nname = \"x\"\ndistribution = \"uniform\"\nlow = 0\nhigh = 2\n\
             [fixed]\nstep_delay = 0.002\n\
             [outputs]\nvariables = [\"y\"]\n",
            study_head("once", fmu, 3, "stop = 1.0\nstep = 0.1")
        ),
    )
}

#[test]
fn an_fmu_instantiable_once_per_process_runs_on_every_thread_with_a_library_copy_each() {
    let Some((fmu, dir)) = test_fmus::test_fmu_and_dir("Once") else {
        return;
    };
    let study = once_study(dir.path(), &fmu);
    let mut files = Vec::new();
    for threads in ["1", "4"] {
        let out = dir.path().join(format!("t{threads}"));
        let o = run(&run_args(
            &study,
            &out,
            &["--threads", threads, "--no-report"],
        ));
        assert!(o.status.success(), "{threads} threads: {}", stderr(&o));
        let points = read(&out.join("points.csv"));
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
        let y = read(&out.join("y.csv"));
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

/// Runs a study of the Once FMU with `method`, `parameter` (a `[[parameters]]` body for x)
/// and `fixed` (the `[fixed]` body) into `out` of a new temporary folder with `--no-report`
/// and `extra` arguments; returns that folder, the FMU, `out` and the run, or `None` when the
/// test FMUs cannot be built.
fn run_once(
    [method, parameter, fixed]: [&str; 3],
    extra: &[&str],
) -> Option<(tempfile::TempDir, PathBuf, PathBuf, Output)> {
    let (fmu, dir) = test_fmus::test_fmu_and_dir("Once")?;
    let study = write_toml(
        dir.path(),
        "s",
        &format!(
            "{}\
             [method]\n{method}\n[[parameters]]\nname = \"x\"\n{parameter}\n\
             [fixed]\n{fixed}\n[outputs]\nvariables = [\"y\"]\n",
            study_head("s", &fmu, 7, "stop = 0.3\nstep = 0.1")
        ),
    );
    let out = dir.path().join("out");
    let mut args = run_args(&study, &out, &["--no-report"]);
    args.extend_from_slice(extra);
    let o = run(&args);
    Some((dir, fmu, out, o))
}

#[test]
fn design_points_outside_the_declared_min_max_are_warned_with_their_weight() {
    // x declares [-10, 10]; N(0, 6) puts about 10 % of the draws outside.
    let Some((_dir, _, out, o)) = run_once(
        [
            "kind = \"mc\"\nsamples = 200",
            "distribution = \"normal\"\nmean = 0\nstd = 6",
            "step_delay = 0",
        ],
        &[],
    ) else {
        return;
    };
    let stderr = stderr(&o);
    assert!(o.status.success(), "{stderr}");
    let points = read(&out.join("points.csv"));
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
    let summary = read(&out.join("summary.json"));
    assert_contains(&summary, &want);
}

#[test]
fn a_distribution_wholly_outside_the_declared_min_max_is_refused_before_any_run() {
    let Some((_dir, fmu, out, o)) = run_once(
        [
            "kind = \"mc\"\nsamples = 4",
            "distribution = \"uniform\"\nlow = 20\nhigh = 30",
            "step_delay = 0",
        ],
        &[],
    ) else {
        return;
    };
    let stderr = stderr(&o);
    assert!(!o.status.success(), "{stderr}");
    assert_contains(
        &stderr,
        "random parameter 'x' takes values in [20, 30], wholly outside the range [-10, 10]",
    );
    assert!(!out.join("store").exists());
    // simulate --set outside the range: a warning, and the run.
    let o = run(&["simulate", utf8(&fmu), "--set", "x=12"]);
    let stderr = crate::support::stderr(&o);
    assert!(o.status.success(), "{stderr}");
    assert_contains(&stderr, "x = 12 is outside the range [-10, 10]");
    let o = run(&["inspect", utf8(&fmu)]);
    let stdout = stdout(&o);
    assert_contains(&stdout, "range [-10, 10] slope");
}

#[test]
fn huge_and_escaped_fmu_log_messages_are_cut_before_reaching_points_csv_and_the_store() {
    // Every step logs 1 MB (a colour escape first); points with x > 1 fail with such a message.
    let Some((_dir, _, out, o)) = run_once(
        [
            "kind = \"mc\"\nsamples = 12",
            "distribution = \"uniform\"\nlow = 0\nhigh = 2",
            "log_bytes = 1000000\nfail_above = 1",
        ],
        &["--allow-failures"],
    ) else {
        return;
    };
    let stderr = stderr(&o);
    assert!(o.status.success(), "{stderr}");
    let points = read(&out.join("points.csv"));
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

#[test]
fn inspect_prints_a_huge_start_value_in_exponent_form() {
    // Once's `fail_above` (start 1e300) was printed as 301 digits.
    let Some(fmu) = test_fmus::test_fmu("Once") else {
        return;
    };
    let o = run(&["inspect", utf8(&fmu)]);
    let stdout = stdout(&o);
    assert!(o.status.success(), "{stdout}");
    let line = stdout
        .lines()
        .find(|l| l.trim_start().starts_with("fail_above"))
        .expect("fail_above listed");
    assert_contains(line, " 1e300 ");
    assert!(line.len() < 200, "{line}");
}

#[test]
fn simulate_set_of_an_integer_outside_its_range_is_refused_as_a_fixed_one_is() {
    // The README promised a warning for any `simulate --set` outside the
    // range; an Integer is refused (as a `[fixed]` one is by `run`), and the message no longer
    // calls a `--set` value "the fixed value".
    let Some(fmu) = test_fmus::test_fmu("Features") else {
        return;
    };
    let o = run(&[
        "simulate",
        utf8(&fmu),
        "--set",
        "misbehave=14",
        "--stop",
        "0.1",
    ]);
    let err = failed(&o);
    assert!(
        err.contains("'misbehave' is an Integer declared with min = 0, max = 13")
            && err.contains("the value 14 given for it is outside that range"),
        "{err}"
    );
}
