//! The VehicleTrack speed `v` declares its range [0, 160] m/s, so a speed given in
//! km/h (`v = 300`, 1080 km/h) is warned about by the driver and refused by the FMU, and a
//! lateral Sperling weighting on the vertical carbody acceleration is warned about.

use std::path::Path;

use crate::support::{assert_contains, built_fmu, read, run_study, stderr, write_toml};

/// A one-run VehicleTrack study (0.5 s, small window) with `fixed` in `[fixed]`, `direction`
/// for its Sperling quantity; returns (success, stderr).
fn run(dir: &Path, tag: &str, fixed: &str, direction: &str) -> (bool, String) {
    let fmu = built_fmu("VehicleTrack");
    let study = write_toml(
        dir,
        tag,
        &format!(
            r#"name = "{tag}"
fmu = "{fmu}"
[experiment]
stop = 0.5
step = 0.002
[method]
kind = "nominal"
[[parameters]]
name = "Kpz"
mean = 1773000.0
cov = 0.1
[fixed]
irregularity = 3
{fixed}
[outputs]
variables = ["Zc_acc_front"]
[[qoi]]
kind = "sperling"
name = "W"
signal = "Zc_acc_front"
direction = "{direction}"
segment = 0.4
limits = [2.5]
"#,
            fmu = fmu.display()
        ),
    );
    let o = run_study(&study, &dir.join(tag), &[]);
    (o.status.success(), stderr(&o))
}

#[test]
fn a_speed_in_km_per_hour_is_warned_about_and_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (ok, err) = run(dir.path(), "kmh", "v = 300.0", "vertical");
    assert!(!ok, "v = 300 m/s (1080 km/h) ran:\n{err}");
    assert_contains(
        &err,
        "v = 300 is outside the range [0, 160] the FMU declares",
    );
    assert!(
        err.contains("not km/h"),
        "the FMU's message is shown:\n{err}"
    );
    // 83.33 m/s (300 km/h) runs, with no range warning.
    let (ok, err) = run(dir.path(), "ms", "v = 83.33", "vertical");
    assert!(ok, "{err}");
    assert!(!err.contains("outside the range"), "{err}");
}

#[test]
fn a_lateral_sperling_on_the_vertical_carbody_acceleration_is_warned_about() {
    let dir = tempfile::tempdir().unwrap();
    let (ok, err) = run(dir.path(), "lat", "", "lateral");
    assert!(ok, "{err}");
    assert!(
        err.contains("quantity 'W': direction = \"lateral\"") && err.contains("as vertical"),
        "{err}"
    );
    let summary = read(&dir.path().join("lat/summary.json"));
    assert_contains(&summary, "which the FMU describes as vertical");
}
