//! The paper's two-degree-of-freedom bogie (§4): Cooperrider's bogie frame with two rigidly
//! attached wheelsets, lateral displacement Y and yaw φ, nonlinear creep forces and a dead-band
//! flange spring on the leading wheelset, run on a slowly falling speed to find the speed at which
//! the hunting motion dies out (the nonlinear critical speed).
//!
//! ```text
//! y_1 = Y + h φ,   y_2 = Y − h φ                        wheelset lateral displacements (m)
//! ξx,i = a φ'/V + λ y_i / r0,   ξy,i = y_i'/V − φ        creepages of the left wheel (the right one has −ξx)
//! u = √((ξx/ψ)² + (ξy/ϕ)²)
//! F_R = μN (u − u²/3 + u³/27) for u < 3,   μN for u ≥ 3  (Shen–Hedrick–Elkins saturation)
//! Fx = F_R (ξx/ψ)/u,   Fy = F_R (ξy/ϕ)/u                 (u → 0: Fx = μN ξx/ψ, Fy = μN ξy/ϕ)
//! F_T = k0 (y_1 − δ) if y_1 > δ;  0 if |y_1| ≤ δ;  k0 (y_1 + δ) if y_1 < −δ
//! m_b Y'' = −2 C_sy Y' − 2 K_sy Y − 2 (Fy1 + Fy2) − F_T                         [paper eq. 24]
//! I_b φ'' = −K_φ φ − 2h (Fy1 − Fy2) − 2a (Fx1 + Fx2) − h F_T                    [paper eq. 25]
//! V(t) = V0 − (t − t_start)/Δf                                                  [paper eq. 29]
//! ```
//!
//! The variables (20 parameters from vr 0, 18 outputs from vr 100, the linear critical speed at
//! vr 120), with units, defaults and sources, are declared once, one line each, in
//! [`variables`].
//!
//! Integration: classical RK4 with equal substeps no longer than `dt` (and no longer than the
//! inverse of the fastest rate of the linearised model at the current speed, which only binds
//! below ~23 m/s with the defaults). The flange force has kinks at ±δ, so the convergence order is
//! below four; the tests show that halving `dt` changes the critical speed by far less than
//! 0.01 m/s.
#![forbid(unsafe_code)]

pub mod equations;
pub mod stability;
pub mod variables;

pub use equations::{creep_force, flange_force, forces, rhs, BogieParams, Forces};
pub use stability::{linear_critical_speed, linear_growth_rate, linear_state_matrix};
pub use variables::*;

use super::{InitContext, Model, ModelError, ModelInfo, SetResult, StateReader, StateWriter};
use crate::models::table::table_accessors;
use crate::solver::{rk4_step, substeps};
use stability::clamped_linear_critical_speed;

/// Lowest speed (m/s) the model runs at: the creepages divide by V.
pub const MIN_SPEED: f64 = 1.0;

/// The bogie model: parameters and state.
#[derive(Clone, Debug)]
pub struct Bogie {
    /// Physical parameters.
    pub p: BogieParams,
    /// Speed at the start time (m/s).
    pub v0: f64,
    /// Ramp Δf (s²/m): V = V0 − (t − t_start)/Δf; 0 = constant speed.
    pub ramp: f64,
    /// Initial lateral displacement (m).
    pub y0: f64,
    /// Initial yaw angle (rad).
    pub phi0: f64,
    /// Largest internal RK4 step (s).
    pub dt: f64,
    /// Time (s) from which V = V0 − (t − t_start)/Δf: the start time of the run, or the time
    /// at which V0 was last set between steps.
    pub t_start: f64,
    /// Current time (s).
    pub t: f64,
    /// State [Y (m), φ (rad), Y' (m/s), φ' (rad/s)].
    pub x: [f64; 4],
    /// Linear critical speed at the initialization's parameters (m/s).
    pub v_cr_linear: f64,
}

impl Default for Bogie {
    fn default() -> Self {
        let mut b = Bogie::zero();
        TABLE.apply_defaults(&mut b);
        b.x = [b.y0, b.phi0, 0.0, 0.0];
        b.v_cr_linear = clamped_linear_critical_speed(&b);
        b
    }
}

impl Bogie {
    /// Every parameter and the state zero (before the table's defaults).
    fn zero() -> Self {
        Bogie {
            p: BogieParams::ZERO,
            v0: 0.0,
            ramp: 0.0,
            y0: 0.0,
            phi0: 0.0,
            dt: 0.0,
            t_start: 0.0,
            t: 0.0,
            x: [0.0; 4],
            v_cr_linear: f64::NAN,
        }
    }

    /// A boxed bogie with default parameters.
    pub fn boxed() -> Box<dyn Model> {
        Box::new(Bogie::default())
    }

    /// Running speed (m/s) at time `t` (s).
    pub fn speed(&self, t: f64) -> f64 {
        if self.ramp == 0.0 {
            self.v0
        } else {
            self.v0 - (t - self.t_start) / self.ramp
        }
    }

    /// Bound (1/s) on the fastest rate of the linearised model at speed `v` (m/s): creep
    /// damping rates and undamped frequencies including the flange spring.
    fn fastest_rate(&self, v: f64) -> f64 {
        let p = &self.p;
        let cx = p.mu * p.n / p.psi;
        let cy = p.mu * p.n / p.phi_c;
        let lateral_damping = (2.0 * p.c_sy + 4.0 * cy / v) / p.m_b;
        let yaw_damping = 4.0 * (p.h * p.h * cy + p.a * p.a * cx) / (v * p.i_b);
        let lateral_freq = ((2.0 * p.k_sy + p.k0) / p.m_b).sqrt();
        let yaw_freq = ((p.k_phi + p.h * p.h * p.k0) / p.i_b).sqrt();
        lateral_damping
            .max(yaw_damping)
            .max(lateral_freq)
            .max(yaw_freq)
    }

    fn speed_error(&self, t: f64, v: f64) -> ModelError {
        let limit = if self.ramp > 0.0 {
            format!(
                "; with V0 = {} m/s and ramp = {} s2/m the run must stop before t = {} s",
                self.v0,
                self.ramp,
                self.t_start + (self.v0 - MIN_SPEED) * self.ramp
            )
        } else {
            String::new()
        };
        ModelError::EndOfSimulation {
            time: t,
            reason: format!(
                "running speed V = {v} m/s is at or below {MIN_SPEED} m/s (the creepages divide by V){limit}"
            ),
        }
    }
}

impl Model for Bogie {
    fn info(&self) -> &'static ModelInfo {
        &INFO
    }

    table_accessors!(TABLE; get_real -> f64);

    fn set_real(&mut self, vr: u32, value: f64) -> SetResult {
        let warning = TABLE.set_real(self, vr, value)?;
        if vr == VR_V0 {
            // A new speed takes effect from now: the ramp (if any) restarts from it (the
            // initialization sets t_start to the start time).
            self.t_start = self.t;
        }
        Ok(warning)
    }

    fn initialize(&mut self, ctx: &InitContext) -> Result<(), ModelError> {
        self.t_start = ctx.start_time;
        self.t = ctx.start_time;
        self.x = [self.y0, self.phi0, 0.0, 0.0];
        self.v_cr_linear = clamped_linear_critical_speed(self);
        Ok(())
    }

    fn do_step(&mut self, t: f64, h: f64) -> Result<(), ModelError> {
        let v_begin = self.speed(t);
        let v_end = self.speed(t + h);
        let v_min = v_begin.min(v_end);
        if v_min <= MIN_SPEED {
            let (tt, vv) = if v_begin <= MIN_SPEED {
                (t, v_begin)
            } else {
                (t + h, v_end)
            };
            return Err(self.speed_error(tt, vv));
        }
        let h_max = self.dt.min(1.0 / self.fastest_rate(v_min));
        let n = substeps(h, h_max)?;
        let dt = h / n as f64;
        let p = self.p;
        let (v0, ramp, t_start) = (self.v0, self.ramp, self.t_start);
        let speed = |tau: f64| {
            if ramp == 0.0 {
                v0
            } else {
                v0 - (tau - t_start) / ramp
            }
        };
        for i in 0..n {
            rk4_step(
                |tau, x: &[f64; 4]| rhs(&p, speed(tau), x),
                t + i as f64 * dt,
                &mut self.x,
                dt,
            );
        }
        self.t = t + h;
        if self.x.iter().all(|x| x.is_finite()) {
            Ok(())
        } else {
            Err(ModelError::SolverFailure {
                time: t + h,
                reason: format!(
                    "state became non-finite (Y = {}, phi = {}, Yd = {}, phid = {})",
                    self.x[0], self.x[1], self.x[2], self.x[3]
                ),
            })
        }
    }

    fn save(&self, out: &mut StateWriter) {
        TABLE.save_parameters(self, out);
        out.f64s(&[
            self.t_start,
            self.t,
            self.x[0],
            self.x[1],
            self.x[2],
            self.x[3],
        ]);
    }

    fn restore(&mut self, input: &mut StateReader<'_>) -> Result<(), ModelError> {
        let mut b = Bogie::zero();
        TABLE.restore_parameters(&mut b, input)?;
        let v = input.f64s(Some(6))?;
        b.t_start = v[0];
        b.t = v[1];
        b.x = [v[2], v[3], v[4], v[5]];
        b.v_cr_linear = clamped_linear_critical_speed(&b);
        *self = b;
        Ok(())
    }
}

#[cfg(test)]
mod tests;
