//! Tests of the Galerkin system: a 2-DOF system against independent collocation, shapes, definiteness.

use super::*;
use crate::uq::quadrature::tensor_grid;

/// A 2-DOF chain with three random germs: ξ0 scales the first spring, ξ1 the second
/// spring, ξ2 the damper between the masses; the first mass starts displaced.
fn two_dof() -> LinearSystem {
    let m = DMatrix::from_row_slice(2, 2, &[2.0, 0.0, 0.0, 1.0]);
    let k0 = DMatrix::from_row_slice(2, 2, &[300.0, -100.0, -100.0, 100.0]);
    let k_a = DMatrix::from_row_slice(2, 2, &[20.0, 0.0, 0.0, 0.0]);
    let k_b = DMatrix::from_row_slice(2, 2, &[10.0, -10.0, -10.0, 10.0]);
    let c0 = DMatrix::from_row_slice(2, 2, &[3.0, -1.0, -1.0, 1.0]);
    let c_c = DMatrix::from_row_slice(2, 2, &[0.2, -0.2, -0.2, 0.2]);
    LinearSystem {
        n_germs: 3,
        m: Affine::constant(m),
        c: Affine {
            mean: c0,
            terms: vec![(2, c_c)],
        },
        k: Affine {
            mean: k0,
            terms: vec![(0, k_a), (1, k_b)],
        },
        force: vec![(
            DVector::from_vec(vec![0.0, 1.0]),
            Waveform::Sine {
                omega: 7.0,
                phase: 0.0,
            },
        )],
        q0: Affine::constant(DMatrix::from_column_slice(2, 1, &[0.01, 0.0])),
        v0: Affine::constant(DMatrix::zeros(2, 1)),
    }
}

/// Independent deterministic solve of one realisation: plain RK4 on [q, v] with its own
/// small step, written here separately from the Galerkin code (fixed-size 2 × 2 matrices:
/// 512 realisations of 8 000 steps, no allocation per step).
fn realisation(sys: &LinearSystem, xi: &[f64], times: &[f64]) -> Vec<[f64; 2]> {
    use nalgebra::{Matrix2, Vector2};
    let fixed = |a: DMatrix<f64>| Matrix2::from_iterator(a.iter().copied());
    let (m, c, k) = (
        fixed(sys.m.at(xi)),
        fixed(sys.c.at(xi)),
        fixed(sys.k.at(xi)),
    );
    let minv = m.try_inverse().unwrap();
    let force: Vec<(Vector2<f64>, &Waveform)> = sys
        .force
        .iter()
        .map(|(amp, w)| (Vector2::new(amp[0], amp[1]), w))
        .collect();
    let f = |t: f64, q: Vector2<f64>, v: Vector2<f64>| {
        let rhs: Vector2<f64> = force.iter().map(|(amp, w)| amp * w.at(t)).sum();
        minv * (rhs - c * v - k * q)
    };
    let (q0, v0) = (sys.q0.at(xi), sys.v0.at(xi));
    let mut q = Vector2::new(q0[0], q0[1]);
    let mut v = Vector2::new(v0[0], v0[1]);
    let h = 2.5e-4;
    let mut out = vec![[q[0], q[1]]];
    let mut t = times[0];
    for w in times.windows(2) {
        let n = ((w[1] - w[0]) / h).round() as usize;
        for _ in 0..n {
            let a1 = f(t, q, v);
            let a2 = f(t + h / 2.0, q + v * (h / 2.0), v + a1 * (h / 2.0));
            let a3 = f(
                t + h / 2.0,
                q + (v + a1 * (h / 2.0)) * (h / 2.0),
                v + a2 * (h / 2.0),
            );
            let a4 = f(t + h, q + (v + a2 * (h / 2.0)) * h, v + a3 * h);
            q += (v * 6.0 + (a1 + a2 + a3) * h) * (h / 6.0);
            v += (a1 + a2 * 2.0 + a3 * 2.0 + a4) * (h / 6.0);
            t += h;
        }
        out.push([q[0], q[1]]);
    }
    out
}

/// Largest |error| of the SGM mean and Std of both DOFs at `order` against collocation.
fn sgm_errors(
    sys: &LinearSystem,
    order: usize,
    times: &[f64],
    reference: &[[(f64, f64); 2]],
) -> (f64, f64) {
    let gs = GalerkinSystem::assemble(sys, order).unwrap();
    let sol = gs.solve(times, 2.5e-4, &[0, 1]).unwrap();
    let (mut em, mut es) = (0.0f64, 0.0f64);
    for (dof, s) in sol.iter().enumerate() {
        let pce = gs.pce(s.0.clone());
        let (mean, std) = (pce.mean(), pce.std());
        for k in 0..times.len() {
            em = em.max((mean[k] - reference[k][dof].0).abs());
            es = es.max((std[k] - reference[k][dof].1).abs());
        }
    }
    (em, es)
}

#[test]
fn sgm_agrees_with_collocation_on_a_two_dof_system() {
    let sys = two_dof();
    let times: Vec<f64> = (0..=20).map(|i| i as f64 * 0.1).collect();
    assert_eq!(
        GalerkinSystem::assemble(&sys, 4).unwrap().basis.len(),
        35,
        "C(4 + 3, 3)"
    );
    // Reference: 8 nodes per germ, each realisation solved independently.
    let grid = tensor_grid(&[8, 8, 8]).unwrap();
    let runs: Vec<Vec<[f64; 2]>> = grid
        .points
        .iter()
        .map(|z| realisation(&sys, z, &times))
        .collect();
    let reference: Vec<[(f64, f64); 2]> = (0..times.len())
        .map(|k| {
            let stat = |dof: usize| {
                let m: f64 = grid
                    .weights
                    .iter()
                    .zip(&runs)
                    .map(|(w, r)| w * r[k][dof])
                    .sum();
                let v: f64 = grid
                    .weights
                    .iter()
                    .zip(&runs)
                    .map(|(w, r)| w * (r[k][dof] - m).powi(2))
                    .sum();
                (m, v.sqrt())
            };
            [stat(0), stat(1)]
        })
        .collect();
    // The response scale is q0 = 0.01 m; Std reaches ~1e-3 m.
    let errors: Vec<(f64, f64)> = [2, 4, 6]
        .iter()
        .map(|&n| sgm_errors(&sys, n, &times, &reference))
        .collect();
    // Spectral convergence in the order: each step of 2 gains at least a factor 5.
    for w in errors.windows(2) {
        assert!(w[1].0 < w[0].0 / 5.0 && w[1].1 < w[0].1 / 5.0, "{errors:?}");
    }
    let (em, es) = errors[2];
    assert!(
        em < 1e-9 && es < 1e-7,
        "order 6: mean error {em:e}, Std error {es:e}"
    );
}

#[test]
fn deterministic_system_matches_its_realisation() {
    // Order 0 with no random terms is the plain deterministic system.
    let mut sys = two_dof();
    sys.n_germs = 0;
    sys.c.terms.clear();
    sys.k.terms.clear();
    let times: Vec<f64> = (0..=10).map(|i| i as f64 * 0.2).collect();
    let gs = GalerkinSystem::assemble(&sys, 0).unwrap();
    let sol = gs.solve(&times, 2.5e-4, &[0, 1]).unwrap();
    let r = realisation(&sys, &[], &times);
    for (k, rk) in r.iter().enumerate() {
        for (dof, s) in sol.iter().enumerate() {
            assert!((s.0[(0, k)] - rk[dof]).abs() < 1e-11);
        }
    }
}

#[test]
fn definiteness_check_warns_when_the_order_is_too_high_for_the_spread() {
    // K ~ N(1, 0.5²): the chaos of order N reaches the nodes of an (N+1)-point rule,
    // beyond 2 sigma for N >= 2, where K < 0.
    let sys = |order: usize| {
        let s = LinearSystem {
            n_germs: 1,
            m: Affine::constant(DMatrix::from_element(1, 1, 1.0)),
            c: Affine::constant(DMatrix::from_element(1, 1, 0.1)),
            k: Affine {
                mean: DMatrix::from_element(1, 1, 1.0),
                terms: vec![(0, DMatrix::from_element(1, 1, 0.5))],
            },
            force: vec![],
            q0: Affine::constant(DMatrix::from_element(1, 1, 1.0)),
            v0: Affine::constant(DMatrix::zeros(1, 1)),
        };
        GalerkinSystem::assemble(&s, order)
            .unwrap()
            .check_definiteness()
    };
    let low = sys(1);
    assert!(low.warnings.is_empty(), "{low:?}");
    assert!(
        (low.min_eig_stiffness - 0.5).abs() < 1e-12,
        "nodes ±1 of the 2-point rule"
    );
    let high = sys(6);
    assert!(high.min_eig_stiffness < 0.0);
    assert_eq!(high.warnings.len(), 1);
}

#[test]
fn bad_shapes_are_errors_not_panics() {
    let mut sys = two_dof();
    sys.k.terms.push((7, DMatrix::zeros(2, 2)));
    assert!(matches!(
        GalerkinSystem::assemble(&sys, 2),
        Err(GalerkinError::Shape(_))
    ));
    let mut sys = two_dof();
    sys.m = Affine::constant(DMatrix::zeros(3, 3));
    assert!(GalerkinSystem::assemble(&sys, 2).is_err());
    let mut sys = two_dof();
    sys.m = Affine::constant(DMatrix::zeros(2, 2));
    assert!(matches!(
        GalerkinSystem::assemble(&sys, 2),
        Err(GalerkinError::SingularMass(_))
    ));
    let gs = GalerkinSystem::assemble(&two_dof(), 1).unwrap();
    assert!(gs.solve(&[0.0, 1.0], 0.0, &[0]).is_err());
    assert!(gs.solve(&[1.0, 0.0], 1e-3, &[0]).is_err());
    assert!(gs.solve(&[0.0, 1.0], 1e-3, &[5]).is_err());
}
