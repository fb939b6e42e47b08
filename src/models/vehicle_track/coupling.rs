//! The coupling of vehicle and track: the wheel–rail forces at the wheels' positions on the
//! computing window, the accelerations of the whole system, static equilibrium, the moving
//! window, and the stepping loop.
#![forbid(unsafe_code)]

use super::contact::{hertz_constant, Contact, ContactLaw};
use super::irregularity::{
    Dip, Excitation, Irregularity, IrregularityKind, MeasuredProfile, RandomProfile, SampleKey,
};
use super::track::Track;
use super::variables::*;
use super::vehicle::{HalfVehicle, NV, ZW1};
use super::{VehicleTrack, MIN_END_MARGIN};
use crate::models::ModelError;
use crate::solver::simd::Job;
use crate::solver::substeps;
use crate::solver::zhai::Zhai;
use std::sync::Arc;

/// Values the equations report besides the state (refreshed at each force evaluation).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Diag {
    pub(super) p: [f64; 4],
    pub(super) zr: [f64; 4],
    pub(super) z0: [f64; 4],
}

/// The rail profile the wheels see: the irregularity times `irregularity_scale`, plus the dip.
#[derive(Clone, Debug)]
pub(super) struct Profile {
    exc: Excitation,
    /// Factor on the irregularity amplitude (1).
    scale: f64,
}

impl Profile {
    /// Z0(x) (m, positive down).
    #[inline(always)]
    fn z0(&self, x: f64) -> f64 {
        self.scale * self.exc.irregularity_at(x) + self.exc.dip.eval(x)
    }

    fn check_range(&self, x_lo: f64, x_hi: f64) -> Result<(), String> {
        self.exc.check_range(x_lo, x_hi)
    }
}

/// Geometry of the running vehicle on the window.
#[derive(Clone, Copy, Debug)]
pub(super) struct Run {
    /// Track position of the carbody centre (m).
    pub(super) xc: f64,
    /// Track position of the window's left support (m), a multiple of l_s.
    pub(super) x_win: f64,
    /// Wheel offsets from the carbody centre (m).
    pub(super) offsets: [f64; 4],
}

/// Simulation data built by `initialize` (or `restore`).
#[derive(Clone, Debug)]
pub(super) struct Sim {
    pub(super) track: Track,
    pub(super) contact: Contact,
    pub(super) exc: Profile,
    pub(super) zhai: Zhai,
    pub(super) time: f64,
    pub(super) run: Run,
    /// Largest drift of the carbody from the window centre before the window moves (m).
    pub(super) shift_trigger: f64,
    /// Largest drift allowed at all (m).
    pub(super) max_drift: f64,
    pub(super) diag: Diag,
}

/// Whether every value is finite: x · 0 is 0 for a finite x and NaN otherwise, summed in four
/// lanes (a vector loop without early exit).
fn all_finite(v: &[f64]) -> bool {
    let mut acc = [0.0; 4];
    let chunks = v.chunks_exact(4);
    let tail = chunks.remainder().iter().fold(0.0, |s, x| s + x * 0.0);
    for c in chunks {
        for l in 0..4 {
            acc[l] += c[l] * 0.0;
        }
    }
    (acc[0] + acc[1] + acc[2] + acc[3] + tail) == 0.0
}

/// The substeps of one communication step, as a [`Job`] compiled for each instruction set.
struct Stepping<'a> {
    model: &'a VehicleTrack,
    sim: &'a mut Sim,
    hv: HalfVehicle,
    /// Number of substeps, their length (s), the speed (m/s).
    n: usize,
    hs: f64,
    v: f64,
    moving: bool,
}

impl Job for Stepping<'_> {
    #[inline(always)]
    fn run(&mut self) {
        let sim = &mut *self.sim;
        for _ in 0..self.n {
            if self.moving {
                self.model.follow(sim);
            }
            sim.zhai.predict(self.hs);
            sim.run.xc += self.v * self.hs;
            sim.update_accelerations(&self.hv);
            sim.zhai.commit(self.hs);
            sim.time += self.hs;
        }
    }
}

impl Sim {
    /// a = M⁻¹F(x, v) of the current state, with the vehicle at `self.run`; refreshes the
    /// reported forces.
    #[inline(always)]
    pub(super) fn update_accelerations(&mut self, hv: &HalfVehicle) {
        let Sim {
            track,
            contact,
            exc,
            zhai,
            diag,
            run,
            ..
        } = self;
        let a = &mut zhai.a;
        accelerations(hv, track, contact, exc, run, &zhai.x, &zhai.v, a, diag);
    }

    /// Vertical acceleration (m/s², Z down) of the carbody point at x = ∓`lc` (m) from its
    /// centre, `sign` = −1 above the front bogie (x = +Lc, attached at Zc − Lc βc), +1 above
    /// the rear one: Zc'' + sign · Lc βc''.
    pub(super) fn carbody_acc_at(&self, sign: f64, lc: f64) -> f64 {
        self.zhai.a[super::vehicle::ZC] + sign * lc * self.zhai.a[super::vehicle::BC]
    }
}

/// Accelerations of the whole system `a = M⁻¹F(x, v)` with the vehicle at `run`.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(super) fn accelerations(
    hv: &HalfVehicle,
    track: &mut Track,
    contact: &Contact,
    exc: &Profile,
    run: &Run,
    x: &[f64],
    v: &[f64],
    a: &mut [f64],
    diag: &mut Diag,
) {
    let mut local = [0.0; 4];
    for j in 0..4 {
        let xa = run.xc + run.offsets[j];
        local[j] = xa - run.x_win;
        diag.z0[j] = exc.z0(xa);
    }
    track.set_wheels(&local);
    diag.zr = track.rail_at_wheels(&x[NV..NV + track.nm]);
    for j in 0..4 {
        diag.p[j] = contact.force(x[ZW1 + j] - diag.zr[j] - diag.z0[j]);
    }
    hv.accelerations(&x[..NV], &v[..NV], &diag.p, &mut a[..NV]);
    track.accelerations(&x[NV..], &v[NV..], &diag.p, &mut a[NV..]);
}

impl VehicleTrack {
    /// Builds track, contact and excitation from the parameters (no equilibrium yet).
    pub(super) fn build(&mut self, start_time: f64) -> Result<Sim, ModelError> {
        let p = &self.p;
        let hv = p.half_vehicle();
        let track = Track::with_kernel(p.track(), self.kernel)
            .map_err(|e| INFO.invalid(VR_N_SLEEPERS, p.n_sleepers, e))?;
        let law = ContactLaw::from_code(p.contact_law)
            .ok_or_else(|| INFO.invalid(VR_CONTACT_LAW, p.contact_law, "must be 0 or 1"))?;
        let contact = Contact::new(law, hertz_constant(p.r(VR_R)), p.static_load());
        let kind = IrregularityKind::from_code(p.irregularity)
            .ok_or_else(|| INFO.invalid(VR_IRREGULARITY, p.irregularity, "must be 0..10"))?;
        let irregularity = match kind {
            IrregularityKind::None => Irregularity::None,
            IrregularityKind::Spectrum(spectrum) => {
                let key = SampleKey {
                    spectrum,
                    lambda_min: p.r(VR_LAMBDA_MIN),
                    lambda_max: p.r(VR_LAMBDA_MAX),
                    length: p.r(VR_IRR_LENGTH),
                    seed: p.seed,
                };
                let sample = match &self.sample_cache {
                    Some(s) if s.key == key => s.clone(),
                    _ => Arc::new(RandomProfile::generate(key).map_err(|e| {
                        // About the three together: name them all, not one the user may not
                        // have changed.
                        ModelError::Other(format!(
                            "irregularity sample (irregularity_length = {} m, lambda_min = {} m, \
                             lambda_max = {} m): {e}",
                            p.r(VR_IRR_LENGTH),
                            p.r(VR_LAMBDA_MIN),
                            p.r(VR_LAMBDA_MAX)
                        ))
                    })?),
                };
                self.sample_cache = Some(sample.clone());
                Irregularity::Random(sample)
            }
            IrregularityKind::Measured => Irregularity::Measured(Arc::new(
                MeasuredProfile::read(&p.profile_file, self.resource_dir.as_deref())
                    .map_err(ModelError::Other)?,
            )),
        };
        let offsets = hv.wheel_offsets();
        let exc = Profile {
            exc: Excitation {
                irregularity,
                dip: Dip {
                    x0: p.r(VR_DIP_X0),
                    length: p.r(VR_DIP_LENGTH),
                    depth: p.r(VR_DIP_DEPTH),
                },
                ramp_start: p.r(VR_X_START) + offsets[0],
                ramp_length: p.r(VR_RAMP_LENGTH),
            },
            scale: p.r(VR_IRREGULARITY_SCALE),
        };
        let (ls, l) = (p.r(VR_LS), track.length);
        let span = offsets[0].max(-offsets[3]);
        let max_drift = 0.5 * l - span - MIN_END_MARGIN;
        if max_drift < ls {
            return Err(INFO.invalid(
                VR_N_SLEEPERS,
                p.n_sleepers,
                format!(
                    "the computing window (l = {l} m) is too short for the vehicle (wheels ±{span} m from its centre) with {MIN_END_MARGIN} m margins: use more sleepers"
                ),
            ));
        }
        let xc = p.r(VR_X_START);
        let run = Run {
            xc,
            x_win: ls * ((xc - 0.5 * l) / ls).round(),
            offsets,
        };
        let dim = NV + track.dim();
        Ok(Sim {
            track,
            contact,
            exc,
            zhai: Zhai::new(dim),
            time: start_time,
            run,
            shift_trigger: (0.5 * max_drift).min(0.1 * l).max(ls),
            max_drift,
            diag: Diag::default(),
        })
    }

    /// Places the vehicle and the track in static equilibrium under gravity, at rest.
    pub(super) fn equilibrate(&self, sim: &mut Sim) -> Result<(), ModelError> {
        let hv = self.p.half_vehicle();
        let loads = hv.static_forces().p;
        let run = sim.run;
        let mut local = [0.0; 4];
        let mut z0 = [0.0; 4];
        for j in 0..4 {
            let xa = run.xc + run.offsets[j];
            local[j] = xa - run.x_win;
            z0[j] = sim.exc.z0(xa);
        }
        sim.track.set_wheels(&local);
        let nm = sim.track.nm;
        let (xs, rest) = sim.zhai.x.split_at_mut(NV);
        sim.track
            .static_solve(&loads, rest)
            .map_err(|reason| ModelError::SolverFailure {
                time: sim.time,
                reason,
            })?;
        let zr = sim.track.rail_at_wheels(&rest[..nm]);
        let mut zw = [0.0; 4];
        for j in 0..4 {
            zw[j] = zr[j] + z0[j] + sim.contact.compression(loads[j]);
        }
        xs.copy_from_slice(&hv.static_displacements(&zw));
        sim.zhai.v.iter_mut().for_each(|v| *v = 0.0);
        sim.update_accelerations(&hv);
        let zhai = &mut sim.zhai;
        zhai.a_prev.copy_from_slice(&zhai.a);
        zhai.restart();
        let veh = zhai.a[..NV].iter().fold(0.0f64, |m, a| m.max(a.abs()));
        let trk = zhai.a[NV..].iter().fold(0.0f64, |m, a| m.max(a.abs()));
        if !(veh < 1e-8 && trk < 1e-4) {
            return Err(ModelError::SolverFailure {
                time: sim.time,
                reason: format!(
                    "static equilibrium not reached: residual accelerations {veh:e} (vehicle), {trk:e} (track)"
                ),
            });
        }
        Ok(())
    }

    /// Moves the window forward by whole sleepers if the carbody has drifted far enough.
    #[inline(always)]
    fn follow(&self, sim: &mut Sim) {
        let drift = sim.run.xc - sim.run.x_win - 0.5 * sim.track.length;
        if drift >= sim.shift_trigger {
            self.shift_window(sim, drift);
        }
    }

    #[cold]
    #[inline(never)]
    fn shift_window(&self, sim: &mut Sim, drift: f64) {
        let ls = self.p.r(VR_LS);
        let m = (drift / ls).round() as usize;
        for arr in [&mut sim.zhai.x, &mut sim.zhai.v, &mut sim.zhai.a_prev] {
            sim.track.shift(m, &mut arr[NV..]);
        }
        sim.run.x_win += m as f64 * ls;
        sim.update_accelerations(&self.p.half_vehicle());
    }

    /// The wheels' track positions over [xc, xc_end] must stay on the window and the profile.
    pub(super) fn check_reach(&self, sim: &Sim, xc_end: f64) -> Result<(), ModelError> {
        let (o, run) = (&sim.run.offsets, &sim.run);
        let (lo, hi) = (run.xc + o[3], xc_end + o[0]);
        sim.exc
            .check_range(lo, hi)
            .map_err(|reason| ModelError::SolverFailure {
                time: sim.time,
                reason,
            })?;
        if self.p.moving_window == 0 {
            let drift = xc_end - run.x_win - 0.5 * sim.track.length;
            if drift > sim.max_drift {
                return Err(ModelError::SolverFailure {
                    time: sim.time,
                    reason: format!(
                        "the vehicle would leave the computing track: the leading wheel would reach x = {:.2} m, beyond the window end {:.2} m less the {MIN_END_MARGIN} m margin; set moving_window = 1 or more n_sleepers",
                        hi,
                        run.x_win + sim.track.length
                    ),
                });
            }
        }
        Ok(())
    }

    /// Advances by `h` (s) in equal substeps no longer than `dt`, on the instruction set the
    /// track's kernel chose.
    pub(super) fn advance(&self, sim: &mut Sim, h: f64) -> Result<(), ModelError> {
        let n = substeps(h, self.p.r(VR_DT))?;
        let hs = h / n as f64;
        let v = self.p.r(VR_V);
        self.check_reach(sim, sim.run.xc + v * h)?;
        let simd = sim.track.simd();
        let mut job = Stepping {
            model: self,
            hv: self.p.half_vehicle(),
            sim: &mut *sim,
            n,
            hs,
            v,
            moving: self.p.moving_window == 1,
        };
        simd.dispatch(&mut job);
        let ok =
            all_finite(&sim.zhai.x[..NV]) && all_finite(&sim.zhai.a) && all_finite(&sim.diag.p);
        if ok {
            Ok(())
        } else {
            Err(ModelError::SolverFailure {
                time: sim.time,
                reason: "the state became non-finite (integration unstable: reduce dt or n_modes)"
                    .into(),
            })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::all_finite;

    #[test]
    fn all_finite_finds_any_nan_or_infinity() {
        let mut v: Vec<f64> = (0..23).map(|i| i as f64 * 1e300).collect();
        assert!(all_finite(&v) && all_finite(&[]));
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            for i in [0, 5, 21, 22] {
                let keep = v[i];
                v[i] = bad;
                assert!(!all_finite(&v), "{bad} at {i}");
                v[i] = keep;
            }
        }
    }
}
