//! Small probabilities from a study file: `kind = "form" | "sorm" | "importance_sampling" |
//! "subset" | "morris"` on the Functions test FMU (`function = 5`: y = x1 + … + x8, a limit
//! state linear in standard normal space for normal inputs, so `P` is known exactly;
//! `function = 6`: y = x1² + … + x8², a chi-square for standard normal inputs), and on the
//! Once test FMU for a run that fails. The references are closed forms written here (the
//! normal tail by its own continued fraction), never the code under test.

use std::path::{Path, PathBuf};

use serde_json::Value;

use crate::support::csv::Csv;
use crate::support::{
    assert_contains, failed, run, run_killed, run_study, run_study_ok, stderr, study_head, summary,
    test_fmus, write_toml,
};

/// `P(Z > z)` of a standard normal, by the Lentz continued fraction of Mills' ratio for
/// `z ≥ 3` and the series of `erf` below (relative error below 1e-12 in both).
fn normal_sf(z: f64) -> f64 {
    if z < 3.0 {
        // Φ(z) = 1/2 + φ(z) Σ z^(2k+1) / (1·3·…·(2k+1)).
        let phi = (-0.5 * z * z).exp() / (2.0 * std::f64::consts::PI).sqrt();
        let (mut term, mut sum) = (z, z);
        for k in 1..400 {
            term *= z * z / (2 * k + 1) as f64;
            sum += term;
            if term.abs() < 1e-17 * sum.abs() {
                break;
            }
        }
        return 0.5 - phi * sum;
    }
    // Mills' ratio R(z) = 1/(z + 1/(z + 2/(z + 3/(z + …)))), evaluated from the tail.
    let mut r = 0.0;
    for k in (1..200).rev() {
        r = k as f64 / (z + r);
    }
    (-0.5 * z * z).exp() / (2.0 * std::f64::consts::PI).sqrt() / (z + r)
}

/// The `z` with `P(Z > z) = p` (bisection on [`normal_sf`]).
fn normal_isf(p: f64) -> f64 {
    let (mut lo, mut hi) = (-10.0, 40.0);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if normal_sf(mid) > p {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// A study on the Functions FMU: `function`, the `[[parameters]]` (and `[[correlation]]`)
/// text `inputs`, the quantity `q` = y with `limits` (above) and `below`, the method table.
fn study(
    dir: &Path,
    name: &str,
    function: u32,
    inputs: &str,
    limits: &[f64],
    below: &[f64],
    method: &str,
) -> PathBuf {
    let fmu = test_fmus::test_fmu("Functions").expect("the Functions test FMU");
    let text = format!(
        "{head}[fixed]\nfunction = {function}\n{inputs}\n[outputs]\nvariables = [\"y\"]\n\
         [[qoi]]\nkind = \"final\"\nname = \"q\"\nsignal = \"y\"\nlimits = {limits:?}\n\
         limits_below = {below:?}\n[method]\n{method}\n",
        head = study_head(name, &fmu, 7, "start = 0.0\nstop = 0.1\nstep = 0.1"),
    );
    write_toml(dir, name, &text)
}

/// Eight normal inputs `x1..x8` (mean `i`, std `0.5 + 0.1 i`), `x1`–`x2` correlated by
/// 0.5 and `x3`–`x4` by −0.3; returns the text and the mean and Std of their sum.
fn correlated_normals() -> (String, f64, f64) {
    let mut text = String::new();
    let (mut mean, mut var) = (0.0, 0.0);
    let sd: Vec<f64> = (1..=8).map(|i| 0.5 + 0.1 * i as f64).collect();
    for i in 1..=8 {
        let m = i as f64;
        text += &format!(
            "[[parameters]]\nname = \"x{i}\"\ndistribution = \"normal\"\nmean = {m}\nstd = {}\n",
            sd[i - 1]
        );
        mean += m;
        var += sd[i - 1] * sd[i - 1];
    }
    text += "[[correlation]]\nbetween = [\"x1\", \"x2\"]\nrho = 0.5\n";
    text += "[[correlation]]\nbetween = [\"x3\", \"x4\"]\nrho = -0.3\n";
    // Normal marginals: the Gaussian copula's correlation is the requested one.
    var += 2.0 * 0.5 * sd[0] * sd[1] - 2.0 * 0.3 * sd[2] * sd[3];
    (text, mean, var.sqrt())
}

/// `quantities.q.reliability` of the output folder `out`.
/// Two parameters `x1`, `x2` of the same law (`law`: the keys after `name`).
fn two_inputs(law: &str) -> String {
    ["x1", "x2"]
        .iter()
        .map(|n| format!("[[parameters]]\nname = \"{n}\"\n{law}\n"))
        .collect()
}

fn reliability(out: &Path) -> Vec<Value> {
    summary(out)["quantities"]["q"]["reliability"]
        .as_array()
        .unwrap_or_else(|| panic!("no reliability in {}", out.display()))
        .clone()
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("{v} is not a number"))
}

#[test]
fn form_and_sorm_give_the_exact_probability_of_a_linear_sum_of_correlated_normals() {
    let Some(dir) = test_fmus::dir_if_built() else {
        return;
    };
    let (inputs, mean, sd) = correlated_normals();
    // P(q > a) = 1e-4 and P(q < b) = 1e-3 exactly.
    let (pa, pb) = (1e-4, 1e-3);
    let a = mean + sd * normal_isf(pa);
    let b = mean - sd * normal_isf(pb);
    for kind in ["form", "sorm"] {
        let p = study(
            dir.path(),
            kind,
            5,
            &inputs,
            &[a],
            &[b],
            &format!("kind = \"{kind}\""),
        );
        let out = dir.path().join(kind);
        let text = run_study_ok(&p, &out, &[]);
        // Its runs are not samples of the inputs' law: no density file (one with a header
        // and no rows was written).
        assert!(!out.join("q_pdf.csv").exists(), "{kind}: q_pdf.csv written");
        let units = std::fs::read_to_string(out.join("units.csv")).unwrap_or_default();
        assert!(!units.contains("q_pdf.csv"), "{units}");
        let r = reliability(&out);
        assert_eq!(r.len(), 2, "{r:?}");
        for (e, exact, direction, limit) in [(&r[0], pa, "above", a), (&r[1], pb, "below", b)] {
            assert_eq!(e["direction"], direction);
            assert_eq!(e["method"], kind);
            assert!((f(&e["limit"]) - limit).abs() < 1e-9 * limit.abs());
            let got = f(&e["p"]);
            assert!(
                (got - exact).abs() < 0.01 * exact,
                "{kind} {direction}: {got} for {exact}"
            );
            let beta = f(&e["beta"]);
            assert!((beta - normal_isf(exact)).abs() < 0.01, "beta {beta}");
            // FORM and SORM give no error estimate: no interval, no CoV.
            assert!(e["ci_95"].is_null() && e["cov"].is_null(), "{e}");
            // At most 20 runs per input for FORM (SORM adds its Hessian).
            let runs = e["runs"].as_u64().unwrap();
            if kind == "form" {
                assert!(runs <= 20 * 8, "{runs} runs");
            }
            // The design point lies on the limit: its sum is the limit.
            let x: f64 = e["design_point"].as_object().unwrap().values().map(f).sum();
            assert!(
                (x - limit).abs() < 1e-3 * sd,
                "design point sums to {x}, limit {limit}"
            );
            let imp: f64 = e["importance"].as_object().unwrap().values().map(f).sum();
            assert!((imp - 1.0).abs() < 1e-6, "importance factors sum to {imp}");
            // The inputs' own importance: for a plain sum gamma_i is proportional to the
            // input's Std, whatever the correlation (alpha is not: x1 and x3 carry x2, x4).
            let gamma = e["importance_gamma"].as_object().unwrap();
            let s2: f64 = (1..=8).map(|i| (0.5 + 0.1 * i as f64).powi(2)).sum();
            for i in 1..=8 {
                let want = (0.5 + 0.1 * i as f64).powi(2) / s2;
                let got = f(&gamma[&format!("x{i}")]);
                assert!(
                    (got - want).abs() < 1e-4,
                    "x{i}: gamma^2 {got}, want {want}"
                );
            }
        }
        // The one-line summary in the terminal names β and P.
        assert!(text.contains("β") && text.contains("P(q > "), "{text}");
        assert!(out.join("index.html").is_file());
    }
}

#[test]
fn importance_sampling_after_form_covers_the_exact_probability_within_its_cov() {
    let Some(dir) = test_fmus::dir_if_built() else {
        return;
    };
    let (inputs, mean, sd) = correlated_normals();
    let exact = 1e-4;
    let a = mean + sd * normal_isf(exact);
    let p = study(
        dir.path(),
        "is",
        5,
        &inputs,
        &[a],
        &[],
        "kind = \"importance_sampling\"\ntarget_cov = 0.05",
    );
    let out = dir.path().join("is");
    run_study_ok(&p, &out, &[]);
    let r = reliability(&out);
    let e = &r[0];
    assert_eq!(e["method"], "importance_sampling");
    let (got, cov) = (f(&e["p"]), f(&e["cov"]));
    assert!(cov <= 0.05 + 1e-12, "cov {cov}");
    // Four standard errors: fails by chance about once in 16 000 seeds.
    assert!(
        (got - exact).abs() < 4.0 * cov * got,
        "{got} ± {cov} for {exact}"
    );
    let ci = e["ci_95"].as_array().unwrap();
    assert!(f(&ci[0]) < got && got < f(&ci[1]));
    assert!(e["runs"].as_u64().unwrap() <= 2_000 + 20 * 8);
    // The page's plots: importance factors and P against runs.
    assert!(out.join("q_1_importance.svg").is_file());
    assert!(out.join("q_1_convergence.svg").is_file());
}

#[test]
fn subset_simulation_covers_the_chi_square_tail_of_a_sum_of_squares() {
    let Some(dir) = test_fmus::dir_if_built() else {
        return;
    };
    // Two standard normal inputs: y is chi-square with 2 degrees of freedom,
    // P(y > b) = exp(-b/2) = 1e-4 at b = 2 ln 1e4 (a circle: FORM's single design point
    // does not describe it).
    let inputs = two_inputs("distribution = \"normal\"\nmean = 0\nstd = 1");
    let exact = 1e-4;
    let b = -2.0 * f64::ln(exact);
    let p = study(
        dir.path(),
        "ss",
        6,
        &inputs,
        &[b],
        &[],
        "kind = \"subset\"\nsamples_per_level = 2000",
    );
    let out = dir.path().join("ss");
    let text = run_study_ok(&p, &out, &[]);
    let e = &reliability(&out)[0];
    assert_eq!(e["method"], "subset");
    let got = f(&e["p"]);
    let cov = f(&e["cov"]);
    assert!(cov < 0.3, "cov {cov}");
    // `cov` takes the levels as independent and is too small; the line says so and gives
    // the fully correlated value the interval is built on (the page says the same).
    let upper = f(&e["subset"]["cov_upper"]);
    assert!(upper > cov, "{upper} vs {cov}");
    let words = format!(
        "CoV {:.1} % with independent levels, {:.1} % with correlated ones (which the interval \
         uses)",
        100.0 * cov,
        100.0 * upper
    );
    assert_contains(&text, &words);
    let page = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert_contains(&page, &words);
    let ci = e["ci_95"].as_array().unwrap();
    assert!(
        f(&ci[0]) <= exact && exact <= f(&ci[1]),
        "{got} ({ci:?}) for {exact}"
    );
    assert!(
        e["design_point"].is_null() && e["importance"].is_null() && e["importance_gamma"].is_null(),
        "{e}"
    );
}

#[test]
fn a_limit_never_reached_gives_a_zero_probability_with_an_upper_bound() {
    let Some(dir) = test_fmus::dir_if_built() else {
        return;
    };
    // x1, x2 uniform on [0, 1]: their sum never exceeds 2.5.
    let inputs = two_inputs("distribution = \"uniform\"\nlow = 0\nhigh = 1");
    let p = study(
        dir.path(),
        "never",
        5,
        &inputs,
        &[2.5],
        &[],
        "kind = \"subset\"\nsamples_per_level = 500\nmax_levels = 4",
    );
    let out = dir.path().join("never");
    run_study_ok(&p, &out, &[]);
    let e = &reliability(&out)[0];
    assert_eq!(f(&e["p"]), 0.0);
    // 4 levels of 500 at p0 = 0.1: the bound is of the order of 0.1³ · 3/500.
    let bound = f(&e["upper_95"]);
    assert!(bound > 0.0 && bound < 1e-4, "upper bound {bound}");
}

#[test]
fn a_failed_run_during_form_is_an_error_naming_the_point() {
    let Some(dir) = test_fmus::dir_if_built() else {
        return;
    };
    let fmu = test_fmus::test_fmu("Once").expect("the Once test FMU");
    // Once: y = x t, so y(1) = x; every step with x > 2 fails with fmi2Error. FORM's first
    // full step goes to x = 3, the limit.
    let text = format!(
        "{head}[fixed]\nfail_above = 2\nlog_bytes = 10\n[[parameters]]\nname = \"x\"\ndistribution = \
         \"normal\"\nmean = 0\nstd = 1\n[outputs]\nvariables = [\"y\"]\n[[qoi]]\nkind = \
         \"final\"\nname = \"q\"\nsignal = \"y\"\nlimits = [3.0]\n[method]\nkind = \"form\"\n",
        head = study_head("failed", &fmu, 1, "start = 0.0\nstop = 1.0\nstep = 0.5"),
    );
    let p = write_toml(dir.path(), "failed", &text);
    let out = dir.path().join("failed");
    let o = run_study(&p, &out, &[]);
    let err = failed(&o);
    assert_contains(&err, "P(q > 3)");
    assert_contains(&err, "failed at x = ");
    let x: f64 = err
        .split("failed at x = ")
        .nth(1)
        .unwrap()
        .split(|c: char| c == ':' || c.is_whitespace())
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!(x > 2.0, "the point named is x = {x}");
    // Run again: the failed run is answered from the store, the same error.
    let again = stderr(&run_study(&p, &out, &[]));
    assert_contains(&again, "failed at x = ");
}

/// A FORM study on the Features test FMU with `misbehave = 13`: a run fails where gain > the
/// number in the file `bound.txt` (written with `bound`); u = 1 makes u_gain = gain, lognormal
/// with median 1 and log-Std 0.25, and the limit is 1.2 (the design point at u = 4 ln 1.2,
/// gain 1.2). Returns the folder, the study file, the bound file and the output folder.
fn bound_study(bound_value: f64) -> Option<(tempfile::TempDir, PathBuf, PathBuf, PathBuf)> {
    let dir = test_fmus::dir_if_built()?;
    let fmu = test_fmus::test_fmu("Features").expect("the Features test FMU");
    let bound = dir.path().join("bound.txt");
    std::fs::write(&bound, format!("{bound_value}\n")).unwrap();
    let sigma = BOUND_SIGMA;
    let mean = (sigma * sigma / 2.0).exp();
    let std = mean * ((sigma * sigma).exp() - 1.0).sqrt();
    let text = format!(
        "{head}[fixed]\nmisbehave = 13\nmisbehave_at = 0.1\nu = 1.0\nread_file = {bound:?}\n\
         [[parameters]]\nname = \"gain\"\ndistribution = \"lognormal\"\nmean = {mean}\n\
         std = {std}\n[outputs]\nvariables = [\"u_gain\"]\n[[qoi]]\nkind = \"final\"\n\
         name = \"q\"\nsignal = \"u_gain\"\nlimits = [1.2]\n[method]\nkind = \"form\"\n",
        head = study_head("bound", &fmu, 1, "start = 0.0\nstop = 0.2\nstep = 0.1"),
    );
    let p = write_toml(dir.path(), "bound", &text);
    let out = dir.path().join("bound");
    Some((dir, p, bound, out))
}

/// The log-Std of the gain in [`bound_study`].
const BOUND_SIGMA: f64 = 0.25;

#[test]
fn retry_failed_keeps_a_form_step_the_search_went_on_past_and_gives_the_same_numbers() {
    // A FORM trial step whose run had failed was shortened; once the cause was gone,
    // `--retry-failed` ran it again, it gave a value, the search took the full step and asked
    // for other points than the stored ones: the study stopped with "stored run N was at u =".
    // FORM's first full step from the median lands at u = 0.8 (gain e^0.2 = 1.221), where
    // the runs fail while the bound is 1.21, and which the line search accepts once it has a
    // value.
    let Some((_dir, p, bound, out)) = bound_study(1.21) else {
        return;
    };
    let sigma = BOUND_SIGMA;
    run_study_ok(&p, &out, &[]);
    let exact = normal_sf((1.2_f64).ln() / sigma);
    let p1 = reliability(&out)[0]["p"].as_f64().unwrap();
    assert!((p1 / exact - 1.0).abs() < 1e-3, "FORM {p1}, exact {exact}");
    let points = std::fs::read_to_string(out.join("points.csv")).unwrap();
    let failed_runs = points.matches("is above file_value = 1.21").count();
    assert!(failed_runs >= 1, "{points}");
    // The cause gone: the failed step is not run again, and the numbers are the same.
    std::fs::write(&bound, "100\n").unwrap();
    let again = run_study(&p, &out, &["--retry-failed"]);
    let err = stderr(&again);
    assert!(again.status.success(), "{err}");
    let n = match failed_runs {
        1 => "1 failed run".to_owned(),
        n => format!("{n} failed runs"),
    };
    assert_contains(&err, &format!("--retry-failed did not run {n} again (run "));
    assert_eq!(reliability(&out)[0]["p"].as_f64().unwrap(), p1);
    assert_eq!(summary(&out)["runs_this_invocation"], 0);
}

#[test]
fn retry_failed_runs_again_the_failure_that_stopped_form() {
    // The runs at the median fail (gain 1 above the bound 0.5): FORM stops on them. Once the
    // cause is gone, `--retry-failed` must run them again (they are the method's last batch)
    // and FORM then finds the exact probability.
    let Some((_dir, p, bound, out)) = bound_study(0.5) else {
        return;
    };
    let err = failed(&run_study(&p, &out, &[]));
    assert_contains(&err, "is above file_value = 0.5");
    std::fs::write(&bound, "100\n").unwrap();
    let again = run_study(&p, &out, &["--retry-failed"]);
    let err = stderr(&again);
    assert!(again.status.success(), "{err}");
    assert!(!err.contains("did not run"), "{err}");
    let exact = normal_sf((1.2_f64).ln() / BOUND_SIGMA);
    let p1 = reliability(&out)[0]["p"].as_f64().unwrap();
    assert!((p1 / exact - 1.0).abs() < 1e-3, "FORM {p1}, exact {exact}");
}

/// Kills `study` once its store holds about 300 runs of 10 001 values, resumes it, and
/// compares the probabilities with those of an uninterrupted run.
fn resumed_after_a_kill_gives_the_uninterrupted_numbers(kind: &str, method: &str) {
    let Some(dir) = test_fmus::dir_if_built() else {
        return;
    };
    let (inputs, mean, sd) = correlated_normals();
    let a = mean + sd * normal_isf(1e-3);
    let fmu = test_fmus::test_fmu("Functions").expect("the Functions test FMU");
    // A long series per run (10 001 points of y), so that the kill lands mid-way.
    let text = format!(
        "{head}[fixed]\nfunction = 5\n{inputs}\n[outputs]\nvariables = [\"y\"]\n\
         [[qoi]]\nkind = \"final\"\nname = \"q\"\nsignal = \"y\"\nlimits = [{a}]\n\
         [method]\n{method}\n",
        head = study_head(kind, &fmu, 3, "start = 0.0\nstop = 1.0\nstep = 0.0001"),
    );
    let p = write_toml(dir.path(), kind, &text);
    let full = dir.path().join("full");
    run_study_ok(&p, &full, &["--no-report"]);
    let part = dir.path().join("part");
    run_killed(
        &p,
        &part,
        &["--threads", "1", "--no-report"],
        300 * 8 * 10_001,
    );
    assert!(!part.join("summary.json").exists(), "killed before the end");
    run_study_ok(&p, &part, &["--no-report"]);
    let (a, b) = (&reliability(&full)[0], &reliability(&part)[0]);
    assert_eq!(a["p"], b["p"], "{kind}");
    assert_eq!(a["cov"], b["cov"], "{kind}");
    assert_eq!(a["runs"], b["runs"], "{kind}");
    let s = summary(&part);
    assert!(
        s["runs_resumed"].as_u64().unwrap() >= 300,
        "{}",
        s["runs_resumed"]
    );
}

#[test]
fn importance_sampling_resumed_after_a_kill_gives_the_uninterrupted_numbers() {
    resumed_after_a_kill_gives_the_uninterrupted_numbers(
        "is",
        "kind = \"importance_sampling\"\ntarget_cov = 0.02\nbatch = 50",
    );
}

#[test]
fn subset_simulation_resumed_after_a_kill_gives_the_uninterrupted_numbers() {
    resumed_after_a_kill_gives_the_uninterrupted_numbers(
        "subset",
        "kind = \"subset\"\nsamples_per_level = 500",
    );
}

#[test]
fn morris_ranks_the_inputs_of_a_linear_sum_by_their_scatter() {
    let Some(dir) = test_fmus::dir_if_built() else {
        return;
    };
    // y = x1 + … + x4 with uniform inputs of widths 1, 2, 3, 4: every elementary effect of
    // x_i, per unit of its probability level, is its width, so μ*_i = i and σ_i = 0.
    let inputs: String = (1..=4)
        .map(|i| {
            format!(
                "[[parameters]]\nname = \"x{i}\"\ndistribution = \"uniform\"\nlow = 0\nhigh = {i}\n"
            )
        })
        .collect();
    let p = study(
        dir.path(),
        "morris",
        5,
        &inputs,
        &[],
        &[],
        "kind = \"morris\"\ntrajectories = 10",
    );
    let out = dir.path().join("morris");
    run_study_ok(&p, &out, &[]);
    let m = &summary(&out)["quantities"]["q"]["morris"];
    let mu: Vec<f64> = (1..=4).map(|i| f(&m["mu_star"][format!("x{i}")])).collect();
    for (i, v) in mu.iter().enumerate() {
        // Per unit of probability level: dy/dq = the width of x_i.
        assert!((v - (i + 1) as f64).abs() < 1e-9, "mu* {mu:?}");
        assert!(f(&m["sigma"][format!("x{}", i + 1)]).abs() < 1e-6 * v);
    }
    assert_eq!(summary(&out)["model_runs"].as_u64().unwrap(), 10 * (4 + 1));
}

#[test]
fn a_chaos_count_with_few_runs_beyond_the_limit_has_no_interval() {
    let Some(dir) = test_fmus::dir_if_built() else {
        return;
    };
    // y = x1 + x2, standard normal: a chaos of order 2 fits it exactly, yet a count of its
    // draws beyond the last few runs is extrapolation as far as the runs can tell.
    let inputs = two_inputs("distribution = \"normal\"\nmean = 0\nstd = 1");
    let sd = 2f64.sqrt();
    // P = 0.3 (about 30 of the 100 runs beyond) and 0.02 (about 2 beyond); below: 0.3.
    let (wide, tail) = (sd * normal_isf(0.3), sd * normal_isf(0.02));
    let p = study(
        dir.path(),
        "chaos",
        5,
        &inputs,
        &[wide, tail],
        &[-wide],
        "kind = \"pce_regression\"\nsamples = 100\norder = 2",
    );
    let out = dir.path().join("chaos");
    let text = run_study_ok(&p, &out, &[]);
    let r = reliability(&out);
    assert_eq!(r.len(), 3);
    let runs = Csv::read(&out.join("q_samples.csv")).numeric().col("q");
    assert_eq!(runs.len(), 100);
    for e in &r {
        assert_eq!(e["method"], "chaos");
        let limit = f(&e["limit"]);
        let beyond = runs
            .iter()
            .filter(|&&x| {
                if e["direction"] == "below" {
                    x < limit
                } else {
                    x > limit
                }
            })
            .count();
        if beyond < 10 {
            assert!(
                e["ci_95"].is_null() && e["cov"].is_null(),
                "{beyond} runs beyond: {e}"
            );
            let w = e["warnings"][0].as_str().unwrap();
            assert_contains(w, "importance_sampling");
        } else {
            assert!(e["ci_95"].is_array(), "{beyond} runs beyond: {e}");
        }
    }
    assert_contains(&text, "no interval");
}

#[test]
fn a_chaos_tail_beyond_its_runs_names_its_design_point_and_sampling_there_finds_the_exact_p() {
    let Some(dir) = test_fmus::dir_if_built() else {
        return;
    };
    // y = x1 · … · x8 with ln xᵢ ~ N(0, s²), s = 0.7/√8: ln y ~ N(0, 0.7²), so
    // P(y > L) = Φ(−ln L / 0.7) exactly; at 1e-4 none of 400 runs lies beyond, on average
    // 0.04 of them.
    let s = 0.7 / 8f64.sqrt();
    let (mean, std) = (
        (s * s / 2.0).exp(),
        (s * s / 2.0).exp() * (s * s).exp_m1().sqrt(),
    );
    let inputs: String = (1..=8)
        .map(|i| {
            format!(
                "[[parameters]]\nname = \"x{i}\"\ndistribution = \"lognormal\"\nmean = {mean}\n\
                 std = {std}\n"
            )
        })
        .collect();
    let (exact, beta) = (1e-4, normal_isf(1e-4));
    let limit = (0.7 * beta).exp();
    let p = study(
        dir.path(),
        "chaos",
        7,
        &inputs,
        &[limit],
        &[],
        "kind = \"pce_regression\"\nsamples = 400\norder = 4\nsparse = true",
    );
    let out = dir.path().join("chaos");
    run_study_ok(&p, &out, &[]);
    let e = &reliability(&out)[0];
    assert_eq!(e["method"], "chaos");
    assert!(e["ci_95"].is_null(), "{e}");
    let guide = &e["chaos_design_point"];
    // The exact design point: every uᵢ = β/√8 (xᵢ = exp(s uᵢ)). The chaos's tail falls off
    // faster than the model's (β 4.18 against 3.72 here: its P is 7× too small), so its point
    // lies further out, but in the same direction: the centre where the model is sampled.
    let b = f(&guide["beta"]);
    assert!(
        b > 0.0 && (b - beta).abs() < 0.25 * beta,
        "the chaos's β {b} against {beta}"
    );
    let u: Vec<f64> = (1..=8)
        .map(|i| f(&guide["design_point"][format!("x{i}")]).ln() / s)
        .collect();
    let cosine = u.iter().sum::<f64>() / 8f64.sqrt() / u.iter().map(|v| v * v).sum::<f64>().sqrt();
    assert!(
        cosine > 0.99,
        "the chaos's design point {u:?} is off the direction (1, …, 1)"
    );
    // The warning's centre, pasted as it is into an importance-sampling study of the model.
    let w = e["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(Value::as_str)
        .find(|w| w.contains("centre = {"))
        .unwrap_or_else(|| panic!("no centre suggested: {e}"));
    let centre = &w[w.find("centre = {").unwrap()..];
    let centre = &centre[..centre.find('}').unwrap() + 1];
    let p = study(
        dir.path(),
        "is",
        7,
        &inputs,
        &[limit],
        &[],
        &format!("kind = \"importance_sampling\"\ntarget_cov = 0.1\n{centre}"),
    );
    let out = dir.path().join("is");
    run_study_ok(&p, &out, &[]);
    let e = &reliability(&out)[0];
    let (got, cov) = (f(&e["p"]), f(&e["cov"]));
    assert!(cov <= 0.1 + 1e-12, "cov {cov}");
    assert!(
        (got - exact).abs() < 4.0 * cov * got,
        "{got} ± {cov} for {exact}"
    );
}

#[test]
fn a_reliability_study_is_refused_by_plan_shards_and_told_to_run_on_one_machine() {
    let Some(dir) = test_fmus::dir_if_built() else {
        return;
    };
    let inputs = two_inputs("distribution = \"normal\"\nmean = 0\nstd = 1");
    for kind in ["form", "importance_sampling", "subset"] {
        let p = study(
            dir.path(),
            kind,
            5,
            &inputs,
            &[3.0],
            &[],
            &format!("kind = \"{kind}\""),
        );
        let out = dir.path().join(format!("{kind}-shards"));
        let o = run(&[
            "plan",
            p.to_str().unwrap(),
            "--shards",
            "2",
            "--out",
            out.to_str().unwrap(),
        ]);
        let err = stderr(&o);
        assert!(!o.status.success(), "{kind}: planned in shards");
        assert_contains(&err, "cannot be split into shards");
        assert_contains(&err, "uq-driver run");
        assert!(
            !out.join("plan.json").exists(),
            "{kind}: a plan was written"
        );
    }
}
