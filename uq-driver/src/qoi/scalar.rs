//! Scalar quantities of interest evaluated on one run's time series, as the study file
//! declares them (`[[qoi]]`): critical speed, Sperling index, peak |signal|, final value.

use crate::qoi::critical_speed::{critical_speed, CriticalSpeed};
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
        QoiSpec::Sperling { .. } => Err("TEMPORARY: Sperling not wired yet".into()),
        QoiSpec::MaxAbs { signal: s, from, to, .. } => {
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
            x.last().map(|v| (*v, Code::Ok)).ok_or_else(|| format!("{s} is empty"))
        }
    }
}
