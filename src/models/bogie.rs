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
//! | variable | vr  | unit      | default     | kind | source |
//! |----------|-----|-----------|-------------|------|--------|
//! | m_b      | 0   | kg        | 4963        | fixed   | [paper] |
//! | I_b      | 1   | kg.m2     | 8135        | fixed   | [paper] |
//! | h        | 2   | m         | 1.5         | fixed   | [paper] |
//! | a        | 3   | m         | 0.7175      | fixed   | [paper] |
//! | K_sy     | 4   | N/m       | 182300      | tunable | [paper] |
//! | C_sy     | 5   | N.s/m     | 29200       | tunable | [paper] |
//! | K_phi    | 6   | N.m/rad   | 2.71e6      | tunable | [paper] (printed as MN/m) |
//! | r0       | 7   | m         | 0.43        | fixed   | [assumed] |
//! | lambda   | 8   | –         | 0.05        | fixed   | [lit] |
//! | mu       | 9   | –         | 0.15        | fixed   | [lit] |
//! | N        | 10  | N         | 66700       | fixed   | [assumed] |
//! | psi      | 11  | –         | 0.54219e-3  | fixed   | [lit] |
//! | phi_c    | 12  | –         | 0.60252e-3  | fixed   | [lit] |
//! | k0       | 13  | N/m       | 14.6e6      | fixed   | [lit] |
//! | delta    | 14  | m         | 9.1e-3      | fixed   | [lit] |
//! | V0       | 15  | m/s       | 100         | fixed   | [assumed] |
//! | ramp     | 16  | s²/m      | 10          | fixed   | [paper] Δf; 0 = constant speed |
//! | Y0       | 17  | m         | 0.012       | fixed   | [assumed] |
//! | phi0     | 18  | rad       | 0           | fixed   | [assumed] |
//! | dt       | 19  | s         | 1e-3        | fixed   | numerical: largest RK4 substep |
//!
//! Outputs (vr 100…): Y, phi, Yd, phid, V, y1, y2, F_T, Fx1, Fy1, Fx2, Fy2, Ydd, phidd,
//! xi_x1, xi_y1, xi_x2, xi_y2.
//!
//! Integration: classical RK4 with equal substeps no longer than `dt` (and no longer than the
//! inverse of the fastest rate of the linearised model at the current speed, which only binds
//! below ~23 m/s with the defaults). The flange force has kinks at ±δ, so the convergence order is
//! below four; the tests show that halving `dt` changes the critical speed by far less than
//! 0.01 m/s.
#![forbid(unsafe_code)]

use super::{
    require_finite, require_non_negative, require_positive, InitContext, Model, ModelError,
    ModelInfo, SetResult, StateReader, StateWriter, VarType, Variability, Variable,
};
use crate::solver::{rk4_step, substeps};
use nalgebra::Matrix4;

const VR_M_B: u32 = 0;
const VR_I_B: u32 = 1;
const VR_H: u32 = 2;
const VR_A: u32 = 3;
const VR_K_SY: u32 = 4;
const VR_C_SY: u32 = 5;
const VR_K_PHI: u32 = 6;
const VR_R0: u32 = 7;
const VR_LAMBDA: u32 = 8;
const VR_MU: u32 = 9;
const VR_N: u32 = 10;
const VR_PSI: u32 = 11;
const VR_PHI_C: u32 = 12;
const VR_K0: u32 = 13;
const VR_DELTA: u32 = 14;
const VR_V0: u32 = 15;
const VR_RAMP: u32 = 16;
const VR_Y0: u32 = 17;
const VR_PHI0: u32 = 18;
const VR_DT: u32 = 19;

const VR_Y: u32 = 100;
const VR_PHI: u32 = 101;
const VR_YD: u32 = 102;
const VR_PHID: u32 = 103;
const VR_V: u32 = 104;
const VR_Y1: u32 = 105;
const VR_Y2: u32 = 106;
const VR_F_T: u32 = 107;
const VR_FX1: u32 = 108;
const VR_FY1: u32 = 109;
const VR_FX2: u32 = 110;
const VR_FY2: u32 = 111;
const VR_YDD: u32 = 112;
const VR_PHIDD: u32 = 113;
const VR_XI_X1: u32 = 114;
const VR_XI_Y1: u32 = 115;
const VR_XI_X2: u32 = 116;
const VR_XI_Y2: u32 = 117;
const VR_V_CR_LINEAR: u32 = 120;

/// Lowest speed (m/s) the model runs at: the creepages divide by V.
pub const MIN_SPEED: f64 = 1.0;

const fn param(
    name: &'static str,
    vr: u32,
    start: f64,
    variability: Variability,
    unit: Option<&'static str>,
    min: Option<f64>,
    description: &'static str,
) -> Variable {
    Variable::real_parameter(name, vr, start, variability, unit, description).with_min(min)
}

const fn output(
    name: &'static str,
    vr: u32,
    unit: Option<&'static str>,
    description: &'static str,
) -> Variable {
    Variable::real_output(name, vr, unit, description)
}

use Variability::{Fixed, Tunable};

/// The bogie's variable table (parameters from vr 0, outputs from vr 100).
pub static VARIABLES: [Variable; 39] = [
    param("m_b", VR_M_B, 4963.0, Fixed, Some("kg"), Some(0.0), "Bogie mass: frame 2918.9 + 2 wheelsets x 1022 [paper]"),
    param("I_b", VR_I_B, 8135.0, Fixed, Some("kg.m2"), Some(0.0), "Bogie yaw moment of inertia: 6780 + 2 x 678 [paper]"),
    param("h", VR_H, 1.5, Fixed, Some("m"), Some(0.0), "Half wheelbase; leading wheelset at +h [paper]"),
    param("a", VR_A, 0.7175, Fixed, Some("m"), Some(0.0), "Half gauge (lateral semi-distance of the contact points) [paper]"),
    param("K_sy", VR_K_SY, 0.1823e6, Tunable, Some("N/m"), Some(0.0), "Lateral stiffness of the secondary suspension, per side [paper]"),
    param("C_sy", VR_C_SY, 29.2e3, Tunable, Some("N.s/m"), Some(0.0), "Lateral damping of the secondary suspension, per side [paper]"),
    param("K_phi", VR_K_PHI, 2.71e6, Tunable, Some("N.m/rad"), Some(0.0), "Anti-yaw stiffness (the paper prints the unit as MN/m) [paper]"),
    param("r0", VR_R0, 0.43, Fixed, Some("m"), Some(0.0), "Wheel rolling radius [assumed]; Cooperrider used 0.4572"),
    param("lambda", VR_LAMBDA, 0.05, Fixed, None, Some(0.0), "Wheel conicity (dimensionless) [lit] Cooperrider / True"),
    param("mu", VR_MU, 0.15, Fixed, None, Some(0.0), "Friction coefficient (dimensionless) [lit] dytsi"),
    param("N", VR_N, 66.7e3, Fixed, Some("N"), Some(0.0), "Normal load per wheel [assumed]"),
    param("psi", VR_PSI, 0.54219e-3, Fixed, None, Some(0.0), "Longitudinal creep normalisation psi (dimensionless) [lit] True & Kaas-Petersen"),
    param("phi_c", VR_PHI_C, 0.60252e-3, Fixed, None, Some(0.0), "Lateral creep normalisation phi (dimensionless) [lit] True & Kaas-Petersen"),
    param("k0", VR_K0, 14.60e6, Fixed, Some("N/m"), Some(0.0), "Flange stiffness [lit] True & Kaas-Petersen"),
    param("delta", VR_DELTA, 9.1e-3, Fixed, Some("m"), Some(0.0), "Flange clearance (dead band of the flange spring) [lit] True & Kaas-Petersen"),
    param("V0", VR_V0, 100.0, Fixed, Some("m/s"), Some(MIN_SPEED), "Speed at the start time; must exceed 1 m/s [assumed]"),
    param("ramp", VR_RAMP, 10.0, Fixed, None, None, "Speed ramp Df in s2/m: V = V0 - (t - t_start)/Df, i.e. the speed falls by 1/Df m/s per second; 0 = constant speed V0, < 0 = rising speed [paper eq. 29]"),
    param("Y0", VR_Y0, 0.012, Fixed, Some("m"), None, "Initial lateral displacement Y(t_start) [assumed]"),
    param("phi0", VR_PHI0, 0.0, Fixed, Some("rad"), None, "Initial yaw angle phi(t_start) [assumed]"),
    param("dt", VR_DT, 1e-3, Fixed, Some("s"), Some(0.0), "Largest internal RK4 step; each communication step is split into equal substeps no longer than dt [numerical]"),
    output("Y", VR_Y, Some("m"), "Lateral displacement of the bogie"),
    output("phi", VR_PHI, Some("rad"), "Yaw angle of the bogie"),
    output("Yd", VR_YD, Some("m/s"), "Lateral velocity Y'"),
    output("phid", VR_PHID, Some("rad/s"), "Yaw rate phi'"),
    output("V", VR_V, Some("m/s"), "Running speed V = V0 - (t - t_start)/ramp"),
    output("y1", VR_Y1, Some("m"), "Lateral displacement of the leading wheelset, Y + h phi"),
    output("y2", VR_Y2, Some("m"), "Lateral displacement of the trailing wheelset, Y - h phi"),
    output("F_T", VR_F_T, Some("N"), "Flange force on the leading wheelset (k0 (y1 - delta) beyond +delta; acts on the bogie as -F_T)"),
    output("Fx1", VR_FX1, Some("N"), "Longitudinal creep force, left wheel of the leading wheelset (the right wheel has -Fx1)"),
    output("Fy1", VR_FY1, Some("N"), "Lateral creep force, one wheel of the leading wheelset"),
    output("Fx2", VR_FX2, Some("N"), "Longitudinal creep force, left wheel of the trailing wheelset (the right wheel has -Fx2)"),
    output("Fy2", VR_FY2, Some("N"), "Lateral creep force, one wheel of the trailing wheelset"),
    output("Ydd", VR_YDD, Some("m/s2"), "Lateral acceleration Y''"),
    output("phidd", VR_PHIDD, Some("rad/s2"), "Yaw acceleration phi''"),
    output("xi_x1", VR_XI_X1, None, "Longitudinal creepage, left wheel of the leading wheelset (dimensionless)"),
    output("xi_y1", VR_XI_Y1, None, "Lateral creepage of the leading wheelset (dimensionless)"),
    output("xi_x2", VR_XI_X2, None, "Longitudinal creepage, left wheel of the trailing wheelset (dimensionless)"),
    output("xi_y2", VR_XI_Y2, None, "Lateral creepage of the trailing wheelset (dimensionless)"),
    Variable::calculated_parameter(
        "v_cr_linear",
        VR_V_CR_LINEAR,
        Some("m/s"),
        "Linear (Hopf) critical speed of the linearised model at the parameters of the initialization (eigenvalues; clamped to the search range 2..1000 m/s)",
    ),
];

/// Static description of the bogie model.
pub static INFO: ModelInfo = ModelInfo {
    name: "Bogie",
    description: "Two-DOF Cooperrider bogie (lateral + yaw) with nonlinear creep and flange forces on a speed ramp (railuq, paper section 4)",
    variables: &VARIABLES,
    default_start: 0.0,
    default_stop: 450.0,
    default_step: 0.01,
    documentation_html: r#"<p>Cooperrider's bogie as used by True, Kaas-Petersen and Bigoni: a frame with two rigidly
attached wheelsets (leading at +h, trailing at &minus;h), states lateral displacement <i>Y</i> and
yaw <i>&phi;</i>, running at a slowly falling speed <i>V</i> so that the speed at which the
hunting motion dies out (the nonlinear critical speed) can be read off.</p>
<pre>
y1 = Y + h &phi;,   y2 = Y &minus; h &phi;
&xi;x,i = a &phi;'/V + &lambda; y_i / r0,   &xi;y,i = y_i'/V &minus; &phi;     (left wheel; the right wheel has &minus;&xi;x)
u = &radic;((&xi;x/&psi;)&sup2; + (&xi;y/&#981;)&sup2;)
F_R = &mu;N (u &minus; u&sup2;/3 + u&sup3;/27) if u &lt; 3,   &mu;N if u &ge; 3      (Shen&ndash;Hedrick&ndash;Elkins)
Fx = F_R (&xi;x/&psi;)/u,   Fy = F_R (&xi;y/&#981;)/u             (u &rarr; 0: Fx = &mu;N &xi;x/&psi;, Fy = &mu;N &xi;y/&#981;)
F_T = k0 (y1 &minus; &delta;) if y1 &gt; &delta;;  0 if |y1| &le; &delta;;  k0 (y1 + &delta;) if y1 &lt; &minus;&delta;
m_b Y''  = &minus;2 C_sy Y' &minus; 2 K_sy Y &minus; 2 (Fy1 + Fy2) &minus; F_T                 (paper eq. 24)
I_b &phi;'' = &minus;K_&phi; &phi; &minus; 2h (Fy1 &minus; Fy2) &minus; 2a (Fx1 + Fx2) &minus; h F_T       (paper eq. 25)
V = V0 &minus; (t &minus; t_start)/&Delta;f                                            (paper eq. 29)
</pre>
<table>
<tr><th>parameter</th><th>default</th><th>source</th></tr>
<tr><td>m_b</td><td>4963 kg (frame 2918.9 + 2 &times; 1022)</td><td>[paper], [lit] dytsi input files</td></tr>
<tr><td>I_b</td><td>8135 kg&middot;m&sup2; (6780 + 2 &times; 678)</td><td>[paper], [lit] same</td></tr>
<tr><td>h, a</td><td>1.5 m, 0.7175 m</td><td>[paper]</td></tr>
<tr><td>K_sy, C_sy</td><td>0.1823 MN/m, 29.2 kN&middot;s/m (tunable)</td><td>[paper]</td></tr>
<tr><td>K_phi</td><td>2.71 MN&middot;m/rad (tunable; the paper prints MN/m)</td><td>[paper]</td></tr>
<tr><td>r0</td><td>0.43 m</td><td>[assumed]; Cooperrider used 0.4572 m</td></tr>
<tr><td>lambda</td><td>0.05</td><td>[lit] Cooperrider / True; the dominant unknown</td></tr>
<tr><td>mu, N</td><td>0.15, 66.7 kN</td><td>[lit] dytsi; [assumed]</td></tr>
<tr><td>psi, phi_c</td><td>0.54219e-3, 0.60252e-3</td><td>[lit] True &amp; Kaas-Petersen</td></tr>
<tr><td>k0, delta</td><td>14.60 MN/m, 9.1 mm</td><td>[lit] True &amp; Kaas-Petersen</td></tr>
<tr><td>V0, Y0, phi0</td><td>100 m/s, 12 mm, 0 rad</td><td>[assumed]</td></tr>
<tr><td>ramp (&Delta;f)</td><td>10 s&sup2;/m (0.1 m/s&sup2;); 0 = constant speed</td><td>[paper]</td></tr>
<tr><td>dt</td><td>1 ms</td><td>numerical</td></tr>
</table>
<p>K_sy, C_sy and K_phi are tunable (the random parameters of the paper's study); a change between
communication steps acts from the next step on. Negative or non-finite stiffnesses and
dampings, non-positive masses, lengths and creep normalisations are refused. The speed must stay
above 1 m/s (the creepages divide by V): a step that would reach V &le; 1 m/s fails with an error;
with the defaults that is after t = 990 s.</p>
<p>Integration: classical Runge&ndash;Kutta (RK4) with equal substeps no longer than <code>dt</code>
(1 ms) and no longer than the inverse of the fastest rate of the linearised model at the current
speed (this only binds below about 23 m/s with the defaults). The flange spring has kinks at
&plusmn;&delta;; halving <code>dt</code> changes Y by less than 1e-6 m over 20 s of hunting at 80 m/s
and leaves the critical speed unchanged at the 0.001 m/s resolution of a 0.01 s output grid.</p>
<p>With the defaults the hunting motion on the ramp from 100 m/s with Y0 = 12 mm dies out at
64.87 m/s (last |Y| &ge; 0.1 mm, confirmed by a 1 s window below it; 64.77 m/s at the end of the
window). The paper reports 64.82 m/s. The linear (Hopf) critical speed of the same model, with
creep forces linearised and no flange contact, is 74.92 m/s. At constant speed the hunting limit
cycle (amplitude about 9 mm, in flange contact) persists down to about 69.3 m/s: between 69.3 and
74.9 m/s both the centred motion and hunting are stable. The ramp value lies some 4.5 m/s lower
because the oscillation needs time to decay from 9 mm to 0.1 mm while the speed keeps falling, so
it depends on the ramp rate (&Delta;f = 5, 10, 20: 62.0, 64.9, 66.7 m/s) and on &lambda;
(0.045, 0.05, 0.055: 69.0, 64.9, 61.3 m/s).</p>"#,
};

/// Physical parameters of the bogie (SI units; see the module table).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BogieParams {
    /// Bogie mass m_b (kg).
    pub m_b: f64,
    /// Bogie yaw moment of inertia I_b (kg·m²).
    pub i_b: f64,
    /// Half wheelbase h (m).
    pub h: f64,
    /// Half gauge a (m).
    pub a: f64,
    /// Lateral secondary stiffness K_sy (N/m).
    pub k_sy: f64,
    /// Lateral secondary damping C_sy (N·s/m).
    pub c_sy: f64,
    /// Anti-yaw stiffness K_φ (N·m/rad).
    pub k_phi: f64,
    /// Rolling radius r0 (m).
    pub r0: f64,
    /// Conicity λ (1).
    pub lambda: f64,
    /// Friction coefficient μ (1).
    pub mu: f64,
    /// Wheel load N (N).
    pub n: f64,
    /// Longitudinal creep normalisation ψ (1).
    pub psi: f64,
    /// Lateral creep normalisation ϕ (1).
    pub phi_c: f64,
    /// Flange stiffness k0 (N/m).
    pub k0: f64,
    /// Flange clearance δ (m).
    pub delta: f64,
}

impl Default for BogieParams {
    fn default() -> Self {
        BogieParams {
            m_b: 4963.0,
            i_b: 8135.0,
            h: 1.5,
            a: 0.7175,
            k_sy: 0.1823e6,
            c_sy: 29.2e3,
            k_phi: 2.71e6,
            r0: 0.43,
            lambda: 0.05,
            mu: 0.15,
            n: 66.7e3,
            psi: 0.54219e-3,
            phi_c: 0.60252e-3,
            k0: 14.60e6,
            delta: 9.1e-3,
        }
    }
}

/// Creep forces (Fx, Fy) in N of one wheel with longitudinal creepage `xi_x` and lateral
/// creepage `xi_y` (both dimensionless): the linear law μN ξx/ψ, μN ξy/ϕ saturated by the
/// Shen–Hedrick–Elkins cubic, F_R = μN (u − u²/3 + u³/27) for u < 3 and μN beyond.
///
/// Written as F = μN (1 − u/3 + u²/27) (ξ/ψ) for u < 3, which is continuous at u = 0.
pub fn creep_force(xi_x: f64, xi_y: f64, p: &BogieParams) -> (f64, f64) {
    let ux = xi_x / p.psi;
    let uy = xi_y / p.phi_c;
    let u = (ux * ux + uy * uy).sqrt();
    let mun = p.mu * p.n;
    // Saturated force per unit normalised creepage, F_R/u.
    let ratio = if u < 3.0 {
        mun * (1.0 - u / 3.0 + u * u / 27.0)
    } else {
        mun / u
    };
    (ratio * ux, ratio * uy)
}

/// Flange force (N) at leading-wheelset displacement `y1` (m): a spring of stiffness `k0` (N/m)
/// beyond the clearance `delta` (m), zero inside it.
pub fn flange_force(y1: f64, k0: f64, delta: f64) -> f64 {
    if y1 > delta {
        k0 * (y1 - delta)
    } else if y1 < -delta {
        k0 * (y1 + delta)
    } else {
        0.0
    }
}

/// Everything the equations of motion compute from a state, for the outputs.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Forces {
    /// Leading wheelset lateral displacement (m).
    pub y1: f64,
    /// Trailing wheelset lateral displacement (m).
    pub y2: f64,
    /// Longitudinal creepage of the left wheel, leading wheelset (1).
    pub xi_x1: f64,
    /// Lateral creepage, leading wheelset (1).
    pub xi_y1: f64,
    /// Longitudinal creepage of the left wheel, trailing wheelset (1).
    pub xi_x2: f64,
    /// Lateral creepage, trailing wheelset (1).
    pub xi_y2: f64,
    /// Longitudinal creep force, left wheel, leading wheelset (N).
    pub fx1: f64,
    /// Lateral creep force per wheel, leading wheelset (N).
    pub fy1: f64,
    /// Longitudinal creep force, left wheel, trailing wheelset (N).
    pub fx2: f64,
    /// Lateral creep force per wheel, trailing wheelset (N).
    pub fy2: f64,
    /// Flange force on the leading wheelset (N).
    pub f_t: f64,
}

/// Creepages and forces at speed `v` (m/s) and state `x` = [Y (m), φ (rad), Y' (m/s), φ' (rad/s)].
pub fn forces(p: &BogieParams, v: f64, x: &[f64; 4]) -> Forces {
    let [y, phi, yd, phid] = *x;
    let y1 = y + p.h * phi;
    let y2 = y - p.h * phi;
    let y1d = yd + p.h * phid;
    let y2d = yd - p.h * phid;
    let spin = p.a * phid / v;
    let xi_x1 = spin + p.lambda * y1 / p.r0;
    let xi_y1 = y1d / v - phi;
    let xi_x2 = spin + p.lambda * y2 / p.r0;
    let xi_y2 = y2d / v - phi;
    let (fx1, fy1) = creep_force(xi_x1, xi_y1, p);
    let (fx2, fy2) = creep_force(xi_x2, xi_y2, p);
    Forces {
        y1,
        y2,
        xi_x1,
        xi_y1,
        xi_x2,
        xi_y2,
        fx1,
        fy1,
        fx2,
        fy2,
        f_t: flange_force(y1, p.k0, p.delta),
    }
}

/// Time derivative of the state `x` = [Y, φ, Y', φ'] at speed `v` (m/s): paper eq. 24–25.
/// Returns [Y' (m/s), φ' (rad/s), Y'' (m/s²), φ'' (rad/s²)].
pub fn rhs(p: &BogieParams, v: f64, x: &[f64; 4]) -> [f64; 4] {
    let f = forces(p, v, x);
    let [y, phi, yd, phid] = *x;
    let ydd = (-2.0 * p.c_sy * yd - 2.0 * p.k_sy * y - 2.0 * (f.fy1 + f.fy2) - f.f_t) / p.m_b;
    let phidd =
        (-p.k_phi * phi - 2.0 * p.h * (f.fy1 - f.fy2) - 2.0 * p.a * (f.fx1 + f.fx2) - p.h * f.f_t)
            / p.i_b;
    [yd, phid, ydd, phidd]
}

/// State matrix A (x' = A x, x = [Y, φ, Y', φ']) of the model linearised about the centred
/// motion at speed `v` (m/s): creep forces F = μN ξ/ψ, μN ξ/ϕ, no flange contact.
pub fn linear_state_matrix(p: &BogieParams, v: f64) -> Matrix4<f64> {
    let cx = p.mu * p.n / p.psi; // N per unit longitudinal creepage
    let cy = p.mu * p.n / p.phi_c; // N per unit lateral creepage
    let (m, i) = (p.m_b, p.i_b);
    // Y''  = [-2K Y - 2C Y' - 2cy (2Y'/V - 2φ)] / m
    // φ'' = [-Kφ φ - 2h cy (2h φ'/V) - 2a cx (2a φ'/V + 2λ Y/r0)] / I
    Matrix4::new(
        0.0,
        0.0,
        1.0,
        0.0,
        0.0,
        0.0,
        0.0,
        1.0,
        -2.0 * p.k_sy / m,
        4.0 * cy / m,
        -(2.0 * p.c_sy + 4.0 * cy / v) / m,
        0.0,
        -4.0 * p.a * cx * p.lambda / (p.r0 * i),
        -p.k_phi / i,
        0.0,
        -4.0 * (p.h * p.h * cy + p.a * p.a * cx) / (v * i),
    )
}

/// Largest real part (1/s) of the eigenvalues of [`linear_state_matrix`] at speed `v` (m/s).
pub fn linear_growth_rate(p: &BogieParams, v: f64) -> f64 {
    linear_state_matrix(p, v)
        .complex_eigenvalues()
        .iter()
        .map(|z| z.re)
        .fold(f64::NEG_INFINITY, f64::max)
}

/// Linear (Hopf) critical speed (m/s) of the bogie's parameters: the lowest speed at which the
/// largest real part of the eigenvalues of the linearised state matrix crosses zero, found by a
/// scan in 1 m/s steps from 2 to 1000 m/s and bisection to 1e-9 m/s. Returns `f64::INFINITY` if
/// the linearised model is stable over the whole scan, and `f64::NAN` if it is already unstable
/// at 2 m/s (for instance with a negative stiffness).
pub fn linear_critical_speed(bogie: &Bogie) -> f64 {
    let p = &bogie.p;
    let g = |v: f64| linear_growth_rate(p, v);
    let mut lo = 2.0;
    let g_lo = g(lo);
    if g_lo.is_nan() || g_lo >= 0.0 {
        return f64::NAN;
    }
    let mut hi = f64::INFINITY;
    let mut v = lo;
    while v < 1000.0 {
        let next = v + 1.0;
        if g(next) >= 0.0 {
            lo = v;
            hi = next;
            break;
        }
        v = next;
    }
    if hi.is_infinite() {
        return f64::INFINITY;
    }
    while hi - lo > 1e-9 {
        let mid = 0.5 * (lo + hi);
        if g(mid) < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

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
    /// Start time of the run (s), where V = V0.
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
        let mut b = Bogie {
            p: BogieParams::default(),
            v0: 100.0,
            ramp: 10.0,
            y0: 0.012,
            phi0: 0.0,
            dt: 1e-3,
            t_start: 0.0,
            t: 0.0,
            x: [0.012, 0.0, 0.0, 0.0],
            v_cr_linear: f64::NAN,
        };
        b.v_cr_linear = clamped_linear_critical_speed(&b);
        b
    }
}

/// [`linear_critical_speed`] clamped to the search range 2..1000 m/s, so the output is finite.
fn clamped_linear_critical_speed(b: &Bogie) -> f64 {
    let v = linear_critical_speed(b);
    if v.is_nan() {
        2.0
    } else {
        v.min(1000.0)
    }
}

/// Number of f64 values written by [`Model::save`].
const SAVED_LEN: usize = 15 + 7 + 4;

impl Bogie {
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
        ModelError::SolverFailure {
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

    fn get_real(&self, vr: u32) -> Result<f64, ModelError> {
        let p = &self.p;
        let needs_forces = (VR_Y1..=VR_XI_Y2).contains(&vr);
        let v = self.speed(self.t);
        let f = if needs_forces {
            forces(p, v, &self.x)
        } else {
            Forces::default()
        };
        Ok(match vr {
            VR_M_B => p.m_b,
            VR_I_B => p.i_b,
            VR_H => p.h,
            VR_A => p.a,
            VR_K_SY => p.k_sy,
            VR_C_SY => p.c_sy,
            VR_K_PHI => p.k_phi,
            VR_R0 => p.r0,
            VR_LAMBDA => p.lambda,
            VR_MU => p.mu,
            VR_N => p.n,
            VR_PSI => p.psi,
            VR_PHI_C => p.phi_c,
            VR_K0 => p.k0,
            VR_DELTA => p.delta,
            VR_V0 => self.v0,
            VR_RAMP => self.ramp,
            VR_Y0 => self.y0,
            VR_PHI0 => self.phi0,
            VR_DT => self.dt,
            VR_Y => self.x[0],
            VR_PHI => self.x[1],
            VR_YD => self.x[2],
            VR_PHID => self.x[3],
            VR_V => v,
            VR_Y1 => f.y1,
            VR_Y2 => f.y2,
            VR_F_T => f.f_t,
            VR_FX1 => f.fx1,
            VR_FY1 => f.fy1,
            VR_FX2 => f.fx2,
            VR_FY2 => f.fy2,
            VR_YDD => rhs(p, v, &self.x)[2],
            VR_PHIDD => rhs(p, v, &self.x)[3],
            VR_XI_X1 => f.xi_x1,
            VR_XI_Y1 => f.xi_y1,
            VR_XI_X2 => f.xi_x2,
            VR_XI_Y2 => f.xi_y2,
            VR_V_CR_LINEAR => self.v_cr_linear,
            _ => return Err(ModelError::NoSuchVariable(VarType::Real, vr)),
        })
    }

    fn set_real(&mut self, vr: u32, value: f64) -> SetResult {
        let p = &mut self.p;
        match vr {
            VR_M_B => {
                require_positive("m_b", value)?;
                p.m_b = value;
            }
            VR_I_B => {
                require_positive("I_b", value)?;
                p.i_b = value;
            }
            VR_H => {
                require_positive("h", value)?;
                p.h = value;
            }
            VR_A => {
                require_positive("a", value)?;
                p.a = value;
            }
            VR_K_SY => {
                require_non_negative("K_sy", value)?;
                p.k_sy = value;
            }
            VR_C_SY => {
                require_non_negative("C_sy", value)?;
                p.c_sy = value;
            }
            VR_K_PHI => {
                require_non_negative("K_phi", value)?;
                p.k_phi = value;
            }
            VR_R0 => {
                require_positive("r0", value)?;
                p.r0 = value;
            }
            VR_LAMBDA => {
                require_non_negative("lambda", value)?;
                p.lambda = value;
            }
            VR_MU => {
                require_non_negative("mu", value)?;
                p.mu = value;
            }
            VR_N => {
                require_non_negative("N", value)?;
                p.n = value;
            }
            VR_PSI => {
                require_positive("psi", value)?;
                p.psi = value;
            }
            VR_PHI_C => {
                require_positive("phi_c", value)?;
                p.phi_c = value;
            }
            VR_K0 => {
                require_non_negative("k0", value)?;
                p.k0 = value;
            }
            VR_DELTA => {
                require_non_negative("delta", value)?;
                p.delta = value;
            }
            VR_V0 => {
                require_finite("V0", value)?;
                if value <= MIN_SPEED {
                    return Err(ModelError::InvalidValue {
                        name: "V0",
                        value: value.to_string(),
                        reason: format!(
                            "must exceed {MIN_SPEED} m/s (the creepages divide by the speed)"
                        ),
                    });
                }
                self.v0 = value;
            }
            VR_RAMP => {
                require_finite("ramp", value)?;
                self.ramp = value;
            }
            VR_Y0 => {
                require_finite("Y0", value)?;
                self.y0 = value;
            }
            VR_PHI0 => {
                require_finite("phi0", value)?;
                self.phi0 = value;
            }
            VR_DT => {
                require_positive("dt", value)?;
                self.dt = value;
            }
            _ => return Err(ModelError::NoSuchVariable(VarType::Real, vr)),
        }
        Ok(None)
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
        let n = substeps(h, h_max);
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

    fn clone_box(&self) -> Box<dyn Model> {
        Box::new(self.clone())
    }

    fn save(&self, out: &mut StateWriter) {
        let p = &self.p;
        out.f64s(&[
            p.m_b,
            p.i_b,
            p.h,
            p.a,
            p.k_sy,
            p.c_sy,
            p.k_phi,
            p.r0,
            p.lambda,
            p.mu,
            p.n,
            p.psi,
            p.phi_c,
            p.k0,
            p.delta,
            self.v0,
            self.ramp,
            self.y0,
            self.phi0,
            self.dt,
            self.t_start,
            self.t,
            self.x[0],
            self.x[1],
            self.x[2],
            self.x[3],
        ]);
    }

    fn restore(&mut self, input: &mut StateReader<'_>) -> Result<(), ModelError> {
        let v = input.f64s(Some(SAVED_LEN))?;
        *self = Bogie {
            p: BogieParams {
                m_b: v[0],
                i_b: v[1],
                h: v[2],
                a: v[3],
                k_sy: v[4],
                c_sy: v[5],
                k_phi: v[6],
                r0: v[7],
                lambda: v[8],
                mu: v[9],
                n: v[10],
                psi: v[11],
                phi_c: v[12],
                k0: v[13],
                delta: v[14],
            },
            v0: v[15],
            ramp: v[16],
            y0: v[17],
            phi0: v[18],
            dt: v[19],
            t_start: v[20],
            t: v[21],
            x: [v[22], v[23], v[24], v[25]],
            v_cr_linear: f64::NAN,
        };
        self.v_cr_linear = clamped_linear_critical_speed(self);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Runs `b` from t = 0 to `stop` (s) with communication step `comm` (s) and returns the
    /// samples (t, Y, V).
    fn run(b: &mut Bogie, stop: f64, comm: f64) -> Vec<(f64, f64, f64)> {
        b.initialize(&InitContext::default()).unwrap();
        let n = (stop / comm).round() as usize;
        let mut out = Vec::with_capacity(n + 1);
        out.push((0.0, b.x[0], b.speed(0.0)));
        for i in 0..n {
            let t = i as f64 * comm;
            b.do_step(t, comm).unwrap();
            let t1 = (i + 1) as f64 * comm;
            out.push((t1, b.x[0], b.speed(t1)));
        }
        out
    }

    /// The paper's "speed at which the oscillation dies out", as the uq-driver's critical-speed
    /// quantity defines it: t* is the first sample time after which every trailing `window` (s)
    /// holds only |Y| < `threshold` (m); the speed reported is V(t* − window). With samples
    /// every `comm` s, t* − window lies within one sample after the last |Y| >= threshold.
    fn died_out_speed(samples: &[(f64, f64, f64)], window: f64, threshold: f64) -> Option<f64> {
        let last = samples.iter().rposition(|s| s.1.abs() >= threshold)?;
        let t_last = samples[last].0;
        let star = samples.iter().find(|s| s.0 - window > t_last)?.0;
        let (t0, v0) = (samples[0].0, samples[0].2);
        let slope = (samples[1].2 - v0) / (samples[1].0 - t0); // the speed is linear in t
        Some(v0 + slope * (star - window - t0))
    }

    fn max_abs_y(samples: &[(f64, f64, f64)], from: f64) -> f64 {
        samples
            .iter()
            .filter(|s| s.0 >= from)
            .fold(0.0, |m, s| m.max(s.1.abs()))
    }

    #[test]
    fn creep_law_is_continuous_at_saturation_and_linear_for_small_creepage() {
        let p = BogieParams::default();
        let mun = p.mu * p.n;
        // Along several directions, u = 3 ± ε gives the same force, of magnitude μN.
        for angle in [0.0f64, 0.3, 1.0, 2.5, 4.0] {
            let (cx, cy) = (angle.cos() * p.psi, angle.sin() * p.phi_c);
            let below = creep_force(cx * (3.0 - 1e-9), cy * (3.0 - 1e-9), &p);
            let above = creep_force(cx * (3.0 + 1e-9), cy * (3.0 + 1e-9), &p);
            assert!((below.0 - above.0).abs() < 1e-5 * mun, "{angle}");
            assert!((below.1 - above.1).abs() < 1e-5 * mun, "{angle}");
            let r = below.0.hypot(below.1);
            assert!((r - mun).abs() < 1e-6 * mun, "|F| = {r} at u = 3");
            // Far beyond saturation the resultant stays μN.
            let far = creep_force(cx * 50.0, cy * 50.0, &p);
            assert!((far.0.hypot(far.1) - mun).abs() < 1e-9 * mun);
        }
        // u -> 0: F -> μN ξ/ψ, μN ξ/ϕ (no 0/0).
        assert_eq!(creep_force(0.0, 0.0, &p), (0.0, 0.0));
        let (xx, xy) = (1e-10, -2e-10);
        let (fx, fy) = creep_force(xx, xy, &p);
        assert!((fx / (mun * xx / p.psi) - 1.0).abs() < 1e-6);
        assert!((fy / (mun * xy / p.phi_c) - 1.0).abs() < 1e-6);
        // The cubic itself: u = 1 along x gives μN (1 - 1/3 + 1/27).
        let (fx, fy) = creep_force(p.psi, 0.0, &p);
        assert!((fx - mun * (1.0 - 1.0 / 3.0 + 1.0 / 27.0)).abs() < 1e-9 * mun);
        assert_eq!(fy, 0.0);
    }

    #[test]
    fn flange_force_is_continuous_at_clearance_and_odd() {
        let (k0, d) = (14.6e6, 9.1e-3);
        for y in [d - 1e-12, d, d + 1e-12] {
            assert!(flange_force(y, k0, d).abs() < 1e-4, "{y}");
            assert!(flange_force(-y, k0, d).abs() < 1e-4, "{y}");
        }
        assert_eq!(flange_force(0.0, k0, d), 0.0);
        assert_eq!(flange_force(0.5 * d, k0, d), 0.0);
        for y in [0.0, 0.005, 0.0091, 0.0095, 0.012, 0.05] {
            assert_eq!(flange_force(-y, k0, d), -flange_force(y, k0, d));
        }
        assert!((flange_force(0.0101, k0, d) - k0 * 0.001).abs() < 1e-6);
    }

    #[test]
    fn linear_state_matrix_is_the_jacobian_of_rhs_at_the_centre() {
        let p = BogieParams::default();
        for v in [30.0, 75.0, 120.0] {
            let a = linear_state_matrix(&p, v);
            // Central differences with steps far inside the dead band and the linear creep range.
            let steps = [1e-7, 1e-8, 1e-6, 1e-7];
            for j in 0..4 {
                let mut xp = [0.0; 4];
                let mut xm = [0.0; 4];
                xp[j] = steps[j];
                xm[j] = -steps[j];
                let (fp, fm) = (rhs(&p, v, &xp), rhs(&p, v, &xm));
                for i in 0..4 {
                    let d = (fp[i] - fm[i]) / (2.0 * steps[j]);
                    let scale = a[(i, j)].abs().max(1e-6);
                    assert!(
                        (d - a[(i, j)]).abs() < 1e-4 * scale,
                        "V={v} A[{i},{j}] = {} vs finite difference {d}",
                        a[(i, j)]
                    );
                }
            }
        }
    }

    #[test]
    fn linear_critical_speed_is_near_75() {
        let b = Bogie::default();
        let v = linear_critical_speed(&b);
        assert!((v - 74.92).abs() < 0.01, "v_lin = {v}");
        assert!(linear_growth_rate(&b.p, v - 0.01) < 0.0);
        assert!(linear_growth_rate(&b.p, v + 0.01) > 0.0);
        // Stiffer anti-yaw suspension raises it; a larger conicity lowers it.
        let mut stiff = Bogie::default();
        stiff.p.k_phi *= 1.1;
        assert!(linear_critical_speed(&stiff) > v);
        let mut conic = Bogie::default();
        conic.p.lambda = 0.055;
        assert!(linear_critical_speed(&conic) < v);
    }

    #[test]
    fn small_disturbance_decays_below_and_grows_above_the_linear_critical_speed() {
        let v_lin = linear_critical_speed(&Bogie::default());
        let at = |v: f64| {
            let mut b = Bogie {
                v0: v,
                ramp: 0.0,
                y0: 1e-3,
                ..Bogie::default()
            };
            let s = run(&mut b, 40.0, 0.01);
            assert!(s.iter().all(|x| x.2 == v), "constant speed");
            max_abs_y(&s, 38.0)
        };
        let below = at(0.95 * v_lin);
        let above = at(1.05 * v_lin);
        assert!(
            below < 1e-4,
            "at 0.95 v_lin the 1 mm disturbance should decay: {below}"
        );
        assert!(
            above > 5e-3,
            "at 1.05 v_lin it should grow into hunting: {above}"
        );
    }

    #[test]
    fn halving_dt_changes_y_by_less_than_2e_6_m_over_20_s() {
        // 20 s from V0 = 80 m/s (hunting with flange contact, amplitude ~ 9 mm). The flange kinks
        // at ±δ make the convergence order irregular: max |Y(dt) - Y(dt/2)| measured for
        // dt = 4, 2, 1, 0.5, 0.25 ms: 2.8e-6, 3.1e-6, 8.0e-7, 2.0e-7, 1.1e-7 m. The default
        // dt = 1 ms is within 1e-4 of the amplitude of dt/2.
        let traj = |dt: f64| {
            let mut b = Bogie {
                v0: 80.0,
                dt,
                ..Bogie::default()
            };
            run(&mut b, 20.0, 0.01)
        };
        let (coarse, fine) = (traj(1e-3), traj(5e-4));
        let amplitude = max_abs_y(&coarse, 10.0);
        assert!(amplitude > 8e-3, "hunting expected: {amplitude}");
        let diff = coarse
            .iter()
            .zip(&fine)
            .map(|(c, f)| (c.1 - f.1).abs())
            .fold(0.0, f64::max);
        assert!(diff < 2e-6, "max |Y(dt) - Y(dt/2)| = {diff:e} m");
    }

    #[test]
    fn ramp_critical_speed_matches_the_paper_within_1_percent() {
        // The paper's ramp: V0 = 100 m/s, Δf = 10, Y0 = 12 mm; "died out" = 1 s sliding maximum
        // of |Y| below 0.1 mm; speed read at the start of the quiet window. Measured 64.865 m/s
        // (V at the end of the window: 64.765 m/s); the paper reports 64.82 m/s, MODELS.md's
        // reconstruction ~64.7 m/s. Halving dt does not move it (the same 0.01 s sample).
        let vcr = |dt: f64| {
            let mut b = Bogie {
                dt,
                ..Bogie::default()
            };
            let s = run(&mut b, 400.0, 0.01);
            died_out_speed(&s, 1.0, 1e-4).expect("the hunting dies out on the ramp")
        };
        let (v, v_half) = (vcr(1e-3), vcr(5e-4));
        assert!((v - v_half).abs() < 0.01, "dt 1 ms: {v}, 0.5 ms: {v_half}");
        let paper = 64.82;
        assert!(
            (v - paper).abs() < 0.01 * paper,
            "v_cr = {v} vs paper {paper}"
        );
        assert!((v - 64.865).abs() < 0.005, "regression: v_cr = {v}");
    }

    #[test]
    fn full_ramp_reaches_55_m_per_s_and_stops_before_1_m_per_s() {
        let mut b = Bogie::default();
        b.initialize(&InitContext::default()).unwrap();
        // One big communication step exercises the substep logic.
        b.do_step(0.0, 450.0).unwrap();
        assert!((b.get_real(VR_V).unwrap() - 55.0).abs() < 1e-9);
        assert!(b.get_real(VR_Y).unwrap().abs() < 1e-9, "hunting died out");
        // Slow speeds are stable thanks to the rate-limited substeps, down to the guard.
        let mut slow = Bogie {
            v0: 10.0,
            ramp: 1.0,
            ..Bogie::default()
        };
        slow.initialize(&InitContext::default()).unwrap();
        let mut i = 0;
        let err = loop {
            match slow.do_step(0.1 * i as f64, 0.1) {
                Ok(()) => i += 1,
                Err(e) => break e,
            }
            assert!(slow.x.iter().all(|x| x.is_finite()));
            assert!(i < 100, "the speed guard must fire before t = 9 s");
        };
        assert_eq!(i, 89, "the step from 8.9 s to 9 s reaches V = 1 m/s");
        let msg = err.to_string();
        assert!(msg.contains("1 m/s") && msg.contains("t = 9 s"), "{msg}");
    }

    #[test]
    fn refuses_bad_parameters() {
        let mut b = Bogie::default();
        for vr in [VR_K_SY, VR_C_SY, VR_K_PHI, VR_K0] {
            assert!(b.set_real(vr, -1.0).is_err(), "vr {vr} negative");
            assert!(b.set_real(vr, f64::NAN).is_err(), "vr {vr} NaN");
            assert!(b.set_real(vr, f64::INFINITY).is_err(), "vr {vr} inf");
        }
        for vr in [VR_M_B, VR_I_B, VR_H, VR_A, VR_R0, VR_PSI, VR_PHI_C, VR_DT] {
            assert!(b.set_real(vr, 0.0).is_err(), "vr {vr} zero");
            assert!(b.set_real(vr, -1.0).is_err(), "vr {vr} negative");
        }
        assert!(b.set_real(VR_V0, 1.0).is_err());
        assert!(b.set_real(VR_V0, f64::NAN).is_err());
        assert!(b.set_real(VR_RAMP, f64::INFINITY).is_err());
        assert!(b.set_real(VR_Y, 0.0).is_err(), "outputs are not settable");
        assert!(b.set_real(999, 0.0).is_err());
        // Refused values leave the parameter unchanged.
        assert_eq!(b.get_real(VR_K_SY).unwrap(), 0.1823e6);
        // Legal edge values.
        assert!(b.set_real(VR_K_SY, 0.0).unwrap().is_none());
        assert!(b.set_real(VR_RAMP, 0.0).unwrap().is_none());
        assert!(b.set_real(VR_RAMP, -5.0).unwrap().is_none());
    }

    #[test]
    fn tunable_parameters_act_from_the_next_step() {
        let mut a = Bogie::default();
        let mut b = Bogie::default();
        a.initialize(&InitContext::default()).unwrap();
        b.initialize(&InitContext::default()).unwrap();
        a.do_step(0.0, 1.0).unwrap();
        b.do_step(0.0, 1.0).unwrap();
        b.set_real(VR_K_SY, 0.2e6).unwrap();
        a.do_step(1.0, 0.5).unwrap();
        b.do_step(1.0, 0.5).unwrap();
        assert_ne!(a.x, b.x);
    }

    #[test]
    fn save_restore_round_trip() {
        let mut b = Bogie {
            v0: 90.0,
            ..Bogie::default()
        };
        b.set_real(VR_C_SY, 31e3).unwrap();
        b.initialize(&InitContext {
            start_time: 2.0,
            ..InitContext::default()
        })
        .unwrap();
        b.do_step(2.0, 0.37).unwrap();
        let mut out = StateWriter::default();
        b.save(&mut out);
        let mut c = Bogie::default();
        c.restore(&mut StateReader::new(&out.bytes)).unwrap();
        assert_eq!(c.x, b.x);
        assert_eq!(c.p, b.p);
        for v in &VARIABLES {
            assert_eq!(
                b.get_real(v.vr).unwrap().to_bits(),
                c.get_real(v.vr).unwrap().to_bits(),
                "{}",
                v.name
            );
        }
        // Both continue identically.
        b.do_step(2.37, 0.5).unwrap();
        c.do_step(2.37, 0.5).unwrap();
        assert_eq!(c.x, b.x);
        assert!(c
            .restore(&mut StateReader::new(&out.bytes[..out.bytes.len() - 3]))
            .is_err());
    }

    #[test]
    fn variable_table_matches_defaults_and_units() {
        let b = Bogie::default();
        for w in VARIABLES.windows(2) {
            assert!(w[0].vr < w[1].vr, "vr not sorted at {}", w[1].name);
        }
        let mut names: Vec<_> = VARIABLES.iter().map(|v| v.name).collect();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), VARIABLES.len());
        for v in &VARIABLES {
            let value = b.get_real(v.vr).unwrap();
            assert!(value.is_finite(), "{}", v.name);
            if let crate::models::Start::Real(Some(start)) = v.start {
                assert_eq!(value, start, "{}: start value vs Bogie::default()", v.name);
            }
            if let Some(u) = v.unit {
                assert!(
                    crate::fmi2::xml::UNITS.iter().any(|(n, _)| *n == u),
                    "{}: unit {u} not in the unit table",
                    v.name
                );
            }
        }
        assert!(crate::fmi2::xml::model_description(&INFO).is_ok());
    }

    #[test]
    fn outputs_are_consistent_with_the_equations() {
        let mut b = Bogie::default();
        b.initialize(&InitContext::default()).unwrap();
        b.do_step(0.0, 3.21).unwrap();
        let g = |vr| b.get_real(vr).unwrap();
        let (y, phi) = (g(VR_Y), g(VR_PHI));
        assert!((g(VR_V) - (100.0 - 0.321)).abs() < 1e-12);
        assert_eq!(g(VR_Y1), y + 1.5 * phi);
        assert_eq!(g(VR_Y2), y - 1.5 * phi);
        assert_eq!(g(VR_F_T), flange_force(g(VR_Y1), 14.6e6, 9.1e-3));
        let (fx1, fy1) = creep_force(g(VR_XI_X1), g(VR_XI_Y1), &b.p);
        assert_eq!((g(VR_FX1), g(VR_FY1)), (fx1, fy1));
        let ydd = (-2.0 * 29.2e3 * g(VR_YD)
            - 2.0 * 0.1823e6 * y
            - 2.0 * (g(VR_FY1) + g(VR_FY2))
            - g(VR_F_T))
            / 4963.0;
        assert!((g(VR_YDD) - ydd).abs() < 1e-9 * ydd.abs().max(1.0));
    }
}
