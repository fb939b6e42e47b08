//! The importer: uq-driver against the Features test FMU (`tests/fmus/features`), every
//! expectation computed here from the FMU's documented behaviour (its README), independently of
//! the driver: parameters of every type read back through outputs, inputs applied as fmpy
//! applies them, an FMU that ends the simulation, a stop time off the grid, and CSV numbers.
//! The same runs are cross-checked against fmpy in `tests/python/test_importer_vs_fmpy.py`.

use std::path::{Path, PathBuf};

use crate::support::csv::Csv;
use crate::support::{
    assert_contains, built_fmu, edit, failed, read, read_json, run, run_study, run_study_ok,
    stderr, succeeded, test_fmus, utf8, write_toml,
};

fn features() -> Option<PathBuf> {
    test_fmus::test_fmu("Features")
}

/// Parses a CSV written by the driver (every field a number).
fn read_csv(text: &str) -> Csv {
    Csv::parse(text).numeric()
}

/// `uq-driver simulate FMU` with the arguments `line` (split at white space) and then `extra`,
/// which must succeed; returns its standard output and standard error.
fn simulate(fmu: &Path, line: &str, extra: &[&str]) -> (String, String) {
    let mut all = vec!["simulate", utf8(fmu)];
    all.extend(line.split_whitespace());
    all.extend_from_slice(extra);
    let o = run(&all);
    let stderr = stderr(&o);
    assert!(o.status.success(), "{stderr}");
    (String::from_utf8(o.stdout).unwrap(), stderr)
}

#[test]
fn integer_boolean_enumeration_and_string_parameters_reach_the_fmu() {
    let Some(fmu) = features() else { return };
    let (out, _) = simulate(
        &fmu,
        "--set int_param=-17 --set bool_param=true --set enum_param=3 --step 0.5",
        &["--set", "string_param=grüße, 世界"],
    );
    let csv = read_csv(&out);
    assert_eq!(csv.col("int_out"), [-17.0; 3]);
    assert_eq!(csv.col("bool_out"), [1.0; 3]);
    assert_eq!(csv.col("enum_out"), [3.0; 3]);
    // string_len = strlen(string_param) in bytes.
    let len = "grüße, 世界".len() as f64;
    assert_eq!(csv.col("string_len"), [len; 3]);
}

#[test]
fn simulate_without_outputs_records_every_number_and_names_the_string_it_skips() {
    // An FMU with only non-Real outputs wrote a CSV with only `time`, silently.
    let Some(fmu) = features() else { return };
    let (out, err) = simulate(&fmu, "--step 0.5", &[]);
    let csv = read_csv(&out);
    for name in [
        "u_echo",
        "u_integral",
        "file_value",
        "u_gain",
        "int_out",
        "enum_out",
        "string_len",
        "k_echo",
        "bool_out",
        "flag_echo",
    ] {
        assert!(
            csv.header.iter().any(|h| h == name),
            "{name} missing: {:?}",
            csv.header
        );
    }
    assert!(!csv.header.iter().any(|h| h == "string_out"));
    assert!(
        err.contains("'string_out' not recorded") && err.contains("String"),
        "{err}"
    );
    assert_eq!(csv.col("int_out"), [3.0; 3], "start value");
    assert_eq!(csv.col("enum_out"), [2.0; 3], "start value (green)");
    assert_eq!(csv.col("file_value"), [2.5e-3; 3], "resources/value.txt");
}

#[test]
fn wrong_values_for_typed_variables_are_refused_clearly() {
    let Some(fmu) = features() else { return };
    let f = utf8(&fmu);
    for (set, needle) in [
        ("int_param=2.5", "not a whole number"),
        ("bool_param=maybe", "true/false"),
        ("u=abc", "not a number"),
        ("nothere=1", "no variable named 'nothere'"),
    ] {
        let o = run(&["simulate", f, "--set", set]);
        let err = failed(&o);
        assert!(err.contains(needle), "{set}: {err}");
    }
    let o = run(&["simulate", f, "--output", "string_out"]);
    assert!(stderr(&o).contains("can be recorded"));
}

#[test]
fn input_signals_are_applied_as_fmpy_applies_them() {
    let Some(fmu) = features() else { return };
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("signal.csv");
    // A jump at 0.5 (time given twice), Integer and Boolean columns held.
    std::fs::write(
        &input,
        "time,u,k,flag\n0,0,0,false\n0.5,1,2,false\n0.5,1,5,true\n1,-2,5,true\n",
    )
    .unwrap();
    let (out, _) = simulate(
        &fmu,
        "--step 0.1 --output u_echo --output u_integral --output k_echo --output flag_echo",
        &["--input", utf8(&input)],
    );
    let csv = read_csv(&out);
    let t = csv.col("time");
    assert_eq!(t.len(), 11);
    // fmpy sets the inputs at the start of each step t_n (after a jump there); the FMU holds
    // them over the step, so the row at t_{n+1} shows u(t_n), and u_integral is the left sum.
    let u = |x: f64| {
        if x < 0.5 - 1e-12 {
            2.0 * x
        } else {
            1.0 - 6.0 * (x - 0.5)
        }
    };
    let (mut integral, echo, integ) = (0.0, csv.col("u_echo"), csv.col("u_integral"));
    assert_eq!(echo[0], 0.0);
    for n in 0..10 {
        let applied = u(t[n]);
        assert!(
            (echo[n + 1] - applied).abs() < 1e-14,
            "u_echo at {}",
            t[n + 1]
        );
        integral += applied * (t[n + 1] - t[n]);
        assert!(
            (integ[n + 1] - integral).abs() < 1e-14,
            "u_integral at {}",
            t[n + 1]
        );
        let after = t[n] >= 0.5 - 1e-12;
        assert_eq!(csv.col("k_echo")[n + 1], if after { 5.0 } else { 0.0 });
        assert_eq!(csv.col("flag_echo")[n + 1], if after { 1.0 } else { 0.0 });
    }
}

#[test]
fn an_fmu_that_ends_the_simulation_ends_simulate_there_not_in_an_error() {
    // Stair (Reference-FMUs) asks to stop at t = 9; uq-driver reported a failure.
    let Some(fmu) = features() else { return };
    for (stop_at, last, rows) in [("0.55", 0.55, 7), ("0.5", 0.5, 6)] {
        let (out, err) = simulate(
            &fmu,
            "--set u=2 --stop 2 --step 0.1 --output u_integral",
            &["--set", &format!("stop_at={stop_at}")],
        );
        let csv = read_csv(&out);
        let t = csv.col("time");
        assert_eq!(t.len(), rows, "{out}");
        assert_eq!(*t.last().unwrap(), last);
        assert!(t.windows(2).all(|w| w[1] > w[0]), "no duplicate row");
        let integral = *csv.col("u_integral").last().unwrap();
        assert!((integral - 2.0 * last).abs() < 1e-12, "{integral}");
        assert_contains(&err, &format!("ended the simulation at t = {last} s"));
    }
}

#[test]
fn a_study_counts_a_run_the_fmu_ends_early_as_failed_and_keeps_runs_that_reach_the_stop() {
    let Some(fmu) = features() else { return };
    let dir = tempfile::tempdir().unwrap();
    // stop_at uniform on [0.5, 2]: runs with stop_at < 1 end early (failed, allowed), the others
    // reach the stop time 1 s (stop_at = 1 exactly would end at the stop time: a whole run).
    let study = early_study(
        dir.path(),
        &fmu,
        "[outputs]\nvariables = [\"u_integral\"]\n[analysis]\nallow_failures = true\n",
    );
    let out = dir.path().join("out");
    run_study_ok(&study, &out, &[]);
    let points = read(&out.join("points.csv"));
    let mut failed = 0;
    for line in points.lines().skip(1) {
        let stop_at: f64 = line.split(',').nth(1).unwrap().parse().unwrap();
        if stop_at < 1.0 - 1e-9 {
            failed += 1;
            assert_contains(line, "ended the simulation at t =");
        } else {
            assert!(line.ends_with(",ok"), "{line}");
        }
    }
    assert!(failed > 0 && failed < 16, "{points}");
    let summary = read(&out.join("summary.json"));
    assert_contains(&summary, &format!("\"failed_runs\": {failed}"));
}

/// A study of the Features FMU over `stop_at` uniform on [0.5, 2] (runs with stop_at < 1 end
/// before the stop time 1 s) at u = 1, with `rest` appended (its quantities, outputs).
fn early_study(dir: &Path, fmu: &Path, rest: &str) -> PathBuf {
    let experiment = "stop = 1.0\nstep = 0.1";
    let rest = format!("[fixed]\nu = 1\n{rest}");
    mc_study(
        dir,
        fmu,
        ["early", experiment],
        16,
        ("stop_at", 0.5, 2.0),
        &rest,
    )
}

/// `s.toml` in `dir`: the Monte Carlo study `name` of the Features FMU `fmu` with the
/// `[experiment]` keys `experiment`, `samples` runs over the one random parameter `parameter`
/// uniform on [low, high], and `rest` appended.
fn mc_study(
    dir: &Path,
    fmu: &Path,
    [name, experiment]: [&str; 2],
    samples: u32,
    (parameter, low, high): (&str, f64, f64),
    rest: &str,
) -> PathBuf {
    let text = format!(
        "name = \"{name}\"\nfmu = {:?}\n[experiment]\n{experiment}\n\
         [method]\nkind = \"mc\"\nsamples = {samples}\n\
         [[parameters]]\nname = \"{parameter}\"\ndistribution = \"uniform\"\nlow = {low}\n\
         high = {high}\n{rest}",
        utf8(fmu)
    );
    write_toml(dir, "s", &text)
}

#[test]
fn a_run_the_fmu_ends_early_takes_the_if_ended_value_and_counts_beyond_the_limit() {
    // A derailment ends the Vehicle's run: for P(Y/Q > 0.8) such a run must count as an
    // exceedance, not drop out as a failed point.
    let Some(fmu) = features() else { return };
    let dir = tempfile::tempdir().unwrap();
    let study = early_study(
        dir.path(),
        &fmu,
        "[[qoi]]\nkind = \"max\"\nname = \"peak\"\nsignal = \"u_integral\"\n\
         if_ended = 100.0\nlimits = [50.0]\n",
    );
    let out = dir.path().join("out");
    run_study_ok(&study, &out, &[]);
    let points = Csv::read(&out.join("points.csv"));
    let (runs, stop_at) = (points.col("index"), points.col("stop_at"));
    let peaks = Csv::read(&out.join("peak_samples.csv")).numbers();
    assert_eq!(peaks.len(), 16);
    let mut ended = 0;
    for row in &peaks {
        let s = stop_at[runs.iter().position(|&r| r == row[0]).unwrap()];
        if s < 1.0 - 1e-9 {
            ended += 1;
            assert_eq!(row[1], 100.0, "stop_at {s}");
        } else {
            // u = 1 integrated over the whole second.
            assert!((row[1] - 1.0).abs() < 1e-12, "stop_at {s}: {}", row[1]);
        }
    }
    assert!(ended > 0 && ended < 16, "{ended}");
    let summary = read_json(&out.join("summary.json"));
    assert_eq!(summary["failed_runs"], 0, "{summary}");
    let counts = &summary["quantities"]["peak"]["exceedance_counts"][0];
    assert_eq!(counts["exceeded"], ended, "{counts}");
    let text = summary["quantities"]["peak"]["definition"]["text"]
        .as_str()
        .unwrap();
    assert_contains(text, "100 in a run the FMU ends before the stop time");
}

#[test]
fn if_ended_on_some_quantities_only_or_with_stored_series_is_refused() {
    let Some(fmu) = features() else { return };
    let dir = tempfile::tempdir().unwrap();
    let peak =
        "[[qoi]]\nkind = \"max\"\nname = \"peak\"\nsignal = \"u_integral\"\nif_ended = 100.0\n";
    for (rest, expected) in [
        (
            format!("{peak}[[qoi]]\nkind = \"final\"\nname = \"last\"\nsignal = \"u_integral\"\n"),
            "quantity 'peak' sets if_ended but 'last' does not",
        ),
        (
            format!("{peak}[outputs]\nvariables = [\"u_integral\"]\n"),
            "quantity 'peak' sets if_ended, but the study stores output series",
        ),
        (
            "[[qoi]]\nkind = \"max\"\nname = \"peak\"\nsignal = \"u_integral\"\nif_ended = nan\n"
                .to_owned(),
            "if_ended must be finite",
        ),
    ] {
        let study = early_study(dir.path(), &fmu, &rest);
        let o = run_study(&study, &dir.path().join("out"), &[]);
        let err = stderr(&o);
        assert!(
            !o.status.success() && err.contains(expected),
            "{rest}: {err}"
        );
    }
}

#[test]
fn a_stop_time_off_the_grid_ends_with_a_shorter_step() {
    // "stop − start is not a whole number of steps" was an error; fmpy takes a
    // shorter last step.
    let Some(fmu) = features() else { return };
    let (out, _) = simulate(
        &fmu,
        "--set u=1 --stop 1.05 --step 0.1 --output u_integral",
        &[],
    );
    let csv = read_csv(&out);
    let t = csv.col("time");
    assert_eq!(t.len(), 12);
    assert_eq!(t[10], 10.0 * 0.1);
    assert_eq!(t[11], 1.05);
    assert!((csv.col("u_integral")[11] - 1.05).abs() < 1e-12);
    let o = run(&["simulate", utf8(&fmu), "--step", "0"]);
    assert_contains(
        &failed(&o),
        "--step 0: the communication step must be positive",
    );
}

#[test]
fn csv_numbers_are_short_and_read_back_exactly() {
    // 2.2e-308 was written as a 326-character decimal.
    let Some(fmu) = features() else { return };
    let (out, _) = simulate(&fmu, "--set u=2.2e-308 --step 0.5 --output u_echo", &[]);
    assert_eq!(out, "time,u_echo\n0,2.2e-308\n0.5,2.2e-308\n1,2.2e-308\n");
    let (out, _) = simulate(
        &fmu,
        "--set u=1.7976931348623157e308 --step 1 --output u_echo",
        &[],
    );
    assert!(out.ends_with("1,1.7976931348623157e308\n"), "{out}");
}

#[test]
fn study_fixed_values_of_every_type_and_integer_random_parameters_reach_the_fmu() {
    let Some(fmu) = features() else { return };
    let dir = tempfile::tempdir().unwrap();
    // misbehave_at, an ordinary Real, is the random parameter; int_param, bool_param,
    // enum_param and string_param come from [fixed] in all their TOML forms.
    let study = mc_study(
        dir.path(),
        &fmu,
        ["typed", "stop = 0.2\nstep = 0.1"],
        3,
        ("gain", 1.0, 2.0),
        "[fixed]\nint_param = -4\nbool_param = true\nenum_param = 1\nstring_param = \"abcdef\"\n\
         u = 2\n[outputs]\nvariables = [\"int_out\", \"bool_out\", \"enum_out\", \"string_len\", \
         \"u_gain\"]\n",
    );
    let out = dir.path().join("out");
    run_study_ok(&study, &out, &[]);
    let mean = |name: &str| read_csv(&read(&out.join(format!("{name}.csv")))).col("mean");
    assert_eq!(mean("int_out"), [-4.0; 3]);
    assert_eq!(mean("bool_out"), [1.0; 3]);
    assert_eq!(mean("enum_out"), [1.0; 3]);
    assert_eq!(mean("string_len"), [6.0; 3]);
    // u_gain = gain u with gain ~ U(1, 2): mean 2 gain over 3 samples, the same at every time.
    let g = mean("u_gain");
    assert!(g.iter().all(|&x| x > 2.0 && x < 4.0 && x == g[0]), "{g:?}");

    // An Integer variable as the random parameter: a normal design has fractional values and
    // is refused before any run, with a message that says why.
    edit(&study, "name = \"gain\"", "name = \"int_param\"");
    edit(&study, "int_param = -4\n", "");
    let o = run_study(&study, &out, &["--fresh"]);
    let err = failed(&o);
    assert!(
        err.contains("random parameter 'int_param' is an Integer variable")
            && err.contains("not a whole number"),
        "{err}"
    );
}

#[test]
fn a_study_applies_its_input_file_and_resumes_only_with_the_same_signals() {
    let Some(fmu) = features() else { return };
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("signal.csv"), "time,u\n0,0\n1,1\n").unwrap();
    let study = mc_study(
        dir.path(),
        &fmu,
        ["inputs", "stop = 1\nstep = 0.25"],
        2,
        ("gain", 1.0, 2.0),
        "[inputs]\nfile = \"signal.csv\"\n[outputs]\nvariables = [\"u_echo\"]\n",
    );
    let out = dir.path().join("out");
    let run = |extra: &[&str]| run_study(&study, &out, extra);
    succeeded(&run(&[]), &study);
    let csv = read_csv(&read(&out.join("u_echo.csv")));
    // u(t) = t applied at the start of each step: the row at t_{n+1} shows t_n.
    assert_eq!(csv.col("mean"), [0.0, 0.0, 0.25, 0.5, 0.75]);
    // Other signals change the records: the folder is not resumed with them.
    std::fs::write(dir.path().join("signal.csv"), "time,u\n0,0\n1,2\n").unwrap();
    let o = run(&[]);
    assert_contains(&failed(&o), "different study");
    // A column that is not an input is refused with the file's name.
    std::fs::write(dir.path().join("signal.csv"), "time,u_echo\n0,0\n1,2\n").unwrap();
    let o = run(&["--fresh"]);
    let err = stderr(&o);
    assert!(
        err.contains("signal.csv") && err.contains("only inputs"),
        "{err}"
    );
}

#[test]
fn vehicle_track_measured_profile_is_set_from_the_command_line() {
    // irregularity = 10 with profile_file could not be used from uq-driver.
    let vt = built_fmu("VehicleTrack");
    let dir = tempfile::tempdir().unwrap();
    let profile = dir.path().join("track.csv");
    // z = 1 mm sin(2 pi x / 5 m) from x = -50 m to 150 m: the rail under wheel 1 is this
    // profile at the wheel's position (x = v t + x_1, v = 83.33 m/s) once the ramp is passed.
    let mut text = String::from("x,z\n");
    for i in 0..=2000 {
        let x = -50.0 + 0.1 * f64::from(i);
        text.push_str(&format!(
            "{x},{}\n",
            1e-3 * (2.0 * std::f64::consts::PI * x / 5.0).sin()
        ));
    }
    std::fs::write(&profile, text).unwrap();
    let (out, _) = simulate(
        &vt,
        "--set irregularity=10 --set ramp_length=0 --stop 0.1 --step 0.001 --output Z0_1",
        &["--set", &format!("profile_file={}", profile.display())],
    );
    let csv = read_csv(&out);
    let z = csv.col("Z0_1");
    let peak = z.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    assert!(peak > 0.9e-3 && peak <= 1.0e-3 + 1e-12, "peak {peak}");
    // A missing profile is the FMU's error, named.
    let o = run(&[
        "simulate",
        utf8(&vt),
        "--set",
        "irregularity=10",
        "--set",
        "profile_file=/nonexistent/track.csv",
        "--stop",
        "0.01",
        "--step",
        "0.001",
    ]);
    assert_contains(&failed(&o), "/nonexistent/track.csv");
}
