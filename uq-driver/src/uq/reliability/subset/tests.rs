use super::super::fixtures::*;
use super::super::model::FnLimitState;
use super::*;

/// Makes a fresh model.
type Factory<'a> = Box<dyn Fn() -> Box<dyn LimitState> + 'a>;

fn run(m: &mut dyn LimitState, settings: &Subset, seed: u64) -> SubsetResult {
    subset_simulation(m, settings, seed, 0).unwrap()
}

#[test]
fn linear_limit_state_at_1e_6_within_10_000_runs() {
    // 6 levels of N = 1500 (7 at worst) fit in 10 000 runs. Theory (Au & Beck) bounds the
    // CoV from below by sqrt(m (1 - p0) / (N p0)) = 0.19 even for independent chains, so
    // CoV 15 % at 1e-6 is out of reach of 10 000 runs; the CoV with the chains' correlation
    // is about 0.3.
    let p = 1e-6;
    let lin = Linear::new(8, p);
    let settings = Subset {
        samples_per_level: 1500,
        ..Subset::default()
    };
    let r = run(&mut lin.model(), &settings, 1);
    let err = (r.probability - p).abs() / p;
    let cov = r.cov.unwrap();
    println!(
        "linear 1e-6: {:.4e}, CoV {cov:.3} (upper {:.3}), {} runs",
        r.probability,
        r.cov_upper.unwrap(),
        r.runs
    );
    assert!(r.runs <= 10_000 && r.reached, "{} runs", r.runs);
    assert!(cov < 0.4, "CoV {cov}");
    assert!(
        err < 2.0 * cov,
        "P^ = {:.4e} ({err:.3}), CoV {cov:.3}",
        r.probability
    );
    let [lo, hi] = r.interval.unwrap();
    assert!(lo <= p && p <= hi);
    // Thresholds decrease to 0, conditional probabilities p0 but the last (more when
    // repeated states of the chains tie at the threshold).
    for w in r.levels.windows(2) {
        assert!(w[1].threshold < w[0].threshold);
        let p = w[0].conditional_probability;
        assert!((0.1..0.11).contains(&p), "{p}");
    }
    assert_eq!(r.levels.last().unwrap().threshold, 0.0);
    let acc = r.levels[1].acceptance.unwrap();
    assert!((0.2..0.7).contains(&acc), "acceptance {acc}");
}

/// Over 20 seeds: how many 95 % intervals hold `exact`, the rms relative error, the mean
/// CoV (Au & Beck) and the mean upper CoV.
fn coverage(
    m: &mut dyn FnMut() -> Box<dyn LimitState>,
    settings: &Subset,
    exact: f64,
) -> (usize, f64, f64, f64) {
    let mut covered = 0;
    let (mut err, mut cov, mut upper) = (0.0, 0.0, 0.0);
    for seed in 0..20 {
        let r = run(m().as_mut(), settings, 100 + seed);
        let [lo, hi] = r.interval.unwrap();
        covered += usize::from(lo <= exact && exact <= hi);
        err += ((r.probability - exact) / exact).powi(2) / 20.0;
        cov += r.cov.unwrap() / 20.0;
        upper += r.cov_upper.unwrap() / 20.0;
    }
    (covered, err.sqrt(), cov, upper)
}

#[test]
fn intervals_cover_the_exact_value_over_seeds() {
    // Linear in 8 dimensions at 1e-4, and the chi-square tail (no design point) at 1e-4.
    let settings = Subset {
        samples_per_level: 500,
        ..Subset::default()
    };
    let lin = Linear::new(8, 1e-4);
    let c = chi_square_limit(6, 1e-4);
    let cases: [(&str, Factory, f64); 2] = [
        ("linear", Box::new(|| Box::new(lin.model())), 1e-4),
        (
            "chi-square",
            Box::new(move || {
                Box::new(FnLimitState::new(6, move |u: &[f64]| {
                    Ok(sum_of_squares(c, u))
                }))
            }),
            chi_square_sf(6, c),
        ),
    ];
    for (name, model, exact) in cases {
        let (covered, rms, cov, upper) = coverage(&mut || model(), &settings, exact);
        let text = format!(
            "{name}: {covered} of 20, rms error {rms:.3}, mean CoV {cov:.3} (upper {upper:.3})"
        );
        println!("{text}");
        assert!(covered >= 18, "{text}");
        // Au & Beck's CoV is too small (see the module documentation), but within a factor
        // 1.8 of the spread over seeds; the upper one is above it.
        assert!(rms < 1.8 * cov && upper > rms, "{text}");
    }
}

#[test]
fn sum_of_squares_is_found_where_form_fails() {
    let d = 8;
    let c = chi_square_limit(d, 1e-5);
    let exact = chi_square_sf(d, c);
    let mut m = FnLimitState::new(d, move |u: &[f64]| Ok(sum_of_squares(c, u)));
    let r = run(&mut m, &Subset::default(), 4);
    let err = (r.probability - exact).abs() / exact;
    let [lo, hi] = r.interval.unwrap();
    println!(
        "chi-square 1e-5: {:.4e} vs {exact:.4e}, CoV {:.3}, {} runs",
        r.probability,
        r.cov.unwrap(),
        r.runs
    );
    assert!(lo <= exact && exact <= hi, "{r:?}");
    assert!(err < 0.5, "{:.4e} vs {exact:.4e}", r.probability);
}

#[test]
fn a_limit_never_reached_gives_zero_with_a_bound() {
    // q = s / (1 + |s|) < 1 with s = sum u: the limit 2 is never reached (g in (1, 3)).
    let mut m = FnLimitState::new(4, |u: &[f64]| {
        let s: f64 = u.iter().sum();
        Ok(2.0 - s / (1.0 + s.abs()))
    });
    let settings = Subset {
        samples_per_level: 200,
        max_levels: 5,
        ..Subset::default()
    };
    let r = run(&mut m, &settings, 2);
    assert_eq!(r.probability, 0.0);
    assert!(!r.reached);
    assert_eq!((r.cov, r.interval), (None, None));
    let bound = r.upper_bound.unwrap();
    assert!(bound > 0.0 && bound < 1e-5, "{bound}");
    assert!(r
        .levels
        .iter()
        .all(|l| l.threshold.is_finite() && l.gamma.is_finite()));
    assert!(r.warnings.iter().any(|w| w.contains("no sample failed")));
}

#[test]
fn failed_runs_are_errors_or_failures_by_setting() {
    // Runs beyond u_1 > 3 "crash": counted as failures they are the failure domain.
    let model = || {
        FnLimitState::new(3, |u: &[f64]| {
            if u[0] > 3.0 {
                Err("crashed".into())
            } else {
                Ok(5.0 - u[0])
            }
        })
    };
    let e = subset_simulation(&mut model(), &Subset::default(), 1, 0).unwrap_err();
    assert!(matches!(e, ReliabilityError::RunFailed { .. }), "{e}");
    let settings = Subset {
        on_failure: OnFailure::CountAsFailure,
        ..Subset::default()
    };
    let r = run(&mut model(), &settings, 1);
    let exact = crate::uq::special::norm_sf(3.0);
    assert!((r.probability - exact).abs() < 3.0 * r.cov.unwrap() * exact);
}

#[test]
fn same_seed_gives_bit_identical_results() {
    let lin = Linear::new(5, 1e-3);
    let settings = Subset {
        samples_per_level: 300,
        ..Subset::default()
    };
    let a = run(&mut lin.model(), &settings, 7);
    let b = run(&mut lin.model(), &settings, 7);
    let c = run(&mut lin.model(), &settings, 8);
    assert_eq!(format!("{a:?}"), format!("{b:?}"));
    assert_ne!(a.probability, c.probability);
}

#[test]
fn fixed_spread_and_bad_settings() {
    let lin = Linear::new(3, 1e-3);
    let settings = Subset {
        spread: Spread::Fixed { sigma: 0.8 },
        ..Subset::default()
    };
    let r = run(&mut lin.model(), &settings, 1);
    assert!(r.levels.iter().all(|l| l.lambda.is_none()));
    let [lo, hi] = r.interval.unwrap();
    assert!(lo <= 1e-3 && 1e-3 <= hi, "{r:?}");
    for bad in [
        Subset {
            p0: 0.7,
            ..Subset::default()
        },
        Subset {
            samples_per_level: 10,
            ..Subset::default()
        },
        Subset {
            spread: Spread::Fixed { sigma: 1.5 },
            ..Subset::default()
        },
    ] {
        assert!(matches!(
            subset_simulation(&mut lin.model(), &bad, 1, 0),
            Err(ReliabilityError::Invalid(_))
        ));
    }
}

/// Calibration over many seeds (run by hand: `--ignored --nocapture`): the spread of the
/// estimates against the reported CoV, and the coverage of the intervals.
#[test]
#[ignore]
fn calibration_over_seeds() {
    let cases: Vec<(&str, usize, f64, Factory, Spread)> = vec![
        (
            "linear8 1e-4",
            500,
            1e-4,
            Box::new(|| Box::new(Linear::new(8, 1e-4).model())),
            Spread::default(),
        ),
        (
            "linear8 1e-4",
            1000,
            1e-4,
            Box::new(|| Box::new(Linear::new(8, 1e-4).model())),
            Spread::default(),
        ),
        (
            "linear3 1e-3 fixed",
            1000,
            1e-3,
            Box::new(|| Box::new(Linear::new(3, 1e-3).model())),
            Spread::Fixed { sigma: 0.8 },
        ),
        (
            "linear8 1e-6",
            1500,
            1e-6,
            Box::new(|| Box::new(Linear::new(8, 1e-6).model())),
            Spread::default(),
        ),
        (
            "chi2 6 1e-4",
            500,
            1e-4,
            Box::new(|| {
                let c = chi_square_limit(6, 1e-4);
                Box::new(FnLimitState::new(6, move |u: &[f64]| {
                    Ok(sum_of_squares(c, u))
                }))
            }),
            Spread::default(),
        ),
    ];
    for (name, n, exact, model, spread) in cases {
        let settings = Subset {
            samples_per_level: n,
            spread,
            ..Subset::default()
        };
        let seeds = 200;
        let (mut lr, mut lr2, mut cov, mut covu, mut c1, mut c2, mut r2) =
            (0.0, 0.0, 0.0, 0.0, 0, 0, 0.0);
        let mut ga = 0.0;
        for seed in 0..seeds {
            let r = run(model().as_mut(), &settings, 1000 + seed);
            let x = r.probability / exact;
            ga += r.levels[1..].iter().map(|l| l.gamma).sum::<f64>()
                / (r.levels.len() - 1) as f64
                / seeds as f64;
            lr += x / seeds as f64;
            r2 += (x - 1.0).powi(2) / seeds as f64;
            lr2 += x.ln().powi(2) / seeds as f64;
            cov += r.cov.unwrap() / seeds as f64;
            covu += r.cov_upper.unwrap() / seeds as f64;
            let within = |c: f64| {
                let s = (1.0 + c * c).ln().sqrt();
                usize::from((r.probability.ln() - exact.ln()).abs() <= 1.96 * s)
            };
            c1 += within(r.cov.unwrap());
            c2 += within(r.cov_upper.unwrap());
        }
        println!(
            "{name} N={n}: mean P/P = {lr:.3}, rms rel err {:.3}, rms log err {:.3}, mean CoV {cov:.3}, \
             mean CoV_upper {covu:.3}, coverage {c1}/{seeds} (upper: {c2}/{seeds}), gamma {ga:.2}",
            r2.sqrt(),
            lr2.sqrt()
        );
    }
}

/// One level of chains from exact seeds, against a fixed threshold: the spread of the
/// level's fraction over seeds against Au & Beck's formula with the estimated gamma.
#[test]
#[ignore]
fn calibration_of_one_level() {
    use crate::uq::special::{norm_isf, norm_sf};
    let d = 8;
    let (b1, b2) = (norm_isf(1e-2), norm_isf(1e-3)); // in z = a.u; P(z > b2 | z > b1) = 0.1
    let lin = Linear::new(d, 1e-3);
    let a = lin.direction.clone();
    let n = 500;
    let reps = 400;
    let settings = Subset {
        samples_per_level: n,
        ..Subset::default()
    };
    let (mut m1, mut m2, mut gam) = (0.0, 0.0, 0.0);
    for rep in 0..reps {
        let mut model = FnLimitState::new(d, |u: &[f64]| {
            Ok(-a.iter().zip(u).map(|(x, y)| x * y).sum::<f64>())
        });
        let mut runs = Runs::new(&mut model).unwrap();
        // Exact seeds: z from the tail beyond b1, orthogonal part free.
        let mut rng = crate::uq::rng::stream(77, rep);
        let seeds: Vec<State> = (0..n / 10)
            .map(|_| {
                let mut u = normals(&mut rng, d);
                let along: f64 = a.iter().zip(&u).map(|(x, y)| x * y).sum();
                let z = norm_isf(crate::uq::rng::uniform_open01(&mut rng) * norm_sf(b1));
                for (ui, ai) in u.iter_mut().zip(&a) {
                    *ui += (z - along) * ai;
                }
                State { g: -z, u }
            })
            .collect();
        let (chains, _, _) =
            run_chains(&mut runs, &settings, 1000 + rep, 1, seeds, -b1, n).unwrap();
        let (p, gamma) = level_statistics(&chains, -b2);
        m1 += p / reps as f64;
        m2 += p * p / reps as f64;
        gam += gamma / reps as f64;
    }
    let var = m2 - m1 * m1;
    println!(
        "mean p {m1:.4}, empirical var {var:.3e}, predicted {:.3e} (gamma {gam:.2}), empirical gamma {:.2}",
        m1 * (1.0 - m1) / n as f64 * (1.0 + gam),
        var / (m1 * (1.0 - m1) / n as f64) - 1.0
    );
}
