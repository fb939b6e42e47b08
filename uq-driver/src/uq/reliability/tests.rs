//! Tests across the methods: physical inputs (lower tails, correlated non-normal inputs)
//! and the resume of an interrupted study by replay.

use std::cell::RefCell;
use std::collections::BTreeMap;

use super::*;
use crate::uq::distributions::{Distribution, RandomParameter};
use crate::uq::random_inputs::{Correlation, CorrelationPair, RandomInputs};
use crate::uq::special::{norm_pdf, norm_sf};

/// A physical model `q(x)` against a threshold.
fn physical<'a>(
    inputs: &'a RandomInputs,
    threshold: Threshold,
    q: impl Fn(&[f64]) -> f64 + 'a,
) -> impl LimitState + 'a {
    PhysicalLimitState::new(inputs, threshold, move |b: &[(u64, Vec<f64>)]| {
        Ok(b.iter().map(|(_, x)| Ok(q(x))).collect())
    })
}

#[test]
fn lower_tails_of_a_linear_response() {
    // q = x0 - 2 x1 + 0.5 x2, x ~ N(10, 1), N(3, 0.5), N(-2, 2): q ~ N(3, sqrt 3).
    let inputs = RandomInputs::independent(vec![
        RandomParameter::new("a", Distribution::normal(10.0, 1.0).unwrap()),
        RandomParameter::new("b", Distribution::normal(3.0, 0.5).unwrap()),
        RandomParameter::new("c", Distribution::normal(-2.0, 2.0).unwrap()),
    ]);
    let q = |x: &[f64]| x[0] - 2.0 * x[1] + 0.5 * x[2];
    let sd = 3f64.sqrt();
    for p in [1e-3, 1e-5] {
        let limit = 3.0 - sd * crate::uq::special::norm_isf(p);
        let threshold = Threshold {
            limit,
            side: Side::Below,
        };
        let exact = norm_sf((3.0 - limit) / sd);
        let mut m = physical(&inputs, threshold, q);
        let f = form(&mut m, &Form::default(), 0).unwrap();
        assert!((f.probability - exact).abs() < 1e-3 * exact, "FORM {f:?}");
        assert!((q(f.x_star.as_ref().unwrap()) - limit).abs() < 1e-6);
        let is = fixtures::sampling_at_design_point(&mut m, &f, 1, f.next_run);
        assert!((is.probability - exact).abs() < 0.1 * exact, "IS {is:?}");
        let s = subset_simulation(&mut m, &Subset::default(), 1, is.next_run).unwrap();
        assert!(
            (s.probability - exact).abs() < 2.5 * s.cov.unwrap() * exact,
            "subset {s:?}"
        );
        // The upper tail of the same limit is the complement.
        let above = Threshold {
            limit,
            side: Side::Above,
        };
        let f = form(&mut physical(&inputs, above, q), &Form::default(), 0).unwrap();
        assert!(
            (f.beta + crate::uq::special::norm_isf(p)).abs() < 1e-6,
            "{}",
            f.beta
        );
    }
}

/// Two correlated log-normals `x_i = exp(mu_i + s_i z_i)`, `corr(z) = r`: `P(x_0 + x_1 > t)`
/// by quadrature over `z_0` of `P(z_1 > ln(t - x_0) | z_0)`, `z_1 | z_0 ~ N(r z_0, 1 - r^2)`.
fn lognormal_sum_tail(mu: [f64; 2], s: [f64; 2], r: f64, t: f64) -> f64 {
    let n = 40_000;
    let (lo, hi) = (-12.0, 12.0);
    let h = (hi - lo) / n as f64;
    let f = |z0: f64| {
        let x0 = (mu[0] + s[0] * z0).exp();
        let cond = if x0 >= t {
            1.0
        } else {
            let z1 = ((t - x0).ln() - mu[1]) / s[1];
            norm_sf((z1 - r * z0) / (1.0 - r * r).sqrt())
        };
        norm_pdf(z0) * cond
    };
    let mut sum = f(lo) + f(hi);
    for k in 1..n {
        sum += if k % 2 == 1 { 4.0 } else { 2.0 } * f(lo + k as f64 * h);
    }
    sum * h / 3.0
}

#[test]
fn correlated_lognormal_inputs_through_the_nataf_transformation() {
    let (mu, s) = ([0.0, 0.2], [0.25, 0.35]);
    let params = vec![
        RandomParameter::new("a", Distribution::lognormal(mu[0], s[0]).unwrap()),
        RandomParameter::new("b", Distribution::lognormal(mu[1], s[1]).unwrap()),
    ];
    let pair = CorrelationPair {
        between: ["a".into(), "b".into()],
        rho: 0.5,
    };
    let correlation = Correlation::new(&params, vec![pair]).unwrap();
    let r = correlation.as_ref().unwrap().normal_correlation[(0, 1)];
    assert!(
        (r - 0.5).abs() > 1e-4 && (r - 0.5).abs() < 0.05,
        "rho_z = {r}"
    );
    let inputs = RandomInputs {
        parameters: params,
        correlation,
    };
    // The limit with P about 1e-4.
    let (mut lo, mut hi) = (2.0, 20.0);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if lognormal_sum_tail(mu, s, r, mid) > 1e-4 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let t = 0.5 * (lo + hi);
    let exact = lognormal_sum_tail(mu, s, r, t);
    let threshold = Threshold {
        limit: t,
        side: Side::Above,
    };
    let mut m = physical(&inputs, threshold, |x| x[0] + x[1]);
    let f = form(&mut m, &Form::default(), 0).unwrap();
    let x = f.x_star.clone().unwrap();
    assert!(f.converged && (x[0] + x[1] - t).abs() < 1e-3 * t, "{f:?}");
    let form_err = (f.probability - exact).abs() / exact;
    assert!(form_err < 0.3, "FORM {:.4e} vs {exact:.4e}", f.probability);
    let so = sorm(&mut m, &f, &Sorm::default()).unwrap();
    let sorm_err = (so.probability - exact).abs() / exact;
    assert!(
        sorm_err < 0.5 * form_err && sorm_err < 0.03,
        "SORM {so:?} vs {exact:.4e}"
    );
    let is = fixtures::sampling_at_design_point(&mut m, &f, 2, so.next_run);
    let [a, b] = is.interval.unwrap();
    assert!(a <= exact && exact <= b, "IS {is:?} vs {exact:.4e}");
    let ss = subset_simulation(&mut m, &Subset::default(), 2, is.next_run).unwrap();
    println!(
        "correlated log-normals, exact {exact:.4e}: FORM {:.4e} ({} runs), SORM {:.4e} ({} \
         runs), IS {:.4e} CoV {:.3} ({} runs), subset {:.4e} CoV {:.3} ({} runs)",
        f.probability,
        f.runs,
        so.probability,
        so.runs,
        is.probability,
        is.cov.unwrap(),
        is.runs,
        ss.probability,
        ss.cov.unwrap(),
        ss.runs
    );
    let [a, b] = ss.interval.unwrap();
    assert!(a <= exact && exact <= b, "subset {ss:?} vs {exact:.4e}");
}

/// The whole chain FORM -> SORM -> IS -> subset on one model, as a runner would call it.
fn chain(m: &mut dyn LimitState) -> Result<String, ReliabilityError> {
    let f = form(m, &Form::default(), 0)?;
    let s = sorm(m, &f, &Sorm::default())?;
    let settings = ImportanceSampling {
        batch: 64,
        ..ImportanceSampling::default()
    };
    let is = importance_sampling(m, &settings, &f.u_star, 5, s.next_run)?;
    let sub = Subset {
        samples_per_level: 400,
        ..Subset::default()
    };
    let ss = subset_simulation(m, &sub, 5, is.next_run)?;
    Ok(format!("{f:?}{s:?}{is:?}{ss:?}"))
}

/// A model that stores each run as it finishes, and is killed after `kill_after` runs
/// (in the middle of a batch: the runs before the kill are stored).
struct Killable<'a> {
    inner: &'a mut dyn LimitState,
    store: &'a RefCell<BTreeMap<u64, StoredRun>>,
    kill_after: usize,
}

impl LimitState for Killable<'_> {
    fn dim(&self) -> usize {
        self.inner.dim()
    }

    fn evaluate(&mut self, batch: &[Point]) -> Result<Vec<Outcome>, Abort> {
        let mut out = Vec::new();
        for p in batch {
            if self.store.borrow().len() >= self.kill_after {
                return Err(Abort::Interrupted("killed".into()));
            }
            let o = self.inner.evaluate(std::slice::from_ref(p))?.remove(0);
            self.store.borrow_mut().insert(
                p.run,
                StoredRun {
                    u: p.u.clone(),
                    outcome: o.clone(),
                },
            );
            out.push(o);
        }
        Ok(out)
    }
}

#[test]
fn a_killed_study_resumes_bit_identically_from_its_stored_runs() {
    let (inputs, limit) = fixtures::lognormal_response(1e-4);
    let reference = chain(&mut fixtures::lognormal_model(&inputs, limit)).unwrap();
    // Kill at several points: mid-FORM, mid-SORM, mid-IS, mid-subset.
    for kill_after in [5, 40, 200, 1500, 3000] {
        let store = RefCell::new(BTreeMap::new());
        let mut model = fixtures::lognormal_model(&inputs, limit);
        let mut killable = Killable {
            inner: &mut model,
            store: &store,
            kill_after,
        };
        let e = chain(&mut killable).unwrap_err();
        assert!(
            matches!(e, ReliabilityError::Aborted(Abort::Interrupted(_))),
            "{e}"
        );
        assert_eq!(store.borrow().len(), kill_after);
        // Resume: the stored runs are replayed, the rest evaluated.
        let mut fresh = fixtures::lognormal_model(&inputs, limit);
        let mut replay = Replay::new(&mut fresh, store.into_inner());
        let resumed = chain(&mut replay).unwrap();
        assert_eq!(resumed, reference, "killed after {kill_after}");
        assert_eq!(replay.replayed(), kill_after);
        // A complete store answers everything: a model that is never called.
        let runs = replay.into_runs();
        let threshold = Threshold {
            limit,
            side: Side::Above,
        };
        let mut never = PhysicalLimitState::new(&inputs, threshold, |_: &[(u64, Vec<f64>)]| {
            panic!("every run is stored")
        });
        let again = chain(&mut Replay::new(&mut never, runs)).unwrap();
        assert_eq!(again, reference);
    }
}

#[test]
fn a_store_from_another_study_is_refused() {
    let (inputs, limit) = fixtures::lognormal_response(1e-4);
    let mut model = fixtures::lognormal_model(&inputs, limit);
    let mut record = Replay::new(&mut model, BTreeMap::new());
    form(&mut record, &Form::default(), 0).unwrap();
    let runs = record.into_runs();
    // Another start point: run 0 is elsewhere.
    let settings = Form {
        start: Some(vec![0.1; 8]),
        ..Form::default()
    };
    let mut model = fixtures::lognormal_model(&inputs, limit);
    let e = form(&mut Replay::new(&mut model, runs), &settings, 0).unwrap_err();
    assert!(
        matches!(
            e,
            ReliabilityError::Aborted(Abort::ReplayMismatch { run: 0, .. })
        ),
        "{e}"
    );
}
