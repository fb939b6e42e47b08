//! Series outputs of a chaos method fitted on their principal components
//! (`[analysis] functional = "pca"`, the default) against the fit of every time column
//! (`functional = "columns"`), on the same runs of the VehicleTrack FMU: the same mean, Std
//! and first-order Sobol' indices over time, from a handful of fits.

use std::path::Path;

use crate::support::csv::Csv;
use crate::support::{built_fmu, run_study_ok, study_head, summary, write_toml};

/// A VehicleTrack study of 2 s (1 001 columns of Zc_acc), four Gaussian inputs at CoV 10 %,
/// a sparse regression chaos of order 3 on 100 Latin hypercube runs, fitted `functional`.
fn study(dir: &Path, functional: &str) -> std::path::PathBuf {
    let fmu = built_fmu("VehicleTrack");
    let mut text = study_head(
        "vt-functional",
        &fmu,
        42,
        "start = 0.0\nstop = 2.0\nstep = 0.002",
    );
    for (name, mean) in [
        ("Kpz", 1_773_000.0),
        ("Csz", 120_000.0),
        ("Mc", 46_060.0),
        ("Ksz", 800_000.0),
    ] {
        text += &format!("[[parameters]]\nname = \"{name}\"\nmean = {mean}\ncov = 0.1\n");
    }
    text += "[fixed]\nirregularity = 3\nseed = 1\nlambda_min = 2.0\nlambda_max = 200.0\n\
             [outputs]\nvariables = [\"Zc_acc\"]\n\
             [[qoi]]\nkind = \"final\"\nname = \"Zf\"\nsignal = \"Zc_acc\"\n\
             [method]\nkind = \"pce_regression\"\ndesign = \"lhs\"\nsamples = 100\norder = 3\n\
             sparse = true\n";
    text += &format!("[analysis]\nfunctional = \"{functional}\"\n");
    write_toml(dir, &format!("vt-{functional}"), &text)
}

#[test]
fn functional_pca_matches_the_column_fit_on_vehicle_track() {
    let dir = tempfile::tempdir().unwrap();
    let columns = dir.path().join("columns");
    run_study_ok(&study(dir.path(), "columns"), &columns, &[]);
    // The same runs (analysis settings do not change the records), analysed on the modes.
    let pca = dir.path().join("pca");
    std::fs::create_dir(&pca).unwrap();
    for f in ["manifest.json", "records.bin"] {
        let from = columns.join("store").join(f);
        if from.exists() {
            std::fs::create_dir_all(pca.join("store")).unwrap();
            std::fs::copy(&from, pca.join("store").join(f)).unwrap();
        }
    }
    run_study_ok(&study(dir.path(), "pca"), &pca, &[]);
    let (sc, sp) = (summary(&columns), summary(&pca));
    assert_eq!(
        sp["runs_this_invocation"], 0,
        "the pca study resumed every run"
    );
    let (fc, fp) = (
        &sc["outputs"]["Zc_acc"]["functional"],
        &sp["outputs"]["Zc_acc"]["functional"],
    );
    assert_eq!(fc["method"], "columns");
    assert_eq!(fp["method"], "pca");
    let modes = fp["modes"].as_u64().unwrap();
    assert!((1..=100).contains(&modes), "{fp}");
    assert_eq!(fp["fits"].as_u64(), Some(modes));
    assert!(fc["fits"].as_u64().unwrap() > 10 * modes, "{fc} {fp}");
    assert!(fp["discarded_variance"].as_f64().unwrap() <= 1e-6, "{fp}");
    assert!(fp["discarded_max"].as_f64().unwrap() <= 1e-3, "{fp}");

    // The final value equals the last column bit for bit: its chaos is that column's, not a
    // fit of its own (a fit of its own would differ from the modes' sum in the last digits).
    for s in [&sc, &sp] {
        let (q, o) = (&s["quantities"]["Zf"], &s["outputs"]["Zc_acc"]);
        assert_eq!(q["mean"], o["mean_at_stop"], "{}", s["study"]);
        assert_eq!(q["std"], o["std_at_stop"]);
    }
    let (c, p) = (
        Csv::read(&columns.join("Zc_acc.csv")),
        Csv::read(&pca.join("Zc_acc.csv")),
    );
    let smax = c.col("std").iter().copied().fold(0.0, f64::max);
    assert!(smax > 0.0);
    // Within 0.5 % of the series' largest Std, at every time.
    for what in ["mean", "std"] {
        let worst = c
            .col(what)
            .iter()
            .zip(p.col(what))
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        println!(
            "{what}: largest difference {:.3} % of the largest Std",
            100.0 * worst / smax
        );
        assert!(worst <= 5e-3 * smax, "{what}: {worst} against Std {smax}");
    }
    // First-order indices within 0.02 wherever the Std is above 10 % of its largest and the
    // column fit vouches for itself (its leave-one-out error below the 5 % of the warnings:
    // where it is 7 %, at 1.49 s, the two fits are apart by about as much, 0.025).
    let (sc, sp) = (
        Csv::read(&columns.join("Zc_acc_sobol.csv")),
        Csv::read(&pca.join("Zc_acc_sobol.csv")),
    );
    let (std, loo) = (c.col("std"), c.col("loo"));
    let kept: Vec<usize> = (0..std.len())
        .filter(|&t| std[t] > 0.1 * smax && loo[t] < 0.05)
        .collect();
    assert!(kept.len() > 100, "{} times", kept.len());
    let mut worst = 0.0_f64;
    for x in ["Kpz", "Csz", "Mc", "Ksz"] {
        let (a, b) = (sc.col(&format!("S_{x}")), sp.col(&format!("S_{x}")));
        for &t in &kept {
            worst = worst.max((a[t] - b[t]).abs());
        }
    }
    println!("first-order indices: largest difference {worst:.4}");
    assert!(worst <= 0.02, "S1 differs by {worst}");
    // The indices of the whole series (variance-weighted over time) within 0.005.
    let (oc, op) = (
        Csv::read(&columns.join("Zc_acc_sobol_overall.csv")),
        Csv::read(&pca.join("Zc_acc_sobol_overall.csv")),
    );
    for x in ["Kpz", "Csz", "Mc", "Ksz"] {
        let (a, b) = (oc.last(&format!("S_{x}")), op.last(&format!("S_{x}")));
        assert!((a - b).abs() <= 5e-3, "overall S_{x}: {a} {b}");
    }
}
