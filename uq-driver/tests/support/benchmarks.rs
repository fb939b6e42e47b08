//! Analytic UQ benchmarks and their references, written independently of the code under
//! test (closed forms, or tensor Gauss quadratures whose nodes are computed here by
//! Golub–Welsch): the Ishigami function, the borehole function, the Sobol' g-function.

use std::f64::consts::PI;

use nalgebra::{DMatrix, SymmetricEigen};

/// Ishigami (a = 7, b = 0.1, x_i ~ U(-pi, pi)): first-order and total indices, closed form.
pub fn ishigami_indices() -> ([f64; 3], [f64; 3]) {
    let (a, b) = (7.0f64, 0.1f64);
    let v1 = 0.5 * (1.0 + b * PI.powi(4) / 5.0).powi(2);
    let v2 = a * a / 8.0;
    let v13 = b * b * PI.powi(8) * (1.0 / 18.0 - 1.0 / 50.0);
    let v = a * a / 8.0 + b * PI.powi(4) / 5.0 + b * b * PI.powi(8) / 18.0 + 0.5;
    ([v1 / v, v2 / v, 0.0], [(v1 + v13) / v, v2 / v, v13 / v])
}

/// Ishigami mean and variance.
pub fn ishigami_moments() -> (f64, f64) {
    let (a, b) = (7.0f64, 0.1f64);
    (
        a / 2.0,
        a * a / 8.0 + b * PI.powi(4) / 5.0 + b * b * PI.powi(8) / 18.0 + 0.5,
    )
}

/// Lower and upper ends of the six uniform borehole inputs Tu, Hu, Tl, Hl, L, Kw.
pub const BOREHOLE_LO: [f64; 6] = [63070.0, 990.0, 63.1, 700.0, 1120.0, 9855.0];
/// Upper ends.
pub const BOREHOLE_HI: [f64; 6] = [115600.0, 1110.0, 116.0, 820.0, 1680.0, 12045.0];
/// rw ~ N(RW.0, RW.1²).
pub const RW: (f64, f64) = (0.10, 0.0161812);
/// ln r ~ N(LN_R.0, LN_R.1²).
pub const LN_R: (f64, f64) = (7.71, 1.0056);

/// The borehole function (m³/yr) at physical values rw, r, Tu, Hu, Tl, Hl, L, Kw.
pub fn borehole(x: &[f64]) -> f64 {
    let (rw, r, tu, hu, tl, hl, l, kw) = (x[0], x[1], x[2], x[3], x[4], x[5], x[6], x[7]);
    let lnr = (r / rw).ln();
    2.0 * PI * tu * (hu - hl) / (lnr * (1.0 + 2.0 * l * tu / (lnr * rw * rw * kw) + tu / tl))
}

/// Borehole at germ `t`: two standard normals (rw, ln r), six in [-1, 1].
pub fn borehole_germ(t: &[f64]) -> f64 {
    let mut x = vec![RW.0 + RW.1 * t[0], (LN_R.0 + LN_R.1 * t[1]).exp()];
    x.extend(
        (0..6).map(|k| BOREHOLE_LO[k] + (BOREHOLE_HI[k] - BOREHOLE_LO[k]) * 0.5 * (t[2 + k] + 1.0)),
    );
    borehole(&x)
}

/// Gauss rule of a symmetric Jacobi matrix with off-diagonal `b(k)` (k = 1..n-1):
/// nodes and weights normalised to 1.
fn golub_welsch(n: usize, b: impl Fn(usize) -> f64) -> (Vec<f64>, Vec<f64>) {
    let j = DMatrix::from_fn(n, n, |i, k| {
        if k == i + 1 || i == k + 1 {
            b(i.max(k))
        } else {
            0.0
        }
    });
    let e = SymmetricEigen::new(j);
    let mut pairs: Vec<(f64, f64)> = (0..n)
        .map(|i| (e.eigenvalues[i], e.eigenvectors[(0, i)].powi(2)))
        .collect();
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    let s: f64 = pairs.iter().map(|p| p.1).sum();
    (
        pairs.iter().map(|p| p.0).collect(),
        pairs.iter().map(|p| p.1 / s).collect(),
    )
}

/// Probabilists' Gauss–Hermite rule (N(0, 1), weights summing to 1).
pub fn gauss_hermite(n: usize) -> (Vec<f64>, Vec<f64>) {
    golub_welsch(n, |k| (k as f64).sqrt())
}

/// Gauss–Legendre rule for U(-1, 1) (weights summing to 1).
pub fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    golub_welsch(n, |k| {
        let k = k as f64;
        k / (4.0 * k * k - 1.0).sqrt()
    })
}

/// Borehole mean and standard deviation by a tensor Gauss rule: `nh` Hermite nodes for
/// the two normal germs, `nl` Legendre nodes for the six uniform ones.
pub fn borehole_reference(nh: usize, nl: usize) -> (f64, f64) {
    let (hx, hw) = gauss_hermite(nh);
    let (lx, lw) = gauss_legendre(nl);
    let (mut m1, mut m2) = (0.0, 0.0);
    let mut t = [0.0; 8];
    for a in 0..nh {
        for b in 0..nh {
            for idx in 0..nl.pow(6) {
                let (mut k, mut w) = (idx, hw[a] * hw[b]);
                t[0] = hx[a];
                t[1] = hx[b];
                for j in 0..6 {
                    t[2 + j] = lx[k % nl];
                    w *= lw[k % nl];
                    k /= nl;
                }
                let f = borehole_germ(&t);
                m1 += w * f;
                m2 += w * f * f;
            }
        }
    }
    (m1, (m2 - m1 * m1).sqrt())
}

/// The g-function coefficients of the Functions test FMU.
pub const G_A: [f64; 8] = [0.0, 1.0, 4.5, 9.0, 99.0, 99.0, 99.0, 99.0];

/// g-function (x_i ~ U(0, 1)) first-order and total indices, closed form.
pub fn g_function_indices() -> (Vec<f64>, Vec<f64>) {
    let vi: Vec<f64> = G_A
        .iter()
        .map(|ai| 1.0 / (3.0 * (1.0 + ai) * (1.0 + ai)))
        .collect();
    let v = vi.iter().map(|x| 1.0 + x).product::<f64>() - 1.0;
    let first = vi.iter().map(|x| x / v).collect();
    let total = (0..8)
        .map(|i| {
            let others: f64 = (0..8).filter(|&j| j != i).map(|j| 1.0 + vi[j]).product();
            vi[i] * others / v
        })
        .collect();
    (first, total)
}
