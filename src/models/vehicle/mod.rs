//! The full passenger car after Cooperrider, as True, Kaas-Petersen and Bigoni studied its
//! stability (MODELS §5): a car body, two bogie frames and four wheelsets with linear
//! suspension elements, wheel–rail contact from a tabulated contact geometry (by default S1002
//! on UIC60 inclined 1:40), Kalker's linear creep law saturated by Shen–Hedrick–Elkins; 66
//! first-order states, on straight or curved track, with optional track irregularities.
//!
//! - [`params`]: parameters, bodies and the 36 suspension elements (attachment points);
//! - [`contact`]: the wheel–rail forces of a wheelset;
//! - [`equations`]: the right-hand side of the 66 states;
//! - [`track`]: speed (constant or a ramp), curve, cant and irregularities over time;
//! - [`integrate`]: RK4 with substeps bounded by the fastest mode (why: see there);
//! - [`stability`]: Jacobian, eigenvalues, linear critical speed;
//! - [`outputs`]: Y, Q, Y/Q, ΣY, ΔQ/Q, floor accelerations;
//! - [`variables`]: the variable table (names, units, defaults, sources) and the description.
//!
//! A wheelset whose lateral displacement relative to the track leaves the contact table has
//! derailed: the step fails with [`ModelError::EndOfSimulation`] naming the wheelset (the FMU
//! returns fmi2Discard and reports fmi2Terminated; the state and outputs stay those of the
//! last communication point). A state that becomes non-finite is a
//! [`ModelError::SolverFailure`].
#![forbid(unsafe_code)]
// Indexed loops over wheelsets, sides and states mirror the equations they implement.
#![allow(clippy::needless_range_loop)]

pub mod contact;
pub mod equations;
pub mod integrate;
pub mod outputs;
pub mod params;
pub mod stability;
mod tables;
pub mod track;
pub mod variables;

pub use tables::{builtin_contact_table, BUILTIN_SMOOTHING};

pub use variables::*;

use super::data_file::{read_data_file, resolve};
use super::vehicle_track::irregularity::{RandomProfile, SampleKey};
use super::{InitContext, Model, ModelError, ModelInfo, SetResult, StateReader, StateWriter};
use crate::contact::table::{ContactSpline, ContactTable, TableRow};
use crate::models::table::table_accessors;
use crate::solver::substeps;
use equations::{base, dof, Car, State, N_STATES};
use integrate::{rk4_substep, RateBound, StepError, STABILITY_FACTOR};
use outputs::Outputs;
use params::{wheelset, Params};
use std::cell::OnceCell;
use std::path::PathBuf;
use std::sync::Arc;
use track::{Course, Irregularity, MeasuredTrack, Source};

/// Lowest running speed (m/s): the creepages divide by the speed.
pub const MIN_SPEED: f64 = 1.0;

/// Track irregularity parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct IrregularityParams {
    /// 0 none, 2 German low, 3 German high interference, 10 measured file.
    pub code: i32,
    /// Seed of the random phases.
    pub seed: i32,
    /// Shortest wavelength (m).
    pub lambda_min: f64,
    /// Longest wavelength (m).
    pub lambda_max: f64,
    /// Length of the random sample, which repeats beyond (m).
    pub length: f64,
    /// Amplitude factor (1).
    pub scale: f64,
    /// Fade-in length (m).
    pub fade_in: f64,
    /// File of x, y, z for code 10.
    pub file: String,
}

/// A run in progress: everything the state needs to move on.
#[derive(Clone, Debug)]
struct Run {
    car: Car,
    table: Arc<ContactTable>,
    spline: Arc<ContactSpline>,
    course: Course,
    irregularity: Irregularity,
    offsets: [f64; 4],
    bound: RateBound,
    t: f64,
    x: State,
}

/// The vehicle model.
#[derive(Clone, Debug)]
pub struct Vehicle {
    /// Masses, geometry, suspension, friction.
    pub p: Params,
    /// Speed (m/s) at the start, or from the time it was set.
    pub v: f64,
    /// Speed ramp (s²/m): the speed falls by 1/ramp m/s per second; 0 = constant speed.
    pub ramp: f64,
    /// Curve radius (m); 0 = straight track. Positive: the curve turns to the right (−y).
    pub radius: f64,
    /// Cant (rad); positive raises the left rail.
    pub cant: f64,
    /// Duration of the entry into the curve (s).
    pub transition: f64,
    /// Initial lateral displacement of wheelsets 1..4 (m).
    pub y0: [f64; 4],
    /// Largest integration substep (s).
    pub dt: f64,
    /// Floor height above rail level (m).
    pub h_floor: f64,
    /// Irregularity parameters.
    pub irr: IrregularityParams,
    /// Contact table file; empty = built in, or computed from the profiles below.
    pub contact_table: String,
    /// Wheel profile file (CSV: y, z in mm from the flange back); empty = S1002. With
    /// `rail_profile`, the contact table is computed from the profiles at initialization.
    pub wheel_profile: String,
    /// Rail profile file (CSV: y, z in mm from the rail's centre line); empty = UIC60.
    pub rail_profile: String,
    run: Option<Run>,
    resource_dir: Option<PathBuf>,
    /// Random samples of the last initialization, reused while their keys do not change.
    samples: Option<(Arc<RandomProfile>, Arc<RandomProfile>)>,
    outputs: OnceCell<Outputs>,
    v_cr: OnceCell<Result<f64, String>>,
}

impl Default for Vehicle {
    fn default() -> Self {
        let mut m = Vehicle::zero();
        TABLE.apply_defaults(&mut m);
        m
    }
}

impl Vehicle {
    fn zero() -> Self {
        Vehicle {
            p: Params::ZERO,
            v: 0.0,
            ramp: 0.0,
            radius: 0.0,
            cant: 0.0,
            transition: 0.0,
            y0: [0.0; 4],
            dt: 0.0,
            h_floor: 0.0,
            irr: IrregularityParams {
                code: 0,
                seed: 0,
                lambda_min: 0.0,
                lambda_max: 0.0,
                length: 0.0,
                scale: 0.0,
                fade_in: 0.0,
                file: String::new(),
            },
            contact_table: String::new(),
            wheel_profile: String::new(),
            rail_profile: String::new(),
            run: None,
            resource_dir: None,
            samples: None,
            outputs: OnceCell::new(),
            v_cr: OnceCell::new(),
        }
    }

    /// A boxed model with default parameters.
    pub fn boxed() -> Box<dyn Model> {
        Box::new(Vehicle::default())
    }

    /// The state (66 values, see [`equations`]), if initialized.
    pub fn state(&self) -> Option<&State> {
        self.run.as_ref().map(|r| &r.x)
    }

    /// Overwrites the state (tests, continuation).
    pub fn set_state(&mut self, x: &State) {
        if let Some(r) = self.run.as_mut() {
            r.x = *x;
        }
        self.outputs = OnceCell::new();
    }

    /// The static load of one wheel (N): the car's weight / 8.
    pub fn static_wheel_load(&self) -> f64 {
        self.p.weight() / 8.0
    }

    /// Current time (s), 0 before the initialization.
    pub fn time(&self) -> f64 {
        self.run.as_ref().map_or(0.0, |r| r.t)
    }

    /// Speed (m/s) now.
    pub fn speed(&self) -> f64 {
        self.run.as_ref().map_or(self.v, |r| r.course.speed(r.t))
    }

    /// Distance (m) run by the car body centre.
    pub fn distance(&self) -> f64 {
        self.run.as_ref().map_or(0.0, |r| r.course.distance(r.t))
    }

    fn x_at(&self, i: usize) -> f64 {
        self.run.as_ref().map_or(0.0, |r| r.x[i])
    }

    /// The outputs at the current time (zero before the initialization).
    pub fn outputs(&self) -> &Outputs {
        self.outputs.get_or_init(|| match &self.run {
            None => Outputs::default(),
            Some(r) => {
                let track = track::track_at(&r.course, &r.irregularity, &r.offsets, r.t)
                    .unwrap_or_default();
                outputs::outputs(
                    &r.car,
                    &r.spline,
                    &track,
                    &r.x,
                    self.static_wheel_load(),
                    self.h_floor,
                )
            }
        })
    }

    /// The envelopes over wheelsets and wheels: largest |y| of the wheelsets (m), largest Y/Q,
    /// largest |ΣY| (N), largest ΔQ/Q.
    fn envelope(&self) -> (f64, f64, f64, f64) {
        let o = self.outputs();
        let max = |it: &mut dyn Iterator<Item = f64>| it.fold(f64::NEG_INFINITY, f64::max);
        let y = max(&mut (0..4).map(|w| self.x_at(base(wheelset(w)) + dof::Y).abs()));
        let yq = max(&mut o.yq.iter().flatten().copied());
        let sum_y = max(&mut o.sum_y.iter().map(|s| s.abs()));
        let dqq = max(&mut o.dqq.iter().flatten().copied());
        (y, yq, sum_y, dqq)
    }

    /// The linear critical speed (m/s) at the current parameters, computed on first use.
    pub fn v_cr_linear(&self) -> Result<f64, ModelError> {
        self.v_cr
            .get_or_init(|| {
                let (spline, car) = match &self.run {
                    Some(r) => (r.spline.clone(), r.car.clone()),
                    None => {
                        let (_, spline) = self.load_table().map_err(|e| e.to_string())?;
                        let car = Car::new(self.p, &spline);
                        (spline, car)
                    }
                };
                use stability::NoCrossing;
                match stability::linear_critical_speed(&car, &spline) {
                    Ok(v) => Ok(v),
                    Err(NoCrossing::StableThroughout) => Ok(stability::SCAN_TO),
                    Err(NoCrossing::UnstableFromTheStart) => Ok(stability::SCAN_FROM),
                    Err(e) => Err(e.to_string()),
                }
            })
            .clone()
            .map_err(|e| ModelError::Other(format!("v_cr_linear: {e}")))
    }

    /// The irregularity of the parameters; random samples are reused while their key holds.
    fn build_irregularity(&mut self, x_lead: f64) -> Result<Irregularity, ModelError> {
        let i = &self.irr;
        let source = match i.code {
            0 => Source::None,
            2 | 3 => {
                let (spectrum, factor) = track::german(i.code).expect("code 2 or 3");
                if i.lambda_min >= i.lambda_max {
                    return Err(INFO.invalid(
                        VR_LAMBDA_MIN,
                        i.lambda_min,
                        format!("must be below lambda_max = {} m", i.lambda_max),
                    ));
                }
                let key = SampleKey {
                    spectrum,
                    lambda_min: i.lambda_min,
                    lambda_max: i.lambda_max,
                    length: i.length,
                    seed: i.seed,
                };
                let samples = match &self.samples {
                    Some((v, l)) if v.key == key => (v.clone(), l.clone()),
                    _ => {
                        let gen = |k| RandomProfile::generate(k).map(Arc::new);
                        let v =
                            gen(key).map_err(|e| INFO.invalid(VR_LAMBDA_MIN, i.lambda_min, e))?;
                        let l = gen(track::lateral_key(key))
                            .map_err(|e| INFO.invalid(VR_LAMBDA_MIN, i.lambda_min, e))?;
                        (v, l)
                    }
                };
                self.samples = Some(samples.clone());
                Source::Random {
                    lateral: samples.1,
                    lateral_factor: factor,
                    vertical: samples.0,
                }
            }
            10 => {
                if i.file.is_empty() {
                    return Err(INFO.invalid(
                        VR_IRREGULARITY_FILE,
                        "",
                        "irregularity = 10 (measured) needs irregularity_file, a file of x, y, z [m]",
                    ));
                }
                let text =
                    read_data_file("irregularity_file", &i.file, self.resource_dir.as_deref())
                        .map_err(ModelError::Other)?;
                let shown = resolve(&i.file, self.resource_dir.as_deref());
                let m = MeasuredTrack::parse(&text).map_err(|e| {
                    ModelError::Other(format!("irregularity_file '{}': {e}", shown.display()))
                })?;
                Source::Measured(Arc::new(m))
            }
            _ => unreachable!("the variable table refuses other codes"),
        };
        let i = &self.irr;
        Ok(Irregularity {
            source,
            scale: i.scale,
            fade_start: x_lead,
            fade_length: i.fade_in,
        })
    }

    fn step_error(&self, t: f64, e: StepError) -> ModelError {
        match e {
            StepError::Derailment(d) => ModelError::EndOfSimulation {
                time: t,
                reason: format!(
                    "derailment: wheelset {} reached a lateral displacement of {:.3} mm \
                     relative to the track, beyond the contact table (|y| <= {:.3} mm)",
                    d.wheelset + 1,
                    d.y * 1e3,
                    self.run
                        .as_ref()
                        .map_or(f64::NAN, |r| r.spline.limit() * 1e3)
                ),
            },
            StepError::OffTrack(x) => ModelError::EndOfSimulation {
                time: t,
                reason: format!(
                    "a wheelset reached x = {x:.3} m, beyond the end of irregularity_file"
                ),
            },
        }
    }
}

/// Format version of [`Model::save`] (2: the parameters include `roll_moment`).
const STATE_VERSION: u64 = 2;

impl Model for Vehicle {
    fn info(&self) -> &'static ModelInfo {
        &INFO
    }

    table_accessors!(TABLE; get_integer -> i32, get_string -> String);

    fn set_integer(&mut self, vr: u32, value: i32) -> SetResult {
        let warning = TABLE.set_integer(self, vr, value)?;
        // `roll_moment` changes the linearised car.
        self.v_cr = OnceCell::new();
        Ok(warning)
    }

    fn get_real(&self, vr: u32) -> Result<f64, ModelError> {
        if vr == VR_V_CR_LINEAR {
            return self.v_cr_linear();
        }
        TABLE.get_real(self, vr)
    }

    fn set_real(&mut self, vr: u32, value: f64) -> SetResult {
        // A new speed takes effect from now: the ramp (if any) restarts from it.
        let (t, x) = (self.time(), self.distance());
        let warning = TABLE.set_real(self, vr, value)?;
        if vr == VR_V {
            if let Some(r) = self.run.as_mut() {
                r.course.v = value;
                r.course.t_v = t;
                r.course.x_v = x;
            }
        }
        self.outputs = OnceCell::new();
        self.v_cr = OnceCell::new();
        Ok(warning)
    }

    fn set_string(&mut self, vr: u32, value: &str) -> SetResult {
        let warning = TABLE.set_string(self, vr, value)?;
        self.v_cr = OnceCell::new();
        Ok(warning)
    }

    fn initialize(&mut self, ctx: &InitContext) -> Result<(), ModelError> {
        self.resource_dir = ctx.resource_dir.clone();
        self.run = None;
        self.outputs = OnceCell::new();
        self.v_cr = OnceCell::new();
        let (table, spline) = self.load_table()?;
        for (w, &y) in self.y0.iter().enumerate() {
            if y.abs() >= spline.limit() {
                return Err(INFO.invalid(
                    VR_Y0_W1 + w as u32,
                    y,
                    format!(
                        "must lie inside the contact table, |y| < {} m",
                        spline.limit()
                    ),
                ));
            }
        }
        let car = Car::new(self.p, &spline);
        if let Some(name) = car.zero_length_link() {
            return Err(ModelError::Other(format!(
                "the {name} has no length along its axis: check the geometry parameters"
            )));
        }
        let offsets: [f64; 4] = std::array::from_fn(|w| self.p.wheelset_x(w));
        let irregularity = self.build_irregularity(offsets[0])?;
        let course = Course {
            v: self.v,
            ramp: self.ramp,
            t_v: ctx.start_time,
            x_v: 0.0,
            kappa: if self.radius == 0.0 {
                0.0
            } else {
                1.0 / self.radius
            },
            cant: self.cant,
            transition: self.transition,
            t_start: ctx.start_time,
        };
        if let Source::Measured(m) = &irregularity.source {
            let (lo, hi) = m.range();
            if offsets[3] < lo || offsets[0] > hi {
                return Err(ModelError::Other(format!(
                    "irregularity_file covers x = {lo} .. {hi} m but the wheelsets start at \
                     x = {} .. {} m",
                    offsets[3], offsets[0]
                )));
            }
        }
        let mut x = [0.0; N_STATES];
        for w in 0..4 {
            x[base(wheelset(w)) + dof::Y] = self.y0[w];
        }
        self.run = Some(Run {
            bound: RateBound::new(&self.p, &spline),
            car,
            table,
            spline,
            course,
            irregularity,
            offsets,
            t: ctx.start_time,
            x,
        });
        Ok(())
    }

    fn do_step(&mut self, t: f64, h: f64) -> Result<(), ModelError> {
        let run = self
            .run
            .as_ref()
            .ok_or_else(|| ModelError::Other("do_step before initialize".into()))?;
        let (v_begin, v_end) = (run.course.speed(t), run.course.speed(t + h));
        if v_begin.min(v_end) <= MIN_SPEED {
            let (when, v) = if v_begin <= MIN_SPEED {
                (t, v_begin)
            } else {
                (t + h, v_end)
            };
            return Err(ModelError::EndOfSimulation {
                time: t,
                reason: format!(
                    "the running speed reaches {v} m/s at t = {when} s, at or below \
                     {MIN_SPEED} m/s (the creepages divide by the speed)"
                ),
            });
        }
        let rate = run.bound.at(v_begin.min(v_end));
        let n = substeps(h, self.dt.min(STABILITY_FACTOR / rate))?;
        let sub = h / n as f64;
        let mut x = run.x;
        let track_at = |tau: f64| {
            track::track_at(&run.course, &run.irregularity, &run.offsets, tau)
                .map_err(|e| StepError::OffTrack(e.x))
        };
        for i in 0..n {
            if let Err(e) = rk4_substep(
                &run.car,
                &run.spline,
                &track_at,
                t + i as f64 * sub,
                &mut x,
                sub,
            ) {
                return Err(self.step_error(t, e));
            }
        }
        if let Some(i) = x.iter().position(|v| !v.is_finite()) {
            return Err(ModelError::SolverFailure {
                time: t + h,
                reason: format!("state {i} of 66 became non-finite"),
            });
        }
        let run = self.run.as_mut().expect("checked above");
        run.x = x;
        run.t = t + h;
        self.outputs = OnceCell::new();
        Ok(())
    }

    fn save(&self, out: &mut StateWriter) {
        TABLE.save_head(self, STATE_VERSION, self.resource_dir.as_deref(), out);
        match &self.run {
            None => out.u64(0),
            Some(r) => {
                out.u64(1);
                let c = &r.course;
                out.f64s(&[r.t, c.v, c.ramp, c.t_v, c.x_v, c.t_start]);
                out.f64s(&r.x);
                let rows: Vec<f64> = r.table.rows().iter().flat_map(|row| row.values()).collect();
                out.f64s(&rows);
            }
        }
    }

    fn restore(&mut self, input: &mut StateReader<'_>) -> Result<(), ModelError> {
        let mut m = Vehicle {
            samples: self.samples.clone(),
            ..Vehicle::default()
        };
        m.resource_dir = TABLE.restore_head(&mut m, STATE_VERSION, input)?;
        match input.u64()? {
            0 => {}
            1 => {
                let head = input.f64s(Some(6))?;
                let x = input.f64s(Some(N_STATES))?;
                let values = input.f64s(None)?;
                if values.is_empty() || values.len() % 12 != 0 {
                    return Err(ModelError::CorruptState(
                        "contact table of the state".into(),
                    ));
                }
                let rows = values
                    .chunks(12)
                    .map(|c| TableRow::from_values(c.try_into().expect("12 values")))
                    .collect();
                let table = ContactTable::from_rows(rows)
                    .map_err(|e| ModelError::CorruptState(format!("contact table: {e}")))?;
                // Rebuild the run as the initialization would, then put the saved state in.
                let start = head[5];
                let spline = Arc::new(ContactSpline::new(&table));
                let car = Car::new(m.p, &spline);
                let offsets: [f64; 4] = std::array::from_fn(|w| m.p.wheelset_x(w));
                let irregularity = m.build_irregularity(offsets[0])?;
                let course = Course {
                    v: head[1],
                    ramp: head[2],
                    t_v: head[3],
                    x_v: head[4],
                    kappa: if m.radius == 0.0 { 0.0 } else { 1.0 / m.radius },
                    cant: m.cant,
                    transition: m.transition,
                    t_start: start,
                };
                m.run = Some(Run {
                    bound: RateBound::new(&m.p, &spline),
                    car,
                    table: Arc::new(table),
                    spline,
                    course,
                    irregularity,
                    offsets,
                    t: head[0],
                    x: x.try_into().expect("66 values"),
                });
            }
            _ => return Err(ModelError::CorruptState("bad initialization flag".into())),
        }
        *self = m;
        Ok(())
    }
}

#[cfg(test)]
mod tests;
