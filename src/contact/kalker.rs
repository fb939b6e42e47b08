//! Kalker's creep coefficients C11, C22, C23 of the linear theory of rolling contact, for an
//! elliptic contact of semi-axes a (rolling direction) and b, interpolated in a/b and in the
//! Poisson ratio ν.
//!
//! Table: J.J. Kalker, *Three-dimensional elastic bodies in rolling contact* (Kluwer, 1990),
//! Table E.3 (also in Kalker 1967 and in the handbooks of railway vehicle dynamics), given at
//! ν = 0, 0.25, 0.5 for g = a/b = 0.1 … 1 and g = b/a = 0.1 … 1. Beyond g = 0.1 the table value at
//! 0.1 is scaled by Kalker's asymptotic formulas for g → 0 (same source). Interpolation: linear in
//! g on the table's grid, then a parabola through the three ν columns in 1/C (the coefficients
//! go roughly as 1/(1 − ν)).
//!
//! The transcription in the open CONTACT code (Vtech CMCC, subroutine `linrol`) was compared:
//! one version there has C23(a/b = 0.8, ν = 0.25) = 1.15, a typo for 1.25 (the row reads 1.13,
//! 1.25, 1.40 in Kalker's table and in CONTACT's later version).

use crate::contact::Portable;
use std::f64::consts::PI;

/// Table rows g = 0.1, 0.2, …, 1.0; for each row [C11; C22; C23] at ν = [0, 0.25, 0.5].
type Rows = [[[f64; 3]; 3]; 10];

/// a/b = g ≤ 1 (contact wider across than along the rolling direction). (3.14 is a table
/// value, not π.)
#[allow(clippy::approx_constant)]
const A_LT_B: Rows = [
    [
        [2.51, 3.31, 4.85],
        [2.51, 2.52, 2.53],
        [0.334, 0.473, 0.731],
    ],
    [
        [2.59, 3.37, 4.81],
        [2.59, 2.63, 2.66],
        [0.483, 0.603, 0.809],
    ],
    [
        [2.68, 3.44, 4.80],
        [2.68, 2.75, 2.81],
        [0.607, 0.715, 0.889],
    ],
    [
        [2.78, 3.53, 4.82],
        [2.78, 2.88, 2.98],
        [0.720, 0.823, 0.977],
    ],
    [[2.88, 3.62, 4.83], [2.88, 3.01, 3.14], [0.827, 0.929, 1.07]],
    [[2.98, 3.72, 4.91], [2.98, 3.14, 3.31], [0.930, 1.03, 1.18]],
    [[3.09, 3.81, 4.97], [3.09, 3.28, 3.48], [1.03, 1.14, 1.29]],
    [[3.19, 3.91, 5.05], [3.19, 3.41, 3.65], [1.13, 1.25, 1.40]],
    [[3.29, 4.01, 5.12], [3.29, 3.54, 3.82], [1.23, 1.36, 1.51]],
    [[3.40, 4.12, 5.20], [3.40, 3.67, 3.98], [1.33, 1.47, 1.63]],
];

/// b/a = g ≤ 1 (contact longer along the rolling direction, as on a flange).
const A_GT_B: Rows = [
    [[10.7, 11.7, 12.9], [10.7, 12.8, 16.0], [12.2, 14.6, 18.0]],
    [[6.96, 7.78, 8.82], [6.96, 8.14, 9.79], [5.72, 6.63, 7.89]],
    [[5.57, 6.34, 7.34], [5.57, 6.40, 7.51], [3.79, 4.32, 5.01]],
    [[4.84, 5.57, 6.57], [4.84, 5.48, 6.31], [2.88, 3.24, 3.70]],
    [[4.37, 5.10, 6.11], [4.37, 4.90, 5.56], [2.35, 2.62, 2.96]],
    [[4.06, 4.78, 5.80], [4.06, 4.50, 5.04], [2.01, 2.23, 2.50]],
    [[3.82, 4.54, 5.58], [3.82, 4.21, 4.67], [1.76, 1.95, 2.18]],
    [[3.65, 4.36, 5.42], [3.65, 3.99, 4.39], [1.58, 1.75, 1.94]],
    [[3.51, 4.22, 5.30], [3.51, 3.81, 4.16], [1.44, 1.59, 1.77]],
    [[3.40, 4.12, 5.20], [3.40, 3.67, 3.98], [1.33, 1.47, 1.63]],
];

/// The ν of the table's columns.
const NU: [f64; 3] = [0.0, 0.25, 0.5];

/// Kalker's coefficients C11, C22, C23 (1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Kalker {
    /// Longitudinal creepage coefficient.
    pub c11: f64,
    /// Lateral creepage coefficient.
    pub c22: f64,
    /// Lateral force from spin creepage.
    pub c23: f64,
}

/// Kalker's asymptotes for g → 0 ([C11, C22, C23] at Poisson ratio `nu`), `wide`: a/b = g (a < b),
/// else b/a = g (a > b).
fn asymptotes(g: f64, nu: f64, wide: bool) -> [f64; 3] {
    if wide {
        [
            PI * PI / (4.0 * (1.0 - nu)),
            PI * PI / 4.0,
            PI * g.sqrt() / (3.0 * (1.0 - nu)) * (1.0 + nu * ((16.0 / g).p_ln() - 5.0)),
        ]
    } else {
        let al = (16.0 / (g * g)).p_ln();
        let l4 = 3.0 - 4f64.p_ln();
        let d = (1.0 - nu) * al + 2.0 * nu;
        [
            2.0 * PI / ((al - 2.0 * nu) * g) * (1.0 + l4 / (al - 2.0 * nu)),
            2.0 * PI / g * (1.0 + (1.0 - nu) * l4 / d) / d,
            2.0 * PI / (3.0 * g.p_powf(1.5) * ((1.0 - nu) * al - 2.0 + 4.0 * nu)),
        ]
    }
}

/// The three coefficients at the table's three ν, linearly interpolated in g ∈ [0.1, 1].
fn table_at(rows: &Rows, g: f64) -> [[f64; 3]; 3] {
    let x = ((g - 0.1) / 0.1).clamp(0.0, 9.0);
    let i = (x.floor() as usize).min(8);
    let t = x - i as f64;
    let mut out = [[0.0; 3]; 3];
    for (c, row) in out.iter_mut().enumerate() {
        for (k, v) in row.iter_mut().enumerate() {
            *v = (1.0 - t) * rows[i][c][k] + t * rows[i + 1][c][k];
        }
    }
    out
}

/// Kalker's coefficients for the semi-axis ratio `a_over_b` (a along the rolling direction) and
/// the Poisson ratio `nu` ∈ [0, 0.5].
pub fn kalker(a_over_b: f64, nu: f64) -> Kalker {
    let wide = a_over_b <= 1.0;
    let g = if wide { a_over_b } else { 1.0 / a_over_b };
    let rows = if wide { &A_LT_B } else { &A_GT_B };
    let cols = table_at(rows, g.max(0.1));
    let mut c = [0.0; 3];
    for (k, out) in c.iter_mut().enumerate() {
        // Parabola through (ν_j, 1/C_j), j = 0..2, evaluated at nu (Lagrange form).
        let mut inv = 0.0;
        for (j, &nj) in NU.iter().enumerate() {
            let l: f64 = NU
                .iter()
                .enumerate()
                .filter(|&(m, _)| m != j)
                .map(|(_, &nm)| (nu - nm) / (nj - nm))
                .product();
            inv += l / cols[k][j];
        }
        *out = 1.0 / inv;
    }
    if g < 0.1 {
        let (far, edge) = (asymptotes(g, nu, wide), asymptotes(0.1, nu, wide));
        for k in 0..3 {
            c[k] *= far[k] / edge[k];
        }
    }
    Kalker {
        c11: c[0],
        c22: c[1],
        c23: c[2],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_points_are_returned_as_published() {
        // (a/b, ν, C11, C22, C23) read from Kalker's Table E.3.
        for (ab, nu, c11, c22, c23) in [
            (0.1, 0.25, 3.31, 2.52, 0.473),
            (0.5, 0.0, 2.88, 2.88, 0.827),
            (0.8, 0.25, 3.91, 3.41, 1.25),
            (1.0, 0.25, 4.12, 3.67, 1.47),
            (1.0, 0.5, 5.20, 3.98, 1.63),
            (2.0, 0.25, 5.10, 4.90, 2.62),
            (1.0 / 0.3, 0.5, 7.34, 7.51, 5.01),
            (10.0, 0.25, 11.7, 12.8, 14.6),
        ] {
            let k = kalker(ab, nu);
            let close = |x: f64, y: f64| (x - y).abs() < 1e-9 * y;
            assert!(close(k.c11, c11), "C11({ab}, {nu}) = {} not {c11}", k.c11);
            assert!(close(k.c22, c22), "C22({ab}, {nu}) = {} not {c22}", k.c22);
            assert!(close(k.c23, c23), "C23({ab}, {nu}) = {} not {c23}", k.c23);
        }
    }

    #[test]
    fn interpolation_lies_between_neighbours_and_extends_continuously() {
        // Between rows and between ν columns.
        let k = kalker(0.85, 0.27);
        assert!(k.c11 > 3.91 && k.c11 < 4.01 + 0.2, "{k:?}");
        let lo = kalker(0.85, 0.25);
        let hi = kalker(0.85, 0.5);
        for (x, l, h) in [
            (k.c11, lo.c11, hi.c11),
            (k.c22, lo.c22, hi.c22),
            (k.c23, lo.c23, hi.c23),
        ] {
            assert!(x > l && x < h, "{x} not in ({l}, {h})");
        }
        // Continuous at a/b = 1 and at g = 0.1 on both sides; growing as b/a → 0.
        for nu in [0.0, 0.27, 0.5] {
            for (a, b) in [
                (0.999_999, 1.000_001),
                (0.1 - 1e-9, 0.1 + 1e-9),
                (10.0 - 1e-7, 10.0 + 1e-7),
            ] {
                let (x, y) = (kalker(a, nu), kalker(b, nu));
                assert!((x.c11 - y.c11).abs() < 1e-5 && (x.c23 - y.c23).abs() < 1e-5);
            }
            assert!(kalker(20.0, nu).c11 > kalker(10.0, nu).c11);
            assert!(kalker(0.05, nu).c23 < kalker(0.1, nu).c23);
        }
    }
}
