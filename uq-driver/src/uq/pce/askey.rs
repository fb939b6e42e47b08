//! Orthonormal polynomial families of the Askey scheme, by three-term recurrences.
//!
//! Each [`Family`] lives on its own *germ* (a standardised random variable):
//!
//! | family | germ | weight on the germ |
//! | --- | --- | --- |
//! | `Hermite` | N(0, 1) on R | `exp(-t^2/2) / sqrt(2 pi)` |
//! | `Legendre` | U(-1, 1) | `1/2` on `[-1, 1]` |
//! | `Laguerre { shape: k }` | Gamma(k, 1) on `[0, inf)` | `t^(k-1) e^-t / Gamma(k)` (generalized Laguerre, `alpha = k - 1`) |
//! | `Jacobi { a, b }` | Beta(a, b) mapped to `[-1, 1]` by `t = 2u - 1` | `(1+t)^(a-1) (1-t)^(b-1) / (2^(a+b-1) B(a, b))` (Jacobi `P^(b-1, a-1)`) |
//!
//! Conventions: the polynomials `p_0 = 1, p_1, ...` are **orthonormal** for the germ's
//! probability measure (`E[p_i p_j] = delta_ij`), with positive leading coefficient.
//! The *monic* recurrence `P_{n+1} = (t - alpha_n) P_n - beta_n P_{n-1}` gives the
//! coefficients returned by [`Family::recurrence`]; the orthonormal polynomials obey
//! `sqrt(beta_{n+1}) p_{n+1} = (t - alpha_n) p_n - sqrt(beta_n) p_{n-1}`.

use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

use crate::uq::distributions::Distribution;
use crate::uq::quadrature::sorted_eigenvalues;

/// Largest number of nodes of a Gauss rule from [`Family::gauss`].
pub const MAX_GAUSS_NODES: usize = 200;

/// Errors of the family constructors and rules.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum AskeyError {
    /// A shape parameter is not a finite positive number.
    #[error("{family}: shape parameter {name} = {value} must be finite and > 0")]
    BadShape {
        /// Family name.
        family: &'static str,
        /// Parameter name.
        name: &'static str,
        /// Offending value.
        value: f64,
    },
    /// A Gauss rule with an unsupported number of nodes was requested.
    #[error("a Gauss rule needs 1..={MAX_GAUSS_NODES} nodes (got {0})")]
    BadNodeCount(usize),
}

/// An orthonormal polynomial family (see the module docs for the germs).
///
/// Serialized with a `family` tag, e.g. `{"family": "jacobi", "a": 2.0, "b": 5.0}`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "family", rename_all = "snake_case")]
pub enum Family {
    /// Probabilists' Hermite, germ N(0, 1).
    Hermite,
    /// Legendre, germ U(-1, 1).
    Legendre,
    /// Generalized Laguerre with `alpha = shape - 1`, germ Gamma(shape, 1).
    Laguerre {
        /// Gamma shape `k > 0`.
        shape: f64,
    },
    /// Jacobi `P^(b-1, a-1)` on `[-1, 1]`, germ `2 Beta(a, b) - 1`.
    Jacobi {
        /// First Beta shape (exponent of `(1 + t)` is `a - 1`).
        a: f64,
        /// Second Beta shape (exponent of `(1 - t)` is `b - 1`).
        b: f64,
    },
}

fn check_shape(family: &'static str, name: &'static str, value: f64) -> Result<(), AskeyError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(AskeyError::BadShape {
            family,
            name,
            value,
        })
    }
}

impl Family {
    /// The family of `d`'s germ in the Askey scheme (normal: Hermite, uniform: Legendre,
    /// Beta: Jacobi, Gamma: Laguerre), `None` for the others. The germ is mapped to `d` by
    /// [`Distribution::askey_affine`].
    pub fn of(d: &Distribution) -> Option<Family> {
        match *d {
            Distribution::Normal { .. } => Some(Family::Hermite),
            Distribution::Uniform { .. } => Some(Family::Legendre),
            Distribution::Beta { alpha, beta, .. } => Some(Family::Jacobi { a: alpha, b: beta }),
            Distribution::Gamma { shape, .. } => Some(Family::Laguerre { shape }),
            _ => None,
        }
    }

    /// The germ's law as a distribution: N(0, 1), U(-1, 1), Gamma(shape, 1) or
    /// Beta(a, b) on [-1, 1].
    pub fn law(&self) -> Distribution {
        match *self {
            Family::Hermite => Distribution::Normal {
                mean: 0.0,
                std: 1.0,
            },
            Family::Legendre => Distribution::Uniform {
                low: -1.0,
                high: 1.0,
            },
            Family::Laguerre { shape } => Distribution::Gamma { shape, scale: 1.0 },
            Family::Jacobi { a, b } => Distribution::Beta {
                alpha: a,
                beta: b,
                low: -1.0,
                high: 1.0,
            },
        }
    }

    /// Lower-case name (`hermite`, `legendre`, `laguerre`, `jacobi`).
    pub fn name(&self) -> &'static str {
        match self {
            Family::Hermite => "hermite",
            Family::Legendre => "legendre",
            Family::Laguerre { .. } => "laguerre",
            Family::Jacobi { .. } => "jacobi",
        }
    }

    /// Checks the shape parameters.
    pub fn validate(&self) -> Result<(), AskeyError> {
        match *self {
            Family::Hermite | Family::Legendre => Ok(()),
            Family::Laguerre { shape } => check_shape("Laguerre", "shape", shape),
            Family::Jacobi { a, b } => {
                check_shape("Jacobi", "a", a)?;
                check_shape("Jacobi", "b", b)
            }
        }
    }

    /// Support of the germ, `(low, high)` (infinite ends as `f64::INFINITY`).
    pub fn support(&self) -> (f64, f64) {
        match self {
            Family::Hermite => (f64::NEG_INFINITY, f64::INFINITY),
            Family::Legendre | Family::Jacobi { .. } => (-1.0, 1.0),
            Family::Laguerre { .. } => (0.0, f64::INFINITY),
        }
    }

    /// Monic recurrence coefficients `(alpha_n, beta_n)`, `beta_0 = 1` (total mass).
    pub fn recurrence(&self, n: usize) -> (f64, f64) {
        let nf = n as f64;
        match *self {
            Family::Hermite => (0.0, if n == 0 { 1.0 } else { nf }),
            Family::Legendre => (
                0.0,
                if n == 0 {
                    1.0
                } else {
                    nf * nf / (4.0 * nf * nf - 1.0)
                },
            ),
            Family::Laguerre { shape } => {
                let al = shape - 1.0;
                (
                    2.0 * nf + al + 1.0,
                    if n == 0 { 1.0 } else { nf * (nf + al) },
                )
            }
            Family::Jacobi { a, b } => jacobi_recurrence(n, b - 1.0, a - 1.0),
        }
    }

    /// Orthonormal values `out[k] = p_k(t)` for `k = 0..out.len()`.
    pub fn eval_all(&self, t: f64, out: &mut [f64]) {
        let (mut pm, mut p) = (0.0, 1.0);
        for (k, o) in out.iter_mut().enumerate() {
            *o = p;
            let (a, b) = self.recurrence(k);
            let sb = if k == 0 { 0.0 } else { b.sqrt() };
            let s1 = self.recurrence(k + 1).1.sqrt();
            let next = ((t - a) * p - sb * pm) / s1;
            pm = p;
            p = next;
        }
    }

    /// Orthonormal values `vals[k] = p_k(t)` and derivatives `ders[k] = p_k'(t)` for
    /// `k = 0..vals.len()` (`ders` as long as `vals`).
    pub fn eval_all_with_derivative(&self, t: f64, vals: &mut [f64], ders: &mut [f64]) {
        let (mut pm, mut p) = (0.0, 1.0);
        let (mut dpm, mut dp) = (0.0, 0.0);
        for k in 0..vals.len() {
            vals[k] = p;
            ders[k] = dp;
            [pm, p, dpm, dp] = self.step_with_derivative(k, t, [pm, p, dpm, dp]);
        }
    }

    /// One step of the orthonormal recurrence and of its derivative: from
    /// `[p_{k-1}, p_k, p_{k-1}', p_k']` at `t` to `[p_k, p_{k+1}, p_k', p_{k+1}']`.
    fn step_with_derivative(&self, k: usize, t: f64, [pm, p, dpm, dp]: [f64; 4]) -> [f64; 4] {
        let (a, b) = self.recurrence(k);
        let sb = if k == 0 { 0.0 } else { b.sqrt() };
        let s1 = self.recurrence(k + 1).1.sqrt();
        let next = ((t - a) * p - sb * pm) / s1;
        let dnext = (p + (t - a) * dp - sb * dpm) / s1;
        [p, next, dp, dnext]
    }

    /// The orthonormal polynomial `p_n(t)`.
    pub fn eval(&self, n: usize, t: f64) -> f64 {
        let mut v = vec![0.0; n + 1];
        self.eval_all(t, &mut v);
        v[n]
    }

    /// `E[P_n^2]` of the *monic* polynomial of degree `n` for the germ:
    /// `prod_{k=1..=n} beta_k`. The orthonormal `p_n` is `P_n / sqrt(monic_norm_sq(n))`.
    pub fn monic_norm_sq(&self, n: usize) -> f64 {
        (1..=n).map(|k| self.recurrence(k).1).product()
    }

    /// `n`-point Gauss rule of the germ (nodes ascending, weights summing to 1), exact for
    /// polynomials of degree `2n - 1`. Golub–Welsch eigenvalues, Newton-polished, with
    /// Christoffel weights `1 / sum_{k<n} p_k(t_i)^2`.
    pub fn gauss(&self, n: usize) -> Result<(Vec<f64>, Vec<f64>), AskeyError> {
        self.validate()?;
        if n == 0 || n > MAX_GAUSS_NODES {
            return Err(AskeyError::BadNodeCount(n));
        }
        let mut jac = DMatrix::<f64>::zeros(n, n);
        for k in 0..n {
            let (a, _) = self.recurrence(k);
            jac[(k, k)] = a;
            if k + 1 < n {
                let s = self.recurrence(k + 1).1.sqrt();
                jac[(k, k + 1)] = s;
                jac[(k + 1, k)] = s;
            }
        }
        let mut x = sorted_eigenvalues(jac);
        let mut vals = vec![0.0; n + 1];
        for xi in x.iter_mut() {
            // Newton on p_n, derivative from the Christoffel–Darboux-free finite recurrence.
            for _ in 0..2 {
                let (p, dp) = self.value_and_derivative(n, *xi);
                if dp == 0.0 || !dp.is_finite() {
                    break;
                }
                let dx = p / dp;
                if !dx.is_finite() || dx.abs() > 1e-6 * (1.0 + xi.abs()) {
                    break;
                }
                *xi -= dx;
            }
        }
        let w: Vec<f64> = x
            .iter()
            .map(|&xi| {
                self.eval_all(xi, &mut vals[..n]);
                1.0 / vals[..n].iter().map(|v| v * v).sum::<f64>()
            })
            .collect();
        let s: f64 = w.iter().sum();
        Ok((x, w.into_iter().map(|wi| wi / s).collect()))
    }

    /// `(p_n(t), p_n'(t))` by differentiating the orthonormal recurrence.
    pub fn value_and_derivative(&self, n: usize, t: f64) -> (f64, f64) {
        let (mut pm, mut p) = (0.0, 1.0);
        let (mut dpm, mut dp) = (0.0, 0.0);
        for k in 0..n {
            [pm, p, dpm, dp] = self.step_with_derivative(k, t, [pm, p, dpm, dp]);
        }
        (p, dp)
    }
}

/// Monic Jacobi recurrence for the weight `(1-t)^al (1+t)^be` normalised to mass 1.
fn jacobi_recurrence(n: usize, al: f64, be: f64) -> (f64, f64) {
    let nf = n as f64;
    let s = 2.0 * nf + al + be;
    let alpha = if n == 0 {
        (be - al) / (al + be + 2.0)
    } else {
        (be * be - al * al) / (s * (s + 2.0))
    };
    let beta = match n {
        0 => 1.0,
        1 => 4.0 * (1.0 + al) * (1.0 + be) / ((2.0 + al + be).powi(2) * (3.0 + al + be)),
        _ => 4.0 * nf * (nf + al) * (nf + be) * (nf + al + be) / (s * s * (s + 1.0) * (s - 1.0)),
    };
    (alpha, beta)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::uq::quadrature::gauss_legendre;
    use statrs::function::gamma::ln_gamma;

    /// Composite 20-point Gauss–Legendre on `[lo, hi]` with `pieces` panels.
    fn integrate(f: impl Fn(f64) -> f64, lo: f64, hi: f64, pieces: usize) -> f64 {
        let (x, w) = gauss_legendre(20).unwrap();
        let h = (hi - lo) / pieces as f64;
        let mut s = 0.0;
        for p in 0..pieces {
            let a = lo + p as f64 * h;
            for (xi, wi) in x.iter().zip(&w) {
                s += wi * 0.5 * h * f(a + 0.5 * h * (xi + 1.0));
            }
        }
        s
    }

    /// `E[f(T)]` for the germ of `fam`, by an independent quadrature of the density.
    fn germ_expect(fam: Family, f: impl Fn(f64) -> f64) -> f64 {
        match fam {
            Family::Hermite => integrate(
                |x| f(x) * (-0.5 * x * x).exp() / (2.0 * std::f64::consts::PI).sqrt(),
                -14.0,
                14.0,
                200,
            ),
            Family::Legendre => integrate(|x| 0.5 * f(x), -1.0, 1.0, 20),
            Family::Laguerre { shape: k } => {
                // t = u^2: E f = int 2 u^(2k-1) e^(-u^2) f(u^2) du / Gamma(k).
                let lg = ln_gamma(k);
                integrate(
                    |u| {
                        if u == 0.0 {
                            return 0.0;
                        }
                        2.0 * ((2.0 * k - 1.0) * u.ln() - u * u - lg).exp() * f(u * u)
                    },
                    0.0,
                    12.0,
                    400,
                )
            }
            Family::Jacobi { a, b } => {
                // u = (1 - cos th)/2, t = 2u - 1 = -cos th:
                // E f = int_0^pi sin(th/2)^(2a-1) cos(th/2)^(2b-1) f(-cos th) dth / B(a, b).
                let lb = ln_gamma(a) + ln_gamma(b) - ln_gamma(a + b);
                integrate(
                    |th| {
                        let (s, c) = ((0.5 * th).sin(), (0.5 * th).cos());
                        if s <= 0.0 || c <= 0.0 {
                            return 0.0;
                        }
                        ((2.0 * a - 1.0) * s.ln() + (2.0 * b - 1.0) * c.ln() - lb).exp()
                            * f(-th.cos())
                    },
                    0.0,
                    std::f64::consts::PI,
                    400,
                )
            }
        }
    }

    fn families() -> Vec<Family> {
        vec![
            Family::Hermite,
            Family::Legendre,
            Family::Laguerre { shape: 1.0 },
            Family::Laguerre { shape: 0.5 },
            Family::Laguerre { shape: 3.7 },
            Family::Jacobi { a: 1.0, b: 1.0 },
            Family::Jacobi { a: 2.0, b: 5.0 },
            Family::Jacobi { a: 0.5, b: 0.5 },
            Family::Jacobi { a: 1.5, b: 3.2 },
        ]
    }

    #[test]
    fn askey_families_are_orthonormal_under_their_germ_densities() {
        let deg = 8;
        for fam in families() {
            for i in 0..=deg {
                for j in 0..=i {
                    let g = germ_expect(fam, |t| fam.eval(i, t) * fam.eval(j, t));
                    let want = if i == j { 1.0 } else { 0.0 };
                    assert!(
                        (g - want).abs() < 1e-9,
                        "{fam:?}: <p{i}, p{j}> = {g}, want {want}"
                    );
                }
            }
        }
    }

    #[test]
    fn legendre_and_hermite_match_closed_forms() {
        // p_2 of Legendre: sqrt(5) (3t^2 - 1)/2; Hermite: (t^2 - 1)/sqrt(2); He_3/sqrt(6).
        for &t in &[-0.9, -0.3, 0.0, 0.4, 1.0] {
            let l2 = 5f64.sqrt() * (3.0 * t * t - 1.0) / 2.0;
            assert!((Family::Legendre.eval(2, t) - l2).abs() < 1e-14);
            let h3 = (t * t * t - 3.0 * t) / 6f64.sqrt();
            assert!((Family::Hermite.eval(3, t) - h3).abs() < 1e-14);
        }
        // Laguerre shape 1 (alpha = 0): L_1 = 1 - t, orthonormal p_1 = -(1 - t) = t - 1
        // (positive leading coefficient).
        let lag = Family::Laguerre { shape: 1.0 };
        assert!((lag.eval(1, 2.5) - 1.5).abs() < 1e-14);
        // Jacobi a = b = 1 is Legendre.
        let jac = Family::Jacobi { a: 1.0, b: 1.0 };
        for n in 0..10 {
            let t = 0.37;
            assert!((jac.eval(n, t) - Family::Legendre.eval(n, t)).abs() < 1e-12);
        }
    }

    #[test]
    fn gauss_rules_reproduce_germ_moments() {
        for fam in families() {
            let n = 12;
            let (x, w) = fam.gauss(n).unwrap();
            assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-14);
            for deg in 0..2 * n {
                let q: f64 = x
                    .iter()
                    .zip(&w)
                    .map(|(xi, wi)| wi * xi.powi(deg as i32))
                    .sum();
                let (exact, ref_scale) = exact_moment(fam, deg);
                // Scale of the terms summed: the absolute moment.
                let scale: f64 = x
                    .iter()
                    .zip(&w)
                    .map(|(xi, wi)| wi * xi.abs().powi(deg as i32))
                    .sum();
                assert!(
                    (q - exact).abs() <= 1e-12 * scale.max(ref_scale).max(1.0),
                    "{fam:?}: moment {deg}: {q} vs {exact}"
                );
            }
        }
    }

    /// Exact germ moments `E[T^m]` from closed forms, with the scale of the terms summed
    /// (the Jacobi binomial sum cancels).
    fn exact_moment(fam: Family, m: usize) -> (f64, f64) {
        let v = match fam {
            Family::Hermite => {
                if m % 2 == 1 {
                    0.0
                } else {
                    (1..m).step_by(2).map(|k| k as f64).product()
                }
            }
            Family::Legendre => {
                if m % 2 == 1 {
                    0.0
                } else {
                    1.0 / (m as f64 + 1.0)
                }
            }
            Family::Laguerre { shape } => (0..m).map(|i| shape + i as f64).product(),
            Family::Jacobi { a, b } => {
                // T = 2U - 1, U ~ Beta(a, b): E[U^j] = prod_{i<j} (a+i)/(a+b+i).
                let mu = |j: usize| -> f64 {
                    (0..j)
                        .map(|i| (a + i as f64) / (a + b + i as f64))
                        .product()
                };
                let terms: Vec<f64> = (0..=m)
                    .map(|j| {
                        let c = binom(m, j);
                        c * 2f64.powi(j as i32) * mu(j) * (-1f64).powi((m - j) as i32)
                    })
                    .collect();
                return (terms.iter().sum(), terms.iter().map(|t| t.abs()).sum());
            }
        };
        (v, v.abs())
    }

    fn binom(n: usize, k: usize) -> f64 {
        (0..k).fold(1.0, |acc, i| acc * (n - i) as f64 / (i + 1) as f64)
    }

    #[test]
    fn derivative_matches_finite_difference() {
        for fam in families() {
            let t = 0.3;
            let h = 1e-6;
            let (_, d) = fam.value_and_derivative(5, t);
            let fd = (fam.eval(5, t + h) - fam.eval(5, t - h)) / (2.0 * h);
            assert!((d - fd).abs() < 1e-6 * d.abs().max(1.0), "{fam:?}");
        }
    }

    #[test]
    fn askey_bases_are_orthonormal_for_the_physical_distributions() {
        // p_i(germ(X)) orthonormal under the physical density (written here), with the
        // germ from Distribution::askey_affine and the family from Family::of.
        let cases = [
            Distribution::gamma(2.5, 3.0).unwrap(),
            Distribution::gamma(1.0, 0.5).unwrap(),
            Distribution::beta(2.0, 3.0, 5.0, 9.0).unwrap(),
            Distribution::beta(1.5, 1.5, -1.0, 2.0).unwrap(),
            Distribution::uniform(-2.0, 6.0).unwrap(),
            Distribution::normal(3.0, 0.5).unwrap(),
        ];
        for m in cases {
            let fam = Family::of(&m).unwrap();
            let (offset, scale) = m.askey_affine().unwrap();
            let (lo, hi) = match m {
                Distribution::Gamma { scale, .. } => (0.0, 60.0 * scale),
                Distribution::Normal { mean, std } => (mean - 14.0 * std, mean + 14.0 * std),
                _ => m.support(),
            };
            let dens = |x: f64| -> f64 {
                match m {
                    Distribution::Gamma { shape, scale } => {
                        x.powf(shape - 1.0) * (-x / scale).exp()
                            / (ln_gamma(shape).exp() * scale.powf(shape))
                    }
                    Distribution::Beta {
                        alpha,
                        beta,
                        low,
                        high,
                    } => {
                        let u = (x - low) / (high - low);
                        let lb = ln_gamma(alpha) + ln_gamma(beta) - ln_gamma(alpha + beta);
                        u.powf(alpha - 1.0) * (1.0 - u).powf(beta - 1.0) / (lb.exp() * (high - low))
                    }
                    Distribution::Uniform { low, high } => 1.0 / (high - low),
                    Distribution::Normal { mean, std } => {
                        let z = (x - mean) / std;
                        (-0.5 * z * z).exp() / (std * (2.0 * std::f64::consts::PI).sqrt())
                    }
                    _ => unreachable!(),
                }
            };
            for i in 0..6 {
                for j in 0..=i {
                    let g = integrate(
                        |x| {
                            let t = (x - offset) / scale;
                            dens(x) * fam.eval(i, t) * fam.eval(j, t)
                        },
                        lo,
                        hi,
                        2000,
                    );
                    let want = if i == j { 1.0 } else { 0.0 };
                    assert!((g - want).abs() < 1e-6, "{m:?} <{i},{j}> = {g}");
                }
            }
            // The germ law pushed through the affine map has the input's moments.
            let law = fam.law();
            assert!((offset + scale * law.mean() - m.mean()).abs() < 1e-12 * m.std());
            assert!((scale * law.std() / m.std() - 1.0).abs() < 1e-12);
        }
        for d in [
            Distribution::weibull(2.0, 1.0).unwrap(),
            Distribution::lognormal(0.0, 1.0).unwrap(),
            Distribution::integer_uniform(1, 3).unwrap(),
            Distribution::truncated_normal(0.0, 1.0, -1.0, 2.0).unwrap(),
        ] {
            assert!(
                Family::of(&d).is_none() && d.askey_affine().is_none(),
                "{d:?}"
            );
        }
    }

    #[test]
    fn bad_shapes_are_refused() {
        assert!(Family::Laguerre { shape: 0.0 }.gauss(3).is_err());
        assert!(Family::Jacobi {
            a: 1.0,
            b: f64::NAN
        }
        .validate()
        .is_err());
        assert_eq!(Family::Hermite.gauss(0), Err(AskeyError::BadNodeCount(0)));
    }
}
