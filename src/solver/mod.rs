//! Fixed-step integrators shared by the models.
#![deny(unsafe_code)]

pub mod simd;
pub mod zhai;

/// Largest number of internal substeps one communication step may take. A step that would
/// need more is refused before any work is done (an absurd step such as 1e300 s would
/// otherwise run for ever): split it into shorter communication steps. 10⁷ substeps take
/// about 0.2 s for the Wheel (h = 1 ms: steps up to 10⁴ s) and about a minute for
/// VehicleTrack (dt = 0.1 ms: steps up to 1 000 s).
pub const MAX_SUBSTEPS: usize = 10_000_000;

/// A step that needs more than [`MAX_SUBSTEPS`] substeps (or a step that is not a number).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error(
    "a step of {} s needs {needed:.3e} internal substeps of at most {} s, more than the \
     {MAX_SUBSTEPS} allowed per step: use shorter communication steps",
    readable(*span),
    readable(*h_max)
)]
pub struct TooManySubsteps {
    /// The step (s).
    pub span: f64,
    /// The largest substep (s).
    pub h_max: f64,
    /// Substeps it would need.
    pub needed: f64,
}

/// `x` as Rust prints it when that is short (0.001, 250), else in exponent form (1e-300, not
/// 300 zeros).
fn readable(x: f64) -> String {
    let plain = x.to_string();
    if plain.len() <= 12 {
        plain
    } else {
        format!("{x:e}")
    }
}

/// Number of equal substeps of length <= `h_max` that cover `span` (at least 1), or an error
/// when that number exceeds [`MAX_SUBSTEPS`] or is not a number.
///
/// A communication step of 0.010000000000000009 s with `h_max` = 1e-3 s gives 10 substeps,
/// not 11: the ratio is rounded up only beyond a relative tolerance of 1e-9.
pub fn substeps(span: f64, h_max: f64) -> Result<usize, TooManySubsteps> {
    let r = span / h_max;
    let n = (r - 1e-9 * r.max(1.0)).ceil();
    if n.is_nan() || n > MAX_SUBSTEPS as f64 {
        return Err(TooManySubsteps {
            span,
            h_max,
            needed: n,
        });
    }
    Ok(if n >= 1.0 { n as usize } else { 1 })
}

/// One classical Runge–Kutta (RK4) step of y' = f(t, y) from `t` with step `h`, in place.
pub fn rk4_step<const N: usize>(
    f: impl Fn(f64, &[f64; N]) -> [f64; N],
    t: f64,
    y: &mut [f64; N],
    h: f64,
) {
    let k1 = f(t, y);
    let y2 = add_scaled(y, &k1, h / 2.0);
    let k2 = f(t + h / 2.0, &y2);
    let y3 = add_scaled(y, &k2, h / 2.0);
    let k3 = f(t + h / 2.0, &y3);
    let y4 = add_scaled(y, &k3, h);
    let k4 = f(t + h, &y4);
    for i in 0..N {
        y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
    }
}

fn add_scaled<const N: usize>(y: &[f64; N], k: &[f64; N], s: f64) -> [f64; N] {
    let mut out = *y;
    for i in 0..N {
        out[i] += s * k[i];
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_tiny_substep_is_written_in_exponent_form_not_with_300_zeros() {
        // H = 1e-300 gave a 452-character message.
        let e = substeps(0.01, 1e-300).unwrap_err().to_string();
        assert!(e.len() < 200, "{e}");
        assert!(e.contains("of at most 1e-300 s"), "{e}");
        let e = substeps(1e300, 1e-3).unwrap_err().to_string();
        assert!(
            e.starts_with("a step of 1e300 s needs") && e.contains("at most 0.001 s"),
            "{e}"
        );
    }

    #[test]
    fn substeps_tolerates_importer_rounding() {
        assert_eq!(substeps(0.010000000000000009, 1e-3), Ok(10));
        assert_eq!(substeps(0.01, 1e-3), Ok(10));
        assert_eq!(substeps(0.0105, 1e-3), Ok(11));
        assert_eq!(substeps(1e-4, 1e-3), Ok(1));
        assert_eq!(substeps(0.0, 1e-3), Ok(1));
    }

    #[test]
    fn an_absurd_step_is_refused_not_counted_into_an_overflow() {
        // h = 1e300 (and 1e6) used to give usize::MAX substeps: a loop that never ended.
        for span in [1e300, 1e6, f64::MAX, f64::INFINITY, f64::NAN] {
            let e = substeps(span, 1e-4).unwrap_err();
            assert!(
                e.to_string().contains("use shorter communication steps"),
                "{e}"
            );
        }
        let limit = MAX_SUBSTEPS as f64 * 1e-4;
        assert_eq!(substeps(limit, 1e-4), Ok(MAX_SUBSTEPS));
        assert!(substeps(limit * (1.0 + 1e-6), 1e-4).is_err());
    }

    #[test]
    fn rk4_is_fourth_order_on_exponential_decay() {
        // y' = -y, y(0) = 1: error at t = 1 must fall by ~16 when h halves.
        let err = |n: usize| {
            let h = 1.0 / n as f64;
            let mut y = [1.0];
            for i in 0..n {
                rk4_step(|_, y| [-y[0]], i as f64 * h, &mut y, h);
            }
            (y[0] - (-1.0f64).exp()).abs()
        };
        let ratio = err(20) / err(40);
        assert!((ratio - 16.0).abs() < 1.0, "ratio {ratio}");
    }
}
