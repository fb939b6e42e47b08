//! Linear stability of the car on straight track: the Jacobian of the 66-state right-hand
//! side at the centred equilibrium (central differences), its eigenvalues, and the linear
//! (Hopf) critical speed, where the largest real part crosses zero.
#![forbid(unsafe_code)]

use super::contact::Running;
use super::equations::{rhs, Car, State, Track, N_STATES};
use crate::contact::table::ContactSpline;
use nalgebra::DMatrix;

/// Straight track, no irregularity, at speed `v` (m/s).
fn straight(v: f64) -> Track {
    Track {
        run: Running {
            v,
            kappa: 0.0,
            cant: 0.0,
        },
        ..Track::default()
    }
}

/// Perturbation of state `j` in the difference quotients: 1e-7 of the state's scale, in its
/// unit (m, m/s, rad, rad/s).
const STEP: f64 = 1e-7;

/// The Jacobian ∂f/∂x (66×66) at state `x` on straight track at speed `v` (m/s), by central
/// differences with step [`STEP`]. `None` if a perturbed state leaves the contact table.
pub fn jacobian(car: &Car, table: &ContactSpline, v: f64, x: &State) -> Option<DMatrix<f64>> {
    let track = straight(v);
    let mut jac = DMatrix::zeros(N_STATES, N_STATES);
    let (mut fp, mut fm) = ([0.0; N_STATES], [0.0; N_STATES]);
    for j in 0..N_STATES {
        let h = STEP * x[j].abs().max(1.0);
        let mut xp = *x;
        xp[j] += h;
        rhs(car, table, &track, &xp, &mut fp, None).ok()?;
        let mut xm = *x;
        xm[j] -= h;
        rhs(car, table, &track, &xm, &mut fm, None).ok()?;
        for i in 0..N_STATES {
            jac[(i, j)] = (fp[i] - fm[i]) / (2.0 * h);
        }
    }
    Some(jac)
}

/// The centred equilibrium on straight track at speed `v` (m/s): from the nominal position,
/// Newton's method on f(x) = 0 (the vertical positions settle by some 1e-8 m on the Hertz
/// contact; the lateral ones stay zero by symmetry). `None` if it does not converge.
pub fn equilibrium(car: &Car, table: &ContactSpline, v: f64) -> Option<State> {
    let track = straight(v);
    let mut x = [0.0; N_STATES];
    let mut f = [0.0; N_STATES];
    // Newton's chord method: the Jacobian of the nominal position throughout (the forces are
    // nearly linear over the 1e-8 m the bodies settle by).
    let lu = jacobian(car, table, v, &x)?.lu();
    for _ in 0..20 {
        rhs(car, table, &track, &x, &mut f, None).ok()?;
        if f.iter().all(|r| r.abs() < 1e-9) {
            return Some(x);
        }
        let dx = lu.solve(&nalgebra::DVector::from_column_slice(&f))?;
        for i in 0..N_STATES {
            x[i] -= dx[i];
        }
    }
    None
}

/// Eigenvalues (re, im) of the Jacobian at the centred equilibrium at speed `v` (m/s).
pub fn eigenvalues(car: &Car, table: &ContactSpline, v: f64) -> Option<Vec<(f64, f64)>> {
    let x = equilibrium(car, table, v)?;
    let jac = jacobian(car, table, v, &x)?;
    spectrum(jac)
}

/// Eigenvalues (re, im) of `m`: balanced (Parlett–Reinsch; the Jacobian's entries span some
/// fifteen orders of magnitude), then the real Schur form. The two bogies make eigenvalues
/// come in nearly equal pairs, where the QR iteration may not meet a deflation test at
/// machine precision: it is retried with the test relaxed to 1e-14, 1e-13, 1e-12.
pub fn spectrum(mut m: DMatrix<f64>) -> Option<Vec<(f64, f64)>> {
    nalgebra::linalg::balancing::balance_parlett_reinsch(&mut m);
    let schur = [f64::EPSILON, 1e-14, 1e-13, 1e-12]
        .into_iter()
        .find_map(|eps| nalgebra::linalg::Schur::try_new(m.clone(), eps, 20_000))?;
    Some(
        schur
            .complex_eigenvalues()
            .iter()
            .map(|z| (z.re, z.im))
            .collect(),
    )
}

/// Largest real part (1/s) of the eigenvalues at speed `v` (m/s).
pub fn growth_rate(car: &Car, table: &ContactSpline, v: f64) -> Option<f64> {
    eigenvalues(car, table, v).map(|l| l.iter().fold(f64::NEG_INFINITY, |m, z| m.max(z.0)))
}

/// Lowest speed of the scan.
pub const SCAN_FROM: f64 = 5.0;
/// Highest speed of the scan.
pub const SCAN_TO: f64 = 300.0;

/// Why no linear critical speed lies in the scan.
#[derive(Clone, Debug, PartialEq)]
pub enum NoCrossing {
    /// The centred motion is unstable already at [`SCAN_FROM`].
    UnstableFromTheStart,
    /// The centred motion is stable up to [`SCAN_TO`].
    StableThroughout,
    /// No equilibrium or no eigenvalues at this speed (m/s).
    Failed(f64),
}

impl std::fmt::Display for NoCrossing {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::UnstableFromTheStart => {
                write!(
                    f,
                    "the centred motion is already unstable at {SCAN_FROM} m/s"
                )
            }
            Self::StableThroughout => {
                write!(
                    f,
                    "the centred motion is stable from {SCAN_FROM} to {SCAN_TO} m/s"
                )
            }
            Self::Failed(v) => write!(f, "no centred equilibrium or no eigenvalues at {v} m/s"),
        }
    }
}

/// Linear (Hopf) critical speed (m/s): the lowest speed at which the largest real part of the
/// eigenvalues at the centred equilibrium crosses zero, by a scan in steps of 2.5 m/s from
/// [`SCAN_FROM`] to [`SCAN_TO`] and bisection to 1e-6 m/s.
///
/// Below it the largest real part belongs to the bogie frames' pitch on the undamped primary
/// vertical springs (49.8 rad/s), which creep damps only by some −8e-6/v 1/s: small, but of
/// a definite sign, far above the eigenvalues' rounding (about 1e-10 1/s).
pub fn linear_critical_speed(car: &Car, table: &ContactSpline) -> Result<f64, NoCrossing> {
    let g = |v: f64| growth_rate(car, table, v).ok_or(NoCrossing::Failed(v));
    if g(SCAN_FROM)? >= 0.0 {
        return Err(NoCrossing::UnstableFromTheStart);
    }
    let mut lo = SCAN_FROM;
    let mut hi = None;
    while lo < SCAN_TO {
        let next = (lo + 2.5).min(SCAN_TO);
        if g(next)? >= 0.0 {
            hi = Some(next);
            break;
        }
        lo = next;
    }
    let mut hi = hi.ok_or(NoCrossing::StableThroughout)?;
    while hi - lo > 1e-6 {
        let mid = 0.5 * (lo + hi);
        if g(mid)? < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok(0.5 * (lo + hi))
}
