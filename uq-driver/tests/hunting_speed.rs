//! The constant-speed critical speed of the bogie by bisection
//! (`[[qoi]] kind = "hunting_speed"`) against a direct scan of constant-speed runs made here,
//! with the hunting criterion written here (largest |Y| over the last second at or above the
//! threshold). Fast configuration: 60 s runs, RK4 step 4 ms, communication step 0.02 s,
//! tolerance 0.1 m/s (the numbers are not the converged critical speed: that needs longer
//! runs, see the bogie in the user guide's models page). Also: the point's random values
//! reach the constant-speed runs, the records are the same in-process, isolated, resumed and
//! sharded, and a bracket that misses the transition or settings that do not fit the FMU are
//! clear errors.

use std::path::{Path, PathBuf};

use uq_driver::fmu::Fmu;
use uq_driver::spec::FixedValue;
use uq_driver::study::simulate;

use crate::support::csv::Csv;
use crate::support::{
    assert_contains, built_fmu, failed, read, run_sharded, run_study, run_study_ok, summary, utf8,
    write_file,
};

/// Settings of the fast configuration.
const DURATION: f64 = 60.0;
const STEP: f64 = 0.02;
const DT: f64 = 0.004;
const WINDOW: f64 = 1.0;
const THRESHOLD: f64 = 1e-4;
const LOW: f64 = 60.0;
const HIGH: f64 = 80.0;
const TOLERANCE: f64 = 0.1;

fn bogie_fmu() -> PathBuf {
    built_fmu("Bogie")
}

/// A new temporary folder with the study `s.toml` of [`study_text`] by `method` between
/// [`LOW`] and [`HIGH`].
fn study_in_new_dir(method: &str) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let study = write_file(dir.path(), "s.toml", study_text(method, LOW, HIGH));
    (dir, study)
}

/// A study of the bogie's hunting speed: `method` (TOML inline table), the bracket.
fn study_text(method: &str, low: f64, high: f64) -> String {
    format!(
        "name = \"hunting\"\nfmu = {fmu:?}\n\
         [experiment]\nstop = 1.0\nstep = 0.01\n\
         [method]\n{method}\n\
         [[parameters]]\nname = \"K_sy\"\nmean = 0.1823e6\ncov = 0.1\n\
         [[parameters]]\nname = \"C_sy\"\nmean = 29.2e3\ncov = 0.1\n\
         [[parameters]]\nname = \"K_phi\"\nmean = 2.71e6\ncov = 0.1\n\
         [[qoi]]\nkind = \"hunting_speed\"\nname = \"v_hunt\"\nspeed_parameter = \"V0\"\n\
         set = {{ ramp = 0.0, dt = {DT} }}\nlow = {low:?}\nhigh = {high:?}\n\
         tolerance = {TOLERANCE}\nduration = {DURATION:?}\nstep = {STEP}\nsignal = \"Y\"\n\
         window = {WINDOW:?}\nthreshold = {THRESHOLD:e}\n",
        fmu = bogie_fmu().to_str().unwrap()
    )
}

/// The values of `<q>_samples.csv` (run index, value), as text and as numbers.
fn samples(out: &Path, q: &str) -> (String, Vec<f64>) {
    let path = out.join(format!("{q}_samples.csv"));
    (read(&path), Csv::read(&path).col(q))
}

/// One constant-speed run of the bogie at `speed` with `params`, classified here: whether
/// the largest |Y| over the last `WINDOW` s is at or above `THRESHOLD`.
fn hunts_directly(fmu: &Fmu, params: &[(&str, f64)], speed: f64) -> bool {
    let mut set: Vec<(String, FixedValue)> = vec![
        ("V0".into(), speed.into()),
        ("ramp".into(), 0.0.into()),
        ("dt".into(), DT.into()),
    ];
    set.extend(params.iter().map(|(n, v)| (n.to_string(), (*v).into())));
    let n = (DURATION / STEP).round() as usize;
    let times: Vec<f64> = (0..=n).map(|i| i as f64 * STEP).collect();
    let sim = simulate(fmu, &set, &["Y".to_string()], None, &times).unwrap();
    assert_eq!(sim.times.len(), times.len());
    let peak = sim
        .times
        .iter()
        .zip(&sim.series[0])
        .filter(|(t, _)| **t >= DURATION - WINDOW - 1e-9)
        .map(|(_, y)| y.abs())
        .fold(0.0, f64::max);
    assert!(peak.is_finite());
    peak >= THRESHOLD
}

#[test]
fn bisection_critical_speed_against_a_direct_scan_of_constant_speed_runs() {
    let (dir, study) = study_in_new_dir("kind = \"nominal\"");
    let out = dir.path().join("out");
    let stdout = run_study_ok(&study, &out, &[]);
    let (_, hunt) = samples(&out, "v_hunt");
    let (_, decay) = samples(&out, "v_hunt_decay");
    let (hunt, decay) = (hunt[0], decay[0]);
    assert!(stdout.contains("v_hunt = ") && stdout.contains("v_hunt_decay = "));
    assert!(decay < hunt && hunt - decay <= TOLERANCE, "{decay} {hunt}");

    // The scan: every 0.25 m/s over the bracket, plus the two speeds the bisection reports.
    let fmu = Fmu::open(&bogie_fmu()).unwrap();
    let speeds: Vec<f64> = (0..=80).map(|i| LOW + 0.25 * i as f64).collect();
    let scan: Vec<bool> = speeds
        .iter()
        .map(|&v| hunts_directly(&fmu, &[], v))
        .collect();
    // One transition: decay below, hunting above, inside the bracket.
    let first = scan.iter().position(|&h| h).expect("hunts somewhere");
    assert!(first > 0, "hunts at the bottom of the bracket");
    assert!(
        scan[first..].iter().all(|&h| h),
        "not monotone in speed: {scan:?}"
    );
    let (scan_decay, scan_hunt) = (speeds[first - 1], speeds[first]);
    // The bisection's interval and the scan's agree: (decay, hunt] and (scan_decay,
    // scan_hunt] both hold the transition, so they overlap, and every scanned speed is on the
    // side the bisection puts it.
    for (&v, &h) in speeds.iter().zip(&scan) {
        if v <= decay {
            assert!(!h, "the scan hunts at {v} <= {decay}");
        }
        if v >= hunt {
            assert!(h, "the scan decays at {v} >= {hunt}");
        }
    }
    assert!(decay < scan_hunt && scan_decay < hunt);
    // The reported speeds themselves, run directly.
    assert!(hunts_directly(&fmu, &[], hunt), "no hunting at {hunt}");
    assert!(!hunts_directly(&fmu, &[], decay), "hunting at {decay}");
    eprintln!("bisection ({decay}, {hunt}], scan ({scan_decay}, {scan_hunt}]");
}

#[test]
fn hunting_speed_uses_each_points_parameters_and_is_the_same_isolated_resumed_and_sharded() {
    let (dir, study) = study_in_new_dir("kind = \"scm\"\nnodes = 2\norder = 1");
    let base = dir.path().join("in-process");
    run_study_ok(&study, &base, &["-t", "2"]);
    let (text, hunt) = samples(&base, "v_hunt");
    let (_, decay) = samples(&base, "v_hunt_decay");
    assert_eq!(hunt.len(), 8);
    // The points differ, and each point's speeds hold for its own parameters.
    let distinct = hunt.iter().filter(|v| **v != hunt[0]).count();
    assert!(distinct > 0, "every point gave {}", hunt[0]);
    let points = std::fs::read_to_string(base.join("points.csv")).unwrap();
    let header: Vec<&str> = points.lines().next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let fmu = Fmu::open(&bogie_fmu()).unwrap();
    let lowest = (0..8).min_by(|&a, &b| hunt[a].total_cmp(&hunt[b])).unwrap();
    let highest = (0..8).max_by(|&a, &b| hunt[a].total_cmp(&hunt[b])).unwrap();
    for i in [lowest, highest] {
        let row: Vec<&str> = points.lines().nth(i + 1).unwrap().split(',').collect();
        let params: Vec<(&str, f64)> = ["K_sy", "C_sy", "K_phi"]
            .iter()
            .map(|n| (*n, row[col(n)].parse().unwrap()))
            .collect();
        assert!(hunts_directly(&fmu, &params, hunt[i]), "point {i}");
        assert!(!hunts_directly(&fmu, &params, decay[i]), "point {i}");
    }
    assert!(hunt[highest] - hunt[lowest] > 1.0, "{hunt:?}");

    // --isolate: the same records.
    let isolated = dir.path().join("isolated");
    run_study_ok(&study, &isolated, &["--isolate", "-t", "2"]);
    assert_eq!(samples(&isolated, "v_hunt").0, text);
    // Interrupted after 3 points, then resumed on one thread.
    let resumed = dir.path().join("resumed");
    let o = run_study(&study, &resumed, &["--max-points", "3"]);
    assert!(!resumed.join("v_hunt_samples.csv").exists(), "{o:?}");
    let stdout = run_study_ok(&study, &resumed, &["-t", "1"]);
    assert!(stdout.contains("(3 resumed)"));
    assert_eq!(samples(&resumed, "v_hunt").0, text);
    // Two shards, merged.
    let merged = run_sharded(&study, dir.path(), 2, "merged");
    assert_eq!(samples(&merged, "v_hunt").0, text);
}

#[test]
fn a_bracket_without_the_transition_is_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    let study = dir.path().join("s.toml");
    for (low, high, needle) in [
        (
            40.0,
            50.0,
            "at 1 points the disturbance dies out even at the top of the bracket (high = 50)",
        ),
        (
            75.0,
            90.0,
            "and at 1 it keeps hunting even at the bottom (low = 75)",
        ),
    ] {
        std::fs::write(&study, study_text("kind = \"nominal\"", low, high)).unwrap();
        let o = run_study(&study, &dir.path().join(format!("out{low}")), &[]);
        let err = failed(&o);
        assert!(
            err.contains("quantity 'v_hunt'") && err.contains(needle),
            "{err}"
        );
        assert_contains(&err, "widen the bracket");
    }
    // A weighted design with a point outside: the same message, and a hint.
    std::fs::write(
        &study,
        study_text("kind = \"scm\"\nnodes = 2\norder = 1", 60.0, 69.0),
    )
    .unwrap();
    let o = run_study(&study, &dir.path().join("scm"), &[]);
    let err = failed(&o);
    assert_contains(
        &err,
        "widen the bracket (or use a method that can leave points out",
    );
}

#[test]
fn a_nested_study_whose_bracket_misses_the_transition_names_the_bracket() {
    // Before: the nested path said only "N of M weighted points have no value".
    let dir = tempfile::tempdir().unwrap();
    let study = dir.path().join("s.toml");
    let text = study_text(
        "kind = \"nested\"\nouter = { kind = \"mc\", samples = 2 }\n\
         inner = { kind = \"scm\", nodes = 2, order = 1 }",
        60.0,
        69.0,
    )
    .replace(
        "name = \"K_phi\"\nmean = 2.71e6\ncov = 0.1\n",
        "name = \"K_phi\"\nmean = 2.71e6\ncov = 0.1\nlevel = \"outer\"\n",
    );
    assert!(text.contains("level = \"outer\""));
    std::fs::write(&study, text).unwrap();
    let o = run_study(&study, &dir.path().join("nested"), &[]);
    let err = failed(&o);
    assert!(
        err.contains("quantity 'v_hunt'")
            && err.contains("the top of the bracket (high = 69)")
            && err.contains("widen the bracket (or use a method that can leave points out"),
        "{err}"
    );
}

#[test]
fn settings_that_do_not_fit_the_fmu_are_refused_before_any_run() {
    let dir = tempfile::tempdir().unwrap();
    let study = dir.path().join("s.toml");
    let base = study_text("kind = \"nominal\"", LOW, HIGH);
    for (text, needle) in [
        (
            base.replace("speed_parameter = \"V0\"", "speed_parameter = \"K_sy\""),
            "the speed parameter 'K_sy' is a random parameter",
        ),
        (
            base.replace("speed_parameter = \"V0\"", "speed_parameter = \"V00\""),
            "no variable named 'V00'",
        ),
        (
            base.replace("ramp = 0.0", "ramp = 0.0, C_sy = 1.0"),
            "`set` names 'C_sy', a random parameter",
        ),
        (
            base.replace("ramp = 0.0", "rampe = 0.0"),
            "no variable named 'rampe'",
        ),
        (
            base.replace("signal = \"Y\"", "signal = \"YY\""),
            "no variable named 'YY'",
        ),
        (
            base.replace(
                "speed_parameter = \"V0\"",
                "speed_parameter = \"v_cr_linear\"",
            ),
            "may not be set before initialization",
        ),
    ] {
        std::fs::write(&study, text).unwrap();
        let out = dir.path().join("out");
        let o = run_study(&study, &out, &[]);
        let err = failed(&o);
        assert!(err.contains(needle), "{err} should mention {needle}");
        assert!(
            !out.join("store").exists()
                || std::fs::read_dir(out.join("store")).unwrap().count() == 0
        );
    }
}

/// A suite whose variants compute different quantities (`quantities = [...]`, as
/// paper-bogie's LHS 20 000 leaves the constant-speed runs out): the comparison matches
/// quantities by name, even when the reference lacks one.
#[test]
fn suite_variants_that_leave_a_quantity_out_are_compared_by_name() {
    let wheel = bogie_fmu().with_file_name("Wheel.fmu");
    let dir = tempfile::tempdir().unwrap();
    let study = dir.path().join("s.toml");
    let text = format!(
        "name = \"suite\"\nfmu = {:?}\nreference = \"b\"\n\
         [experiment]\nstop = 1.0\nstep = 0.01\n[method]\nkind = \"mc\"\nsamples = 10\n\
         [[parameters]]\nname = \"K\"\nmean = 100.0\nstd = 10.0\n\
         [[parameters]]\nname = \"C\"\nmean = 20.0\nstd = 2.0\n\
         [[qoi]]\nkind = \"max_abs\"\nname = \"peak\"\nsignal = \"q\"\nfrom = 0.5\n\
         [[qoi]]\nkind = \"final\"\nname = \"end\"\nsignal = \"q\"\n\
         [[variants]]\nname = \"a\"\n\
         [[variants]]\nname = \"b\"\nmethod = {{ kind = \"mc\", samples = 12 }}\nquantities = [\"end\"]\n",
        utf8(&wheel)
    );
    std::fs::write(&study, text).unwrap();
    let out = dir.path().join("out");
    run_study_ok(&study, &out, &[]);
    let summary = summary(&out);
    let names = |v: &serde_json::Value| -> Vec<String> {
        v["quantities"]
            .as_array()
            .unwrap()
            .iter()
            .map(|q| q["name"].as_str().unwrap().to_owned())
            .collect()
    };
    assert_eq!(names(&summary["variants"][0]), ["peak", "end"]);
    assert_eq!(names(&summary["variants"][1]), ["end"]);
    // Each comparison file holds the variants that have the quantity, with their own means.
    let rows = |q: &str| -> Vec<Vec<f64>> {
        std::fs::read_to_string(out.join(format!("{q}_compare.csv")))
            .unwrap()
            .lines()
            .skip(1)
            .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
            .collect()
    };
    let mean = |v: usize, qi: usize| {
        summary["variants"][v]["quantities"][qi]["mean"]
            .as_f64()
            .unwrap()
    };
    let peak = rows("peak");
    assert_eq!(peak.len(), 1);
    assert_eq!(
        (peak[0][0], peak[0][1], peak[0][2]),
        (0.0, 10.0, mean(0, 0))
    );
    let end = rows("end");
    assert_eq!(end.len(), 2);
    assert_eq!((end[0][0], end[0][2]), (0.0, mean(0, 1)));
    assert_eq!((end[1][0], end[1][1], end[1][2]), (1.0, 12.0, mean(1, 0)));
    // The table of variants: the reference's quantities first (end, then peak); b's cells of
    // peak are blank.
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    let row_b = html
        .split("<tr>")
        .find(|r| r.starts_with("<td>b</td>"))
        .expect("row of b");
    let row_b = &row_b[..row_b.find("</tr>").expect("end of the row")];
    let cells: Vec<&str> = row_b.split("<td").skip(1).collect();
    // variant, method, runs, wall time, mean/Std end, mean/Std peak (blank).
    assert_eq!(cells.len(), 8, "{row_b}");
    // The mean to the resolution of its Std, as the page writes statistics (M8).
    let std_b = summary["variants"][1]["quantities"][0]["std"]
        .as_f64()
        .unwrap();
    let text = uq_driver::results::numbers::to_spread(mean(1, 0), std_b);
    assert!(cells[4].contains(&text), "{text} not in {row_b}");
    assert_contains(
        &html,
        "<th>mean end [m]</th><th>Std end [m]</th><th>mean peak [m]</th>",
    );
    assert_eq!(&cells[6..], ["></td>", "></td>"], "{row_b}");
}
