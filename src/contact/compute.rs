//! A contact table computed from wheel and rail profiles: the rigid contact geometry on a grid
//! of wheelset displacements ([`super::geometry`]), then at each row the Hertz ellipse and the
//! static penetration under the static normal force N0 ([`super::hertz`]) and Kalker's
//! coefficients ([`super::kalker`]).
//!
//! Hertz's curvatures at the left wheel's contact: along the rolling direction the wheel's
//! cos δ / r (the principal curvature of a body of revolution across its meridian, δ the contact
//! angle relative to the axle; [`RollingCurvature::Radius`] takes 1/r instead, as RSGEO does)
//! and 0 for the straight rail; across it the lateral curvatures of the two profiles (convex
//! positive). The two differ on the flange only (cos 70° = 0.34). Where
//! the profiles are close to conformal (the sum of the lateral curvatures below a twentieth of
//! the longitudinal one), the sum is held at that floor, so that b ≤ about 7 a; the number of
//! such rows is reported.

use crate::contact::Portable;
use std::sync::OnceLock;

use super::geometry::{Geometry, GeometryRow};
use super::hertz::hertz;
use super::kalker::kalker;
use super::profile::{Profile, ProfileError};
use super::table::{ContactTable, TableError, TableRow};
use super::{s1002, uic60};

/// Mass of the Cooperrider car body (kg).
pub const CAR_BODY_MASS: f64 = 44_388.0;
/// Mass of one bogie frame of the Cooperrider car (kg).
pub const BOGIE_FRAME_MASS: f64 = 2_918.9;
/// Mass of one wheelset of the Cooperrider car (kg).
pub const WHEELSET_MASS: f64 = 1_022.0;
/// Gravity (m/s²).
pub const GRAVITY: f64 = 9.81;

/// The static normal force on one wheel of the Cooperrider car: its total weight / 8 (car body,
/// 2 bogie frames, 4 wheelsets) = 66 602.3 N.
pub fn cooperrider_wheel_load() -> f64 {
    (CAR_BODY_MASS + 2.0 * BOGIE_FRAME_MASS + 4.0 * WHEELSET_MASS) * GRAVITY / 8.0
}

/// The lateral relative curvature is held at least this fraction of the longitudinal one.
const CONFORMAL_FLOOR: f64 = 0.05;

/// Why a contact table cannot be computed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ContactError {
    /// A setting is out of range.
    #[error("contact settings: {0}")]
    Settings(String),
    /// A profile could not be read.
    #[error("{role} profile: {source}")]
    Profile {
        /// "wheel" or "rail".
        role: &'static str,
        /// The cause.
        #[source]
        source: ProfileError,
    },
    /// The rail cannot be placed on the track.
    #[error("rail: {0}")]
    Rail(String),
    /// No rigid contact of both wheels was found.
    #[error("no rigid contact of both wheels found at y = {y} m (the wheelset would roll by more than 0.2 rad)")]
    NoContact {
        /// The wheelset displacement (m).
        y: f64,
    },
    /// The table's rows were refused.
    #[error(transparent)]
    Table(#[from] TableError),
}

/// The wheel's curvature along the rolling direction used for the Hertz ellipse.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum RollingCurvature {
    /// cos δ / r: the principal curvature of the wheel's surface of revolution (exact).
    #[default]
    Meridian,
    /// 1/r: the rolling circle's curvature (the usual simplification; RSGEO's tables use it).
    Radius,
}

/// What to compute: profiles, track and wheelset layout, loads, material and the grid of
/// displacements. All lengths in m, angles in rad, forces in N, moduli in Pa.
#[derive(Clone, Debug, PartialEq)]
pub struct ContactSettings {
    /// Wheel profile (u from the nominal rolling circle, z the radius offset; see [`Profile`]).
    pub wheel: Profile,
    /// Rail profile (u from the rail's centre line, z the height; see [`Profile`]).
    pub rail: Profile,
    /// Rail inclination toward the track centre (rad): atan(1/40) for 1:40.
    pub inclination: f64,
    /// Track gauge, between the rails' gauge points (m).
    pub gauge: f64,
    /// Depth of the gauge points below the top of the rails (m).
    pub gauge_depth: f64,
    /// Distance between the wheels' flange backs (m).
    pub flange_back: f64,
    /// Distance of the nominal rolling circle from the flange back (m).
    pub rolling_circle: f64,
    /// Wheel radius at the nominal rolling circle (m).
    pub r0: f64,
    /// Static normal force on each wheel (N).
    pub n0: f64,
    /// Young's modulus of wheel and rail (Pa).
    pub young: f64,
    /// Poisson ratio of wheel and rail (1).
    pub poisson: f64,
    /// The wheel's curvature along the rolling direction for Hertz.
    pub rolling_curvature: RollingCurvature,
    /// First wheelset displacement of the table (m).
    pub y_min: f64,
    /// Last wheelset displacement of the table (m).
    pub y_max: f64,
    /// Step between displacements (m).
    pub y_step: f64,
}

impl Default for ContactSettings {
    /// S1002 on UIC60 inclined 1:40, standard gauge 1435 mm (14 mm below the top), flange backs
    /// 1360 mm apart, r0 = 0.425 m, N0 = the Cooperrider car's weight / 8, steel (E = 2.1e11 Pa,
    /// ν = 0.27, the value behind the reference study's shear modulus), y ∈ [−17, 17] mm in
    /// steps of 0.01 mm (3401 rows).
    fn default() -> Self {
        ContactSettings {
            wheel: s1002::s1002(),
            rail: uic60::uic60(),
            inclination: (1.0f64 / 40.0).p_atan(),
            gauge: 1.435,
            gauge_depth: 0.014,
            flange_back: 1.360,
            rolling_circle: s1002::ROLLING_CIRCLE_FROM_FLANGE_BACK,
            r0: 0.425,
            n0: cooperrider_wheel_load(),
            young: 2.1e11,
            poisson: 0.27,
            rolling_curvature: RollingCurvature::Meridian,
            y_min: -0.017,
            y_max: 0.017,
            y_step: 1e-5,
        }
    }
}

impl ContactSettings {
    /// The displacements of the table, ascending: y_min + i·y_step up to y_max.
    pub fn displacements(&self) -> Result<Vec<f64>, ContactError> {
        let bad = |m: &str| Err(ContactError::Settings(m.to_owned()));
        let span = self.y_max - self.y_min;
        if !(self.y_step > 0.0 && span > 0.0 && span.is_finite()) {
            return bad("the displacements need y_min < y_max and a positive step");
        }
        let n = (span / self.y_step).round();
        if (n * self.y_step - span).abs() > 1e-6 * self.y_step || n + 1.0 < 4.0 || n > 1e6 {
            return bad("(y_max − y_min) / y_step must be a whole number from 3 to 1e6");
        }
        Ok((0..=n as usize)
            .map(|i| self.y_min + self.y_step * i as f64)
            .collect())
    }

    fn check(&self) -> Result<(), ContactError> {
        let bad = |m: String| Err(ContactError::Settings(m));
        for (name, v) in [
            ("gauge", self.gauge),
            ("gauge_depth", self.gauge_depth),
            ("flange_back", self.flange_back),
            ("rolling_circle", self.rolling_circle),
            ("r0", self.r0),
            ("n0", self.n0),
            ("young", self.young),
        ] {
            if !(v > 0.0 && v.is_finite()) {
                return bad(format!("{name} = {v} must be a positive number"));
            }
        }
        if !(0.0..=0.2).contains(&self.inclination) {
            return bad(format!(
                "inclination = {} rad must lie in [0, 0.2] (1:5 or flatter)",
                self.inclination
            ));
        }
        if !(0.0..0.5).contains(&self.poisson) {
            return bad(format!("poisson = {} must lie in [0, 0.5)", self.poisson));
        }
        if self.flange_back >= self.gauge {
            return bad("the flange backs must lie inside the gauge".into());
        }
        if !(self.y_min.is_finite() && self.y_max.is_finite()) {
            return bad("y_min and y_max must be finite".into());
        }
        Ok(())
    }
}

/// A computed contact table with the geometry behind it.
#[derive(Clone, Debug, PartialEq)]
pub struct ContactSolution {
    /// The table (left wheel).
    pub table: ContactTable,
    /// The rigid contact of both wheels at each row.
    pub geometry: Vec<GeometryRow>,
    /// Rows where the profiles were close to conformal and the lateral curvature sum was held
    /// at its floor.
    pub conformal_rows: usize,
}

impl ContactSolution {
    /// Rolling radius difference Δr = r_L − r_R at each displacement, as (y, Δr) (m).
    pub fn delta_r(&self) -> Vec<(f64, f64)> {
        self.geometry
            .iter()
            .map(|g| (g.y, g.left.r - g.right.r))
            .collect()
    }

    /// The smallest displacement y ≥ 0 at which the left wheel touches with its flange
    /// (contact angle of at least 0.5 rad), if any (m).
    pub fn flange_contact(&self) -> Option<f64> {
        self.geometry
            .iter()
            .find(|g| g.y >= 0.0 && g.left.delta >= 0.5)
            .map(|g| g.y)
    }
}

/// The contact table of `settings`, with its geometry.
pub fn compute(settings: &ContactSettings) -> Result<ContactSolution, ContactError> {
    settings.check()?;
    let ys = settings.displacements()?;
    let geometry = Geometry::new(&settings.wheel, &settings.rail, settings)?;
    let rows = geometry.sweep(&ys)?;
    let mut conformal_rows = 0;
    let table_rows = rows
        .iter()
        .map(|g| {
            let c = &g.left;
            let ax = 0.5 / c.r
                * match settings.rolling_curvature {
                    RollingCurvature::Meridian => c.delta.p_cos(),
                    RollingCurvature::Radius => 1.0,
                };
            let mut by = 0.5 * (c.wheel_curvature + c.rail_curvature);
            if by < CONFORMAL_FLOOR * ax {
                by = CONFORMAL_FLOOR * ax;
                conformal_rows += 1;
            }
            let h = hertz(settings.n0, ax, by, settings.young, settings.poisson);
            let k = kalker(h.a / h.b, settings.poisson);
            TableRow {
                y: g.y,
                n0: settings.n0,
                delta: c.delta,
                a: h.a,
                b: h.b,
                aw: c.aw,
                r: c.r,
                c11: k.c11,
                c22: k.c22,
                c23: k.c23,
                zc: c.zc,
                q0: h.q0,
            }
        })
        .collect();
    Ok(ContactSolution {
        table: ContactTable::from_rows(table_rows)?,
        geometry: rows,
        conformal_rows,
    })
}

/// The contact table of `settings` (see [`compute`]).
pub fn compute_table(settings: &ContactSettings) -> Result<ContactTable, ContactError> {
    compute(settings).map(|s| s.table)
}

/// The built-in table: S1002 on UIC60 at 1:40, standard gauge ([`ContactSettings::default`]),
/// computed once per process.
pub fn default_table() -> Result<ContactTable, ContactError> {
    static TABLE: OnceLock<Result<ContactTable, ContactError>> = OnceLock::new();
    TABLE
        .get_or_init(|| compute_table(&ContactSettings::default()))
        .clone()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::conicity::DeltaR;

    #[test]
    fn symmetric_profiles_give_a_symmetric_table() {
        let s = compute(&ContactSettings::default()).unwrap();
        let g = &s.geometry;
        assert_eq!(g.len(), 3401);
        for (a, b) in g.iter().zip(g.iter().rev()) {
            assert!((a.y + b.y).abs() < 1e-12);
            assert!((a.roll + b.roll).abs() < 1e-12, "roll at {}", a.y);
            for (x, y) in [
                (a.left.r, b.right.r),
                (a.left.aw, b.right.aw),
                (a.left.delta, b.right.delta),
                (a.left.zc, b.right.zc),
            ] {
                assert!((x - y).abs() < 1e-10, "at y = {}: {x} vs {y}", a.y);
            }
        }
    }

    #[test]
    fn s1002_on_uic60_at_1_to_40_has_a_plausible_flange_contact_and_conicity() {
        let s = compute(&ContactSettings::default()).unwrap();
        let flange = s.flange_contact().unwrap();
        assert!(
            (0.006..=0.010).contains(&flange),
            "flange contact at {flange} m"
        );
        let (y, dr): (Vec<f64>, Vec<f64>) = s.delta_r().into_iter().unzip();
        let lambda = DeltaR::new(&y, &dr).unwrap().conicity(3e-3).unwrap();
        assert!((0.1..=0.25).contains(&lambda), "λ_eq(3 mm) = {lambda}");
        // Tread contact at the centre, r close to r0, static penetration of a tenth of a mm.
        let t = s.table.rows();
        let mid = &t[1700];
        assert!(mid.y.abs() < 1e-12 && (mid.r - 0.425).abs() < 2e-4 && mid.delta < 0.05);
        assert!(t
            .iter()
            .all(|r| r.q0 > 3e-5 && r.q0 < 2e-4 && r.n0 == s.table.rows()[0].n0));
        assert_eq!(s.conformal_rows, 0);
    }

    #[test]
    fn the_default_table_is_the_default_settings_table() {
        let a = default_table().unwrap();
        assert_eq!(a, compute_table(&ContactSettings::default()).unwrap());
        assert_eq!(a.range(), (-0.017, 0.017));
        assert!((a.rows()[0].n0 - 66_602.297).abs() < 1e-3);
    }

    #[test]
    fn sampled_profiles_read_as_csv_give_nearly_the_built_in_table() {
        let mm = |p: &Profile, n: usize, shift: f64| -> String {
            p.sample(n)
                .iter()
                .map(|(u, z)| format!("{},{}\n", (u + shift) * 1e3, z * 1e3))
                .collect()
        };
        let d = ContactSettings::default();
        let settings = ContactSettings {
            wheel: Profile::wheel_from_csv(&mm(&d.wheel, 1228, 0.07), 0.07).unwrap(),
            rail: Profile::rail_from_csv(&mm(&d.rail, 731, 0.0)).unwrap(),
            y_step: 1e-4,
            ..d.clone()
        };
        let built_in = compute(&ContactSettings { y_step: 1e-4, ..d }).unwrap();
        let sampled = compute(&settings).unwrap();
        let fb = |s: &ContactSolution| s.flange_contact().unwrap();
        assert!((fb(&built_in) - fb(&sampled)).abs() < 2e-4);
        for (a, b) in built_in.geometry.iter().zip(&sampled.geometry) {
            // The same contact (away from the jumps of the contact point and from the nearly
            // conformal flange root), to the splines' accuracy: r within 2 µm on the tread,
            // 0.1 mm on the flange (where r changes by 2.7 mm per mm across the profile).
            let conformity = a.left.wheel_curvature + a.left.rail_curvature;
            if (a.left.s - b.left.s).abs() < 1e-4 && (a.left.delta < 0.2 || conformity > 30.0) {
                assert!((a.left.r - b.left.r).abs() < 1e-4, "at {}", a.y);
                assert!((a.left.delta - b.left.delta).abs() < 5e-3, "at {}", a.y);
                if a.left.delta < 0.2 {
                    assert!((a.left.r - b.left.r).abs() < 2e-6, "at {}", a.y);
                }
            }
        }
    }

    #[test]
    fn settings_out_of_range_are_refused() {
        let d = ContactSettings::default();
        for bad in [
            ContactSettings {
                y_step: 3e-5 * 0.7,
                ..d.clone()
            },
            ContactSettings {
                gauge: 1.3,
                ..d.clone()
            },
            ContactSettings {
                poisson: 0.5,
                ..d.clone()
            },
            ContactSettings {
                n0: -1.0,
                ..d.clone()
            },
            ContactSettings {
                inclination: 0.5,
                ..d.clone()
            },
            ContactSettings {
                gauge_depth: 0.05,
                ..d.clone()
            },
        ] {
            assert!(compute(&bad).is_err(), "{bad:?}");
        }
    }
}
