//! The standard shapes behind the Beta, Gamma and Weibull inputs: Beta(a, b) on [0, 1],
//! Gamma(k, 1) and Weibull(k, 1), each with density, CDF and survival function (both tails
//! accurate), and the quantile solved from whichever tail is small.
//!
//! The regularized incomplete beta function comes from `statrs`; the regularized incomplete
//! gamma function is computed here (series / Lentz continued fraction), since `statrs` 0.18
//! returns 0 for arguments below about 1e-20 (the far left tail of a gamma with shape < 1).
//! Quantiles are solved by a bracketed Newton iteration on the logarithms (relative accuracy
//! about 1e-14, tested), Weibull's in closed form.

use statrs::function::beta::{beta_reg, ln_beta};
use statrs::function::gamma::ln_gamma;

/// A standard shape (the physical input is an affine image of it).
#[derive(Clone, Copy, Debug)]
pub(super) enum Shape {
    /// Beta(a, b) on [0, 1].
    Beta(f64, f64),
    /// Gamma(k, 1).
    Gamma(f64),
    /// Weibull(k, 1): CDF 1 - exp(-x^k).
    Weibull(f64),
}

impl Shape {
    /// Support `(low, high)`.
    pub(super) fn support(self) -> (f64, f64) {
        match self {
            Shape::Beta(..) => (0.0, 1.0),
            Shape::Gamma(_) | Shape::Weibull(_) => (0.0, f64::INFINITY),
        }
    }

    /// Mean and variance.
    pub(super) fn moments(self) -> (f64, f64) {
        match self {
            Shape::Beta(a, b) => {
                let s = a + b;
                (a / s, a * b / (s * s * (s + 1.0)))
            }
            Shape::Gamma(k) => (k, k),
            Shape::Weibull(k) => {
                let g1 = ln_gamma(1.0 + 1.0 / k).exp();
                let g2 = ln_gamma(1.0 + 2.0 / k).exp();
                (g1, g2 - g1 * g1)
            }
        }
    }

    /// Density.
    pub(super) fn pdf(self, x: f64) -> f64 {
        match self {
            Shape::Beta(a, b) => {
                if !(0.0..=1.0).contains(&x) {
                    return 0.0;
                }
                // 0 · ln 0 terms vanish (a = 1 at 0, b = 1 at 1).
                let left = if a == 1.0 { 0.0 } else { (a - 1.0) * x.ln() };
                let right = if b == 1.0 {
                    0.0
                } else {
                    (b - 1.0) * (-x).ln_1p()
                };
                (left + right - ln_beta(a, b)).exp()
            }
            Shape::Gamma(k) => {
                if x < 0.0 {
                    0.0
                } else if x == 0.0 {
                    match k.partial_cmp(&1.0) {
                        Some(std::cmp::Ordering::Less) => f64::INFINITY,
                        Some(std::cmp::Ordering::Equal) => 1.0,
                        _ => 0.0,
                    }
                } else {
                    ((k - 1.0) * x.ln() - x - ln_gamma(k)).exp()
                }
            }
            Shape::Weibull(k) => {
                if x < 0.0 {
                    0.0
                } else {
                    k * x.powf(k - 1.0) * (-x.powf(k)).exp()
                }
            }
        }
    }

    /// `P(X <= x)`.
    pub(super) fn cdf(self, x: f64) -> f64 {
        match self {
            Shape::Beta(a, b) => beta_reg(a, b, x.clamp(0.0, 1.0)),
            Shape::Gamma(k) => gamma_pq(k, x).0,
            Shape::Weibull(k) => {
                if x <= 0.0 {
                    0.0
                } else {
                    -(-x.powf(k)).exp_m1()
                }
            }
        }
    }

    /// `P(X > x)`, accurate in the upper tail.
    pub(super) fn sf(self, x: f64) -> f64 {
        match self {
            Shape::Beta(a, b) => beta_reg(b, a, 1.0 - x.clamp(0.0, 1.0)),
            Shape::Gamma(k) => gamma_pq(k, x).1,
            Shape::Weibull(k) => {
                if x <= 0.0 {
                    1.0
                } else {
                    (-x.powf(k)).exp()
                }
            }
        }
    }

    /// The `x` with `F(x) = p` (solved from the lower tail when `lower`) or `S(x) = q`
    /// (otherwise); `p + q = 1`, each given accurately.
    pub(super) fn quantile(self, p: f64, q: f64, lower: bool) -> f64 {
        let (lo, hi) = self.support();
        if p <= 0.0 {
            return lo;
        }
        if q <= 0.0 {
            return hi;
        }
        match self {
            Shape::Weibull(k) => {
                let h = if lower { -(-p).ln_1p() } else { -q.ln() };
                h.powf(1.0 / k)
            }
            Shape::Beta(..) => solve_increasing(self, p, q, lower, 0.0, 1.0),
            Shape::Gamma(k) => {
                let mut b = k + 10.0 * k.sqrt() + 10.0;
                while self.sf(b) > q.min(0.5) {
                    b *= 2.0;
                }
                solve_increasing(self, p, q, lower, 0.0, b)
            }
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
    if x.is_infinite() {
        return (1.0, 0.0);
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
fn solve_increasing(m: Shape, p: f64, q: f64, lower: bool, a: f64, b: f64) -> f64 {
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
