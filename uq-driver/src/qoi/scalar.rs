//! Scalar quantities of interest evaluated on one run's time series, as the study file
//! declares them (`[[qoi]]`): critical speed, Sperling index, peak |signal|, final value.

use crate::qoi::critical_speed::{critical_speed, CriticalSpeed};
use crate::qoi::sperling::{sperling_index, Direction, SperlingSettings};
use crate::study::spec::QoiSpec;

/// Outcome code stored beside a scalar value.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[repr(u8)]
pub enum Code {
    /// The value is valid.
    Ok = 0,
    /// Critical speed: the signal never exceeds the threshold (value NaN).
    NeverHunts = 1,
    /// Critical speed: the oscillation never dies out within the run (value NaN).
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
) -> Result<(f64, Code), String> {
    match q {
        QoiSpec::CriticalSpeed {
            signal: s,
            speed,
            window,
            threshold,
            ..
        } => match critical_speed(times, signal(s), signal(speed), *window, *threshold)
            .map_err(|e| e.to_string())?
        {
            CriticalSpeed::Found { speed, .. } => Ok((speed, Code::Ok)),
            CriticalSpeed::NeverHunts => Ok((f64::NAN, Code::NeverHunts)),
            CriticalSpeed::NeverStops => Ok((f64::NAN, Code::NeverStops)),
        },
        QoiSpec::Sperling {
            signal: s,
            direction,
            segment,
            f_min,
            f_max,
            skip,
            ..
        } => {
            let dt = times
                .get(1)
                .map(|t1| t1 - times[0])
                .ok_or("fewer than two samples")?;
            let start = times.partition_point(|&t| t < times[0] + skip - 1e-9 * dt);
            let settings = SperlingSettings {
                direction: if direction == "lateral" {
                    Direction::Lateral
                } else {
                    Direction::Vertical
                },
                segment_length_s: *segment,
                f_min: *f_min,
                f_max: *f_max,
            };
            let r =
                sperling_index(&signal(s)[start..], dt, &settings).map_err(|e| e.to_string())?;
            Ok((r.w, Code::Ok))
        }
        QoiSpec::MaxAbs {
            signal: s,
            from,
            to,
            ..
        } => {
            let x = signal(s);
            let to = to.unwrap_or(f64::INFINITY);
            let m = times
                .iter()
                .zip(x)
                .filter(|(t, _)| **t >= *from && **t <= to)
                .map(|(_, v)| v.abs())
                .fold(f64::NAN, f64::max);
            if m.is_nan() {
                return Err(format!("no sample of {s} in [{from}, {to}] s"));
            }
            Ok((m, Code::Ok))
        }
        QoiSpec::Final { signal: s, .. } => {
            let x = signal(s);
            x.last()
                .map(|v| (*v, Code::Ok))
                .ok_or_else(|| format!("{s} is empty"))
        }
    }
}
