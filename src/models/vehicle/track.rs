//! The track the car runs on, as a function of time: speed (constant, or a ramp), curvature
//! and cant (entered through a transition), and the track irregularity under each wheelset.
//!
//! ```text
//! V(t) = v − (t − t_v)/ramp            (ramp = 0: V = v); t_v = start time, or the time v was set
//! x(t) = x_v + ∫ V dt                  distance run by the car body centre since the start
//! f(t) = min(1, (t − t_start)/transition)   (transition = 0: f = 1)
//! κ(t) = f(t)/R  (R = 0: straight),   φse(t) = f(t) · cant
//! wheelset w at track position x(t) + x_w,   x_w = ±u1 ± u2
//! y_irr(x) = scale · w(x) · y_lat(x),   z_irr(x) = scale · w(x) · z_vert(x)
//! w(x) = fade-in from 0 to 1 as ½(1 − cos(π (x − x_f)/L_f)) over L_f after x_f, the start
//!        position of the leading wheelset
//! ```
//!
//! Random irregularities are samples of the German (ORE B176) spectra of the vehicle–track
//! model ([`crate::models::vehicle_track::irregularity`]): the vertical profile with
//! A_v = 4.032e-7 (low) or 1.080e-6 m·rad (high), the lateral alignment the same shape with
//! A_a = 2.119e-7 or 6.125e-7 m·rad, i.e. the vertical sample's generator scaled by
//! √(A_a/A_v) with phases of its own. A measured track is a file of `x, y, z` (m): alignment
//! y positive to the left, vertical profile z positive upward, linearly interpolated.
#![forbid(unsafe_code)]

use super::contact::Running;
use super::equations::Track;
use crate::contact::table::fields;
use crate::models::vehicle_track::irregularity::{RandomProfile, SampleKey, Spectrum};
use std::f64::consts::PI;
use std::sync::Arc;

/// Speed, curve and cant over time.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Course {
    /// Speed at `t_v` (m/s).
    pub v: f64,
    /// Ramp (s²/m): the speed falls by 1/ramp m/s per second; 0 = constant speed.
    pub ramp: f64,
    /// Time at which the speed was `v` (s).
    pub t_v: f64,
    /// Distance run at `t_v` (m).
    pub x_v: f64,
    /// Curvature 1/R of the full curve (1/m).
    pub kappa: f64,
    /// Cant of the full curve (rad).
    pub cant: f64,
    /// Duration of the transition from straight track into the curve (s); 0 = none.
    pub transition: f64,
    /// Start time of the run (s).
    pub t_start: f64,
}

impl Course {
    /// Speed (m/s) at time `t` (s).
    #[inline]
    pub fn speed(&self, t: f64) -> f64 {
        if self.ramp == 0.0 {
            self.v
        } else {
            self.v - (t - self.t_v) / self.ramp
        }
    }

    /// Distance (m) run by the car body centre at time `t` (s).
    #[inline]
    pub fn distance(&self, t: f64) -> f64 {
        let dt = t - self.t_v;
        self.x_v + dt * 0.5 * (self.v + self.speed(t))
    }

    /// Speed, curvature and cant at time `t` (s).
    #[inline]
    pub fn running(&self, t: f64) -> Running {
        let f = if self.transition > 0.0 {
            ((t - self.t_start) / self.transition).clamp(0.0, 1.0)
        } else {
            1.0
        };
        Running {
            v: self.speed(t),
            kappa: f * self.kappa,
            cant: f * self.cant,
        }
    }
}

/// A measured track: alignment and vertical profile at increasing positions.
#[derive(Clone, Debug, PartialEq)]
pub struct MeasuredTrack {
    /// Positions (m), strictly increasing.
    pub x: Vec<f64>,
    /// Alignment (m, positive left).
    pub y: Vec<f64>,
    /// Vertical profile (m, positive up).
    pub z: Vec<f64>,
}

impl MeasuredTrack {
    /// Parses `x, y, z` lines (commas, semicolons, tabs or spaces between the numbers; blank
    /// lines, `#` lines and one header line before the data are skipped). Errors give the line
    /// number and what was expected, never the line.
    pub fn parse(text: &str) -> Result<MeasuredTrack, String> {
        let mut t = MeasuredTrack {
            x: Vec::new(),
            y: Vec::new(),
            z: Vec::new(),
        };
        let mut header_allowed = true;
        for (no, raw) in text.lines().enumerate() {
            let line = raw.trim();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            let nums: Option<Vec<f64>> = fields(line).iter().map(|s| s.parse().ok()).collect();
            match nums {
                Some(v) if v.len() >= 3 => {
                    if v[..3].iter().any(|x| !x.is_finite()) {
                        return Err(format!("line {}: x, y and z must be finite", no + 1));
                    }
                    if t.x.last().is_some_and(|&last| v[0] <= last) {
                        return Err(format!(
                            "line {}: x must increase from line to line",
                            no + 1
                        ));
                    }
                    t.x.push(v[0]);
                    t.y.push(v[1]);
                    t.z.push(v[2]);
                }
                None if header_allowed => {}
                _ => {
                    return Err(format!(
                        "line {}: expected three numbers x [m], y [m], z [m]",
                        no + 1
                    ))
                }
            }
            header_allowed = false;
        }
        if t.x.len() < 2 {
            return Err("a measured track needs at least two lines of x, y, z".into());
        }
        Ok(t)
    }

    /// Range of x covered (m).
    pub fn range(&self) -> (f64, f64) {
        (self.x[0], self.x[self.x.len() - 1])
    }

    /// (y, z) at `x` (m) by linear interpolation; `None` outside the range.
    #[inline]
    pub fn eval(&self, x: f64) -> Option<(f64, f64)> {
        let (lo, hi) = self.range();
        if !(x >= lo && x <= hi) {
            return None;
        }
        let i = (self.x.partition_point(|&xi| xi <= x) - 1).min(self.x.len() - 2);
        let t = (x - self.x[i]) / (self.x[i + 1] - self.x[i]);
        Some((
            self.y[i] + t * (self.y[i + 1] - self.y[i]),
            self.z[i] + t * (self.z[i + 1] - self.z[i]),
        ))
    }
}

/// Where the irregularity comes from.
#[derive(Clone, Debug)]
pub enum Source {
    /// A perfect track.
    None,
    /// Random samples: lateral (with its amplitude factor) and vertical.
    Random {
        /// Lateral alignment sample.
        lateral: Arc<RandomProfile>,
        /// √(A_a/A_v).
        lateral_factor: f64,
        /// Vertical profile sample.
        vertical: Arc<RandomProfile>,
    },
    /// A measured track.
    Measured(Arc<MeasuredTrack>),
}

/// The German spectrum of `code` (2 low, 3 high interference) and √(A_a/A_v).
pub fn german(code: i32) -> Option<(Spectrum, f64)> {
    match code {
        2 => Some((Spectrum::GermanLow, (2.119e-7f64 / 4.032e-7).sqrt())),
        3 => Some((Spectrum::GermanHigh, (6.125e-7f64 / 1.080e-6).sqrt())),
        _ => None,
    }
}

/// The key of the lateral sample: the vertical one's with other phases.
pub fn lateral_key(vertical: SampleKey) -> SampleKey {
    SampleKey {
        seed: (vertical.seed as u32 ^ 0x6c61_7431) as i32,
        ..vertical
    }
}

/// The irregularity under the wheelsets.
#[derive(Clone, Debug)]
pub struct Irregularity {
    /// Source.
    pub source: Source,
    /// Amplitude factor.
    pub scale: f64,
    /// Position where the fade-in starts (m).
    pub fade_start: f64,
    /// Length of the fade-in (m); 0 = none.
    pub fade_length: f64,
}

/// A wheelset beyond the end of the measured track.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OffTrack {
    /// Position reached (m).
    pub x: f64,
}

impl Irregularity {
    /// None at all.
    pub fn none() -> Irregularity {
        Irregularity {
            source: Source::None,
            scale: 0.0,
            fade_start: 0.0,
            fade_length: 0.0,
        }
    }

    #[inline]
    fn weight(&self, x: f64) -> f64 {
        if self.fade_length <= 0.0 || x >= self.fade_start + self.fade_length {
            1.0
        } else if x <= self.fade_start {
            0.0
        } else {
            0.5 * (1.0 - libm::cos(PI * (x - self.fade_start) / self.fade_length))
        }
    }

    /// Lateral and vertical irregularity (m) at track position `x` (m).
    #[inline]
    pub fn at(&self, x: f64) -> Result<(f64, f64), OffTrack> {
        let (y, z) = match &self.source {
            Source::None => return Ok((0.0, 0.0)),
            Source::Random {
                lateral,
                lateral_factor,
                vertical,
            } => (lateral_factor * lateral.eval(x), vertical.eval(x)),
            Source::Measured(m) => m.eval(x).ok_or(OffTrack { x })?,
        };
        let w = self.scale * self.weight(x);
        Ok((w * y, w * z))
    }
}

/// The track under the wheelsets (longitudinal positions `offsets` from the car body centre)
/// at time `t`.
#[inline]
pub fn track_at(
    course: &Course,
    irregularity: &Irregularity,
    offsets: &[f64; 4],
    t: f64,
) -> Result<Track, OffTrack> {
    let mut track = Track {
        run: course.running(t),
        ..Track::default()
    };
    if !matches!(irregularity.source, Source::None) {
        let xc = course.distance(t);
        for w in 0..4 {
            let (y, z) = irregularity.at(xc + offsets[w])?;
            track.y[w] = y;
            track.z[w] = z;
        }
    }
    Ok(track)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn speed_distance_and_transition() {
        let c = Course {
            v: 50.0,
            ramp: 10.0,
            t_v: 2.0,
            x_v: 100.0,
            kappa: 1.0 / 1600.0,
            cant: 0.06,
            transition: 4.0,
            t_start: 0.0,
        };
        assert_eq!(c.speed(2.0), 50.0);
        assert!((c.speed(12.0) - 49.0).abs() < 1e-12);
        // ∫ from 2 to 12 of (50 − (t − 2)/10) dt = 500 − 5 = 495.
        assert!((c.distance(12.0) - 595.0).abs() < 1e-9);
        let r = c.running(1.0);
        assert!((r.kappa - 0.25 / 1600.0).abs() < 1e-15 && (r.cant - 0.015).abs() < 1e-15);
        assert_eq!(c.running(9.0).kappa, 1.0 / 1600.0);
    }

    #[test]
    fn measured_track_parsing_and_interpolation() {
        let t = MeasuredTrack::parse("x,y,z\n0,0,0\n10,0.001,-0.002\n# end\n").unwrap();
        assert_eq!(t.eval(5.0), Some((0.0005, -0.001)));
        assert_eq!(t.eval(10.5), None);
        let e = MeasuredTrack::parse("0,0,0\n5,1,SECRET\n").unwrap_err();
        assert!(
            e.starts_with("line 2: expected three numbers") && !e.contains("SECRET"),
            "{e}"
        );
        let e = MeasuredTrack::parse("0,0,0\n0,1,1\n").unwrap_err();
        assert!(e.contains("line 2: x must increase"), "{e}");
        let e = MeasuredTrack::parse("0,0,0\n1,inf,1\n").unwrap_err();
        assert!(e.contains("line 2: x, y and z must be finite"), "{e}");
    }
}
