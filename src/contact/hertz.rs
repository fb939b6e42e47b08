//! Hertz's elliptic contact: the semi-axes, the approach (penetration) and the peak pressure of
//! two elastic bodies of equal material pressed together by a normal force, from the sums of
//! their principal curvatures.
//!
//! With A and B the half-sums of the principal curvatures in the two directions (x: rolling,
//! y: lateral) and the semi-axes α ≥ β (α along the direction of the smaller sum), e² = 1 − β²/α²,
//! K(e), E(e) the complete elliptic integrals, E* = E / (2 (1 − ν²)) and p0 = 3N / (2π α β)
//! (Johnson, Contact Mechanics, §4.2):
//!
//! - A_small = (p0 / E*) · β / (e² α²) · (K − E),
//! - A_large = (p0 / E*) · β / (e² α²) · ((α²/β²) E − K),
//! - approach q0 = (p0 / E*) · β · K.
//!
//! The ratio A_large / A_small fixes e; then A_small fixes α.

use crate::contact::Portable;
use std::f64::consts::PI;

/// Complete elliptic integrals of the first and second kind, K(m) and E(m), for the parameter
/// m = e² ∈ [0, 1), by the arithmetic–geometric mean.
pub fn elliptic_ke(m: f64) -> (f64, f64) {
    let mut a = 1.0;
    let mut b = (1.0 - m).sqrt();
    let mut c = m.sqrt();
    let mut sum = 0.5 * c * c;
    let mut pow = 0.5;
    for _ in 0..40 {
        if c.abs() < 1e-17 {
            break;
        }
        let an = 0.5 * (a + b);
        let bn = (a * b).sqrt();
        c = 0.5 * (a - b);
        pow *= 2.0;
        sum += pow * c * c;
        a = an;
        b = bn;
    }
    let k = PI / (2.0 * a);
    (k, k * (1.0 - sum))
}

/// Hertz contact of an ellipse.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hertz {
    /// Semi-axis along x, the rolling direction (m).
    pub a: f64,
    /// Semi-axis along y, across the rolling direction (m).
    pub b: f64,
    /// Approach of the two bodies (static penetration) (m).
    pub q0: f64,
    /// Peak pressure (Pa).
    pub p0: f64,
}

/// (K − E)/m and (E/(1 − m) − K)/m for m = e², with their series at small m (m < 1e-4), where
/// the differences lose digits.
fn differences(m: f64) -> (f64, f64, f64) {
    let (k, e) = elliptic_ke(m);
    if m < 1e-4 {
        // K = π/2 (1 + m/4 + 9m²/64), E = π/2 (1 − m/4 − 3m²/64), E/(1−m) = π/2 (1 + 3m/4 + 45m²/64).
        let p = PI / 2.0;
        let km_e = p * (0.5 + 12.0 / 64.0 * m);
        let e1_k = p * (0.5 + 36.0 / 64.0 * m);
        return (k, km_e, e1_k);
    }
    (k, (k - e) / m, (e / (1.0 - m) - k) / m)
}

/// The Hertz contact of bodies of Young's modulus `young` (Pa) and Poisson ratio `poisson`
/// (both bodies) pressed by `normal` (N), with half-sums of principal curvatures `ax` along x
/// (rolling) and `by` along y (1/m), both > 0.
pub fn hertz(normal: f64, ax: f64, by: f64, young: f64, poisson: f64) -> Hertz {
    let e_star = young / (2.0 * (1.0 - poisson * poisson));
    let (small, large) = if ax <= by { (ax, by) } else { (by, ax) };
    let ratio = large / small;
    // Solve ratio = g(m) = ((E/(1−m) − K)/m) / ((K − E)/m) for m = e² ∈ [0, 1), g increasing.
    let g = |m: f64| {
        let (_, d1, d2) = differences(m);
        d2 / d1
    };
    let m = if ratio <= 1.0 + 1e-12 {
        0.0
    } else {
        // Solve in t = −ln(1 − m) (β/α = e^(−t/2)): f(t) = ln g − ln ratio rises with t. Start
        // from β/α ≈ (small/large)^(2/3), then secant steps kept in a bracket that grows until
        // it holds the root and shrinks with every step (bisection when the secant leaves it).
        let f = |t: f64| (g(-(-t).p_exp_m1()) / ratio).p_ln();
        let mut t = (-(4.0 / 3.0) * (small / large).p_ln()).max(1e-8);
        let mut ft = f(t);
        let (mut lo, mut hi) = (0.0f64, f64::INFINITY);
        let mut prev: Option<(f64, f64)> = None;
        for _ in 0..200 {
            if ft < 0.0 {
                lo = t;
            } else {
                hi = t;
            }
            let mut next = match prev {
                Some((tp, fp)) if fp != ft => t - ft * (t - tp) / (ft - fp),
                _ => t * if ft < 0.0 { 1.1 } else { 0.9 },
            };
            if !(next > lo && next < hi) {
                next = if hi.is_finite() {
                    0.5 * (lo + hi)
                } else {
                    2.0 * lo.max(1e-8)
                };
            }
            if (next - t).abs() <= 1e-15 * t.max(1.0) || hi - lo <= 1e-15 * t.max(1.0) {
                t = next;
                break;
            }
            prev = Some((t, ft));
            t = next;
            ft = f(t);
        }
        -(-t).p_exp_m1()
    };
    let (k, d1, _) = differences(m);
    // small = (p0/E*) β/(e² α²) (K − E) with p0 = 3N/(2π α β) → α³ = 3N (K − E)/(2π E* e² small).
    let alpha = (3.0 * normal * d1 / (2.0 * PI * e_star * small)).p_cbrt();
    let beta = alpha * (1.0 - m).sqrt();
    let p0 = 3.0 * normal / (2.0 * PI * alpha * beta);
    let q0 = p0 * beta * k / e_star;
    let (a, b) = if ax <= by {
        (alpha, beta)
    } else {
        (beta, alpha)
    };
    Hertz { a, b, q0, p0 }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ∫₀^∞ dw / ((α² + w)^p (β² + w)^q √w), by w = t² and the substitution t = tan θ, with
    /// a composite Gauss–Legendre rule (independent of the elliptic integrals above).
    fn kellogg(alpha: f64, beta: f64, p: f64, q: f64) -> f64 {
        // ∫₀^∞ 2 dt / ((α² + t²)^p (β² + t²)^q), t = β tan θ.
        let nodes = [
            (-0.906179845938664, 0.236926885056189),
            (-0.538469310105683, 0.478628670499366),
            (0.0, 0.568888888888889),
            (0.538469310105683, 0.478628670499366),
            (0.906179845938664, 0.236926885056189),
        ];
        let n = 4000;
        let h = (PI / 2.0) / n as f64;
        let mut sum = 0.0;
        for i in 0..n {
            let c = (i as f64 + 0.5) * h;
            for (x, w) in nodes {
                let th = c + 0.5 * h * x;
                let t = beta * th.tan();
                let dt = beta / (th.p_cos() * th.p_cos());
                let f = 2.0 * dt
                    / ((alpha * alpha + t * t).p_powf(p) * (beta * beta + t * t).p_powf(q));
                sum += 0.5 * h * w * f;
            }
        }
        sum
    }

    #[test]
    fn elliptic_integrals_at_known_values() {
        let (k, e) = elliptic_ke(0.0);
        assert!((k - PI / 2.0).abs() < 1e-15 && (e - PI / 2.0).abs() < 1e-15);
        // K(m = 1/2) = Γ(1/4)²/(4√π) = 1.854074677301372, E(1/2) = 1.350643881047675.
        let (k, e) = elliptic_ke(0.5);
        assert!((k - 1.854074677301372).abs() < 1e-14, "{k}");
        assert!((e - 1.350643881047675).abs() < 1e-14, "{e}");
    }

    #[test]
    fn a_sphere_on_a_plane_gives_hertz_circle() {
        // Sphere of radius R on a plane: a = (3NR/(4E*))^(1/3), approach a²/R.
        let (n, r, young, nu) = (1e4, 0.5, 2.1e11, 0.3);
        let e_star = young / (2.0 * (1.0 - nu * nu));
        let h = hertz(n, 0.5 / r, 0.5 / r, young, nu);
        let a = (3.0 * n * r / (4.0 * e_star)).p_cbrt();
        assert!((h.a - a).abs() < 1e-12 * a && (h.b - a).abs() < 1e-12 * a);
        assert!((h.q0 - a * a / r).abs() < 1e-10 * h.q0);
    }

    #[test]
    fn crossed_cylinders_satisfy_hertz_s_integral_equations() {
        // A wheel (cylinder of radius 0.46 m across y) on a rail crown of radius 0.3 m (a
        // cylinder along x), and a flange-like contact: the surface displacements of Hertz's
        // ellipsoidal pressure, as Kellogg's potential integrals, must equal the gap:
        // A = (p0 α β / (2E*)) ∫ dw/((α²+w)^{3/2}(β²+w)^{1/2}√w) along α, likewise B along β,
        // and the approach q0 = (p0 α β / (2E*)) ∫ dw/((α²+w)^{1/2}(β²+w)^{1/2}√w).
        for (n, ax, by) in [
            (66_600.0, 0.5 / 0.46, 0.5 / 0.3),
            (66_600.0, 0.5 / 0.3, 0.5 / 0.46),
            (40_000.0, 0.5 / 1.3, 0.5 / 0.004),
        ] {
            let (young, nu) = (2.1e11, 0.27);
            let e_star = young / (2.0 * (1.0 - nu * nu));
            let h = hertz(n, ax, by, young, nu);
            let c = h.p0 * h.a * h.b / (2.0 * e_star);
            let a_x = c * kellogg(h.a, h.b, 1.5, 0.5);
            let b_y = c * kellogg(h.a, h.b, 0.5, 1.5);
            let q0 = c * kellogg(h.a, h.b, 0.5, 0.5);
            assert!(
                (a_x / ax - 1.0).abs() < 1e-7,
                "{n} {ax} {by}: A {a_x} vs {ax}"
            );
            assert!((b_y / by - 1.0).abs() < 1e-7, "B {b_y} vs {by}");
            assert!((q0 / h.q0 - 1.0).abs() < 1e-7, "q0 {q0} vs {}", h.q0);
            assert!((h.p0 - 3.0 * n / (2.0 * PI * h.a * h.b)).abs() < 1e-6 * h.p0);
        }
    }
}
