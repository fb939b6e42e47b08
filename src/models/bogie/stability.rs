//! Linear stability of the bogie: the state matrix of the model linearised about the centred
//! motion, its growth rate and the linear (Hopf) critical speed.
#![forbid(unsafe_code)]

use super::{Bogie, BogieParams};
use nalgebra::Matrix4;

/// State matrix A (x' = A x, x = [Y, φ, Y', φ']) of the model linearised about the centred
/// motion at speed `v` (m/s): creep forces F = μN ξ/ψ, μN ξ/ϕ, no flange contact.
pub fn linear_state_matrix(p: &BogieParams, v: f64) -> Matrix4<f64> {
    let cx = p.mu * p.n / p.psi; // N per unit longitudinal creepage
    let cy = p.mu * p.n / p.phi_c; // N per unit lateral creepage
    let (m, i) = (p.m_b, p.i_b);
    // Y''  = [-2K Y - 2C Y' - 2cy (2Y'/V - 2φ)] / m
    // φ'' = [-Kφ φ - 2h cy (2h φ'/V) - 2a cx (2a φ'/V + 2λ Y/r0)] / I
    Matrix4::new(
        0.0,
        0.0,
        1.0,
        0.0,
        0.0,
        0.0,
        0.0,
        1.0,
        -2.0 * p.k_sy / m,
        4.0 * cy / m,
        -(2.0 * p.c_sy + 4.0 * cy / v) / m,
        0.0,
        -4.0 * p.a * cx * p.lambda / (p.r0 * i),
        -p.k_phi / i,
        0.0,
        -4.0 * (p.h * p.h * cy + p.a * p.a * cx) / (v * i),
    )
}

/// Largest real part (1/s) of the eigenvalues of [`linear_state_matrix`] at speed `v` (m/s).
pub fn linear_growth_rate(p: &BogieParams, v: f64) -> f64 {
    linear_state_matrix(p, v)
        .complex_eigenvalues()
        .iter()
        .map(|z| z.re)
        .fold(f64::NEG_INFINITY, f64::max)
}

/// Linear (Hopf) critical speed (m/s) of the bogie's parameters: the lowest speed at which the
/// largest real part of the eigenvalues of the linearised state matrix crosses zero, found by a
/// scan in 1 m/s steps from 2 to 1000 m/s and bisection to 1e-9 m/s. Returns `f64::INFINITY` if
/// the linearised model is stable over the whole scan, and `f64::NAN` if it is already unstable
/// at 2 m/s (for instance with a negative stiffness).
pub fn linear_critical_speed(bogie: &Bogie) -> f64 {
    let p = &bogie.p;
    let g = |v: f64| linear_growth_rate(p, v);
    let mut lo = 2.0;
    let g_lo = g(lo);
    if g_lo.is_nan() || g_lo >= 0.0 {
        return f64::NAN;
    }
    let mut hi = f64::INFINITY;
    let mut v = lo;
    while v < 1000.0 {
        let next = v + 1.0;
        if g(next) >= 0.0 {
            lo = v;
            hi = next;
            break;
        }
        v = next;
    }
    if hi.is_infinite() {
        return f64::INFINITY;
    }
    while hi - lo > 1e-9 {
        let mid = 0.5 * (lo + hi);
        if g(mid) < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// [`linear_critical_speed`] clamped to the search range 2..1000 m/s, so the output is finite.
pub(super) fn clamped_linear_critical_speed(b: &Bogie) -> f64 {
    let v = linear_critical_speed(b);
    if v.is_nan() {
        2.0
    } else {
        v.min(1000.0)
    }
}
