//! Equivalent conicity λ_eq (tan γ_e) of a wheelset on a track from its rolling radius
//! difference Δr(y) = r_L − r_R, by EN 15302's reference method: the wavelength of the
//! wheelset's kinematic (Klingel) motion of amplitude ŷ, integrated through the nonlinear
//! Δr(y), compared with the wavelength of a conical wheelset.
//!
//! The kinematic motion obeys y'' = −Δr(y)/(e r0) (x the distance run, e the distance between
//! the contact points, r0 the rolling radius). With S(y) = ∫_{y0}^{y} Δr (y0 where Δr = 0), a
//! motion between the turning points y1 < y2 has S(y1) = S(y2) = E, ŷ = (y2 − y1)/2, slope
//! ψ² = 2 (E − S(y)) / (e r0), and wavelength λ = 2 ∫_{y1}^{y2} dy/ψ. A conical wheelset of
//! conicity γ has λ = 2π √(e r0 / (2γ)), so tan γ_e = 2π² e r0 / λ²; e r0 cancels.
//!
//! Δr between the given points is taken as linear, so S is piecewise quadratic and exact.
//! The integral is taken by y = (y1 + y2)/2 − ŷ cos θ, which removes the square-root
//! singularities at the turning points, with the midpoint rule in θ. Where the motion would
//! stop between the turning points (Δr = 0 over a range), λ is infinite and tan γ_e = 0.

use crate::contact::Portable;
use std::f64::consts::PI;

/// Why an equivalent conicity cannot be computed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ConicityError {
    /// The Δr function is not usable.
    #[error("Δr(y): {0}")]
    Input(String),
    /// The amplitude reaches beyond the Δr function.
    #[error("amplitude {amplitude} m reaches beyond the Δr function")]
    Beyond {
        /// The amplitude (m).
        amplitude: f64,
    },
}

/// Points of the midpoint rule in θ.
const POINTS: usize = 4000;

/// Δr(y) on a grid with its primitive S.
#[derive(Clone, Debug)]
pub struct DeltaR {
    y: Vec<f64>,
    dr: Vec<f64>,
    /// S at the grid points, from y0.
    s: Vec<f64>,
    y0: f64,
}

impl DeltaR {
    /// Δr (m) at ascending displacements y (m). Δr must change sign (from negative to positive
    /// with growing y) somewhere in the range.
    pub fn new(y: &[f64], dr: &[f64]) -> Result<DeltaR, ConicityError> {
        let bad = |m: &str| Err(ConicityError::Input(m.to_owned()));
        if y.len() != dr.len() || y.len() < 3 {
            return bad("needs at least 3 points, as many y as Δr");
        }
        if y.iter().chain(dr).any(|v| !v.is_finite()) {
            return bad("values must be finite");
        }
        if (1..y.len()).any(|i| y[i] <= y[i - 1]) {
            return bad("y must increase strictly");
        }
        // Primitive from the first point, by exact integration of the linear pieces.
        let mut s = vec![0.0; y.len()];
        for i in 1..y.len() {
            s[i] = s[i - 1] + 0.5 * (dr[i] + dr[i - 1]) * (y[i] - y[i - 1]);
        }
        // y0: the sign change of Δr nearest the middle of the range (a zero run counts at its
        // middle).
        let mid = 0.5 * (y[0] + y[y.len() - 1]);
        let mut y0: Option<f64> = None;
        let mut consider = |c: f64| {
            if y0.is_none_or(|b| (c - mid).abs() < (b - mid).abs()) {
                y0 = Some(c);
            }
        };
        let mut i = 0;
        while i + 1 < y.len() {
            if dr[i] < 0.0 && dr[i + 1] > 0.0 {
                consider(y[i] - dr[i] * (y[i + 1] - y[i]) / (dr[i + 1] - dr[i]));
            } else if dr[i] < 0.0 && dr[i + 1] == 0.0 {
                let mut j = i + 1;
                while j + 1 < y.len() && dr[j + 1] == 0.0 {
                    j += 1;
                }
                if j + 1 < y.len() && dr[j + 1] > 0.0 {
                    consider(0.5 * (y[i + 1] + y[j]));
                }
                i = j;
                continue;
            }
            i += 1;
        }
        let Some(y0) = y0 else {
            return bad("Δr must pass from negative to positive as y grows");
        };
        let mut out = DeltaR {
            y: y.to_vec(),
            dr: dr.to_vec(),
            s,
            y0: 0.0,
        };
        let s0 = out.primitive(y0);
        out.s.iter_mut().for_each(|v| *v -= s0);
        out.y0 = y0;
        Ok(out)
    }

    /// The displacement where Δr = 0 (m).
    pub fn centre(&self) -> f64 {
        self.y0
    }

    /// S(y) = ∫_{y0}^{y} Δr, Δr linear between the points (m²).
    fn primitive(&self, y: f64) -> f64 {
        let n = self.y.len();
        let i = self.y.partition_point(|&v| v <= y).clamp(1, n - 1) - 1;
        let h = y - self.y[i];
        let slope = (self.dr[i + 1] - self.dr[i]) / (self.y[i + 1] - self.y[i]);
        self.s[i] + self.dr[i] * h + 0.5 * slope * h * h
    }

    /// The equivalent conicity tan γ_e (1) for the amplitude ŷ (m, > 0).
    pub fn conicity(&self, amplitude: f64) -> Result<f64, ConicityError> {
        let (first, last) = (self.y[0], self.y[self.y.len() - 1]);
        let w = 2.0 * amplitude;
        if amplitude.is_nan() || amplitude <= 0.0 || w > last - first {
            return Err(ConicityError::Beyond { amplitude });
        }
        // y1 ∈ [y0 − w, y0] with S(y1 + w) = S(y1): h(y1) = S(y1 + w) − S(y1) rises through 0.
        let (mut a, mut b) = ((self.y0 - w).max(first), self.y0.min(last - w));
        let h = |y1: f64| self.primitive(y1 + w) - self.primitive(y1);
        if a > b || h(a) > 0.0 || h(b) < 0.0 {
            return Err(ConicityError::Beyond { amplitude });
        }
        for _ in 0..200 {
            let m = 0.5 * (a + b);
            if h(m) < 0.0 {
                a = m;
            } else {
                b = m;
            }
            if b - a < 1e-15 * (1.0 + w) {
                break;
            }
        }
        let y1 = 0.5 * (a + b);
        let energy = 0.5 * (self.primitive(y1) + self.primitive(y1 + w));
        let centre = y1 + amplitude;
        // A drop this small is rounding: the motion stops (Δr = 0 over a range).
        let scale = amplitude * self.dr.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let dth = PI / POINTS as f64;
        let mut integral = 0.0;
        for k in 0..POINTS {
            let th = (k as f64 + 0.5) * dth;
            let y = centre - amplitude * th.p_cos();
            let drop = energy - self.primitive(y);
            if drop <= 1e-12 * scale {
                return Ok(0.0);
            }
            integral += amplitude * th.p_sin() / (2.0 * drop).sqrt() * dth;
        }
        let lambda = 2.0 * integral;
        Ok(2.0 * PI * PI / (lambda * lambda))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(from: f64, to: f64, n: usize) -> Vec<f64> {
        (0..n)
            .map(|i| from + (to - from) * i as f64 / (n - 1) as f64)
            .collect()
    }

    #[test]
    fn a_conical_wheelset_has_its_cone_angle_at_every_amplitude() {
        let y = grid(-0.01, 0.01, 201);
        for gamma in [0.025, 0.15] {
            let dr: Vec<f64> = y.iter().map(|v| 2.0 * gamma * v).collect();
            let d = DeltaR::new(&y, &dr).unwrap();
            for amp in [1e-4, 3e-3, 0.0099] {
                let c = d.conicity(amp).unwrap();
                assert!((c - gamma).abs() < 1e-6 * gamma, "{gamma} {amp}: {c}");
            }
        }
    }

    #[test]
    fn an_offset_and_asymmetric_cone_follows_its_closed_form() {
        // Δr = 2γ1 (y − c) for y < c, 2γ2 (y − c) above: the half-periods add,
        // λ = π√(e r0) (1/√(2γ1) + 1/√(2γ2)), so tan γe = 2π² / λ'² = 4 / (1/√γ1 + 1/√γ2)².
        let (g1, g2, c) = (0.05, 0.2, 0.7e-3);
        let y = grid(-0.012, 0.012, 2401);
        let dr: Vec<f64> = y
            .iter()
            .map(|v| 2.0 * if *v < c { g1 } else { g2 } * (v - c))
            .collect();
        let d = DeltaR::new(&y, &dr).unwrap();
        assert!((d.centre() - c).abs() < 1e-12);
        let expect = 4.0 / (1.0 / g1.sqrt() + 1.0 / g2.sqrt()).powi(2);
        for amp in [5e-4, 2e-3, 7e-3] {
            let got = d.conicity(amp).unwrap();
            assert!(
                (got - expect).abs() < 1e-5 * expect,
                "{amp}: {got} vs {expect}"
            );
        }
    }

    /// One EN 15302 reference case: Δr (m) on y (m), and (ŷ, tan γe, upper, lower, upper
    /// wider, lower wider).
    struct Case {
        name: String,
        y: Vec<f64>,
        dr: Vec<f64>,
        refs: Vec<[f64; 6]>,
    }

    fn en15302_cases() -> Vec<Case> {
        let mut cases: Vec<Case> = Vec::new();
        for line in include_str!("testdata/en15302.txt").lines() {
            let line = line.split('#').next().unwrap_or("");
            let mut f = line.split_whitespace();
            let num = |s: &str| s.parse::<f64>().unwrap();
            match f.next() {
                Some("case") => {
                    let name = f.next().unwrap().to_owned();
                    let (a, b, h) = (
                        num(f.next().unwrap()),
                        num(f.next().unwrap()),
                        num(f.next().unwrap()),
                    );
                    let n = ((b - a) / h).round() as usize + 1;
                    let y = (0..n).map(|i| (a + h * i as f64) * 1e-3).collect();
                    cases.push(Case {
                        name,
                        y,
                        dr: Vec::new(),
                        refs: Vec::new(),
                    });
                }
                Some("dr") => {
                    let c = cases.last_mut().unwrap();
                    c.dr.extend(f.map(|v| num(v) * 1e-3));
                }
                Some("ref") => {
                    let v: Vec<f64> = f.map(num).collect();
                    cases
                        .last_mut()
                        .unwrap()
                        .refs
                        .push([v[0], v[1], v[2], v[3], v[4], v[5]]);
                }
                _ => {}
            }
        }
        cases
    }

    #[test]
    fn en15302_reference_cases_lie_within_their_tolerances() {
        let cases = en15302_cases();
        assert_eq!(cases.len(), 9);
        let mut checked = 0;
        for c in &cases {
            assert_eq!(c.y.len(), c.dr.len(), "{}", c.name);
            let d = DeltaR::new(&c.y, &c.dr).unwrap();
            for r in &c.refs {
                let Ok(got) = d.conicity(r[0] * 1e-3) else {
                    continue; // beyond the tabulated Δr
                };
                // Annex F's band, and (tighter) within 0.01 of the reference value itself.
                let (name, amp) = (&c.name, r[0]);
                assert!(
                    got >= r[3] && got <= r[2],
                    "{name} ŷ = {amp} mm: {got} not in [{}, {}]",
                    r[3],
                    r[2]
                );
                assert!(
                    (got - r[1]).abs() < 0.01,
                    "{name} ŷ = {amp} mm: {got} vs {}",
                    r[1]
                );
                checked += 1;
            }
        }
        assert!(checked > 400, "{checked}");
    }

    #[test]
    fn a_dead_zone_gives_zero_and_too_large_amplitudes_are_refused() {
        let y = grid(-0.005, 0.005, 101);
        let dr: Vec<f64> = y
            .iter()
            .map(|v| 0.2 * v.signum() * (v.abs() - 1e-3).max(0.0))
            .collect();
        let d = DeltaR::new(&y, &dr).unwrap();
        assert_eq!(d.conicity(0.8e-3).unwrap(), 0.0);
        assert!(d.conicity(3e-3).unwrap() > 0.0);
        assert!(matches!(
            d.conicity(6e-3),
            Err(ConicityError::Beyond { .. })
        ));
        let flat = vec![0.0; y.len()];
        assert!(DeltaR::new(&y, &flat).is_err());
    }
}
