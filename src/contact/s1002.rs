//! The S1002 wheel profile (EN 13715; UIC 510-2), as the piecewise definition by polynomials and
//! circular arcs that circulates in open code.
//!
//! Source of the numbers: the definition attributed to H. Netter (DLR Oberpfaffenhofen), as
//! published in several open teaching codes (e.g. the `s1002(S)` function of Lund University's
//! numerical-analysis exercises). In its coordinates S (mm) is the lateral position from the
//! nominal rolling circle, positive toward the field side, the flange at negative S (its back at
//! S = −70 mm, so the rolling circle lies 70 mm from the flange back), and F(S) (mm) is the radius
//! offset, 0 at S = 0:
//!
//! | section | S from | S to | F(S) |
//! |---|---|---|---|
//! | A | 32.15796 | 60 | AA − BA·S |
//! | B | −26 | 32.15796 | AB − BB·S + CB·S² − DB·S³ + EB·S⁴ − FB·S⁵ + GB·S⁶ − HB·S⁷ + IB·S⁸ |
//! | C | −35 | −26 | −AC − BC·S − CC·S² − DC·S³ − EC·S⁴ − FC·S⁵ − GC·S⁶ − HC·S⁷ |
//! | D | −38.426669071 | −35 | AD − √(BD² − (S + CD)²) (concave flange root, R13) |
//! | E | −39.764473993 | −38.426669071 | −AE − BE·S (flange flank, tan 70°) |
//! | F | −49.662510381 | −39.764473993 | AF + √(BF² − (S + CF)²) (R20) |
//! | G | −62.764705882 | −49.662510381 | AG + √(BG² − (S + CG)²) (flange tip, R12) |
//! | H | −70 | −62.764705882 | AH + √(BH² − (S + CH)²) (flange back, R20.5) |
//!
//! The published coefficients join to within 0.12 µm in value (at S = −35 mm, the C/D junction)
//! and 2e-5 in slope; they are used as published.
//!
//! The profile here stops at the G/H junction (S = −62.76 mm): section H turns vertical at the
//! flange back and can never touch the rail head.

use super::profile::Profile;

// Section A.
const AA: f64 = 1.364323640;
const BA: f64 = 0.066666667;
// Section B.
const AB: f64 = 0.0;
const BB: f64 = 3.358537058e-02;
const CB: f64 = 1.565681624e-03;
const DB: f64 = 2.810427944e-05;
const EB: f64 = 5.844240864e-08;
const FB: f64 = 1.562379023e-08;
const GB: f64 = 5.309217349e-15;
const HB: f64 = 5.957839843e-12;
const IB: f64 = 2.646656573e-13;
// Section C.
const AC: f64 = 4.320221063e+03;
const BC: f64 = 1.038384026e+03;
const CC: f64 = 1.065501873e+02;
const DC: f64 = 6.051367875;
const EC: f64 = 2.054332446e-01;
const FC: f64 = 4.169739389e-03;
const GC: f64 = 4.687195829e-05;
const HC: f64 = 2.252755540e-07;
// Section D.
const AD: f64 = 16.446;
const BD: f64 = 13.0;
const CD: f64 = 26.210665;
// Section E.
const AE: f64 = 93.576667419;
const BE: f64 = 2.747477419;
// Section F.
const AF: f64 = 8.834924130;
const BF: f64 = 20.0;
const CF: f64 = 58.558326413;
// Section G.
const AG: f64 = 16.0;
const BG: f64 = 12.0;
const CG: f64 = 55.0;

/// Section bounds (mm), from the flange tip side to the field side.
const S_GH: f64 = -62.764705882;
const S_FG: f64 = -49.662510381;
const S_EF: f64 = -39.764473993;
const S_DE: f64 = -38.426669071;
const S_CD: f64 = -35.0;
const S_BC: f64 = -26.0;
const S_AB: f64 = 32.15796;
const S_END: f64 = 60.0;

/// The lateral position of the nominal rolling circle from the flange back (m).
pub const ROLLING_CIRCLE_FROM_FLANGE_BACK: f64 = 0.070;

/// A polynomial given in mm (F_mm = Σ c·S_mmᵏ) as a piece in metres on [s0, s1] (mm).
fn poly_mm(s0: f64, s1: f64, c_mm: &[f64]) -> (f64, f64, super::profile::ShapeSpec) {
    // F_m(s) = F_mm(1000 s) / 1000 = Σ c_k 1000^(k−1) s^k.
    let coef = c_mm
        .iter()
        .enumerate()
        .map(|(k, c)| c * 1000f64.powi(k as i32 - 1))
        .collect();
    Profile::poly(s0 * 1e-3, s1 * 1e-3, 0.0, coef)
}

/// An arc given in mm: F = cz ± √(R² − (S − cu)²), on [s0, s1] (mm).
fn arc_mm(
    s0: f64,
    s1: f64,
    cu: f64,
    cz: f64,
    radius: f64,
    upper: bool,
) -> (f64, f64, super::profile::ShapeSpec) {
    Profile::arc(
        s0 * 1e-3,
        s1 * 1e-3,
        (cu * 1e-3, cz * 1e-3),
        radius * 1e-3,
        upper,
    )
}

/// The S1002 wheel profile: u (m) from the nominal rolling circle, positive toward the field
/// side; z (m) the radius offset (see [`Profile`] for the wheel's conventions).
pub fn s1002() -> Profile {
    let pieces = vec![
        arc_mm(S_GH, S_FG, -CG, AG, BG, true),
        arc_mm(S_FG, S_EF, -CF, AF, BF, true),
        poly_mm(S_EF, S_DE, &[-AE, -BE]),
        arc_mm(S_DE, S_CD, -CD, AD, BD, false),
        poly_mm(S_CD, S_BC, &[-AC, -BC, -CC, -DC, -EC, -FC, -GC, -HC]),
        poly_mm(S_BC, S_AB, &[AB, -BB, CB, -DB, EB, -FB, GB, -HB, IB]),
        poly_mm(S_AB, S_END, &[AA, -BA]),
    ];
    Profile::from_specs(pieces).expect("the S1002 sections are contiguous")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sections_join_continuously_with_continuous_slope() {
        let p = s1002();
        for s in [S_FG, S_EF, S_DE, S_CD, S_BC, S_AB] {
            let u = s * 1e-3;
            let (a, b) = (p.eval(u - 1e-12), p.eval(u + 1e-12));
            // The published coefficients join to 0.12 µm (at S = −35 mm) and slopes to 2e-5.
            assert!((a.z - b.z).abs() < 2e-7, "value jumps at S = {s}");
            assert!(
                (a.dz - b.dz).abs() < 2e-3,
                "slope jumps at S = {s}: {} {}",
                a.dz,
                b.dz
            );
        }
    }

    #[test]
    fn known_points_of_the_profile() {
        let p = s1002();
        // Rolling circle: radius offset 0; the flange tip 28 mm above it at S = −55 mm.
        assert_eq!(p.eval(0.0).z, 0.0);
        assert!((p.eval(-0.055).z - 0.028).abs() < 1e-12);
        // The flange flank is inclined at tan 70° (2.7475) over section E.
        assert!((p.eval(-0.039).dz + 2.747477419).abs() < 1e-9);
        // The tread slopes about 1:30 at the rolling circle.
        assert!((p.eval(0.0).dz + 0.03358537058).abs() < 1e-12);
        assert_eq!(p.domain(), (S_GH * 1e-3, 0.06));
    }
}
