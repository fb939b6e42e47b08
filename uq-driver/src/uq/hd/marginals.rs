//! More input families: Beta, Gamma, Weibull and integer-uniform marginals.
//!
//! Each marginal has its pdf, cdf, survival function and quantile (accurate in both
//! tails: the upper tail is inverted from the survival function), the isoprobabilistic
//! map to and from the standard normal (`x = F^-1(Phi(z))`), and where the Askey scheme
//! has one, the affine map to its Askey germ (see [`super::askey`]):
//!
//! | marginal | Askey family | germ `t` |
//! | --- | --- | --- |
//! | `Beta { alpha, beta, low, high }` | `Jacobi { a: alpha, b: beta }` | `t = 2 (x - low) / (high - low) - 1` in `[-1, 1]` |
//! | `Gamma { shape, scale }` | `Laguerre { shape }` | `t = x / scale` in `[0, inf)` |
//! | `Weibull { shape, scale }` | none: use the normal map (Hermite) | |
//! | `IntegerUniform { low, high }` | none (discrete) | `x = low + floor(u (high - low + 1))`, `u` uniform |
//!
//! The regularized incomplete beta function comes from `statrs`; the regularized
//! incomplete gamma function is computed here (series / Lentz continued fraction), since
//! `statrs` 0.18 returns 0 for arguments below about 1e-20 (the far left tail of a
//! gamma with shape < 1). Quantiles are
//! solved here by a bracketed Newton iteration (relative accuracy about 1e-14, tested).
//! Random draws use `rand_distr` on the caller's stream (e.g. a ChaCha20 stream from
//! [`crate::uq::rng::stream`]); [`Marginal::from_uniform`] gives inversion instead.

use rand::Rng;
use rand_distr::Distribution as _;
use statrs::function::beta::{beta_reg, ln_beta};
use statrs::function::gamma::ln_gamma;

use super::askey::Family;
use crate::uq::special::{norm_cdf, norm_isf, norm_ppf, norm_sf};

/// Errors of the marginal constructors.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MarginalError {
    /// A parameter is not finite and positive.
    #[error("{family}: {name} = {value} must be finite and > 0")]
    NotPositive {
        /// Family.
        family: &'static str,
        /// Parameter.
        name: &'static str,
        /// Value.
        value: f64,
    },
    /// The bounds are not ordered or not finite.
    #[error("{family}: need finite low < high (got low = {low}, high = {high})")]
    Bounds {
        /// Family.
        family: &'static str,
        /// Lower bound.
        low: f64,
        /// Upper bound.
        high: f64,
    },
}

/// A marginal distribution (see the module docs for the parameters and germs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Marginal {
    /// Beta(alpha, beta) scaled to `[low, high]`.
    Beta {
        /// First shape.
        alpha: f64,
        /// Second shape.
        beta: f64,
        /// Lower end.
        low: f64,
        /// Upper end.
        high: f64,
    },
    /// Gamma with density `x^(shape-1) e^(-x/scale) / (Gamma(shape) scale^shape)`.
    Gamma {
        /// Shape `k`.
        shape: f64,
        /// Scale `theta` (mean `k theta`).
        scale: f64,
    },
    /// Weibull with cdf `1 - exp(-(x/scale)^shape)`.
    Weibull {
        /// Shape `k`.
        shape: f64,
        /// Scale `lambda`.
        scale: f64,
    },
    /// Uniform on the integers `low..=high`.
    IntegerUniform {
        /// Smallest value.
        low: i64,
        /// Largest value.
        high: i64,
    },
}

fn positive(family: &'static str, name: &'static str, value: f64) -> Result<(), MarginalError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(MarginalError::NotPositive {
            family,
            name,
            value,
        })
    }
}

impl Marginal {
    /// Beta(alpha, beta) on `[low, high]`.
    pub fn beta(alpha: f64, beta: f64, low: f64, high: f64) -> Result<Self, MarginalError> {
        positive("beta", "alpha", alpha)?;
        positive("beta", "beta", beta)?;
        if !(low.is_finite() && high.is_finite() && low < high) {
            return Err(MarginalError::Bounds {
                family: "beta",
                low,
                high,
            });
        }
        Ok(Marginal::Beta {
            alpha,
            beta,
            low,
            high,
        })
    }

    /// Gamma(shape, scale).
    pub fn gamma(shape: f64, scale: f64) -> Result<Self, MarginalError> {
        positive("gamma", "shape", shape)?;
        positive("gamma", "scale", scale)?;
        Ok(Marginal::Gamma { shape, scale })
    }

    /// Weibull(shape, scale).
    pub fn weibull(shape: f64, scale: f64) -> Result<Self, MarginalError> {
        positive("weibull", "shape", shape)?;
        positive("weibull", "scale", scale)?;
        Ok(Marginal::Weibull { shape, scale })
    }

    /// Uniform on `low..=high` (inclusive).
    pub fn integer_uniform(low: i64, high: i64) -> Result<Self, MarginalError> {
        if low > high {
            return Err(MarginalError::Bounds {
                family: "integer_uniform",
                low: low as f64,
                high: high as f64,
            });
        }
        Ok(Marginal::IntegerUniform { low, high })
    }

    /// Support `(low, high)`.
    pub fn support(&self) -> (f64, f64) {
        match *self {
            Marginal::Beta { low, high, .. } => (low, high),
            Marginal::Gamma { .. } | Marginal::Weibull { .. } => (0.0, f64::INFINITY),
            Marginal::IntegerUniform { low, high } => (low as f64, high as f64),
        }
    }

    /// Mean.
    pub fn mean(&self) -> f64 {
        match *self {
            Marginal::Beta {
                alpha,
                beta,
                low,
                high,
            } => low + (high - low) * alpha / (alpha + beta),
            Marginal::Gamma { shape, scale } => shape * scale,
            Marginal::Weibull { shape, scale } => scale * ln_gamma(1.0 + 1.0 / shape).exp(),
            Marginal::IntegerUniform { low, high } => 0.5 * (low as f64 + high as f64),
        }
    }

    /// Variance.
    pub fn variance(&self) -> f64 {
        match *self {
            Marginal::Beta {
                alpha,
                beta,
                low,
                high,
            } => {
                let s = alpha + beta;
                (high - low).powi(2) * alpha * beta / (s * s * (s + 1.0))
            }
            Marginal::Gamma { shape, scale } => shape * scale * scale,
            Marginal::Weibull { shape, scale } => {
                let g1 = ln_gamma(1.0 + 1.0 / shape).exp();
                let g2 = ln_gamma(1.0 + 2.0 / shape).exp();
                scale * scale * (g2 - g1 * g1)
            }
            Marginal::IntegerUniform { low, high } => {
                let n = (high - low) as f64 + 1.0;
                (n * n - 1.0) / 12.0
            }
        }
    }

    /// Density (for `IntegerUniform`: the probability mass at an integer, else 0).
    pub fn pdf(&self, x: f64) -> f64 {
        match *self {
            Marginal::Beta {
                alpha,
                beta,
                low,
                high,
            } => {
                if x < low || x > high {
                    return 0.0;
                }
                let w = high - low;
                let u = (x - low) / w;
                let l = (alpha - 1.0) * u.ln() + (beta - 1.0) * (1.0 - u).ln()
                    - ln_beta(alpha, beta)
                    - w.ln();
                if (u == 0.0 && alpha == 1.0) || (u == 1.0 && beta == 1.0) {
                    // 0 * ln 0 terms.
                    let l = (if u == 0.0 {
                        0.0
                    } else {
                        (alpha - 1.0) * u.ln()
                    }) + (if u == 1.0 {
                        0.0
                    } else {
                        (beta - 1.0) * (1.0 - u).ln()
                    }) - ln_beta(alpha, beta)
                        - w.ln();
                    return l.exp();
                }
                l.exp()
            }
            Marginal::Gamma { shape, scale } => {
                if x < 0.0 {
                    return 0.0;
                }
                let t = x / scale;
                if t == 0.0 {
                    return if shape < 1.0 {
                        f64::INFINITY
                    } else if shape == 1.0 {
                        1.0 / scale
                    } else {
                        0.0
                    };
                }
                ((shape - 1.0) * t.ln() - t - ln_gamma(shape)).exp() / scale
            }
            Marginal::Weibull { shape, scale } => {
                if x < 0.0 {
                    return 0.0;
                }
                let t = x / scale;
                shape / scale * t.powf(shape - 1.0) * (-t.powf(shape)).exp()
            }
            Marginal::IntegerUniform { low, high } => {
                if x.fract() == 0.0 && x >= low as f64 && x <= high as f64 {
                    1.0 / ((high - low) as f64 + 1.0)
                } else {
                    0.0
                }
            }
        }
    }

    /// Cumulative distribution function `P(X <= x)`.
    pub fn cdf(&self, x: f64) -> f64 {
        match *self {
            Marginal::Beta {
                alpha,
                beta,
                low,
                high,
            } => {
                let u = ((x - low) / (high - low)).clamp(0.0, 1.0);
                beta_reg(alpha, beta, u)
            }
            Marginal::Gamma { shape, scale } => {
                if x <= 0.0 {
                    0.0
                } else {
                    gamma_pq(shape, x / scale).0
                }
            }
            Marginal::Weibull { shape, scale } => {
                if x <= 0.0 {
                    0.0
                } else {
                    -(-(x / scale).powf(shape)).exp_m1()
                }
            }
            Marginal::IntegerUniform { low, high } => {
                let k = x.floor();
                if k < low as f64 {
                    0.0
                } else if k >= high as f64 {
                    1.0
                } else {
                    (k - low as f64 + 1.0) / ((high - low) as f64 + 1.0)
                }
            }
        }
    }

    /// Survival function `P(X > x)`, accurate in the upper tail.
    pub fn sf(&self, x: f64) -> f64 {
        match *self {
            Marginal::Beta {
                alpha,
                beta,
                low,
                high,
            } => {
                let u = ((x - low) / (high - low)).clamp(0.0, 1.0);
                beta_reg(beta, alpha, 1.0 - u)
            }
            Marginal::Gamma { shape, scale } => {
                if x <= 0.0 {
                    1.0
                } else {
                    gamma_pq(shape, x / scale).1
                }
            }
            Marginal::Weibull { shape, scale } => {
                if x <= 0.0 {
                    1.0
                } else {
                    (-(x / scale).powf(shape)).exp()
                }
            }
            Marginal::IntegerUniform { .. } => 1.0 - self.cdf(x),
        }
    }

    /// Quantile `F^-1(p)`, `p` in `[0, 1]` (the support's ends at 0 and 1).
    pub fn quantile(&self, p: f64) -> f64 {
        self.invert(p, 1.0 - p, p <= 0.5)
    }

    /// Inverse survival function: the `x` with `P(X > x) = q` (accurate for tiny `q`).
    pub fn quantile_sf(&self, q: f64) -> f64 {
        self.invert(1.0 - q, q, q > 0.5)
    }

    /// Solves `F(x) = p` (when `lower`) or `S(x) = q` otherwise.
    fn invert(&self, p: f64, q: f64, lower: bool) -> f64 {
        let (lo, hi) = self.support();
        if p <= 0.0 {
            return lo;
        }
        if q <= 0.0 {
            return hi;
        }
        match *self {
            Marginal::Weibull { shape, scale } => {
                // Closed form: x = scale (-ln(1 - p))^(1/k).
                let h = if lower { -(-p).ln_1p() } else { -q.ln() };
                scale * h.powf(1.0 / shape)
            }
            Marginal::IntegerUniform { low, high } => {
                let n = (high - low) as f64 + 1.0;
                let k = (p * n).ceil() - 1.0;
                (low as f64 + k.max(0.0)).min(high as f64)
            }
            // Solved on the standard variable (u in [0, 1], t = x / scale) so that
            // the tails near a finite end keep their relative accuracy.
            Marginal::Beta {
                alpha,
                beta,
                low,
                high,
            } => {
                let std = Marginal::Beta {
                    alpha,
                    beta,
                    low: 0.0,
                    high: 1.0,
                };
                let u = solve_increasing(&std, p, q, lower, 0.0, 1.0);
                low + (high - low) * u
            }
            Marginal::Gamma { shape, scale } => {
                let std = Marginal::Gamma { shape, scale: 1.0 };
                let mut b = shape + 10.0 * shape.sqrt() + 10.0;
                while std.sf(b) > q.min(0.5) {
                    b *= 2.0;
                }
                scale * solve_increasing(&std, p, q, lower, 0.0, b)
            }
        }
    }

    /// `x = F^-1(Phi(z))`: the value of standard-normal germ `z` (tails via `sf`).
    pub fn from_standard_normal(&self, z: f64) -> f64 {
        if z <= 0.0 {
            self.quantile(norm_cdf(z))
        } else {
            self.quantile_sf(norm_sf(z))
        }
    }

    /// `z = Phi^-1(F(x))`, the inverse of [`Marginal::from_standard_normal`] (for the
    /// integer uniform: the normal value of the cell's centre).
    pub fn to_standard_normal(&self, x: f64) -> f64 {
        if let Marginal::IntegerUniform { low, high } = *self {
            let n = (high - low) as f64 + 1.0;
            let k = (x.round() - low as f64).clamp(0.0, n - 1.0);
            return norm_ppf((k + 0.5) / n);
        }
        let p = self.cdf(x);
        if p <= 0.5 {
            norm_ppf(p)
        } else {
            norm_isf(self.sf(x))
        }
    }

    /// The value at uniform germ `u` in (0, 1): `F^-1(u)` (for the integer uniform,
    /// `low + floor(u (high - low + 1))`).
    pub fn from_uniform(&self, u: f64) -> f64 {
        if let Marginal::IntegerUniform { low, high } = *self {
            let n = (high - low) as f64 + 1.0;
            return (low as f64 + (u * n).floor()).clamp(low as f64, high as f64);
        }
        self.quantile(u)
    }

    /// The Askey family of this marginal, if the scheme has one.
    pub fn askey_family(&self) -> Option<Family> {
        match *self {
            Marginal::Beta { alpha, beta, .. } => Some(Family::Jacobi { a: alpha, b: beta }),
            Marginal::Gamma { shape, .. } => Some(Family::Laguerre { shape }),
            _ => None,
        }
    }

    /// Physical value of Askey germ `t` (`None` when there is no Askey family).
    pub fn from_askey_germ(&self, t: f64) -> Option<f64> {
        match *self {
            Marginal::Beta { low, high, .. } => Some(low + (high - low) * 0.5 * (t + 1.0)),
            Marginal::Gamma { scale, .. } => Some(scale * t),
            _ => None,
        }
    }

    /// Askey germ of physical value `x` (`None` when there is no Askey family).
    pub fn to_askey_germ(&self, x: f64) -> Option<f64> {
        match *self {
            Marginal::Beta { low, high, .. } => Some(2.0 * (x - low) / (high - low) - 1.0),
            Marginal::Gamma { scale, .. } => Some(x / scale),
            _ => None,
        }
    }

    /// A random draw with `rand_distr` (parameters validated by the constructors).
    pub fn sample<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        match *self {
            Marginal::Beta {
                alpha,
                beta,
                low,
                high,
            } => {
                let d = rand_distr::Beta::new(alpha, beta).expect("validated shapes");
                low + (high - low) * d.sample(rng)
            }
            Marginal::Gamma { shape, scale } => rand_distr::Gamma::new(shape, scale)
                .expect("validated parameters")
                .sample(rng),
            Marginal::Weibull { shape, scale } => rand_distr::Weibull::new(scale, shape)
                .expect("validated parameters")
                .sample(rng),
            Marginal::IntegerUniform { low, high } => rng.gen_range(low..=high) as f64,
        }
    }
}

/// Regularized incomplete gamma functions `(P(a, x), Q(a, x))`, `a > 0`, `x >= 0`:
/// the series for `x < a + 1`, the continued fraction for `Q` otherwise (Numerical
/// Recipes 6.2), each with the prefactor `x^a e^-x / Gamma(a)` in logs.
pub fn gamma_pq(a: f64, x: f64) -> (f64, f64) {
    if x <= 0.0 {
        return (0.0, 1.0);
    }
    let log_pre = -x + a * x.ln() - ln_gamma(a);
    if x < a + 1.0 {
        let mut term = 1.0 / a;
        let mut sum = term;
        for n in 1..10_000 {
            term *= x / (a + n as f64);
            sum += term;
            if term.abs() < sum.abs() * f64::EPSILON {
                break;
            }
        }
        let p = sum * log_pre.exp();
        (p, 1.0 - p)
    } else {
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..10_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < tiny {
                d = tiny;
            }
            c = b + an / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            let del = d * c;
            h *= del;
            if (del - 1.0).abs() < f64::EPSILON {
                break;
            }
        }
        let q = log_pre.exp() * h;
        (1.0 - q, q)
    }
}

/// Bracketed Newton for `F(x) = p` (`lower`) or `S(x) = q` on `[a, b]`, `F(a) <= p <=
/// F(b)`, on the logarithms (`ln F(x) - ln p`, slope `pdf / F`; `ln q - ln S(x)`, slope
/// `pdf / S`), which converges in a few steps even in far, log-concave tails; bisection
/// (geometric near 0) whenever Newton leaves the bracket.
fn solve_increasing(m: &Marginal, p: f64, q: f64, lower: bool, a: f64, b: f64) -> f64 {
    // (g(x), g'(x)): increasing in x, zero at the root.
    let g = |x: f64| -> (f64, f64) {
        let d = m.pdf(x);
        if lower {
            let f = m.cdf(x);
            if f <= 0.0 {
                (f64::NEG_INFINITY, f64::NAN)
            } else {
                (f.ln() - p.ln(), d / f)
            }
        } else {
            let sv = m.sf(x);
            if sv <= 0.0 {
                (f64::INFINITY, f64::NAN)
            } else {
                (q.ln() - sv.ln(), d / sv)
            }
        }
    };
    let (mut a, mut b) = (a, b);
    let mut x = 0.5 * (a + b);
    for _ in 0..400 {
        let (gx, dg) = g(x);
        if gx == 0.0 {
            return x;
        }
        if gx < 0.0 {
            a = x;
        } else {
            b = x;
        }
        let newton = x - gx / dg;
        let next = if dg > 0.0 && newton.is_finite() && newton > a && newton < b {
            newton
        } else if a == 0.0 {
            // Geometric step towards 0: the left tail can be far below b.
            b * 1e-3
        } else if a > 0.0 && b / a > 4.0 {
            (a * b).sqrt()
        } else {
            0.5 * (a + b)
        };
        if (next - x).abs() <= 2.0 * f64::EPSILON * x.abs() || b - a <= 2.0 * f64::EPSILON * b {
            return next;
        }
        x = next;
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::uq::quadrature::gauss_legendre;
    use crate::uq::rng::stream;

    fn integrate(f: impl Fn(f64) -> f64, lo: f64, hi: f64, pieces: usize) -> f64 {
        let (x, w) = gauss_legendre(20).unwrap();
        let h = (hi - lo) / pieces as f64;
        (0..pieces)
            .map(|p| {
                let a = lo + p as f64 * h;
                x.iter()
                    .zip(&w)
                    .map(|(xi, wi)| wi * 0.5 * h * f(a + 0.5 * h * (xi + 1.0)))
                    .sum::<f64>()
            })
            .sum()
    }

    fn continuous() -> Vec<Marginal> {
        vec![
            Marginal::beta(2.0, 5.0, 1.0, 3.0).unwrap(),
            Marginal::beta(0.5, 0.5, -1.0, 1.0).unwrap(),
            Marginal::beta(3.5, 1.2, 0.0, 10.0).unwrap(),
            Marginal::gamma(0.5, 2.0).unwrap(),
            Marginal::gamma(3.0, 0.7).unwrap(),
            Marginal::gamma(40.0, 1.5).unwrap(),
            Marginal::weibull(1.5, 2.0).unwrap(),
            Marginal::weibull(0.7, 1.0).unwrap(),
        ]
    }

    #[test]
    fn closed_form_special_cases() {
        // Gamma(1, theta) is exponential.
        let e = Marginal::gamma(1.0, 2.5).unwrap();
        for &x in &[0.01, 0.5, 3.0, 20.0, 80.0] {
            assert!((e.cdf(x) - (1.0 - (-x / 2.5).exp())).abs() < 1e-15);
            assert!((e.sf(x) / (-x / 2.5).exp() - 1.0).abs() < 1e-13);
        }
        assert!((e.quantile(0.3) - (-2.5 * 0.7f64.ln())).abs() < 1e-14);
        // Gamma(3, 1) is Erlang: F = 1 - e^-x (1 + x + x^2/2).
        let g = Marginal::gamma(3.0, 1.0).unwrap();
        for &x in &[0.2f64, 1.0, 4.0, 12.0] {
            let f = 1.0 - (-x).exp() * (1.0 + x + x * x / 2.0);
            assert!((g.cdf(x) - f).abs() < 1e-14, "{x}");
        }
        // Beta(1,1) on [low, high] is uniform; Beta(2,2): 3u^2 - 2u^3; Beta(a,1): u^a.
        let u = Marginal::beta(1.0, 1.0, -2.0, 6.0).unwrap();
        assert!((u.cdf(0.0) - 0.25).abs() < 1e-15);
        assert!((u.quantile(0.75) - 4.0).abs() < 1e-13);
        assert!((u.pdf(1.0) - 0.125).abs() < 1e-15);
        let b22 = Marginal::beta(2.0, 2.0, 0.0, 1.0).unwrap();
        for &x in &[0.1f64, 0.5, 0.93] {
            assert!((b22.cdf(x) - (3.0 * x * x - 2.0 * x.powi(3))).abs() < 1e-14);
        }
        let ba1 = Marginal::beta(2.7, 1.0, 0.0, 1.0).unwrap();
        assert!((ba1.cdf(0.4) - 0.4f64.powf(2.7)).abs() < 1e-15);
        // Weibull closed forms.
        let w = Marginal::weibull(1.5, 2.0).unwrap();
        assert!((w.cdf(1.0) - (1.0 - (-(0.5f64).powf(1.5)).exp())).abs() < 1e-15);
        assert!((w.quantile(0.5) - 2.0 * 2f64.ln().powf(1.0 / 1.5)).abs() < 1e-14);
    }

    #[test]
    fn incomplete_gamma_matches_closed_forms_far_into_both_tails() {
        // a = 1: P = 1 - e^-x; a = 1/2: P = erf(sqrt x) (small x: 2 sqrt(x/pi)).
        for &x in &[1e-30f64, 1e-10, 0.3, 2.0, 30.0, 700.0] {
            let (p, q) = gamma_pq(1.0, x);
            assert!((p / -(-x).exp_m1() - 1.0).abs() < 1e-14, "{x}");
            assert!((q / (-x).exp() - 1.0).abs() < 1e-13, "{x}");
        }
        let (p, _) = gamma_pq(0.5, 1e-24);
        assert!((p / (2.0 * (1e-24 / std::f64::consts::PI).sqrt()) - 1.0).abs() < 1e-11);
        // Q(1/2, x) = erfc(sqrt x).
        let (_, q) = gamma_pq(0.5, 25.0);
        assert!((q / crate::uq::special::erfc(5.0) - 1.0).abs() < 1e-13);
    }

    #[test]
    fn quantile_inverts_cdf_in_both_tails() {
        for m in continuous() {
            for &p in &[1e-12, 1e-6, 0.01, 0.3, 0.5, 0.77, 0.99] {
                // Tolerance: 1e-11 relative, plus the resolution of x itself
                // (pdf * a few ulps of x) where x sits close to a finite end.
                let x = m.quantile(p);
                let res = |x: f64| m.pdf(x) * 4.0 * f64::EPSILON * x.abs().max(1e-300);
                assert!(
                    (m.cdf(x) - p).abs() < 1e-11 * p + res(x),
                    "{m:?}: cdf(quantile({p})) = {}",
                    m.cdf(x)
                );
                let xs = m.quantile_sf(p);
                assert!(
                    (m.sf(xs) - p).abs() < 1e-11 * p + res(xs),
                    "{m:?}: sf(quantile_sf({p})) = {}",
                    m.sf(xs)
                );
            }
        }
    }

    #[test]
    fn extreme_shapes_are_accurate_or_at_the_representable_end() {
        // Quantiles for tail probabilities down to 1e-300: accurate to 1e-10 relative or
        // to the resolution of x (pdf * a few ulps), unless the exact quantile is not
        // representable (it underflows below the smallest double, or lies closer to a
        // finite end than one ulp), in which case the end itself is returned.
        for m in [
            Marginal::beta(0.1, 0.1, 0.0, 1.0).unwrap(),
            Marginal::beta(50.0, 0.3, 0.0, 1.0).unwrap(),
            Marginal::gamma(0.02, 1.0).unwrap(),
            Marginal::gamma(800.0, 2.0).unwrap(),
            Marginal::weibull(0.2, 3.0).unwrap(),
            Marginal::weibull(20.0, 3.0).unwrap(),
        ] {
            let (lo, hi) = m.support();
            let at_end =
                |x: f64| x == lo || (hi.is_finite() && x >= hi * (1.0 - 4.0 * f64::EPSILON));
            let res = |x: f64| m.pdf(x) * 16.0 * f64::EPSILON * x.abs();
            for &p in &[1e-300, 1e-100, 1e-15, 1e-8, 0.1, 0.5, 0.9] {
                let x = m.quantile(p);
                let ok = (m.cdf(x) - p).abs() < 1e-10 * p + res(x) || at_end(x);
                assert!(ok, "{m:?}: quantile({p:e}) = {x:e}, cdf {:e}", m.cdf(x));
                let xs = m.quantile_sf(p);
                let ok = (m.sf(xs) - p).abs() < 1e-10 * p + res(xs) || at_end(xs);
                assert!(ok, "{m:?}: quantile_sf({p:e}) = {xs:e}, sf {:e}", m.sf(xs));
            }
        }
    }

    #[test]
    fn normal_map_round_trips_into_the_tails() {
        for m in continuous() {
            for &z in &[-7.0, -3.0, -1.0, 0.0, 0.5, 2.0, 6.5] {
                let x = m.from_standard_normal(z);
                let (lo, hi) = m.support();
                if (x - lo).abs() < 1e-6 * (1.0 + lo.abs())
                    || (hi - x).abs() < 1e-6 * (1.0 + hi.abs())
                {
                    // Too close to a finite end for x to resolve the probability.
                    continue;
                }
                let back = m.to_standard_normal(x);
                assert!(
                    (back - z).abs() < 1e-8 * (1.0 + z.abs()),
                    "{m:?} z={z}: {back}"
                );
            }
        }
    }

    #[test]
    fn moments_by_quadrature_match_the_closed_forms() {
        for m in continuous() {
            // Integrate in u = F(x) space: E[g(X)] = int_0^1 g(F^-1(u)) du, split to
            // resolve the tails (substitution-free, independent of pdf and mean code).
            let e = |g: &dyn Fn(f64) -> f64| -> f64 {
                let ln = |u: f64| g(m.quantile(u));
                let un = |u: f64| g(m.quantile_sf(u));
                // Lower half by u = exp(-s), upper by 1 - u = exp(-s), s in (ln 2, 60).
                let lo = integrate(|s| (-s).exp() * ln((-s).exp()), 2f64.ln(), 60.0, 400);
                let hi = integrate(|s| (-s).exp() * un((-s).exp()), 2f64.ln(), 60.0, 400);
                lo + hi
            };
            let mean = e(&|x| x);
            let var = e(&|x| (x - mean).powi(2));
            let sd = m.variance().sqrt();
            assert!(
                (mean - m.mean()).abs() < 1e-8 * sd,
                "{m:?}: {mean} vs {}",
                m.mean()
            );
            assert!(
                (var / m.variance() - 1.0).abs() < 1e-7,
                "{m:?}: {var} vs {}",
                m.variance()
            );
        }
    }

    #[test]
    fn askey_bases_are_orthonormal_for_the_physical_distributions() {
        // p_i(germ(X)) orthonormal under the physical density (written here).
        let cases = [
            Marginal::gamma(2.5, 3.0).unwrap(),
            Marginal::gamma(1.0, 0.5).unwrap(),
            Marginal::beta(2.0, 3.0, 5.0, 9.0).unwrap(),
            Marginal::beta(1.5, 1.5, -1.0, 2.0).unwrap(),
        ];
        for m in cases {
            let fam = m.askey_family().unwrap();
            let (lo, hi) = match m {
                Marginal::Gamma { scale, .. } => (0.0, 60.0 * scale),
                _ => m.support(),
            };
            let dens = |x: f64| -> f64 {
                match m {
                    Marginal::Gamma { shape, scale } => {
                        x.powf(shape - 1.0) * (-x / scale).exp()
                            / (ln_gamma(shape).exp() * scale.powf(shape))
                    }
                    Marginal::Beta {
                        alpha,
                        beta,
                        low,
                        high,
                    } => {
                        let u = (x - low) / (high - low);
                        u.powf(alpha - 1.0) * (1.0 - u).powf(beta - 1.0)
                            / (ln_beta(alpha, beta).exp() * (high - low))
                    }
                    _ => unreachable!(),
                }
            };
            for i in 0..6 {
                for j in 0..=i {
                    let g = integrate(
                        |x| {
                            let t = m.to_askey_germ(x).unwrap();
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
            let x = m.mean();
            assert!((m.from_askey_germ(m.to_askey_germ(x).unwrap()).unwrap() - x).abs() < 1e-14);
        }
        assert!(Marginal::weibull(2.0, 1.0)
            .unwrap()
            .askey_family()
            .is_none());
    }

    #[test]
    fn draws_are_reproducible_and_have_the_right_mean() {
        for m in continuous() {
            let mut r1 = stream(7, 3);
            let mut r2 = stream(7, 3);
            let n = 40_000;
            let a: Vec<f64> = (0..n).map(|_| m.sample(&mut r1)).collect();
            let b: Vec<f64> = (0..n).map(|_| m.sample(&mut r2)).collect();
            assert_eq!(a, b);
            let mean = a.iter().sum::<f64>() / n as f64;
            let se = (m.variance() / n as f64).sqrt();
            assert!((mean - m.mean()).abs() < 5.0 * se, "{m:?}: {mean}");
        }
    }

    #[test]
    fn integer_uniform_is_inclusive_and_equiprobable() {
        let m = Marginal::integer_uniform(-2, 3).unwrap();
        let mut counts = [0usize; 6];
        let n = 6000;
        for k in 0..n {
            let u = (k as f64 + 0.5) / n as f64;
            let x = m.from_uniform(u);
            counts[(x as i64 + 2) as usize] += 1;
        }
        assert_eq!(counts, [1000; 6]);
        assert_eq!(m.cdf(-2.0), 1.0 / 6.0);
        assert_eq!(m.cdf(3.0), 1.0);
        assert_eq!(m.quantile(0.5), 0.0);
        assert!((m.variance() - 35.0 / 12.0).abs() < 1e-15);
        let z = m.to_standard_normal(3.0);
        assert_eq!(m.from_standard_normal(z), 3.0);
        let mut r = stream(1, 1);
        assert!((0..1000).all(|_| {
            let x = m.sample(&mut r);
            (-2.0..=3.0).contains(&x)
        }));
        assert!(Marginal::integer_uniform(3, 2).is_err());
    }

    #[test]
    fn bad_parameters_are_refused() {
        assert!(Marginal::beta(0.0, 1.0, 0.0, 1.0).is_err());
        assert!(Marginal::beta(1.0, 1.0, 1.0, 1.0).is_err());
        assert!(Marginal::gamma(1.0, -1.0).is_err());
        assert!(Marginal::weibull(f64::NAN, 1.0).is_err());
    }
}
