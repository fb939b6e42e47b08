//! Nonlinear critical speed from a run on a falling speed ramp: the speed at which the hunting
//! oscillation dies out (the paper's definition, §4), read off a time series of a displacement
//! (typically the bogie's lateral displacement Y, in m) and the running speed (m/s).
//!
//! # Definition
//!
//! Samples (t_k, s_k, V_k), k = 0..n, t strictly increasing (s), window w > 0 (s),
//! threshold a > 0 (units of s). The trailing sliding maximum is
//!
//! ```text
//! M_k = max { |s_j| : t_k − w ≤ t_j ≤ t_k }
//! ```
//!
//! (samples within 1e-9·w of the window's start count as inside, so that rounding in the time
//! grid does not decide membership). Let L be the last index with M_L ≥ a.
//!
//! - no such L (every |s_k| < a): [`CriticalSpeed::NeverHunts`];
//! - L = n (the sliding maximum is still at or above the threshold at the end of the record,
//!   which includes every window longer than the quiet tail of the record):
//!   [`CriticalSpeed::NeverStops`];
//! - otherwise t* = t_{L+1} is the first sample time from which the sliding maximum stays below
//!   the threshold for good, and the result is [`CriticalSpeed::Found`] with
//!   `time` = t* − w and `speed` = V(t* − w), V linearly interpolated between samples.
//!
//! # Why V(t* − w) and not V(t*)
//!
//! t* − w lies after the last sample with |s| ≥ a and at most one sample spacing later: it is the
//! moment the oscillation last reached the threshold, i.e. where it "dies out". Because the
//! quiet must last for good, zero crossings inside the hunting never end it early; the window
//! demands a quiet tail of at least w before the end of the record (and bridges the zero
//! crossings when the sliding maximum itself is plotted). Reporting V(t*) would add a bias of
//! w·|dV/dt| that depends on that confirmation length alone (0.1 m/s for w = 1 s on the paper's
//! 0.1 m/s² ramp); V(t* − w) does not depend on w as long as the record holds the quiet window.
//!
//! The sliding maximum uses a monotone deque: O(n) time, O(w / Δt) memory.

use std::collections::VecDeque;

/// Result of the critical-speed detection.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub enum CriticalSpeed {
    /// The oscillation died out.
    Found {
        /// Speed (m/s, units of the `speed` series) at `time`.
        speed: f64,
        /// Time (s) at which the oscillation last reached the threshold: t* − window.
        time: f64,
    },
    /// The amplitude is below the threshold from the start: no hunting to die out.
    NeverHunts,
    /// Still at or above the threshold within the last window of the record: the oscillation
    /// does not die out within the run (or the record is too short to confirm that it did).
    NeverStops,
}

/// Why the input of [`critical_speed`] was refused.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CriticalSpeedError {
    /// The three series differ in length.
    #[error("series lengths differ: {times} times, {signal} signal values, {speed} speeds")]
    LengthMismatch {
        /// Number of times.
        times: usize,
        /// Number of signal values.
        signal: usize,
        /// Number of speed values.
        speed: usize,
    },
    /// No samples at all.
    #[error("empty record: no samples")]
    Empty,
    /// A value is NaN or infinite.
    #[error("non-finite {series} at sample {index}: {value}")]
    NonFinite {
        /// Which series ("time", "signal" or "speed").
        series: &'static str,
        /// Sample index.
        index: usize,
        /// The value.
        value: f64,
    },
    /// The times do not increase strictly.
    #[error("times must increase strictly: t[{index}] = {value} s after {previous} s")]
    NotIncreasing {
        /// Sample index.
        index: usize,
        /// Its time (s).
        value: f64,
        /// The previous time (s).
        previous: f64,
    },
    /// The window is not finite and positive.
    #[error("window must be finite and > 0 s, got {0}")]
    BadWindow(f64),
    /// The threshold is not finite and positive.
    #[error("threshold must be finite and > 0, got {0}")]
    BadThreshold(f64),
}

/// Speed at which the oscillation in `signal` dies out: see the module documentation for the
/// exact definition.
///
/// `times` in s (strictly increasing), `signal` in any unit (e.g. the lateral displacement in m),
/// `speed` in m/s, `window` (s) the length of the trailing sliding maximum, `threshold` in the
/// unit of `signal` (e.g. 1e-4 m with a 1 s window, as for the paper's bogie).
pub fn critical_speed(
    times: &[f64],
    signal: &[f64],
    speed: &[f64],
    window: f64,
    threshold: f64,
) -> Result<CriticalSpeed, CriticalSpeedError> {
    validate(times, signal, speed, window, threshold)?;
    let maxima = sliding_max_abs(times, signal, window);
    let Some(last_loud) = maxima.iter().rposition(|&m| m >= threshold) else {
        return Ok(CriticalSpeed::NeverHunts);
    };
    if last_loud + 1 == times.len() {
        return Ok(CriticalSpeed::NeverStops);
    }
    let time = times[last_loud + 1] - window;
    Ok(CriticalSpeed::Found {
        speed: interpolate(times, speed, time),
        time,
    })
}

fn validate(
    times: &[f64],
    signal: &[f64],
    speed: &[f64],
    window: f64,
    threshold: f64,
) -> Result<(), CriticalSpeedError> {
    if times.len() != signal.len() || times.len() != speed.len() {
        return Err(CriticalSpeedError::LengthMismatch {
            times: times.len(),
            signal: signal.len(),
            speed: speed.len(),
        });
    }
    if times.is_empty() {
        return Err(CriticalSpeedError::Empty);
    }
    if !(window.is_finite() && window > 0.0) {
        return Err(CriticalSpeedError::BadWindow(window));
    }
    if !(threshold.is_finite() && threshold > 0.0) {
        return Err(CriticalSpeedError::BadThreshold(threshold));
    }
    for (series, values) in [("time", times), ("signal", signal), ("speed", speed)] {
        if let Some(index) = values.iter().position(|v| !v.is_finite()) {
            return Err(CriticalSpeedError::NonFinite {
                series,
                index,
                value: values[index],
            });
        }
    }
    if let Some(i) = times.windows(2).position(|w| w[1] <= w[0]) {
        return Err(CriticalSpeedError::NotIncreasing {
            index: i + 1,
            value: times[i + 1],
            previous: times[i],
        });
    }
    Ok(())
}

/// Trailing sliding maximum of |values| over [t_k − window, t_k] for every k, by a monotone
/// deque of indices whose |values| decrease from front to back: O(n).
fn sliding_max_abs(times: &[f64], values: &[f64], window: f64) -> Vec<f64> {
    let slack = 1e-9 * window;
    let mut deque: VecDeque<usize> = VecDeque::new();
    let mut out = Vec::with_capacity(values.len());
    for (k, (&t, &v)) in times.iter().zip(values).enumerate() {
        let a = v.abs();
        while deque.back().is_some_and(|&j| values[j].abs() <= a) {
            deque.pop_back();
        }
        deque.push_back(k);
        let start = t - window - slack;
        while deque.front().is_some_and(|&j| times[j] < start) {
            deque.pop_front();
        }
        // The deque holds k itself, so it is never empty here.
        out.push(deque.front().map_or(a, |&j| values[j].abs()));
    }
    out
}

/// Linear interpolation of `values` at time `t` (clamped to the record).
fn interpolate(times: &[f64], values: &[f64], t: f64) -> f64 {
    let n = times.len();
    if t <= times[0] {
        return values[0];
    }
    if t >= times[n - 1] {
        return values[n - 1];
    }
    // First index with times[i] > t; 1 <= i <= n - 1.
    let i = times.partition_point(|&x| x <= t);
    let (t0, t1) = (times[i - 1], times[i]);
    let f = (t - t0) / (t1 - t0);
    values[i - 1] + f * (values[i] - values[i - 1])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The signal `f(t)` at the times `t` before `end` (s), 0 from then on.
    fn until(t: &[f64], end: f64, f: impl Fn(f64) -> f64) -> Vec<f64> {
        t.iter()
            .map(|&t| if t < end { f(t) } else { 0.0 })
            .collect()
    }

    /// Uniform grid 0, dt, …, stop and the paper's ramp V = 100 − t/10.
    fn grid(stop: f64, dt: f64) -> (Vec<f64>, Vec<f64>) {
        let n = (stop / dt).round() as usize;
        let t: Vec<f64> = (0..=n).map(|i| i as f64 * dt).collect();
        let v = t.iter().map(|t| 100.0 - t / 10.0).collect();
        (t, v)
    }

    /// O(n·w) sliding maximum, written independently of the deque.
    fn brute_force_max(times: &[f64], values: &[f64], window: f64) -> Vec<f64> {
        times
            .iter()
            .map(|&tk| {
                times
                    .iter()
                    .zip(values)
                    .filter(|(&tj, _)| tj <= tk && tj >= tk - window - 1e-9 * window)
                    .fold(0.0f64, |m, (_, v)| m.max(v.abs()))
            })
            .collect()
    }

    #[test]
    fn decaying_sinusoid_dies_out_where_its_envelope_crosses_the_threshold() {
        // s = A e^{-σt} sin(2π f t): the envelope reaches a = 1e-4 at t_c = ln(A/a)/σ = 23.03 s.
        // After t_c, |s| < a; in [t_c − 1/(2f), t_c] there is a point with |sin| = 1, where
        // |s| > a. So the last |s| >= a lies in [t_c − 0.125 s, t_c], and t* − w within one
        // sample (1 ms) after it.
        let (a_0, sigma, f, thr) = (0.01, 0.2, 4.0, 1e-4);
        let (t, v) = grid(60.0, 1e-3);
        let s: Vec<f64> = t
            .iter()
            .map(|&t| a_0 * (-sigma * t).exp() * (2.0 * std::f64::consts::PI * f * t).sin())
            .collect();
        let t_c = (a_0 / thr).ln() / sigma;
        let mut found = Vec::new();
        for w in [0.5, 1.0, 2.0] {
            match critical_speed(&t, &s, &v, w, thr).unwrap() {
                CriticalSpeed::Found { speed, time } => {
                    assert!(
                        time <= t_c + 1e-3 && time >= t_c - 0.125 - 1e-3,
                        "w = {w}: time {time} vs envelope crossing {t_c}"
                    );
                    assert!((speed - (100.0 - time / 10.0)).abs() < 1e-9);
                    found.push((speed, time));
                }
                other => panic!("w = {w}: {other:?}"),
            }
        }
        // Independent of the window length (to within the sample spacing, 1 ms).
        for (speed, time) in &found[1..] {
            assert!((time - found[0].1).abs() <= 1e-3 + 1e-9);
            assert!((speed - found[0].0).abs() <= 1e-4 + 1e-9);
        }
        // A lower threshold is reached later, i.e. at a lower speed: ln 2 / σ = 3.47 s later.
        let CriticalSpeed::Found { time: later, .. } =
            critical_speed(&t, &s, &v, 1.0, thr / 2.0).unwrap()
        else {
            panic!("expected Found")
        };
        let shift = later - found[1].1;
        assert!((shift - 2f64.ln() / sigma).abs() < 0.13, "shift {shift}");
    }

    #[test]
    fn zero_crossings_inside_the_hunting_are_no_false_end() {
        // A 4 Hz sine of amplitude 2a has |s| < a for 42 ms around each zero crossing. Because
        // the quiet must last for good, even a window shorter than that finds the end of the
        // hunting (at 5 s), not a zero crossing inside it.
        let (t, v) = grid(10.0, 1e-3);
        let s: Vec<f64> = t
            .iter()
            .map(|&t| {
                let amp = if t < 5.0 { 2e-4 } else { 0.0 };
                amp * (2.0 * std::f64::consts::PI * 4.0 * t).sin()
            })
            .collect();
        for w in [0.02, 0.2, 1.0] {
            match critical_speed(&t, &s, &v, w, 1e-4).unwrap() {
                CriticalSpeed::Found { time, .. } => {
                    assert!(time > 4.8 && time <= 5.0, "w = {w}: time {time}")
                }
                other => panic!("w = {w}: {other:?}"),
            }
        }
    }

    #[test]
    fn always_small_never_hunts() {
        let (t, v) = grid(10.0, 0.01);
        let s: Vec<f64> = t.iter().map(|t| 5e-5 * (7.0 * t).sin()).collect();
        assert_eq!(
            critical_speed(&t, &s, &v, 1.0, 1e-4).unwrap(),
            CriticalSpeed::NeverHunts
        );
        // Even with a window longer than the record.
        assert_eq!(
            critical_speed(&t, &s, &v, 100.0, 1e-4).unwrap(),
            CriticalSpeed::NeverHunts
        );
        // A single sample below the threshold.
        assert_eq!(
            critical_speed(&[0.0], &[0.0], &[70.0], 1.0, 1e-4).unwrap(),
            CriticalSpeed::NeverHunts
        );
    }

    #[test]
    fn hunting_to_the_end_never_stops() {
        let (t, v) = grid(30.0, 0.01);
        let s: Vec<f64> = t.iter().map(|t| 9e-3 * (27.0 * t).sin()).collect();
        assert_eq!(
            critical_speed(&t, &s, &v, 1.0, 1e-4).unwrap(),
            CriticalSpeed::NeverStops
        );
        // Dies out, but less than one window before the end: not confirmed.
        let s = until(&t, 29.5, |t| 9e-3 * (27.0 * t).sin());
        assert_eq!(
            critical_speed(&t, &s, &v, 1.0, 1e-4).unwrap(),
            CriticalSpeed::NeverStops
        );
        // The same with a 0.4 s window is confirmed.
        assert!(matches!(
            critical_speed(&t, &s, &v, 0.4, 1e-4).unwrap(),
            CriticalSpeed::Found { .. }
        ));
        // Loud only at the very last sample.
        let mut s = vec![0.0; t.len()];
        *s.last_mut().unwrap() = 1.0;
        assert_eq!(
            critical_speed(&t, &s, &v, 1.0, 1e-4).unwrap(),
            CriticalSpeed::NeverStops
        );
    }

    #[test]
    fn window_longer_than_the_record() {
        // Hunting that dies out at 3 s in a 10 s record: a 20 s window can never be quiet.
        let (t, v) = grid(10.0, 0.01);
        let s = until(&t, 3.0, |t| 5e-3 * (27.0 * t).cos());
        assert_eq!(
            critical_speed(&t, &s, &v, 20.0, 1e-4).unwrap(),
            CriticalSpeed::NeverStops
        );
        // With a 1 s window: the last loud sample is at 2.99 s (|cos| large there).
        match critical_speed(&t, &s, &v, 1.0, 1e-4).unwrap() {
            CriticalSpeed::Found { speed, time } => {
                assert!((time - 3.0).abs() < 1e-9, "time {time}");
                assert!((speed - 99.7).abs() < 1e-9, "speed {speed}");
            }
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn deque_matches_brute_force_on_irregular_samples() {
        // Deterministic pseudo-random signal on a non-uniform grid.
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut t = vec![0.0];
        for _ in 0..2000 {
            let last = *t.last().unwrap();
            t.push(last + 0.001 + 0.02 * next());
        }
        let s: Vec<f64> = t.iter().map(|_| 2.0 * next() - 1.0).collect();
        for w in [0.005, 0.05, 0.3, 1.0, 50.0] {
            assert_eq!(
                sliding_max_abs(&t, &s, w),
                brute_force_max(&t, &s, w),
                "w {w}"
            );
        }
        // And the result agrees with "last sample with |s| >= a, plus the window".
        let v: Vec<f64> = t.iter().map(|t| 100.0 - t / 10.0).collect();
        let mut quiet = s.clone();
        let cut = t.len() - 400;
        for q in &mut quiet[cut..] {
            *q *= 1e-6;
        }
        let thr = 0.5;
        let last = quiet.iter().rposition(|x| x.abs() >= thr).unwrap();
        let star = t.iter().copied().find(|&x| x - 1.0 > t[last]).unwrap();
        assert_eq!(
            critical_speed(&t, &quiet, &v, 1.0, thr).unwrap(),
            CriticalSpeed::Found {
                speed: interpolate(&t, &v, star - 1.0),
                time: star - 1.0
            }
        );
    }

    #[test]
    fn refuses_bad_input() {
        let (t, v) = grid(1.0, 0.1);
        let s = vec![0.0; t.len()];
        assert!(matches!(
            critical_speed(&t, &s[1..], &v, 1.0, 1e-4),
            Err(CriticalSpeedError::LengthMismatch { .. })
        ));
        assert!(matches!(
            critical_speed(&t, &s, &v[1..], 1.0, 1e-4),
            Err(CriticalSpeedError::LengthMismatch { .. })
        ));
        assert_eq!(
            critical_speed(&[], &[], &[], 1.0, 1e-4),
            Err(CriticalSpeedError::Empty)
        );
        for w in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(matches!(
                critical_speed(&t, &s, &v, w, 1e-4),
                Err(CriticalSpeedError::BadWindow(_))
            ));
        }
        for a in [0.0, -1e-4, f64::NAN] {
            assert!(matches!(
                critical_speed(&t, &s, &v, 1.0, a),
                Err(CriticalSpeedError::BadThreshold(_))
            ));
        }
        let mut bad = s.clone();
        bad[3] = f64::NAN;
        assert!(matches!(
            critical_speed(&t, &bad, &v, 1.0, 1e-4),
            Err(CriticalSpeedError::NonFinite {
                series: "signal",
                index: 3,
                ..
            })
        ));
        let mut bad = v.clone();
        bad[2] = f64::INFINITY;
        assert!(matches!(
            critical_speed(&t, &s, &bad, 1.0, 1e-4),
            Err(CriticalSpeedError::NonFinite {
                series: "speed",
                ..
            })
        ));
        let mut bad = t.clone();
        bad[5] = f64::NEG_INFINITY;
        assert!(matches!(
            critical_speed(&bad, &s, &v, 1.0, 1e-4),
            Err(CriticalSpeedError::NonFinite { series: "time", .. })
        ));
        let mut bad = t.clone();
        bad[4] = bad[3];
        assert!(matches!(
            critical_speed(&bad, &s, &v, 1.0, 1e-4),
            Err(CriticalSpeedError::NotIncreasing { index: 4, .. })
        ));
        let msg = CriticalSpeedError::BadWindow(0.0).to_string();
        assert!(msg.contains("window"), "{msg}");
    }

    #[test]
    fn serializes_as_tagged_variants() {
        let found = CriticalSpeed::Found {
            speed: 64.865,
            time: 351.35,
        };
        assert_eq!(
            serde_json::to_string(&found).unwrap(),
            r#"{"Found":{"speed":64.865,"time":351.35}}"#
        );
        assert_eq!(
            serde_json::to_string(&CriticalSpeed::NeverStops).unwrap(),
            r#""NeverStops""#
        );
    }
}
