//! The paper's single-degree-of-freedom wheel (§3): a mass on a spring and a damper released
//! from an initial displacement.
//!
//! ```text
//! m q'' + C q' + K q = 0,   q(0) = q0,   q'(0) = v0
//! ```
//!
//! The variables (parameters m, K, C, q0, v0, h; outputs q, v, a), their value references,
//! units and defaults are declared once, in the `variables!` table below ([`TABLE`]).
//!
//! K and C are tunable: a change between communication steps acts from the next step on.
//! K <= 0 (an unstable or neutral spring, which a Gaussian stiffness reaches far in its tail) is
//! accepted with a warning: the integrator handles it. m <= 0, C < 0, and non-finite values are
//! refused.
#![forbid(unsafe_code)]

use super::table::{finite, non_negative, positive, table_accessors, variables};
use super::{InitContext, Model, ModelError, ModelInfo, SetResult, StateReader, StateWriter};
use crate::solver::{rk4_step, substeps};

/// K may be zero or negative (a Gaussian stiffness reaches it far in its tail): accepted with
/// a warning, the integrator handles it.
fn stiffness(name: &'static str, value: f64) -> SetResult {
    finite(name, value)?;
    Ok((value <= 0.0)
        .then(|| format!("K = {value} N/m is not positive: the wheel is unstable or neutral")))
}

variables! {
    static TABLE: [Wheel as w];
    real_parameter("m", VR_M = 0, Some("kg"), w.m, 10.0, Fixed, positive, "Mass"),
    real_parameter("K", VR_K = 1, Some("N/m"), w.k, 100.0, Tunable, stiffness, "Stiffness"),
    real_parameter("C", VR_C = 2, Some("N.s/m"), w.c, 20.0, Tunable, non_negative, "Damping coefficient"),
    real_parameter("q0", VR_Q0 = 3, Some("m"), w.q0, 0.1, Fixed, finite, "Initial displacement q(0)"),
    real_parameter("v0", VR_V0 = 4, Some("m/s"), w.v0, 0.0, Fixed, finite, "Initial velocity q'(0)"),
    real_parameter("h", VR_H = 5, Some("s"), w.h, 1e-3, Fixed, positive, "Largest internal RK4 step; each communication step is split into equal substeps no longer than h"),
    output("q", VR_Q = 10, Some("m"), w.y[0], "Displacement q"),
    output("v", VR_V = 11, Some("m/s"), w.y[1], "Velocity q'"),
    output("a", VR_A = 12, Some("m/s2"), w.acceleration(w.y[0], w.y[1]), "Acceleration q''"),
}

/// Static description of the wheel model.
pub static INFO: ModelInfo = ModelInfo {
    name: "Wheel",
    description: "Single-DOF wheel: m q'' + C q' + K q = 0 (railuq, paper section 3)",
    variables: &VARIABLES,
    default_start: 0.0,
    default_stop: 5.0,
    default_step: 0.01,
    documentation_html: r#"<p>A mass <i>m</i> on a spring <i>K</i> and a viscous damper <i>C</i>, released from
<i>q</i>(0) = q0 with <i>q'</i>(0) = v0:</p>
<pre>m q'' + C q' + K q = 0</pre>
<p>Defaults (paper): m = 10 kg, K = 100 N/m, C = 20 N&middot;s/m, q0 = 0.1 m, giving
&zeta; = C / (2&radic;(K m)) = 0.316, &omega;<sub>d</sub> = 3 rad/s and
q(t) = 0.1 e<sup>&minus;t</sup>(cos 3t + sin(3t)/3).</p>
<p>Integration: classical Runge&ndash;Kutta (RK4) with equal substeps no longer than the
parameter <code>h</code> (default 1 ms; error below 1e-9 q0 over 0&ndash;5 s). A communication
step that would need more than 10<sup>7</sup> substeps is refused with an error.
K and C are tunable: a change between communication steps acts from the next step on.
K &le; 0 is accepted with a warning; m &le; 0, C &lt; 0 and non-finite values are refused.</p>"#,
};

/// The wheel model: parameters and state.
#[derive(Clone, Debug)]
pub struct Wheel {
    /// Mass (kg).
    pub m: f64,
    /// Stiffness (N/m).
    pub k: f64,
    /// Damping (N·s/m).
    pub c: f64,
    /// Initial displacement (m).
    pub q0: f64,
    /// Initial velocity (m/s).
    pub v0: f64,
    /// Largest internal step (s).
    pub h: f64,
    /// State: displacement (m) and velocity (m/s).
    pub y: [f64; 2],
}

impl Default for Wheel {
    fn default() -> Self {
        let mut w = Wheel {
            m: 0.0,
            k: 0.0,
            c: 0.0,
            q0: 0.0,
            v0: 0.0,
            h: 0.0,
            y: [0.0; 2],
        };
        TABLE.apply_defaults(&mut w);
        w.y = [w.q0, w.v0];
        w
    }
}

impl Wheel {
    /// A boxed wheel with default parameters.
    pub fn boxed() -> Box<dyn Model> {
        Box::new(Wheel::default())
    }

    /// Acceleration q'' (m/s²) at displacement `q` and velocity `v`.
    pub fn acceleration(&self, q: f64, v: f64) -> f64 {
        -(self.c * v + self.k * q) / self.m
    }
}

impl Model for Wheel {
    fn info(&self) -> &'static ModelInfo {
        &INFO
    }

    table_accessors!(TABLE; get_real -> f64, set_real(f64));

    fn initialize(&mut self, _ctx: &InitContext) -> Result<(), ModelError> {
        self.y = [self.q0, self.v0];
        Ok(())
    }

    fn do_step(&mut self, t: f64, h: f64) -> Result<(), ModelError> {
        let n = substeps(h, self.h)?;
        let dt = h / n as f64;
        let (m, k, c) = (self.m, self.k, self.c);
        for i in 0..n {
            rk4_step(
                |_, y: &[f64; 2]| [y[1], -(c * y[1] + k * y[0]) / m],
                t + i as f64 * dt,
                &mut self.y,
                dt,
            );
        }
        if self.y.iter().all(|x| x.is_finite()) {
            Ok(())
        } else {
            Err(ModelError::SolverFailure {
                time: t + h,
                reason: format!(
                    "state became non-finite (q = {}, v = {})",
                    self.y[0], self.y[1]
                ),
            })
        }
    }

    fn save(&self, out: &mut StateWriter) {
        TABLE.save_parameters(self, out);
        out.f64s(&self.y);
    }

    fn restore(&mut self, input: &mut StateReader<'_>) -> Result<(), ModelError> {
        let mut w = Wheel::default();
        TABLE.restore_parameters(&mut w, input)?;
        let y = input.f64s(Some(2))?;
        w.y = [y[0], y[1]];
        *self = w;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Closed-form free response of m q'' + c q' + k q = 0, q(0) = q0, q'(0) = 0, written
    /// independently of the model for every regime: underdamped, critically damped,
    /// overdamped, neutral (k = 0) and unstable (k < 0).
    fn closed_form(m: f64, k: f64, c: f64, q0: f64, t: f64) -> f64 {
        // Characteristic polynomial m s^2 + c s + k = 0.
        let a = -c / (2.0 * m);
        let disc = a * a - k / m;
        if disc < -1e-14 {
            let wd = (-disc).sqrt();
            q0 * (a * t).exp() * ((wd * t).cos() - a / wd * (wd * t).sin())
        } else if disc > 1e-14 {
            let r = disc.sqrt();
            let (s1, s2) = (a + r, a - r);
            // q = A e^{s1 t} + B e^{s2 t}, A + B = q0, s1 A + s2 B = 0.
            let amp = -s2 * q0 / (s1 - s2);
            let bmp = s1 * q0 / (s1 - s2);
            amp * (s1 * t).exp() + bmp * (s2 * t).exp()
        } else {
            q0 * (a * t).exp() * (1.0 - a * t)
        }
    }

    fn simulate(k: f64, c: f64, h_comm: f64, stop: f64) -> Vec<(f64, f64)> {
        let mut w = Wheel::default();
        w.set_real(VR_K, k).unwrap();
        w.set_real(VR_C, c).unwrap();
        w.initialize(&InitContext::default()).unwrap();
        let n = (stop / h_comm).round() as usize;
        let mut out = vec![(0.0, w.y[0])];
        for i in 0..n {
            let t = i as f64 * h_comm;
            w.do_step(t, h_comm).unwrap();
            out.push(((i + 1) as f64 * h_comm, w.y[0]));
        }
        out
    }

    fn max_err(k: f64, c: f64) -> f64 {
        simulate(k, c, 0.01, 5.0)
            .iter()
            .map(|&(t, q)| (q - closed_form(10.0, k, c, 0.1, t)).abs() / 0.1)
            .fold(0.0, f64::max)
    }

    #[test]
    fn nominal_matches_closed_form_within_1e_9() {
        // Paper's nominal case: q = 0.1 e^{-t}(cos 3t + sin(3t)/3).
        let e = max_err(100.0, 20.0);
        assert!(e < 1e-9, "max relative error {e:e}");
        let q1 = 0.1 * (-1.0f64).exp() * (3.0f64.cos() + 3.0f64.sin() / 3.0);
        let traj = simulate(100.0, 20.0, 0.01, 1.0);
        assert!((traj.last().unwrap().1 - q1).abs() < 1e-10);
    }

    #[test]
    fn overdamped_critical_neutral_and_unstable_regimes() {
        assert!(max_err(100.0, 80.0) < 1e-9, "overdamped zeta = 1.26");
        assert!(max_err(10.0, 20.0) < 1e-9, "critically damped zeta = 1");
        assert!(max_err(0.0, 20.0) < 1e-9, "neutral spring");
        // Unstable spring: the solution grows like e^{2.3 t}; compare relative to its size.
        let traj = simulate(-50.0, 20.0, 0.01, 5.0);
        for (t, q) in traj {
            let r = closed_form(10.0, -50.0, 20.0, 0.1, t);
            assert!(
                (q - r).abs() <= 1e-9 * r.abs().max(0.1),
                "t={t}: {q} vs {r}"
            );
        }
    }

    #[test]
    fn refuses_bad_parameters() {
        let mut w = Wheel::default();
        assert!(w.set_real(VR_M, 0.0).is_err());
        assert!(w.set_real(VR_M, -1.0).is_err());
        assert!(w.set_real(VR_K, f64::NAN).is_err());
        assert!(w.set_real(VR_C, -1.0).is_err());
        assert!(w.set_real(VR_H, f64::INFINITY).is_err());
        assert!(w.set_real(VR_K, -1.0).unwrap().is_some(), "K < 0 warns");
        assert!(w.set_real(VR_Q, 1.0).is_err(), "outputs are not settable");
    }

    #[test]
    fn divergence_is_an_error_not_a_nan() {
        let mut w = Wheel::default();
        w.set_real(VR_K, -1e6).unwrap();
        w.set_real(VR_M, 1e-3).unwrap();
        w.initialize(&InitContext::default()).unwrap();
        let mut t = 0.0;
        let mut failed = false;
        for _ in 0..10_000 {
            if w.do_step(t, 0.01).is_err() {
                failed = true;
                break;
            }
            t += 0.01;
        }
        assert!(failed);
    }

    #[test]
    fn an_absurd_step_is_refused_with_an_error_not_a_hang() {
        // fmi2DoStep with h = 1e300 (or 1e6) used to overflow the substep count and never return.
        let mut w = Wheel::default();
        w.initialize(&InitContext::default()).unwrap();
        for h in [1e300, 1e6, f64::MAX] {
            let e = w.do_step(0.0, h).unwrap_err();
            assert!(matches!(e, ModelError::StepTooLong(_)), "{e}");
        }
        assert_eq!(w.y, [0.1, 0.0], "a refused step leaves the state");
        w.do_step(0.0, 0.01).unwrap();
    }

    #[test]
    fn save_restore_round_trip() {
        let mut w = Wheel::default();
        w.initialize(&InitContext::default()).unwrap();
        w.do_step(0.0, 0.3).unwrap();
        let mut out = StateWriter::default();
        w.save(&mut out);
        let mut w2 = Wheel::default();
        w2.restore(&mut StateReader::new(&out.bytes)).unwrap();
        assert_eq!(w.y, w2.y);
        assert!(w2.restore(&mut StateReader::new(&out.bytes[..20])).is_err());
    }
}
