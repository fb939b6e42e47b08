//! The equations of motion of the car (MODELS §5.7): 66 first-order states, Newton–Euler per
//! body in the track frame, small rotations.
//!
//! ```text
//! state of the car body and of each bogie frame (10):  y, ẏ, z, ż, φ, φ̇, χ, χ̇, ψ, ψ̇
//! state of each wheelset (9):                          y, ẏ, z, ż, φ, φ̇, β, ψ, ψ̇
//! order: car body (0..10), bogie 1, bogie 2, wheelsets 1..4 (30..66), front to back
//!
//! rotation of a body       T = I + [[0, −ψ, χ], [ψ, 0, −φ], [−χ, φ, 0]]     (χ = 0 for a wheelset)
//! point p of a body        r = c + (0, y, z) + T p,   ṙ = (0, ẏ, ż) + Ṫ p
//! element, lower body L    l = r_U − r_L;  spring  F_L[axis] = s k (|l[axis]| − L0),
//!                          s = sign of the rest vector's component, L0 its length with preload;
//!                          damper  F_L[axis] = D (ṙ_U − ṙ_L)[axis]  (or along l/|l|)
//!                          F_U = −F_L;  moment on each body  p × (Tᵀ F)  (body frame)
//! every body               m ÿ = ΣFy + m (v² cos φse κ − g sin φse)
//!                          m z̈ = ΣFz − m (v² sin φse κ + g cos φse)
//!                          Ix φ̈ = ΣMx,  Iy χ̈ = ΣMy,  Iz ψ̈ = ΣMz
//! wheelset, Ω = v/r_t + β  Mx += −Ix Ω v cos φse κ + (Iy − Iz)(−Ω v cos φse κ + Ω ψ̇)
//!                          Mz += (Ix − Iy) φ̇ Ω,     Iy β̇ = spin torque of the wheel–rail forces
//! ```
//!
//! Trigonometric functions come from the `libm` crate (pure Rust), so that every platform
//! computes the same numbers.
//!
//! The reference implementation divides the pitch moments of the car body and the bogie
//! frames by Ix; here they are divided by Iy (MODELS §5.7). Pitch does not enter the lateral
//! dynamics on straight track; `Iy_c` = 2.8e5 kg·m² reproduces the reference exactly.
#![forbid(unsafe_code)]

use super::contact::{self, ContactConst, Running, Wheelset};
use super::params::{DamperKind, Link, Params, BODIES, GRAVITY, LINKS};
use crate::contact::table::ContactSpline;

/// Number of first-order states.
pub const N_STATES: usize = 66;
/// The state vector.
pub type State = [f64; N_STATES];

/// Offsets of the states of a car body or bogie frame from its first state.
pub mod dof {
    /// Lateral displacement y (m).
    pub const Y: usize = 0;
    /// Lateral velocity (m/s).
    pub const YD: usize = 1;
    /// Vertical displacement z (m), up.
    pub const Z: usize = 2;
    /// Vertical velocity (m/s).
    pub const ZD: usize = 3;
    /// Roll φ (rad).
    pub const PHI: usize = 4;
    /// Roll rate (rad/s).
    pub const PHID: usize = 5;
    /// Pitch χ (rad) of a car body or bogie frame.
    pub const CHI: usize = 6;
    /// Pitch rate (rad/s).
    pub const CHID: usize = 7;
    /// Yaw ψ (rad) of a car body or bogie frame.
    pub const PSI: usize = 8;
    /// Yaw rate (rad/s).
    pub const PSID: usize = 9;
    /// Spin perturbation β (rad/s) of a wheelset.
    pub const BETA: usize = 6;
    /// Yaw ψ (rad) of a wheelset.
    pub const W_PSI: usize = 7;
    /// Yaw rate (rad/s) of a wheelset.
    pub const W_PSID: usize = 8;
}

/// Index of the first state of body `i` (0 car body, 1–2 bogies, 3–6 wheelsets).
pub const fn base(i: usize) -> usize {
    if i < 3 {
        10 * i
    } else {
        30 + 9 * (i - 3)
    }
}

/// Displacement, velocity, rotation and rotation rate of a body.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Kin {
    /// Displacement (0, y, z) (m).
    pub d: [f64; 3],
    /// Velocity (0, ẏ, ż) (m/s).
    pub dd: [f64; 3],
    /// Roll, pitch, yaw (rad).
    pub ang: [f64; 3],
    /// Their rates (rad/s).
    pub rate: [f64; 3],
}

impl Kin {
    /// The kinematics of body `i` in state `x`.
    #[inline]
    pub fn of(x: &State, i: usize) -> Kin {
        let s = &x[base(i)..];
        let (chi, chid, psi, psid) = if i < 3 {
            (s[dof::CHI], s[dof::CHID], s[dof::PSI], s[dof::PSID])
        } else {
            (0.0, 0.0, s[dof::W_PSI], s[dof::W_PSID])
        };
        Kin {
            d: [0.0, s[dof::Y], s[dof::Z]],
            dd: [0.0, s[dof::YD], s[dof::ZD]],
            ang: [s[dof::PHI], chi, psi],
            rate: [s[dof::PHID], chid, psid],
        }
    }

    /// (T − I) p: the displacement of body point `p` by the rotation (m).
    #[inline]
    fn turn(a: &[f64; 3], p: &[f64; 3]) -> [f64; 3] {
        let [phi, chi, psi] = *a;
        [
            -psi * p[1] + chi * p[2],
            psi * p[0] - phi * p[2],
            -chi * p[0] + phi * p[1],
        ]
    }

    /// Position of body point `p` relative to the body's nominal centre (m).
    #[inline]
    pub fn point(&self, p: &[f64; 3]) -> [f64; 3] {
        let t = Self::turn(&self.ang, p);
        [
            p[0] + t[0],
            p[1] + self.d[1] + t[1],
            p[2] + self.d[2] + t[2],
        ]
    }

    /// Velocity of body point `p` (m/s).
    #[inline]
    pub fn point_velocity(&self, p: &[f64; 3]) -> [f64; 3] {
        let t = Self::turn(&self.rate, p);
        [t[0], self.dd[1] + t[1], self.dd[2] + t[2]]
    }

    /// Tᵀ f: a track-frame vector in the body frame.
    #[inline]
    pub fn to_body(&self, f: &[f64; 3]) -> [f64; 3] {
        let [phi, chi, psi] = self.ang;
        [
            f[0] + psi * f[1] - chi * f[2],
            f[1] - psi * f[0] + phi * f[2],
            f[2] + chi * f[0] - phi * f[1],
        ]
    }
}

#[inline]
fn cross(p: &[f64; 3], f: &[f64; 3]) -> [f64; 3] {
    [
        p[1] * f[2] - p[2] * f[1],
        p[2] * f[0] - p[0] * f[2],
        p[0] * f[1] - p[1] * f[0],
    ]
}

/// Everything the right-hand side needs that does not change during a run.
#[derive(Clone, Debug)]
pub struct Car {
    /// Parameters.
    pub p: Params,
    /// Suspension elements.
    pub links: [Link; LINKS],
    /// Contact constants.
    pub contact: ContactConst,
}

impl Car {
    /// The car of parameters `p` on the contact table `table`.
    pub fn new(p: Params, table: &ContactSpline) -> Car {
        let r_t = table.left(0.0).map_or(p.r0, |row| row.r);
        Car {
            p,
            links: p.links(),
            contact: ContactConst {
                a: p.a,
                g_mod: p.g_mod,
                mu: p.mu,
                r_t,
                lateral_roll: p.roll_moment == 1,
            },
        }
    }
}

impl Car {
    /// The name of a spring whose attachment points coincide along its axis at rest (its
    /// force would have no direction), if any.
    pub fn zero_length_link(&self) -> Option<&'static str> {
        self.links
            .iter()
            .find(|l| l.dc[l.axis] + l.pu[l.axis] - l.pl[l.axis] == 0.0)
            .map(|l| l.name)
    }
}

/// The track under the wheelsets at one instant: running conditions and the irregularity.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Track {
    /// Speed, curvature and cant.
    pub run: Running,
    /// Lateral track irregularity under wheelset 1..4 (m, positive left).
    pub y: [f64; 4],
    /// Vertical track irregularity under wheelset 1..4 (m, positive up).
    pub z: [f64; 4],
}

/// A wheelset beyond the contact table: the run derails.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Derailment {
    /// Wheelset (0 = the leading one).
    pub wheelset: usize,
    /// Its lateral displacement relative to the track (m).
    pub y: f64,
}

/// Forces computed on the way to the derivatives (for the outputs).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Diagnostics {
    /// Wheel–rail forces of each wheelset.
    pub wheelsets: [Wheelset; 4],
}

/// The right-hand side x' = f(x) of the car on track `track`, into `dx`; the wheel–rail forces
/// into `diag` when given.
pub fn rhs(
    car: &Car,
    table: &ContactSpline,
    track: &Track,
    x: &State,
    dx: &mut State,
    diag: Option<&mut Diagnostics>,
) -> Result<(), Derailment> {
    let p = &car.p;
    let kin: [Kin; BODIES] = std::array::from_fn(|i| Kin::of(x, i));
    let mut force = [[0.0; 3]; BODIES];
    let mut moment = [[0.0; 3]; BODIES];
    for link in &car.links {
        let (ku, kl) = (&kin[link.upper], &kin[link.lower]);
        let (ru, rl) = (ku.point(&link.pu), kl.point(&link.pl));
        let l: [f64; 3] = std::array::from_fn(|i| link.dc[i] + ru[i] - rl[i]);
        let mut f = [0.0; 3];
        f[link.axis] = link.rest_sign * link.k * (l[link.axis].abs() - link.rest_length);
        if link.damping != 0.0 {
            let (vu, vl) = (ku.point_velocity(&link.pu), kl.point_velocity(&link.pl));
            let rel: [f64; 3] = std::array::from_fn(|i| vu[i] - vl[i]);
            match link.damper {
                DamperKind::Axis => f[link.axis] += link.damping * rel[link.axis],
                DamperKind::Vector => {
                    let len2 = l[0] * l[0] + l[1] * l[1] + l[2] * l[2];
                    let along =
                        link.damping * (rel[0] * l[0] + rel[1] * l[1] + rel[2] * l[2]) / len2;
                    for i in 0..3 {
                        f[i] += along * l[i];
                    }
                }
            }
        }
        // f acts on the lower body, −f on the upper.
        let ml = cross(&link.pl, &kl.to_body(&f));
        let fu = [-f[0], -f[1], -f[2]];
        let mu = cross(&link.pu, &ku.to_body(&fu));
        for i in 0..3 {
            force[link.lower][i] += f[i];
            force[link.upper][i] += fu[i];
            moment[link.lower][i] += ml[i];
            moment[link.upper][i] += mu[i];
        }
    }
    let run = &track.run;
    let (sin_se, cos_se) = libm::sincos(run.cant);
    let v2k = run.v * run.v * run.kappa;
    let lateral = v2k * cos_se - GRAVITY * sin_se;
    let vertical = -v2k * sin_se - GRAVITY * cos_se;
    let mut diag = diag;
    for i in 0..BODIES {
        let m = p.mass(i);
        let inertia = p.inertia(i);
        let k = &kin[i];
        let s = base(i);
        let (mut fy, mut fz) = (force[i][1] + m * lateral, force[i][2] + m * vertical);
        let mut mom = moment[i];
        if i >= 3 {
            let w = i - 3;
            let (y_rel, z_rel) = (k.d[1] - track.y[w], k.d[2] - track.z[w]);
            let beta = x[s + dof::BETA];
            let b = Params::wheelset_sign(w) * p.u2;
            let c = contact::wheelset_forces(table, &car.contact, run, k, beta, y_rel, z_rel, b)
                .ok_or(Derailment {
                    wheelset: w,
                    y: y_rel,
                })?;
            fy += c.force[1];
            fz += c.force[2];
            let omega = run.v / car.contact.r_t + beta;
            let [ix, iy, iz] = inertia;
            let turn = omega * run.v * cos_se * run.kappa;
            mom[0] += c.roll - ix * turn + (iy - iz) * (-turn + omega * k.rate[2]);
            mom[2] += c.yaw + (ix - iy) * k.rate[0] * omega;
            dx[s + dof::BETA] = c.spin / iy;
            dx[s + dof::W_PSI] = k.rate[2];
            dx[s + dof::W_PSID] = mom[2] / iz;
            if let Some(d) = diag.as_deref_mut() {
                d.wheelsets[w] = c;
            }
        } else {
            dx[s + dof::CHI] = k.rate[1];
            dx[s + dof::CHID] = mom[1] / inertia[1];
            dx[s + dof::PSI] = k.rate[2];
            dx[s + dof::PSID] = mom[2] / inertia[2];
        }
        dx[s + dof::Y] = k.dd[1];
        dx[s + dof::YD] = fy / m;
        dx[s + dof::Z] = k.dd[2];
        dx[s + dof::ZD] = fz / m;
        dx[s + dof::PHI] = k.rate[0];
        dx[s + dof::PHID] = mom[0] / inertia[0];
    }
    Ok(())
}
