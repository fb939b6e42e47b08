//! Sensitivity from the runs of a sampling design (Latin hypercube), end to end through the
//! `uq-driver` binary and the Functions test FMU: first-order Sobol' indices from given data
//! against the Ishigami closed form and a borehole reference by tensor Gauss quadrature
//! written here, Spearman's coefficient of a linear function of normal inputs against its
//! closed form, and the fields and plots they leave in `summary.json` and on the page.

use std::f64::consts::PI;
use std::path::{Path, PathBuf};

use crate::study_chaos::{borehole_parameters, run_functions, run_ishigami};
use crate::support::csv::Csv;
use crate::support::{benchmarks, read, summary, test_fmus};

/// An unreplicated Latin hypercube of 2 000 runs.
const LHS_2000: &str = "kind = \"lhs\"\nsamples = 2000";

/// The first-order index of `p` in `quantities.Y.sobol` and its interval.
fn first_order(out: &Path, p: &str) -> (f64, [f64; 2]) {
    let s = &summary(out)["quantities"]["Y"]["sobol"];
    let ci = &s["first_ci"][p];
    (
        s["first"][p].as_f64().unwrap(),
        [ci[0].as_f64().unwrap(), ci[1].as_f64().unwrap()],
    )
}

/// The Ishigami function's inputs, uniform on [-π, π].
const ISHIGAMI_INPUTS: [&str; 3] = ["x1", "x2", "x3"];

/// Runs the Ishigami function (function 1 of the test FMU) by `method` into `name` of a new
/// temporary folder; returns the folder and `name`, or `None` when the test FMUs cannot be
/// built.
fn ishigami(name: &str, method: &str) -> Option<(tempfile::TempDir, PathBuf)> {
    let dir = test_fmus::dir_if_built()?;
    let out = run_ishigami(dir.path(), name, method);
    Some((dir, out))
}

#[test]
fn lhs_of_2000_runs_gives_the_ishigami_first_order_indices_within_0_05() {
    let Some((_dir, out)) = ishigami("ishigami", LHS_2000) else {
        return;
    };
    let names = ISHIGAMI_INPUTS;
    // Closed form (a = 7, b = 0.1): V1 = (1 + b pi^4 / 5)^2 / 2, V2 = a^2 / 8, V3 = 0.
    let (a, b) = (7.0f64, 0.1f64);
    let var = a * a / 8.0 + b * PI.powi(4) / 5.0 + b * b * PI.powi(8) / 18.0 + 0.5;
    let exact = [
        0.5 * (1.0 + b * PI.powi(4) / 5.0).powi(2) / var,
        a * a / 8.0 / var,
        0.0,
    ];
    assert!((exact[0] - 0.3139).abs() < 1e-4 && (exact[1] - 0.4424).abs() < 1e-4);
    assert_eq!(benchmarks::ishigami_indices().0[0], exact[0]);
    let mut covered = 0;
    for (i, p) in names.iter().enumerate() {
        let (s, [lo, hi]) = first_order(&out, p);
        println!(
            "ishigami, lhs 2000 runs, given data: S_{p} = {s:.4} [{lo:.4}, {hi:.4}] (exact {:.4})",
            exact[i]
        );
        assert!((s - exact[i]).abs() < 0.05, "S_{p} = {s} vs {}", exact[i]);
        assert!(lo <= s && s <= hi && hi - lo < 0.15, "{p}: [{lo}, {hi}]");
        covered += usize::from(lo - 1e-9 <= exact[i] && exact[i] <= hi + 1e-9);
    }
    assert!(
        covered >= 2,
        "{covered} of 3 intervals cover the exact indices"
    );
    // The fields: marked as given data, intervals as sobol_sampling writes them, no totals.
    let q = &summary(&out)["quantities"]["Y"];
    assert_eq!(q["sobol"]["estimator"], "given_data");
    assert_eq!(q["sobol"]["ci_level"], 0.95);
    assert!(q["sobol"].get("total").is_none() && q["sobol"].get("total_ci").is_none());
    assert_eq!(q["sobol_first"].as_array().unwrap().len(), 3);
    assert!(q["sobol_total"].is_null());
    let rc = &q["rank_correlation"];
    for p in names {
        assert!(rc["spearman"][p].is_f64() && rc["prcc"][p].is_f64(), "{rc}");
    }
    // x3 enters only through x3^4 sin x1: no monotone trend.
    assert!(rc["spearman"]["x3"].as_f64().unwrap().abs() < 0.1, "{rc}");
    assert!(rc["spearman"]["x1"].as_f64().unwrap() > 0.3, "{rc}");
    // Over time: first-order indices from the runs in Y_sobol.csv, no total columns.
    let csv = Csv::read(&out.join("y_sobol.csv"));
    assert!(csv.header.contains(&"S_x2".to_string()));
    assert!(
        !csv.header.iter().any(|h| h.starts_with("ST_")),
        "{:?}",
        csv.header
    );
    assert!((csv.last("S_x2") - exact[1]).abs() < 0.05);
}

#[test]
fn the_page_of_an_lhs_study_has_the_scatter_plots_and_the_given_data_bars() {
    let Some((_dir, out)) = ishigami("scatter", "kind = \"lhs\"\nsamples = 200") else {
        return;
    };
    let names = ISHIGAMI_INPUTS;
    let page = read(&out.join("index.html"));
    assert!(
        page.contains("Y_scatter.svg"),
        "no scatter plot on the page"
    );
    assert!(page.contains("estimated from the") && page.contains("given data"));
    assert!(page.contains("Spearman / PRCC"));
    let svg = read(&out.join("Y_scatter.svg"));
    assert_eq!(svg.matches("class=\"panel\"").count(), 3);
    assert_eq!(svg.matches("class=\"trend\"").count(), 3);
    for p in names {
        assert!(svg.contains(&format!(">{p} (S = ")), "panel of {p}");
    }
    // The most influential first: x2 (S ≈ 0.44), then x1, then x3.
    let at = |p: &str| svg.find(&format!(">{p} (S = ")).unwrap();
    assert!(at("x2") < at("x1") && at("x1") < at("x3"));
    let bars = read(&out.join("Y_sobol.svg"));
    assert!(bars.contains("estimated from the runs") && !bars.contains("total ST"));
}

/// The borehole function's first-order indices by a tensor Gauss rule written here
/// (`nh` Hermite nodes for rw and ln r, `nl` Legendre nodes for the six uniform inputs):
/// `E[Y | X_i = node]` is the weighted sum over the other inputs' nodes.
fn borehole_first_order(nh: usize, nl: usize) -> [f64; 8] {
    let (hx, hw) = benchmarks::gauss_hermite(nh);
    let (lx, lw) = benchmarks::gauss_legendre(nl);
    let sizes: Vec<usize> = (0..8).map(|i| if i < 2 { nh } else { nl }).collect();
    let node = |i: usize, k: usize| {
        if i < 2 {
            (hx[k], hw[k])
        } else {
            (lx[k], lw[k])
        }
    };
    let mut cond: Vec<Vec<f64>> = sizes.iter().map(|&m| vec![0.0; m]).collect();
    let (mut m1, mut m2) = (0.0, 0.0);
    let total: usize = sizes.iter().product();
    let (mut t, mut k) = ([0.0; 8], [0usize; 8]);
    for idx in 0..total {
        let (mut rest, mut w) = (idx, 1.0);
        for i in 0..8 {
            k[i] = rest % sizes[i];
            rest /= sizes[i];
            let (x, wi) = node(i, k[i]);
            t[i] = x;
            w *= wi;
        }
        let f = benchmarks::borehole_germ(&t);
        m1 += w * f;
        m2 += w * f * f;
        for i in 0..8 {
            cond[i][k[i]] += w * f;
        }
    }
    let var = m2 - m1 * m1;
    let mut s = [0.0; 8];
    for i in 0..8 {
        // Σ_k w_k E[Y | node k]², E[Y | node k] = cond / w_k.
        let e2: f64 = (0..sizes[i])
            .map(|kk| {
                let wk = node(i, kk).1;
                cond[i][kk] * cond[i][kk] / wk
            })
            .sum();
        s[i] = (e2 - m1 * m1) / var;
    }
    s
}

#[test]
fn lhs_of_2000_runs_gives_the_borehole_first_order_indices_within_0_05_of_a_quadrature() {
    if test_fmus::built().is_none() {
        return;
    }
    let reference = borehole_first_order(12, 5);
    // Converged: a coarser rule agrees to 1e-4.
    let coarse = borehole_first_order(10, 4);
    for i in 0..8 {
        assert!(
            (reference[i] - coarse[i]).abs() < 1e-4,
            "{reference:?} {coarse:?}"
        );
    }
    // The known ordering: rw dominates (about 0.66), then L, Hu, Hl (about 0.09–0.10).
    assert!(reference[0] > 0.6 && reference[6] > 0.08, "{reference:?}");
    let dir = tempfile::tempdir().unwrap();
    let out = run_functions(dir.path(), "borehole", 2, &borehole_parameters(), LHS_2000);
    let names = ["rw", "r", "Tu", "Hu", "Tl", "Hl", "L", "Kw"];
    for (i, p) in names.iter().enumerate() {
        let (s, [lo, hi]) = first_order(&out, p);
        println!(
            "borehole, lhs 2000 runs, given data: S_{p} = {s:.4} [{lo:.4}, {hi:.4}] (quadrature {:.4})",
            reference[i]
        );
        assert!(
            (s - reference[i]).abs() < 0.05,
            "S_{p} = {s} vs {}",
            reference[i]
        );
    }
}

#[test]
fn spearman_of_a_linear_function_of_normal_inputs_is_the_closed_form() {
    if test_fmus::built().is_none() {
        return;
    }
    // y = x1 + x2 + x3 (the other five at 0), x_i ~ N(1, s_i²): (x_i, y) is bivariate normal
    // with correlation rho_i = s_i / s_y, and Spearman's coefficient is (6 / pi) asin(rho_i / 2).
    let s = [1.0f64, 2.0, 0.5];
    let names = ["x1", "x2", "x3"];
    let params: String = names
        .iter()
        .zip(s)
        .map(|(n, sd)| format!("[[parameters]]\nname = \"{n}\"\nmean = 1.0\nstd = {sd}\n"))
        .collect();
    let dir = tempfile::tempdir().unwrap();
    let out = run_functions(dir.path(), "linear", 5, &params, LHS_2000);
    let sy = s.iter().map(|x| x * x).sum::<f64>().sqrt();
    let q = &summary(&out)["quantities"]["Y"];
    for (i, p) in names.iter().enumerate() {
        let exact = 6.0 / PI * (s[i] / sy / 2.0).asin();
        let spearman = q["rank_correlation"]["spearman"][p].as_f64().unwrap();
        let prcc = q["rank_correlation"]["prcc"][p].as_f64().unwrap();
        let first = q["sobol"]["first"][p].as_f64().unwrap();
        println!(
            "linear, lhs 2000 runs: Spearman_{p} = {spearman:.4} (exact {exact:.4}), PRCC {prcc:.4}, S {first:.4} (exact {:.4})",
            (s[i] / sy).powi(2)
        );
        assert!(
            (spearman - exact).abs() < 0.03,
            "{p}: {spearman} vs {exact}"
        );
        // The other inputs' effect on the ranks removed: a stronger association than
        // Spearman's (not 1: the ranks of normals are not linear in them).
        assert!(
            prcc > spearman && prcc > 0.5,
            "{p}: PRCC {prcc}, Spearman {spearman}"
        );
        assert!((first - (s[i] / sy).powi(2)).abs() < 0.05, "{p}: S {first}");
    }
}

#[test]
fn correlated_inputs_give_the_first_order_indices_of_the_physical_inputs() {
    if test_fmus::built().is_none() {
        return;
    }
    // y = x1 + x2 (the other six at 0), x1, x2 ~ N(0, 1) with correlation 0.5:
    // E[y | x1] = 1.5 x1, Var y = 3, so S1 = S2 = 2.25 / 3 = 0.75 (adding up to 1.5), and
    // corr(x_i, y) = 1.5 / sqrt(3): Spearman (6 / pi) asin(0.75 / sqrt(3)).
    let params = "[[parameters]]\nname = \"x1\"\nmean = 0.0\nstd = 1.0\n\
                  [[parameters]]\nname = \"x2\"\nmean = 0.0\nstd = 1.0\n\
                  [[correlation]]\nbetween = [\"x1\", \"x2\"]\nrho = 0.5\n";
    let dir = tempfile::tempdir().unwrap();
    let out = run_functions(dir.path(), "correlated", 5, params, LHS_2000);
    let sum = summary(&out);
    let q = &sum["quantities"]["Y"];
    let spearman_exact = 6.0 / PI * (0.75 / 3f64.sqrt()).asin();
    for p in ["x1", "x2"] {
        let s = q["sobol"]["first"][p].as_f64().unwrap();
        let rho = q["rank_correlation"]["spearman"][p].as_f64().unwrap();
        println!("correlated, lhs 2000 runs: S_{p} = {s:.4} (exact 0.75), Spearman {rho:.4} (exact {spearman_exact:.4})");
        assert!((s - 0.75).abs() < 0.05, "S_{p} = {s}");
        assert!((rho - spearman_exact).abs() < 0.03, "Spearman {p} = {rho}");
    }
    // The warning had runs of 14 spaces where a string continuation was lost ("estimated
    // from the runs              are those").
    let warnings: Vec<&str> = sum["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|w| w.as_str())
        .collect();
    assert!(
        warnings
            .iter()
            .any(|w| w.contains("estimated from the runs are those of the physical parameters")),
        "{warnings:?}"
    );
    for w in &warnings {
        assert!(!w.contains("  "), "a run of spaces: {w:?}");
    }
}
