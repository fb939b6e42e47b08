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
pub mod fft;
pub mod irregularity;
pub mod track;
pub mod vehicle;

use super::{
    require_finite, require_non_negative, require_positive, Causality, InitContext, Initial, Model,
    ModelError, ModelInfo, SetResult, Start, StateReader, StateWriter, VarType, Variability,
    Variable,
};
use crate::solver::substeps;
use crate::solver::zhai::Zhai;
use contact::{hertz_constant, Contact, ContactLaw};
use irregularity::{
    Dip, Excitation, Irregularity, IrregularityKind, MeasuredProfile, RandomProfile, SampleKey,
};
use std::path::PathBuf;
use std::sync::Arc;
use track::{Track, TrackParams};
use vehicle::{HalfVehicle, NV, ZW1};

/// Closest a wheel may come to an end of the computing window (m).
pub const MIN_END_MARGIN: f64 = 5.0;

// Value references. Real parameters 0..=36, Integer 40..=45, String 46, calculated 50..=52,
// outputs 100..
const VR_MC: u32 = 0;
const VR_MT: u32 = 1;
const VR_MW: u32 = 2;
const VR_JC: u32 = 3;
const VR_JT: u32 = 4;
const VR_KPZ: u32 = 5;
const VR_CPZ: u32 = 6;
const VR_KSZ: u32 = 7;
const VR_CSZ: u32 = 8;
const VR_LC: u32 = 9;
const VR_LT: u32 = 10;
const VR_V: u32 = 11;
const VR_G: u32 = 12;
const VR_R: u32 = 13;
const VR_MR: u32 = 14;
const VR_EI: u32 = 15;
const VR_MS: u32 = 16;
const VR_MB: u32 = 17;
const VR_KP: u32 = 18;
const VR_CP: u32 = 19;
const VR_KB: u32 = 20;
const VR_CB: u32 = 21;
const VR_KF: u32 = 22;
const VR_CF: u32 = 23;
const VR_KW: u32 = 24;
const VR_CW: u32 = 25;
const VR_LS: u32 = 26;
const VR_DT: u32 = 27;
const VR_X_START: u32 = 28;
const VR_DIP_X0: u32 = 29;
const VR_DIP_LENGTH: u32 = 30;
const VR_DIP_DEPTH: u32 = 31;
const VR_LAMBDA_MIN: u32 = 32;
const VR_LAMBDA_MAX: u32 = 33;
const VR_IRR_LENGTH: u32 = 34;
const VR_RAMP_LENGTH: u32 = 35;
const N_REAL_PARAMS: u32 = 36;
const VR_N_SLEEPERS: u32 = 40;
const VR_N_MODES: u32 = 41;
const VR_CONTACT_LAW: u32 = 42;
const VR_IRREGULARITY: u32 = 43;
const VR_SEED: u32 = 44;
const VR_MOVING_WINDOW: u32 = 45;
const VR_PROFILE_FILE: u32 = 46;
const VR_HERTZ_G: u32 = 50;
const VR_TRACK_LENGTH: u32 = 51;
const VR_P_STATIC: u32 = 52;
const VR_ZC: u32 = 100;
const VR_ZC_ACC: u32 = 101;
const VR_BETA_C: u32 = 102;
const VR_BETA_C_ACC: u32 = 103;
const VR_ZT1: u32 = 104;
const VR_BETA_T1: u32 = 105;
const VR_ZT2: u32 = 106;
const VR_BETA_T2: u32 = 107;
const VR_ZW1: u32 = 108; // ..111
const VR_P1: u32 = 112; // ..115
const VR_ZR1: u32 = 116; // ..119
const VR_Z0_1: u32 = 120;
const VR_X: u32 = 121;

use Variability::{Fixed, Tunable};

const fn real(
    name: &'static str,
    vr: u32,
    start: f64,
    variability: Variability,
    unit: &'static str,
    description: &'static str,
) -> Variable {
    Variable::real_parameter(name, vr, start, variability, Some(unit), description)
}

const fn integer(name: &'static str, vr: u32, start: i32, description: &'static str) -> Variable {
    Variable::integer_parameter(name, vr, start, description)
}

const fn calculated(
    name: &'static str,
    vr: u32,
    unit: Option<&'static str>,
    description: &'static str,
) -> Variable {
    Variable::calculated_parameter(name, vr, unit, description)
}

const fn output(
    name: &'static str,
    vr: u32,
    unit: &'static str,
    description: &'static str,
) -> Variable {
    Variable::real_output(name, vr, Some(unit), description)
}

/// Default speed: 300 km/h (m/s).
pub const DEFAULT_SPEED: f64 = 300.0 / 3.6;

/// The variable table (sorted by value reference).
pub static VARIABLES: [Variable; 68] = [
    real("Mc", VR_MC, 46_060.0, Fixed, "kg", "Carbody mass, whole car [paper]; the half model uses Mc/2"),
    real("Mt", VR_MT, 2_235.0, Fixed, "kg", "Bogie mass [paper]; halved per rail"),
    real("Mw", VR_MW, 1_457.0, Fixed, "kg", "Wheelset mass [paper]; halved per rail"),
    real("Jc", VR_JC, 1.95e6, Fixed, "kg.m2", "Carbody pitch inertia, whole car [paper]; halved per rail"),
    real("Jt", VR_JT, 1_238.0, Fixed, "kg.m2", "Bogie pitch inertia [paper]; halved per rail"),
    real("Kpz", VR_KPZ, 1.773e6, Tunable, "N/m", "Primary vertical stiffness per wheel (per side) [paper]"),
    real("Cpz", VR_CPZ, 20e3, Tunable, "N.s/m", "Primary vertical damping per wheel (per side) [paper]"),
    real("Ksz", VR_KSZ, 0.8e6, Tunable, "N/m", "Secondary vertical stiffness per bogie side [paper]"),
    real("Csz", VR_CSZ, 120e3, Tunable, "N.s/m", "Secondary vertical damping per bogie side [paper]"),
    real("Lc", VR_LC, 8.6875, Fixed, "m", "Half distance between bogie centres [paper]"),
    real("Lt", VR_LT, 1.25, Fixed, "m", "Half wheelbase of a bogie [paper]"),
    real("v", VR_V, DEFAULT_SPEED, Fixed, "m/s", "Running speed (300 km/h) [paper]"),
    real("g", VR_G, 9.8, Fixed, "m/s2", "Gravity [paper]"),
    real("R", VR_R, 0.43, Fixed, "m", "Wheel rolling radius, sets the Hertz constant G [assumed]"),
    real("mr", VR_MR, 60.64, Fixed, "kg/m", "Rail mass per metre [paper]"),
    real("EI", VR_EI, 6.6e6, Fixed, "N.m2", "Rail bending stiffness [paper]"),
    real("Ms", VR_MS, 125.5, Fixed, "kg", "Half-sleeper mass [paper]"),
    real("Mb", VR_MB, 310.0, Fixed, "kg", "Ballast block mass under one rail seat [paper]"),
    real("Kp", VR_KP, 60e6, Fixed, "N/m", "Rail pad stiffness (60 kN/mm) [paper]"),
    real("Cp", VR_CP, 75e3, Fixed, "N.s/m", "Rail pad damping [paper]"),
    real("Kb", VR_KB, 150e6, Fixed, "N/m", "Ballast stiffness (150 kN/mm) [paper]"),
    real("Cb", VR_CB, 60e3, Fixed, "N.s/m", "Ballast damping [paper]"),
    real("Kf", VR_KF, 70e6, Fixed, "N/m", "Subgrade stiffness (70 kN/mm) [paper]"),
    real("Cf", VR_CF, 100e3, Fixed, "N.s/m", "Subgrade damping [paper]"),
    real("Kw", VR_KW, 78e6, Fixed, "N/m", "Ballast shear stiffness between neighbouring blocks [lit]"),
    real("Cw", VR_CW, 80e3, Fixed, "N.s/m", "Ballast shear damping [lit]"),
    real("ls", VR_LS, 0.6, Fixed, "m", "Sleeper spacing [paper]"),
    real("dt", VR_DT, 1e-4, Fixed, "s", "Largest integration step; communication steps are split into equal substeps <= dt [assumed]"),
    real("x_start", VR_X_START, 0.0, Fixed, "m", "Track position of the carbody centre at the start time [assumed]"),
    real("dip_x0", VR_DIP_X0, 25.0, Fixed, "m", "Track position where the rail dip starts [assumed]"),
    real("dip_length", VR_DIP_LENGTH, 0.3, Fixed, "m", "Length L of the cosine rail dip [assumed]"),
    real("dip_depth", VR_DIP_DEPTH, 0.0, Fixed, "m", "Depth d of the cosine rail dip; 0 = no dip (default) [assumed]"),
    real("lambda_min", VR_LAMBDA_MIN, 2.0, Fixed, "m", "Shortest wavelength of the random irregularity [lit: TB/T 3352 range]"),
    real("lambda_max", VR_LAMBDA_MAX, 200.0, Fixed, "m", "Longest wavelength of the random irregularity [lit: TB/T 3352 range]"),
    real("irregularity_length", VR_IRR_LENGTH, 4096.0, Fixed, "m", "Length of the random irregularity sample; it repeats beyond [assumed]"),
    real("ramp_length", VR_RAMP_LENGTH, 20.0, Fixed, "m", "Irregularity fades in over this length ahead of the leading wheel's start position; 0 = none [assumed]"),
    integer("n_sleepers", VR_N_SLEEPERS, 255, "Sleepers in the computing window N (N + 1 a power of two: 63, 127, 255, 511, ...) [assumed]"),
    integer("n_modes", VR_N_MODES, 255, "Rail modes NM, 1..2N+1; default N: shortest modal wavelength 2 l/NM = 2 ls [assumed]"),
    integer("contact_law", VR_CONTACT_LAW, 0, "0 = nonlinear Hertz, 1 = Hertz linearised at the static load"),
    integer("irregularity", VR_IRREGULARITY, 1, "0 none, 1 Chinese ballastless TB/T 3352-2014 (default), 2 German low, 3 German high, 4..9 FRA class 1..6, 10 measured profile_file"),
    integer("seed", VR_SEED, 1, "Seed of the random phases of the irregularity sample"),
    integer("moving_window", VR_MOVING_WINDOW, 1, "1 = the computing window follows the vehicle; 0 = fixed window (error when a wheel nears its end)"),
    Variable {
        name: "profile_file",
        vr: VR_PROFILE_FILE,
        start: Start::String(Some("")),
        causality: Causality::Parameter,
        variability: Fixed,
        initial: Some(Initial::Exact),
        unit: None,
        min: None,
        description: "CSV of x [m], z [m] (z positive down) for irregularity = 10; a relative path is resolved in the FMU resources folder",
    },
    calculated("G", VR_HERTZ_G, None, "Hertz constant G = 4.57e-8 R^-0.149 in m/N^(2/3)"),
    calculated("track_length", VR_TRACK_LENGTH, Some("m"), "Computing length l = (n_sleepers + 1) ls"),
    calculated("P_static", VR_P_STATIC, Some("N"), "Static wheel load g (Mc/8 + Mt/4 + Mw/2)"),
    output("Zc", VR_ZC, "m", "Carbody vertical displacement (down)"),
    output("Zc_acc", VR_ZC_ACC, "m/s2", "Carbody vertical acceleration, from the equations of motion"),
    output("beta_c", VR_BETA_C, "rad", "Carbody pitch"),
    output("beta_c_acc", VR_BETA_C_ACC, "rad/s2", "Carbody pitch acceleration"),
    output("Zt1", VR_ZT1, "m", "Front bogie vertical displacement"),
    output("beta_t1", VR_BETA_T1, "rad", "Front bogie pitch"),
    output("Zt2", VR_ZT2, "m", "Rear bogie vertical displacement"),
    output("beta_t2", VR_BETA_T2, "rad", "Rear bogie pitch"),
    output("Zw1", VR_ZW1, "m", "Wheelset 1 (leading) vertical displacement"),
    output("Zw2", VR_ZW1 + 1, "m", "Wheelset 2 vertical displacement"),
    output("Zw3", VR_ZW1 + 2, "m", "Wheelset 3 vertical displacement"),
    output("Zw4", VR_ZW1 + 3, "m", "Wheelset 4 vertical displacement"),
    output("P1", VR_P1, "N", "Wheel-rail force, wheel 1 (0 when the wheel is off the rail)"),
    output("P2", VR_P1 + 1, "N", "Wheel-rail force, wheel 2"),
    output("P3", VR_P1 + 2, "N", "Wheel-rail force, wheel 3"),
    output("P4", VR_P1 + 3, "N", "Wheel-rail force, wheel 4"),
    output("Zr1", VR_ZR1, "m", "Rail displacement under wheel 1"),
    output("Zr2", VR_ZR1 + 1, "m", "Rail displacement under wheel 2"),
    output("Zr3", VR_ZR1 + 2, "m", "Rail displacement under wheel 3"),
    output("Zr4", VR_ZR1 + 3, "m", "Rail displacement under wheel 4"),
    output("Z0_1", VR_Z0_1, "m", "Rail profile under wheel 1: irregularity plus dip (down)"),
    output("x", VR_X, "m", "Track position of the carbody centre"),
];

/// Static description of the vehicle–track model.
pub static INFO: ModelInfo = ModelInfo {
    name: "VehicleTrack",
    description: "Vertical vehicle-track coupled model after Zhai: 10-DOF half car, Hertz contact, modal rail on sleepers and ballast (railuq, paper section 5)",
    variables: &VARIABLES,
    default_start: 0.0,
    default_stop: 10.0,
    default_step: 0.002,
    documentation_html: include_str!("doc.html"),
};

/// All parameters (SI units; whole-car vehicle values as in the paper).
#[derive(Clone, Debug, PartialEq)]
pub struct Params {
    /// Real parameters indexed by value reference 0..36.
    pub reals: [f64; N_REAL_PARAMS as usize],
    /// Number of sleepers N.
    pub n_sleepers: i32,
    /// Number of rail modes NM.
    pub n_modes: i32,
    /// Contact law code.
    pub contact_law: i32,
    /// Irregularity code.
    pub irregularity: i32,
    /// Seed.
    pub seed: i32,
    /// Moving window flag.
    pub moving_window: i32,
    /// Measured profile path.
    pub profile_file: String,
}

impl Default for Params {
    fn default() -> Self {
        let mut reals = [0.0; N_REAL_PARAMS as usize];
        for v in VARIABLES.iter().filter(|v| v.vr < N_REAL_PARAMS) {
            if let Start::Real(Some(s)) = v.start {
                reals[v.vr as usize] = s;
            }
        }
        Self {
            reals,
            n_sleepers: 255,
            n_modes: 255,
            contact_law: 0,
            irregularity: 1,
            seed: 1,
            moving_window: 1,
            profile_file: String::new(),
        }
    }
}

impl Params {
    fn r(&self, vr: u32) -> f64 {
        self.reals[vr as usize]
    }

    /// The half vehicle (masses and inertias halved).
    pub fn half_vehicle(&self) -> HalfVehicle {
        HalfVehicle {
            mc: 0.5 * self.r(VR_MC),
            jc: 0.5 * self.r(VR_JC),
            mt: 0.5 * self.r(VR_MT),
            jt: 0.5 * self.r(VR_JT),
            mw: 0.5 * self.r(VR_MW),
            kpz: self.r(VR_KPZ),
            cpz: self.r(VR_CPZ),
            ksz: self.r(VR_KSZ),
            csz: self.r(VR_CSZ),
            lc: self.r(VR_LC),
            lt: self.r(VR_LT),
            g: self.r(VR_G),
        }
    }

    /// Track parameters.
    pub fn track(&self) -> TrackParams {
        TrackParams {
            mr: self.r(VR_MR),
            ei: self.r(VR_EI),
            ms: self.r(VR_MS),
            mb: self.r(VR_MB),
            kp: self.r(VR_KP),
            cp: self.r(VR_CP),
            kb: self.r(VR_KB),
            cb: self.r(VR_CB),
            kf: self.r(VR_KF),
            cf: self.r(VR_CF),
            kw: self.r(VR_KW),
            cw: self.r(VR_CW),
            ls: self.r(VR_LS),
            n_sleepers: self.n_sleepers.max(0) as usize,
            n_modes: self.n_modes.max(0) as usize,
        }
    }

    fn static_load(&self) -> f64 {
        self.half_vehicle().static_forces().p[0]
    }
}

/// What a Real parameter must satisfy.
enum Rule {
    Positive,
    NonNegative,
    Finite,
}

fn rule(vr: u32) -> Rule {
    match vr {
        VR_CPZ | VR_CSZ | VR_CP | VR_CB | VR_CF | VR_CW | VR_KW | VR_V | VR_DIP_LENGTH
        | VR_RAMP_LENGTH | VR_G => Rule::NonNegative,
        VR_X_START | VR_DIP_X0 | VR_DIP_DEPTH => Rule::Finite,
        _ => Rule::Positive,
    }
}

/// Values the equations report besides the state (refreshed at each force evaluation).
#[derive(Clone, Copy, Debug, Default)]
struct Diag {
    p: [f64; 4],
    zr: [f64; 4],
    z0: [f64; 4],
}

/// Geometry of the running vehicle on the window.
#[derive(Clone, Copy, Debug)]
struct Run {
    /// Track position of the carbody centre (m).
    xc: f64,
    /// Track position of the window's left support (m), a multiple of l_s.
    x_win: f64,
    /// Wheel offsets from the carbody centre (m).
    offsets: [f64; 4],
}

/// Simulation data built by `initialize` (or `restore`).
#[derive(Clone, Debug)]
struct Sim {
    track: Track,
    contact: Contact,
    exc: Excitation,
    zhai: Zhai,
    time: f64,
    run: Run,
    /// Largest drift of the carbody from the window centre before the window moves (m).
    shift_trigger: f64,
    /// Largest drift allowed at all (m).
    max_drift: f64,
    diag: Diag,
}

/// Accelerations of the whole system `a = M⁻¹F(x, v)` with the vehicle at `run`.
#[allow(clippy::too_many_arguments)]
fn accelerations(
    hv: &HalfVehicle,
    track: &mut Track,
    contact: &Contact,
    exc: &Excitation,
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

/// The vehicle–track model.
#[derive(Clone, Debug, Default)]
pub struct VehicleTrack {
    /// Parameters.
    pub p: Params,
    sim: Option<Sim>,
    resource_dir: Option<PathBuf>,
    /// Last random sample, reused while its key does not change.
    sample_cache: Option<Arc<RandomProfile>>,
}

impl VehicleTrack {
    /// A boxed model with default parameters.
    pub fn boxed() -> Box<dyn Model> {
        Box::new(VehicleTrack::default())
    }

    fn invalid(vr: u32, value: impl ToString, reason: impl Into<String>) -> ModelError {
        ModelError::InvalidValue {
            name: INFO.variable(vr).map_or("?", |v| v.name),
            value: value.to_string(),
            reason: reason.into(),
        }
    }

    /// Builds track, contact and excitation from the parameters (no equilibrium yet).
    fn build(&mut self, start_time: f64) -> Result<Sim, ModelError> {
        let p = &self.p;
        let hv = p.half_vehicle();
        let track =
            Track::new(p.track()).map_err(|e| Self::invalid(VR_N_SLEEPERS, p.n_sleepers, e))?;
        let law = ContactLaw::from_code(p.contact_law)
            .ok_or_else(|| Self::invalid(VR_CONTACT_LAW, p.contact_law, "must be 0 or 1"))?;
        let contact = Contact::new(law, hertz_constant(p.r(VR_R)), p.static_load());
        let kind = IrregularityKind::from_code(p.irregularity)
            .ok_or_else(|| Self::invalid(VR_IRREGULARITY, p.irregularity, "must be 0..10"))?;
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
                    _ => Arc::new(
                        RandomProfile::generate(key)
                            .map_err(|e| Self::invalid(VR_LAMBDA_MIN, p.r(VR_LAMBDA_MIN), e))?,
                    ),
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
        let exc = Excitation {
            irregularity,
            dip: Dip {
                x0: p.r(VR_DIP_X0),
                length: p.r(VR_DIP_LENGTH),
                depth: p.r(VR_DIP_DEPTH),
            },
            ramp_start: p.r(VR_X_START) + offsets[0],
            ramp_length: p.r(VR_RAMP_LENGTH),
        };
        let (ls, l) = (p.r(VR_LS), track.length);
        let span = offsets[0].max(-offsets[3]);
        let max_drift = 0.5 * l - span - MIN_END_MARGIN;
        if max_drift < ls {
            return Err(Self::invalid(
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
    fn equilibrate(&self, sim: &mut Sim) -> Result<(), ModelError> {
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
        let Sim {
            track,
            contact,
            exc,
            zhai,
            diag,
            ..
        } = sim;
        zhai.init_accel(|x, v, a| -> Result<(), ModelError> {
            accelerations(&hv, track, contact, exc, &run, x, v, a, diag);
            Ok(())
        })?;
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

    fn sim(&self) -> Option<&Sim> {
        self.sim.as_ref()
    }

    fn output(&self, vr: u32) -> f64 {
        let Some(s) = self.sim() else { return 0.0 };
        let x = &s.zhai.x;
        match vr {
            VR_ZC => x[vehicle::ZC],
            VR_ZC_ACC => s.zhai.a[vehicle::ZC],
            VR_BETA_C => x[vehicle::BC],
            VR_BETA_C_ACC => s.zhai.a[vehicle::BC],
            VR_ZT1 => x[vehicle::ZT1],
            VR_BETA_T1 => x[vehicle::BT1],
            VR_ZT2 => x[vehicle::ZT2],
            VR_BETA_T2 => x[vehicle::BT2],
            v if (VR_ZW1..VR_ZW1 + 4).contains(&v) => x[ZW1 + (v - VR_ZW1) as usize],
            v if (VR_P1..VR_P1 + 4).contains(&v) => s.diag.p[(v - VR_P1) as usize],
            v if (VR_ZR1..VR_ZR1 + 4).contains(&v) => s.diag.zr[(v - VR_ZR1) as usize],
            VR_Z0_1 => s.diag.z0[0],
            VR_X => s.run.xc,
            _ => f64::NAN,
        }
    }

    /// Moves the window forward by whole sleepers if the carbody has drifted far enough.
    fn follow(&self, sim: &mut Sim) {
        let ls = self.p.r(VR_LS);
        let drift = sim.run.xc - sim.run.x_win - 0.5 * sim.track.length;
        if drift < sim.shift_trigger {
            return;
        }
        let m = (drift / ls).round() as usize;
        for arr in [&mut sim.zhai.x, &mut sim.zhai.v, &mut sim.zhai.a_prev] {
            sim.track.shift(m, &mut arr[NV..]);
        }
        sim.run.x_win += m as f64 * ls;
        let hv = self.p.half_vehicle();
        let Sim {
            track,
            contact,
            exc,
            zhai,
            diag,
            run,
            ..
        } = sim;
        let run = *run;
        let _ = zhai.init_accel(|x, v, a| -> Result<(), ModelError> {
            accelerations(&hv, track, contact, exc, &run, x, v, a, diag);
            Ok(())
        });
    }

    /// The wheels' track positions over [xc, xc_end] must stay on the window and the profile.
    fn check_reach(&self, sim: &Sim, xc_end: f64) -> Result<(), ModelError> {
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

    fn save_params(&self, out: &mut StateWriter) {
        let p = &self.p;
        out.f64s(&p.reals);
        out.f64s(&[
            p.n_sleepers as f64,
            p.n_modes as f64,
            p.contact_law as f64,
            p.irregularity as f64,
            p.seed as f64,
            p.moving_window as f64,
        ]);
        out.str(&p.profile_file);
        out.str(
            &self
                .resource_dir
                .as_ref()
                .map_or(String::new(), |d| d.display().to_string()),
        );
    }
}

/// Format version of [`Model::save`].
const STATE_VERSION: u64 = 1;

impl Model for VehicleTrack {
    fn info(&self) -> &'static ModelInfo {
        &INFO
    }

    fn get_real(&self, vr: u32) -> Result<f64, ModelError> {
        Ok(match vr {
            v if v < N_REAL_PARAMS => self.p.r(v),
            VR_HERTZ_G => hertz_constant(self.p.r(VR_R)),
            VR_TRACK_LENGTH => (self.p.n_sleepers as f64 + 1.0) * self.p.r(VR_LS),
            VR_P_STATIC => self.p.static_load(),
            v if (VR_ZC..=VR_X).contains(&v) => self.output(v),
            _ => return Err(ModelError::NoSuchVariable(VarType::Real, vr)),
        })
    }

    fn set_real(&mut self, vr: u32, value: f64) -> SetResult {
        if vr >= N_REAL_PARAMS {
            return Err(ModelError::NoSuchVariable(VarType::Real, vr));
        }
        let name = INFO.variable(vr).map_or("?", |v| v.name);
        match rule(vr) {
            Rule::Positive => require_positive(name, value)?,
            Rule::NonNegative => require_non_negative(name, value)?,
            Rule::Finite => require_finite(name, value)?,
        }
        self.p.reals[vr as usize] = value;
        Ok(None)
    }

    fn get_integer(&self, vr: u32) -> Result<i32, ModelError> {
        let p = &self.p;
        Ok(match vr {
            VR_N_SLEEPERS => p.n_sleepers,
            VR_N_MODES => p.n_modes,
            VR_CONTACT_LAW => p.contact_law,
            VR_IRREGULARITY => p.irregularity,
            VR_SEED => p.seed,
            VR_MOVING_WINDOW => p.moving_window,
            _ => return Err(ModelError::NoSuchVariable(VarType::Integer, vr)),
        })
    }

    fn set_integer(&mut self, vr: u32, value: i32) -> SetResult {
        let bad = |reason: &str| Err(Self::invalid(vr, value, reason));
        match vr {
            VR_N_SLEEPERS => {
                if value < 3 || !((value as u32) + 1).is_power_of_two() {
                    return bad("n_sleepers + 1 must be a power of two >= 4 (63, 127, 255, 511, 1023, ...): the fast sine transform is radix 2");
                }
                self.p.n_sleepers = value;
            }
            VR_N_MODES => {
                if value < 1 {
                    return bad("must be >= 1 (and <= 2 n_sleepers + 1)");
                }
                self.p.n_modes = value;
            }
            VR_CONTACT_LAW => {
                if ContactLaw::from_code(value).is_none() {
                    return bad("must be 0 (Hertz) or 1 (linearised Hertz)");
                }
                self.p.contact_law = value;
            }
            VR_IRREGULARITY => {
                if IrregularityKind::from_code(value).is_none() {
                    return bad("must be 0 (none), 1..9 (spectrum) or 10 (measured)");
                }
                self.p.irregularity = value;
            }
            VR_SEED => self.p.seed = value,
            VR_MOVING_WINDOW => {
                if !(value == 0 || value == 1) {
                    return bad("must be 0 or 1");
                }
                self.p.moving_window = value;
            }
            _ => return Err(ModelError::NoSuchVariable(VarType::Integer, vr)),
        }
        Ok(None)
    }

    fn get_string(&self, vr: u32) -> Result<String, ModelError> {
        match vr {
            VR_PROFILE_FILE => Ok(self.p.profile_file.clone()),
            _ => Err(ModelError::NoSuchVariable(VarType::String, vr)),
        }
    }

    fn set_string(&mut self, vr: u32, value: &str) -> SetResult {
        match vr {
            VR_PROFILE_FILE => {
                self.p.profile_file = value.to_string();
                Ok(None)
            }
            _ => Err(ModelError::NoSuchVariable(VarType::String, vr)),
        }
    }

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
            return Err(Self::invalid(
                VR_LAMBDA_MIN,
                lmin,
                format!("must be below lambda_max = {lmax} m"),
            ));
        }
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

    fn clone_box(&self) -> Box<dyn Model> {
        Box::new(self.clone())
    }

    fn save(&self, out: &mut StateWriter) {
        out.u64(STATE_VERSION);
        self.save_params(out);
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
        let version = input.u64()?;
        if version != STATE_VERSION {
            return Err(ModelError::CorruptState(format!(
                "state version {version}, expected {STATE_VERSION}"
            )));
        }
        let reals = input.f64s(Some(N_REAL_PARAMS as usize))?;
        let ints = input.f64s(Some(6))?;
        let profile_file = input.str()?;
        let dir = input.str()?;
        let mut p = Params {
            profile_file,
            ..Params::default()
        };
        p.reals.copy_from_slice(&reals);
        p.n_sleepers = ints[0] as i32;
        p.n_modes = ints[1] as i32;
        p.contact_law = ints[2] as i32;
        p.irregularity = ints[3] as i32;
        p.seed = ints[4] as i32;
        p.moving_window = ints[5] as i32;
        let initialized = input.u64()?;
        let mut model = VehicleTrack {
            p,
            sim: None,
            resource_dir: (!dir.is_empty()).then(|| PathBuf::from(dir)),
            sample_cache: self.sample_cache.clone(),
        };
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
            // Refresh the reported forces from the restored state.
            let hv = model.p.half_vehicle();
            let mut scratch = vec![0.0; dim];
            let run = sim.run;
            let Sim {
                track,
                contact,
                exc,
                zhai,
                diag,
                ..
            } = &mut sim;
            accelerations(
                &hv,
                track,
                contact,
                exc,
                &run,
                &zhai.x,
                &zhai.v,
                &mut scratch,
                diag,
            );
            model.sim = Some(sim);
        } else if initialized != 0 {
            return Err(ModelError::CorruptState("bad initialization flag".into()));
        }
        *self = model;
        Ok(())
    }
}

impl VehicleTrack {
    /// Advances by `h` (s) in equal substeps no longer than `dt`.
    fn advance(&self, sim: &mut Sim, h: f64) -> Result<(), ModelError> {
        let n = substeps(h, self.p.r(VR_DT));
        let hs = h / n as f64;
        let v = self.p.r(VR_V);
        self.check_reach(sim, sim.run.xc + v * h)?;
        let hv = self.p.half_vehicle();
        let moving = self.p.moving_window == 1;
        for _ in 0..n {
            if moving {
                self.follow(sim);
            }
            let mut run = sim.run;
            run.xc += v * hs;
            let Sim {
                track,
                contact,
                exc,
                zhai,
                diag,
                ..
            } = sim;
            zhai.step(hs, |x, v, a| -> Result<(), ModelError> {
                accelerations(&hv, track, contact, exc, &run, x, v, a, diag);
                Ok(())
            })?;
            sim.run = run;
            sim.time += hs;
        }
        let ok = sim.zhai.x[..NV].iter().all(|x| x.is_finite())
            && sim.zhai.a.iter().all(|a| a.is_finite())
            && sim.diag.p.iter().all(|p| p.is_finite());
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
    use super::*;

    /// A model with a small window (fast in debug builds) and no excitation.
    fn small(n: i32, nm: i32) -> VehicleTrack {
        let mut m = VehicleTrack::default();
        m.set_integer(VR_N_SLEEPERS, n).unwrap();
        m.set_integer(VR_N_MODES, nm).unwrap();
        m.set_integer(VR_IRREGULARITY, 0).unwrap();
        m
    }

    fn out(m: &VehicleTrack, vr: u32) -> f64 {
        m.get_real(vr).unwrap()
    }

    /// Runs to `stop` (s) with communication step `h`, returning (t, Zc_acc, P1..P4) rows.
    fn run(m: &mut VehicleTrack, stop: f64, h: f64) -> Vec<[f64; 6]> {
        m.initialize(&InitContext::default()).unwrap();
        let n = (stop / h).round() as usize;
        let mut rows = Vec::with_capacity(n);
        for i in 0..n {
            m.do_step(i as f64 * h, h).unwrap();
            let mut r = [(i + 1) as f64 * h, out(m, VR_ZC_ACC), 0.0, 0.0, 0.0, 0.0];
            for j in 0..4 {
                r[2 + j] = out(m, VR_P1 + j as u32);
            }
            rows.push(r);
        }
        rows
    }

    #[test]
    fn variable_table_is_sorted_unique_and_exports() {
        for w in VARIABLES.windows(2) {
            assert!(w[0].vr < w[1].vr, "{} / {}", w[0].name, w[1].name);
        }
        let mut names: Vec<_> = VARIABLES.iter().map(|v| v.name).collect();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), VARIABLES.len());
        let xml = crate::fmi2::xml::model_description(&INFO).unwrap();
        assert!(xml.contains("name=\"Kpz\"") && xml.contains("tunable"));
        // Every variable answers get_* with its type, and parameters return their start.
        let m = VehicleTrack::default();
        for v in VARIABLES.iter() {
            match v.start {
                Start::Real(start) => {
                    let x = m.get_real(v.vr).unwrap();
                    if let Some(s) = start {
                        assert_eq!(x, s, "{}", v.name);
                    }
                }
                Start::Integer(Some(s)) => assert_eq!(m.get_integer(v.vr).unwrap(), s),
                Start::String(Some(s)) => assert_eq!(m.get_string(v.vr).unwrap(), s),
                _ => unreachable!(),
            }
        }
    }

    #[test]
    fn static_equilibrium_matches_the_hand_calculation() {
        let mut m = small(127, 64);
        m.initialize(&InitContext::default()).unwrap();
        // Whole-car masses halved per rail: P = g (Mc/8 + Mt/4 + Mw/2) ≈ 69.04 kN per wheel.
        let p: f64 = 9.8 * (46_060.0 / 8.0 + 2_235.0 / 4.0 + 1_457.0 / 2.0);
        let g = 4.57e-8 * 0.43f64.powf(-0.149);
        let delta = g * p.powf(2.0 / 3.0); // ≈ 87 µm
        assert!((p - 69_038.6).abs() < 0.1 && (delta - 87.2e-6).abs() < 0.2e-6);
        for j in 0..4u32 {
            let pj = out(&m, VR_P1 + j);
            let d = out(&m, VR_ZW1 + j) - out(&m, VR_ZR1 + j); // perfect track: Z0 = 0
            assert!((pj - p).abs() < 1e-6 * p, "P{} = {pj}", j + 1);
            assert!((d - delta).abs() < 1e-12, "compression {d:e} vs {delta:e}");
        }
        assert!((out(&m, VR_P_STATIC) - p).abs() < 1e-9);
        assert!((out(&m, VR_HERTZ_G) - g).abs() < 1e-20);
        // The rail is pressed down (Z positive down) by a fraction of a millimetre.
        let zr = out(&m, VR_ZR1);
        assert!((2e-4..2e-3).contains(&zr), "rail deflection {zr}");
        assert!(out(&m, VR_ZC) > out(&m, VR_ZT1) && out(&m, VR_ZT1) > out(&m, VR_ZW1));
    }

    #[test]
    fn at_rest_on_perfect_track_it_stays_still() {
        let mut m = small(127, 64);
        m.set_real(VR_V, 0.0).unwrap();
        let rows = run(&mut m, 1.0, 0.01);
        let worst = rows.iter().map(|r| r[1].abs()).fold(0.0, f64::max);
        assert!(worst < 1e-6, "|Zc_acc| up to {worst:e} m/s2");
        let p = m.p.static_load();
        for r in &rows {
            for j in 0..4 {
                assert!((r[2 + j] - p).abs() < 1e-3, "P drifts: {}", r[2 + j]);
            }
        }
    }

    #[test]
    fn at_speed_on_perfect_track_only_sleeper_passing_remains() {
        // Discrete sleepers excite the wheels at v/l_s = 139 Hz; the suspensions filter it.
        let mut m = small(127, 64);
        let rows = run(&mut m, 0.5, 0.005);
        let tail = &rows[rows.len() / 2..];
        let acc = tail.iter().map(|r| r[1].abs()).fold(0.0, f64::max);
        let p = m.p.static_load();
        let dp = tail
            .iter()
            .flat_map(|r| r[2..].iter().map(move |x| (x - p).abs()))
            .fold(0.0, f64::max);
        eprintln!("perfect track at 300 km/h: |Zc_acc| <= {acc:e} m/s2, |P - Ps| <= {dp:.0} N");
        assert!(acc < 0.02, "carbody acceleration {acc} m/s2");
        assert!(dp < 0.1 * p, "wheel-rail force varies by {dp} N");
    }

    /// Peak P1 and Zc_acc history for a dip at (dt, NM).
    fn dip_run(n: i32, dt: f64, nm: i32, depth: f64) -> (f64, Vec<f64>, Vec<[f64; 6]>) {
        let mut m = small(n, nm);
        m.set_real(VR_DT, dt).unwrap();
        m.set_real(VR_DIP_DEPTH, depth).unwrap();
        m.set_real(VR_DIP_X0, 15.0).unwrap();
        let rows = run(&mut m, 0.12, 0.0005);
        let peak = rows.iter().map(|r| r[2]).fold(0.0, f64::max);
        (peak, rows.iter().map(|r| r[1]).collect(), rows)
    }

    #[test]
    fn dip_impact_converges_in_step_and_modes() {
        // Default window (N = 255) and modes (NM = 255, dt = 1e-4 s) against NM = 510, dt/2.
        let (p1, a1, _) = dip_run(255, 1e-4, 255, 0.3e-3);
        let (p2, a2, _) = dip_run(255, 5e-5, 510, 0.3e-3);
        // The carbody acceleration in the ride-comfort band after the start (t > 0.05 s, the
        // dip is met at 0.06 s): 10 ms moving averages remove the sleeper-passing content at
        // v/l_s = 139 Hz, which NM = N modes resolve only in part.
        let smooth = |a: &[f64]| -> Vec<f64> {
            a[100..]
                .windows(20)
                .map(|w| w.iter().sum::<f64>() / 20.0)
                .collect()
        };
        let (s1, s2) = (smooth(&a1), smooth(&a2));
        let amax = s2.iter().fold(0.0f64, |m, a| m.max(a.abs()));
        let da = s1
            .iter()
            .zip(&s2)
            .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
        let raw = a1
            .iter()
            .zip(&a2)
            .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
        let stat = VehicleTrack::default().p.static_load();
        eprintln!("peak P1 {p1:.0} N vs {p2:.0} N; max 10 ms-mean Zc_acc {amax:e}, difference {da:e} (raw {raw:e})");
        assert!(p2 > 1.2 * stat, "the dip must raise the force: {p2}");
        assert!(
            (p1 - p2).abs() < 0.01 * (p2 - stat),
            "peak force {p1} vs {p2}"
        );
        assert!(
            da < 0.03 * amax,
            "carbody acceleration differs by {da:e} of {amax:e}"
        );
    }

    #[test]
    fn a_deep_dip_at_speed_lifts_the_wheel_and_the_run_goes_on() {
        let (_, acc, rows) = dip_run(127, 1e-4, 64, 3e-3);
        let zero_rows = rows.iter().filter(|r| r[2] == 0.0).count();
        assert!(zero_rows > 0, "wheel 1 never left the rail");
        assert!(rows.iter().all(|r| r.iter().all(|v| v.is_finite())));
        assert!(rows.iter().all(|r| r[2..].iter().all(|&p| p >= 0.0)));
        assert!(acc.iter().all(|a| a.is_finite()));
        // The wheel comes back onto the rail with an impact.
        let after = rows
            .iter()
            .skip_while(|r| r[2] > 0.0)
            .skip_while(|r| r[2] == 0.0);
        let impact = after.map(|r| r[2]).fold(0.0, f64::max);
        assert!(
            impact > VehicleTrack::default().p.static_load(),
            "impact {impact}"
        );
    }

    #[test]
    fn the_moving_window_is_transparent() {
        // The default 154 m window following the vehicle (a shift every 15 m) against a
        // fixed 307 m window that holds the whole 0.4 s run, on the default random track.
        let make = |n: i32, moving: i32| {
            let mut m = small(n, n);
            m.set_integer(VR_MOVING_WINDOW, moving).unwrap();
            m.set_integer(VR_IRREGULARITY, 1).unwrap();
            m
        };
        let (mut fixed, mut moving) = (make(511, 0), make(255, 1));
        let a = run(&mut fixed, 0.4, 0.002);
        let b = run(&mut moving, 0.4, 0.002);
        let amax = a.iter().fold(0.0f64, |m, r| m.max(r[1].abs()));
        let da = a
            .iter()
            .zip(&b)
            .fold(0.0f64, |m, (x, y)| m.max((x[1] - y[1]).abs()));
        let dp = a.iter().zip(&b).fold(0.0f64, |m, (x, y)| {
            (2..6).fold(m, |m, j| m.max((x[j] - y[j]).abs()))
        });
        eprintln!("moving vs fixed: Zc_acc diff {da:e} of {amax:e}; P diff {dp:.1} N");
        let start = -0.6 * (0.5 * 153.6f64 / 0.6).round();
        assert!(
            moving.sim().unwrap().run.x_win > start + 25.0,
            "the window did not move"
        );
        assert!(da < 0.01 * amax, "Zc_acc differs by {da:e} (max {amax:e})");
        assert!(dp < 0.005 * m_static(), "P differs by {dp} N");
    }

    fn m_static() -> f64 {
        VehicleTrack::default().p.static_load()
    }

    #[test]
    fn a_fixed_window_refuses_to_run_off_its_end() {
        let mut m = small(127, 64);
        m.set_integer(VR_MOVING_WINDOW, 0).unwrap();
        m.initialize(&InitContext::default()).unwrap();
        let mut err = None;
        for i in 0..100 {
            if let Err(e) = m.do_step(i as f64 * 0.01, 0.01) {
                err = Some(e);
                break;
            }
        }
        let e = err.expect("a 77 m window cannot hold a 1 s run at 83 m/s");
        assert!(e.to_string().contains("leave the computing track"), "{e}");
    }

    #[test]
    fn refuses_bad_parameters_with_clear_messages() {
        let mut m = VehicleTrack::default();
        for (vr, v) in [
            (VR_KPZ, -1.0),
            (VR_KSZ, f64::NAN),
            (VR_KP, 0.0),
            (VR_EI, -5.0),
        ] {
            let e = m.set_real(vr, v).unwrap_err().to_string();
            assert!(e.contains(INFO.variable(vr).unwrap().name), "{e}");
        }
        assert!(m.set_real(VR_DT, 0.0).is_err());
        assert!(m.set_real(VR_DT, -1e-4).is_err());
        assert!(m.set_real(VR_CPZ, -1.0).is_err());
        assert!(m.set_real(VR_MC, f64::INFINITY).is_err());
        assert!(m.set_real(VR_CPZ, 0.0).is_ok());
        assert!(m.set_integer(VR_N_SLEEPERS, 100).is_err());
        assert!(m.set_integer(VR_N_SLEEPERS, 511).is_ok());
        assert!(m.set_integer(VR_N_MODES, 0).is_err());
        assert!(m.set_integer(VR_CONTACT_LAW, 2).is_err());
        assert!(m.set_integer(VR_IRREGULARITY, 11).is_err());
        assert!(m.set_integer(VR_MOVING_WINDOW, 2).is_err());
        assert!(m.set_real(VR_ZC, 1.0).is_err(), "outputs are not settable");
        // Combinations are checked at initialization.
        let mut m = small(63, 200);
        assert!(m.initialize(&InitContext::default()).is_err());
        let mut m = small(63, 32);
        m.set_integer(VR_IRREGULARITY, 1).unwrap();
        m.set_real(VR_LAMBDA_MIN, 300.0).unwrap();
        assert!(m.initialize(&InitContext::default()).is_err());
        let mut m = small(63, 32);
        m.set_integer(VR_IRREGULARITY, 10).unwrap();
        let e = m
            .initialize(&InitContext::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("profile_file"), "{e}");
    }

    #[test]
    fn tunable_suspension_is_read_at_every_step() {
        let mut m = small(127, 64);
        m.initialize(&InitContext::default()).unwrap();
        m.do_step(0.0, 0.01).unwrap();
        let zc0 = out(&m, VR_ZC);
        m.set_real(VR_KSZ, 0.4e6).unwrap(); // softer: the carbody sinks
        for i in 1..50 {
            m.do_step(i as f64 * 0.01, 0.01).unwrap();
        }
        assert!(out(&m, VR_ZC) > zc0 + 1e-3, "{} vs {zc0}", out(&m, VR_ZC));
    }

    #[test]
    fn save_and_restore_reproduce_the_run_exactly() {
        let mut m = small(127, 64);
        m.set_integer(VR_IRREGULARITY, 2).unwrap();
        m.initialize(&InitContext::default()).unwrap();
        for i in 0..30 {
            m.do_step(i as f64 * 0.01, 0.01).unwrap();
        }
        let mut w = StateWriter::default();
        m.save(&mut w);
        let mut copy = VehicleTrack::default();
        copy.restore(&mut StateReader::new(&w.bytes)).unwrap();
        assert_eq!(out(&copy, VR_P1), out(&m, VR_P1));
        for i in 30..60 {
            m.do_step(i as f64 * 0.01, 0.01).unwrap();
            copy.do_step(i as f64 * 0.01, 0.01).unwrap();
        }
        for vr in [VR_ZC, VR_ZC_ACC, VR_P1, VR_ZR1 + 3, VR_X] {
            assert_eq!(out(&copy, vr), out(&m, vr), "vr {vr}");
        }
        assert!(copy
            .restore(&mut StateReader::new(&w.bytes[..w.bytes.len() - 3]))
            .is_err());
    }

    #[test]
    fn measured_profile_from_the_resources_folder() {
        let dir = std::env::temp_dir().join(format!("railuq-vt-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let csv: String = (0..=400)
            .map(|i| {
                let x = -50.0 + i as f64 * 0.5;
                format!("{x},{}\n", 1e-3 * (0.2 * x).sin())
            })
            .collect();
        std::fs::write(dir.join("profile.csv"), format!("x,z\n{csv}")).unwrap();
        let mut m = small(127, 64);
        m.set_integer(VR_IRREGULARITY, 10).unwrap();
        m.set_string(VR_PROFILE_FILE, "profile.csv").unwrap();
        m.set_real(VR_RAMP_LENGTH, 0.0).unwrap();
        let ctx = InitContext {
            start_time: 0.0,
            resource_dir: Some(dir.clone()),
        };
        m.initialize(&ctx).unwrap();
        let z0 = out(&m, VR_Z0_1);
        let x1: f64 = 8.6875 + 1.25;
        assert!((z0 - 1e-3 * (0.2 * x1).sin()).abs() < 2e-6, "{z0}");
        // The profile ends at 150 m: running past it is an error, not an extrapolation.
        let mut failed = false;
        for i in 0..200 {
            if m.do_step(i as f64 * 0.01, 0.01).is_err() {
                failed = true;
                break;
            }
        }
        assert!(failed);
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn default_model_runs_on_the_default_track() {
        let mut m = VehicleTrack::default();
        let rows = run(&mut m, 0.2, 0.01);
        assert!(rows.iter().all(|r| r.iter().all(|v| v.is_finite())));
        assert!(out(&m, VR_Z0_1) != 0.0, "default irregularity is on");
        assert_eq!(out(&m, VR_TRACK_LENGTH), 153.6);
    }

    /// Real-time factor of the default model: `cargo test --release -p railuq --lib
    /// vehicle_track::tests::speed -- --ignored --nocapture`.
    #[test]
    #[ignore]
    fn speed() {
        let mut m = VehicleTrack::default();
        m.initialize(&InitContext::default()).unwrap();
        let t0 = std::time::Instant::now();
        for i in 0..500 {
            m.do_step(i as f64 * 0.002, 0.002).unwrap();
        }
        let wall = t0.elapsed().as_secs_f64();
        eprintln!(
            "1 s simulated (dt = 1e-4 s, N = 255, NM = 255) in {wall:.3} s wall: {:.1}x faster than real time",
            1.0 / wall
        );
    }
}
