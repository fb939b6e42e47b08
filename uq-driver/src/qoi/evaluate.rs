//! A scalar quantity evaluated on one run: [`evaluate`] and the [`Code`] stored beside its
//! value (split from `scalar.rs`, which defines the quantities).

use serde::Serialize;

use super::critical_speed::{critical_speed, CriticalSpeed};
use super::scalar::{QoiError, QoiSpec};
use super::sperling::{sperling_index, SperlingSettings, Statistic};

/// Outcome code stored beside a scalar value.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[repr(u8)]
pub enum Code {
    /// The value is valid.
    Ok = 0,
    /// Critical speed: the signal never exceeds the threshold (value NaN); `hunting_speed`:
    /// the disturbance dies out even at the top of the bracket.
    NeverHunts = 1,
    /// Critical speed: the oscillation never dies out within the run (value NaN);
    /// `hunting_speed`: the disturbance keeps hunting even at the bottom of the bracket.
    NeverStops = 2,
}

impl Code {
    /// From the stored number.
    pub fn from_f64(x: f64) -> Code {
        match x as u8 {
            1 => Code::NeverHunts,
            2 => Code::NeverStops,
            _ => Code::Ok,
        }
    }
}

/// Evaluates `q` on a run: `signal(name)` gives a series sampled at `times`. Returns the
/// value (NaN unless the code is Ok) and its code.
pub fn evaluate<'a>(
    q: &QoiSpec,
    times: &[f64],
    signal: impl Fn(&str) -> &'a [f64],
) -> Result<(f64, Code), QoiError> {
    match q {
        QoiSpec::CriticalSpeed {
            signal: s,
            speed,
            window,
            threshold,
            ..
        } => Ok(
            match critical_speed(times, signal(s), signal(speed), *window, *threshold)? {
                CriticalSpeed::Found { speed, .. } => (speed, Code::Ok),
                CriticalSpeed::NeverHunts => (f64::NAN, Code::NeverHunts),
                CriticalSpeed::NeverStops => (f64::NAN, Code::NeverStops),
            },
        ),
        QoiSpec::Sperling {
            signal: s,
            direction,
            segment,
            f_min,
            f_max,
            skip,
            window,
            statistic,
            ..
        } => {
            let dt = times
                .get(1)
                .map(|t1| t1 - times[0])
                .ok_or(QoiError::TooShort)?;
            let start = times.partition_point(|&t| t < times[0] + skip - 1e-9 * dt);
            let settings = SperlingSettings {
                direction: *direction,
                window: *window,
                segment_length_s: *segment,
                f_min: *f_min,
                f_max: *f_max,
            };
            let r = sperling_index(&signal(s)[start..], dt, &settings)?;
            let w = match statistic {
                Statistic::Max => r.w,
                Statistic::Mean => r.mean,
            };
            Ok((w, Code::Ok))
        }
        QoiSpec::MaxAbs(w) | QoiSpec::Min(w) | QoiSpec::Max(w) | QoiSpec::Range(w) => {
            let values = in_window(times, signal(&w.signal), w.from, w.to);
            // NaN-skipping folds: a window of NaN only has no value (NaN here).
            let m = match q {
                QoiSpec::MaxAbs(_) => values.map(f64::abs).fold(f64::NAN, f64::max),
                QoiSpec::Min(_) => values.fold(f64::NAN, f64::min),
                QoiSpec::Max(_) => values.fold(f64::NAN, f64::max),
                _ => {
                    let (lo, hi) = values
                        .filter(|v| v.is_finite())
                        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                            (lo.min(v), hi.max(v))
                        });
                    if lo > hi {
                        f64::NAN
                    } else {
                        hi - lo
                    }
                }
            };
            if m.is_nan() {
                return Err(QoiError::EmptyInterval {
                    signal: w.signal.clone(),
                    from: w.from,
                    to: w.to.unwrap_or(f64::INFINITY),
                });
            }
            Ok((m, Code::Ok))
        }
        QoiSpec::Final { signal: s, .. } => signal(s)
            .last()
            .map(|v| (*v, Code::Ok))
            .ok_or_else(|| QoiError::EmptySignal(s.clone())),
        QoiSpec::HuntingSpeed(h) => Err(QoiError::NeedsOwnRuns(h.name.clone())),
    }
}

/// The values of `values` (sampled at `times`, s) with from <= t <= to (to: the end if None).
fn in_window<'a>(
    times: &'a [f64],
    values: &'a [f64],
    from: f64,
    to: Option<f64>,
) -> impl Iterator<Item = f64> + 'a {
    let to = to.unwrap_or(f64::INFINITY);
    times
        .iter()
        .zip(values)
        .filter(move |(t, _)| **t >= from && **t <= to)
        .map(|(_, v)| *v)
}
