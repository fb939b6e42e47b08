//! Tests of study files: every built-in parses; wrong files give errors with their place.

use super::*;

#[test]
fn every_builtin_parses() {
    for (name, _) in BUILTINS {
        let s = Study::load(&format!("builtin:{name}")).unwrap();
        assert_eq!(&s.name, name);
        if let Some(suite) = &s.suite {
            assert!(suite.reference < suite.variants.len());
        }
    }
}

#[test]
fn wrong_study_files_give_clear_errors() {
    let base = include_str!("../../studies/wheel-scm.toml");
    let cases = [
        (base.replace("stop = 5.0", "stop = -1.0"), "start < stop"),
        (base.replace("order = 5", "order = 6"), "below the nodes"),
        (base.replace("std = 10.0", "std = -10.0"), "parameter 'K'"),
        (
            base.replace("kind = \"scm\"", "kind = \"magic\""),
            "unknown variant",
        ),
        (
            base.replace("[outputs]", "[outputs]\ncolour = 1"),
            "unknown field",
        ),
        (
            base.replace("step = 0.01", "step = 0.0"),
            "communication step is 0",
        ),
        // Settings of another method are not representable.
        (
            base.replace("nodes = 6", "nodes = 6\nsamples = 100"),
            "unknown field `samples`",
        ),
        (
            base.replace("distribution = \"normal\"", "distribution = \"uniform\""),
            "unknown field",
        ),
    ];
    for (text, needle) in cases {
        let err = Study::parse(&text, "t.toml", None).unwrap_err().to_string();
        assert!(err.contains(needle), "{err} should mention {needle}");
        assert!(err.starts_with("t.toml:"), "{err}");
    }
    assert!(matches!(
        Study::load("builtin:nope"),
        Err(StudyError::UnknownBuiltin(_))
    ));
    assert!(matches!(
        Study::load("/nonexistent.toml"),
        Err(StudyError::Io { .. })
    ));
}

#[test]
fn errors_point_at_the_line_and_column() {
    let base = include_str!("../../studies/wheel-scm.toml");
    let line_of = |needle: &str| base.lines().position(|l| l.contains(needle)).unwrap() + 1;
    // A bad value inside the second parameter: the error names that [[parameters]] table.
    let text = base.replace("std = 2.0", "std = -2.0");
    match Study::parse(&text, "t.toml", None).unwrap_err() {
        StudyError::Invalid { at: Some(at), .. } => {
            let header = text
                .lines()
                .take(at.line)
                .filter(|l| l.starts_with("[[parameters]]"));
            assert_eq!(header.count(), 2, "{at}");
        }
        e => panic!("{e}"),
    }
    // A key the method does not have: the error points into [method].
    let text = base.replace("order = 5", "order = 5\nlevel = 3");
    match Study::parse(&text, "t.toml", None).unwrap_err() {
        StudyError::Parse { at, message, .. } => {
            assert!(message.contains("unknown field `level`"), "{message}");
            assert!(at.line >= line_of("[method]") && at.line <= line_of("order = 5") + 1);
        }
        e => panic!("{e}"),
    }
    // A syntax error: its own line and column.
    let text = base.replace("seed = 42", "seed = = 42");
    match Study::parse(&text, "t.toml", None).unwrap_err() {
        StudyError::Parse { at, .. } => assert_eq!(at.line, line_of("seed = 42")),
        e => panic!("{e}"),
    }
}

#[test]
fn an_unknown_key_is_pointed_at_not_its_table() {
    // README audit F9: `level` in an scm [method] was reported at the `[method]` header line.
    let base = include_str!("../../studies/wheel-scm.toml");
    let text = base.replace("order = 5", "order = 5\n\nlevel = 3");
    let line = text.lines().position(|l| l == "level = 3").unwrap() + 1;
    match Study::parse(&text, "t.toml", None).unwrap_err() {
        StudyError::Parse { at, message, .. } => {
            assert!(message.contains("unknown field `level`"), "{message}");
            assert_eq!(at, Location { line, column: 1 }, "{message}");
        }
        e => panic!("{e}"),
    }
    // In the second [[parameters]] table (toml spans the array from its first header).
    let text = base.replacen("std = 2.0", "std = 2.0\n  lowe = 1.0", 1);
    let line = text.lines().position(|l| l.contains("lowe = 1.0")).unwrap() + 1;
    match Study::parse(&text, "t.toml", None).unwrap_err() {
        StudyError::Parse { at, message, .. } => assert_eq!(at.line, line, "{message}"),
        e => panic!("{e}"),
    }
}

#[test]
fn location_counts_lines_and_characters() {
    let text = "a = 1\nbé = 2\n";
    assert_eq!(Location::of(text, 0), Location { line: 1, column: 1 });
    assert_eq!(Location::of(text, 6), Location { line: 2, column: 1 });
    assert_eq!(Location::of(text, 9), Location { line: 2, column: 3 });
}

#[test]
fn times_do_not_drift() {
    let e = Experiment {
        start: 0.0,
        stop: 5.0,
        step: 0.01,
    };
    let t = e.times();
    assert_eq!(t.len(), 501);
    assert_eq!(t[500], 5.0);
    assert_eq!(t[3], 0.03);
}

#[test]
fn correlations_are_checked_where_they_are_written() {
    let base = include_str!("../../studies/wheel-scm.toml");
    let with = |extra: &str| format!("{base}\n{extra}");
    let ok = Study::parse(
        &with("[[correlation]]\nbetween = [\"K\", \"C\"]\nrho = 0.5"),
        "t.toml",
        None,
    )
    .unwrap();
    let c = ok.correlation.as_ref().unwrap();
    // Two normal inputs: the normal-space correlation is the requested one.
    assert!((c.normal_correlation[(0, 1)] - 0.5).abs() < 1e-12);
    assert_eq!(ok.random_inputs().correlation.as_ref(), Some(c));
    for (extra, needle) in [
        (
            "[[correlation]]\nbetween = [\"K\", \"X\"]\nrho = 0.5",
            "'X' is not a random parameter",
        ),
        (
            "[[correlation]]\nbetween = [\"K\", \"C\"]\nrho = 1.5",
            "strictly between -1 and 1",
        ),
        (
            "[[correlation]]\nbetween = [\"K\", \"C\"]\nrho = 0.5\ncolour = 1",
            "unknown field",
        ),
    ] {
        let err = Study::parse(&with(extra), "t.toml", None)
            .unwrap_err()
            .to_string();
        assert!(err.contains(needle), "{err} should mention {needle}");
        assert!(err.starts_with("t.toml:"), "{err}");
    }
    // Three inputs whose pairwise correlations cannot coexist.
    let three = base.replace(
        "[outputs]",
        "[[parameters]]\nname = \"m\"\nmean = 10.0\nstd = 1.0\n\n[outputs]",
    );
    let text = format!(
        "{three}\n[[correlation]]\nbetween = [\"K\", \"C\"]\nrho = 0.9\n\
         [[correlation]]\nbetween = [\"C\", \"m\"]\nrho = 0.9\n\
         [[correlation]]\nbetween = [\"K\", \"m\"]\nrho = -0.9"
    );
    let err = Study::parse(&text, "t.toml", None).unwrap_err().to_string();
    assert!(err.contains("not positive definite"), "{err}");
    // SGM refuses correlated inputs.
    let sgm = include_str!("../../studies/wheel-sgm.toml");
    let err = Study::parse(
        &format!("{sgm}\n[[correlation]]\nbetween = [\"K\", \"C\"]\nrho = 0.3"),
        "t.toml",
        None,
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("independent Gaussian"), "{err}");
}

#[test]
fn a_stop_time_off_the_grid_gets_a_shorter_last_step_not_an_error() {
    // Regression: stop − start not a whole number of steps was refused; fmpy ends with a
    // shorter step.
    let e = Experiment {
        start: 0.0,
        stop: 1.05,
        step: 0.1,
    };
    e.check().unwrap();
    let t = e.times();
    assert_eq!(t.len(), 12);
    assert_eq!(t[10], 10.0 * 0.1);
    assert_eq!(t[11], 1.05);
    assert_eq!(e.n_steps(), 11);
    // Within 1e-6 of a whole number of steps: the grid ends at stop with a full step.
    let e = Experiment {
        start: 0.0,
        stop: 5.0 + 1e-9,
        step: 0.01,
    };
    assert_eq!(e.times().len(), 501);
    assert_eq!(e.n_steps(), 500);
}

#[test]
fn a_zero_step_has_its_own_message() {
    let e = Experiment {
        start: 0.0,
        stop: 1.0,
        step: 0.0,
    };
    let err = e.check().unwrap_err();
    assert_eq!(err, InvalidExperiment::ZeroStep);
    assert!(err.to_string().contains("step is 0"), "{err}");
}

#[test]
fn hunting_speed_yields_two_quantities_and_variants_can_leave_quantities_out() {
    let s = Study::load("builtin:paper-bogie").unwrap();
    let names =
        |s: &Study| -> Vec<String> { s.qoi.iter().flat_map(|q| q.quantity_names()).collect() };
    assert_eq!(names(&s), ["v_cr", "v_cr_linear", "v_hunt", "v_hunt_decay"]);
    let times = s.times();
    assert_eq!(s.problem(&times).quantities, 4);
    let suite = s.suite.as_ref().unwrap();
    for v in &suite.variants {
        let expected: &[&str] = if v.name == "lhs-20000" {
            &["v_cr", "v_cr_linear"]
        } else {
            &["v_cr", "v_cr_linear", "v_hunt", "v_hunt_decay"]
        };
        assert_eq!(names(v), expected, "variant {}", v.name);
    }
    let base = include_str!("../../studies/paper-bogie.toml");
    let cases = [
        // The second quantity's name is taken like any other.
        (
            base.replace("name = \"v_cr_linear\"", "name = \"v_hunt_decay\""),
            "quantity name 'v_hunt_decay' is used twice",
        ),
        (
            base.replace(
                "quantities = [\"v_cr\", \"v_cr_linear\"]",
                "quantities = [\"v_crr\"]",
            ),
            "'v_crr', which is not a [[qoi]]",
        ),
        (
            base.replace("tolerance = 0.02", "tolerance = 0.0"),
            "quantity 'v_hunt': tolerance must be > 0",
        ),
        (base.replace("low = 40.0", "low = 140.0"), "low < high"),
        (
            base.replace("duration = 300.0", "duration = 300.0\nspeed = \"V\""),
            "unknown field `speed`",
        ),
    ];
    for (text, needle) in cases {
        let err = Study::parse(&text, "t.toml", None).unwrap_err().to_string();
        assert!(err.contains(needle), "{err} should mention {needle}");
    }
}

/// F6: quantile columns were named by 100·p rounded to 0.1 (0.0015 → `q0.2`, 0.9951 →
/// `q99.5`), so distinct levels shared a name. The expected names are the percentages
/// written out by hand.
#[test]
fn quantile_column_names_are_exact_not_rounded_to_a_tenth_of_a_percent() {
    let cases = [
        // The names that were already exact stay as they were.
        (0.01, "q1"),
        (0.5, "q50"),
        (0.99, "q99"),
        (0.025, "q2.5"),
        (0.001, "q0.1"),
        (0.123, "q12.3"),
        (0.0, "q0"),
        (-0.0, "q0"),
        (1.0, "q100"),
        (0.1, "q10"),
        (0.05, "q5"),
        (0.975, "q97.5"),
        // The ones that were rounded (0.0015 · 100 is 0.15000000000000002 in binary).
        (0.0015, "q0.15"),
        (0.002, "q0.2"),
        (0.9951, "q99.51"),
        (0.995, "q99.5"),
        (0.123456, "q12.3456"),
        (0.00001, "q0.001"),
        (1e-7, "q0.00001"),
        (0.3333, "q33.33"),
    ];
    for (p, name) in cases {
        assert_eq!(quantile_column(p), name, "level {p}");
    }
}

/// F6: two levels that give one column name are refused when the study file is read.
#[test]
fn quantile_levels_that_share_a_column_name_are_refused() {
    let base = include_str!("../../studies/wheel-scm.toml");
    let with = |q: &str| format!("{base}\n[analysis]\nquantiles = {q}\n");
    for q in [
        "[0.5, 0.5]",
        "[0.01, 0.0, 0.3, -0.0]",
        "[0.995, 0.99, 0.995]",
    ] {
        let err = Study::parse(&with(q), "t.toml", None)
            .unwrap_err()
            .to_string();
        assert!(err.contains("both give the column"), "{q}: {err}");
    }
    for q in ["[0.001, 0.0015]", "[0.0015, 0.002]", "[0.995, 0.9951]"] {
        let s = Study::parse(&with(q), "t.toml", None).unwrap();
        assert_eq!(s.analysis.quantiles.len(), 2, "{q}");
    }
}

/// One bad `[analysis]` value was refused with the rules of every key, naming none.
#[test]
fn a_bad_analysis_value_is_refused_naming_its_key_and_rule() {
    let base = include_str!("../../studies/wheel-scm.toml");
    let with = |a: &str| format!("{base}\n[analysis]\n{a}\n");
    for (setting, needle) in [
        (
            "pdf_times = 0",
            "analysis: pdf_times = 0: must be at least 1",
        ),
        ("pdf_grid = 1", "analysis: pdf_grid = 1: must be at least 2"),
        (
            "surrogate_samples = 0",
            "analysis: surrogate_samples = 0: must be at least 2",
        ),
        (
            "series_samples = 1",
            "analysis: series_samples = 1: must be at least 2",
        ),
        (
            "quantiles = [0.5, 1.5]",
            "analysis: quantiles: level 1.5 must be in [0, 1]",
        ),
        (
            "quantiles = [-0.01]",
            "analysis: quantiles: level -0.01 must be in [0, 1]",
        ),
        (
            "quantiles = [nan]",
            "analysis: quantiles: level NaN must be in [0, 1]",
        ),
    ] {
        let err = Study::parse(&with(setting), "t.toml", None)
            .unwrap_err()
            .to_string();
        assert!(err.contains(needle), "{setting}: {err}");
        // Only the offending key's rule, not every key's.
        assert_eq!(err.matches("must be").count(), 1, "{setting}: {err}");
    }
}

/// The quantile levels 0 and 1 (the smallest and the largest value) are accepted, as the
/// reference documents: columns `q0` and `q100`.
#[test]
fn quantile_levels_zero_and_one_are_accepted_as_min_and_max() {
    let base = include_str!("../../studies/wheel-scm.toml");
    let s = Study::parse(
        &format!("{base}\n[analysis]\nquantiles = [0.0, 0.5, 1.0]\n"),
        "t.toml",
        None,
    )
    .unwrap();
    assert_eq!(s.analysis.quantiles, [0.0, 0.5, 1.0]);
    let sorted = [1.0, 2.0, 7.0];
    assert_eq!(crate::uq::moments::quantile(&sorted, 0.0), 1.0);
    assert_eq!(crate::uq::moments::quantile(&sorted, 1.0), 7.0);
}

#[test]
fn retained_variance_outside_zero_to_one_is_refused() {
    let base = include_str!("../../studies/wheel-scm.toml");
    let with = |a: &str| format!("{base}\n[analysis]\n{a}\n");
    for v in ["0.0", "-0.5", "1.0000001", "2.0", "nan"] {
        let err = Study::parse(&with(&format!("retained_variance = {v}")), "t.toml", None)
            .unwrap_err()
            .to_string();
        assert!(err.contains("retained_variance"), "{v}: {err}");
        assert!(err.contains("(0, 1]"), "{v}: {err}");
    }
    let err = Study::parse(&with("functional = \"modes\""), "t.toml", None)
        .unwrap_err()
        .to_string();
    assert!(err.contains("pca") && err.contains("columns"), "{err}");
    let s = Study::parse(&with("retained_variance = 1.0"), "t.toml", None).unwrap();
    assert_eq!(s.analysis.retained_variance, 1.0);
    assert_eq!(s.analysis.functional, crate::spec::Functional::Pca);
    let s = Study::parse(
        &with("functional = \"columns\"\nretained_variance = 0.99"),
        "t.toml",
        None,
    )
    .unwrap();
    assert_eq!(s.analysis.functional, crate::spec::Functional::Columns);
    assert_eq!(s.analysis.retained_variance, 0.99);
}

#[test]
fn quantity_settings_the_communication_grid_cannot_meet_are_refused_when_the_study_is_read() {
    let base = include_str!("../../studies/wheel-scm.toml");
    // wheel-scm: 0 to 5 s by 0.01 s (Nyquist 50 Hz).
    let with = |qoi: &str| format!("{base}\n{qoi}\n");
    let cases = [
        (
            with("[[qoi]]\nkind = \"sperling\"\nname = \"W\"\nsignal = \"z\"\ndirection = \"vertical\"\nsegment = 1.0\nf_min = 0.5\nf_max = 1000.0"),
            "f_max = 1000 Hz is above the Nyquist frequency 50 Hz of the communication step 0.01 s",
        ),
        (
            with("[[qoi]]\nkind = \"max_abs\"\nname = \"m\"\nsignal = \"z\"\nfrom = 6.0\nto = 7.0"),
            "the window from 6 s to 7 s holds no communication point",
        ),
        (
            with("[[qoi]]\nkind = \"range\"\nname = \"m\"\nsignal = \"z\"\nfrom = 0.001\nto = 0.002"),
            "the window from 0.001 s to 0.002 s holds no communication point",
        ),
        (
            with("[[qoi]]\nkind = \"max_abs\"\nname = \"m\"\nsignal = \"z\"\nfrom = 5.5"),
            "the window from 5.5 s to the stop time 5 s holds no communication point",
        ),
    ];
    for (text, needle) in cases {
        let err = Study::parse(&text, "t.toml", None).unwrap_err().to_string();
        assert!(err.contains(needle), "{err} should mention {needle}");
    }
    // Windows that hold a point, and f_max at Nyquist, are fine.
    for qoi in [
        "[[qoi]]\nkind = \"max_abs\"\nname = \"m\"\nsignal = \"z\"\nfrom = 4.995\nto = 5.0",
        "[[qoi]]\nkind = \"max_abs\"\nname = \"m\"\nsignal = \"z\"\nfrom = 5.0",
        "[[qoi]]\nkind = \"sperling\"\nname = \"W\"\nsignal = \"z\"\ndirection = \"vertical\"\nsegment = 1.0\nf_min = 0.5\nf_max = 50.0",
    ] {
        Study::parse(&with(qoi), "t.toml", None).unwrap();
    }
}
