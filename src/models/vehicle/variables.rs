//! The vehicle's variables, one line each (see [`crate::models::table`]), and its description.
//!
//! Value references: Real parameters 0..60, Integer 70–71, String 80–83, calculated 90–91,
//! outputs from 100. Sources: [MODELS] = MODELS.md §5, [ref] = the reference implementation
//! (DYTSI, its Cooperrider input files), [assumed] = chosen here.
#![forbid(unsafe_code)]

use super::{Vehicle, MIN_SPEED};
use crate::models::table::{any_integer, any_string, finite, non_negative, positive, variables};
use crate::models::{ModelError, ModelInfo, SetResult};

/// Highest speed accepted (m/s): 576 km/h, as for the vehicle–track model; it catches a speed
/// given in km/h.
pub const MAX_SPEED: f64 = 160.0;

/// A running speed in (1, 160] m/s.
fn speed(name: &'static str, value: f64) -> SetResult {
    finite(name, value)?;
    if value <= MIN_SPEED || value > MAX_SPEED {
        return Err(ModelError::invalid(
            name,
            value,
            format!(
                "must exceed {MIN_SPEED} m/s (the creepages divide by the speed) and be at most \
                 {MAX_SPEED} m/s: the speed is in m/s, not km/h"
            ),
        ));
    }
    Ok(None)
}

/// The roll moments the vehicle knows.
fn roll_moment_code(name: &'static str, value: i32) -> SetResult {
    if !matches!(value, 0 | 1) {
        return Err(ModelError::invalid(
            name,
            value,
            "must be 0 (the vertical contact forces about aw, as the reference) or 1 (also the \
             lateral contact forces about the rolling radius r)",
        ));
    }
    Ok(None)
}

/// The irregularity codes the vehicle knows.
fn irregularity_code(name: &'static str, value: i32) -> SetResult {
    if !matches!(value, 0 | 2 | 3 | 10) {
        return Err(ModelError::invalid(
            name,
            value,
            "must be 0 (none), 2 (German low interference), 3 (German high \
                     interference) or 10 (measured, irregularity_file): the other spectra of the \
                     vehicle-track model have no lateral counterpart here",
        ));
    }
    Ok(None)
}

/// The reference implementation's shear modulus: E / (2 (1 − ν)), E = 2.1e11 Pa, ν = 0.27.
pub const G_REFERENCE: f64 = 2.1e11 / (2.0 * (1.0 - 0.27));

variables! {
    static TABLE: [Vehicle as m];
    real_parameter("m_c", VR_M_C = 0, Some("kg"), m.p.m_c, 44_388.0, Fixed, positive, "Car body mass [MODELS, ref]", min = 0.0),
    real_parameter("Ix_c", VR_IX_C = 1, Some("kg.m2"), m.p.ix_c, 2.80e5, Fixed, positive, "Car body roll inertia [MODELS, ref]", min = 0.0),
    real_parameter("Iy_c", VR_IY_C = 2, Some("kg.m2"), m.p.iy_c, 5.0e5, Fixed, positive, "Car body pitch inertia [MODELS, ref]; the reference's pitch equation divides by Ix_c (2.8e5) instead: no effect on the lateral dynamics on straight track", min = 0.0),
    real_parameter("Iz_c", VR_IZ_C = 3, Some("kg.m2"), m.p.iz_c, 5.0e5, Fixed, positive, "Car body yaw inertia [MODELS, ref]", min = 0.0),
    real_parameter("m_b", VR_M_B = 4, Some("kg"), m.p.m_b, 2_918.9, Fixed, positive, "Bogie frame mass, each [MODELS, ref]", min = 0.0),
    real_parameter("Ix_b", VR_IX_B = 5, Some("kg.m2"), m.p.ix_b, 6_780.0, Fixed, positive, "Bogie frame roll inertia [MODELS, ref]", min = 0.0),
    real_parameter("Iy_b", VR_IY_B = 6, Some("kg.m2"), m.p.iy_b, 6_780.0, Fixed, positive, "Bogie frame pitch inertia [MODELS, ref]", min = 0.0),
    real_parameter("Iz_b", VR_IZ_B = 7, Some("kg.m2"), m.p.iz_b, 6_780.0, Fixed, positive, "Bogie frame yaw inertia [MODELS, ref]", min = 0.0),
    real_parameter("m_w", VR_M_W = 8, Some("kg"), m.p.m_w, 1_022.0, Fixed, positive, "Wheelset mass, each [MODELS, ref]", min = 0.0),
    real_parameter("Ix_w", VR_IX_W = 9, Some("kg.m2"), m.p.ix_w, 678.0, Fixed, positive, "Wheelset roll inertia [MODELS, ref]", min = 0.0),
    real_parameter("Iy_w", VR_IY_W = 10, Some("kg.m2"), m.p.iy_w, 80.0, Fixed, positive, "Wheelset spin inertia [MODELS, ref]", min = 0.0),
    real_parameter("Iz_w", VR_IZ_W = 11, Some("kg.m2"), m.p.iz_w, 678.0, Fixed, positive, "Wheelset yaw inertia [MODELS, ref]", min = 0.0),
    real_parameter("r0", VR_R0 = 12, Some("m"), m.p.r0, 0.425, Fixed, positive, "Nominal rolling radius, also the axle height [MODELS, ref]; the creepages use the table's rolling radius at y = 0", min = 0.0),
    real_parameter("h1", VR_H1 = 13, Some("m"), m.p.h1, 0.0762, Fixed, finite, "Height of the bogie-frame centre above the axle [MODELS, ref]"),
    real_parameter("h2", VR_H2 = 14, Some("m"), m.p.h2, 1.5584, Fixed, finite, "Height of the car-body centre of mass above the bogie-frame centre [MODELS, ref]"),
    real_parameter("a", VR_A = 15, Some("m"), m.p.a, 0.75, Fixed, positive, "Half lateral distance of the contact points in the creepages; inner end of the primary lateral springs [MODELS, ref]", min = 0.0),
    real_parameter("l1", VR_L1 = 16, Some("m"), m.p.l1, 0.30, Fixed, finite, "Length (y) of the primary lateral spring [MODELS, ref]"),
    real_parameter("l2", VR_L2 = 17, Some("m"), m.p.l2, 0.30, Fixed, finite, "Lateral offset of the secondary lateral spring's bogie point beyond a + l1 [MODELS, ref]"),
    real_parameter("l3", VR_L3 = 18, Some("m"), m.p.l3, 0.30, Fixed, finite, "Length (y) of the secondary lateral spring; yaw dampers at y = a + l1 + l2 + l3/2 [MODELS, ref]"),
    real_parameter("v1", VR_V1 = 19, Some("m"), m.p.v1, 0.6488, Fixed, finite, "Height of the primary vertical spring's bogie point above the bogie centre [MODELS, ref]"),
    real_parameter("v2", VR_V2 = 20, Some("m"), m.p.v2, 0.30, Fixed, finite, "Secondary vertical spring's bogie point at v1 + v2 above the bogie centre [MODELS, ref]"),
    real_parameter("v3", VR_V3 = 21, Some("m"), m.p.v3, 0.30, Fixed, finite, "Read but not used by the model [MODELS, ref]"),
    real_parameter("v4", VR_V4 = 22, Some("m"), m.p.v4, 0.3096, Fixed, finite, "Secondary vertical spring's car-body point v4 below the car-body centre of mass [MODELS, ref]"),
    real_parameter("u1", VR_U1 = 23, Some("m"), m.p.u1, 7.5, Fixed, positive, "Half distance between the bogie centres [MODELS, ref]", min = 0.0),
    real_parameter("u2", VR_U2 = 24, Some("m"), m.p.u2, 1.074, Fixed, positive, "Half wheelbase; the b of the curve terms in the creepages [MODELS, ref]", min = 0.0),
    real_parameter("x1", VR_X1 = 25, Some("m"), m.p.x1, 0.349, Fixed, finite, "Primary longitudinal spring's bogie point at x = +-x1 (side of its wheelset) [MODELS, ref]"),
    real_parameter("s1", VR_S1 = 26, Some("m"), m.p.s1, 0.62, Fixed, finite, "Lateral half spacing of the primary vertical and longitudinal springs [MODELS, ref]"),
    real_parameter("s2", VR_S2 = 27, Some("m"), m.p.s2, 0.6584, Fixed, finite, "Height of the secondary lateral spring above the bogie centre [MODELS, ref]"),
    real_parameter("s3", VR_S3 = 28, Some("m"), m.p.s3, 0.68, Fixed, finite, "Lateral half spacing of the secondary vertical springs [MODELS, ref]"),
    real_parameter("s4", VR_S4 = 29, Some("m"), m.p.s4, 0.759, Fixed, finite, "Length (x) of the yaw damper and spring: car-body point at x = +-(u1 + s4) [MODELS, ref]"),
    real_parameter("k1", VR_K1 = 30, Some("N/m"), m.p.k[0], 1.823e6, Fixed, non_negative, "Primary lateral stiffness, per side [MODELS, ref]", min = 0.0),
    real_parameter("k2", VR_K2 = 31, Some("N/m"), m.p.k[1], 3.646e6, Fixed, non_negative, "Primary longitudinal stiffness, per side (yaw stiffness 2 k2 s1^2) [MODELS, ref]", min = 0.0),
    real_parameter("k3", VR_K3 = 32, Some("N/m"), m.p.k[2], 3.646e6, Fixed, positive, "Primary vertical stiffness, per side (carries the static load: > 0) [MODELS, ref]", min = 0.0),
    real_parameter("k4", VR_K4 = 33, Some("N/m"), m.p.k[3], 1.823e5, Fixed, non_negative, "Secondary lateral stiffness, per side [MODELS, ref]", min = 0.0),
    real_parameter("k5", VR_K5 = 34, Some("N/m"), m.p.k[4], 3.333e5, Fixed, positive, "Secondary vertical stiffness, per side (carries the static load: > 0) [MODELS, ref]", min = 0.0),
    real_parameter("k6", VR_K6 = 35, Some("N/m"), m.p.k[5], 9.0335e5, Fixed, non_negative, "Secondary longitudinal (yaw) stiffness, per side, at the yaw dampers [MODELS, ref]", min = 0.0),
    real_parameter("D1", VR_D1 = 36, Some("N.s/m"), m.p.d[0], 2.0e4, Fixed, non_negative, "Secondary vertical damping, per side, beside k5 [MODELS, ref]", min = 0.0),
    real_parameter("D2", VR_D2 = 37, Some("N.s/m"), m.p.d[1], 2.92e4, Fixed, non_negative, "Secondary lateral damping, per side, beside k4 [MODELS, ref]", min = 0.0),
    real_parameter("D3", VR_D3 = 38, Some("N.s/m"), m.p.d[2], 0.0, Fixed, non_negative, "Primary longitudinal damping, per side, along the element [MODELS, ref]", min = 0.0),
    real_parameter("D4", VR_D4 = 39, Some("N.s/m"), m.p.d[3], 0.0, Fixed, non_negative, "Primary vertical damping, per side, along the element [MODELS, ref]", min = 0.0),
    real_parameter("D5", VR_D5 = 40, Some("N.s/m"), m.p.d[4], 0.0, Fixed, non_negative, "Primary lateral damping, per side, along the element [MODELS, ref]", min = 0.0),
    real_parameter("D6", VR_D6 = 41, Some("N.s/m"), m.p.d[5], 1.66669e5, Fixed, non_negative, "Yaw damping between car body and bogie, per side, at y = +-(a + l1 + l2 + l3/2) [MODELS, ref]", min = 0.0),
    real_parameter("mu", VR_MU = 42, None, m.p.mu, 0.15, Fixed, positive, "Friction coefficient [MODELS, ref]", min = 0.0),
    real_parameter("G", VR_G = 43, Some("Pa"), m.p.g_mod, G_REFERENCE, Fixed, positive, "Shear modulus in Kalker's law: the reference's 2.1e11/(2(1 - 0.27)) = 1.4384e11 Pa [ref]; the textbook E/(2(1 + nu)) is 8.27e10 Pa", min = 0.0),
    real_parameter("v", VR_V = 44, Some("m/s"), m.v, 40.0, Tunable, speed, "Running speed in m/s (not km/h), in (1, 160]; set between steps it takes effect from then on (the ramp restarts from it) [ref: transient input]", min = MIN_SPEED, max = MAX_SPEED),
    real_parameter("ramp", VR_RAMP = 45, Some("s2/m"), m.ramp, 0.0, Fixed, finite, "Speed ramp Df in s2/m: V = v - (t - t_v)/Df, the speed falls by 1/Df m/s per second from the time t_v at which v was set; 0 = constant speed, < 0 = rising (as the Bogie's ramp) [assumed]"),
    real_parameter("R", VR_R = 46, Some("m"), m.radius, 0.0, Fixed, finite, "Curve radius; 0 = straight track; > 0 turns to the right (-y), the left rail is the outer one [assumed]"),
    real_parameter("cant", VR_CANT = 47, Some("rad"), m.cant, 0.0, Fixed, finite, "Cant angle of the track; > 0 raises the left rail (the outer one of a curve with R > 0) [assumed]"),
    real_parameter("transition", VR_TRANSITION = 48, Some("s"), m.transition, 0.0, Fixed, non_negative, "Time over which curvature and cant grow linearly from 0 to 1/R and cant (the reference enters its curves so); 0 = on the curve from the start [ref]", min = 0.0),
    real_parameter("y0_w1", VR_Y0_W1 = 49, Some("m"), m.y0[0], 1e-4, Fixed, finite, "Initial lateral displacement of wheelset 1 (the leading one) [ref: transient input]"),
    real_parameter("y0_w2", VR_Y0_W2 = 50, Some("m"), m.y0[1], 0.0, Fixed, finite, "Initial lateral displacement of wheelset 2 [ref]"),
    real_parameter("y0_w3", VR_Y0_W3 = 51, Some("m"), m.y0[2], 8e-3, Fixed, finite, "Initial lateral displacement of wheelset 3 (leading wheelset of the trailing bogie) [ref: transient input]"),
    real_parameter("y0_w4", VR_Y0_W4 = 52, Some("m"), m.y0[3], 0.0, Fixed, finite, "Initial lateral displacement of wheelset 4 [ref]"),
    real_parameter("dt", VR_DT = 53, Some("s"), m.dt, 1e-3, Fixed, positive, "Largest RK4 substep; the substep is also kept below 2/rho, rho a bound on the fastest mode at the current speed [numerical]", min = 0.0),
    real_parameter("h_floor", VR_H_FLOOR = 54, Some("m"), m.h_floor, 1.2, Fixed, finite, "Height above rail level of the floor points (above the bogie centres) of ay_floor_b, az_floor_b [assumed]"),
    real_parameter("lambda_min", VR_LAMBDA_MIN = 55, Some("m"), m.irr.lambda_min, 3.0, Fixed, positive, "Shortest wavelength of the random irregularity [assumed: EN 14363 D1 band from 3 m]", min = 0.0),
    real_parameter("lambda_max", VR_LAMBDA_MAX = 56, Some("m"), m.irr.lambda_max, 150.0, Fixed, positive, "Longest wavelength of the random irregularity [assumed: EN 13848 D3 band to 150 m]", min = 0.0),
    real_parameter("irregularity_length", VR_IRR_LENGTH = 57, Some("m"), m.irr.length, 4096.0, Fixed, positive, "Length of the random irregularity sample; it repeats beyond [assumed]", min = 0.0),
    real_parameter("irregularity_scale", VR_IRR_SCALE = 58, None, m.irr.scale, 1.0, Fixed, non_negative, "Factor on the irregularity's amplitude (random or measured) [assumed]", min = 0.0),
    real_parameter("irregularity_fade_in", VR_IRR_FADE_IN = 59, Some("m"), m.irr.fade_in, 20.0, Fixed, non_negative, "The irregularity fades in over this length ahead of the leading wheelset's start position; 0 = none [assumed]", min = 0.0),
    integer_parameter("irregularity", VR_IRREGULARITY = 70, m.irr.code, 0, irregularity_code, "Track irregularity: 0 none (default), 2 German low, 3 German high interference (random, lateral and vertical), 10 measured (irregularity_file)"),
    integer_parameter("seed", VR_SEED = 71, m.irr.seed, 1, any_integer, "Seed of the random phases of the irregularity"),
    integer_parameter("roll_moment", VR_ROLL_MOMENT = 72, m.p.roll_moment, 0, roll_moment_code, "Wheelset roll moment: 0 the vertical contact forces about the lever arm aw (as the reference implementation), 1 also the lateral contact forces about the rolling radius r (the inner wheels' unloading dQQ on curves some 20-30 % higher) [ref: 0]"),
    string_parameter("contact_table", VR_CONTACT_TABLE = 80, m.contact_table, "", any_string, "Contact table file (CSV: y, N0, delta, a, b, aw, r, c11, c22, c23, zc, q0 in SI units, left wheel, y ascending in equal steps); a relative path is resolved in the FMU resources folder; empty = the built-in S1002/UIC60 1:40 table"),
    string_parameter("irregularity_file", VR_IRREGULARITY_FILE = 81, m.irr.file, "", any_string, "Measured track for irregularity = 10: lines of x [m], y [m] (alignment, left +), z [m] (vertical, up +); a relative path is resolved in the FMU resources folder"),
    string_parameter("wheel_profile", VR_WHEEL_PROFILE = 82, m.wheel_profile, "", any_string, "Wheel profile file (CSV: y, z in mm, y from the flange back, positive toward the field side, z up; the rolling circle 70 mm from the flange back): with contact_table empty, the contact table is computed from it and rail_profile at initialization (rails at 1:40, standard gauge, smoothed over 0.05 mm, as the built-in one); empty = S1002; a relative path is resolved in the FMU resources folder"),
    string_parameter("rail_profile", VR_RAIL_PROFILE = 83, m.rail_profile, "", any_string, "Rail profile file (CSV: y, z in mm, y from the rail's centre line, positive toward the field side, z up, uninclined): see wheel_profile; empty = UIC60"),
    calculated("v_cr_linear", VR_V_CR_LINEAR = 90, Some("m/s"), m.v_cr_linear().unwrap_or(f64::NAN), "Linear (Hopf) critical speed on straight track: eigenvalues of the Jacobian at the centred equilibrium, scan 5..300 m/s and bisection (clamped to that range); computed when first read"),
    calculated("Q_static", VR_Q_STATIC = 91, Some("N"), m.static_wheel_load(), "Static wheel load: g (m_c + 2 m_b + 4 m_w)/8"),
    output("speed", VR_SPEED = 100, Some("m/s"), m.speed(), "Running speed now"),
    output("x", VR_X = 101, Some("m"), m.distance(), "Distance run by the car body centre"),
    output("y_w1", VR_Y_W1 = 102, Some("m"), m.x_at(30), "Lateral displacement of wheelset 1 (leading)"),
    output("y_w2", VR_Y_W2 = 103, Some("m"), m.x_at(39), "Lateral displacement of wheelset 2"),
    output("y_w3", VR_Y_W3 = 104, Some("m"), m.x_at(48), "Lateral displacement of wheelset 3"),
    output("y_w4", VR_Y_W4 = 105, Some("m"), m.x_at(57), "Lateral displacement of wheelset 4"),
    output("psi_w1", VR_PSI_W1 = 106, Some("rad"), m.x_at(37), "Yaw of wheelset 1"),
    output("psi_w2", VR_PSI_W2 = 107, Some("rad"), m.x_at(46), "Yaw of wheelset 2"),
    output("psi_w3", VR_PSI_W3 = 108, Some("rad"), m.x_at(55), "Yaw of wheelset 3"),
    output("psi_w4", VR_PSI_W4 = 109, Some("rad"), m.x_at(64), "Yaw of wheelset 4"),
    output("Y_1L", VR_Y_1L = 110, Some("N"), m.outputs().y[0][0], "Lateral force of the left wheel of wheelset 1 on the rail, track frame, + to the left"),
    output("Y_1R", VR_Y_1R = 111, Some("N"), m.outputs().y[0][1], "Lateral force of the right wheel of wheelset 1 on the rail, track frame, + to the left"),
    output("Y_2L", VR_Y_2L = 112, Some("N"), m.outputs().y[1][0], "Lateral wheel force, wheelset 2 left"),
    output("Y_2R", VR_Y_2R = 113, Some("N"), m.outputs().y[1][1], "Lateral wheel force, wheelset 2 right"),
    output("Y_3L", VR_Y_3L = 114, Some("N"), m.outputs().y[2][0], "Lateral wheel force, wheelset 3 left"),
    output("Y_3R", VR_Y_3R = 115, Some("N"), m.outputs().y[2][1], "Lateral wheel force, wheelset 3 right"),
    output("Y_4L", VR_Y_4L = 116, Some("N"), m.outputs().y[3][0], "Lateral wheel force, wheelset 4 left"),
    output("Y_4R", VR_Y_4R = 117, Some("N"), m.outputs().y[3][1], "Lateral wheel force, wheelset 4 right"),
    output("Q_1L", VR_Q_1L = 118, Some("N"), m.outputs().q[0][0], "Vertical force of the left wheel of wheelset 1 on the rail, + downward"),
    output("Q_1R", VR_Q_1R = 119, Some("N"), m.outputs().q[0][1], "Vertical wheel force, wheelset 1 right"),
    output("Q_2L", VR_Q_2L = 120, Some("N"), m.outputs().q[1][0], "Vertical wheel force, wheelset 2 left"),
    output("Q_2R", VR_Q_2R = 121, Some("N"), m.outputs().q[1][1], "Vertical wheel force, wheelset 2 right"),
    output("Q_3L", VR_Q_3L = 122, Some("N"), m.outputs().q[2][0], "Vertical wheel force, wheelset 3 left"),
    output("Q_3R", VR_Q_3R = 123, Some("N"), m.outputs().q[2][1], "Vertical wheel force, wheelset 3 right"),
    output("Q_4L", VR_Q_4L = 124, Some("N"), m.outputs().q[3][0], "Vertical wheel force, wheelset 4 left"),
    output("Q_4R", VR_Q_4R = 125, Some("N"), m.outputs().q[3][1], "Vertical wheel force, wheelset 4 right"),
    output("YQ_1L", VR_YQ_1L = 126, None, m.outputs().yq[0][0], "Derailment ratio Y/Q (Nadal) of wheelset 1 left, + when the wheel pushes its rail outward; 0 while Q <= 1 N (limit 0.8 in EN 14363)"),
    output("YQ_1R", VR_YQ_1R = 127, None, m.outputs().yq[0][1], "Derailment ratio -Y/Q of wheelset 1 right, + when the wheel pushes its rail outward"),
    output("YQ_2L", VR_YQ_2L = 128, None, m.outputs().yq[1][0], "Derailment ratio, wheelset 2 left"),
    output("YQ_2R", VR_YQ_2R = 129, None, m.outputs().yq[1][1], "Derailment ratio, wheelset 2 right"),
    output("YQ_3L", VR_YQ_3L = 130, None, m.outputs().yq[2][0], "Derailment ratio, wheelset 3 left"),
    output("YQ_3R", VR_YQ_3R = 131, None, m.outputs().yq[2][1], "Derailment ratio, wheelset 3 right"),
    output("YQ_4L", VR_YQ_4L = 132, None, m.outputs().yq[3][0], "Derailment ratio, wheelset 4 left"),
    output("YQ_4R", VR_YQ_4R = 133, None, m.outputs().yq[3][1], "Derailment ratio, wheelset 4 right"),
    output("SumY_1", VR_SUMY_1 = 134, Some("N"), m.outputs().sum_y[0], "Track-shifting force of wheelset 1, Y_1L + Y_1R (Prud'homme limit 10 kN + P/3)"),
    output("SumY_2", VR_SUMY_2 = 135, Some("N"), m.outputs().sum_y[1], "Track-shifting force of wheelset 2"),
    output("SumY_3", VR_SUMY_3 = 136, Some("N"), m.outputs().sum_y[2], "Track-shifting force of wheelset 3"),
    output("SumY_4", VR_SUMY_4 = 137, Some("N"), m.outputs().sum_y[3], "Track-shifting force of wheelset 4"),
    output("dQQ_1L", VR_DQQ_1L = 138, None, m.outputs().dqq[0][0], "Wheel unloading (Q_static - Q)/Q_static, wheelset 1 left (+ = unloaded)"),
    output("dQQ_1R", VR_DQQ_1R = 139, None, m.outputs().dqq[0][1], "Wheel unloading, wheelset 1 right"),
    output("dQQ_2L", VR_DQQ_2L = 140, None, m.outputs().dqq[1][0], "Wheel unloading, wheelset 2 left"),
    output("dQQ_2R", VR_DQQ_2R = 141, None, m.outputs().dqq[1][1], "Wheel unloading, wheelset 2 right"),
    output("dQQ_3L", VR_DQQ_3L = 142, None, m.outputs().dqq[2][0], "Wheel unloading, wheelset 3 left"),
    output("dQQ_3R", VR_DQQ_3R = 143, None, m.outputs().dqq[2][1], "Wheel unloading, wheelset 3 right"),
    output("dQQ_4L", VR_DQQ_4L = 144, None, m.outputs().dqq[3][0], "Wheel unloading, wheelset 4 left"),
    output("dQQ_4R", VR_DQQ_4R = 145, None, m.outputs().dqq[3][1], "Wheel unloading, wheelset 4 right"),
    output("ay_floor_1", VR_AY_FLOOR_1 = 146, Some("m/s2"), m.outputs().ay_floor[0], "Car body lateral acceleration on the floor (height h_floor) above bogie 1, in the track-following frame"),
    output("ay_floor_2", VR_AY_FLOOR_2 = 147, Some("m/s2"), m.outputs().ay_floor[1], "Car body lateral acceleration on the floor above bogie 2"),
    output("az_floor_1", VR_AZ_FLOOR_1 = 148, Some("m/s2"), m.outputs().az_floor[0], "Car body vertical acceleration on the floor above bogie 1 (+ up)"),
    output("az_floor_2", VR_AZ_FLOOR_2 = 149, Some("m/s2"), m.outputs().az_floor[1], "Car body vertical acceleration on the floor above bogie 2"),
    output("y_rel_w1", VR_Y_REL_W1 = 150, Some("m"), m.outputs().y_rel[0], "Lateral displacement of wheelset 1 relative to the track (y_w1 minus the alignment irregularity): the contact table's argument"),
    output("y_rel_w2", VR_Y_REL_W2 = 151, Some("m"), m.outputs().y_rel[1], "Lateral displacement of wheelset 2 relative to the track"),
    output("y_rel_w3", VR_Y_REL_W3 = 152, Some("m"), m.outputs().y_rel[2], "Lateral displacement of wheelset 3 relative to the track"),
    output("y_rel_w4", VR_Y_REL_W4 = 153, Some("m"), m.outputs().y_rel[3], "Lateral displacement of wheelset 4 relative to the track"),
    output("y_c", VR_Y_C = 154, Some("m"), m.x_at(0), "Lateral displacement of the car body"),
    output("phi_c", VR_PHI_C = 155, Some("rad"), m.x_at(4), "Roll of the car body"),
    output("psi_c", VR_PSI_C = 156, Some("rad"), m.x_at(8), "Yaw of the car body"),
    output("y_b1", VR_Y_B1 = 157, Some("m"), m.x_at(10), "Lateral displacement of bogie frame 1 (leading)"),
    output("psi_b1", VR_PSI_B1 = 158, Some("rad"), m.x_at(18), "Yaw of bogie frame 1"),
    output("y_b2", VR_Y_B2 = 159, Some("m"), m.x_at(20), "Lateral displacement of bogie frame 2"),
    output("psi_b2", VR_PSI_B2 = 160, Some("rad"), m.x_at(28), "Yaw of bogie frame 2"),
    output("y_w_max", VR_Y_W_MAX = 161, Some("m"), m.envelope().0, "Largest |lateral displacement| of the four wheelsets, max |y_w1..4|: one signal in which the hunting of either bogie shows"),
    output("YQ_max", VR_YQ_MAX = 162, None, m.envelope().1, "Largest derailment ratio Y/Q of the eight wheels (as YQ_*)"),
    output("SumY_max", VR_SUMY_MAX = 163, Some("N"), m.envelope().2, "Largest |track-shifting force| of the four wheelsets, max |SumY_1..4|"),
    output("dQQ_max", VR_DQQ_MAX = 164, None, m.envelope().3, "Largest wheel unloading of the eight wheels, max dQQ_*"),
}

/// Static description of the vehicle model.
pub static INFO: ModelInfo = ModelInfo {
    name: "Vehicle",
    description: "Full passenger car after Cooperrider (car body, two bogies, four wheelsets; 66 states): tabulated S1002/UIC60 contact, Kalker creep with Shen-Hedrick-Elkins saturation, straight or curved track, irregularities, linear critical speed (railuq)",
    variables: &VARIABLES,
    default_start: 0.0,
    default_stop: 10.0,
    default_step: 0.01,
    documentation_html: include_str!("doc.html"),
};
