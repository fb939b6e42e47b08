//! Time integration of the car: classical Runge–Kutta (RK4) with equal substeps, each no
//! longer than `dt` and than [`STABILITY_FACTOR`] / ρ, ρ a bound on the largest eigenvalue
//! modulus of the Jacobian at the running speed ([`RateBound`]).
//!
//! Why explicit RK4. The car is stiff through a few fast, well-damped or weakly damped modes,
//! measured as the largest |λ| of the Jacobian at the centred equilibrium with the RSGEO
//! table (`stability::eigenvalues`): 10 024 1/s at 10 m/s, 5 012 at 20, 2 506 at 40, then
//! 1 673 from 60 m/s up. The first is the spin perturbation β relaxed by longitudinal creep,
//! λ = −2 r² G a b C11/(v Iy) ≈ −1e5/v (real); the second the wheelsets' vertical and roll
//! modes on the Hertz contact, ±1 673 i rad/s (undamped: D4 = 0). Along hunting limit cycles
//! in flange contact (60, 80, 100 m/s) the largest |λ| reached 1.15× the centred value. The
//! bound of [`RateBound`] is 1.26× the centred value below 60 m/s and 1.03× above, so
//! h |λ| ≤ 1.8 × 1.15 / 1.03 = 2.0 in the worst state seen, inside RK4's stability region
//! (2.78 on the negative real axis, 2.83 on the imaginary one). An RK4 step costs four
//! right-hand sides (about 3 µs each) and no linear algebra: at 40 m/s, 18 substeps per 10 ms,
//! 66–118× faster than real time on one (shared) core. A linearly implicit (Rosenbrock) step could take steps of a
//! few ms, set by accuracy (the hunting frequency is 5 Hz), but needs the 66×66 Jacobian (132
//! right-hand sides by differences, or an analytic one) and an LU factorisation, refreshed as
//! the contact moves into and out of the flange; the explicit scheme is simpler and fast
//! enough. Halving the step moves the hunting amplitude by less than 0.2 % (the flange makes
//! the convergence order low: states 3.7e-5 m apart at 1 ms and 3.6e-6 m at 0.25 ms from a
//! 0.05 ms reference after 6 s of hunting).
#![forbid(unsafe_code)]

use super::equations::{rhs, Car, Derailment, State, Track, N_STATES};
use super::params::Params;
use crate::contact::table::ContactSpline;

/// h ρ of a substep (see the module documentation).
pub const STABILITY_FACTOR: f64 = 1.8;

/// Why a substep could not be taken.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum StepError {
    /// A wheelset left the contact table.
    Derailment(Derailment),
    /// The measured track ended under a wheelset at this position (m).
    OffTrack(f64),
}

/// A bound on the largest eigenvalue modulus (1/s) of the car's Jacobian at speed v:
/// ρ(v) = max(A/v, B), A/v for the modes relaxed by creep (rates ∝ 1/v), B for the
/// frequencies on the Hertz contact.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RateBound {
    /// Creep-relaxed rates times the speed (m/s²).
    pub creep: f64,
    /// Hertz frequencies (rad/s).
    pub hertz: f64,
}

impl RateBound {
    /// The bound for the car `p` on `table`: the largest over the table's rows y of the
    /// wheelset's fast rates with its left wheel at the row of y and its right wheel at the row
    /// of −y, normal forces N0: the relaxation of the spin perturbation by longitudinal creep,
    /// Σ r² G a b C11/(v Iy), of lateral motion and yaw, Σ G a b C22/(v m) and
    /// Σ aw² G a b C11/(v Iz), and the vertical and roll frequencies on the Hertz contact
    /// (stiffness 3 N0/(2 q0) per wheel), √(Σ k/m) and √(Σ k aw²/Ix).
    pub fn new(p: &Params, table: &ContactSpline) -> RateBound {
        let (lo, hi) = table.range();
        let limit = table.limit();
        let n = ((hi - lo) / 1e-5).ceil().max(2.0) as usize;
        let mut bound = RateBound {
            creep: 0.0,
            hertz: 0.0,
        };
        for i in 0..=n {
            let y = (-limit + 2.0 * limit * i as f64 / n as f64).clamp(-limit, limit);
            let (Some(l), Some(r)) = (table.left(y), table.right(y)) else {
                continue;
            };
            let f = |w: &crate::contact::table::TableRow, c: f64| p.g_mod * w.a * w.b * c;
            let spin = (l.r * l.r * f(&l, l.c11) + r.r * r.r * f(&r, r.c11)) / p.iy_w;
            let lateral = (f(&l, l.c22) + f(&r, r.c22)) / p.m_w;
            let yaw = (l.aw * l.aw * f(&l, l.c11) + r.aw * r.aw * f(&r, r.c11)) / p.iz_w;
            let k = |w: &crate::contact::table::TableRow| 1.5 * w.n0 / w.q0;
            let vertical = ((k(&l) + k(&r)) / p.m_w).sqrt();
            let roll = ((k(&l) * l.aw * l.aw + k(&r) * r.aw * r.aw) / p.ix_w).sqrt();
            bound.creep = bound.creep.max(spin).max(lateral).max(yaw);
            bound.hertz = bound.hertz.max(vertical).max(roll);
        }
        bound
    }

    /// ρ at speed `v` (m/s).
    pub fn at(&self, v: f64) -> f64 {
        (self.creep / v).max(self.hertz)
    }
}

/// One RK4 substep of length `h` from `t`, with the track of [`Track`] at each stage time
/// given by `track_at`.
pub fn rk4_substep(
    car: &Car,
    table: &ContactSpline,
    track_at: &impl Fn(f64) -> Result<Track, StepError>,
    t: f64,
    x: &mut State,
    h: f64,
) -> Result<(), StepError> {
    let f = |t: f64, x: &State, dx: &mut State| -> Result<(), StepError> {
        let track = track_at(t)?;
        rhs(car, table, &track, x, dx, None).map_err(StepError::Derailment)
    };
    let mut k1 = [0.0; N_STATES];
    let mut k2 = [0.0; N_STATES];
    let mut k3 = [0.0; N_STATES];
    let mut k4 = [0.0; N_STATES];
    let mut y = [0.0; N_STATES];
    f(t, x, &mut k1)?;
    for i in 0..N_STATES {
        y[i] = x[i] + 0.5 * h * k1[i];
    }
    f(t + 0.5 * h, &y, &mut k2)?;
    for i in 0..N_STATES {
        y[i] = x[i] + 0.5 * h * k2[i];
    }
    f(t + 0.5 * h, &y, &mut k3)?;
    for i in 0..N_STATES {
        y[i] = x[i] + h * k3[i];
    }
    f(t + h, &y, &mut k4)?;
    for i in 0..N_STATES {
        x[i] += h / 6.0 * (k1[i] + 2.0 * (k2[i] + k3[i]) + k4[i]);
    }
    Ok(())
}
