//! The maps between an input and the standard spaces designs are built in ([`Germ`]):
//! the isoprobabilistic map from the standard normal, the quantile from the unit interval,
//! the affine map from the input's Askey germ, and their inverses.

use super::truncated::clamp_to;
use super::{Distribution, Germ};
use crate::uq::special::{norm_cdf, norm_isf, norm_ppf, norm_sf};

impl Distribution {
    /// Isoprobabilistic map from the standard-normal germ `z` to this
    /// distribution, `F^{-1}(Phi(z))`, as used by stochastic collocation.
    ///
    /// Normal: `mean + std z`; log-normal: `exp(mu + sigma z)` (both exact);
    /// others through the quantile with `Phi(z)` and `1 - Phi(z) = Phi(-z)`
    /// both computed in relative precision, so nodes far in either tail map
    /// to distinct points inside the support.
    pub fn from_standard_normal(&self, z: f64) -> f64 {
        if z.is_nan() {
            return f64::NAN;
        }
        match *self {
            Distribution::Normal { mean, std } => mean + std * z,
            Distribution::LogNormal { mu, sigma } => (mu + sigma * z).exp(),
            _ => self.quantile(norm_cdf(z), norm_sf(z)),
        }
    }

    /// The affine map `x = offset + scale · t` from this input's germ in the Askey scheme,
    /// as `(offset, scale)`, or `None` when the scheme has no family for it:
    ///
    /// | input | germ `t` | family |
    /// | --- | --- | --- |
    /// | normal | N(0, 1) | Hermite |
    /// | uniform on `[low, high]` | U(-1, 1) | Legendre |
    /// | Beta(alpha, beta) on `[low, high]` | Beta(alpha, beta) on `[-1, 1]` | Jacobi |
    /// | Gamma(shape, scale) | Gamma(shape, 1) | Laguerre |
    ///
    /// (see `crate::uq::pce::askey::Family::of`, which names the family).
    pub fn askey_affine(&self) -> Option<(f64, f64)> {
        match *self {
            Distribution::Normal { mean, std } => Some((mean, std)),
            Distribution::Uniform { low, high } | Distribution::Beta { low, high, .. } => {
                Some((0.5 * (low + high), 0.5 * (high - low)))
            }
            Distribution::Gamma { scale, .. } => Some((0.0, scale)),
            _ => None,
        }
    }

    /// The value of this input at the germ coordinate `x` of a design built in the
    /// standard space `germ`: `F^{-1}(Phi(x))` (normal), `F^{-1}(x)` (uniform), the affine
    /// Askey map or, without an Askey family, the normal map (Askey).
    pub fn from_germ(&self, germ: Germ, x: f64) -> f64 {
        match germ {
            Germ::Normal => self.from_standard_normal(x),
            Germ::Uniform => self.inverse_cdf(x),
            Germ::Askey => match self.askey_affine() {
                Some((offset, scale)) => offset + scale * x,
                None => self.from_standard_normal(x),
            },
        }
    }

    /// The germ coordinate of `value` in the standard space `germ`, the inverse of
    /// [`Distribution::from_germ`]; tails keep their relative precision. For the integer
    /// uniform, the centre of the value's cell (`(k + 1/2) / n` on the unit interval).
    pub fn to_germ(&self, germ: Germ, value: f64) -> f64 {
        if let Distribution::IntegerUniform { low, high } = *self {
            let n = Distribution::count(low, high);
            let k = clamp_to(value.round() - low as f64, 0.0, n - 1.0);
            let u = (k + 0.5) / n;
            return match germ {
                Germ::Uniform => u,
                Germ::Normal | Germ::Askey => norm_ppf(u),
            };
        }
        match (germ, self) {
            (Germ::Uniform, _) => self.cdf(value),
            (Germ::Askey, d) if d.askey_affine().is_some() => {
                let (offset, scale) = d.askey_affine().expect("checked");
                (value - offset) / scale
            }
            (_, &Distribution::Normal { mean, std }) => (value - mean) / std,
            (_, &Distribution::LogNormal { mu, sigma }) => (value.ln() - mu) / sigma,
            _ => {
                let u = self.cdf(value);
                if u <= 0.5 {
                    norm_ppf(u)
                } else {
                    norm_isf(self.sf(value))
                }
            }
        }
    }

    /// The standard-normal score `Phi^{-1}(F(x))` of the input at germ coordinate `t` of
    /// `germ` (`t` itself where the germ is already the standard normal): the coordinate a
    /// Gaussian copula correlates.
    pub fn normal_score(&self, germ: Germ, t: f64) -> f64 {
        match germ {
            Germ::Normal => t,
            Germ::Askey if self.askey_affine().is_none() || self.is_gaussian() => t,
            Germ::Uniform => {
                if t <= 0.5 {
                    norm_ppf(t)
                } else {
                    norm_isf(1.0 - t)
                }
            }
            Germ::Askey => self.to_germ(Germ::Normal, self.from_germ(germ, t)),
        }
    }
}
