//! The `min` and `max` quantity kinds (signed smallest and largest value of a signal
//! over a window) on the Wheel FMU, against its closed form q(t) of m q'' + C q' + K q = 0
//! (`support/wheel.rs`) at each run's K and C.

use std::path::Path;

use crate::support::csv::Csv;
use crate::support::wheel;
use crate::support::{assert_contains, qoi, read, run_study_ok};

/// The values of `<quantity>_samples.csv` (`run,<quantity>`), by run.
fn samples(path: &Path) -> Vec<f64> {
    let csv = Csv::read(path);
    let mut rows: Vec<(usize, f64)> = csv
        .numbers()
        .iter()
        .map(|r| (r[0] as usize, r[1]))
        .collect();
    rows.sort_by_key(|r| r.0);
    rows.into_iter().map(|r| r.1).collect()
}

/// The (K, C) of each design point, from points.csv.
fn points(path: &Path) -> Vec<(f64, f64)> {
    let csv = Csv::read(path);
    csv.col("K").into_iter().zip(csv.col("C")).collect()
}

#[test]
fn min_and_max_quantities_meet_the_wheel_closed_form() {
    let dir = tempfile::tempdir().unwrap();
    let extra = format!(
        "{}{}from = 1.5\nto = 3.0\n{}from = 1.5\n",
        qoi("min", "q_min", "q"),
        qoi("max", "q_max_late", "q"),
        qoi("min", "q_min_late", "q")
    );
    let study = wheel::write_study(
        dir.path(),
        "mm",
        "mm",
        3,
        wheel::EXPERIMENT,
        "kind = \"lhs\"\nsamples = 12",
        &extra,
    );
    let out = dir.path().join("out");
    run_study_ok(&study, &out, &[]);
    let kc = points(&out.join("points.csv"));
    // The communication grid 0, 0.01, ..., 5 s.
    let grid: Vec<f64> = (0..=500).map(|i| i as f64 * 0.01).collect();
    let window = |from: f64, to: f64, k: f64, c: f64| {
        grid.iter()
            .filter(|&&t| t >= from - 1e-12 && t <= to + 1e-12)
            .map(|&t| wheel::closed_form(10.0, k, c, 0.1, t))
            .collect::<Vec<f64>>()
    };
    let cases: [(&str, f64, f64, bool); 3] = [
        ("q_min", 0.0, 5.0, true),
        ("q_max_late", 1.5, 3.0, false),
        ("q_min_late", 1.5, 5.0, true),
    ];
    for (name, from, to, is_min) in cases {
        let got = samples(&out.join(format!("{name}_samples.csv")));
        assert_eq!(got.len(), kc.len(), "{name}");
        for (run, (&(k, c), &g)) in kc.iter().zip(&got).enumerate() {
            let w = window(from, to, k, c);
            let exact = if is_min {
                w.iter().copied().fold(f64::INFINITY, f64::min)
            } else {
                w.iter().copied().fold(f64::NEG_INFINITY, f64::max)
            };
            // The FMU's error is below 1e-9 q0 (its documentation).
            assert!(
                (g - exact).abs() < 1e-8,
                "{name} run {run} (K = {k}, C = {c}): {g} vs {exact}"
            );
        }
    }
    // Signed: the whole-run minimum is the first undershoot, negative, near
    // -q0 exp(-pi c / (2 m w_d)) at t = pi / w_d (underdamped: every run here).
    let got = samples(&out.join("q_min_samples.csv"));
    for (&(k, c), &g) in kc.iter().zip(&got) {
        let a = c / 20.0;
        let wd = (k / 10.0 - a * a).sqrt();
        let extremum = -0.1 * (-a * std::f64::consts::PI / wd).exp();
        assert!(
            g < 0.0 && (g - extremum).abs() < 2e-4 * extremum.abs() + 1e-9,
            "{g} vs {extremum}"
        );
    }
    let summary = read(&out.join("summary.json"));
    assert_contains(&summary, "smallest value of q");
}
