//! Tests of `rules`.

use super::*;

const ALL: [RuleKind; 5] = [
    RuleKind::GenzKeister,
    RuleKind::ClenshawCurtis,
    RuleKind::GaussPatterson,
    RuleKind::GaussLegendre,
    RuleKind::GaussHermite,
];

/// Exact moments `E[t^m]` of the germ of each rule: N(0,1): (m-1)!! for even m; U(-1,1):
/// 1/(m+1) for even m.
pub(in crate::uq::hd) fn moment(kind: RuleKind, m: usize) -> f64 {
    if m % 2 == 1 {
        return 0.0;
    }
    match kind.family() {
        Family::Hermite => (1..m).step_by(2).map(|k| k as f64).product(),
        _ => 1.0 / (m as f64 + 1.0),
    }
}

fn quad(r: &Rule1d, m: usize) -> (f64, f64) {
    let v = r
        .nodes
        .iter()
        .zip(&r.weights)
        .map(|(x, w)| w * x.powi(m as i32));
    let s: f64 = v.clone().sum();
    let a: f64 = v.map(f64::abs).sum();
    (s, a)
}

fn levels(kind: RuleKind) -> usize {
    match kind {
        RuleKind::ClenshawCurtis => 6,
        RuleKind::GaussLegendre | RuleKind::GaussHermite => 12,
        k => k.max_level(),
    }
}

#[test]
fn every_rule_is_exact_to_its_stated_degree_and_not_beyond() {
    for kind in ALL {
        for level in 0..=levels(kind) {
            let r = kind.rule(level).unwrap();
            assert_eq!(r.nodes.len(), kind.points(level).unwrap());
            assert_eq!(r.exactness, kind.exactness(level).unwrap());
            for m in 0..=r.exactness {
                let (q, scale) = quad(&r, m);
                let exact = moment(kind, m);
                assert!(
                    (q - exact).abs() <= 2e-14 * scale.max(exact).max(1.0),
                    "{kind:?} level {level}: moment {m}: {q} vs {exact}"
                );
            }
            // The next (even) degree is not integrated exactly (the table is tight):
            // the orthonormal polynomial of that degree has mean 0.
            let m = r.exactness + 1;
            let fam = kind.family();
            let q: f64 = r
                .nodes
                .iter()
                .zip(&r.weights)
                .map(|(x, w)| w * fam.eval(m, *x))
                .sum();
            assert!(
                q.abs() > 1e-10,
                "{kind:?} level {level} is exact beyond degree {}",
                r.exactness
            );
        }
    }
}

#[test]
fn nested_rules_are_nested() {
    for kind in [
        RuleKind::GenzKeister,
        RuleKind::ClenshawCurtis,
        RuleKind::GaussPatterson,
    ] {
        for level in 0..levels(kind) {
            let a = kind.rule(level).unwrap();
            let b = kind.rule(level + 1).unwrap();
            for x in &a.nodes {
                assert!(
                    b.nodes.iter().any(|y| (x - y).abs() < 1e-14),
                    "{kind:?}: node {x} of level {level} missing at level {}",
                    level + 1
                );
            }
        }
    }
}

#[test]
fn genz_keister_matches_published_figures() {
    // Published for the weight exp(-x^2) (Genz & Keister 1996, as tabulated by
    // Burkardt): node t_phys and weight w_phys; probabilists' node = sqrt(2) t_phys,
    // probability weight = w_phys / sqrt(pi).
    let s2 = std::f64::consts::SQRT_2;
    let sp = std::f64::consts::PI.sqrt();
    let check = |level: usize, t: f64, w: Option<f64>| {
        let r = RuleKind::GenzKeister.rule(level).unwrap();
        let i = r
            .nodes
            .iter()
            .position(|x| (x - s2 * t).abs() < 1e-12 * (1.0 + t))
            .unwrap_or_else(|| panic!("level {level}: node {} missing", s2 * t));
        if let Some(w) = w {
            let got = r.weights[i];
            assert!(
                (got / (w / sp) - 1.0).abs() < 1e-15,
                "level {level} weight at {t}: {got} vs {}",
                w / sp
            );
        }
    };
    check(1, 1.2247448713915889, Some(0.2954089751509193));
    check(2, 0.52403354748695763, Some(0.47869428549114124));
    check(2, 2.0232301911005157, Some(1.4173117873979098e-2));
    check(2, 2.9592107790638380, Some(1.6708826306882348e-4));
    check(3, 2.0232301911005157, Some(-0.011232438489069229));
    check(3, 4.4995993983103881, Some(1.5295717705322357e-9));
    check(3, 0.87004089535290285, Some(0.10838861955003017));
    check(4, 6.37593927098223561, None);
    check(4, 0.176064142082008934, None);
    check(4, 1.57941213484676712, None);
}

#[test]
fn genz_keister_table_agrees_with_the_patterson_construction() {
    // The same extension algorithm that builds Gauss–Patterson, run for the Gaussian
    // weight, reproduces the transcribed table (to its double-precision accuracy).
    let built = nested_family(Family::Hermite, &GK_POINTS).unwrap();
    for (level, (x, w)) in built.iter().enumerate() {
        let t = RuleKind::GenzKeister.rule(level).unwrap();
        for i in 0..x.len() {
            assert!((x[i] - t.nodes[i]).abs() < 1e-10, "level {level} node {i}");
            assert!(
                (w[i] - t.weights[i]).abs() < 1e-9,
                "level {level} weight {i}: {} vs {}",
                w[i],
                t.weights[i]
            );
        }
    }
}

#[test]
fn gauss_patterson_matches_published_seven_point_rule() {
    // Patterson (1968): 7-point rule on [-1, 1], weights summing to 2.
    let r = RuleKind::GaussPatterson.rule(2).unwrap();
    let want_x = [
        0.0,
        0.434243749346802558,
        0.774596669241483377,
        0.960491268708020283,
    ];
    let want_w = [
        0.450916538658474142,
        0.401397414775962223,
        0.268488089868333441,
        0.104656226026467265,
    ];
    for (k, (x, w)) in want_x.iter().zip(&want_w).enumerate() {
        assert!((r.nodes[3 + k] - x).abs() < 1e-15);
        assert!((2.0 * r.weights[3 + k] - w).abs() < 1e-14);
    }
}

#[test]
fn clenshaw_curtis_five_points_closed_form() {
    // n = 5 on [-1, 1] (sum 2): 1/15, 8/15, 12/15, 8/15, 1/15.
    let r = RuleKind::ClenshawCurtis.rule(2).unwrap();
    let want = [1.0, 8.0, 12.0, 8.0, 1.0];
    for (w, v) in r.weights.iter().zip(want) {
        assert!((2.0 * w - v / 15.0).abs() < 1e-15);
    }
    assert!((r.nodes[3] - 0.5f64.sqrt()).abs() < 1e-15);
}

#[test]
fn tables_and_level_errors() {
    let t = RuleKind::GenzKeister.table(10);
    assert_eq!(
        t.iter()
            .map(|r| (r.points, r.exactness))
            .collect::<Vec<_>>(),
        vec![(1, 1), (3, 5), (9, 15), (19, 29), (35, 51)]
    );
    let gp: Vec<_> = RuleKind::GaussPatterson
        .table(5)
        .iter()
        .map(|r| r.points)
        .collect();
    assert_eq!(gp, vec![1, 3, 7, 15, 31, 63]);
    let cc: Vec<_> = RuleKind::ClenshawCurtis
        .table(4)
        .iter()
        .map(|r| r.points)
        .collect();
    assert_eq!(cc, vec![1, 3, 5, 9, 17]);
    assert!(matches!(
        RuleKind::GenzKeister.rule(5),
        Err(RuleError::LevelTooHigh {
            level: 5,
            max: 4,
            ..
        })
    ));
}
