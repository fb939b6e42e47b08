//! Wheel and rail profiles: a cross-section curve z(u) made of pieces (polynomials and circular
//! arcs), in metres.
//!
//! A profile is the same kind of curve for both roles; what u and z mean depends on the role:
//!
//! - **wheel**: u is the lateral position from the nominal rolling circle, positive toward the
//!   field side (away from the flange), so the flange lies at negative u; z is the radius offset,
//!   positive where the radius is larger (the flange), 0 on the nominal rolling circle. The wheel's
//!   radius at u is r0 + z(u).
//! - **rail**: u is the lateral position from the rail's centre line, positive toward the field
//!   side, so the gauge corner lies at negative u; z is the height, positive up, in the rail's own
//!   (uninclined) frame, with any datum (the geometry finds the top of the rail).
//!
//! Measured or worn profiles come from CSV text ([`Profile::wheel_from_csv`],
//! [`Profile::rail_from_csv`]) and are interpolated by a natural cubic spline.

/// The shape of one piece of a profile.
#[derive(Clone, Debug, PartialEq)]
enum Shape {
    /// z = Σₖ coef\[k\]·(u − origin)ᵏ.
    Poly { origin: f64, coef: Vec<f64> },
    /// A circular arc of centre (cu, cz) and radius `radius`: its upper half (z ≥ cz) or its
    /// lower half.
    Arc {
        cu: f64,
        cz: f64,
        radius: f64,
        upper: bool,
    },
}

/// One piece of a profile, valid on [u0, u1] (m).
#[derive(Clone, Debug, PartialEq)]
struct Piece {
    u0: f64,
    u1: f64,
    shape: Shape,
}

/// The value of a profile and its first two derivatives at one point.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ProfilePoint {
    /// z (m).
    pub z: f64,
    /// dz/du (1).
    pub dz: f64,
    /// d²z/du² (1/m).
    pub d2z: f64,
}

/// A profile: z(u) on [u_min, u_max], piecewise polynomials and circular arcs (m).
#[derive(Clone, Debug, PartialEq)]
pub struct Profile {
    pieces: Vec<Piece>,
}

/// Why a profile is refused. Messages name a line and what was expected there, never the text
/// found (the text may come from any file).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ProfileError {
    /// A line is not two numbers.
    #[error(
        "line {line}: expected two numbers (y, z in mm) separated by a comma, semicolon or blanks"
    )]
    Syntax {
        /// Line number (from 1).
        line: usize,
    },
    /// A number is infinite or NaN.
    #[error("line {line}: expected finite numbers (y, z in mm)")]
    NotFinite {
        /// Line number (from 1).
        line: usize,
    },
    /// y does not keep strictly increasing (or decreasing) along the file.
    #[error("line {line}: y must increase strictly along the file (or decrease strictly along all of it)")]
    NotMonotone {
        /// Line number (from 1).
        line: usize,
    },
    /// Too few points for a spline.
    #[error("a profile needs at least 4 points (y, z in mm), found {found}")]
    TooFewPoints {
        /// Points found.
        found: usize,
    },
    /// The wheel's nominal rolling circle lies outside the profile.
    #[error("the wheel profile must cover the nominal rolling circle at y = {at_mm} mm from the flange back (it covers {from_mm} to {to_mm} mm)")]
    NoRollingCircle {
        /// The rolling circle's position from the flange back (mm).
        at_mm: f64,
        /// First y of the profile (mm).
        from_mm: f64,
        /// Last y of the profile (mm).
        to_mm: f64,
    },
    /// A profile built in code is inconsistent.
    #[error("{0}")]
    Invalid(String),
}

impl Shape {
    fn eval(&self, u: f64) -> ProfilePoint {
        match self {
            Shape::Poly { origin, coef } => {
                let t = u - origin;
                let (mut z, mut dz, mut d2z) = (0.0, 0.0, 0.0);
                for &c in coef.iter().rev() {
                    d2z = d2z * t + dz * 2.0;
                    dz = dz * t + z;
                    z = z * t + c;
                }
                ProfilePoint { z, dz, d2z }
            }
            Shape::Arc {
                cu,
                cz,
                radius,
                upper,
            } => {
                let x = u - cu;
                let q = (radius * radius - x * x).max(0.0).sqrt();
                let s = if *upper { 1.0 } else { -1.0 };
                ProfilePoint {
                    z: cz + s * q,
                    dz: -s * x / q,
                    d2z: -s * radius * radius / (q * q * q),
                }
            }
        }
    }
}

impl Profile {
    /// A profile from pieces given in order of u; each piece as (u0, u1, shape). Checks that the
    /// pieces are contiguous and that arcs stay within their circle.
    fn from_pieces(pieces: Vec<Piece>) -> Result<Profile, ProfileError> {
        if pieces.is_empty() {
            return Err(ProfileError::Invalid(
                "a profile needs at least one piece".into(),
            ));
        }
        for (i, p) in pieces.iter().enumerate() {
            if p.u0.is_nan() || p.u1.is_nan() || p.u0 >= p.u1 {
                return Err(ProfileError::Invalid(format!("piece {i}: empty range")));
            }
            if i > 0 && (p.u0 - pieces[i - 1].u1).abs() > 1e-12 {
                return Err(ProfileError::Invalid(format!(
                    "piece {i} does not start where piece {} ends",
                    i - 1
                )));
            }
            if let Shape::Arc { cu, radius, .. } = p.shape {
                if (p.u0 - cu).abs() > radius * (1.0 + 1e-12)
                    || (p.u1 - cu).abs() > radius * (1.0 + 1e-12)
                {
                    return Err(ProfileError::Invalid(format!(
                        "piece {i}: the arc leaves its circle"
                    )));
                }
            }
        }
        Ok(Profile { pieces })
    }

    /// A polynomial piece on [u0, u1]: z = Σₖ coef\[k\]·(u − origin)ᵏ (m).
    pub(crate) fn poly(u0: f64, u1: f64, origin: f64, coef: Vec<f64>) -> (f64, f64, ShapeSpec) {
        (u0, u1, ShapeSpec(Shape::Poly { origin, coef }))
    }

    /// An arc piece on [u0, u1] of the circle of centre (cu, cz) and radius `radius` (m).
    pub(crate) fn arc(
        u0: f64,
        u1: f64,
        (cu, cz): (f64, f64),
        radius: f64,
        upper: bool,
    ) -> (f64, f64, ShapeSpec) {
        (
            u0,
            u1,
            ShapeSpec(Shape::Arc {
                cu,
                cz,
                radius,
                upper,
            }),
        )
    }

    /// A profile from pieces made by [`Profile::poly`] and [`Profile::arc`], in order of u.
    pub(crate) fn from_specs(specs: Vec<(f64, f64, ShapeSpec)>) -> Result<Profile, ProfileError> {
        Profile::from_pieces(
            specs
                .into_iter()
                .map(|(u0, u1, s)| Piece { u0, u1, shape: s.0 })
                .collect(),
        )
    }

    /// A rail whose head is one circular arc of radius `radius` (m), top at u = 0, z = 0, over
    /// |u| ≤ `half_width` (< radius). A "knife-edge" rail when the radius is small.
    pub fn crown(radius: f64, half_width: f64) -> Result<Profile, ProfileError> {
        if !(radius > 0.0 && half_width > 0.0 && half_width < radius) {
            return Err(ProfileError::Invalid(
                "a crown needs 0 < half width < radius".into(),
            ));
        }
        Profile::from_specs(vec![Profile::arc(
            -half_width,
            half_width,
            (0.0, -radius),
            radius,
            true,
        )])
    }

    /// A natural cubic spline through the points (u, z) (m), u strictly increasing.
    pub fn spline(u: &[f64], z: &[f64]) -> Result<Profile, ProfileError> {
        let n = u.len();
        if n < 4 || z.len() != n {
            return Err(ProfileError::TooFewPoints {
                found: n.min(z.len()),
            });
        }
        if (1..n).any(|i| u[i].is_nan() || u[i] <= u[i - 1]) {
            return Err(ProfileError::Invalid(
                "spline points must be finite, u strictly increasing".into(),
            ));
        }
        // Second derivatives m[i] of the natural spline (m[0] = m[n-1] = 0): tridiagonal system
        // h[i-1] m[i-1] + 2 (h[i-1] + h[i]) m[i] + h[i] m[i+1] = 6 (slope[i] - slope[i-1]).
        let h: Vec<f64> = (0..n - 1).map(|i| u[i + 1] - u[i]).collect();
        let slope: Vec<f64> = (0..n - 1).map(|i| (z[i + 1] - z[i]) / h[i]).collect();
        let mut m = vec![0.0; n];
        let mut diag = vec![0.0; n];
        let mut rhs = vec![0.0; n];
        for i in 1..n - 1 {
            diag[i] = 2.0 * (h[i - 1] + h[i]);
            rhs[i] = 6.0 * (slope[i] - slope[i - 1]);
        }
        // Thomas algorithm on rows 1..n-2.
        for i in 2..n - 1 {
            let w = h[i - 1] / diag[i - 1];
            diag[i] -= w * h[i - 1];
            rhs[i] -= w * rhs[i - 1];
        }
        for i in (1..n - 1).rev() {
            m[i] = (rhs[i] - h[i] * m[i + 1]) / diag[i];
        }
        let pieces = (0..n - 1)
            .map(|i| {
                let c = vec![
                    z[i],
                    slope[i] - h[i] * (2.0 * m[i] + m[i + 1]) / 6.0,
                    m[i] / 2.0,
                    (m[i + 1] - m[i]) / (6.0 * h[i]),
                ];
                Piece {
                    u0: u[i],
                    u1: u[i + 1],
                    shape: Shape::Poly {
                        origin: u[i],
                        coef: c,
                    },
                }
            })
            .collect();
        Profile::from_pieces(pieces)
    }

    /// A wheel profile from CSV text: one point a line, `y, z` in mm (comma, semicolon or blanks
    /// between), y the lateral position from the flange back (the inner face of the wheel),
    /// positive toward the field side, z up (the flange high), any datum. Blank lines and lines
    /// starting with `#` are skipped; the first other line may be a header. The nominal rolling
    /// circle lies `rolling_circle` (m) from the flange back (70 mm for S1002); the profile is
    /// shifted so that z = 0 there.
    pub fn wheel_from_csv(text: &str, rolling_circle: f64) -> Result<Profile, ProfileError> {
        let (y, z) = parse_csv(text)?;
        let (from, to) = (y[0], y[y.len() - 1]);
        if !(rolling_circle >= from && rolling_circle <= to) {
            return Err(ProfileError::NoRollingCircle {
                at_mm: rolling_circle * 1e3,
                from_mm: from * 1e3,
                to_mm: to * 1e3,
            });
        }
        let u: Vec<f64> = y.iter().map(|v| v - rolling_circle).collect();
        let p = Profile::spline(&u, &z)?;
        let z0 = p.eval(0.0).z;
        let z: Vec<f64> = z.iter().map(|v| v - z0).collect();
        Profile::spline(&u, &z)
    }

    /// A rail profile from CSV text: one point a line, `y, z` in mm, y the lateral position from
    /// the rail's centre line, positive toward the field side (the gauge corner at negative y), z
    /// up in the rail's own (uninclined) frame, any datum. Same syntax as
    /// [`Profile::wheel_from_csv`].
    pub fn rail_from_csv(text: &str) -> Result<Profile, ProfileError> {
        let (y, z) = parse_csv(text)?;
        Profile::spline(&y, &z)
    }

    /// The range of u covered (m).
    pub fn domain(&self) -> (f64, f64) {
        (self.pieces[0].u0, self.pieces[self.pieces.len() - 1].u1)
    }

    /// z, dz/du and d²z/du² at u (m); u outside the domain is moved to its nearest end.
    pub fn eval(&self, u: f64) -> ProfilePoint {
        let (lo, hi) = self.domain();
        let u = u.clamp(lo, hi);
        let i = self
            .pieces
            .partition_point(|p| p.u1 < u)
            .min(self.pieces.len() - 1);
        self.pieces[i].shape.eval(u)
    }

    /// The profile sampled at `n` points evenly spread over its domain, as (u, z) in m.
    pub fn sample(&self, n: usize) -> Vec<(f64, f64)> {
        let (lo, hi) = self.domain();
        let n = n.max(2);
        (0..n)
            .map(|i| {
                let u = lo + (hi - lo) * i as f64 / (n - 1) as f64;
                (u, self.eval(u).z)
            })
            .collect()
    }
}

/// A piece's shape, opaque outside this module (built by [`Profile::poly`] and [`Profile::arc`]).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct ShapeSpec(Shape);

/// Parses `y, z` lines in mm into metres, ascending in y.
fn parse_csv(text: &str) -> Result<(Vec<f64>, Vec<f64>), ProfileError> {
    let mut y = Vec::new();
    let mut z = Vec::new();
    let mut lines = Vec::new();
    let mut first = true;
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let s = raw.trim();
        if s.is_empty() || s.starts_with('#') {
            continue;
        }
        let fields = super::table::fields(s);
        let nums: Option<Vec<f64>> = fields.iter().map(|f| f.parse::<f64>().ok()).collect();
        match nums {
            Some(v) if v.len() == 2 => {
                if !(v[0].is_finite() && v[1].is_finite()) {
                    return Err(ProfileError::NotFinite { line });
                }
                y.push(v[0] * 1e-3);
                z.push(v[1] * 1e-3);
                lines.push(line);
            }
            // A header: only as the first line that is not blank or a comment.
            None if first && fields.iter().any(|f| f.parse::<f64>().is_err()) => {}
            _ => return Err(ProfileError::Syntax { line }),
        }
        first = false;
    }
    if y.len() < 4 {
        return Err(ProfileError::TooFewPoints { found: y.len() });
    }
    let descending = y[1] < y[0];
    for k in 1..y.len() {
        let ok = if descending {
            y[k] < y[k - 1]
        } else {
            y[k] > y[k - 1]
        };
        if !ok {
            return Err(ProfileError::NotMonotone { line: lines[k] });
        }
    }
    if descending {
        y.reverse();
        z.reverse();
    }
    Ok((y, z))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_spline_through_a_cubic_with_natural_ends_reproduces_a_line_and_interpolates_points() {
        let u: Vec<f64> = (0..7).map(|i| i as f64 * 0.01).collect();
        let z: Vec<f64> = u.iter().map(|v| 0.002 - 0.05 * v).collect();
        let p = Profile::spline(&u, &z).unwrap();
        for x in [0.0, 0.003, 0.0271, 0.06] {
            let q = p.eval(x);
            assert!((q.z - (0.002 - 0.05 * x)).abs() < 1e-15, "{x}");
            assert!((q.dz + 0.05).abs() < 1e-12 && q.d2z.abs() < 1e-9);
        }
        let z: Vec<f64> = u.iter().map(|v| (30.0 * v).sin()).collect();
        let p = Profile::spline(&u, &z).unwrap();
        for (a, b) in u.iter().zip(&z) {
            assert!((p.eval(*a).z - b).abs() < 1e-14);
        }
    }

    #[test]
    fn arcs_give_the_circle_s_slope_and_curvature() {
        let p = Profile::crown(0.3, 0.01).unwrap();
        let q = p.eval(0.006);
        let z = (0.09f64 - 0.006 * 0.006).sqrt() - 0.3;
        assert!((q.z - z).abs() < 1e-15);
        assert!((q.dz + 0.006 / (z + 0.3)).abs() < 1e-14);
        let kappa = -q.d2z / (1.0 + q.dz * q.dz).powf(1.5);
        assert!((kappa - 1.0 / 0.3).abs() < 1e-9, "{kappa}");
    }

    #[test]
    fn csv_errors_name_the_line_and_never_quote_it() {
        let e = Profile::rail_from_csv("y,z\n0,0\n1,0\nsecret-token,3\n4,5\n").unwrap_err();
        assert_eq!(e, ProfileError::Syntax { line: 4 });
        assert!(!e.to_string().contains("secret"), "{e}");
        let e = Profile::rail_from_csv("0,0\n1,0\n1,3\n4,5\n").unwrap_err();
        assert_eq!(e, ProfileError::NotMonotone { line: 3 });
        let e = Profile::rail_from_csv("0,0\n1,0\n2,inf\n4,5\n").unwrap_err();
        assert_eq!(e, ProfileError::NotFinite { line: 3 });
        let e = Profile::rail_from_csv("# c\n0,0\n1 0\n").unwrap_err();
        assert_eq!(e, ProfileError::TooFewPoints { found: 2 });
        let e = Profile::rail_from_csv("0,0,1\n1,0\n2,0\n4,5\n").unwrap_err();
        assert_eq!(e, ProfileError::Syntax { line: 1 });
        let e = Profile::wheel_from_csv("0,0\n10,0\n20,0\n30,0\n", 0.07).unwrap_err();
        assert!(matches!(e, ProfileError::NoRollingCircle { .. }), "{e}");
    }

    #[test]
    fn csv_accepts_headers_comments_separators_and_descending_y() {
        let p = Profile::rail_from_csv("# worn\ny;z\n3 -1\n2\t-0.5\n1,0\n0 ; 0\n").unwrap();
        assert_eq!(p.domain(), (0.0, 3e-3));
        assert!((p.eval(3e-3).z + 1e-3).abs() < 1e-15);
        let w = Profile::wheel_from_csv("60,5\n70,4\n80,3\n90,2\n", 0.07).unwrap();
        assert!(w.eval(0.0).z.abs() < 1e-15 && (w.eval(-0.01).z - 1e-3).abs() < 1e-15);
    }
}
