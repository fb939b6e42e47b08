//! Zhai's explicit two-step integration method ("new fast explicit integration", Zhai 1996,
//! *Int. J. Numer. Meth. Engng* 39, 4199–4214) for `M x'' = F(x, x')` with a diagonal (or
//! otherwise cheaply inverted) mass matrix:
//!
//! ```text
//! x_{n+1} = x_n + v_n h + (1/2 + ψ) a_n h² − ψ a_{n−1} h²
//! v_{n+1} = v_n + (1 + φ) a_n h − φ a_{n−1} h
//! a_{n+1} = M⁻¹ F(x_{n+1}, v_{n+1})
//! ```
//!
//! with ψ = φ = 1/2 (second order), and ψ = φ = 0 on a start step (no `a_{n−1}` yet).
//!
//! A step `h` after a step of another length `h'` uses the variable-step form: the
//! difference `a_n − a_{n−1}` stands for `ȧ h'`, so it is scaled by `r = h / h'`:
//!
//! ```text
//! x_{n+1} = x_n + v_n h + a_n h²/2 + ψ r (a_n − a_{n−1}) h²
//! v_{n+1} = v_n + a_n h + φ r (a_n − a_{n−1}) h        (the variable-step Adams–Bashforth 2)
//! ```
//!
//! which is the formula above when `r = 1`. Only when the step more than doubles
//! (`r > 2`, e.g. after a short last substep) is it a start step again. Restarting at every
//! change of length instead (as this module did before) is the one-step formula, which
//! gains energy: an importer that varies its communication step by 1 % from step to step made
//! the vehicle–track model blow up within 0.03 s.
//! The caller supplies the accelerations `M⁻¹F` as a closure writing into a slice, so the
//! integrator is generic over the state dimension and never allocates while stepping.
#![forbid(unsafe_code)]

/// ψ = φ of the regular step.
pub const PSI: f64 = 0.5;

/// State of Zhai's method: positions, velocities, current and previous accelerations.
#[derive(Clone, Debug, Default)]
pub struct Zhai {
    /// Positions x_n.
    pub x: Vec<f64>,
    /// Velocities v_n.
    pub v: Vec<f64>,
    /// Accelerations a_n = M⁻¹F(x_n, v_n).
    pub a: Vec<f64>,
    /// Accelerations a_{n−1} (meaningful once [`Zhai::started`] is true).
    pub a_prev: Vec<f64>,
    /// Whether `a_prev` belongs to a previous step of length [`Zhai::last_h`].
    pub started: bool,
    /// Length of the previous step (s).
    pub last_h: f64,
}

impl Zhai {
    /// A zero state of dimension `dim`.
    pub fn new(dim: usize) -> Self {
        Self {
            x: vec![0.0; dim],
            v: vec![0.0; dim],
            a: vec![0.0; dim],
            a_prev: vec![0.0; dim],
            started: false,
            last_h: 0.0,
        }
    }

    /// Dimension of the state.
    pub fn dim(&self) -> usize {
        self.x.len()
    }

    /// Makes the next step a start step (ψ = φ = 0).
    pub fn restart(&mut self) {
        self.started = false;
    }

    /// Computes `a = M⁻¹F(x, v)` for the current state (call once after setting x and v).
    pub fn init_accel<E>(
        &mut self,
        mut accel: impl FnMut(&[f64], &[f64], &mut [f64]) -> Result<(), E>,
    ) -> Result<(), E> {
        accel(&self.x, &self.v, &mut self.a)
    }

    /// One step of length `h` (s). `accel(x, v, a)` writes `M⁻¹F(x, v)` into `a`.
    #[inline(always)]
    pub fn step<E>(
        &mut self,
        h: f64,
        mut accel: impl FnMut(&[f64], &[f64], &mut [f64]) -> Result<(), E>,
    ) -> Result<(), E> {
        self.predict(h);
        accel(&self.x, &self.v, &mut self.a)?;
        self.commit(h);
        Ok(())
    }

    /// First half of [`Zhai::step`]: advances x and v by `h` (s) and moves a to a_prev; the
    /// caller then writes `M⁻¹F(x, v)` into `a` and calls [`Zhai::commit`].
    #[inline(always)]
    pub fn predict(&mut self, h: f64) {
        let same_h = self.started && (h - self.last_h).abs() <= 1e-12 * h.abs();
        let h2 = h * h;
        let state = self.x.iter_mut().zip(self.v.iter_mut());
        let accel = self.a.iter().zip(&self.a_prev);
        let r = h / self.last_h;
        if same_h {
            for ((x, v), (&a, &ap)) in state.zip(accel) {
                *x += *v * h + (0.5 + PSI) * a * h2 - PSI * ap * h2;
                *v += (1.0 + PSI) * a * h - PSI * ap * h;
            }
        } else if self.started && r <= 2.0 {
            // ψ = φ: one scaled coefficient for both.
            let c = PSI * r;
            for ((x, v), (&a, &ap)) in state.zip(accel) {
                let da = a - ap;
                *x += *v * h + 0.5 * a * h2 + c * da * h2;
                *v += a * h + c * da * h;
            }
        } else {
            for ((x, v), (&a, _)) in state.zip(accel) {
                *x += *v * h + 0.5 * a * h2;
                *v += a * h;
            }
        }
        std::mem::swap(&mut self.a, &mut self.a_prev);
    }

    /// Second half of [`Zhai::step`], after the new accelerations are in `a`.
    #[inline(always)]
    pub fn commit(&mut self, h: f64) {
        self.started = true;
        self.last_h = h;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::convert::Infallible;

    /// Accelerations of a model as a function pointer.
    type Accel = fn(&[f64], &[f64], &mut [f64]) -> Result<(), Infallible>;

    /// x'' = −x.
    fn unit(x: &[f64], _: &[f64], a: &mut [f64]) -> Result<(), Infallible> {
        a[0] = -x[0];
        Ok(())
    }

    /// The state x(0) = 1, x'(0) = 0 of [`unit`], with its acceleration, and the model.
    fn unit_oscillator() -> (Zhai, Accel) {
        let mut z = Zhai::new(1);
        z.x[0] = 1.0;
        z.init_accel(unit).unwrap();
        (z, unit)
    }

    /// Damped oscillator x'' = −ω² x − 2ζω x', x(0) = 1, x'(0) = 0, integrated by `steps`
    /// (s; to t = 1): the error of x against the exact solution.
    fn damped_error(zeta: f64, steps: impl IntoIterator<Item = f64>) -> f64 {
        let w = 2.0 * std::f64::consts::PI * 1.5;
        let f = |x: &[f64], v: &[f64], a: &mut [f64]| -> Result<(), Infallible> {
            a[0] = -w * w * x[0] - 2.0 * zeta * w * v[0];
            Ok(())
        };
        let mut z = Zhai::new(1);
        z.x[0] = 1.0;
        z.init_accel(f).unwrap();
        for h in steps {
            z.step(h, f).unwrap();
        }
        let wd = w * (1.0 - zeta * zeta).sqrt();
        let exact = (-zeta * w).exp() * (wd.cos() + zeta * w / wd * wd.sin());
        (z.x[0] - exact).abs()
    }

    /// [`damped_error`] with `n` equal steps.
    fn error(n: usize, zeta: f64) -> f64 {
        damped_error(zeta, std::iter::repeat_n(1.0 / n as f64, n))
    }

    #[test]
    fn second_order_convergence_undamped_and_damped() {
        // Damped: second order (ratio 4 when h halves). Undamped: the phase error is
        // even smaller (ratio 16), so at least second order in both cases.
        let ratio = error(2000, 0.05) / error(4000, 0.05);
        assert!((ratio - 4.0).abs() < 0.3, "damped: ratio {ratio}");
        let ratio = error(2000, 0.0) / error(4000, 0.0);
        assert!(ratio > 3.7, "undamped: ratio {ratio}");
        assert!(error(4000, 0.05) < 1e-6 && error(4000, 0.0) < 1e-10);
    }

    /// Growth of an undamped oscillator over many steps at Ω = ωh.
    fn growth(omega_h: f64) -> f64 {
        let (mut z, f) = unit_oscillator();
        let mut peak: f64 = 0.0;
        for _ in 0..20_000 {
            z.step(omega_h, f).unwrap();
            peak = peak.max(z.x[0].abs());
        }
        peak
    }

    #[test]
    fn stable_below_and_unstable_above_the_critical_step() {
        // Undamped, ψ = φ = 1/2 is stable up to ωh = 2 (like the central difference);
        // the vehicle–track model runs its stiffest mode at ωh ≈ 0.5 by default.
        for oh in [0.5, 1.0, 1.5, 1.95] {
            assert!(growth(oh) < 1.0 + 1e-6, "stable at {oh}");
        }
        assert!(growth(2.05) > 1e6, "unstable at 2.05");
    }

    #[test]
    fn a_step_more_than_twice_the_last_restarts_with_the_one_step_formula() {
        let (mut z, f) = unit_oscillator();
        z.step(0.01, f).unwrap();
        let (x1, v1) = (z.x[0], z.v[0]);
        z.step(0.05, f).unwrap();
        // r = 5: restarted, x = x1 + v1·0.05 + 0.5·(−x1)·0.05², not the two-step formula.
        let expected = x1 + v1 * 0.05 - 0.5 * x1 * 0.0025;
        assert!((z.x[0] - expected).abs() < 1e-15, "{}", z.x[0]);
        assert_eq!(z.last_h, 0.05);
    }

    #[test]
    fn a_shorter_step_uses_the_variable_step_formula() {
        let (mut z, f) = unit_oscillator();
        z.step(0.1, f).unwrap();
        let (x1, v1, a0, a1) = (z.x[0], z.v[0], -1.0, -z.x[0]);
        z.step(0.05, f).unwrap();
        // r = 1/2: the difference a1 − a0 over 0.1 s scaled to 0.05 s.
        let (h, r) = (0.05, 0.5);
        let x = x1 + v1 * h + 0.5 * a1 * h * h + 0.5 * r * (a1 - a0) * h * h;
        let v = v1 + a1 * h + 0.5 * r * (a1 - a0) * h;
        assert!((z.x[0] - x).abs() < 1e-15 && (z.v[0] - v).abs() < 1e-15);
    }

    /// Undamped x'' = −x with 20 000 steps alternating between `ωh` and `ωh·q`: the largest
    /// |x| (1 when the energy is kept).
    fn alternating_peak(omega_h: f64, q: f64) -> f64 {
        let (mut z, f) = unit_oscillator();
        let mut peak: f64 = 0.0;
        for k in 0..20_000 {
            let h = if k % 2 == 0 { omega_h } else { omega_h * q };
            z.step(h, f).unwrap();
            peak = peak.max(z.x[0].abs());
        }
        peak
    }

    #[test]
    fn steps_that_change_length_every_step_stay_stable() {
        // The vehicle–track model (stiffest mode at ωh ≈ 0.5) blew up when an importer
        // alternated communication steps of 1e-4 and 0.99e-4 s: each change restarted the
        // method with the one-step formula, which gains energy.
        for q in [0.99, 0.9, 0.5] {
            for oh in [0.25, 0.5, 1.0] {
                let peak = alternating_peak(oh, q);
                assert!(peak < 1.0 + 1e-3, "ωh = {oh}, q = {q}: peak {peak}");
            }
        }
    }

    #[test]
    fn alternating_steps_converge_at_second_order() {
        // Damped oscillator to t = 1 with steps h, 0.7h, h, 0.7h ...: halving h quarters the
        // error, as with constant steps.
        let err = |h: f64| {
            let mut steps = Vec::new();
            let (mut t, mut k) = (0.0, 0);
            while t < 1.0 - 1e-12 {
                let step = (if k % 2 == 0 { h } else { 0.7 * h }).min(1.0 - t);
                steps.push(step);
                t += step;
                k += 1;
            }
            damped_error(0.05, steps)
        };
        let ratio = err(1.0 / 1700.0) / err(1.0 / 3400.0);
        assert!((ratio - 4.0).abs() < 0.5, "ratio {ratio}");
    }
}
