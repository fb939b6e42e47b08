//! Tests of the distributions: constructors, moments, CDF/quantile round trips, tails.

use super::*;
use crate::uq::special::{norm_cdf, norm_pdf, norm_sf};

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * b.abs().max(1e-300)
}

fn all() -> Vec<Distribution> {
    vec![
        Distribution::normal(3.0, 0.5).unwrap(),
        Distribution::lognormal_from_mean_std(2.0e7, 3.0e6).unwrap(),
        Distribution::uniform(-1.0, 4.0).unwrap(),
        Distribution::truncated_normal(1.0, 2.0, 0.0, 3.0).unwrap(),
        Distribution::truncated_normal(0.0, 1.0, 0.0, f64::INFINITY).unwrap(),
        Distribution::truncated_normal(0.0, 1.0, f64::NEG_INFINITY, -4.0).unwrap(),
        Distribution::truncated_normal(10.0, 1.0, 9.7, 9.9).unwrap(),
        Distribution::beta(2.0, 5.0, 1.0, 3.0).unwrap(),
        Distribution::gamma(3.0, 0.7).unwrap(),
        Distribution::weibull(1.5, 2.0).unwrap(),
    ]
}

#[test]
fn constructors_reject_bad_parameters() {
    use DistributionError as E;
    assert!(matches!(
        Distribution::normal(0.0, 0.0),
        Err(E::NotPositive { name: "std", .. })
    ));
    assert!(matches!(
        Distribution::normal(f64::NAN, 1.0),
        Err(E::NotFinite { name: "mean", .. })
    ));
    assert!(matches!(
        Distribution::normal(0.0, f64::INFINITY),
        Err(E::NotFinite { name: "std", .. })
    ));
    assert!(matches!(
        Distribution::normal(1.0, -1.0),
        Err(E::NotPositive { .. })
    ));
    assert_eq!(Distribution::normal_cov(0.0, 0.1), Err(E::ZeroMeanCov));
    assert!(matches!(
        Distribution::normal_cov(1.0, 0.0),
        Err(E::NotPositive { name: "cov", .. })
    ));
    assert!(matches!(
        Distribution::lognormal_from_mean_std(-1.0, 1.0),
        Err(E::NotPositive { name: "mean", .. })
    ));
    assert!(matches!(
        Distribution::lognormal(0.0, 0.0),
        Err(E::NotPositive { name: "sigma", .. })
    ));
    assert!(matches!(
        Distribution::lognormal(710.0, 1.0),
        Err(E::MomentsNotFinite)
    ));
    assert!(matches!(
        Distribution::uniform(1.0, 1.0),
        Err(E::EmptyInterval { .. })
    ));
    assert!(matches!(
        Distribution::uniform(0.0, f64::INFINITY),
        Err(E::NotFinite { .. })
    ));
    assert!(matches!(
        Distribution::uniform(-1e308, 1e308),
        Err(E::EmptyInterval { .. })
    ));
    assert!(matches!(
        Distribution::truncated_normal(0.0, 1.0, 2.0, 1.0),
        Err(E::EmptyInterval { .. })
    ));
    assert!(matches!(
        Distribution::truncated_normal(0.0, 1.0, f64::NAN, 1.0),
        Err(E::EmptyInterval { .. })
    ));
    assert!(matches!(
        Distribution::truncated_normal(0.0, 1.0, 50.0, 60.0),
        Err(E::NegligibleMass { .. })
    ));
    assert!(Distribution::truncated_normal(0.0, 1.0, 30.0, f64::INFINITY).is_ok());
    let bad = Distribution::Normal {
        mean: 0.0,
        std: -1.0,
    };
    assert!(bad.validate().is_err());
}

#[test]
fn normal_cov_sets_std() {
    let d = Distribution::normal_cov(-4.0, 0.25).unwrap();
    assert_eq!(d, Distribution::normal(-4.0, 1.0).unwrap());
    assert!(d.is_gaussian());
    assert!(!Distribution::lognormal(0.0, 1.0).unwrap().is_gaussian());
}

#[test]
fn serde_uses_a_kind_tag() {
    let d = Distribution::normal(1.0, 2.0).unwrap();
    let s = serde_json::to_string(&d).unwrap();
    assert_eq!(s, r#"{"kind":"normal","mean":1.0,"std":2.0}"#);
    let t: Distribution =
        serde_json::from_str(r#"{"kind":"truncated_normal","mean":0,"std":1,"low":-1,"high":2}"#)
            .unwrap();
    assert_eq!(
        t,
        Distribution::truncated_normal(0.0, 1.0, -1.0, 2.0).unwrap()
    );
    let l: Distribution =
        serde_json::from_str(r#"{"kind":"lognormal","mu":0,"sigma":0.5}"#).unwrap();
    assert_eq!(l, Distribution::lognormal(0.0, 0.5).unwrap());
    for d in all().into_iter().filter(|d| {
        let (a, b) = d.support();
        a.is_finite() && b.is_finite()
    }) {
        let back: Distribution = serde_json::from_str(&serde_json::to_string(&d).unwrap()).unwrap();
        assert_eq!(back, d);
    }
}

#[test]
fn closed_form_moments() {
    let l = Distribution::lognormal_from_mean_std(10.0, 2.0).unwrap();
    assert!(close(l.mean(), 10.0, 1e-14));
    assert!(close(l.std(), 2.0, 1e-14));
    let u = Distribution::uniform(1.0, 4.0).unwrap();
    assert_eq!(u.mean(), 2.5);
    assert!(close(u.std(), 3.0 / 12f64.sqrt(), 1e-15));
    // Half-normal: mean sqrt(2/pi), variance 1 - 2/pi.
    let h = Distribution::truncated_normal(0.0, 1.0, 0.0, f64::INFINITY).unwrap();
    assert!(close(h.mean(), (2.0 / std::f64::consts::PI).sqrt(), 1e-14));
    assert!(close(
        h.std(),
        (1.0 - 2.0 / std::f64::consts::PI).sqrt(),
        1e-14
    ));
    // Symmetric [-1, 1] (quadrature branch) and [-1.5, 1.5] (closed form).
    for c in [1.0, 1.5f64] {
        let t = Distribution::truncated_normal(5.0, 2.0, 5.0 - 2.0 * c, 5.0 + 2.0 * c).unwrap();
        let z = 2.0 * norm_cdf(c) - 1.0;
        let var = 1.0 - 2.0 * c * norm_pdf(c) / z;
        assert!(close(t.mean(), 5.0, 1e-15));
        assert!(close(t.std(), 2.0 * var.sqrt(), 1e-13), "c={c}");
    }
}

#[test]
fn truncated_moments_continuous_across_the_quadrature_switch() {
    let a = Distribution::truncated_normal(0.0, 1.0, 0.3, 2.3 - 1e-9).unwrap();
    let b = Distribution::truncated_normal(0.0, 1.0, 0.3, 2.3 + 1e-9).unwrap();
    assert!(close(a.mean(), b.mean(), 1e-8));
    assert!(close(a.std(), b.std(), 1e-8));
    // A very narrow interval is nearly uniform.
    let n = Distribution::truncated_normal(0.0, 1.0, 3.0, 3.0 + 1e-6).unwrap();
    assert!(close(n.std(), 1e-6 / 12f64.sqrt(), 1e-6));
    assert!(n.mean() > 3.0 && n.mean() < 3.0 + 0.5e-6);
}

#[test]
fn moments_match_the_quantile_function() {
    // Midpoint rule in u of x(u) and x(u)^2 (checks inverse_cdf against mean/std).
    let m = 20_000;
    for d in all() {
        let (mut s1, mut s2) = (0.0, 0.0);
        for i in 0..m {
            let x = d.inverse_cdf((i as f64 + 0.5) / m as f64) - d.mean();
            s1 += x;
            s2 += x * x;
        }
        let mean = d.mean() + s1 / m as f64;
        let std = (s2 / m as f64 - (s1 / m as f64).powi(2)).sqrt();
        assert!(
            (mean - d.mean()).abs() < 1e-4 * d.std(),
            "{d:?}: {mean} vs {}",
            d.mean()
        );
        assert!(close(std, d.std(), 2e-3), "{d:?}: {std} vs {}", d.std());
    }
}

#[test]
fn cdf_and_inverse_cdf_round_trip() {
    for d in all() {
        for i in 1..100 {
            let u = f64::from(i) / 100.0;
            let x = d.inverse_cdf(u);
            assert!(close(d.cdf(x), u, 1e-12), "{d:?} u={u}");
            assert!(close(d.sf(x), 1.0 - u, 1e-11), "{d:?} u={u}");
        }
        let (lo, hi) = d.support();
        assert_eq!(d.inverse_cdf(0.0), lo);
        assert_eq!(d.inverse_cdf(1.0), hi);
        assert!(d.inverse_cdf(-0.1).is_nan());
        assert!(d.inverse_cdf(f64::NAN).is_nan());
        assert_eq!(d.cdf(f64::INFINITY), 1.0);
        assert_eq!(d.cdf(f64::NEG_INFINITY), 0.0);
    }
}

#[test]
fn pdf_integrates_to_one() {
    for d in all() {
        let m = 20_000;
        let (a, b) = (d.inverse_cdf(1e-12), d.inverse_cdf(1.0 - 1e-12));
        let h = (b - a) / m as f64;
        let s: f64 = (0..m).map(|i| d.pdf(a + (i as f64 + 0.5) * h)).sum::<f64>() * h;
        assert!((s - 1.0).abs() < 1e-4, "{d:?}: {s}");
    }
}

#[test]
fn from_standard_normal_is_exact_for_gaussian_and_lognormal() {
    let n = Distribution::normal(3.0, 0.5).unwrap();
    assert_eq!(n.from_standard_normal(2.0), 4.0);
    let l = Distribution::lognormal(1.0, 0.5).unwrap();
    assert_eq!(l.from_standard_normal(-2.0), 0.0f64.exp());
    assert!(l.from_standard_normal(-40.0) > 0.0);
}

#[test]
fn from_standard_normal_matches_inverse_cdf_of_phi() {
    for d in all() {
        for i in -30..=30 {
            let z = f64::from(i) * 0.1;
            let a = d.from_standard_normal(z);
            let b = d.inverse_cdf(norm_cdf(z));
            assert!((a - b).abs() <= 1e-12 * (a.abs() + d.std()), "{d:?} z={z}");
        }
    }
}

#[test]
fn far_tail_nodes_map_inside_the_support_and_stay_ordered() {
    // Gauss-Hermite nodes reach beyond 10 sigma for ~40 nodes.
    let zs = [-13.0, -11.0, -9.0, -7.0, 7.0, 9.0, 11.0, 13.0];
    let h = Distribution::truncated_normal(0.0, 1.0, 0.0, f64::INFINITY).unwrap();
    let xs: Vec<f64> = zs.iter().map(|&z| h.from_standard_normal(z)).collect();
    assert!(xs.iter().all(|&x| x >= 0.0 && x.is_finite()));
    assert!(xs.windows(2).all(|w| w[0] < w[1]), "{xs:?}");
    // Upper tail of a half-normal: Q(x) = Q(z) / 2.
    for &z in &[7.0, 9.0, 11.0, 13.0] {
        let x = h.from_standard_normal(z);
        assert!(close(norm_sf(x), 0.5 * norm_sf(z), 1e-12));
    }
    // Left-truncated far below the mean, mapped in its own tail.
    let t = Distribution::truncated_normal(0.0, 1.0, f64::NEG_INFINITY, -4.0).unwrap();
    let xs: Vec<f64> = zs.iter().map(|&z| t.from_standard_normal(z)).collect();
    assert!(xs.iter().all(|&x| x <= -4.0));
    // Near the bound -4 the f64 resolution (9e-16) merges the upper nodes.
    assert!(xs.windows(2).all(|w| w[0] <= w[1]), "{xs:?}");
    assert!(xs[..5].windows(2).all(|w| w[0] < w[1]), "{xs:?}");
    let target = norm_sf(3.0) * norm_sf(4.0) / norm_pdf(4.0);
    assert!(close(-4.0 - t.from_standard_normal(3.0), target, 2e-3));
    // Relative accuracy next to a bound: half-normal CDF ~ 2 phi(0) x.
    assert!(close(h.cdf(1e-20), 2.0 * norm_pdf(0.0) * 1e-20, 1e-14));
    assert!(close(
        h.inverse_cdf(1e-20),
        1e-20 / (2.0 * norm_pdf(0.0)),
        1e-14
    ));
    let eps = 2f64.powi(-30); // exact distance to the bound
    assert!(close(
        t.sf(-4.0 - eps),
        eps * norm_pdf(4.0) / norm_sf(4.0),
        1e-8
    ));
    let u = Distribution::uniform(0.0, 1.0).unwrap();
    let xs: Vec<f64> = zs.iter().map(|&z| u.from_standard_normal(z)).collect();
    assert!(xs.iter().all(|&x| (0.0..=1.0).contains(&x)));
    assert!(xs[0] > 0.0 && xs[0] < 1e-38);
    assert!(u.from_standard_normal(7.0) < 1.0);
}

#[test]
fn germ_maps_round_trip() {
    for d in all() {
        for germ in [Germ::Normal, Germ::Uniform, Germ::Askey] {
            let xs: &[f64] = match (germ, d.askey_affine()) {
                (Germ::Uniform, _) => &[1e-3, 0.3, 0.5, 0.9, 0.999],
                (Germ::Askey, Some(_)) => match d {
                    Distribution::Normal { .. } => &[-3.0, -0.5, 0.0, 0.7, 3.0],
                    Distribution::Gamma { .. } => &[0.01, 0.5, 2.0, 7.0],
                    _ => &[-0.999, -0.3, 0.0, 0.4, 0.98],
                },
                _ => &[-3.0, -0.5, 0.0, 0.7, 3.0],
            };
            for &x in xs {
                let v = d.from_germ(germ, x);
                let back = d.to_germ(germ, v);
                assert!(
                    (back - x).abs() <= 1e-8 * x.abs().max(1.0),
                    "{d:?} {germ:?} x={x}: {v} -> {back}"
                );
            }
        }
    }
    // Sampling designs: from_germ(Uniform) is the quantile; collocation: the normal map.
    let l = Distribution::lognormal(1.0, 0.5).unwrap();
    assert_eq!(l.from_germ(Germ::Uniform, 0.3), l.inverse_cdf(0.3));
    assert_eq!(
        l.from_germ(Germ::Normal, -2.0),
        l.from_standard_normal(-2.0)
    );
    // Askey germs are affine; inputs without an Askey family use the normal map.
    let b = Distribution::beta(2.0, 3.0, 1.0, 5.0).unwrap();
    assert_eq!(b.from_germ(Germ::Askey, -1.0), 1.0);
    assert_eq!(b.from_germ(Germ::Askey, 0.5), 4.0);
    assert_eq!(l.from_germ(Germ::Askey, 1.5), l.from_standard_normal(1.5));
    let g = Distribution::gamma(2.5, 4.0).unwrap();
    assert_eq!(g.from_germ(Germ::Askey, 0.25), 1.0);
}

#[test]
fn normal_scores_of_every_germ_agree() {
    // The standard-normal score of the same physical value, from any germ.
    for d in all() {
        let z: f64 = 0.8;
        let x = d.from_standard_normal(z);
        for germ in [Germ::Normal, Germ::Uniform, Germ::Askey] {
            let t = d.to_germ(germ, x);
            let s = d.normal_score(germ, t);
            assert!((s - z).abs() < 1e-8, "{d:?} {germ:?}: {s}");
        }
    }
}

#[test]
fn serde_of_the_new_families() {
    for (d, text) in [
        (
            Distribution::beta(2.0, 5.0, 0.0, 1.0).unwrap(),
            r#"{"kind":"beta","alpha":2.0,"beta":5.0,"low":0.0,"high":1.0}"#,
        ),
        (
            Distribution::gamma(2.0, 3.0).unwrap(),
            r#"{"kind":"gamma","shape":2.0,"scale":3.0}"#,
        ),
        (
            Distribution::weibull(1.5, 3.0).unwrap(),
            r#"{"kind":"weibull","shape":1.5,"scale":3.0}"#,
        ),
        (
            Distribution::integer_uniform(1, 6).unwrap(),
            r#"{"kind":"integer_uniform","low":1,"high":6}"#,
        ),
    ] {
        assert_eq!(serde_json::to_string(&d).unwrap(), text);
        assert_eq!(serde_json::from_str::<Distribution>(text).unwrap(), d);
    }
}

/// `Distribution::Uniform { low: 1, high: 0 }.inverse_cdf(0.5)` and the
/// integer uniform with `low > high` or the full i64 range panicked (`min > max` in
/// `f64::clamp`, an i64 overflow) instead of giving a meaningless value; `validate` is where
/// they are refused.
#[test]
fn unvalidated_struct_literals_do_not_panic_in_the_mapping_functions() {
    let bad = [
        Distribution::Uniform {
            low: 1.0,
            high: 0.0,
        },
        Distribution::Uniform {
            low: f64::NAN,
            high: 0.0,
        },
        Distribution::IntegerUniform { low: 5, high: 1 },
        Distribution::IntegerUniform {
            low: i64::MIN,
            high: i64::MAX,
        },
        Distribution::TruncatedNormal {
            mean: 0.0,
            std: 1.0,
            low: 2.0,
            high: -2.0,
        },
        Distribution::Beta {
            alpha: 2.0,
            beta: 3.0,
            low: 1.0,
            high: 0.0,
        },
        Distribution::Normal {
            mean: 0.0,
            std: -1.0,
        },
    ];
    for d in bad {
        assert!(d.validate().is_err(), "{d:?} must be refused by validate");
        for u in [0.0, 0.1, 0.5, 0.9, 1.0] {
            let _ = d.inverse_cdf(u);
        }
        for germ in [Germ::Normal, Germ::Uniform, Germ::Askey] {
            let t = d.to_germ(germ, 0.5);
            let _ = d.from_germ(germ, if t.is_finite() { t } else { 0.0 });
            let _ = d.normal_score(germ, 0.25);
        }
        let _ = (d.from_standard_normal(0.3), d.cdf(0.5), d.pdf(0.5));
        let _ = (d.mean(), d.std(), d.nominal(), d.support());
    }
    // The full i64 range keeps its centre and count without wrapping.
    let wide = Distribution::IntegerUniform {
        low: i64::MIN,
        high: i64::MAX,
    };
    assert_eq!(wide.nominal(), -1.0);
    assert!(wide.std() > 1e18);
}
