//! A result is reproducible bit for bit only on the same solver kernel: the VehicleTrack FMU
//! picks its instruction sets at run time (AVX2 + FMA or SSE2 loops, and rustfft's FFT), and
//! the paths agree to about 1e-13 only. The FMU reports its pick in the String calculated
//! parameter `solver.kernel`; uq-driver records every String calculated parameter of any FMU
//! in `summary.json` (`fmu.calculated_strings`) and beside `simulate`'s CSV (`FILE.meta.json`).
//! The expected text is derived here from the CPU's features, not from the FMU.

use std::path::Path;

use serde_json::Value;

use crate::support::{
    built_fmu, read_json, run, run_study_ok, stderr, study_head, uniform, utf8, write_toml,
};

/// What `solver.kernel` must say on this machine: the loops on AVX2 + FMA where the CPU has
/// both, else SSE2 (x86-64's baseline); rustfft's planner on AVX + FMA, else SSE4.1, else its
/// scalar code.
fn expected_kernel() -> String {
    #[cfg(target_arch = "x86_64")]
    let (loops, fft) = {
        use std::arch::is_x86_feature_detected as has;
        let loops = if has!("avx2") && has!("fma") {
            "avx2+fma"
        } else {
            "sse2"
        };
        let fft = if has!("avx") && has!("fma") {
            "avx+fma"
        } else if has!("sse4.1") {
            "sse4.1"
        } else {
            "scalar"
        };
        (loops, fft)
    };
    #[cfg(target_arch = "aarch64")]
    let (loops, fft) = ("baseline", "neon");
    #[cfg(not(any(target_arch = "x86_64", target_arch = "aarch64")))]
    let (loops, fft) = ("baseline", "scalar");
    format!("{}: loops {loops}, FFT {fft}", std::env::consts::ARCH)
}

/// A one-run (`nominal`) study of `model` over `experiment`, recording `output`; returns its
/// summary.json.
fn nominal_summary(
    dir: &Path,
    model: &str,
    (param, low, high): (&str, f64, f64),
    experiment: &str,
    output: &str,
) -> Value {
    nominal_summary_with(dir, model, (param, low, high), experiment, output, &[])
}

/// [`nominal_summary`] with more options of `run`.
fn nominal_summary_with(
    dir: &Path,
    model: &str,
    (param, low, high): (&str, f64, f64),
    experiment: &str,
    output: &str,
    extra: &[&str],
) -> Value {
    let fmu = built_fmu(model);
    let text = format!(
        "{}[method]\nkind = \"nominal\"\n{}[outputs]\nvariables = [\"{output}\"]\n",
        study_head(model, &fmu, 1, experiment),
        uniform(&[param], low, high)
    );
    let study = write_toml(dir, model, &text);
    let out = dir.join(format!("{model}-out"));
    run_study_ok(&study, &out, extra);
    read_json(&out.join("summary.json"))
}

#[test]
fn summary_json_records_the_vehicle_track_solver_kernel() {
    let dir = tempfile::tempdir().unwrap();
    let s = nominal_summary(
        dir.path(),
        "VehicleTrack",
        ("irregularity_scale", 0.9, 1.1),
        "stop = 0.02\nstep = 0.002",
        "P1",
    );
    assert_eq!(
        s["fmu"]["calculated_strings"],
        serde_json::json!({ "solver.kernel": expected_kernel() }),
        "{s}"
    );
}

#[test]
fn summary_json_of_isolated_runs_records_no_calculated_strings() {
    // Under --isolate the FMU never runs in uq-driver's own process, so nothing is read: the
    // field stays empty rather than being read in another process than the runs ran in.
    let dir = tempfile::tempdir().unwrap();
    let s = nominal_summary_with(
        dir.path(),
        "VehicleTrack",
        ("irregularity_scale", 0.9, 1.1),
        "stop = 0.02\nstep = 0.002",
        "P1",
        &["--isolate"],
    );
    assert_eq!(s["fmu"]["calculated_strings"], serde_json::json!({}), "{s}");
}

#[test]
fn summary_json_of_an_fmu_without_string_calculated_parameters_records_none() {
    let dir = tempfile::tempdir().unwrap();
    let s = nominal_summary(
        dir.path(),
        "Wheel",
        ("K", 90.0, 110.0),
        "stop = 0.1\nstep = 0.01",
        "q",
    );
    assert_eq!(s["fmu"]["calculated_strings"], serde_json::json!({}), "{s}");
    assert_eq!(s["fmu"]["model_name"], "Wheel");
}

#[test]
fn simulate_writes_the_solver_kernel_beside_its_csv() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("vt.csv");
    let fmu = built_fmu("VehicleTrack");
    let args = [
        "simulate",
        utf8(&fmu),
        "--stop",
        "0.01",
        "--output",
        "P1",
        "--set",
        "n_sleepers=127",
        "--set",
        "n_modes=127",
        "--out",
        utf8(&csv),
    ];
    let o = run(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let kernel = expected_kernel();
    assert!(
        stderr(&o).contains(&format!(
            "note: the FMU reports solver.kernel = \"{kernel}\""
        )),
        "{}",
        stderr(&o)
    );
    // The CSV stays a plain table; the record is in its sidecar.
    let text = std::fs::read_to_string(&csv).unwrap();
    assert!(text.starts_with("time,P1\n"), "{text}");
    let meta = read_json(&dir.path().join("vt.csv.meta.json"));
    assert_eq!(
        meta["fmu"]["calculated_strings"]["solver.kernel"], kernel,
        "{meta}"
    );
    assert_eq!(meta["fmu"]["model_name"], "VehicleTrack");
    assert_eq!(meta["experiment"]["stop"], 0.01);
    assert_eq!(meta["set"]["n_sleepers"], "127");

    // An FMU without String calculated parameters: an empty record, no note.
    let csv = dir.path().join("wheel.csv");
    let wheel = built_fmu("Wheel");
    let o = run(&[
        "simulate",
        utf8(&wheel),
        "--stop",
        "0.1",
        "--out",
        utf8(&csv),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!stderr(&o).contains("the FMU reports"), "{}", stderr(&o));
    let meta = read_json(&dir.path().join("wheel.csv.meta.json"));
    assert_eq!(meta["fmu"]["calculated_strings"], serde_json::json!({}));
    // To standard output: no sidecar file anywhere.
    let o = run(&["simulate", utf8(&wheel), "--stop", "0.1"]);
    assert!(o.status.success());
    let mut names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(
        names,
        [
            "vt.csv",
            "vt.csv.meta.json",
            "wheel.csv",
            "wheel.csv.meta.json"
        ]
    );
}
