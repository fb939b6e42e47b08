//! The paper's vertical vehicle–track coupled model after Zhai (§5): a 10-DOF half vehicle on
//! one rail ([`vehicle`]), Hertz wheel–rail contact ([`contact`]), a ballasted track with a
//! modal Euler–Bernoulli rail over discrete sleepers and ballast blocks ([`track`], with the
//! fast sine transform of [`fft`]), rail defects and track irregularities ([`irregularity`]),
//! integrated by Zhai's explicit two-step method ([`crate::solver::zhai`]).
//!
//! The track is a computing window of N sleepers that follows the vehicle: whenever the
//! carbody has run a set distance past the window centre, the window moves forward by whole
//! sleepers ([`track::Track::shift`]), so a run may be as long as wanted at a fixed cost per
//! step. With `moving_window = 0` the window stays put and a run that would bring a wheel
//! within 5 m of its end stops with an error.
//!
//! Parameters, defaults and sources are in [`VARIABLES`] and the HTML documentation in [`INFO`].
#![forbid(unsafe_code)]
// Indexed loops over wheels, DOFs and sleepers mirror the equations they implement.
#![allow(clippy::needless_range_loop)]

pub mod contact;
mod coupling;
pub mod fft;
pub mod irregularity;
pub mod plain;
pub mod track;
pub mod variables;
pub mod vehicle;

pub use variables::*;

#[cfg(test)]
use super::Start;
use super::{InitContext, Model, ModelError, ModelInfo, StateReader, StateWriter};
use crate::models::table::table_accessors;
use coupling::Sim;
use irregularity::{IrregularityKind, RandomProfile};
use std::path::PathBuf;
use std::sync::Arc;
pub use track::Kernel;

/// Closest a wheel may come to an end of the computing window (m).
pub const MIN_END_MARGIN: f64 = 5.0;

/// The vehicle–track model.
#[derive(Clone, Debug, Default)]
pub struct VehicleTrack {
    /// Parameters.
    pub p: Params,
    sim: Option<Sim>,
    resource_dir: Option<PathBuf>,
    /// Last random sample, reused while its key does not change.
    sample_cache: Option<Arc<RandomProfile>>,
    /// Implementation of the track's equations (not an FMI variable).
    kernel: Kernel,
}

impl VehicleTrack {
    /// A boxed model with default parameters.
    pub fn boxed() -> Box<dyn Model> {
        Box::new(VehicleTrack::default())
    }

    /// A model whose parameters are all zero (before the table's defaults).
    fn unset() -> Self {
        VehicleTrack {
            p: Params::zero(),
            sim: None,
            resource_dir: None,
            sample_cache: None,
            kernel: Kernel::Fast,
        }
    }

    /// Selects the implementation of the track's equations for the next initialization: the
    /// fast kernel (default) or the plain reference (tests and benchmarks compare them).
    pub fn set_kernel(&mut self, kernel: Kernel) {
        self.kernel = kernel;
    }

    /// Refuses a `dt` at which the explicit integration surely diverges: the highest rail
    /// mode, `ω = (NM π / l)² √(EI / mr)` (bending alone; the supports only raise it), beyond
    /// the undamped stability limit `ω dt = 2` of Zhai's method (damping lowers the limit
    /// further). Such a run used to return fmi2OK with forces of 1e63 N until the state
    /// overflowed (dt = 0.01 s).
    fn check_stability_limit(&self) -> Result<(), ModelError> {
        let p = &self.p;
        let length = (f64::from(p.n_sleepers) + 1.0) * p.r(VR_LS);
        let k = f64::from(p.n_modes) * std::f64::consts::PI / length;
        let omega = k * k * (p.r(VR_EI) / p.r(VR_MR)).sqrt();
        let dt = p.r(VR_DT);
        if omega * dt > 2.0 {
            return Err(INFO.invalid(
                VR_DT,
                dt,
                format!(
                    "the explicit integration diverges: the highest rail mode (n_modes = {}, \
                     {omega:.4e} rad/s) needs dt < 2/omega = {:.3e} s (a margin of 1.5-2 below \
                     that, as the default 1e-4 s has, keeps it stable with damping); reduce dt \
                     or n_modes",
                    p.n_modes,
                    2.0 / omega
                ),
            ));
        }
        Ok(())
    }

    fn sim(&self) -> Option<&Sim> {
        self.sim.as_ref()
    }

    /// A value of the running simulation (0 before the initialization).
    fn state(&self, f: impl FnOnce(&Sim) -> f64) -> f64 {
        self.sim().map_or(0.0, f)
    }
}

/// Format version of [`Model::save`].
const STATE_VERSION: u64 = 2;

impl Model for VehicleTrack {
    fn info(&self) -> &'static ModelInfo {
        &INFO
    }

    table_accessors!(TABLE; get_real -> f64, set_real(f64), get_integer -> i32, set_integer(i32), get_string -> String, set_string(&str));

    fn initialize(&mut self, ctx: &InitContext) -> Result<(), ModelError> {
        self.resource_dir = ctx.resource_dir.clone();
        self.sim = None;
        let p = &self.p;
        let (lmin, lmax) = (p.r(VR_LAMBDA_MIN), p.r(VR_LAMBDA_MAX));
        if matches!(
            IrregularityKind::from_code(p.irregularity),
            Some(IrregularityKind::Spectrum(_))
        ) && lmin >= lmax
        {
            return Err(INFO.invalid(
                VR_LAMBDA_MIN,
                lmin,
                format!("must be below lambda_max = {lmax} m"),
            ));
        }
        self.check_stability_limit()?;
        let mut sim = self.build(ctx.start_time)?;
        self.check_reach(&sim, sim.run.xc)?;
        self.equilibrate(&mut sim)?;
        self.sim = Some(sim);
        Ok(())
    }

    fn do_step(&mut self, _t: f64, h: f64) -> Result<(), ModelError> {
        let mut sim = self
            .sim
            .take()
            .ok_or_else(|| ModelError::Other("do_step before initialize".into()))?;
        let result = self.advance(&mut sim, h);
        self.sim = Some(sim);
        result
    }

    fn save(&self, out: &mut StateWriter) {
        TABLE.save_head(self, STATE_VERSION, self.resource_dir.as_deref(), out);
        match &self.sim {
            None => out.u64(0),
            Some(s) => {
                out.u64(1);
                out.f64s(&[
                    s.time,
                    s.run.xc,
                    s.run.x_win,
                    s.zhai.started as u8 as f64,
                    s.zhai.last_h,
                ]);
                for v in [&s.zhai.x, &s.zhai.v, &s.zhai.a, &s.zhai.a_prev] {
                    out.f64s(v);
                }
            }
        }
    }

    fn restore(&mut self, input: &mut StateReader<'_>) -> Result<(), ModelError> {
        let mut model = VehicleTrack {
            sample_cache: self.sample_cache.clone(),
            kernel: self.kernel,
            ..VehicleTrack::default()
        };
        model.resource_dir = TABLE.restore_head(&mut model, STATE_VERSION, input)?;
        let initialized = input.u64()?;
        if initialized == 1 {
            let head = input.f64s(Some(5))?;
            let mut sim = model.build(head[0])?;
            sim.run.xc = head[1];
            sim.run.x_win = head[2];
            sim.zhai.started = head[3] != 0.0;
            sim.zhai.last_h = head[4];
            let dim = sim.zhai.dim();
            sim.zhai.x = input.f64s(Some(dim))?;
            sim.zhai.v = input.f64s(Some(dim))?;
            sim.zhai.a = input.f64s(Some(dim))?;
            sim.zhai.a_prev = input.f64s(Some(dim))?;
            // Refresh the reported forces from the restored state; the restored accelerations
            // stay as they were saved.
            let restored = sim.zhai.a.clone();
            sim.update_accelerations(&model.p.half_vehicle());
            sim.zhai.a = restored;
            model.sim = Some(sim);
        } else if initialized != 0 {
            return Err(ModelError::CorruptState("bad initialization flag".into()));
        }
        *self = model;
        Ok(())
    }
}

#[cfg(test)]
mod tests;
