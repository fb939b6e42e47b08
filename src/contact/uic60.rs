//! The UIC60 (60E1, EN 13674-1) rail head: arcs R300, R80 and R13 on each side of the crown, then
//! the head's flanks at 1:20.
//!
//! Construction (as documented for GENSYS, "Creation of a rail profile from a drawing",
//! create_UIC60): the arcs are mutually tangent; R300 is centred on the rail's axis and ends at
//! the half-width X1 = 20.456/2 mm, R80 at X2 = 52.053/2 mm and R13 at the head's half-width
//! X3 = 72/2 mm, where the straight flank at 1:20 (lateral : vertical) begins.

use super::profile::{Profile, ShapeSpec};
use crate::contact::Portable;

const R1: f64 = 300.0;
const R2: f64 = 80.0;
const R3: f64 = 13.0;
const X1: f64 = 20.456 / 2.0;
const X2: f64 = 52.053 / 2.0;
const X3: f64 = 72.000 / 2.0;
/// Flank slope, lateral per vertical.
const FLANK: f64 = 1.0 / 20.0;
/// Depth below the top to which the flanks are kept (mm).
const FLANK_DEPTH: f64 = 25.0;

/// Centres of the arcs: (lateral, height) in mm, top of the rail at (0, 0), field side +.
fn centres() -> [(f64, f64); 3] {
    let c1 = (0.0, -R1);
    let f1 = (X1 / R1).p_asin();
    let c2 = (c1.0 + (R1 - R2) * f1.p_sin(), c1.1 + (R1 - R2) * f1.p_cos());
    let f2 = ((X2 - c2.0) / R2).p_asin();
    let c3 = (c2.0 + (R2 - R3) * f2.p_sin(), c2.1 + (R2 - R3) * f2.p_cos());
    [c1, c2, c3]
}

/// The UIC60 rail head: u (m) from the rail's centre line, positive toward the field side; z (m)
/// the height above the top of the rail (≤ 0), in the rail's own frame.
pub fn uic60() -> Profile {
    let [c1, c2, c3] = centres();
    let m = |v: f64| v * 1e-3;
    // Where the R13 arc ends (u = X3) and the flank begins.
    let z3 = c3.1 + (R3 * R3 - (X3 - c3.0).powi(2)).sqrt();
    let u_end = X3 + (FLANK_DEPTH + z3) * FLANK;
    let arc = |u0: f64, u1: f64, c: (f64, f64), r: f64| -> (f64, f64, ShapeSpec) {
        Profile::arc(m(u0), m(u1), (m(c.0), m(c.1)), m(r), true)
    };
    let mirror = |c: (f64, f64)| (-c.0, c.1);
    let pieces = vec![
        Profile::poly(m(-u_end), m(-X3), m(-X3), vec![m(z3), 1.0 / FLANK]),
        arc(-X3, -X2, mirror(c3), R3),
        arc(-X2, -X1, mirror(c2), R2),
        arc(-X1, X1, c1, R1),
        arc(X1, X2, c2, R2),
        arc(X2, X3, c3, R3),
        Profile::poly(m(X3), m(u_end), m(X3), vec![m(z3), -1.0 / FLANK]),
    ];
    Profile::from_specs(pieces).expect("the UIC60 arcs are contiguous")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arcs_are_tangent_and_the_head_is_72_mm_wide_at_the_flanks() {
        let p = uic60();
        for u in [X1, X2] {
            for s in [-1.0, 1.0] {
                let x = s * u * 1e-3;
                let (a, b) = (p.eval(x - 1e-12), p.eval(x + 1e-12));
                assert!(
                    (a.z - b.z).abs() < 1e-12 && (a.dz - b.dz).abs() < 1e-9,
                    "{x}"
                );
            }
        }
        // Top of the rail at the centre line, symmetric head.
        assert_eq!(p.eval(0.0).z, 0.0);
        assert!((p.eval(-0.02).z - p.eval(0.02).z).abs() < 1e-15);
        // The R13 arc meets the 1:20 flank at u = ±36 mm, 14.3 mm below the top, with almost the
        // same slope (the drawing's construction is tangent to within 0.1°).
        let q = p.eval(0.036 - 1e-12);
        assert!((q.z + 0.014304).abs() < 2e-6, "{}", q.z);
        assert!((q.dz.p_atan() + 20f64.p_atan()).abs() < 2e-3, "{}", q.dz);
        // 14 mm below the top the head is 71.96 mm wide (the gauge is measured there).
        let (mut lo, mut hi) = (0.030, 0.036);
        for _ in 0..100 {
            let mid = 0.5 * (lo + hi);
            if p.eval(mid).z > -0.014 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        assert!((lo - 0.03598).abs() < 2e-5, "{lo}");
    }
}
