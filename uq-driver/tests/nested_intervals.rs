//! Coverage of the intervals of a two-level study and the bias of its split with a sampled
//! inner design, over 20 study seeds on the C test FMU `Functions` (function 4:
//! y = x1 + x2² + sigma_h · h(seed), `seed` the outer parameter, x1, x2 ~ N(0, 1) inner). The
//! true split comes from the closed form: inner variance 3 (Var x1 + Var x2²), outer variance
//! sigma_h² times the population variance of h over the seeds of the range (the hash written
//! again in `study_nested`).

use std::path::Path;

use crate::study_nested::{hashed_normal, nested_text, pair, population, X1_X2};
use crate::support::csv::Csv;
use crate::support::{run_beside, summary, test_fmus, write_toml};

/// sigma_h² = 1.5: the outer share is 1.5 / 4.5 = 1/3 over the whole population of seeds.
const SIGMA_H: f64 = 1.224_744_871_391_589;

/// The true (Std, outer share) of y over the seeds of the range (`study_nested::SEEDS`).
fn truth() -> (f64, f64) {
    let (_, _, var_h) = population();
    let var_outer = SIGMA_H * SIGMA_H * var_h;
    let total = 3.0 + var_outer;
    (total.sqrt(), var_outer / total)
}

/// Runs the studies of seeds 1..=`seeds` with the outer design `outer` and the inner
/// `inner`; per seed the Std, its interval, the outer share, its interval, the corrected
/// outer variance, the sample variance of the true conditional means over the outer samples
/// drawn (from their seeds) and the warnings.
fn studies(dir: &Path, fmu: &Path, tag: &str, [outer, inner]: [&str; 2], seeds: u64) -> Vec<Study> {
    (1..=seeds)
        .map(|seed| {
            let name = format!("{tag}-{seed}");
            let fixed = format!("sigma_h = {SIGMA_H}\n");
            let text = nested_text(&name, fmu, seed, [outer, inner], [X1_X2, &fixed], "[3.0]");
            let out = run_beside(&write_toml(dir, &name, &text), &[]);
            let s = summary(&out);
            let q = &s["quantities"]["y_end"];
            let table = Csv::read(&out.join("y_end_conditional.csv")).numeric();
            let col = table.index("seed");
            let mu: Vec<f64> = table
                .numbers()
                .iter()
                .map(|r| SIGMA_H * hashed_normal(r[col] as i64))
                .collect();
            let m = mu.iter().sum::<f64>() / mu.len() as f64;
            let drawn = mu.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (mu.len() - 1) as f64;
            Study {
                var_outer: q["variance_split"]["var_outer"].as_f64().unwrap(),
                var_outer_drawn: drawn,
                std: q["std"].as_f64().unwrap(),
                std_ci: pair(&q["std_ci"]),
                outer: q["variance_split"]["outer"].as_f64().unwrap(),
                outer_ci: pair(&q["variance_split"]["outer_ci"]),
                warnings: s["warnings"]
                    .as_array()
                    .map(|w| w.iter().map(|x| x.to_string()).collect())
                    .unwrap_or_default(),
            }
        })
        .collect()
}

struct Study {
    var_outer: f64,
    var_outer_drawn: f64,
    std: f64,
    std_ci: [f64; 2],
    outer: f64,
    outer_ci: [f64; 2],
    warnings: Vec<String>,
}

fn inside(x: f64, ci: [f64; 2]) -> bool {
    ci[0] <= x && x <= ci[1]
}

/// With 16 outer samples the percentile bootstrap covered the true Std in 13 and the true
/// outer share in 15 of 20 seeds; a simulation of these studies (numpy, 400 repetitions)
/// gives it 85 % and 87 %, the jackknife t on ln(variance) and logit(share) 93 % and 96 %.
/// Over 100 seeds the 200 intervals then cover about 172 (old) and 189 (new) times, with a
/// standard deviation near 4: the bound 180 separates them. On these 100 seeds the
/// percentile bootstrap alone covered 88 + 87 = 175 (it fails), the joined intervals 94 + 96.
#[test]
fn nested_intervals_of_the_std_and_the_outer_share_cover_the_true_split_with_16_outer_samples() {
    let Some(fmu) = test_fmus::test_fmu("Functions") else {
        return;
    };
    let (std_true, outer_true) = truth();
    assert!((outer_true - 1.0 / 3.0).abs() < 0.01, "{outer_true}");
    let dir = tempfile::tempdir().unwrap();
    let mc16 = "{ kind = \"mc\", samples = 16 }";
    let runs = studies(dir.path(), &fmu, "cover", [mc16, mc16], 100);
    let std_covered = runs.iter().filter(|s| inside(std_true, s.std_ci)).count();
    let outer_covered = runs
        .iter()
        .filter(|s| inside(outer_true, s.outer_ci))
        .count();
    eprintln!(
        "Std {std_true:.4}: covered {std_covered}/100; outer share {outer_true:.4}: covered \
         {outer_covered}/100"
    );
    for s in &runs {
        assert!(inside(s.std, s.std_ci) && inside(s.outer, s.outer_ci));
        // Below 32 outer samples the study says its intervals may cover less.
        assert!(
            s.warnings
                .iter()
                .any(|w| w.contains("only 16 outer samples")),
            "{:?}",
            s.warnings
        );
    }
    assert!(
        std_covered + outer_covered >= 180,
        "{std_covered} + {outer_covered} of 200"
    );
    assert!(std_covered >= 88 && outer_covered >= 88);
}

/// An unreplicated Latin hypercube inner design had the Monte Carlo s²/n subtracted as its
/// sampling error: the outer share came out 0.264 ± 0.015 for a true 0.334. Here each
/// study's corrected outer variance is compared with the sample variance of the true
/// conditional means of the outer samples it drew (σ_h h(seed), from the seeds in its
/// conditional table), which takes the outer sampling error out of the comparison: what is
/// left is the inner error and its correction. With x1 + x2² (additive: a Latin hypercube
/// removes nearly all of its error) the old correction subtracted about 3/16 = 0.19 per study;
/// the mean difference must now be within three standard errors of 0 and below 0.03. The
/// outer share over the seeds must meet the truth within three of its standard errors.
#[test]
fn a_latin_hypercube_inner_design_gives_an_unbiased_outer_share() {
    let Some(fmu) = test_fmus::test_fmu("Functions") else {
        return;
    };
    let (_, outer_true) = truth();
    let dir = tempfile::tempdir().unwrap();
    let outer = "{ kind = \"mc\", samples = 16 }";
    let inner = "{ kind = \"lhs\", samples = 16 }";
    let runs = studies(dir.path(), &fmu, "lhs", [outer, inner], 40);
    let mean_se = |v: &[f64]| {
        let n = v.len() as f64;
        let m = v.iter().sum::<f64>() / n;
        (
            m,
            (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0) / n).sqrt(),
        )
    };
    let diff: Vec<f64> = runs
        .iter()
        .map(|s| s.var_outer - s.var_outer_drawn)
        .collect();
    let (d, d_se) = mean_se(&diff);
    let f: Vec<f64> = runs.iter().map(|s| s.outer).collect();
    let (m, se) = mean_se(&f);
    eprintln!(
        "outer variance minus that of the drawn conditional means: {d:.5} ± {d_se:.5}; \
         outer share {m:.4} ± {se:.4} (true {outer_true:.4})"
    );
    assert!(
        d.abs() < 3.0 * d_se + 1e-9 && d.abs() < 0.03,
        "{d} ± {d_se}"
    );
    assert!(
        (m - outer_true).abs() < 3.0 * se,
        "{m} ± {se} vs {outer_true}"
    );
}
