//! The vehicle–track model's variables, one line each (see [`crate::models::table`]), its
//! parameter store and its description.
#![forbid(unsafe_code)]

use super::contact::{hertz_constant, ContactLaw};
use super::irregularity::IrregularityKind;
use super::track::TrackParams;
use super::vehicle::{self, HalfVehicle, ZW1};
use super::VehicleTrack;
use crate::models::table::{any_integer, any_string, finite, non_negative, positive, variables};
use crate::models::{ModelError, ModelInfo, SetResult};

/// Default speed: 300 km/h (m/s).
pub const DEFAULT_SPEED: f64 = 300.0 / 3.6;

/// Slots of the Real-parameter store: Real parameters have value references 0..40.
pub const REAL_SLOTS: usize = 40;

fn invalid(name: &'static str, value: i32, reason: &str) -> SetResult {
    Err(ModelError::invalid(name, value, reason))
}

/// Largest computing window (sleepers): 2^16 − 1 sleepers are about 39 km of track at 0.6 m,
/// a few tens of MB. A larger value is refused here rather than failing to allocate at
/// initialization, which would abort the importing process (2^24 − 1 sleepers
/// under a 3 GB limit).
pub const MAX_SLEEPERS: i32 = 65_535;

fn sleeper_count(name: &'static str, value: i32) -> SetResult {
    if value < 3 || !((value as u32) + 1).is_power_of_two() {
        return invalid(name, value, "n_sleepers + 1 must be a power of two >= 4 (63, 127, 255, 511, 1023, ...): the fast sine transform is radix 2");
    }
    if value > MAX_SLEEPERS {
        return invalid(
            name,
            value,
            &format!(
                "must be at most {MAX_SLEEPERS} (2^16 - 1: about 39 km of track at 0.6 m sleeper \
                 spacing)"
            ),
        );
    }
    Ok(None)
}

fn mode_count(name: &'static str, value: i32) -> SetResult {
    if value < 1 {
        return invalid(name, value, "must be >= 1 (and <= 2 n_sleepers + 1)");
    }
    Ok(None)
}

fn contact_law(name: &'static str, value: i32) -> SetResult {
    if ContactLaw::from_code(value).is_none() {
        return invalid(name, value, "must be 0 (Hertz) or 1 (linearised Hertz)");
    }
    Ok(None)
}

fn irregularity_code(name: &'static str, value: i32) -> SetResult {
    if IrregularityKind::from_code(value).is_none() {
        return invalid(
            name,
            value,
            "must be 0 (none), 1..9 (spectrum) or 10 (measured)",
        );
    }
    Ok(None)
}

/// Highest running speed accepted (m/s): 576 km/h, just above the rail speed record of
/// 574.8 km/h (TGV, 2007). It catches a speed given in km/h (`v = 300` would be 1080 km/h).
pub const MAX_SPEED: f64 = 160.0;

/// A running speed in `[0, MAX_SPEED]` m/s.
fn speed_in_range(name: &'static str, value: f64) -> SetResult {
    non_negative(name, value)?;
    if value > MAX_SPEED {
        return Err(ModelError::invalid(
            name,
            value,
            format!(
                "must be at most {MAX_SPEED} m/s ({} km/h, above the 574.8 km/h rail speed \
                 record): the speed is in m/s, not km/h ({value} km/h = {:.2} m/s)",
                MAX_SPEED * 3.6,
                value / 3.6
            ),
        ));
    }
    Ok(None)
}

fn flag(name: &'static str, value: i32) -> SetResult {
    if !(value == 0 || value == 1) {
        return invalid(name, value, "must be 0 or 1");
    }
    Ok(None)
}

// Value references: Real parameters 0..40, Integer 40..=45, String 46, calculated 50..=53,
// outputs from 100. `m` is the model; its Real parameters live in `m.p.reals[vr]`.
variables! {
    static TABLE: [VehicleTrack as m];
    real_parameter("Mc", VR_MC = 0, Some("kg"), m.p.reals[0], 46_060.0, Fixed, positive, "Carbody mass, whole car [paper]; the half model uses Mc/2"),
    real_parameter("Mt", VR_MT = 1, Some("kg"), m.p.reals[1], 2_235.0, Fixed, positive, "Bogie mass [paper]; halved per rail"),
    real_parameter("Mw", VR_MW = 2, Some("kg"), m.p.reals[2], 1_457.0, Fixed, positive, "Wheelset mass [paper]; halved per rail"),
    real_parameter("Jc", VR_JC = 3, Some("kg.m2"), m.p.reals[3], 1.95e6, Fixed, positive, "Carbody pitch inertia, whole car [paper]; halved per rail"),
    real_parameter("Jt", VR_JT = 4, Some("kg.m2"), m.p.reals[4], 1_238.0, Fixed, positive, "Bogie pitch inertia [paper]; halved per rail"),
    real_parameter("Kpz", VR_KPZ = 5, Some("N/m"), m.p.reals[5], 1.773e6, Tunable, positive, "Primary vertical stiffness per wheel (per side) [paper]"),
    real_parameter("Cpz", VR_CPZ = 6, Some("N.s/m"), m.p.reals[6], 20e3, Tunable, non_negative, "Primary vertical damping per wheel (per side) [paper]"),
    real_parameter("Ksz", VR_KSZ = 7, Some("N/m"), m.p.reals[7], 0.8e6, Tunable, positive, "Secondary vertical stiffness per bogie side [paper]"),
    real_parameter("Csz", VR_CSZ = 8, Some("N.s/m"), m.p.reals[8], 120e3, Tunable, non_negative, "Secondary vertical damping per bogie side [paper]"),
    real_parameter("Lc", VR_LC = 9, Some("m"), m.p.reals[9], 8.6875, Fixed, positive, "Half distance between bogie centres [paper]"),
    real_parameter("Lt", VR_LT = 10, Some("m"), m.p.reals[10], 1.25, Fixed, positive, "Half wheelbase of a bogie [paper]"),
    real_parameter("v", VR_V = 11, Some("m/s"), m.p.reals[11], DEFAULT_SPEED, Fixed, speed_in_range, "Running speed in m/s, not km/h (83.33 = 300 km/h) [paper]; range [0, 160] m/s: 160 m/s = 576 km/h, just above the 574.8 km/h rail speed record", min = 0.0, max = MAX_SPEED),
    real_parameter("g", VR_G = 12, Some("m/s2"), m.p.reals[12], 9.8, Fixed, non_negative, "Gravity [paper]"),
    real_parameter("R", VR_R = 13, Some("m"), m.p.reals[13], 0.43, Fixed, positive, "Wheel rolling radius, sets the Hertz constant G [assumed]"),
    real_parameter("mr", VR_MR = 14, Some("kg/m"), m.p.reals[14], 60.64, Fixed, positive, "Rail mass per metre [paper]"),
    real_parameter("EI", VR_EI = 15, Some("N.m2"), m.p.reals[15], 6.6e6, Fixed, positive, "Rail bending stiffness [paper]"),
    real_parameter("Ms", VR_MS = 16, Some("kg"), m.p.reals[16], 125.5, Fixed, positive, "Half-sleeper mass [paper]"),
    real_parameter("Mb", VR_MB = 17, Some("kg"), m.p.reals[17], 310.0, Fixed, positive, "Ballast block mass under one rail seat [paper]"),
    real_parameter("Kp", VR_KP = 18, Some("N/m"), m.p.reals[18], 60e6, Fixed, positive, "Rail pad stiffness (60 kN/mm) [paper]"),
    real_parameter("Cp", VR_CP = 19, Some("N.s/m"), m.p.reals[19], 75e3, Fixed, non_negative, "Rail pad damping [paper]"),
    real_parameter("Kb", VR_KB = 20, Some("N/m"), m.p.reals[20], 150e6, Fixed, positive, "Ballast stiffness (150 kN/mm) [paper]"),
    real_parameter("Cb", VR_CB = 21, Some("N.s/m"), m.p.reals[21], 60e3, Fixed, non_negative, "Ballast damping [paper]"),
    real_parameter("Kf", VR_KF = 22, Some("N/m"), m.p.reals[22], 70e6, Fixed, positive, "Subgrade stiffness (70 kN/mm) [paper]"),
    real_parameter("Cf", VR_CF = 23, Some("N.s/m"), m.p.reals[23], 100e3, Fixed, non_negative, "Subgrade damping [paper]"),
    real_parameter("Kw", VR_KW = 24, Some("N/m"), m.p.reals[24], 78e6, Fixed, non_negative, "Ballast shear stiffness between neighbouring blocks [lit]"),
    real_parameter("Cw", VR_CW = 25, Some("N.s/m"), m.p.reals[25], 80e3, Fixed, non_negative, "Ballast shear damping [lit]"),
    real_parameter("ls", VR_LS = 26, Some("m"), m.p.reals[26], 0.6, Fixed, positive, "Sleeper spacing [paper]"),
    real_parameter("dt", VR_DT = 27, Some("s"), m.p.reals[27], 1e-4, Fixed, positive, "Largest integration step; communication steps are split into equal substeps <= dt [assumed]"),
    real_parameter("x_start", VR_X_START = 28, Some("m"), m.p.reals[28], 0.0, Fixed, finite, "Track position of the carbody centre at the start time [assumed]"),
    real_parameter("dip_x0", VR_DIP_X0 = 29, Some("m"), m.p.reals[29], 25.0, Fixed, finite, "Track position where the rail dip starts [assumed]"),
    real_parameter("dip_length", VR_DIP_LENGTH = 30, Some("m"), m.p.reals[30], 0.3, Fixed, non_negative, "Length L of the cosine rail dip [assumed]"),
    real_parameter("dip_depth", VR_DIP_DEPTH = 31, Some("m"), m.p.reals[31], 0.0, Fixed, finite, "Depth d of the cosine rail dip; 0 = no dip (default) [assumed]"),
    real_parameter("lambda_min", VR_LAMBDA_MIN = 32, Some("m"), m.p.reals[32], 2.0, Fixed, positive, "Shortest wavelength of the random irregularity [lit: TB/T 3352 range]"),
    real_parameter("lambda_max", VR_LAMBDA_MAX = 33, Some("m"), m.p.reals[33], 200.0, Fixed, positive, "Longest wavelength of the random irregularity [lit: TB/T 3352 range]"),
    real_parameter("irregularity_length", VR_IRR_LENGTH = 34, Some("m"), m.p.reals[34], 4096.0, Fixed, positive, "Length of the random irregularity sample; it repeats beyond [assumed]"),
    real_parameter("ramp_length", VR_RAMP_LENGTH = 35, Some("m"), m.p.reals[35], 20.0, Fixed, non_negative, "Irregularity fades in over this length ahead of the leading wheel's start position; 0 = none [assumed]"),
    real_parameter("irregularity_scale", VR_IRREGULARITY_SCALE = 36, None, m.p.reals[36], 1.0, Fixed, non_negative, "Factor on the amplitude of the irregularity (random or measured; not the dip): 0 = perfect track, 2 = twice as rough [assumed]"),
    integer_parameter("n_sleepers", VR_N_SLEEPERS = 40, m.p.n_sleepers, 255, sleeper_count, "Sleepers in the computing window N (N + 1 a power of two: 63, 127, 255, 511, ..., at most 65535) [assumed]"),
    integer_parameter("n_modes", VR_N_MODES = 41, m.p.n_modes, 255, mode_count, "Rail modes NM, 1..2N+1; default N: shortest modal wavelength 2 l/NM = 2 ls [assumed]"),
    integer_parameter("contact_law", VR_CONTACT_LAW = 42, m.p.contact_law, 0, contact_law, "0 = nonlinear Hertz, 1 = Hertz linearised at the static load"),
    integer_parameter("irregularity", VR_IRREGULARITY = 43, m.p.irregularity, 1, irregularity_code, "0 none, 1 Chinese ballastless TB/T 3352-2014 (default), 2 German low, 3 German high, 4..9 FRA class 1..6, 10 measured profile_file"),
    integer_parameter("seed", VR_SEED = 44, m.p.seed, 1, any_integer, "Seed of the random phases of the irregularity sample"),
    integer_parameter("moving_window", VR_MOVING_WINDOW = 45, m.p.moving_window, 1, flag, "1 = the computing window follows the vehicle; 0 = fixed window (error when a wheel nears its end)"),
    string_parameter("profile_file", VR_PROFILE_FILE = 46, m.p.profile_file, "", any_string, "CSV of x [m], z [m] (z positive down) for irregularity = 10; a relative path is resolved in the FMU resources folder"),
    calculated("G", VR_HERTZ_G = 50, None, hertz_constant(m.p.r(VR_R)), "Hertz constant G = 4.57e-8 R^-0.149 in m/N^(2/3)"),
    calculated("track_length", VR_TRACK_LENGTH = 51, Some("m"), (m.p.n_sleepers as f64 + 1.0) * m.p.r(VR_LS), "Computing length l = (n_sleepers + 1) ls"),
    calculated("P_static", VR_P_STATIC = 52, Some("N"), m.p.static_load(), "Static wheel load g (Mc/8 + Mt/4 + Mw/2)"),
    calculated_string("solver.kernel", VR_SOLVER_KERNEL = 53, m.kernel.describe(), "Instruction sets the track's equations run on here, chosen at run time from the CPU: architecture, stepping loops (avx2+fma, else sse2 on x86-64) and FFT, e.g. 'x86_64: loops avx2+fma, FFT avx+fma'; results of two kernels agree to about 1e-13 only, so record it with a result"),
    output("Zc", VR_ZC = 100, Some("m"), m.state(|s| s.zhai.x[vehicle::ZC]), "Carbody vertical displacement (down)"),
    output("Zc_acc", VR_ZC_ACC = 101, Some("m/s2"), m.state(|s| s.zhai.a[vehicle::ZC]), "Carbody vertical acceleration at the carbody centre (centre of mass), from the equations of motion; above the bogies, where ride standards measure: Zc_acc_front, Zc_acc_rear"),
    output("beta_c", VR_BETA_C = 102, Some("rad"), m.state(|s| s.zhai.x[vehicle::BC]), "Carbody pitch"),
    output("beta_c_acc", VR_BETA_C_ACC = 103, Some("rad/s2"), m.state(|s| s.zhai.a[vehicle::BC]), "Carbody pitch acceleration"),
    output("Zt1", VR_ZT1 = 104, Some("m"), m.state(|s| s.zhai.x[vehicle::ZT1]), "Front bogie vertical displacement"),
    output("beta_t1", VR_BETA_T1 = 105, Some("rad"), m.state(|s| s.zhai.x[vehicle::BT1]), "Front bogie pitch"),
    output("Zt2", VR_ZT2 = 106, Some("m"), m.state(|s| s.zhai.x[vehicle::ZT2]), "Rear bogie vertical displacement"),
    output("beta_t2", VR_BETA_T2 = 107, Some("rad"), m.state(|s| s.zhai.x[vehicle::BT2]), "Rear bogie pitch"),
    output("Zw1", VR_ZW1 = 108, Some("m"), m.state(|s| s.zhai.x[ZW1]), "Wheelset 1 (leading) vertical displacement"),
    output("Zw2", VR_ZW2 = 109, Some("m"), m.state(|s| s.zhai.x[ZW1 + 1]), "Wheelset 2 vertical displacement"),
    output("Zw3", VR_ZW3 = 110, Some("m"), m.state(|s| s.zhai.x[ZW1 + 2]), "Wheelset 3 vertical displacement"),
    output("Zw4", VR_ZW4 = 111, Some("m"), m.state(|s| s.zhai.x[ZW1 + 3]), "Wheelset 4 vertical displacement"),
    output("P1", VR_P1 = 112, Some("N"), m.state(|s| s.diag.p[0]), "Wheel-rail contact force at wheel 1, not Jenkins' P1 peak (0 when the wheel is off the rail)"),
    output("P2", VR_P2 = 113, Some("N"), m.state(|s| s.diag.p[1]), "Wheel-rail contact force at wheel 2, not Jenkins' P2 peak"),
    output("P3", VR_P3 = 114, Some("N"), m.state(|s| s.diag.p[2]), "Wheel-rail contact force at wheel 3"),
    output("P4", VR_P4 = 115, Some("N"), m.state(|s| s.diag.p[3]), "Wheel-rail contact force at wheel 4"),
    output("Zr1", VR_ZR1 = 116, Some("m"), m.state(|s| s.diag.zr[0]), "Rail displacement under wheel 1"),
    output("Zr2", VR_ZR2 = 117, Some("m"), m.state(|s| s.diag.zr[1]), "Rail displacement under wheel 2"),
    output("Zr3", VR_ZR3 = 118, Some("m"), m.state(|s| s.diag.zr[2]), "Rail displacement under wheel 3"),
    output("Zr4", VR_ZR4 = 119, Some("m"), m.state(|s| s.diag.zr[3]), "Rail displacement under wheel 4"),
    output("Z0_1", VR_Z0_1 = 120, Some("m"), m.state(|s| s.diag.z0[0]), "Rail profile under wheel 1: irregularity plus dip (down)"),
    output("x", VR_X = 121, Some("m"), m.state(|s| s.run.xc), "Track position of the carbody centre"),
    output("Zc_acc_front", VR_ZC_ACC_FRONT = 122, Some("m/s2"), m.state(|s| s.carbody_acc_at(-1.0, m.p.r(VR_LC))), "Carbody vertical acceleration above the front bogie centre (x = +Lc): Zc_acc - Lc beta_c_acc (Z down)"),
    output("Zc_acc_rear", VR_ZC_ACC_REAR = 123, Some("m/s2"), m.state(|s| s.carbody_acc_at(1.0, m.p.r(VR_LC))), "Carbody vertical acceleration above the rear bogie centre (x = -Lc): Zc_acc + Lc beta_c_acc (Z down)"),
}

/// Static description of the vehicle–track model.
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

/// All parameters (SI units; whole-car vehicle values as in the paper), as the variable
/// table stores them.
#[derive(Clone, Debug, PartialEq)]
pub struct Params {
    /// Real parameters indexed by value reference (slots without a parameter stay 0).
    pub reals: [f64; REAL_SLOTS],
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
        let mut m = VehicleTrack::unset();
        TABLE.apply_defaults(&mut m);
        m.p
    }
}

impl Params {
    /// Every parameter zero (before the table's defaults).
    pub(super) fn zero() -> Self {
        Params {
            reals: [0.0; REAL_SLOTS],
            n_sleepers: 0,
            n_modes: 0,
            contact_law: 0,
            irregularity: 0,
            seed: 0,
            moving_window: 0,
            profile_file: String::new(),
        }
    }

    /// The Real parameter of value reference `vr`.
    pub(super) fn r(&self, vr: u32) -> f64 {
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

    /// Static wheel load (N).
    pub(super) fn static_load(&self) -> f64 {
        self.half_vehicle().static_forces().p[0]
    }
}
