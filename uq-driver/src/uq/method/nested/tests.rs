use nalgebra::DMatrix;

use super::split::{bootstrap, Split};
use super::*;
use crate::uq::distributions::Germ;
use crate::uq::Distribution;

/// x1, x2 ~ N(0, 1) inner; u ~ U(0, 2) outer (second in study order).
fn inputs() -> RandomInputs {
    RandomInputs::independent(vec![
        RandomParameter::new("x1", Distribution::normal(0.0, 1.0).unwrap()),
        RandomParameter::new("u", Distribution::uniform(0.0, 2.0).unwrap()),
        RandomParameter::new("x2", Distribution::normal(0.0, 1.0).unwrap()),
    ])
}

fn nested(outer: &str, inner: &str) -> Nested {
    let text = format!("kind = \"nested\"\nouter = {outer}\ninner = {inner}");
    let mut spec: MethodSpec = toml::from_str(&text).unwrap();
    spec.set_levels(&["u".to_string()]).unwrap();
    match spec {
        MethodSpec::Nested(n) => n,
        other => panic!("{other:?}"),
    }
}

/// y = x1 + x2² + u: inner variance 1 + 2 = 3, outer variance Var(u) = 4/12.
fn model(v: &[f64]) -> f64 {
    v[0] + v[2] * v[2] + v[1]
}

fn run(n: &Nested, seed: u64) -> (Design, DMatrix<f64>) {
    let design = n.design(&inputs(), seed).unwrap();
    let y: Vec<f64> = design.values.iter().map(|v| model(v)).collect();
    (design, DMatrix::from_column_slice(y.len(), 1, &y))
}

#[test]
fn the_design_is_the_product_of_the_outer_design_and_one_inner_design_per_outer_sample() {
    let n = nested(
        "{ kind = \"mc\", samples = 5 }",
        "{ kind = \"mc\", samples = 4 }",
    );
    let design = n.design(&inputs(), 7).unwrap();
    assert_eq!(design.len(), 20);
    assert!(design.weights.is_none());
    let outer = mc_design(5, 7);
    for (k, &u) in outer.iter().enumerate() {
        let inner = crate::uq::method::mc::Mc { samples: 4 }
            .design(
                &RandomInputs::independent(vec![inputs()[0].clone(), inputs()[2].clone()]),
                Nested::inner_seed(7, k),
            )
            .unwrap();
        for i in 0..4 {
            let v = &design.values[k * 4 + i];
            assert_eq!(v[1], u, "outer value of point {k},{i}");
            assert_eq!([v[0], v[2]], [inner.values[i][0], inner.values[i][1]]);
        }
    }
    // Fresh inner designs: the inner points of two outer samples differ.
    assert_ne!(design.values[0][0], design.values[4][0]);
    let blocks = n.blocks(&design).unwrap();
    assert_eq!(blocks.inner_len, 4);
    assert_eq!(blocks.outer_values.len(), 5);
    assert_eq!(blocks.outer_values[3], vec![outer[3]]);
    assert_eq!(
        blocks.inner[3].values[2],
        vec![design.values[14][0], design.values[14][2]]
    );
    assert_eq!(n.label(3), "nested mc 5 × mc 4");
}

/// The outer values an `mc` design of `u` alone gives with `seed`.
fn mc_design(samples: usize, seed: u64) -> Vec<f64> {
    let u = RandomInputs::independent(vec![inputs()[1].clone()]);
    crate::uq::method::mc::Mc { samples }
        .design(&u, seed)
        .unwrap()
        .values
        .iter()
        .map(|v| v[0])
        .collect()
}

#[test]
fn a_collocation_inner_design_gives_exact_conditional_moments_and_weights() {
    let n = nested(
        "{ kind = \"lhs\", samples = 4 }",
        "{ kind = \"scm\", nodes = 3 }",
    );
    let (design, data) = run(&n, 1);
    assert_eq!(design.len(), 36);
    assert_eq!(design.germ, Germ::Normal);
    let w = design.weights.as_ref().unwrap();
    assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-14);
    let blocks = n.blocks(&design).unwrap();
    let rows: Vec<usize> = (0..36).collect();
    let cond = n.conditional(&blocks, &rows, &data).unwrap();
    for (k, e) in cond.estimates.iter().enumerate() {
        let e = e.as_ref().unwrap();
        let u = blocks.outer_values[k][0];
        assert!((e.mean[0] - (1.0 + u)).abs() < 1e-12, "{}", e.mean[0]);
        assert!((e.std[0] - 3f64.sqrt()).abs() < 1e-12);
        assert!(e.std_error_mean.is_none() && e.chaos.is_some());
    }
    // A missing weighted point is refused, not dropped.
    let e = n.conditional(&blocks, &rows[1..], &data.rows(1, 35).into_owned());
    assert!(matches!(e, Err(MethodError::MissingPoints { .. })));
}

#[test]
fn the_split_of_an_additive_model_matches_the_closed_form() {
    // Var u = 4/12 outer, 3 inner: fractions 0.1 and 0.9.
    let exact_outer = (1.0 / 3.0) / (3.0 + 1.0 / 3.0);
    for (inner, tolerance) in [
        ("{ kind = \"scm\", nodes = 3 }", 0.01),
        // Sampled conditional means: without the correction the outer part would be
        // 1/3 + 3/8, a fraction of 0.19.
        ("{ kind = \"mc\", samples = 8 }", 0.02),
    ] {
        let n = nested("{ kind = \"mc\", samples = 4000 }", inner);
        let (design, data) = run(&n, 3);
        let blocks = n.blocks(&design).unwrap();
        let rows: Vec<usize> = (0..design.len()).collect();
        let cond = n.conditional(&blocks, &rows, &data).unwrap();
        let c = cond.column(0);
        let s = Split::all(&c);
        let (fi, fo) = s.fractions();
        assert!((fo - exact_outer).abs() < tolerance, "{inner}: {fo}");
        assert!((fi + fo - 1.0).abs() < 1e-12);
        let ci = bootstrap(&c, &[], 400, 5);
        assert!(
            ci.outer[0] < exact_outer && exact_outer < ci.outer[1],
            "{inner}: {ci:?}"
        );
        let e = n.estimate(&design, &rows, &data).unwrap();
        assert!((e.std[0] - s.std()).abs() < 1e-15);
        assert!((e.mean[0] - 2.0).abs() < 4.0 * e.std_error_mean.as_ref().unwrap()[0]);
        if inner.contains("mc") {
            assert!(
                s.correction > 0.3 && s.correction < 0.45,
                "{}",
                s.correction
            );
        } else {
            assert_eq!(s.correction, 0.0);
        }
    }
}

#[test]
fn failed_runs_of_a_sampled_inner_design_are_left_out() {
    let n = nested(
        "{ kind = \"mc\", samples = 3 }",
        "{ kind = \"mc\", samples = 3 }",
    );
    let (_, data) = run(&n, 2);
    let design = n.design(&inputs(), 2).unwrap();
    let blocks = n.blocks(&design).unwrap();
    // Outer sample 1 keeps one run only: no estimate; outer sample 2 loses one.
    let rows = [0, 1, 2, 3, 6, 8];
    let sub = data.select_rows(&rows);
    let cond = n.conditional(&blocks, &rows, &sub).unwrap();
    assert!(cond.estimates[0].is_some() && cond.estimates[1].is_none());
    assert_eq!(cond.data_rows[2], vec![4, 5]);
    assert_eq!(cond.present(), vec![0, 2]);
    let e2 = cond.estimates[2].as_ref().unwrap();
    assert_eq!(e2.mean[0], (data[(6, 0)] + data[(8, 0)]) / 2.0);
}

#[test]
fn levels_and_kinds_are_checked() {
    let problem = |params: &[RandomParameter]| {
        let p = Problem {
            parameters: params,
            correlation: None,
            outputs: &[],
            quantities: 1,
            times: &[0.0, 1.0],
            system: None,
        };
        nested_validate(&p)
    };
    fn nested_validate(p: &Problem) -> Vec<String> {
        [
            (
                "{ kind = \"scm\", nodes = 3 }",
                "{ kind = \"mc\", samples = 4 }",
            ),
            ("{ kind = \"mc\", samples = 4 }", "{ kind = \"nominal\" }"),
            (
                "{ kind = \"mc\", samples = 4 }",
                "{ kind = \"scm\", nodes = 3 }",
            ),
            (
                "{ kind = \"mc\", samples = 1 }",
                "{ kind = \"mc\", samples = 4 }",
            ),
        ]
        .iter()
        .map(|(o, i)| {
            nested(o, i)
                .validate(p)
                .err()
                .map_or(String::new(), |e| e.to_string())
        })
        .collect()
    }
    let params = inputs().parameters;
    let errors = problem(&params);
    assert!(
        errors[0].contains("outer design must be one of mc, lhs, qmc"),
        "{}",
        errors[0]
    );
    assert!(errors[1].contains("not nominal"), "{}", errors[1]);
    assert_eq!(errors[2], "");
    assert!(
        errors[3].starts_with("outer: `samples` must be at least 2"),
        "{}",
        errors[3]
    );
    // A discrete input is fine outside the chaos level, refused inside it.
    let mut p = params.clone();
    p[1].distribution = Distribution::integer_uniform(1, 100).unwrap();
    assert_eq!(problem(&p)[2], "");
    let mut n = nested(
        "{ kind = \"mc\", samples = 4 }",
        "{ kind = \"scm\", nodes = 3 }",
    );
    n.outer_parameters = vec!["x1".into()];
    let mut q = params.clone();
    q[1].distribution = Distribution::integer_uniform(1, 100).unwrap();
    let pr = Problem {
        parameters: &q,
        correlation: None,
        outputs: &[],
        quantities: 1,
        times: &[0.0, 1.0],
        system: None,
    };
    let e = n.validate(&pr).unwrap_err().to_string();
    assert!(
        e.starts_with("inner: 'u' is an integer_uniform input"),
        "{e}"
    );
    // No outer parameter, or no inner one.
    n.outer_parameters.clear();
    assert!(n
        .validate(&pr)
        .unwrap_err()
        .to_string()
        .contains("level = \"outer\""));
    n.outer_parameters = vec!["x1".into(), "u".into(), "x2".into()];
    assert!(n
        .validate(&pr)
        .unwrap_err()
        .to_string()
        .contains("every parameter is outer"));
    // A correlation across the levels.
    let pairs = vec![CorrelationPair {
        between: ["x1".into(), "u".into()],
        rho: 0.5,
    }];
    let corr = Correlation::new(&params, pairs).unwrap().unwrap();
    let n = nested(
        "{ kind = \"mc\", samples = 4 }",
        "{ kind = \"mc\", samples = 4 }",
    );
    let pr = Problem {
        parameters: &params,
        correlation: Some(&corr),
        outputs: &[],
        quantities: 1,
        times: &[0.0, 1.0],
        system: None,
    };
    let e = n.validate(&pr).unwrap_err().to_string();
    assert!(e.contains("crosses the levels"), "{e}");
}

#[test]
fn a_correlation_within_a_level_reaches_the_inner_designs() {
    let params = inputs().parameters;
    let pairs = vec![CorrelationPair {
        between: ["x1".into(), "x2".into()],
        rho: 0.8,
    }];
    let corr = Correlation::new(&params, pairs).unwrap();
    let inputs = RandomInputs {
        parameters: params,
        correlation: corr,
    };
    let n = nested(
        "{ kind = \"mc\", samples = 2 }",
        "{ kind = \"mc\", samples = 4000 }",
    );
    let design = n.design(&inputs, 4).unwrap();
    let (a, b): (Vec<f64>, Vec<f64>) = design.values[..4000].iter().map(|v| (v[0], v[2])).unzip();
    let r = a.iter().zip(&b).map(|(x, y)| x * y).sum::<f64>() / 4000.0;
    assert!((r - 0.8).abs() < 0.03, "{r}");
}

/// Pearson's chi-square statistic of `counts` against equal expected counts.
fn chi_square(counts: &[usize]) -> f64 {
    let n: usize = counts.iter().sum();
    let e = n as f64 / counts.len() as f64;
    counts.iter().map(|&c| (c as f64 - e).powi(2) / e).sum()
}

/// The counts of the integers `low..=high` among `values`; panics on any other value.
fn counts(values: impl Iterator<Item = f64>, low: i64, high: i64) -> Vec<usize> {
    let mut c = vec![0usize; (high - low + 1) as usize];
    for v in values {
        assert_eq!(v, v.round(), "{v} is not an integer");
        assert!(
            v >= low as f64 && v <= high as f64,
            "{v} outside {low}..={high}"
        );
        c[(v as i64 - low) as usize] += 1;
    }
    c
}

#[test]
fn integer_uniform_covers_its_range_uniformly_in_every_sampling_design() {
    // 99.9 % quantile of chi-square with 11 degrees of freedom: 31.26.
    const CHI2_11_999: f64 = 31.26;
    let (low, high) = (-3, 8);
    let inputs = RandomInputs::independent(vec![
        RandomParameter::new("s", Distribution::integer_uniform(low, high).unwrap()),
        RandomParameter::new("x", Distribution::normal(0.0, 1.0).unwrap()),
    ]);
    for kind in ["mc", "lhs"] {
        let spec: MethodSpec =
            toml::from_str(&format!("kind = \"{kind}\"\nsamples = 12000")).unwrap();
        let Evaluation::Sampling(m) = spec.method().evaluation() else {
            unreachable!()
        };
        let d = m.design(&inputs, 21).unwrap();
        let c = counts(d.values.iter().map(|v| v[0]), low, high);
        let chi2 = chi_square(&c);
        assert!(chi2 < CHI2_11_999, "{kind}: chi2 = {chi2}, counts {c:?}");
        if kind == "lhs" {
            // 1000 strata per value: exactly equal counts.
            assert_eq!(c, vec![1000; 12]);
        }
        assert_eq!(m.design(&inputs, 21).unwrap().values, d.values, "{kind}");
        assert_ne!(m.design(&inputs, 22).unwrap().values, d.values, "{kind}");
    }
    // And in the outer design of a nested study.
    let mut n = nested(
        "{ kind = \"mc\", samples = 6000 }",
        "{ kind = \"mc\", samples = 2 }",
    );
    n.outer_parameters = vec!["s".into()];
    let d = n.design(&inputs, 5).unwrap();
    let c = counts(d.values.iter().step_by(2).map(|v| v[0]), low, high);
    assert!(chi_square(&c) < CHI2_11_999, "{c:?}");
    assert_eq!(n.design(&inputs, 5).unwrap().values, d.values);
}

#[test]
fn small_quasi_monte_carlo_inner_designs_give_unbiased_conditional_variances() {
    // The conditional variance of an inner design of 16 scrambled Sobol' points
    // was its sample variance, whose divisor n − 1 overstates σ² by n/(n − 1) when the
    // design's mean hardly varies (2.48 ± 0.05 for a true 2.33). The inner variance of
    // y = x1 + x2² + u is 1 + 2 = 3 at every u.
    for inner in [
        "{ kind = \"qmc\", samples = 8, replicates = 2 }",
        "{ kind = \"mc\", samples = 16 }",
    ] {
        let n = nested("{ kind = \"mc\", samples = 4000 }", inner);
        let (design, data) = run(&n, 11);
        let blocks = n.blocks(&design).unwrap();
        let rows: Vec<usize> = (0..design.len()).collect();
        let cond = n.conditional(&blocks, &rows, &data).unwrap();
        let s = Split::all(&cond.column(0));
        // Sampling error of the mean of 4000 conditional variances: about 0.02; the
        // n/(n − 1) excess would be 0.2.
        assert!((s.var_inner - 3.0).abs() < 0.08, "{inner}: {}", s.var_inner);
    }
}
