//! Gauss quadrature rules: probabilists' Gauss–Hermite (standard normal
//! weight) for stochastic collocation, tensor grids of them, and
//! Gauss–Legendre (used for moments of narrow truncated normals).
//!
//! Nodes come from the Golub–Welsch eigenvalue problem, are polished by
//! Newton's method on the orthonormal polynomials, then symmetrised; weights
//! come from the Christoffel function `w_i = 1 / sum_{k<n} p_k(x_i)^2`
//! evaluated with a rescaled recurrence (no overflow for large `n`).

use nalgebra::{DMatrix, SymmetricEigen};

/// Largest number of nodes of a one-dimensional rule.
pub const MAX_NODES: usize = 1000;
/// Largest number of points of a tensor grid.
pub const MAX_TENSOR_POINTS: usize = 10_000_000;

/// Errors of the quadrature constructors.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum QuadratureError {
    /// A rule with zero nodes was requested.
    #[error("a Gauss rule needs at least one node (got 0)")]
    ZeroNodes,
    /// More than [`MAX_NODES`] nodes were requested.
    #[error("{0} nodes requested for a Gauss rule; at most {MAX_NODES} are supported")]
    TooManyNodes(usize),
    /// A tensor grid over zero dimensions was requested.
    #[error("a tensor grid needs at least one dimension")]
    NoDimensions,
    /// The tensor grid would exceed [`MAX_TENSOR_POINTS`] points.
    #[error("the tensor grid would have more than {MAX_TENSOR_POINTS} points")]
    TooManyPoints,
}

fn check_nodes(n: usize) -> Result<(), QuadratureError> {
    match n {
        0 => Err(QuadratureError::ZeroNodes),
        n if n > MAX_NODES => Err(QuadratureError::TooManyNodes(n)),
        _ => Ok(()),
    }
}

/// Threshold above which the recurrence values are rescaled by `2^-RESCALE_EXP`.
const RESCALE_EXP: i32 = 500;

/// Values of a three-term orthonormal recurrence at `x`, rescaled:
/// the true values are `p * 2^(log2_scale)` and the true Christoffel sum is
/// `sum_prev * 2^(2 log2_scale)`.
struct Recurrence {
    /// `p_n(x)` (scaled).
    p_n: f64,
    /// `p_{n-1}(x)` (scaled).
    p_n1: f64,
    /// `sum_{k<n} p_k(x)^2` (scaled by the square).
    sum_prev: f64,
    /// Base-2 exponent of the scale.
    log2_scale: i32,
}

/// Orthonormal probabilists' Hermite polynomials
/// `h_{k+1} = (x h_k - sqrt(k) h_{k-1}) / sqrt(k+1)`, `h_0 = 1`.
fn hermite_orthonormal(n: usize, x: f64) -> Recurrence {
    recurrence(n, x, |k, x, p, pm| {
        let kf = k as f64;
        (x * p - kf.sqrt() * pm) / (kf + 1.0).sqrt()
    })
}

/// Orthonormal Legendre polynomials on [-1, 1] for the weight 1/2:
/// `q_k = sqrt(2k+1) P_k`, with `(k+1) P_{k+1} = (2k+1) x P_k - k P_{k-1}`.
fn legendre_orthonormal(n: usize, x: f64) -> Recurrence {
    recurrence(n, x, |k, x, p, pm| {
        let kf = k as f64;
        let a = ((2.0 * kf + 1.0) * (2.0 * kf + 3.0)).sqrt() / (kf + 1.0);
        let b = kf / (kf + 1.0) * ((2.0 * kf + 3.0) / (2.0 * kf - 1.0)).sqrt();
        if k == 0 {
            a * x * p
        } else {
            a * x * p - b * pm
        }
    })
}

fn recurrence(n: usize, x: f64, step: impl Fn(usize, f64, f64, f64) -> f64) -> Recurrence {
    let big = 2f64.powi(RESCALE_EXP);
    let shrink = 2f64.powi(-RESCALE_EXP);
    let mut pm = 0.0;
    let mut p = 1.0;
    let mut sum = 0.0;
    let mut log2_scale = 0;
    for k in 0..n {
        sum += p * p;
        let next = step(k, x, p, pm);
        pm = p;
        p = next;
        if p.abs() > big {
            p *= shrink;
            pm *= shrink;
            sum *= shrink * shrink;
            log2_scale += RESCALE_EXP;
        }
    }
    Recurrence {
        p_n: p,
        p_n1: pm,
        sum_prev: sum,
        log2_scale,
    }
}

/// The eigenvalues of the symmetric (Jacobi) matrix `m`, ascending: the nodes of its Gauss
/// rule.
pub(crate) fn sorted_eigenvalues(m: DMatrix<f64>) -> Vec<f64> {
    let mut x: Vec<f64> = SymmetricEigen::new(m).eigenvalues.iter().copied().collect();
    x.sort_by(f64::total_cmp);
    x
}

/// Makes the ascending `x` exactly symmetric about 0 (each pair of mirror nodes at its mean
/// distance, a middle node at 0).
pub(crate) fn symmetrize_nodes(x: &mut [f64]) {
    let n = x.len();
    for i in 0..n / 2 {
        let a = 0.5 * (x[n - 1 - i] - x[i]);
        x[i] = -a;
        x[n - 1 - i] = a;
    }
    if n % 2 == 1 {
        x[n / 2] = 0.0;
    }
}

/// Nodes (ascending) and weights of an `n`-point Gauss rule from its Jacobi
/// matrix (zero diagonal, off-diagonal `beta(k)`, `k = 1..n`), polished with
/// `eval` (orthonormal recurrence) and `deriv_coef` (`p_n' = c p_{n-1}` at the
/// roots), symmetrised, weights normalised to `total`.
fn symmetric_gauss_rule(
    n: usize,
    beta: impl Fn(usize) -> f64,
    eval: impl Fn(usize, f64) -> Recurrence,
    deriv: impl Fn(usize, f64, &Recurrence) -> f64,
    total: f64,
) -> (Vec<f64>, Vec<f64>) {
    if n == 1 {
        return (vec![0.0], vec![total]);
    }
    let mut jacobi = DMatrix::<f64>::zeros(n, n);
    for k in 1..n {
        let b = beta(k);
        jacobi[(k - 1, k)] = b;
        jacobi[(k, k - 1)] = b;
    }
    let mut x = sorted_eigenvalues(jacobi);
    // Newton polish: p_n(x) = 0.
    for xi in x.iter_mut() {
        for _ in 0..3 {
            let r = eval(n, *xi);
            let d = deriv(n, *xi, &r);
            if d == 0.0 || !d.is_finite() {
                break;
            }
            let dx = r.p_n / d;
            if !dx.is_finite() {
                break;
            }
            *xi -= dx;
            if dx.abs() <= 1e-17 * xi.abs().max(1.0) {
                break;
            }
        }
    }
    symmetrize_nodes(&mut x);
    let mut w: Vec<f64> = x
        .iter()
        .map(|&xi| {
            let r = eval(n, xi);
            // w = 1 / (sum * 2^(2 log2_scale))
            (-(r.sum_prev.log2() + 2.0 * f64::from(r.log2_scale))).exp2()
        })
        .collect();
    for i in 0..n / 2 {
        let a = 0.5 * (w[i] + w[n - 1 - i]);
        w[i] = a;
        w[n - 1 - i] = a;
    }
    // Normalise (the Christoffel weights already sum to 1 within a few ulp).
    let s: f64 = pairwise_sum(&w);
    for wi in w.iter_mut() {
        *wi *= total / s;
    }
    (x, w)
}

/// Sum from the smallest terms up (weights are symmetric with tiny tails).
fn pairwise_sum(v: &[f64]) -> f64 {
    let mut sorted: Vec<f64> = v.to_vec();
    sorted.sort_by(|a, b| a.abs().total_cmp(&b.abs()));
    sorted.iter().sum()
}

/// Probabilists' Gauss–Hermite rule with `n` points: nodes `z_i` (ascending,
/// symmetric about 0) and weights `w_i` (summing to 1) such that
/// `sum_i w_i f(z_i) = E[f(Z)]`, `Z ~ N(0, 1)`, exactly for polynomials of
/// degree up to `2n - 1`.
///
/// Errors: `n = 0` or `n > MAX_NODES`.
///
/// Note: the outer nodes grow like `2 sqrt(n)` (about 4.1 for 8 nodes, 13.4
/// for 50); a Gaussian input mapped through them may leave its physical range.
pub fn gauss_hermite(n: usize) -> Result<(Vec<f64>, Vec<f64>), QuadratureError> {
    check_nodes(n)?;
    Ok(symmetric_gauss_rule(
        n,
        |k| (k as f64).sqrt(),
        hermite_orthonormal,
        // h_n' = sqrt(n) h_{n-1}
        |n, _x, r| (n as f64).sqrt() * r.p_n1,
        1.0,
    ))
}

/// Gauss–Legendre rule with `n` points on `[-1, 1]`: nodes (ascending) and
/// weights (summing to 2), exact for polynomials of degree up to `2n - 1`.
///
/// Errors: `n = 0` or `n > MAX_NODES`.
pub fn gauss_legendre(n: usize) -> Result<(Vec<f64>, Vec<f64>), QuadratureError> {
    check_nodes(n)?;
    Ok(symmetric_gauss_rule(
        n,
        // Jacobi matrix of the Legendre weight: beta_k = k / sqrt(4k^2 - 1).
        |k| {
            let kf = k as f64;
            kf / (4.0 * kf * kf - 1.0).sqrt()
        },
        legendre_orthonormal,
        // (1 - x^2) P_n' = n (P_{n-1} - x P_n); in orthonormal terms
        // q_n' = n (sqrt((2n+1)/(2n-1)) q_{n-1} - x q_n) / (1 - x^2).
        |n, x, r| {
            let nf = n as f64;
            nf * (((2.0 * nf + 1.0) / (2.0 * nf - 1.0)).sqrt() * r.p_n1 - x * r.p_n) / (1.0 - x * x)
        },
        2.0,
    ))
}

/// A tensor-product quadrature grid in standard-normal space.
#[derive(Clone, Debug, PartialEq)]
pub struct TensorGrid {
    /// Points, each with one coordinate per dimension, in lexicographic order
    /// of the per-dimension node indices with the LAST dimension varying
    /// fastest (point `(i_1, ..., i_d)` is at flat index
    /// `((i_1 n_2 + i_2) n_3 + i_3) ...`).
    pub points: Vec<Vec<f64>>,
    /// Product weights (summing to 1), one per point.
    pub weights: Vec<f64>,
}

/// Tensor product of probabilists' Gauss–Hermite rules with
/// `nodes_per_dim[j]` nodes in dimension `j` (see [`TensorGrid`] for the
/// order of the points). Exact for products of polynomials of degree up to
/// `2 n_j - 1` in each dimension `j`.
///
/// Errors: no dimension, a dimension with 0 or too many nodes, or more than
/// [`MAX_TENSOR_POINTS`] points.
pub fn tensor_grid(nodes_per_dim: &[usize]) -> Result<TensorGrid, QuadratureError> {
    if nodes_per_dim.is_empty() {
        return Err(QuadratureError::NoDimensions);
    }
    for &n in nodes_per_dim {
        check_nodes(n)?;
    }
    // Too many points are refused before any rule is computed (a rule of n nodes is an n × n
    // eigenproblem: three of 1000 nodes took seconds).
    nodes_per_dim
        .iter()
        .try_fold(1, |total, &n| times_nodes(total, n))?;
    let rules: Vec<(Vec<f64>, Vec<f64>)> = nodes_per_dim
        .iter()
        .map(|&n| gauss_hermite(n))
        .collect::<Result<_, _>>()?;
    tensor_product(&rules)
}

/// The points of a tensor grid of `total` points times a dimension of `n` nodes, or
/// [`QuadratureError::TooManyPoints`] beyond [`MAX_TENSOR_POINTS`].
fn times_nodes(total: usize, n: usize) -> Result<usize, QuadratureError> {
    total
        .checked_mul(n)
        .filter(|&t| t <= MAX_TENSOR_POINTS)
        .ok_or(QuadratureError::TooManyPoints)
}

/// Tensor product of one-dimensional rules `(nodes, weights)`, one per dimension, in the
/// order of [`TensorGrid`] (last dimension fastest); each point's weight is the product of
/// its nodes' weights.
///
/// Errors: no dimension, an empty rule, or more than [`MAX_TENSOR_POINTS`] points.
pub fn tensor_product(rules: &[(Vec<f64>, Vec<f64>)]) -> Result<TensorGrid, QuadratureError> {
    if rules.is_empty() {
        return Err(QuadratureError::NoDimensions);
    }
    let sizes: Vec<usize> = rules.iter().map(|r| r.0.len().min(r.1.len())).collect();
    let mut total: usize = 1;
    for &n in &sizes {
        if n == 0 {
            return Err(QuadratureError::ZeroNodes);
        }
        total = times_nodes(total, n)?;
    }
    let d = rules.len();
    let mut points = Vec::with_capacity(total);
    let mut weights = Vec::with_capacity(total);
    let mut idx = vec![0usize; d];
    for _ in 0..total {
        points.push((0..d).map(|j| rules[j].0[idx[j]]).collect());
        weights.push((0..d).map(|j| rules[j].1[idx[j]]).product());
        // Odometer increment, last dimension fastest.
        for j in (0..d).rev() {
            idx[j] += 1;
            if idx[j] < sizes[j] {
                break;
            }
            idx[j] = 0;
        }
    }
    Ok(TensorGrid { points, weights })
}

#[cfg(test)]
// Reference values are quoted with all 17 digits of their 50-digit source.
#[allow(clippy::excessive_precision)]
mod tests {
    use super::*;

    /// E[Z^k] for Z ~ N(0, 1): (k-1)!! for even k, 0 for odd k.
    fn normal_moment(k: u32) -> f64 {
        if k % 2 == 1 {
            0.0
        } else {
            (1..k).step_by(2).map(f64::from).product()
        }
    }

    #[test]
    fn zero_and_too_many_nodes_are_errors() {
        assert_eq!(gauss_hermite(0), Err(QuadratureError::ZeroNodes));
        assert_eq!(
            gauss_hermite(MAX_NODES + 1),
            Err(QuadratureError::TooManyNodes(MAX_NODES + 1))
        );
        assert_eq!(gauss_legendre(0), Err(QuadratureError::ZeroNodes));
        assert_eq!(tensor_grid(&[]), Err(QuadratureError::NoDimensions));
        assert_eq!(tensor_grid(&[3, 0]), Err(QuadratureError::ZeroNodes));
        assert_eq!(
            tensor_grid(&[1000, 1000, 1000]),
            Err(QuadratureError::TooManyPoints)
        );
    }

    #[test]
    fn known_rules_n1_to_n8() {
        // Non-negative nodes and their weights, from mpmath at 40 digits.
        let known: [(&[f64], &[f64]); 8] = [
            (&[0.0], &[1.0]),
            (&[1.0], &[0.5]),
            (
                &[0.0, 1.732_050_807_568_877_3],
                &[0.666_666_666_666_666_67, 0.166_666_666_666_666_67],
            ),
            (
                &[0.741_963_784_302_725_86, 2.334_414_218_338_977_2],
                &[0.454_124_145_231_931_51, 0.045_875_854_768_068_492],
            ),
            (
                &[0.0, 1.355_626_179_974_265_9, 2.856_970_013_872_805_7],
                &[
                    0.533_333_333_333_333_33,
                    0.222_075_922_005_612_64,
                    0.011_257_411_327_720_689,
                ],
            ),
            (
                &[
                    0.616_706_590_192_594_15,
                    1.889_175_877_753_710_7,
                    3.324_257_433_552_119,
                ],
                &[
                    0.408_828_469_556_029_23,
                    0.088_615_746_041_914_527,
                    0.002_555_784_402_056_246_4,
                ],
            ),
            (
                &[
                    0.0,
                    1.154_405_394_739_968_1,
                    2.366_759_410_734_541_3,
                    3.750_439_717_725_742_3,
                ],
                &[
                    0.457_142_857_142_857_14,
                    0.240_123_178_605_012_71,
                    0.030_757_123_967_586_497,
                    0.000_548_268_855_972_217_79,
                ],
            ),
            (
                &[
                    0.539_079_811_351_375_11,
                    1.636_519_042_435_108,
                    2.802_485_861_287_541_7,
                    4.144_547_186_125_894_3,
                ],
                &[
                    0.373_012_257_679_077_35,
                    0.117_239_907_661_759_02,
                    0.009_635_220_120_788_267_2,
                    0.000_112_614_538_375_367_77,
                ],
            ),
        ];
        for (i, (nodes, weights)) in known.iter().enumerate() {
            let n = i + 1;
            let (x, w) = gauss_hermite(n).unwrap();
            assert_eq!(x.len(), n);
            let half = n / 2;
            for (k, (&xk, &wk)) in nodes.iter().zip(weights.iter()).enumerate() {
                // Non-negative nodes start at index n/2 (odd n: the 0 node).
                let j = half + k;
                assert!((x[j] - xk).abs() <= 2e-15 * xk.max(1.0), "n={n} node {k}");
                assert!(
                    (w[j] - wk).abs() <= 2e-15 * wk,
                    "n={n} weight {k}: {} vs {wk}",
                    w[j]
                );
            }
        }
    }

    #[test]
    fn nodes_ascending_symmetric_and_weights_sum_to_one() {
        for n in [1, 2, 3, 7, 10, 31, 64, 100, 150] {
            let (x, w) = gauss_hermite(n).unwrap();
            assert!(x.windows(2).all(|p| p[0] < p[1]), "n={n}");
            for i in 0..n {
                assert_eq!(x[i], -x[n - 1 - i]);
                assert_eq!(w[i], w[n - 1 - i]);
                assert!(w[i] > 0.0);
            }
            let s: f64 = w.iter().sum();
            assert!((s - 1.0).abs() < 1e-14, "n={n}: sum {s}");
        }
    }

    #[test]
    fn exact_normal_moments_up_to_degree_2n_minus_1() {
        for n in [1, 2, 3, 4, 5, 6, 8, 10, 12, 15] {
            let (x, w) = gauss_hermite(n).unwrap();
            for k in 0..(2 * n as u32) {
                let q: f64 = x.iter().zip(&w).map(|(x, w)| w * x.powi(k as i32)).sum();
                let want = normal_moment(k);
                let scale = normal_moment(k + k % 2).max(1.0);
                assert!(
                    (q - want).abs() <= 1e-13 * scale,
                    "n={n} k={k}: {q} vs {want}"
                );
            }
            // Degree 2n is not integrated exactly.
            let k = 2 * n as i32;
            let q: f64 = x.iter().zip(&w).map(|(x, w)| w * x.powi(k)).sum();
            assert!((q - normal_moment(k as u32)).abs() > 1e-6);
        }
    }

    #[test]
    fn large_rules_are_accurate() {
        // E[cos(z)] = exp(-1/2); E[exp(z/2)] = exp(1/8).
        for n in [60, 100, 200] {
            let (x, w) = gauss_hermite(n).unwrap();
            let c: f64 = x.iter().zip(&w).map(|(x, w)| w * x.cos()).sum();
            assert!((c - (-0.5f64).exp()).abs() < 1e-14, "n={n}: {c}");
            let e: f64 = x.iter().zip(&w).map(|(x, w)| w * (0.5 * x).exp()).sum();
            assert!((e - 0.125f64.exp()).abs() < 1e-14, "n={n}: {e}");
            // Largest node of probabilists' Hermite is below 2 sqrt(n).
            assert!(x[n - 1] < 2.0 * (n as f64).sqrt());
        }
    }

    #[test]
    fn legendre_rule_is_exact() {
        for n in [1, 2, 5, 16, 24, 40] {
            let (x, w) = gauss_legendre(n).unwrap();
            let s: f64 = w.iter().sum();
            assert!((s - 2.0).abs() < 1e-14);
            assert!(x.windows(2).all(|p| p[0] < p[1]));
            for k in 0..(2 * n as i32) {
                let q: f64 = x.iter().zip(&w).map(|(x, w)| w * x.powi(k)).sum();
                let want = if k % 2 == 1 {
                    0.0
                } else {
                    2.0 / f64::from(k + 1)
                };
                assert!((q - want).abs() < 1e-14, "n={n} k={k}");
            }
        }
        let (x, w) = gauss_legendre(2).unwrap();
        assert!((x[1] - 1.0 / 3f64.sqrt()).abs() < 2.3e-16);
        assert!((w[0] - 1.0).abs() < 1e-15);
    }

    #[test]
    fn tensor_grid_order_last_dimension_fastest() {
        let g = tensor_grid(&[2, 3]).unwrap();
        let (x3, w3) = gauss_hermite(3).unwrap();
        assert_eq!(g.points.len(), 6);
        let expected = [
            [-1.0, x3[0]],
            [-1.0, x3[1]],
            [-1.0, x3[2]],
            [1.0, x3[0]],
            [1.0, x3[1]],
            [1.0, x3[2]],
        ];
        for (p, e) in g.points.iter().zip(expected.iter()) {
            assert_eq!(p.as_slice(), e.as_slice());
        }
        assert_eq!(g.weights[4], 0.5 * w3[1]);
        let s: f64 = g.weights.iter().sum();
        assert!((s - 1.0).abs() < 1e-15);
    }

    #[test]
    fn tensor_grid_integrates_product_polynomials_exactly() {
        // E[z1^a z2^b z3^c] = E[z1^a] E[z2^b] E[z3^c], degrees < 2 n_j.
        let npd = [3, 4, 2];
        let g = tensor_grid(&npd).unwrap();
        for a in 0..6u32 {
            for b in 0..8u32 {
                for c in 0..4u32 {
                    let q: f64 = g
                        .points
                        .iter()
                        .zip(&g.weights)
                        .map(|(p, w)| {
                            w * p[0].powi(a as i32) * p[1].powi(b as i32) * p[2].powi(c as i32)
                        })
                        .sum();
                    let want = normal_moment(a) * normal_moment(b) * normal_moment(c);
                    assert!((q - want).abs() < 1e-12 * want.max(1.0), "{a} {b} {c}");
                }
            }
        }
        // Non-polynomial: E[exp(z1 + z2/2)] = exp(1/2 + 1/8) with 12 nodes each.
        let g = tensor_grid(&[12, 12]).unwrap();
        let q: f64 = g
            .points
            .iter()
            .zip(&g.weights)
            .map(|(p, w)| w * (p[0] + 0.5 * p[1]).exp())
            .sum();
        assert!((q - 0.625f64.exp()).abs() < 1e-9);
    }
}
