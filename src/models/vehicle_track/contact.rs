//! Wheel–rail normal contact: Hertz's law, or its tangent at the static load.
//!
//! ```text
//! δ = Z_w − Z_r(x_w) − Z_0(x_w)            compression of the contact (m), Z positive down
//! P = (δ / G)^{3/2}   for δ > 0, else 0    nonlinear Hertz (N)
//! P = max(0, P_s + k_H (δ − δ_s))          linearised at the static load P_s, δ_s = G P_s^{2/3},
//!                                          k_H = 3 P_s^{1/3} / (2 G)
//! G = 4.57 R^{−0.149} × 10⁻⁸ m/N^{2/3}     conical tread (Zhai), R the wheel radius (m)
//! ```
//! Either law gives P = 0 exactly, never a negative or NaN force, when the wheel leaves the rail.
#![forbid(unsafe_code)]

/// Which contact law to use (Integer variable `contact_law`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ContactLaw {
    /// 0: nonlinear Hertz, P = (δ/G)^{3/2}.
    Hertz,
    /// 1: Hertz linearised at the static wheel load.
    LinearisedHertz,
}

impl ContactLaw {
    /// From the Integer code (0 or 1).
    pub fn from_code(code: i32) -> Option<Self> {
        match code {
            0 => Some(Self::Hertz),
            1 => Some(Self::LinearisedHertz),
            _ => None,
        }
    }
    /// The Integer code.
    pub fn code(self) -> i32 {
        match self {
            Self::Hertz => 0,
            Self::LinearisedHertz => 1,
        }
    }
}

/// Hertz constant G (m/N^{2/3}) of a conical tread of rolling radius `r` (m): 4.57e-8 r^−0.149.
pub fn hertz_constant(r: f64) -> f64 {
    4.57e-8 * r.powf(-0.149)
}

/// One wheel's contact spring.
#[derive(Clone, Copy, Debug)]
pub struct Contact {
    /// The law.
    pub law: ContactLaw,
    /// Hertz constant G (m/N^{2/3}).
    pub g: f64,
    /// Static load P_s (N), the linearisation point.
    pub p_static: f64,
    /// δ_s = G P_s^{2/3} (m).
    delta_static: f64,
    /// k_H = 3 P_s^{1/3}/(2G) (N/m).
    k_lin: f64,
}

impl Contact {
    /// A contact with Hertz constant `g` (m/N^{2/3}) linearised (if asked) at `p_static` (N).
    pub fn new(law: ContactLaw, g: f64, p_static: f64) -> Self {
        let delta_static = g * p_static.cbrt().powi(2);
        Self {
            law,
            g,
            p_static,
            delta_static,
            k_lin: 1.5 * p_static.cbrt() / g,
        }
    }

    /// Contact force P (N) at compression `delta` (m); 0 when the wheel is off the rail.
    #[inline(always)]
    pub fn force(&self, delta: f64) -> f64 {
        match self.law {
            ContactLaw::Hertz => {
                if delta > 0.0 {
                    let s = delta / self.g;
                    s * s.sqrt()
                } else {
                    0.0
                }
            }
            ContactLaw::LinearisedHertz => {
                let p = self.p_static + self.k_lin * (delta - self.delta_static);
                if p > 0.0 {
                    p
                } else {
                    0.0
                }
            }
        }
    }

    /// Compression (m) that carries the load `p` (N) ≥ 0: the inverse of [`Contact::force`].
    pub fn compression(&self, p: f64) -> f64 {
        match self.law {
            ContactLaw::Hertz => self.g * p.cbrt().powi(2),
            ContactLaw::LinearisedHertz => self.delta_static + (p - self.p_static) / self.k_lin,
        }
    }

    /// Tangent stiffness dP/dδ (N/m) at the static load.
    pub fn static_stiffness(&self) -> f64 {
        self.k_lin
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hertz_constant_at_the_default_radius() {
        // 4.57e-8 · 0.43^−0.149 = 4.57e-8 · e^{0.149·0.84397} = 5.1824e-8 m/N^(2/3).
        let g = hertz_constant(0.43);
        assert!((g - 5.1824e-8).abs() < 1e-12, "{g:e}");
    }

    #[test]
    fn hertz_force_and_compression_are_inverse() {
        let c = Contact::new(ContactLaw::Hertz, hertz_constant(0.43), 69_000.0);
        for &p in &[1.0, 1e3, 69e3, 3e5] {
            let d = c.compression(p);
            assert!((c.force(d) - p).abs() < 1e-9 * p);
        }
        // 69 kN compresses the contact by about 87 µm.
        assert!((c.compression(69_000.0) - 87.2e-6).abs() < 0.5e-6);
    }

    #[test]
    fn no_tension_and_no_nan_when_the_wheel_lifts() {
        for law in [ContactLaw::Hertz, ContactLaw::LinearisedHertz] {
            let c = Contact::new(law, hertz_constant(0.43), 69_000.0);
            for &d in &[0.0, -1e-9, -1e-3, -1.0] {
                let p = c.force(d);
                assert_eq!(p, 0.0, "{law:?} at {d}");
            }
        }
    }

    #[test]
    fn linearised_law_is_the_tangent_at_the_static_load() {
        let g = hertz_constant(0.43);
        let (h, l) = (
            Contact::new(ContactLaw::Hertz, g, 69_000.0),
            Contact::new(ContactLaw::LinearisedHertz, g, 69_000.0),
        );
        let d0 = h.compression(69_000.0);
        assert!((l.force(d0) - 69_000.0).abs() < 1e-6);
        let e = 1e-9;
        let slope = (h.force(d0 + e) - h.force(d0 - e)) / (2.0 * e);
        assert!((slope - l.static_stiffness()).abs() < 1e-5 * slope);
        // Unloads to zero at δ_s/3, where the tangent crosses zero.
        assert_eq!(l.force(d0 / 3.0 - 1e-12), 0.0);
    }
}
