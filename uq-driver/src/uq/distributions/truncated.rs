//! The standardised truncation interval of a truncated normal: mass, CDF, survival function,
//! quantile and moments, each computed without cancellation near a bound or in a tail.

use std::sync::OnceLock;

use crate::uq::quadrature::gauss_legendre;
use crate::uq::special::{norm_cdf, norm_isf, norm_pdf, norm_ppf, norm_sf};

/// Standardised truncation interval of a truncated normal.
pub(super) struct Trunc {
    pub(super) alpha: f64,
    pub(super) beta: f64,
    /// `Phi(alpha)`: mass below the interval.
    pub(super) cdf_alpha: f64,
    /// `Q(beta)`: mass above the interval.
    pub(super) sf_beta: f64,
    /// `Phi(beta) - Phi(alpha)`, computed without cancellation of large terms.
    pub(super) mass: f64,
}

impl Trunc {
    pub(super) fn new(mean: f64, std: f64, low: f64, high: f64) -> Self {
        let alpha = (low - mean) / std;
        let beta = (high - mean) / std;
        let cdf_alpha = norm_cdf(alpha);
        let sf_beta = norm_sf(beta);
        let mass = if alpha.is_finite() && is_short(alpha, beta - alpha) {
            // Narrow interval: integrate instead of subtracting close numbers.
            norm_pdf(alpha) * increment_integral(alpha, beta - alpha)
        } else if alpha >= 0.0 {
            norm_sf(alpha) - sf_beta
        } else if beta <= 0.0 {
            norm_cdf(beta) - cdf_alpha
        } else {
            1.0 - cdf_alpha - sf_beta
        };
        Trunc {
            alpha,
            beta,
            cdf_alpha,
            sf_beta,
            mass,
        }
    }

    /// Standardised quantile for probability `u` with `v = 1 - u` given
    /// separately (both accurate).
    pub(super) fn quantile(&self, u: f64, v: f64) -> f64 {
        // Near a finite bound, solve for the (small) distance to it directly,
        // so that points near the bound keep their relative resolution.
        if u <= 0.5 && self.alpha.is_finite() {
            if let Some(d) = increment_for(self.alpha, u * self.mass / norm_pdf(self.alpha)) {
                return clamp_to(self.alpha + d, self.alpha, self.beta);
            }
        }
        if v <= 0.5 && self.beta.is_finite() {
            if let Some(d) = increment_for(-self.beta, v * self.mass / norm_pdf(self.beta)) {
                return clamp_to(self.beta - d, self.alpha, self.beta);
            }
        }
        let z = if self.alpha >= 0.0 {
            // Q(z) = Q(beta) + v Z: a sum of positive terms.
            norm_isf(self.sf_beta + v * self.mass)
        } else if self.beta <= 0.0 {
            norm_ppf(self.cdf_alpha + u * self.mass)
        } else {
            let t = self.cdf_alpha + u * self.mass;
            if t <= 0.5 {
                norm_ppf(t)
            } else {
                norm_isf(self.sf_beta + v * self.mass)
            }
        };
        clamp_to(z, self.alpha, self.beta)
    }

    /// `P(alpha < Z <= z) / mass`.
    pub(super) fn cdf(&self, z: f64) -> f64 {
        if z <= self.alpha {
            0.0
        } else if z >= self.beta {
            1.0
        } else if is_short(self.alpha, z - self.alpha) {
            (norm_pdf(self.alpha) * increment_integral(self.alpha, z - self.alpha) / self.mass)
                .clamp(0.0, 1.0)
        } else if self.alpha >= 0.0 {
            ((norm_sf(self.alpha) - norm_sf(z)) / self.mass).clamp(0.0, 1.0)
        } else {
            ((norm_cdf(z) - self.cdf_alpha) / self.mass).clamp(0.0, 1.0)
        }
    }

    /// `P(Z > z) / mass` for `alpha < z < beta`.
    pub(super) fn sf(&self, z: f64) -> f64 {
        if z <= self.alpha {
            1.0
        } else if z >= self.beta {
            0.0
        } else if is_short(-self.beta, self.beta - z) {
            (norm_pdf(self.beta) * increment_integral(-self.beta, self.beta - z) / self.mass)
                .clamp(0.0, 1.0)
        } else if self.beta <= 0.0 {
            ((norm_cdf(self.beta) - norm_cdf(z)) / self.mass).clamp(0.0, 1.0)
        } else {
            ((norm_sf(z) - self.sf_beta) / self.mass).clamp(0.0, 1.0)
        }
    }

    /// Mean and standard deviation of the standardised truncated variable.
    pub(super) fn moments(&self) -> (f64, f64) {
        let (a, b) = (self.alpha, self.beta);
        if b - a <= 2.0 {
            // Narrow interval: the closed form cancels; integrate instead.
            // Density relative to phi(c): exp(-(c h u + h^2 u^2 / 2)).
            let (nodes, weights) = legendre_24();
            let c = 0.5 * (a + b);
            let h = 0.5 * (b - a);
            let f: Vec<f64> = nodes
                .iter()
                .zip(weights)
                .map(|(&u, &w)| w * (-(c * h * u + 0.5 * h * h * u * u)).exp())
                .collect();
            let s: f64 = f.iter().sum();
            let mu: f64 = f.iter().zip(nodes).map(|(f, u)| f * u).sum::<f64>() / s;
            let var: f64 = f
                .iter()
                .zip(nodes)
                .map(|(f, u)| f * (u - mu) * (u - mu))
                .sum::<f64>()
                / s;
            return (c + h * mu, h * var.max(0.0).sqrt());
        }
        let xphi = |x: f64| if x.is_finite() { x * norm_pdf(x) } else { 0.0 };
        let lambda = (norm_pdf(a) - norm_pdf(b)) / self.mass;
        let var = 1.0 + (xphi(a) - xphi(b)) / self.mass - lambda * lambda;
        (lambda, var.max(0.0).sqrt())
    }
}

/// Whether `[a, a + d]` is short enough for [`increment_integral`] to be
/// exact to rounding (the integrand varies by at most a factor e^4 or so).
fn is_short(a: f64, d: f64) -> bool {
    d.is_finite() && d * a.abs().max((a + d).abs()).max(1.0) <= 4.0
}

/// `int_0^d exp(-a t - t^2 / 2) dt = (Phi(a + d) - Phi(a)) / phi(a)`, by
/// 24-point Gauss–Legendre (accurate to rounding when [`is_short`]).
fn increment_integral(a: f64, d: f64) -> f64 {
    let (nodes, weights) = legendre_24();
    let half = 0.5 * d;
    let s: f64 = nodes
        .iter()
        .zip(weights)
        .map(|(&x, &w)| {
            let t = half * (1.0 + x);
            w * (-(a * t + 0.5 * t * t)).exp()
        })
        .sum();
    half * s
}

/// The `d >= 0` with `increment_integral(a, d) = target`, when it is small
/// (`target * max(|a|, 1) <= 0.5`); `None` otherwise.
fn increment_for(a: f64, target: f64) -> Option<f64> {
    if target.is_nan() || target < 0.0 || target * a.abs().max(1.0) > 0.5 {
        return None;
    }
    let mut d = target;
    for _ in 0..30 {
        let slope = (-(a * d + 0.5 * d * d)).exp();
        let step = (increment_integral(a, d) - target) / slope;
        d = (d - step).max(0.0);
        if step.abs() <= 1e-16 * d {
            break;
        }
    }
    Some(d)
}

/// The 24-point Gauss–Legendre rule, computed once.
fn legendre_24() -> (&'static [f64], &'static [f64]) {
    static RULE: OnceLock<(Vec<f64>, Vec<f64>)> = OnceLock::new();
    let rule = RULE.get_or_init(|| gauss_legendre(24).unwrap_or_default());
    (&rule.0, &rule.1)
}

/// `x` limited to `[lo, hi]`, NaN kept; unlike `f64::clamp` it never panics (`lo > hi` or a
/// NaN bound, possible for a `Distribution` built as a struct literal and not validated:
/// the result is then meaningless, but the host is not brought down).
pub(super) fn clamp_to(x: f64, lo: f64, hi: f64) -> f64 {
    if x.is_nan() {
        x
    } else {
        x.max(lo).min(hi)
    }
}
