//! The bogie's variables, one line each (see [`crate::models::table`]), and its description.
#![forbid(unsafe_code)]

use super::equations::{forces, rhs};
use super::{Bogie, MIN_SPEED};
use crate::models::table::{finite, non_negative, positive, variables};
use crate::models::{ModelError, ModelInfo, SetResult};

/// V0 must exceed [`MIN_SPEED`]: the creepages divide by the speed.
fn above_min_speed(name: &'static str, value: f64) -> SetResult {
    finite(name, value)?;
    if value <= MIN_SPEED {
        return Err(ModelError::invalid(
            name,
            value,
            format!("must exceed {MIN_SPEED} m/s (the creepages divide by the speed)"),
        ));
    }
    Ok(None)
}

// Parameters from vr 0, outputs from vr 100; `b` is the model.
variables! {
    static TABLE: [Bogie as b];
    real_parameter("m_b", VR_M_B = 0, Some("kg"), b.p.m_b, 4963.0, Fixed, positive, "Bogie mass: frame 2918.9 + 2 wheelsets x 1022 [paper]", min = 0.0),
    real_parameter("I_b", VR_I_B = 1, Some("kg.m2"), b.p.i_b, 8135.0, Fixed, positive, "Bogie yaw moment of inertia: 6780 + 2 x 678 [paper]", min = 0.0),
    real_parameter("h", VR_H = 2, Some("m"), b.p.h, 1.5, Fixed, positive, "Half wheelbase; leading wheelset at +h [paper]", min = 0.0),
    real_parameter("a", VR_A = 3, Some("m"), b.p.a, 0.7175, Fixed, positive, "Half gauge (lateral semi-distance of the contact points) [paper]", min = 0.0),
    real_parameter("K_sy", VR_K_SY = 4, Some("N/m"), b.p.k_sy, 0.1823e6, Tunable, non_negative, "Lateral stiffness of the secondary suspension, per side [paper]", min = 0.0),
    real_parameter("C_sy", VR_C_SY = 5, Some("N.s/m"), b.p.c_sy, 29.2e3, Tunable, non_negative, "Lateral damping of the secondary suspension, per side [paper]", min = 0.0),
    real_parameter("K_phi", VR_K_PHI = 6, Some("N.m/rad"), b.p.k_phi, 2.71e6, Tunable, non_negative, "Anti-yaw stiffness (the paper prints the unit as MN/m) [paper]", min = 0.0),
    real_parameter("r0", VR_R0 = 7, Some("m"), b.p.r0, 0.43, Fixed, positive, "Wheel rolling radius [assumed]; Cooperrider used 0.4572", min = 0.0),
    real_parameter("lambda", VR_LAMBDA = 8, None, b.p.lambda, 0.05, Fixed, non_negative, "Wheel conicity (dimensionless) [lit] Cooperrider / True", min = 0.0),
    real_parameter("mu", VR_MU = 9, None, b.p.mu, 0.15, Fixed, non_negative, "Friction coefficient (dimensionless) [lit] dytsi", min = 0.0),
    real_parameter("N", VR_N = 10, Some("N"), b.p.n, 66.7e3, Fixed, non_negative, "Normal load per wheel [assumed]", min = 0.0),
    real_parameter("psi", VR_PSI = 11, None, b.p.psi, 0.54219e-3, Fixed, positive, "Longitudinal creep normalisation psi (dimensionless) [lit] True & Kaas-Petersen", min = 0.0),
    real_parameter("phi_c", VR_PHI_C = 12, None, b.p.phi_c, 0.60252e-3, Fixed, positive, "Lateral creep normalisation phi (dimensionless) [lit] True & Kaas-Petersen", min = 0.0),
    real_parameter("k0", VR_K0 = 13, Some("N/m"), b.p.k0, 14.60e6, Fixed, non_negative, "Flange stiffness [lit] True & Kaas-Petersen", min = 0.0),
    real_parameter("delta", VR_DELTA = 14, Some("m"), b.p.delta, 9.1e-3, Fixed, non_negative, "Flange clearance (dead band of the flange spring) [lit] True & Kaas-Petersen", min = 0.0),
    real_parameter("V0", VR_V0 = 15, Some("m/s"), b.v0, 100.0, Tunable, above_min_speed, "Speed at the start time; must exceed 1 m/s; set between steps it takes effect from then on (the ramp restarts from it) [assumed]", min = MIN_SPEED),
    real_parameter("ramp", VR_RAMP = 16, Some("s2/m"), b.ramp, 10.0, Fixed, finite, "Speed ramp Df in s2/m: V = V0 - (t - t_start)/Df, i.e. the speed falls by 1/Df m/s per second; 0 = constant speed V0, < 0 = rising speed [paper eq. 29]"),
    real_parameter("Y0", VR_Y0 = 17, Some("m"), b.y0, 0.012, Fixed, finite, "Initial lateral displacement Y(t_start) [assumed]"),
    real_parameter("phi0", VR_PHI0 = 18, Some("rad"), b.phi0, 0.0, Fixed, finite, "Initial yaw angle phi(t_start) [assumed]"),
    real_parameter("dt", VR_DT = 19, Some("s"), b.dt, 1e-3, Fixed, positive, "Largest internal RK4 step; each communication step is split into equal substeps no longer than dt [numerical]", min = 0.0),
    output("Y", VR_Y = 100, Some("m"), b.x[0], "Lateral displacement of the bogie"),
    output("phi", VR_PHI = 101, Some("rad"), b.x[1], "Yaw angle of the bogie"),
    output("Yd", VR_YD = 102, Some("m/s"), b.x[2], "Lateral velocity Y'"),
    output("phid", VR_PHID = 103, Some("rad/s"), b.x[3], "Yaw rate phi'"),
    output("V", VR_V = 104, Some("m/s"), b.speed(b.t), "Running speed V = V0 - (t - t_start)/ramp"),
    output("y1", VR_Y1 = 105, Some("m"), b.forces().y1, "Lateral displacement of the leading wheelset, Y + h phi"),
    output("y2", VR_Y2 = 106, Some("m"), b.forces().y2, "Lateral displacement of the trailing wheelset, Y - h phi"),
    output("F_T", VR_F_T = 107, Some("N"), b.forces().f_t, "Flange force on the leading wheelset (k0 (y1 - delta) beyond +delta; acts on the bogie as -F_T)"),
    output("Fx1", VR_FX1 = 108, Some("N"), b.forces().fx1, "Longitudinal creep force, left wheel of the leading wheelset (the right wheel has -Fx1)"),
    output("Fy1", VR_FY1 = 109, Some("N"), b.forces().fy1, "Lateral creep force, one wheel of the leading wheelset"),
    output("Fx2", VR_FX2 = 110, Some("N"), b.forces().fx2, "Longitudinal creep force, left wheel of the trailing wheelset (the right wheel has -Fx2)"),
    output("Fy2", VR_FY2 = 111, Some("N"), b.forces().fy2, "Lateral creep force, one wheel of the trailing wheelset"),
    output("Ydd", VR_YDD = 112, Some("m/s2"), rhs(&b.p, b.speed(b.t), &b.x)[2], "Lateral acceleration Y''"),
    output("phidd", VR_PHIDD = 113, Some("rad/s2"), rhs(&b.p, b.speed(b.t), &b.x)[3], "Yaw acceleration phi''"),
    output("xi_x1", VR_XI_X1 = 114, None, b.forces().xi_x1, "Longitudinal creepage, left wheel of the leading wheelset (dimensionless)"),
    output("xi_y1", VR_XI_Y1 = 115, None, b.forces().xi_y1, "Lateral creepage of the leading wheelset (dimensionless)"),
    output("xi_x2", VR_XI_X2 = 116, None, b.forces().xi_x2, "Longitudinal creepage, left wheel of the trailing wheelset (dimensionless)"),
    output("xi_y2", VR_XI_Y2 = 117, None, b.forces().xi_y2, "Lateral creepage of the trailing wheelset (dimensionless)"),
    calculated("v_cr_linear", VR_V_CR_LINEAR = 120, Some("m/s"), b.v_cr_linear, "Linear (Hopf) critical speed of the linearised model at the parameters of the initialization (eigenvalues; clamped to the search range 2..1000 m/s)"),
}

impl Bogie {
    /// Creepages and forces of the current state.
    fn forces(&self) -> super::Forces {
        forces(&self.p, self.speed(self.t), &self.x)
    }
}

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
communication steps acts from the next step on. V0 is tunable too: set between steps, the speed
is V0 from then on (the ramp restarts from it), so that a run can lower its speed in stages
with its state carried over (continuation). Negative or non-finite stiffnesses and
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
