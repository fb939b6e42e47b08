//! Finite-difference gradients in standard normal space (FORM's search directions).

use serde::{Deserialize, Serialize};

use super::error::ReliabilityError;

/// A finite-difference scheme.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Scheme {
    /// `dg/du_i = (g(u + h_i e_i) - g(u)) / h_i`: `d` runs besides `g(u)`, error `O(h)`.
    #[default]
    Forward,
    /// `dg/du_i = (g(u + h_i e_i) - g(u - h_i e_i)) / (2 h_i)`: `2d` runs, error `O(h^2)`.
    Central,
}

/// The finite differences of a gradient: scheme and step
/// `h_i = max(absolute, relative |u_i|)` (standard normal units).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Differences {
    /// Forward or central.
    pub scheme: Scheme,
    /// Step relative to `|u_i|`.
    pub relative: f64,
    /// Smallest step. A model with numerical noise of relative size `eps` (a simulation's
    /// solver tolerance) needs `h` well above `eps`: the gradient's noise is about
    /// `eps |g| / h`.
    pub absolute: f64,
}

impl Default for Differences {
    /// Forward differences with `h = 1e-3` (and `1e-3 |u_i|` beyond `|u_i| = 1`).
    fn default() -> Self {
        Differences {
            scheme: Scheme::Forward,
            relative: 1e-3,
            absolute: 1e-3,
        }
    }
}

impl Differences {
    /// Checks the steps.
    pub(crate) fn validate(&self) -> Result<(), ReliabilityError> {
        let ok = |h: f64| h.is_finite() && h >= 0.0;
        if !ok(self.relative) || !ok(self.absolute) || !super::positive(self.absolute) {
            return Err(ReliabilityError::Invalid(format!(
                "finite-difference steps must be finite, `absolute` positive and `relative` \
                 non-negative (got absolute = {}, relative = {})",
                self.absolute, self.relative
            )));
        }
        Ok(())
    }

    /// Runs per gradient besides the centre: `d` (forward) or `2d` (central).
    pub(crate) fn runs(&self, d: usize) -> usize {
        match self.scheme {
            Scheme::Forward => d,
            Scheme::Central => 2 * d,
        }
    }

    fn step(&self, ui: f64) -> f64 {
        self.absolute.max(self.relative * ui.abs())
    }

    /// The points of the differences around `u` (not `u` itself): `u + h_i e_i` for each
    /// `i` (forward), or `u + h_i e_i, u - h_i e_i` for each `i` (central).
    pub(crate) fn points(&self, u: &[f64]) -> Vec<Vec<f64>> {
        let mut out = Vec::with_capacity(self.runs(u.len()));
        for i in 0..u.len() {
            let h = self.step(u[i]);
            let signs: &[f64] = match self.scheme {
                Scheme::Forward => &[1.0],
                Scheme::Central => &[1.0, -1.0],
            };
            for s in signs {
                let mut v = u.to_vec();
                v[i] += s * h;
                out.push(v);
            }
        }
        out
    }

    /// The gradient at `u` from `g(u) = g0` and the values at [`Differences::points`]
    /// (the actual steps `v_i - u_i` are used, exact in floating point).
    pub(crate) fn gradient(&self, u: &[f64], g0: f64, points: &[Vec<f64>], g: &[f64]) -> Vec<f64> {
        (0..u.len())
            .map(|i| match self.scheme {
                Scheme::Forward => (g[i] - g0) / (points[i][i] - u[i]),
                Scheme::Central => {
                    (g[2 * i] - g[2 * i + 1]) / (points[2 * i][i] - points[2 * i + 1][i])
                }
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn forward_and_central_gradients_of_a_quadratic() {
        let g = |u: &[f64]| 3.0 * u[0] - u[1] * u[1] + 0.5 * u[0] * u[1];
        let u = [0.7, -1.3];
        let exact = [3.0 + 0.5 * u[1], -2.0 * u[1] + 0.5 * u[0]];
        for (scheme, tol) in [(Scheme::Forward, 2e-3), (Scheme::Central, 1e-9)] {
            let fd = Differences {
                scheme,
                ..Differences::default()
            };
            let pts = fd.points(&u);
            assert_eq!(pts.len(), fd.runs(2));
            let values: Vec<f64> = pts.iter().map(|p| g(p)).collect();
            let grad = fd.gradient(&u, g(&u), &pts, &values);
            for (a, b) in grad.iter().zip(exact) {
                assert!((a - b).abs() < tol, "{scheme:?}: {grad:?} vs {exact:?}");
            }
        }
    }

    #[test]
    fn bad_steps_are_refused() {
        for (absolute, relative) in [(0.0, 0.1), (1e-3, -1.0), (f64::NAN, 0.0)] {
            let fd = Differences {
                scheme: Scheme::Forward,
                relative,
                absolute,
            };
            assert!(fd.validate().is_err());
        }
    }
}
