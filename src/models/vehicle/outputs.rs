//! What an engineer assesses a running vehicle by, computed from the state at a communication
//! point: wheel forces Y and Q, Nadal's ratio Y/Q, the track-shifting force ΣY, the wheel
//! unloading ΔQ/Q and the car-body accelerations on the floor above the bogies.
//!
//! ```text
//! Y_iσ   lateral force of wheel σ of wheelset i on its rail, track frame, positive to the left (N)
//! Q_iσ   vertical force of the wheel on the rail, positive downward (N)
//! YQ_iL  =  Y_iL / Q_iL,   YQ_iR = −Y_iR / Q_iR     positive when the wheel pushes its rail
//!                                                    outward (flange side); 0 when Q ≤ 1 N
//! SumY_i = Y_iL + Y_iR                              track-shifting force of axle i (N)
//! dQQ_iσ = (Q0 − Q_iσ) / Q0,  Q0 = g (m_c + 2 m_b + 4 m_w)/8   wheel unloading (1)
//! floor point above bogie b: (±u1, 0, h_floor − (r0 + h1 + h2)) from the car body's centre
//! ay = ÿ + ψ̈ x_p − φ̈ z_p,   az = z̈ − χ̈ x_p        accelerations in the track-following frame
//! ```
#![forbid(unsafe_code)]

use super::contact::MIN_NORMAL_FORCE;
use super::equations::{base, dof, rhs, Car, Diagnostics, State, Track, N_STATES};
use super::params::{wheelset, CAR};
use crate::contact::table::ContactSpline;

/// The outputs at one instant.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Outputs {
    /// Y per wheelset and side (0 left, 1 right) (N).
    pub y: [[f64; 2]; 4],
    /// Q per wheelset and side (N).
    pub q: [[f64; 2]; 4],
    /// Nadal's ratio per wheelset and side (1).
    pub yq: [[f64; 2]; 4],
    /// Track-shifting force per wheelset (N).
    pub sum_y: [f64; 4],
    /// Wheel unloading per wheelset and side (1).
    pub dqq: [[f64; 2]; 4],
    /// Lateral acceleration of the floor above bogie 1, 2 (m/s²).
    pub ay_floor: [f64; 2],
    /// Vertical acceleration of the floor above bogie 1, 2 (m/s²).
    pub az_floor: [f64; 2],
    /// Lateral displacement of each wheelset relative to the track (m).
    pub y_rel: [f64; 4],
}

/// The outputs of state `x` on `track`; `q0` is the static wheel load (N) and `h_floor` the
/// floor height above rail level (m). Zero forces if the state is beyond the table.
pub fn outputs(
    car: &Car,
    table: &ContactSpline,
    track: &Track,
    x: &State,
    q0: f64,
    h_floor: f64,
) -> Outputs {
    let mut out = Outputs::default();
    let mut dx = [0.0; N_STATES];
    let mut diag = Diagnostics::default();
    if rhs(car, table, track, x, &mut dx, Some(&mut diag)).is_err() {
        return out;
    }
    for w in 0..4 {
        let ws = &diag.wheelsets[w];
        for side in 0..2 {
            let wheel = &ws.wheels[side];
            let (y, q) = (-wheel.y, wheel.z);
            out.y[w][side] = y;
            out.q[w][side] = q;
            let outward = if side == 0 { y } else { -y };
            out.yq[w][side] = if q > MIN_NORMAL_FORCE {
                outward / q
            } else {
                0.0
            };
            out.dqq[w][side] = (q0 - q) / q0;
        }
        out.sum_y[w] = out.y[w][0] + out.y[w][1];
        out.y_rel[w] = x[base(wheelset(w)) + dof::Y] - track.y[w];
    }
    let p = &car.p;
    let c = base(CAR);
    let zp = h_floor - (p.r0 + p.h1 + p.h2);
    for b in 0..2 {
        let xp = if b == 0 { p.u1 } else { -p.u1 };
        out.ay_floor[b] = dx[c + dof::YD] + dx[c + dof::PSID] * xp - dx[c + dof::PHID] * zp;
        out.az_floor[b] = dx[c + dof::ZD] - dx[c + dof::CHID] * xp;
    }
    out
}
