//! Tests of the chaos: Hermite identities, index sets, projection, moments, Sobol' indices.

use super::*;
use crate::uq::quadrature::{gauss_hermite, tensor_grid};
use crate::uq::rng;

fn factorial_exact(n: u32) -> u128 {
    (1..=u128::from(n)).product()
}

#[test]
fn hermite_polynomials_match_explicit_forms() {
    for &x in &[-2.5f64, -1.0, 0.0, 0.3, 2.0, 7.0] {
        let explicit = [
            1.0,
            x,
            x * x - 1.0,
            x * x * x - 3.0 * x,
            x.powi(4) - 6.0 * x * x + 3.0,
            x.powi(5) - 10.0 * x.powi(3) + 15.0 * x,
        ];
        for (n, &e) in explicit.iter().enumerate() {
            let tol = 1e-13 * e.abs().max(1.0);
            assert!((hermite_he(n, x) - e).abs() <= tol, "He_{n}({x})");
        }
    }
}

#[test]
fn norms_are_exact_factorials_and_match_quadrature() {
    assert_eq!(hermite_norm_sq(0), 1.0);
    assert_eq!(hermite_norm_sq(20), 2_432_902_008_176_640_000.0);
    assert_eq!(hermite_norm_sq(30), factorial_exact(30) as f64);
    assert_eq!(hermite_norm_sq(34), factorial_exact(34) as f64);
    assert!((hermite_norm_sq(40) / 8.159_152_832_478_977e47 - 1.0).abs() < 1e-14);
    let (x, w) = gauss_hermite(20).unwrap();
    for m in 0..12 {
        for n in 0..12 {
            let q: f64 = x
                .iter()
                .zip(&w)
                .map(|(&x, &w)| w * hermite_he(m, x) * hermite_he(n, x))
                .sum();
            let want = if m == n { hermite_norm_sq(n) } else { 0.0 };
            assert!(
                (q - want).abs() < 1e-12 * hermite_norm_sq(m.max(n)),
                "{m} {n}"
            );
        }
    }
}

#[test]
fn triple_products_exact_values() {
    assert_eq!(hermite_triple(0, 0, 0), 1.0);
    assert_eq!(hermite_triple(1, 1, 2), 2.0);
    assert_eq!(hermite_triple(2, 2, 2), 8.0);
    assert_eq!(hermite_triple(0, 3, 3), 6.0);
    assert_eq!(hermite_triple(1, 2, 2), 0.0); // odd sum
    assert_eq!(hermite_triple(1, 1, 4), 0.0); // s = 3 < 4
    assert_eq!(hermite_triple(3, 4, 5), 1440.0); // 3!4!5!/(3!2!1!)
                                                 // 10!^3 / 5!^3 = 30240^3, exact in f64.
    assert_eq!(hermite_triple(10, 10, 10), 27_653_197_824_000.0);
    // Symmetric in its arguments.
    for (i, j, k) in [(2, 5, 7), (6, 6, 4), (12, 9, 5)] {
        let v = hermite_triple(i, j, k);
        for p in [(i, k, j), (j, i, k), (j, k, i), (k, i, j), (k, j, i)] {
            assert_eq!(hermite_triple(p.0, p.1, p.2), v);
        }
    }
    // Beyond u128: (40!/20!)^3, floating-point path.
    let r: f64 = (21..=40).map(f64::from).product();
    let v = hermite_triple(40, 40, 40);
    assert!((v / r.powi(3) - 1.0).abs() < 1e-13);
    // Galerkin identity He_1 He_n = He_{n+1} + n He_{n-1}.
    for n in 1..20 {
        assert_eq!(hermite_triple(1, n, n + 1), hermite_norm_sq(n + 1));
        assert_eq!(
            hermite_triple(1, n, n - 1),
            n as f64 * hermite_norm_sq(n - 1)
        );
    }
}

#[test]
fn triple_products_match_quadrature() {
    let (x, w) = gauss_hermite(20).unwrap(); // exact to degree 39
    for i in 0..=9 {
        for j in 0..=9 {
            for k in 0..=9 {
                let q: f64 = x
                    .iter()
                    .zip(&w)
                    .map(|(&x, &w)| w * hermite_he(i, x) * hermite_he(j, x) * hermite_he(k, x))
                    .sum();
                let want = hermite_triple(i, j, k);
                let scale = (hermite_norm_sq(i) * hermite_norm_sq(j) * hermite_norm_sq(k))
                    .sqrt()
                    .max(1.0);
                assert!(
                    (q - want).abs() < 1e-12 * scale,
                    "{i} {j} {k}: {q} vs {want}"
                );
            }
        }
    }
}

/// The Hermite basis of total order `p` in `d` germs.
fn hermite(d: usize, p: usize) -> Basis {
    Basis::new(
        vec![Family::Hermite; d],
        MultiIndexSet::total_degree(d, p).unwrap(),
    )
    .unwrap()
}

#[test]
fn total_order_sets() {
    let s = MultiIndexSet::total_degree(2, 2).unwrap();
    let expect: Vec<Vec<usize>> = vec![
        vec![0, 0],
        vec![1, 0],
        vec![0, 1],
        vec![2, 0],
        vec![1, 1],
        vec![0, 2],
    ];
    assert_eq!(s.indices(), expect.as_slice());
    assert_eq!(MultiIndexSet::total_degree(2, 6).unwrap().len(), 28);
    assert_eq!(MultiIndexSet::total_degree(3, 4).unwrap().len(), 35);
    assert_eq!(MultiIndexSet::total_degree(5, 3).unwrap().len(), 56);
    assert_eq!(MultiIndexSet::total_degree(1, 7).unwrap().len(), 8);
    let s3 = MultiIndexSet::total_degree(3, 2).unwrap();
    assert_eq!(
        s3.indices()[4..10],
        [
            vec![2, 0, 0],
            vec![1, 1, 0],
            vec![1, 0, 1],
            vec![0, 2, 0],
            vec![0, 1, 1],
            vec![0, 0, 2]
        ]
    );
    assert_eq!(s3.position(&[1, 0, 1]), Some(6));
    assert_eq!(s3.position(&[3, 0, 0]), None);
    assert_eq!((s3.dim(), s3.order(), s3.len()), (3, 2, 10));
    let zero = MultiIndexSet::total_degree(0, 3).unwrap();
    assert_eq!(zero.len(), 1);
    assert_eq!(
        MultiIndexSet::total_degree(3, 3).unwrap().max_per_dim(),
        vec![3, 3, 3]
    );
}

#[test]
fn hermite_basis_is_the_normalized_product_of_hermites() {
    let b = hermite(3, 4);
    let z = [0.3, -1.2, 2.1];
    let mut out = vec![0.0; b.len()];
    b.eval(&z, &mut out);
    for (t, k) in b.set().indices().iter().enumerate() {
        let want: f64 = k
            .iter()
            .zip(&z)
            .map(|(&n, &x)| hermite_he(n, x) / hermite_norm_sq(n).sqrt())
            .product();
        assert!((out[t] - want).abs() < 1e-13 * want.abs().max(1.0));
    }
}

#[test]
fn galerkin_coefficients_convert_by_the_exact_norms() {
    // 1 + 2 He1(z1) + 3 He2(z2) + He1 He2: orthonormal 1, 2, 3 sqrt 2, sqrt 2.
    let set = MultiIndexSet::total_degree(2, 3).unwrap();
    let mut he = DMatrix::zeros(set.len(), 1);
    for (k, c) in [([0, 0], 1.0), ([1, 0], 2.0), ([0, 2], 3.0), ([1, 2], 1.0)] {
        he[(set.position(&k).unwrap(), 0)] = c;
    }
    let pce = Pce::from_hermite_he(set.clone(), he).unwrap();
    let at = |k: [usize; 2]| pce.coeffs[(set.position(&k).unwrap(), 0)];
    assert_eq!(at([0, 0]), 1.0);
    assert_eq!(at([1, 0]), 2.0);
    assert!((at([0, 2]) - 3.0 * 2f64.sqrt()).abs() < 1e-15);
    assert!((at([1, 2]) - 2f64.sqrt()).abs() < 1e-15);
    // Var = 4 + 9 * 2 + 2 = 24.
    assert!((pce.variance()[0] - 24.0).abs() < 1e-13);
    let z = [0.4, -1.3];
    let direct = 1.0 + 2.0 * z[0] + (3.0 + z[0]) * (z[1] * z[1] - 1.0);
    assert!((pce.eval(&z)[0] - direct).abs() < 1e-13);
}

#[test]
fn union_of_column_sets_keeps_each_column() {
    let fams = vec![Family::Legendre, Family::Hermite];
    let cols = vec![
        (vec![vec![0, 0], vec![2, 0]], vec![1.0, 0.5]),
        (vec![vec![0, 1], vec![0, 0]], vec![-2.0, 3.0]),
    ];
    let pce = Pce::from_columns(fams, &cols).unwrap();
    assert_eq!(pce.set().indices(), &[vec![0, 0], vec![0, 1], vec![2, 0]]);
    assert_eq!(pce.mean(), vec![1.0, 3.0]);
    assert_eq!(pce.variance(), vec![0.25, 4.0]);
}

type Fun<'a> = &'a dyn Fn(&[f64]) -> f64;

/// Values of `f` at the points of a tensor grid, one output column per function.
fn grid_values(points: &[Vec<f64>], fs: &[Fun]) -> DMatrix<f64> {
    DMatrix::from_fn(points.len(), fs.len(), |q, c| fs[c](&points[q]))
}

#[test]
fn projection_of_a_polynomial_is_exact() {
    // f = 1 + 2 He1(z1) + 3 He1(z1) He2(z2) + 0.5 He3(z2)
    let f = |z: &[f64]| {
        1.0 + 2.0 * hermite_he(1, z[0])
            + 3.0 * hermite_he(1, z[0]) * hermite_he(2, z[1])
            + 0.5 * hermite_he(3, z[1])
    };
    let g = |z: &[f64]| z[0] * z[0]; // = He2 + 1
    let npd = [4, 4];
    let grid = tensor_grid(&npd).unwrap();
    let vals = grid_values(&grid.points, &[&f, &g]);
    let basis = hermite(2, 3);
    let pce = Pce::project(basis.clone(), &grid.points, &grid.weights, &vals, &npd).unwrap();
    let idx = basis.set().indices();
    let pos = |k: [usize; 2]| idx.iter().position(|b| b == &k).unwrap();
    // Orthonormal coefficients: the He coefficients times sqrt(prod k_i!).
    for (t, k) in idx.iter().enumerate() {
        let want = match k.as_slice() {
            [0, 0] => 1.0,
            [1, 0] => 2.0,
            [1, 2] => 3.0 * 2f64.sqrt(),
            [0, 3] => 0.5 * 6f64.sqrt(),
            _ => 0.0,
        };
        assert!(
            (pce.coeffs[(t, 0)] - want).abs() < 1e-13,
            "term {:?}",
            idx[t]
        );
    }
    assert!((pce.coeffs[(pos([2, 0]), 1)] - 2f64.sqrt()).abs() < 1e-13);
    assert!((pce.mean()[0] - 1.0).abs() < 1e-13);
    assert!((pce.mean()[1] - 1.0).abs() < 1e-13);
    // Var f = 4 * 1 + 9 * 1! 2! + 0.25 * 3! = 23.5; Var z1^2 = 2.
    let var = pce.variance();
    assert!((var[0] - 23.5).abs() < 1e-12);
    assert!((var[1] - 2.0).abs() < 1e-12);
    assert!((pce.std()[1] - 2f64.sqrt()).abs() < 1e-12);
    // The surrogate reproduces f anywhere.
    let z = [0.7, -1.9];
    assert!((pce.eval(&z)[0] - f(&z)).abs() < 1e-12);
    assert!((pce.eval_column(1, &z) - g(&z)).abs() < 1e-12);
}

#[test]
fn lognormal_fixture_mean_and_variance() {
    // f = exp(a z): mean exp(a^2/2), variance exp(2a^2) - exp(a^2);
    // exact coefficients exp(a^2/2) a^n / n!.
    let a: f64 = 0.5;
    let (order, nodes) = (10, 11);
    let grid = tensor_grid(&[nodes]).unwrap();
    let vals = grid_values(&grid.points, &[&|z: &[f64]| (a * z[0]).exp()]);
    let pce = Pce::project(
        hermite(1, order),
        &grid.points,
        &grid.weights,
        &vals,
        &[nodes],
    )
    .unwrap();
    let m = (0.5 * a * a).exp();
    assert!((pce.mean()[0] - m).abs() < 1e-14);
    let exact_var = (2.0 * a * a).exp() - (a * a).exp();
    // Truncation: sum_{n > 10} exp(a^2) a^(2n) / n! ~ 3e-14.
    assert!((pce.variance()[0] - exact_var).abs() < 1e-12);
    // Exact up to the aliasing of the neglected degrees (largest for n = order).
    for n in 0..=order {
        // Orthonormal: the He coefficient m a^n / n! times sqrt(n!) (and so is the error).
        let norm = hermite_norm_sq(n).sqrt();
        let c = m * a.powi(n as i32) / norm;
        assert!((pce.coeffs[(n, 0)] - c).abs() < 1e-11 * m * norm, "n={n}");
    }
    // Sampling the surrogate reproduces the moments.
    let s = pce.sample(40_000, 5);
    // Draws of a Legendre germ are uniform on (-1, 1), reproducibly.
    let leg = Pce::new(
        Basis::new(
            vec![Family::Legendre],
            MultiIndexSet::total_degree(1, 1).unwrap(),
        )
        .unwrap(),
        DMatrix::from_column_slice(2, 1, &[0.0, 1.0 / 3f64.sqrt()]),
    )
    .unwrap();
    let u = leg.sample(20_000, 9);
    assert!(u.iter().all(|v| v.abs() < 1.0));
    assert!((u.column(0).mean()).abs() < 5.0 / (3.0 * 20_000f64).sqrt());
    assert_eq!(u, leg.sample(20_000, 9));
    let mean = s.column(0).mean();
    let sd = exact_var.sqrt();
    assert!((mean - m).abs() < 5.0 * sd / 200.0);
    assert_eq!(s, pce.sample(40_000, 5));
    assert_eq!(s.rows(0, 100), pce.sample(100, 5));
    // Row i is the chaos at the standard normals of stream (5, i).
    let mut r = rng::stream(5, 17);
    let z = [rng::standard_normal(&mut r)];
    assert!((s[(17, 0)] - pce.eval(&z)[0]).abs() < 1e-12 * m);
}

#[test]
fn sobol_indices_of_additive_and_interacting_functions() {
    let npd = [3, 3];
    let grid = tensor_grid(&npd).unwrap();
    let vals = grid_values(
        &grid.points,
        &[
            &|z: &[f64]| z[0] + 2.0 * z[1],
            &|z: &[f64]| z[0] * z[1] + z[0],
            &|_: &[f64]| 3.0,
        ],
    );
    let pce = Pce::project(hermite(2, 2), &grid.points, &grid.weights, &vals, &npd).unwrap();
    let close = |a: &[f64], b: &[f64]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-13);
    assert!(close(&pce.sobol_first(0), &[0.2, 0.8]));
    assert!(close(&pce.sobol_total(0), &[0.2, 0.8]));
    // z1 z2 + z1: Var = 2; S = (1/2, 0), T = (1, 1/2).
    assert!(close(&pce.sobol_first(1), &[0.5, 0.0]));
    assert!(close(&pce.sobol_total(1), &[1.0, 0.5]));
    // Constant output: zero variance gives zero indices.
    assert_eq!(pce.sobol_first(2), vec![0.0, 0.0]);
    assert!(pce.variance()[2] < 1e-28);
}

#[test]
fn order_not_below_nodes_is_refused() {
    // The trap: 6 nodes, order 6. He_6 vanishes at all 6 nodes, so its
    // quadrature norm is ~1e-14 and dividing by it would explode.
    let npd = [6];
    let grid = tensor_grid(&npd).unwrap();
    let quad_norm: f64 = grid
        .points
        .iter()
        .zip(&grid.weights)
        .map(|(p, w)| w * hermite_he(6, p[0]).powi(2))
        .sum();
    assert!(quad_norm < 1e-10, "{quad_norm}");
    let vals = grid_values(&grid.points, &[&|z: &[f64]| hermite_he(6, z[0]) + z[0]]);
    let err = Pce::project(hermite(1, 6), &grid.points, &grid.weights, &vals, &npd).unwrap_err();
    assert_eq!(
        err,
        PceError::OrderNotBelowNodes {
            dim: 0,
            degree: 6,
            nodes: 6
        }
    );
    assert!(err
        .to_string()
        .contains("order must be below the nodes per dimension"));
    // Lenient: a warning, aliased (zero) top coefficient, no explosion.
    let (pce, warnings) =
        Pce::project_lenient(hermite(1, 6), &grid.points, &grid.weights, &vals, &npd).unwrap();
    assert_eq!(warnings.len(), 1);
    assert!(pce.coeffs[(6, 0)].abs() < 1e-12);
    assert!((pce.std()[0] - 1.0).abs() < 1e-12);
    // Order 5 with 6 nodes is fine.
    assert!(Pce::project(hermite(1, 5), &grid.points, &grid.weights, &vals, &npd).is_ok());
}

#[test]
fn bad_shapes_and_values_are_errors() {
    let npd = [2, 2];
    let grid = tensor_grid(&npd).unwrap();
    let basis = hermite(2, 1);
    let vals = DMatrix::from_element(4, 3, 1.0);
    let ok = Pce::project(basis.clone(), &grid.points, &grid.weights, &vals, &npd);
    assert!(ok.is_ok());
    let r = Pce::project(basis.clone(), &grid.points, &grid.weights[..3], &vals, &npd);
    assert!(matches!(r, Err(PceError::Shape(_))));
    let r = Pce::project(basis.clone(), &grid.points, &grid.weights, &vals, &[2]);
    assert!(matches!(r, Err(PceError::Shape(_))));
    let mut bad = vals.clone();
    bad[(2, 1)] = f64::NAN;
    let r = Pce::project(basis, &grid.points, &grid.weights, &bad, &npd);
    assert_eq!(
        r,
        Err(PceError::NotFinite {
            what: "value",
            point: 2
        })
    );
}
