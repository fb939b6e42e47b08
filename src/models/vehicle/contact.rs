//! Wheel–rail forces of one wheelset (MODELS §5.5–5.6): the contact table read at the
//! wheelset's lateral displacement relative to the track, quasi-static Hertz normal force,
//! Kalker's linear creep forces saturated by Shen–Hedrick–Elkins, and their resultants in the
//! track frame.
//!
//! For wheel side σ (+1 left, −1 right) with the table row (N0, δ, a, b, aw, r, C11, C22, C23,
//! q0) of that wheel (left: the row at y, right: the row at −y), wheelset state y, z, φ, ψ,
//! β and rates, speed v, curvature κ = 1/R, cant φse, Ω0 = v/r_t (r_t the table's rolling
//! radius at y = 0) and b = +u2 (leading wheelset of a bogie) or −u2 (trailing):
//!
//! ```text
//! g(s) = (r − aw tan s) sin s + aw / cos s − aw − r s                 (s = σφ; ≈ −aw s²/2)
//! Δq   = −g(σφ) sin(δ + σφ) − (z + σφ aw) cos(δ + σφ)                 extra penetration
//! N    = N0 (1 + Δq/q0)^(3/2), 0 when the bracket is negative;  a, b scaled by (N/N0)^(1/3)
//! ψb   = ψ + b κ
//! ξx   = [v + ψb ẏ + r (ψb φ̇ − (Ω0 + β)) − σ aw ψ̇ + σ a v cos φse κ] / v
//! ξy   = [(−v ψb (1 + σ a cos φse κ) + φ ż + ẏ + r φ̇) cos δ + σ (−φ ẏ + ż + σ aw φ̇) sin δ] / v
//! ξs   = [−σ (Ω0 + β − ψb φ̇) sin δ + ψ̇ cos δ] / v
//! Fx   = −G a b C11 ξx,   Fy = −G a b (C22 ξy + √(ab) C23 ξs)                    (Kalker)
//! u    = |F| / (μN);  |F| → μN (u − u²/3 + u³/27) for u < 3, μN beyond         (SHE)
//! track frame:  X = Fx − Fy ψ cos δ,  Y = Fx ψ + Fy cos(δ + σφ) − σ N sin(δ + σφ),
//!               Z = σ Fy sin(δ + σφ) + N cos(δ + σφ)
//! torques:      roll  σ aw (Z − Y φ),   spin −r (X + Y ψ),   yaw −σ aw (X + Y ψ)
//!               roll_moment = 1: roll + r (Y cos φ + Z sin φ) (the force acts r below the axle)
//! ```
//!
//! A wheel whose normal force is at most 1 N exerts no force at all. The lateral position
//! and the vertical position used in the table and in Δq are relative to the track (minus the
//! track irregularity under the wheelset); the velocities in the creepages are absolute (the
//! rail does not move).
#![forbid(unsafe_code)]

use super::equations::Kin;
use crate::contact::table::{ContactSpline, TableRow};

/// Normal force (N) at or below which a wheel exerts no force (it has left the rail).
pub const MIN_NORMAL_FORCE: f64 = 1.0;

/// What the contact needs of the running conditions at one instant.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Running {
    /// Speed v (m/s).
    pub v: f64,
    /// Track curvature κ = 1/R (1/m); 0 on straight track.
    pub kappa: f64,
    /// Cant angle φse (rad).
    pub cant: f64,
}

/// The forces one wheel and the rail exert on each other.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Wheel {
    /// Lateral force of the rail on the wheel, creep plus normal, track frame (N).
    pub y: f64,
    /// Vertical force of the rail on the wheel, creep plus normal, track frame (N).
    pub z: f64,
    /// Normal force (N).
    pub n: f64,
}

/// Resultant of the wheel–rail forces on a wheelset.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Wheelset {
    /// Force on the wheelset, track frame (N): x, y, z.
    pub force: [f64; 3],
    /// Roll torque (N·m).
    pub roll: f64,
    /// Torque about the axle (N·m).
    pub spin: f64,
    /// Yaw torque (N·m).
    pub yaw: f64,
    /// Left (0) and right (1) wheels.
    pub wheels: [Wheel; 2],
}

/// Shen–Hedrick–Elkins: the factor by which Kalker's force of magnitude `f` (N) is scaled
/// under the normal force `n` (N) and friction coefficient `mu`.
#[inline]
pub fn she_factor(f: f64, mu: f64, n: f64) -> f64 {
    let limit = mu * n;
    let u = f / limit;
    if u < 3.0 {
        // μN (u − u²/3 + u³/27) / |F| = 1 − u/3 + u²/27 (continuous at |F| = 0).
        1.0 - u / 3.0 + u * u / 27.0
    } else {
        limit / f
    }
}

/// The constant inputs of [`wheelset_forces`].
#[derive(Clone, Copy, Debug)]
pub struct ContactConst {
    /// Half distance of the contact points in the creepages, a (m).
    pub a: f64,
    /// Shear modulus G (Pa).
    pub g_mod: f64,
    /// Friction coefficient μ (1).
    pub mu: f64,
    /// Rolling radius of the table at y = 0, r_t (m): Ω0 = v / r_t.
    pub r_t: f64,
    /// The roll moment includes that of the contact force about the rolling radius,
    /// r (Y cos φ + Z sin φ).
    pub lateral_roll: bool,
}

/// The wheel–rail forces of a wheelset with kinematics `k` and spin perturbation `beta`
/// (rad/s) at lateral and vertical positions `y_rel`, `z_rel` (m) relative to the track,
/// with `b` = ±u2 (m): `None` when `y_rel` or `−y_rel` lies beyond the table (derailment).
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn wheelset_forces(
    table: &ContactSpline,
    c: &ContactConst,
    run: &Running,
    k: &Kin,
    beta: f64,
    y_rel: f64,
    z_rel: f64,
    b: f64,
) -> Option<Wheelset> {
    let left = table.left(y_rel)?;
    let right = table.right(y_rel)?;
    let mut out = Wheelset::default();
    let roll = libm::sincos(k.ang[0]);
    for (i, (sigma, row)) in [(1.0, left), (-1.0, right)].into_iter().enumerate() {
        let w = wheel(c, run, k, beta, z_rel, b, sigma, roll, &row);
        let (x, y, z) = (w.0, w.1.y, w.1.z);
        let (phi, psi) = (k.ang[0], k.ang[2]);
        out.force[0] += x;
        out.force[1] += y;
        out.force[2] += z;
        out.roll += sigma * row.aw * (z - y * phi);
        if c.lateral_roll {
            // The whole contact force acts r below the axle, turned by the roll φ.
            out.roll += row.r * (y * roll.1 + z * roll.0);
        }
        out.spin -= row.r * (x + y * psi);
        out.yaw -= sigma * row.aw * (x + y * psi);
        out.wheels[i] = w.1;
    }
    Some(out)
}

/// One wheel (side `sigma`, table row `row`; `roll` = (sin φ, cos φ) of the wheelset): the
/// longitudinal force and the [`Wheel`].
#[allow(clippy::too_many_arguments)]
#[inline]
fn wheel(
    c: &ContactConst,
    run: &Running,
    k: &Kin,
    beta: f64,
    z_rel: f64,
    b: f64,
    sigma: f64,
    roll: (f64, f64),
    row: &TableRow,
) -> (f64, Wheel) {
    let [_, yd, zd] = k.dd;
    let [phi, _, psi] = k.ang;
    let [phid, _, psid] = k.rate;
    let (delta, aw, r) = (row.delta, row.aw, row.r);
    // Normal force from the extra penetration (s = σφ: sin s = σ sin φ, cos s = cos φ).
    let s = sigma * phi;
    let (sin_s, cos_s) = (sigma * roll.0, roll.1);
    let g = (r - aw * sin_s / cos_s) * sin_s + aw / cos_s - aw - r * s;
    let (sin_d, cos_d) = libm::sincos(delta);
    let (sin_t, cos_t) = (sin_d * cos_s + cos_d * sin_s, cos_d * cos_s - sin_d * sin_s);
    let dq = -g * sin_t - (z_rel + s * aw) * cos_t;
    let bracket = 1.0 + dq / row.q0;
    if bracket <= 0.0 {
        return (0.0, Wheel::default());
    }
    // N = N0 bracket^(3/2); the contact ellipse grows as (N/N0)^(1/3) = bracket^(1/2).
    let scale = bracket.sqrt();
    let n = row.n0 * bracket * scale;
    if n <= MIN_NORMAL_FORCE {
        return (0.0, Wheel::default());
    }
    let (ca, cb) = (row.a * scale, row.b * scale);
    // Creepages.
    let v = run.v;
    let omega = v / c.r_t + beta;
    let psi_b = psi + b * run.kappa;
    let cos_se = libm::cos(run.cant);
    let xi_x = (v + psi_b * yd + r * (psi_b * phid - omega) - sigma * aw * psid
        + sigma * c.a * v * cos_se * run.kappa)
        / v;
    let xi_y = ((-v * psi_b * (1.0 + sigma * c.a * cos_se * run.kappa) + phi * zd + yd + r * phid)
        * cos_d
        + sigma * (-phi * yd + zd + sigma * aw * phid) * sin_d)
        / v;
    let xi_s = (-sigma * (omega - psi_b * phid) * sin_d + psid * cos_d) / v;
    // Kalker's linear forces, saturated.
    let gab = c.g_mod * ca * cb;
    let mut fx = -gab * row.c11 * xi_x;
    let mut fy = -gab * (row.c22 * xi_y + (ca * cb).sqrt() * row.c23 * xi_s);
    let f = (fx * fx + fy * fy).sqrt();
    if f > 0.0 {
        let e = she_factor(f, c.mu, n);
        fx *= e;
        fy *= e;
    }
    // Into the track frame.
    let x = fx - fy * psi * cos_d;
    let y = fx * psi + fy * cos_t - sigma * n * sin_t;
    let z = sigma * fy * sin_t + n * cos_t;
    (x, Wheel { y, z, n })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn she_is_kalker_for_small_forces_and_mu_n_beyond_saturation() {
        let (mu, n) = (0.15, 66_600.0);
        let limit = mu * n;
        // Small force: unchanged to first order.
        assert!((she_factor(1e-6 * limit, mu, n) - 1.0).abs() < 1e-6);
        // The saturated magnitude is continuous at u = 3 and equals μN there and beyond.
        for u in [3.0 - 1e-12, 3.0, 3.0 + 1e-12, 10.0] {
            let sat = she_factor(u * limit, mu, n) * u * limit;
            assert!((sat - limit).abs() < 1e-6, "u = {u}: {sat}");
        }
        // Independent evaluation of the cubic at u = 1.5: 1.5 − 0.75 + 0.125 = 0.875.
        let sat = she_factor(1.5 * limit, mu, n) * 1.5 * limit;
        assert!((sat - 0.875 * limit).abs() < 1e-9 * limit);
    }
}
