//! Robustness of the importer and the runner against FMUs that are legal but awkward (the QA
//! campaign of 2026-11-30): FMUs with global state, each expectation computed here from the
//! test FMU's documented behaviour (`tests/fmus/README.md`).

#[path = "support/test_fmus.rs"]
mod test_fmus;

use std::path::Path;
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
