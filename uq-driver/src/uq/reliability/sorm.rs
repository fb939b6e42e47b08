//! SORM: the curvatures of the limit-state surface at the FORM design point and the
//! probability of the second-order (paraboloid) approximation.
//!
//! At the design point `u*` with `alpha = -grad g / |grad g|`, an orthonormal basis
//! `r_1, ..., r_{d-1}` of the plane orthogonal to `alpha` (a Householder reflection) and the
//! Hessian of `g` in it, `H'_ij = r_i^T H r_j` by finite differences (all points in one
//! batch), give the surface as the paraboloid
//!
//! `v_d = beta + (1/2) sum_ij A_ij v_i v_j`,  `A = H' / |grad g|`,
//!
//! (`v_d` along `alpha`; failure beyond it). The principal curvatures `kappa_i` are the
//! eigenvalues of `A`: positive where the surface bends away from the origin (less failure
//! than FORM's half-space), negative towards it. Four probabilities:
//!
//! - Breitung (1984), asymptotic for large `beta`:
//!   `P1 = Phi(-beta) prod_i (1 + beta kappa_i)^(-1/2)`;
//! - Hohenbichler & Rackwitz (1988), `beta` replaced by `psi = phi(beta) / Phi(-beta)`:
//!   `P2 = Phi(-beta) prod_i (1 + psi kappa_i)^(-1/2)`;
//! - Tvedt's three-term formula (Tvedt 1990): `P1 + A2 + A3` with
//!   `A2 = (beta Phi(-beta) - phi(beta)) [prod (1 + beta kappa)^(-1/2) - prod (1 + (1 + beta) kappa)^(-1/2)]`,
//!   `A3 = (beta + 1)(beta Phi(-beta) - phi(beta)) [prod (1 + beta kappa)^(-1/2) - Re prod (1 + (beta + i) kappa)^(-1/2)]`;
//! - the exact probability of the paraboloid (Tvedt 1990 gives it as a single integral),
//!   here by the inversion of its Laplace transform along the line `Re s = c`:
//!   with `Q = v_d - (1/2) sum kappa_i v_i^2`, `E[e^(sQ)] = e^(s^2/2) prod (1 + kappa_i s)^(-1/2)`
//!   and
//!   `P(Q >= beta) = (1/pi) int_0^inf Re[ e^(s^2/2 - s beta) prod (1 + kappa_i s)^(-1/2) / s ] dy`,
//!   `s = c + i y`, for any `c > 0` with `1 + c kappa_i > 0`. With `c = beta` (the saddle
//!   point) the exponential is `e^(-(beta^2 + y^2)/2)`: no oscillation, no cancellation,
//!   relative accuracy at any `beta`. (When a curvature below `-1/beta` forbids `c = beta`,
//!   a smaller `c`; for `beta < 0`, `1 - ` the paraboloid of `-Q`.) Integrated by Simpson's
//!   rule on geometrically growing panels up to `y = 12` (256 intervals each; `1e-9`
//!   relative against direct quadrature).
//!
//! `probability` is the paraboloid's exact value (the other three approximate it); the
//! others are reported beside it. Breitung's and Tvedt's need `1 + beta kappa_i > 0` and
//! `beta > 0`, Hohenbichler–Rackwitz's `1 + psi kappa_i > 0`; they are `None` otherwise.

use nalgebra::{Complex, DMatrix, SymmetricEigen};
use serde::{Deserialize, Serialize};

use super::error::ReliabilityError;
use super::form::FormResult;
use super::gradient::Scheme;
use super::model::{LimitState, OnFailure, Runs};
use super::{norm, positive};
use crate::uq::special::{norm_pdf, norm_sf};

/// SORM settings.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Sorm {
    /// Finite-difference step of the Hessian (standard normal units).
    pub step: f64,
    /// Central: `2(d-1)` runs for the diagonal and `4` per pair (`2(d-1)^2` in all);
    /// forward: `2(d-1)` and `1` per pair (about `(d-1)(d+2)/2`), less accurate.
    pub scheme: Scheme,
}

impl Default for Sorm {
    fn default() -> Self {
        Sorm {
            step: 0.05,
            scheme: Scheme::Central,
        }
    }
}

/// What SORM found.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SormResult {
    /// FORM's reliability index.
    pub beta: f64,
    /// FORM's `Phi(-beta)`.
    pub form_probability: f64,
    /// Principal curvatures, ascending (`d - 1` of them).
    pub curvatures: Vec<f64>,
    /// Breitung (1984).
    pub breitung: Option<f64>,
    /// Hohenbichler & Rackwitz (1988).
    pub hohenbichler_rackwitz: Option<f64>,
    /// Tvedt's three-term formula (1990).
    pub tvedt: Option<f64>,
    /// The exact probability of the paraboloid.
    pub paraboloid: Option<f64>,
    /// The chosen probability: `paraboloid` (or, should its integral fail, the first of
    /// Tvedt, Hohenbichler–Rackwitz, Breitung, FORM that exists).
    pub probability: f64,
    /// Which one `probability` is.
    pub chosen: String,
    /// Model runs of the Hessian.
    pub runs: u64,
    /// The run index after the last run.
    pub next_run: u64,
    /// For the user.
    pub warnings: Vec<String>,
}

/// SORM at the design point of `form` (its gradient is reused; the Hessian's runs are
/// numbered from `form.next_run`).
pub fn sorm(
    model: &mut dyn LimitState,
    form: &FormResult,
    settings: &Sorm,
) -> Result<SormResult, ReliabilityError> {
    let mut runs = Runs::starting_at(model, form.next_run)?;
    let d = runs.dim();
    let h = settings.step;
    if !(h.is_finite() && h > 0.0) {
        return Err(ReliabilityError::Invalid(format!(
            "the SORM step must be positive (got {h})"
        )));
    }
    if form.u_star.len() != d || form.gradient.len() != d {
        return Err(ReliabilityError::Invalid(format!(
            "the FORM result has {} coordinates, the model {d}",
            form.u_star.len()
        )));
    }
    let mut warnings = Vec::new();
    if !form.converged {
        warnings.push("FORM did not converge: the curvatures are those of its last point".into());
    }
    let gn = norm(&form.gradient);
    if !(gn > 0.0 && gn.is_finite()) {
        return Err(ReliabilityError::ZeroGradient {
            u: form.u_star.clone(),
            norm: gn,
        });
    }
    let alpha: Vec<f64> = form.gradient.iter().map(|v| -v / gn).collect();
    let basis = orthogonal_basis(&alpha);
    let (points, assemble) = hessian_design(&form.u_star, &basis, h, settings.scheme);
    let values = runs.eval(points, OnFailure::Error)?;
    let hess = assemble(&values, form.g);
    let n = d - 1;
    let mut curvatures: Vec<f64> = if n == 0 {
        Vec::new()
    } else {
        let a = DMatrix::from_fn(n, n, |i, j| 0.5 * (hess[i][j] + hess[j][i]) / gn);
        SymmetricEigen::new(a).eigenvalues.iter().copied().collect()
    };
    curvatures.sort_by(f64::total_cmp);
    let beta = form.beta;
    let breitung = breitung(beta, &curvatures);
    let hohenbichler_rackwitz = hohenbichler_rackwitz(beta, &curvatures);
    let tvedt = tvedt(beta, &curvatures);
    let paraboloid = paraboloid(beta, &curvatures);
    let (probability, chosen) = [
        (paraboloid, "paraboloid"),
        (tvedt, "tvedt"),
        (hohenbichler_rackwitz, "hohenbichler_rackwitz"),
        (breitung, "breitung"),
    ]
    .into_iter()
    .find_map(|(p, name)| p.map(|p| (p, name)))
    .unwrap_or((form.probability, "form"));
    if breitung.is_none() && beta > 0.0 {
        warnings.push(format!(
            "a curvature is at or below -1/beta = {:.4} (the surface bends around the origin): \
             Breitung's and Tvedt's formulas do not apply and a single design point may not \
             describe the failure domain",
            -1.0 / beta
        ));
    }
    Ok(SormResult {
        beta,
        form_probability: form.probability,
        curvatures,
        breitung,
        hohenbichler_rackwitz,
        tvedt,
        paraboloid,
        probability,
        chosen: chosen.into(),
        runs: runs.count() - form.next_run,
        next_run: runs.count(),
        warnings,
    })
}

/// `d - 1` orthonormal vectors orthogonal to the unit vector `alpha`: the columns `j != k`
/// of the Householder reflection that maps `e_k` to `-sign(alpha_k) alpha`
/// (`k` the largest component, for stability).
fn orthogonal_basis(alpha: &[f64]) -> Vec<Vec<f64>> {
    let d = alpha.len();
    let k = (0..d)
        .max_by(|&a, &b| alpha[a].abs().total_cmp(&alpha[b].abs()))
        .expect("d >= 1");
    let mut v = alpha.to_vec();
    v[k] += alpha[k].signum();
    let vv: f64 = v.iter().map(|x| x * x).sum();
    (0..d)
        .filter(|&j| j != k)
        .map(|j| {
            (0..d)
                .map(|i| f64::from(u8::from(i == j)) - 2.0 * v[i] * v[j] / vv)
                .collect()
        })
        .collect()
}

/// How the Hessian is assembled from the values at its points and `g(u*)`.
type Assemble = Box<dyn Fn(&[f64], f64) -> Vec<Vec<f64>>>;

/// The points of the Hessian of `g` at `u` in the directions `basis` (step `h`), and its
/// assembly from their values and `g(u)`.
fn hessian_design(
    u: &[f64],
    basis: &[Vec<f64>],
    h: f64,
    scheme: Scheme,
) -> (Vec<Vec<f64>>, Assemble) {
    let n = basis.len();
    let at = |steps: &[(usize, f64)]| -> Vec<f64> {
        let mut p = u.to_vec();
        for &(i, s) in steps {
            for (pk, rk) in p.iter_mut().zip(&basis[i]) {
                *pk += s * h * rk;
            }
        }
        p
    };
    let mut points = Vec::new();
    match scheme {
        Scheme::Central => {
            // Diagonal: +-h r_i; pairs i < j: (+,+), (+,-), (-,+), (-,-).
            for i in 0..n {
                points.push(at(&[(i, 1.0)]));
                points.push(at(&[(i, -1.0)]));
            }
            for (i, j) in pairs(n) {
                for (si, sj) in [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)] {
                    points.push(at(&[(i, si), (j, sj)]));
                }
            }
            let assemble = move |g: &[f64], g0: f64| {
                let mut m = vec![vec![0.0; n]; n];
                for (i, row) in m.iter_mut().enumerate() {
                    row[i] = (g[2 * i] - 2.0 * g0 + g[2 * i + 1]) / (h * h);
                }
                for (p, (i, j)) in pairs(n).enumerate() {
                    let k = 2 * n + 4 * p;
                    let v = (g[k] - g[k + 1] - g[k + 2] + g[k + 3]) / (4.0 * h * h);
                    m[i][j] = v;
                    m[j][i] = v;
                }
                m
            };
            (points, Box::new(assemble))
        }
        Scheme::Forward => {
            // u + h r_i, u + 2h r_i, then u + h r_i + h r_j for i < j.
            for i in 0..n {
                points.push(at(&[(i, 1.0)]));
                points.push(at(&[(i, 2.0)]));
            }
            for (i, j) in pairs(n) {
                points.push(at(&[(i, 1.0), (j, 1.0)]));
            }
            let assemble = move |g: &[f64], g0: f64| {
                let mut m = vec![vec![0.0; n]; n];
                for (i, row) in m.iter_mut().enumerate() {
                    row[i] = (g[2 * i + 1] - 2.0 * g[2 * i] + g0) / (h * h);
                }
                for (p, (i, j)) in pairs(n).enumerate() {
                    let v = (g[2 * n + p] - g[2 * i] - g[2 * j] + g0) / (h * h);
                    m[i][j] = v;
                    m[j][i] = v;
                }
                m
            };
            (points, Box::new(assemble))
        }
    }
}

/// The pairs `i < j` of `0..n`, in order.
fn pairs(n: usize) -> impl Iterator<Item = (usize, usize)> {
    (0..n).flat_map(move |i| (i + 1..n).map(move |j| (i, j)))
}

/// `prod_i (1 + b kappa_i)^(-1/2)`, `None` unless every factor is positive.
fn real_factor(b: f64, kappa: &[f64]) -> Option<f64> {
    let mut p = 1.0;
    for k in kappa {
        let f = 1.0 + b * k;
        if !positive(f) {
            return None;
        }
        p /= f.sqrt();
    }
    Some(p)
}

/// `prod_i (1 + s kappa_i)^(-1/2)` for complex `s` (principal branch of each factor).
fn complex_factor(s: Complex<f64>, kappa: &[f64]) -> Complex<f64> {
    kappa
        .iter()
        .fold(Complex::new(1.0, 0.0), |p, &k| p / (s * k + 1.0).sqrt())
}

/// Breitung (1984).
pub(crate) fn breitung(beta: f64, kappa: &[f64]) -> Option<f64> {
    if !positive(beta) {
        return None;
    }
    Some(norm_sf(beta) * real_factor(beta, kappa)?)
}

/// Hohenbichler & Rackwitz (1988).
pub(crate) fn hohenbichler_rackwitz(beta: f64, kappa: &[f64]) -> Option<f64> {
    let q = norm_sf(beta);
    if !positive(q) {
        return Some(0.0);
    }
    let psi = norm_pdf(beta) / q;
    Some(q * real_factor(psi, kappa)?)
}

/// Tvedt's three-term formula (1990).
pub(crate) fn tvedt(beta: f64, kappa: &[f64]) -> Option<f64> {
    if !positive(beta) {
        return None;
    }
    let q = norm_sf(beta);
    let f0 = real_factor(beta, kappa)?;
    let f1 = real_factor(beta + 1.0, kappa)?;
    let fi = complex_factor(Complex::new(beta, 1.0), kappa).re;
    let m = beta * q - norm_pdf(beta);
    let p = q * f0 + m * (f0 - f1) + (beta + 1.0) * m * (f0 - fi);
    Some(p.max(0.0))
}

/// The exact probability of the paraboloid `Q = v_d - (1/2) sum kappa_i v_i^2 >= beta`, by
/// the inversion integral of the module documentation.
pub(crate) fn paraboloid(beta: f64, kappa: &[f64]) -> Option<f64> {
    if beta < 0.0 {
        // P(Q >= beta) = 1 - P(-Q > -beta), and -Q is the paraboloid with curvatures
        // -kappa (v_d is symmetric): the saddle point c = -beta > 0 is then available.
        let flipped: Vec<f64> = kappa.iter().map(|k| -k).collect();
        return paraboloid(-beta, &flipped).map(|p| 1.0 - p);
    }
    // The line Re s = c must keep 1 + c kappa_i > 0.
    let most_negative = kappa.iter().fold(0.0f64, |m, &k| m.min(k));
    let c_max = if most_negative < 0.0 {
        0.9 / -most_negative
    } else {
        f64::INFINITY
    };
    let c = if beta > 0.0 { beta } else { 1.0 }.min(c_max);
    if !positive(c) {
        return None;
    }
    let integrand = |y: f64| -> f64 {
        let s = Complex::new(c, y);
        let mag = ((c * c - y * y) / 2.0 - c * beta).exp();
        let phase = Complex::new(0.0, y * (c - beta)).exp();
        (phase * complex_factor(s, kappa) / s).re * mag
    };
    // Simpson on panels [0, y0], [y0, 2 y0], [2 y0, 4 y0], ... up to 12.
    let y0 = c.min(1.0) / 4.0;
    let mut edges = vec![0.0, y0];
    while *edges.last().expect("non-empty") < 12.0 {
        let next = (2.0 * edges.last().expect("non-empty")).min(12.0);
        edges.push(next);
    }
    const INTERVALS: usize = 256;
    let mut total = 0.0;
    for w in edges.windows(2) {
        let (a, b) = (w[0], w[1]);
        let step = (b - a) / INTERVALS as f64;
        let mut s = integrand(a) + integrand(b);
        for k in 1..INTERVALS {
            let weight = if k % 2 == 1 { 4.0 } else { 2.0 };
            s += weight * integrand(a + k as f64 * step);
        }
        total += s * step / 3.0;
    }
    let p = total / std::f64::consts::PI;
    (p.is_finite()).then_some(p.clamp(0.0, 1.0))
}

#[cfg(test)]
mod tests {
    use super::super::fixtures::*;
    use super::super::form::{form, Form};
    use super::super::model::FnLimitState;
    use super::*;

    #[test]
    fn flat_surfaces_give_the_form_probability() {
        for beta in [-1.0, 0.5, 3.0, 4.753, 8.0] {
            let p = paraboloid(beta, &[0.0; 5]).unwrap();
            let e = norm_sf(beta);
            assert!((p - e).abs() < 1e-9 * e, "beta {beta}: {p} vs {e}");
        }
    }

    /// `P(v_3 >= beta + (kappa/2)(v_1^2 + v_2^2))`: the sum of two squares is exponential
    /// with mean 2, so `P = int_0^inf e^(-t/2)/2 Phi(-beta - kappa t/2) dt`.
    fn two_equal_curvatures(beta: f64, kappa: f64) -> f64 {
        let n = 200_000;
        let top = 80.0;
        let h = top / n as f64;
        let f = |t: f64| 0.5 * (-t / 2.0).exp() * norm_sf(beta + kappa * t / 2.0);
        let mut s = f(0.0) + f(top);
        for k in 1..n {
            s += if k % 2 == 1 { 4.0 } else { 2.0 } * f(k as f64 * h);
        }
        s * h / 3.0
    }

    #[test]
    fn paraboloid_integral_matches_a_direct_quadrature() {
        let cases = [
            (3.0, 0.2),
            (3.0, -0.2),
            (3.0, 0.1),
            (3.0, -0.1),
            (4.5, 0.5),
            (2.0, -0.4),
            (0.5, 1.0),
            (-1.0, 0.3),
        ];
        for (beta, kappa) in cases {
            let exact = two_equal_curvatures(beta, kappa);
            let p = paraboloid(beta, &[kappa, kappa]).unwrap();
            assert!(
                (p - exact).abs() < 1e-7 * exact,
                "{beta} {kappa}: {p} vs {exact}"
            );
            // The three approximations, within 10 % where beta kappa is small.
            if (beta * kappa).abs() <= 0.3 && beta >= 2.0 {
                for q in [
                    breitung(beta, &[kappa, kappa]),
                    hohenbichler_rackwitz(beta, &[kappa, kappa]),
                    tvedt(beta, &[kappa, kappa]),
                ] {
                    let q = q.unwrap();
                    assert!(
                        (q - exact).abs() < 0.1 * exact,
                        "{beta} {kappa}: {q} vs {exact}"
                    );
                }
            }
        }
    }

    #[test]
    fn sorm_equals_form_on_a_linear_limit_state() {
        for p in [1e-3, 1e-4, 1e-6] {
            let lin = Linear::new(8, p);
            let mut m = lin.model();
            let f = form(&mut m, &Form::default(), 0).unwrap();
            let s = sorm(&mut m, &f, &Sorm::default()).unwrap();
            assert!(
                s.curvatures.iter().all(|k| k.abs() < 1e-8),
                "{:?}",
                s.curvatures
            );
            for q in [s.breitung, s.hohenbichler_rackwitz, s.tvedt, s.paraboloid] {
                assert!((q.unwrap() - f.probability).abs() < 1e-6 * f.probability);
            }
            assert_eq!(s.runs, 2 * 7 * 7);
            assert_eq!(s.next_run, f.next_run + s.runs);
        }
    }

    #[test]
    fn sorm_finds_the_curvatures_of_a_paraboloid() {
        // g = beta - u_4 + (1/2)(0.3 u_1^2 - 0.1 u_2^2 + 0.2 u_3^2)
        let kappa = [0.3, -0.1, 0.2];
        let beta = 3.5;
        let mut m = FnLimitState::new(4, move |u: &[f64]| {
            Ok(beta - u[3]
                + 0.5 * (kappa[0] * u[0] * u[0] + kappa[1] * u[1] * u[1] + kappa[2] * u[2] * u[2]))
        });
        let f = form(&mut m, &Form::default(), 0).unwrap();
        for scheme in [Scheme::Central, Scheme::Forward] {
            let settings = Sorm {
                scheme,
                ..Sorm::default()
            };
            let s = sorm(&mut m, &f, &settings).unwrap();
            let mut want = kappa.to_vec();
            want.sort_by(f64::total_cmp);
            for (a, b) in s.curvatures.iter().zip(&want) {
                assert!((a - b).abs() < 1e-5, "{scheme:?}: {:?}", s.curvatures);
            }
            assert_eq!(s.chosen, "paraboloid");
            let exact = paraboloid(beta, &want).unwrap();
            assert!((s.probability - exact).abs() < 1e-4 * exact);
            assert!(s.probability < f.probability);
        }
    }
}
