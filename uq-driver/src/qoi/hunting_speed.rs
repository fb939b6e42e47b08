//! Constant-speed critical speed: the lowest speed at which hunting persists, and the highest
//! at which it dies out, found from runs at fixed speeds (the quantity a bogie designer
//! compares with), not read off a speed ramp; by bisection over runs from a disturbance
//! (`mode = "bisection"`, the default) or by continuation (`mode = "continuation"`: see
//! [Continuation](#continuation)).
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
//! speeds downwards; choose it from a convergence check (see the bogie's in the user guide,
//! `docs/src/reference/models.md`).
//!
//! # Continuation
//!
//! Where the limit cycle's basin is small near the fold (the full car: a large displacement of
//! one wheelset dies out at speeds well above the fold), runs that each start from the
//! disturbance find a speed well above the fold. `continue_down` follows the hunting branch
//! instead, on one simulation whose speed is lowered between steps (the speed parameter must
//! be tunable):
//!
//! - a first stage of `duration` s at `high` from the disturbance: dies out there:
//!   [`HuntingSpeed::NeverHunts`];
//! - then stages of `duration` s at high − `speed_step`, high − 2 `speed_step`, … (not below
//!   `low`), each continuing from the final state of the one before, until a stage dies out;
//!   still hunting at `low`: [`HuntingSpeed::AlwaysHunts`];
//! - then bisection between the last speed that kept hunting and the first that did not, to
//!   `tolerance`: each trial continues from the final state of the lowest speed that kept
//!   hunting so far (fmi2GetFMUstate / fmi2SetFMUstate; needed only when `tolerance` is below
//!   `speed_step`).
//!
//! A stage keeps hunting by [`keeps_hunting`] over its last `window` s. The result is
//! [`HuntingSpeed::Found`] with the lowest speed at which the hunting persisted and the
//! highest at which it died out; that costs one stage per `speed_step` from `high` down to the
//! fold plus ⌈log2(`speed_step`/`tolerance`)⌉ (the runs reported count the stages).

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::fmu::FixedValue;

/// How a `hunting_speed` quantity searches the speeds (`mode`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SearchMode {
    /// Bisection over runs that each start from the disturbance (the default).
    #[default]
    Bisection,
    /// Continuation down the hunting branch, the state carried from speed to speed.
    Continuation,
}

/// Settings of a `hunting_speed` quantity (`[[qoi]] kind = "hunting_speed"`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HuntingSpeedSpec {
    /// Name in reports: the lowest speed that keeps hunting. The highest speed at which the
    /// disturbance dies out is reported as `<name>_decay`.
    pub name: String,
    /// The FMU parameter holding the (constant) speed, e.g. "V0" (a Real, settable before
    /// initialization, not a random parameter; tunable for `mode = "continuation"`).
    pub speed_parameter: String,
    /// How the speeds are searched (default bisection). Left out of the serialized settings
    /// when default, so the study hash of existing studies is unchanged.
    #[serde(default, skip_serializing_if = "is_bisection")]
    pub mode: SearchMode,
    /// Continuation only: how far the speed is lowered from one stage to the next (units of
    /// the speed parameter, e.g. m/s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub speed_step: Option<f64>,
    /// Further values set for these runs only, after `[fixed]` and the point's random values
    /// (e.g. `{ ramp = 0.0 }` for a constant speed); not random parameters.
    #[serde(default)]
    pub set: BTreeMap<String, FixedValue>,
    /// Lower end of the bracket (units of the speed parameter, e.g. m/s); continuation: the
    /// lowest speed a stage runs at.
    pub low: f64,
    /// Upper end of the bracket; continuation: the speed of the first stage.
    pub high: f64,
    /// Bisection stops when the two speeds are at most this far apart.
    pub tolerance: f64,
    /// Simulated time of each constant-speed run (s), from the study's start time;
    /// continuation: of each stage.
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

fn is_bisection(m: &SearchMode) -> bool {
    *m == SearchMode::Bisection
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
        match (self.mode, self.speed_step) {
            (SearchMode::Bisection, Some(_)) => {
                return Some("speed_step is a setting of mode = \"continuation\"".into())
            }
            (SearchMode::Continuation, None) => {
                return Some(
                    "mode = \"continuation\" needs speed_step, how far the speed is lowered \
                     from one stage to the next"
                        .into(),
                )
            }
            (SearchMode::Continuation, Some(d)) if !positive(d) || d > self.high - self.low => {
                return Some(format!(
                    "speed_step must be > 0 and at most high - low = {}, got {d}",
                    self.high - self.low
                ))
            }
            _ => {}
        }
        None
    }

    /// Whether the search needs to go back to a saved state (fmi2GetFMUstate and
    /// fmi2SetFMUstate): continuation refined below its `speed_step`.
    pub(crate) fn needs_fmu_state(&self) -> bool {
        self.mode == SearchMode::Continuation && self.speed_step.is_some_and(|d| self.tolerance < d)
    }

    /// Constant-speed runs (continuation: stages) of one point when the transition is inside
    /// the bracket (continuation: at most, with the fold at `low`).
    pub fn runs_when_found(&self) -> usize {
        match (self.mode, self.speed_step) {
            (SearchMode::Continuation, Some(d)) => {
                let stages = ((self.high - self.low) / d).ceil() as usize;
                1 + stages
                    + if self.tolerance < d {
                        bisection_steps(d, self.tolerance)
                    } else {
                        0
                    }
            }
            _ => 2 + bisection_steps(self.high - self.low, self.tolerance),
        }
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

/// One simulation whose speed can be changed between stages, for [`continue_down`].
pub(crate) trait Stages {
    /// A saved state.
    type Saved;
    /// Why a stage failed.
    type Error;
    /// The first stage, from the disturbance at `speed`: whether it keeps hunting.
    fn first(&mut self, speed: f64) -> Result<bool, Self::Error>;
    /// One more stage at `speed` from the current state: whether it keeps hunting.
    fn next(&mut self, speed: f64) -> Result<bool, Self::Error>;
    /// The current state, saved.
    fn save(&mut self) -> Result<Self::Saved, Self::Error>;
    /// Back to a saved state (which stays saved).
    fn restore(&mut self, saved: &Self::Saved) -> Result<(), Self::Error>;
    /// A saved state no longer needed.
    fn release(&mut self, saved: Self::Saved) -> Result<(), Self::Error>;
}

/// Continuation down the hunting branch from `high` in steps of `speed_step`, not below `low`,
/// then bisection to `tolerance` (see [Continuation](self#continuation)).
pub(crate) fn continue_down<S: Stages>(
    low: f64,
    high: f64,
    speed_step: f64,
    tolerance: f64,
    sim: &mut S,
) -> Result<HuntingSpeed, S::Error> {
    if !sim.first(high)? {
        return Ok(HuntingSpeed::NeverHunts);
    }
    let refine = tolerance < speed_step;
    let mut saved = if refine { Some(sim.save()?) } else { None };
    let (mut hunts, mut runs) = (high, 1);
    let mut decays = loop {
        let v = (hunts - speed_step).max(low);
        if v >= hunts {
            if let Some(s) = saved.take() {
                sim.release(s)?;
            }
            return Ok(HuntingSpeed::AlwaysHunts);
        }
        runs += 1;
        if !sim.next(v)? {
            break v;
        }
        hunts = v;
        if refine {
            let old = saved.replace(sim.save()?);
            if let Some(s) = old {
                sim.release(s)?;
            }
        }
    };
    if let Some(mut from) = saved {
        while hunts - decays > tolerance {
            let mid = 0.5 * (decays + hunts);
            if mid <= decays || mid >= hunts {
                break; // floating-point resolution reached
            }
            sim.restore(&from)?;
            runs += 1;
            if sim.next(mid)? {
                hunts = mid;
                let old = std::mem::replace(&mut from, sim.save()?);
                sim.release(old)?;
            } else {
                decays = mid;
            }
        }
        sim.release(from)?;
    }
    Ok(HuntingSpeed::Found {
        hunts,
        decays,
        runs,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The bracket (hunts, decays) and the runs of a search that found one.
    fn found(r: HuntingSpeed) -> (f64, f64, usize) {
        match r {
            HuntingSpeed::Found {
                hunts,
                decays,
                runs,
            } => (hunts, decays, runs),
            r => panic!("{r:?}"),
        }
    }

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
            let (hunts, decays, runs) = found(r);
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
        let (hunts, decays, _) = found(r);
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

    /// A model with a fold at `fold` whose disturbance reaches the limit cycle only above
    /// `basin`: the first stage hunts from `basin` up, a later one keeps hunting when the
    /// state before it hunted and its speed is at least `fold`.
    struct Hysteresis {
        fold: f64,
        basin: f64,
        hunting: bool,
        speeds: Vec<f64>,
        live: i32,
        restores: usize,
    }

    impl Hysteresis {
        fn new(fold: f64, basin: f64) -> Self {
            Hysteresis {
                fold,
                basin,
                hunting: false,
                speeds: Vec::new(),
                live: 0,
                restores: 0,
            }
        }
    }

    impl Stages for Hysteresis {
        type Saved = bool;
        type Error = f64;
        fn first(&mut self, speed: f64) -> Result<bool, f64> {
            self.speeds.push(speed);
            self.hunting = speed >= self.basin;
            Ok(self.hunting)
        }
        fn next(&mut self, speed: f64) -> Result<bool, f64> {
            if speed < 0.0 {
                return Err(speed);
            }
            self.speeds.push(speed);
            self.hunting = self.hunting && speed >= self.fold;
            Ok(self.hunting)
        }
        fn save(&mut self) -> Result<bool, f64> {
            self.live += 1;
            Ok(self.hunting)
        }
        fn restore(&mut self, saved: &bool) -> Result<(), f64> {
            self.restores += 1;
            self.hunting = *saved;
            Ok(())
        }
        fn release(&mut self, _: bool) -> Result<(), f64> {
            self.live -= 1;
            Ok(())
        }
    }

    #[test]
    fn continuation_finds_the_fold_below_the_basin_that_bisection_finds() {
        for fold in [52.13, 55.0, 60.01, 79.99] {
            let mut m = Hysteresis::new(fold, 85.0);
            let r = continue_down(40.0, 120.0, 2.0, 0.05, &mut m).unwrap();
            let (hunts, decays, runs) = found(r);
            assert!(decays < fold && fold <= hunts, "{decays} {fold} {hunts}");
            assert!(hunts - decays <= 0.05, "{decays} {hunts}");
            assert_eq!(runs, m.speeds.len());
            assert_eq!(m.live, 0, "every saved state is released");
            // Down in steps of 2 m/s from 120, then 6 bisections of the last 2 m/s.
            let stages = ((120.0 - fold) / 2.0).floor() as usize + 1;
            assert_eq!(runs, 1 + stages + 6, "{:?}", m.speeds);
            assert_eq!(m.restores, 6);
            assert_eq!(&m.speeds[..3], &[120.0, 118.0, 116.0]);
            // Bisection from the disturbance finds the basin instead.
            let mut b = Hysteresis::new(fold, 85.0);
            let (hunts, _, _) = found(bisect(40.0, 120.0, 0.05, |v| b.first(v)).unwrap());
            assert!((hunts - 85.0).abs() <= 0.05, "{hunts}");
        }
    }

    #[test]
    fn continuation_without_refinement_saves_no_state() {
        let mut m = Hysteresis::new(61.0, 85.0);
        let r = continue_down(40.0, 120.0, 2.0, 2.0, &mut m).unwrap();
        assert_eq!(
            r,
            HuntingSpeed::Found {
                hunts: 62.0,
                decays: 60.0,
                runs: 31
            }
        );
        assert_eq!((m.live, m.restores), (0, 0));
    }

    #[test]
    fn continuation_outside_the_bracket_and_failures() {
        // Never hunts at `high`.
        let mut m = Hysteresis::new(50.0, 130.0);
        assert_eq!(
            continue_down(40.0, 120.0, 2.0, 0.1, &mut m).unwrap(),
            HuntingSpeed::NeverHunts
        );
        assert_eq!(m.speeds, [120.0]);
        // Still hunting at `low`: the last stage runs at `low` exactly.
        let mut m = Hysteresis::new(30.0, 85.0);
        assert_eq!(
            continue_down(41.0, 120.0, 2.0, 0.1, &mut m).unwrap(),
            HuntingSpeed::AlwaysHunts
        );
        assert_eq!(*m.speeds.last().unwrap(), 41.0);
        assert_eq!(m.live, 0);
        // A failed stage stops the search with its error.
        let mut m = Hysteresis::new(-10.0, 0.0);
        assert_eq!(continue_down(-5.0, 3.0, 2.0, 0.1, &mut m), Err(-1.0));
    }

    #[test]
    fn continuation_settings_are_checked() {
        let mut s = spec();
        s.mode = SearchMode::Continuation;
        assert!(s.problem().unwrap().contains("needs speed_step"));
        s.speed_step = Some(2.0);
        assert_eq!(s.problem(), None);
        assert!(s.needs_fmu_state());
        // 60 / 2 = 30 stages below 100 m/s, the first at 100, 7 halvings of 2 m/s to 0.02.
        assert_eq!(s.runs_when_found(), 1 + 30 + 7);
        s.tolerance = 2.0;
        assert!(!s.needs_fmu_state());
        s.speed_step = Some(0.0);
        assert!(s.problem().unwrap().contains("speed_step must be > 0"));
        s.speed_step = Some(61.0);
        assert!(s.problem().unwrap().contains("at most high - low"));
        let mut b = spec();
        b.speed_step = Some(2.0);
        assert!(b
            .problem()
            .unwrap()
            .contains("setting of mode = \"continuation\""));
        let parsed: HuntingSpeedSpec = toml::from_str(
            "name = \"v\"\nspeed_parameter = \"v\"\nmode = \"continuation\"\nspeed_step = 2.0\n\
             low = 40.0\nhigh = 120.0\ntolerance = 0.05\nduration = 40.0\nsignal = \"y\"",
        )
        .unwrap();
        assert_eq!(
            (parsed.mode, parsed.speed_step),
            (SearchMode::Continuation, Some(2.0))
        );
        assert!(toml::from_str::<HuntingSpeedSpec>(
            "name = \"v\"\nspeed_parameter = \"v\"\nmode = \"continued\"\nlow = 1.0\n\
             high = 2.0\ntolerance = 0.1\nduration = 4.0\nsignal = \"y\""
        )
        .is_err());
        // The default mode is left out of the serialized settings (study hashes unchanged).
        let text = serde_json::to_string(&spec()).unwrap();
        assert!(
            !text.contains("mode") && !text.contains("speed_step"),
            "{text}"
        );
    }
}
