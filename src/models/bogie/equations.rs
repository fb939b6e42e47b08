//! The bogie's equations of motion (paper eq. 24–25): creepages, the Shen–Hedrick–Elkins
//! saturated creep law, the flange spring and the right-hand side of the first-order system.
#![forbid(unsafe_code)]

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

impl BogieParams {
    /// Every parameter zero (the variable table then sets the defaults).
    pub(super) const ZERO: BogieParams = BogieParams {
        m_b: 0.0,
        i_b: 0.0,
        h: 0.0,
        a: 0.0,
        k_sy: 0.0,
        c_sy: 0.0,
        k_phi: 0.0,
        r0: 0.0,
        lambda: 0.0,
        mu: 0.0,
        n: 0.0,
        psi: 0.0,
        phi_c: 0.0,
        k0: 0.0,
        delta: 0.0,
    };
}

impl Default for BogieParams {
    /// The paper's bogie (the start values of the variable table).
    fn default() -> Self {
        super::Bogie::default().p
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
