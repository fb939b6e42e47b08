//! Wheel–rail contact geometry: the contact table a vehicle model reads (one row per wheelset
//! lateral displacement, the format of a table file, interpolation), and its computation from
//! wheel and rail profiles.
//!
//! - [`profile`]: profiles as curves (built-in [`s1002`] wheel and [`uic60`] rail, or CSV);
//! - [`geometry`]: the rigid contact of a wheelset on a track (roll, contact points, radii,
//!   contact angles);
//! - [`hertz`], [`kalker`]: the contact ellipse, penetration and creep coefficients;
//! - [`compute`](mod@compute): all of it as a [`ContactTable`] ([`compute_table`], [`default_table`]);
//! - [`conicity`]: equivalent conicity from Δr(y) (EN 15302);
//! - [`smooth`]: a short moving average in y that makes a rigid table fit for splines.
//!
//! Pure Rust, no FMI types.
#![forbid(unsafe_code)]

pub mod compute;
pub mod conicity;
pub mod geometry;
pub mod hertz;
pub mod kalker;
pub mod profile;
pub mod s1002;
pub mod smooth;
pub mod table;
pub mod uic60;

pub use compute::{
    compute, compute_table, cooperrider_wheel_load, default_table, ContactError, ContactSettings,
    ContactSolution, RollingCurvature,
};
pub use profile::{Profile, ProfileError};
pub use table::{ContactTable, TableError, TableRow};

/// The transcendental functions of the contact geometry, from the pure-Rust `libm`: the same
/// last bits on every platform, so that the win64 DLL computes the built-in table the Linux
/// library does (the C libraries' atan, pow and log differ in the last ulp, and the Vehicle's
/// outputs followed by 2e-11 instead of bit for bit).
pub(crate) trait Portable {
    fn p_atan(self) -> f64;
    fn p_cos(self) -> f64;
    fn p_sin(self) -> f64;
    fn p_asin(self) -> f64;
    fn p_ln(self) -> f64;
    fn p_cbrt(self) -> f64;
    fn p_exp_m1(self) -> f64;
    fn p_powf(self, e: f64) -> f64;
}

impl Portable for f64 {
    fn p_atan(self) -> f64 {
        libm::atan(self)
    }
    fn p_cos(self) -> f64 {
        libm::cos(self)
    }
    fn p_sin(self) -> f64 {
        libm::sin(self)
    }
    fn p_asin(self) -> f64 {
        libm::asin(self)
    }
    fn p_ln(self) -> f64 {
        libm::log(self)
    }
    fn p_cbrt(self) -> f64 {
        libm::cbrt(self)
    }
    fn p_exp_m1(self) -> f64 {
        libm::expm1(self)
    }
    fn p_powf(self, e: f64) -> f64 {
        libm::pow(self, e)
    }
}
