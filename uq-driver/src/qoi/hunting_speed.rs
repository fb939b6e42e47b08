//! Constant-speed critical speed by bisection: the lowest speed at which a given initial
//! disturbance keeps hunting, and the highest at which it dies out, found from runs at fixed
//! speeds (the quantity a bogie designer compares with), not read off a speed ramp.
//!
//! # Definition
//!
//! A run at speed v (a parameter of the FMU, e.g. the bogie's `V0` with `ramp = 0`) lasts
//! `duration` s from the study's start time. It **keeps hunting** when the largest |signal|
//! over its last `window` s (samples at t ≥ t_end − window, within 1e-9·window) is at or above
//! `threshold`; otherwise the disturbance has **died out** ([`keeps_hunting`]).
//!
//! Given a bracket [low, high] and a tolerance, [`bisect`] first runs `high`, then `low`:
//!
//! - dies out at `high`: [`HuntingSpeed::NeverHunts`] (the transition is above the bracket);
//! - keeps hunting at `low`: [`HuntingSpeed::AlwaysHunts`] (it is below the bracket);
//! - otherwise bisection of (decays, hunts) = (low, high) at the midpoint until
//!   hunts − decays ≤ tolerance: [`HuntingSpeed::Found`] with both ends. Every end is a speed
//!   actually run: the disturbance was seen to die out at `decays` and to keep hunting at
//!   `hunts`.
//!
//! That costs 2 + ⌈log2((high − low)/tolerance)⌉ runs per point.
//!
//! # Physics, and why `duration` matters
//!
//! Above the nonlinear critical speed a stable limit cycle (hunting) exists, and a large enough
//! disturbance settles on it and persists; below it every disturbance decays. The bisection
//! assumes one transition in the bracket (hunting at every speed above it, decay below), which
//! holds for a disturbance that reaches the limit cycle's basin (e.g. the bogie's Y0 = 12 mm;
//! a small disturbance finds the boundary of the basin instead, between the nonlinear and the
//! linear critical speed). Just below the fold of the limit cycles the decay is slow: the
//! motion lingers near the vanished cycle before it decays (measured on the bogie: 0.005 m/s
//! below the fold, |Y| stays above 0.1 mm for 90 s; 0.035 m/s below, 76 s; 0.8 m/s below, 51 s).
//! A run that ends before the decay is counted as hunting, so a short `duration` biases both
//! speeds downwards; choose it from a convergence check (see the README for the bogie's).

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::fmu::FixedValue;

/// Settings of a `hunting_speed` quantity (`[[qoi]] kind = "hunting_speed"`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HuntingSpeedSpec {
    /// Name in reports: the lowest speed that keeps hunting. The highest speed at which the
    /// disturbance dies out is reported as `<name>_decay`.
    pub name: String,
    /// The FMU parameter holding the (constant) speed, e.g. "V0" (a Real, settable before
    /// initialization, not a random parameter).
    pub speed_parameter: String,
    /// Further values set for these runs only, after `[fixed]` and the point's random values
    /// (e.g. `{ ramp = 0.0 }` for a constant speed); not random parameters.
    #[serde(default)]
    pub set: BTreeMap<String, FixedValue>,
    /// Lower end of the bracket (units of the speed parameter, e.g. m/s).
    pub low: f64,
    /// Upper end of the bracket.
    pub high: f64,
    /// Bisection stops when the two speeds are at most this far apart.
    pub tolerance: f64,
    /// Simulated time of each constant-speed run (s), from the study's start time.
    pub duration: f64,
    /// Communication step of these runs (s; default: the study's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub step: Option<f64>,
    /// Oscillating signal (e.g. "Y").
    pub signal: String,
    /// Length of the final stretch of each run that is checked (s).
    #[serde(default = "default_window")]
    pub window: f64,
    /// Amplitude threshold (units of the signal).
    #[serde(default = "default_threshold")]
    pub threshold: f64,
    /// Exceedance limits: P(q > limit) is reported for both speeds.
    #[serde(default)]
    pub limits: Vec<f64>,
    /// Limits below: P(q < limit) is reported for both speeds (e.g. the probability that
    /// the bogie hunts below a line speed).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub limits_below: Vec<f64>,
}

fn default_window() -> f64 {
    1.0
}
fn default_threshold() -> f64 {
    1e-4
}

impl HuntingSpeedSpec {
    /// Name of the second quantity: the highest speed at which the disturbance dies out.
    pub fn decay_name(&self) -> String {
        format!("{}_decay", self.name)
    }

    /// What is wrong with the settings, if anything.
    pub fn problem(&self) -> Option<String> {
        let finite = [self.low, self.high, self.tolerance, self.duration]
            .iter()
            .all(|x| x.is_finite());
        if !finite || self.low >= self.high {
            return Some(format!(
                "needs finite low < high (got low {}, high {})",
                self.low, self.high
            ));
        }
        let positive = |x: f64| x.is_finite() && x > 0.0;
        if !positive(self.tolerance) {
            return Some(format!("tolerance must be > 0, got {}", self.tolerance));
        }
        if !positive(self.window) || !positive(self.threshold) {
            return Some("window and threshold must be finite and > 0".into());
        }
        if self.duration < self.window {
            return Some(format!(
                "duration ({} s) must be at least the window ({} s)",
                self.duration, self.window
            ));
        }
        if let Some(s) = self.step {
            if !positive(s) || s > self.window {
                return Some(format!(
                    "step must be finite, > 0 and at most the window ({} s), got {s}",
                    self.window
                ));
            }
        }
        if let Some(k) = self.set.keys().find(|k| **k == self.speed_parameter) {
            return Some(format!(
                "`set` names the speed parameter '{k}', which the bisection sets"
            ));
        }
        if let Some((k, _)) = self.set.iter().find(|(_, v)| !v.is_finite()) {
            return Some(format!("`set` value of '{k}' is not finite"));
        }
        None
    }

    /// Constant-speed runs of one point when the transition is inside the bracket.
    pub fn runs_when_found(&self) -> usize {
        2 + bisection_steps(self.high - self.low, self.tolerance)
    }
}

/// Halvings of `width` until it is at most `tolerance`.
fn bisection_steps(width: f64, tolerance: f64) -> usize {
    let mut w = width;
    let mut n = 0;
    while w > tolerance {
        w *= 0.5;
        n += 1;
    }
    n
}

/// Outcome of the bisection.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub enum HuntingSpeed {
    /// The transition lies in (decays, hunts], hunts − decays ≤ tolerance.
    Found {
        /// Lowest speed run at which the disturbance kept hunting.
        hunts: f64,
        /// Highest speed run at which it died out.
        decays: f64,
        /// Constant-speed runs made.
        runs: usize,
    },
    /// The disturbance died out even at the top of the bracket.
    NeverHunts,
    /// It kept hunting even at the bottom of the bracket.
    AlwaysHunts,
}

/// Whether a run keeps hunting: the largest |signal| over its last `window` s (samples at
/// t ≥ t_end − window, within 1e-9·window) is at or above `threshold`. `times` increasing (s),
/// as long as `signal`, not empty.
pub fn keeps_hunting(times: &[f64], signal: &[f64], window: f64, threshold: f64) -> bool {
    let Some(&end) = times.last() else {
        return false;
    };
    let from = end - window - 1e-9 * window;
    let start = times.partition_point(|&t| t < from);
    signal[start..]
        .iter()
        .any(|v| v.abs() >= threshold || v.is_nan())
}

/// Bisection over speeds in [low, high] to `tolerance` (see the module documentation);
/// `hunts(v)` runs the model at speed v and says whether the disturbance keeps hunting.
pub fn bisect<E>(
    low: f64,
    high: f64,
    tolerance: f64,
    mut hunts: impl FnMut(f64) -> Result<bool, E>,
) -> Result<HuntingSpeed, E> {
    if !hunts(high)? {
        return Ok(HuntingSpeed::NeverHunts);
    }
    if hunts(low)? {
        return Ok(HuntingSpeed::AlwaysHunts);
    }
    let (mut lo, mut hi, mut runs) = (low, high, 2);
    while hi - lo > tolerance {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break; // floating-point resolution reached
        }
        runs += 1;
        if hunts(mid)? {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    Ok(HuntingSpeed::Found {
        hunts: hi,
        decays: lo,
        runs,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec() -> HuntingSpeedSpec {
        toml::from_str(
            "name = \"v\"\nspeed_parameter = \"V0\"\nset = { ramp = 0.0 }\nlow = 40.0\n\
             high = 100.0\ntolerance = 0.02\nduration = 200.0\nsignal = \"Y\"",
        )
        .unwrap()
    }

    #[test]
    fn bisection_brackets_a_step_to_the_tolerance() {
        for v_star in [40.0001, 55.5, 69.2857, 73.0, 99.999] {
            let mut seen = Vec::new();
            let r = bisect(40.0, 100.0, 0.02, |v| {
                seen.push(v);
                Ok::<_, ()>(v >= v_star)
            })
            .unwrap();
            let HuntingSpeed::Found {
                hunts,
                decays,
                runs,
            } = r
            else {
                panic!("{r:?}")
            };
            assert!(
                decays < v_star && v_star <= hunts,
                "{decays} {v_star} {hunts}"
            );
            assert!(hunts - decays <= 0.02 && hunts - decays > 0.01);
            assert_eq!(runs, seen.len());
            assert_eq!(runs, spec().runs_when_found());
            // 60 / 0.02 = 3000 → 12 halvings, plus the two ends.
            assert_eq!(runs, 14);
            assert_eq!(&seen[..2], &[100.0, 40.0]);
            // Both reported speeds were run.
            assert!(seen.contains(&hunts) && seen.contains(&decays));
        }
    }

    #[test]
    fn bracket_without_the_transition() {
        let r = bisect(60.0, 80.0, 0.1, |_| Ok::<_, ()>(false)).unwrap();
        assert_eq!(r, HuntingSpeed::NeverHunts);
        let mut n = 0;
        let r = bisect(60.0, 80.0, 0.1, |_| {
            n += 1;
            Ok::<_, ()>(true)
        })
        .unwrap();
        assert_eq!((r, n), (HuntingSpeed::AlwaysHunts, 2));
        // A failed run stops the bisection with its error.
        let r = bisect(
            60.0,
            80.0,
            0.1,
            |v| if v < 70.0 { Err(v) } else { Ok(true) },
        );
        assert_eq!(r, Err(60.0));
    }

    #[test]
    fn tiny_tolerance_stops_at_floating_point_resolution() {
        let r = bisect(1.0, 2.0, 1e-300, |v| Ok::<_, ()>(v >= 1.5)).unwrap();
        let HuntingSpeed::Found { hunts, decays, .. } = r else {
            panic!()
        };
        assert_eq!(hunts, 1.5);
        assert_eq!(decays, 1.5f64.next_down());
    }

    #[test]
    fn keeps_hunting_looks_at_the_last_window_only() {
        let t: Vec<f64> = (0..=1000).map(|i| i as f64 * 0.01).collect();
        // Decays as e^{-t}: below 1e-4 after 9.2 s.
        let s: Vec<f64> = t.iter().map(|&t| (-t).exp() * (30.0 * t).cos()).collect();
        assert!(!keeps_hunting(&t, &s, 0.5, 1e-4));
        assert!(
            keeps_hunting(&t, &s, 2.0, 1e-4),
            "e^-8 > 1e-4 inside 8–10 s"
        );
        let lc: Vec<f64> = t.iter().map(|&t| 9e-3 * (30.0 * t).sin()).collect();
        assert!(keeps_hunting(&t, &lc, 1.0, 1e-4));
        assert!(!keeps_hunting(&t, &lc, 1.0, 1e-2));
        // The window includes the sample exactly at t_end − window.
        let mut spike = vec![0.0; t.len()];
        spike[900] = 1.0; // t = 9.0
        assert!(keeps_hunting(&t, &spike, 1.0, 0.5));
        assert!(!keeps_hunting(&t, &spike, 0.99, 0.5));
        // A NaN counts as loud, never as quiet.
        let mut nan = vec![0.0; t.len()];
        nan[1000] = f64::NAN;
        assert!(keeps_hunting(&t, &nan, 1.0, 0.5));
        assert!(!keeps_hunting(&[], &[], 1.0, 0.5));
    }

    #[test]
    fn settings_are_checked() {
        assert_eq!(spec().problem(), None);
        assert_eq!(spec().decay_name(), "v_decay");
        let bad = |f: &dyn Fn(&mut HuntingSpeedSpec)| {
            let mut s = spec();
            f(&mut s);
            s.problem().expect("refused")
        };
        assert!(bad(&|s| s.high = 30.0).contains("low < high"));
        assert!(bad(&|s| s.tolerance = 0.0).contains("tolerance"));
        assert!(bad(&|s| s.low = f64::NAN).contains("low < high"));
        assert!(bad(&|s| s.duration = 0.5).contains("duration"));
        assert!(bad(&|s| s.threshold = -1.0).contains("threshold"));
        assert!(bad(&|s| s.step = Some(2.0)).contains("step"));
        assert!(bad(&|s| {
            s.set.insert("V0".into(), 70.0.into());
        })
        .contains("speed parameter"));
        assert!(bad(&|s| {
            s.set.insert("x".into(), f64::INFINITY.into());
        })
        .contains("not finite"));
        let r: Result<HuntingSpeedSpec, _> = toml::from_str(
            "name = \"v\"\nspeed_parameter = \"V0\"\nlow = 40.0\nhigh = 100.0\n\
             tolerance = 0.02\nduration = 200.0\nsignal = \"Y\"\ntolerence = 1.0",
        );
        assert!(r.unwrap_err().to_string().contains("unknown field"));
    }
}
