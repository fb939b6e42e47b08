//! Scalar quantities of interest as the study file declares them (`[[qoi]]`): critical speed,
//! Sperling index, peak |signal|, signed minimum and maximum, peak-to-peak, final value,
//! evaluated on one run's time series; and the constant-speed critical speed
//! (`hunting_speed`), which needs runs of its own ([`crate::qoi::hunting_speed`]).

use serde::{Deserialize, Serialize};

use crate::qoi::critical_speed::CriticalSpeedError;
use crate::qoi::hunting_speed::{HuntingSpeedSpec, SearchMode};
use crate::qoi::sperling::{Direction, SperlingError, Statistic, Window};

/// A scalar quantity of interest computed from each run's time series (`[[qoi]]`, tagged by
/// `kind`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum QoiSpec {
    /// Speed at which an oscillation dies out on a speed ramp (see [`critical_speed`](crate::qoi::critical_speed::critical_speed)).
    CriticalSpeed {
        /// Name in reports.
        name: String,
        /// Oscillating signal (e.g. "Y").
        signal: String,
        /// Speed signal (e.g. "V").
        speed: String,
        /// Sliding window (s).
        #[serde(default = "default_window")]
        window: f64,
        /// Amplitude threshold (units of the signal).
        #[serde(default = "default_threshold")]
        threshold: f64,
        /// Exceedance limits: P(q > limit) is reported.
        #[serde(default)]
        limits: Vec<f64>,
        /// Limits below: P(q < limit) is reported.
        #[serde(default, skip_serializing_if = "Vec::is_empty")]
        limits_below: Vec<f64>,
    },
    /// Sperling ride index of an acceleration signal (see [`sperling_index`](crate::qoi::sperling::sperling_index)).
    Sperling {
        /// Name in reports.
        name: String,
        /// Acceleration signal (m/s²).
        signal: String,
        /// Weighting direction.
        #[serde(default)]
        direction: Direction,
        /// FFT segment length (s).
        #[serde(default = "default_segment")]
        segment: f64,
        /// Lowest frequency (Hz).
        #[serde(default = "default_fmin")]
        f_min: f64,
        /// Highest frequency (Hz).
        #[serde(default = "default_fmax")]
        f_max: f64,
        /// Initial transient left out (s).
        #[serde(default)]
        skip: f64,
        /// Window of each segment (default none). Left out of the serialized settings when
        /// default, so the study hash of existing studies is unchanged.
        #[serde(default, skip_serializing_if = "is_default")]
        window: Window,
        /// W of the record: the largest segment W (default) or their mean.
        #[serde(default, skip_serializing_if = "is_default")]
        statistic: Statistic,
        /// Exceedance limits.
        #[serde(default)]
        limits: Vec<f64>,
        /// Limits below: P(q < limit) is reported.
        #[serde(default, skip_serializing_if = "Vec::is_empty")]
        limits_below: Vec<f64>,
    },
    /// Largest |signal| over [from, to] (s).
    MaxAbs(WindowQoi),
    /// Smallest value of the signal (signed) over [from, to] (s): e.g. the least wheel–rail
    /// force, 0 when the wheel leaves the rail.
    Min(WindowQoi),
    /// Largest value of the signal (signed) over [from, to] (s).
    Max(WindowQoi),
    /// Peak-to-peak value, max − min of the signal over [from, to] (s): e.g. the ripple of a
    /// wheel–rail force as the wheel passes the sleepers.
    Range(WindowQoi),
    /// Value of a signal at the stop time.
    Final {
        /// Name in reports.
        name: String,
        /// Signal.
        signal: String,
        /// Exceedance limits.
        #[serde(default)]
        limits: Vec<f64>,
        /// Limits below: P(q < limit) is reported.
        #[serde(default, skip_serializing_if = "Vec::is_empty")]
        limits_below: Vec<f64>,
    },
    /// Constant-speed critical speed by bisection over runs of its own (see
    /// [`crate::qoi::hunting_speed`]): two quantities, `name` (lowest speed that keeps hunting)
    /// and `name_decay` (highest speed at which the disturbance dies out).
    HuntingSpeed(HuntingSpeedSpec),
}

/// Settings of a quantity over a window [from, to] (s) of one signal: the kinds `max_abs`,
/// `min`, `max` and `range`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WindowQoi {
    /// Name in reports.
    pub name: String,
    /// Signal.
    pub signal: String,
    /// Start of the interval (s).
    #[serde(default)]
    pub from: f64,
    /// End of the interval (s; default the stop time).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub to: Option<f64>,
    /// The value the quantity takes in a run the FMU ends before the stop time
    /// (fmi2Terminated: e.g. the Vehicle's derailment) instead of the point failing
    /// (every quantity of the study must then set it, and the study may store no
    /// series). Left out of the serialized settings when unset, so the study hash of
    /// existing studies is unchanged.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub if_ended: Option<f64>,
    /// Exceedance limits.
    #[serde(default)]
    pub limits: Vec<f64>,
    /// Limits below: P(q < limit) is reported.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub limits_below: Vec<f64>,
}

fn is_default<T: Default + PartialEq>(x: &T) -> bool {
    *x == T::default()
}

fn default_window() -> f64 {
    1.0
}
fn default_threshold() -> f64 {
    1e-4
}
fn default_segment() -> f64 {
    5.0
}
fn default_fmin() -> f64 {
    0.5
}
fn default_fmax() -> f64 {
    40.0
}

/// Settings of a quantity that make no sense.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("quantity '{name}': {problem}")]
pub struct InvalidQuantity {
    /// The quantity.
    pub name: String,
    /// What is wrong.
    pub problem: String,
}

/// Why a quantity could not be evaluated on a run.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum QoiError {
    /// The critical-speed detection refused the series.
    #[error(transparent)]
    CriticalSpeed(#[from] CriticalSpeedError),
    /// The Sperling index could not be computed.
    #[error(transparent)]
    Sperling(#[from] SperlingError),
    /// Fewer than two samples (no time step).
    #[error("fewer than two samples")]
    TooShort,
    /// No sample in the interval of a `max_abs`.
    #[error("no sample of {signal} in [{from}, {to}] s")]
    EmptyInterval {
        /// The signal.
        signal: String,
        /// Start (s).
        from: f64,
        /// End (s).
        to: f64,
    },
    /// The signal has no sample.
    #[error("{0} is empty")]
    EmptySignal(String),
    /// A quantity that is not computed from the study's run (`hunting_speed`).
    #[error("'{0}' is computed from runs of its own, not from the study's run")]
    NeedsOwnRuns(String),
}

/// What the model says of its variables, for the text of a quantity's definition
/// ([`QoiSpec::definition_with`]): the description of the quantity's (first) signal and the
/// unit of each variable. The default knows nothing (names and plain numbers only).
#[derive(Default)]
pub struct Words<'a> {
    /// The signal the description belongs to, and the description.
    pub description: Option<(&'a str, &'a str)>,
    /// The declared unit of a variable (`None`: not declared).
    pub unit: Option<&'a UnitOf<'a>>,
}

/// The declared unit of a variable by name (`None`: not declared).
pub type UnitOf<'a> = dyn Fn(&str) -> Option<String> + 'a;

impl Words<'_> {
    /// `signal`, followed by its description in parentheses if it is the described one.
    fn signal(&self, signal: &str) -> String {
        match self.description {
            Some((s, d)) if s == signal => format!("{signal} ({d})"),
            _ => signal.to_owned(),
        }
    }

    /// `x` in the unit of variable `of`: `0.0001 m`, or `0.0001` when it has none.
    fn value(&self, x: f64, of: &str) -> String {
        match self
            .unit
            .and_then(|u| u(of))
            .filter(|u| !u.is_empty() && u != "1")
        {
            Some(u) => format!("{x} {u}"),
            None => format!("{x}"),
        }
    }
}

impl QoiSpec {
    /// The name of the `[[qoi]]` entry (of its first quantity).
    pub fn name(&self) -> &str {
        match self {
            QoiSpec::CriticalSpeed { name, .. }
            | QoiSpec::Sperling { name, .. }
            | QoiSpec::Final { name, .. } => name,
            QoiSpec::MaxAbs(w) | QoiSpec::Min(w) | QoiSpec::Max(w) | QoiSpec::Range(w) => &w.name,
            QoiSpec::HuntingSpeed(h) => &h.name,
        }
    }

    /// The scalar quantities it yields, in the order they are stored: one, except
    /// `hunting_speed`'s two (`name`, `name_decay`).
    pub fn quantity_names(&self) -> Vec<String> {
        match self {
            QoiSpec::HuntingSpeed(h) => vec![h.name.clone(), h.decay_name()],
            q => vec![q.name().to_owned()],
        }
    }

    /// The FMU signals it reads from the study's run (`hunting_speed` reads its signal from
    /// its own runs only).
    pub fn signals(&self) -> Vec<&str> {
        match self {
            QoiSpec::CriticalSpeed { signal, speed, .. } => vec![signal, speed],
            QoiSpec::Sperling { signal, .. } | QoiSpec::Final { signal, .. } => vec![signal],
            QoiSpec::MaxAbs(w) | QoiSpec::Min(w) | QoiSpec::Max(w) | QoiSpec::Range(w) => {
                vec![&w.signal]
            }
            QoiSpec::HuntingSpeed(_) => Vec::new(),
        }
    }

    /// Exceedance limits (of each of its quantities).
    pub fn limits(&self) -> &[f64] {
        match self {
            QoiSpec::CriticalSpeed { limits, .. }
            | QoiSpec::Sperling { limits, .. }
            | QoiSpec::Final { limits, .. } => limits,
            QoiSpec::MaxAbs(w) | QoiSpec::Min(w) | QoiSpec::Max(w) | QoiSpec::Range(w) => &w.limits,
            QoiSpec::HuntingSpeed(h) => &h.limits,
        }
    }

    /// Limits below (of each of its quantities): P(q < limit) is reported.
    pub fn limits_below(&self) -> &[f64] {
        match self {
            QoiSpec::CriticalSpeed { limits_below, .. }
            | QoiSpec::Sperling { limits_below, .. }
            | QoiSpec::Final { limits_below, .. } => limits_below,
            QoiSpec::MaxAbs(w) | QoiSpec::Min(w) | QoiSpec::Max(w) | QoiSpec::Range(w) => {
                &w.limits_below
            }
            QoiSpec::HuntingSpeed(h) => &h.limits_below,
        }
    }

    /// The value it takes in a run the FMU ends before the stop time (`if_ended`; only the
    /// window kinds `max_abs`, `min`, `max`, `range` have the setting).
    pub(crate) fn if_ended(&self) -> Option<f64> {
        self.window().and_then(|w| w.if_ended)
    }

    /// The settings of a window kind (`max_abs`, `min`, `max`, `range`).
    pub(crate) fn window(&self) -> Option<&WindowQoi> {
        match self {
            QoiSpec::MaxAbs(w) | QoiSpec::Min(w) | QoiSpec::Max(w) | QoiSpec::Range(w) => Some(w),
            _ => None,
        }
    }

    /// The signal whose unit the quantity has (`None`: dimensionless, as the Sperling index).
    pub fn unit_signal(&self) -> Option<&str> {
        match self {
            QoiSpec::CriticalSpeed { speed, .. } => Some(speed),
            QoiSpec::Sperling { .. } => None,
            QoiSpec::Final { signal, .. } => Some(signal),
            QoiSpec::MaxAbs(w) | QoiSpec::Min(w) | QoiSpec::Max(w) | QoiSpec::Range(w) => {
                Some(&w.signal)
            }
            QoiSpec::HuntingSpeed(h) => Some(&h.speed_parameter),
        }
    }

    /// How the quantity is computed, every setting explicit (defaults included), with a
    /// line of text for the report (no description of the signal, no units: see
    /// [`Self::definition_with`]).
    pub fn definition(&self) -> QuantityDefinition {
        self.definition_with(&Words::default())
    }

    /// [`Self::definition`] with what the model says of its variables in the text: the
    /// description of the first signal after its name (`peak-to-peak (max − min) of a
    /// (Acceleration q'') over 0.5–2 s`) and the units of thresholds and speeds (`0.0001 m`,
    /// `to 0.02 m/s`). The sentence is built from its parts: a signal's name is never searched
    /// for in the text (a short name such as `a` occurs inside other words).
    pub fn definition_with(&self, words: &Words) -> QuantityDefinition {
        let mut settings = match serde_json::to_value(self) {
            Ok(serde_json::Value::Object(m)) => m,
            _ => serde_json::Map::new(),
        };
        let kind = settings
            .remove("kind")
            .and_then(|k| k.as_str().map(str::to_owned))
            .unwrap_or_default();
        settings.remove("name");
        let text = match self {
            QoiSpec::CriticalSpeed {
                signal,
                speed,
                window,
                threshold,
                ..
            } => format!(
                "critical speed (speed-ramp estimate, the paper's method): the {speed} at which \
                 the largest |{}| over a sliding {window} s window last exceeds {}",
                words.signal(signal),
                words.value(*threshold, signal)
            ),
            QoiSpec::Sperling {
                signal,
                direction,
                segment,
                f_min,
                f_max,
                skip,
                window,
                statistic,
                ..
            } => {
                settings.insert("window".into(), window.as_str().into());
                settings.insert("statistic".into(), statistic.as_str().into());
                let direction = match direction {
                    Direction::Vertical => "vertical",
                    Direction::Lateral => "lateral",
                };
                let window = match window {
                    Window::None => "no window",
                    Window::Hann => "Hann window",
                };
                let statistic = match statistic {
                    Statistic::Max => "the largest segment W",
                    Statistic::Mean => "the mean of the segment W",
                };
                format!(
                    "Sperling index of {}, {direction} weighting, {segment} s segments, \
                     {window}, {statistic}, {f_min}–{f_max} Hz, first {skip} s left out",
                    words.signal(signal)
                )
            }
            QoiSpec::MaxAbs(w) | QoiSpec::Min(w) | QoiSpec::Max(w) | QoiSpec::Range(w) => {
                let signal = words.signal(&w.signal);
                let what = match self {
                    QoiSpec::MaxAbs(_) => format!("largest |{signal}|"),
                    QoiSpec::Min(_) => format!("smallest value of {signal} (signed)"),
                    QoiSpec::Max(_) => format!("largest value of {signal} (signed)"),
                    _ => format!("peak-to-peak (max − min) of {signal}"),
                };
                let from = w.from;
                match w.to {
                    Some(to) => format!("{what} over {from}–{to} s"),
                    None => format!("{what} from {from} s to the end"),
                }
            }
            QoiSpec::Final { signal, .. } => format!("{} at the stop time", words.signal(signal)),
            QoiSpec::HuntingSpeed(h) => {
                let speed = |x: f64| words.value(x, &h.speed_parameter);
                let search = match h.speed_step {
                    Some(d) if h.mode == SearchMode::Continuation => format!(
                        "continuation on {} from {} down in steps of {} (not below {}), each \
                         stage of {} s from the state the one before left, refined to {}",
                        h.speed_parameter,
                        speed(h.high),
                        speed(d),
                        h.low,
                        h.duration,
                        speed(h.tolerance)
                    ),
                    _ => format!(
                        "bisection on {} over {}–{} (to {}) by runs of {} s",
                        h.speed_parameter,
                        h.low,
                        speed(h.high),
                        speed(h.tolerance),
                        h.duration
                    ),
                };
                format!(
                    "constant-speed critical speed: {search}; a run keeps hunting when max |{}| \
                     over its last {} s is at least {} ({} = lowest speed seen hunting, \
                     {}_decay = highest seen dying out)",
                    words.signal(&h.signal),
                    h.window,
                    words.value(h.threshold, &h.signal),
                    h.name,
                    h.name
                )
            }
        };
        let text = match self.if_ended() {
            Some(v) => format!("{text}; {v} in a run the FMU ends before the stop time"),
            None => text,
        };
        QuantityDefinition {
            kind,
            settings,
            text,
        }
    }

    /// Checks the settings for a run of `duration` seconds.
    pub fn validate(&self, duration: f64) -> Result<(), InvalidQuantity> {
        let problem = match self {
            QoiSpec::CriticalSpeed {
                window, threshold, ..
            } => {
                (!(*window > 0.0 && *threshold > 0.0)).then_some("window and threshold must be > 0")
            }
            QoiSpec::Sperling {
                segment,
                f_min,
                f_max,
                skip,
                ..
            } => {
                if !(*segment > 0.0 && *f_min > 0.0 && f_max > f_min && *skip >= 0.0) {
                    Some("segment > 0, 0 < f_min < f_max and skip >= 0 are needed")
                } else if *skip + *segment > duration + 1e-9 {
                    Some("skip + segment must fit within the run")
                } else {
                    None
                }
            }
            QoiSpec::MaxAbs(w) | QoiSpec::Min(w) | QoiSpec::Max(w) | QoiSpec::Range(w) => {
                if w.to.is_some_and(|t| t <= w.from) {
                    Some("`to` must be after `from`")
                } else if w.if_ended.is_some_and(|v| !v.is_finite()) {
                    Some("if_ended must be finite")
                } else {
                    None
                }
            }
            QoiSpec::Final { .. } => None,
            QoiSpec::HuntingSpeed(h) => {
                return match h.problem() {
                    Some(problem) => Err(InvalidQuantity {
                        name: h.name.clone(),
                        problem,
                    }),
                    None => self.check_limits(),
                }
            }
        };
        match problem {
            Some(p) => Err(InvalidQuantity {
                name: self.name().to_owned(),
                problem: p.to_owned(),
            }),
            None => self.check_limits(),
        }
    }

    /// Refuses settings that no run on the communication grid from `start` to `stop` (s) by
    /// `step` (s) can satisfy, so that the study is refused when it is read instead of every
    /// point failing: a Sperling `f_max` above the Nyquist frequency `0.5 / step`, a window
    /// (`from`, `to`) that holds no communication point.
    pub fn check_grid(&self, start: f64, stop: f64, step: f64) -> Result<(), InvalidQuantity> {
        let fail = |problem: String| {
            Err(InvalidQuantity {
                name: self.name().to_owned(),
                problem,
            })
        };
        match self {
            QoiSpec::Sperling { f_max, .. } if *f_max > 0.5 / step * (1.0 + 1e-12) => {
                fail(format!(
                    "f_max = {f_max} Hz is above the Nyquist frequency {} Hz of the communication \
                 step {step} s: lower f_max or use a smaller step",
                    0.5 / step
                ))
            }
            QoiSpec::MaxAbs(w) | QoiSpec::Min(w) | QoiSpec::Max(w) | QoiSpec::Range(w) => {
                let WindowQoi { from, to, .. } = w;
                let tol = 1e-9 * step;
                let to_t = to.unwrap_or(stop).min(stop);
                // The first communication point at or after `from`.
                let k = ((from - start) / step - 1e-9).ceil().max(0.0);
                let first = (start + k * step).min(stop);
                if first < *from - tol || first > to_t + tol {
                    return fail(format!(
                        "the window from {from} s to {} s holds no communication point of the run \
                         ({start} s to {stop} s by {step} s)",
                        to.map_or_else(|| format!("the stop time {stop}"), |t| t.to_string())
                    ));
                }
                Ok(())
            }
            _ => Ok(()),
        }
    }

    /// A warning when a Sperling quantity's `direction` contradicts the description of its
    /// signal (`description` gives a variable's modelDescription description): `lateral` on
    /// a signal described as vertical (and not lateral), or the reverse. The weighting
    /// differs (W 3.33 with the lateral weighting of a vertical acceleration, silently).
    pub fn direction_warning(
        &self,
        description: &dyn Fn(&str) -> Option<String>,
    ) -> Option<String> {
        let QoiSpec::Sperling {
            name,
            signal,
            direction,
            ..
        } = self
        else {
            return None;
        };
        let text = description(signal)?.to_lowercase();
        let (chosen, other) = match direction {
            Direction::Vertical => ("vertical", "lateral"),
            Direction::Lateral => ("lateral", "vertical"),
        };
        (text.contains(other) && !text.contains(chosen)).then(|| {
            format!(
                "quantity '{name}': direction = \"{chosen}\" (the {chosen} Sperling weighting) on \
                 {signal}, which the FMU describes as {other} (\"{}\"): W is then not a {chosen} \
                 ride index; set direction = \"{other}\" or pick a {chosen} acceleration",
                description(signal).unwrap_or_default()
            )
        })
    }

    fn check_limits(&self) -> Result<(), InvalidQuantity> {
        match self
            .limits()
            .iter()
            .chain(self.limits_below())
            .any(|l| !l.is_finite())
        {
            true => Err(InvalidQuantity {
                name: self.name().to_owned(),
                problem: "limits must be finite".to_owned(),
            }),
            false => Ok(()),
        }
    }
}

/// How a scalar quantity is computed from each run (`definition` in `summary.json`).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct QuantityDefinition {
    /// `kind` of the `[[qoi]]` entry.
    pub kind: String,
    /// Every setting, defaults included (e.g. the Sperling index's `signal`, `segment`,
    /// `window`, `statistic`).
    pub settings: serde_json::Map<String, serde_json::Value>,
    /// The same in words, e.g. `Sperling index of Zc_acc (<the FMU's description of it>),
    /// vertical weighting, 5 s segments, no window, the largest segment W, 0.5–40 Hz, first
    /// 1 s left out`.
    pub text: String,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::qoi::evaluate::{evaluate, Code};

    #[test]
    fn direction_is_typed_with_vertical_default() {
        let q: QoiSpec =
            toml::from_str("kind = \"sperling\"\nname = \"W\"\nsignal = \"a\"").unwrap();
        assert!(matches!(
            q,
            QoiSpec::Sperling {
                direction: Direction::Vertical,
                ..
            }
        ));
        let q: QoiSpec = toml::from_str(
            "kind = \"sperling\"\nname = \"W\"\nsignal = \"a\"\ndirection = \"lateral\"",
        )
        .unwrap();
        assert!(matches!(
            q,
            QoiSpec::Sperling {
                direction: Direction::Lateral,
                ..
            }
        ));
        let r: Result<QoiSpec, _> = toml::from_str(
            "kind = \"sperling\"\nname = \"W\"\nsignal = \"a\"\ndirection = \"sideways\"",
        );
        assert!(r.unwrap_err().to_string().contains("unknown variant"));
    }

    /// `direction = "lateral"` on a vertical carbody acceleration gave a lateral W
    /// without a word.
    #[test]
    fn a_lateral_sperling_on_a_vertical_signal_is_warned_about() {
        let describe = |s: &str| match s {
            "Zc_acc" => Some("Carbody vertical acceleration above the front bogie".to_owned()),
            "Ydd" => Some("Lateral acceleration of the bogie frame".to_owned()),
            _ => None,
        };
        let q = |signal: &str, direction: &str| -> QoiSpec {
            toml::from_str(&format!(
                "kind = \"sperling\"\nname = \"W\"\nsignal = \"{signal}\"\ndirection = \"{direction}\""
            ))
            .unwrap()
        };
        let w = q("Zc_acc", "lateral").direction_warning(&describe).unwrap();
        assert!(
            w.contains("quantity 'W'") && w.contains("describes as vertical"),
            "{w}"
        );
        let w = q("Ydd", "vertical").direction_warning(&describe).unwrap();
        assert!(w.contains("describes as lateral"), "{w}");
        assert_eq!(q("Zc_acc", "vertical").direction_warning(&describe), None);
        assert_eq!(q("Ydd", "lateral").direction_warning(&describe), None);
        // No description, or one that names neither direction: nothing to say.
        assert_eq!(q("a", "lateral").direction_warning(&describe), None);
    }

    #[test]
    fn invalid_settings_name_the_quantity() {
        let q: QoiSpec = toml::from_str(
            "kind = \"max_abs\"\nname = \"P\"\nsignal = \"a\"\nfrom = 2.0\nto = 1.0",
        )
        .unwrap();
        let e = q.validate(10.0).unwrap_err();
        assert!(e.to_string().starts_with("quantity 'P': "), "{e}");
        let q: QoiSpec =
            toml::from_str("kind = \"sperling\"\nname = \"W\"\nsignal = \"a\"\nskip = 6.0")
                .unwrap();
        assert!(q.validate(10.0).is_err());
        assert!(q.validate(11.0).is_ok());
    }

    /// A window quantity of signal `x` from `from` to `to` (s), no limits.
    fn window(name: &str, from: f64, to: Option<f64>) -> WindowQoi {
        WindowQoi {
            name: name.into(),
            signal: "x".into(),
            from,
            to,
            if_ended: None,
            limits: vec![],
            limits_below: vec![],
        }
    }

    #[test]
    fn max_abs_and_final() {
        let t = [0.0, 1.0, 2.0, 3.0];
        let x = [1.0, -4.0, 2.0, 0.5];
        let q = QoiSpec::MaxAbs(window("m", 1.5, None));
        assert_eq!(evaluate(&q, &t, |_| &x[..]).unwrap(), (2.0, Code::Ok));
        let q = QoiSpec::Range(window("r", 0.5, Some(2.5)));
        // Values at t = 1 and 2 only: the range is their difference, by hand.
        let (r, code) = evaluate(&q, &t, |_| &x[..]).unwrap();
        assert_eq!(code, Code::Ok);
        assert_eq!(r, (x[2] - x[1]).abs());
        let q = QoiSpec::Range(window("r", 10.0, None));
        assert!(evaluate(&q, &t, |_| &x[..]).is_err());
        let q = QoiSpec::Final {
            name: "f".into(),
            signal: "x".into(),
            limits: vec![],
            limits_below: vec![],
        };
        assert_eq!(evaluate(&q, &t, |_| &x[..]).unwrap(), (0.5, Code::Ok));
        let empty: [f64; 0] = [];
        assert_eq!(
            evaluate(&q, &empty, |_| &empty[..]).unwrap_err(),
            QoiError::EmptySignal("x".into())
        );
    }

    #[test]
    fn sperling_window_and_statistic_are_read_shown_and_hash_neutral() {
        let base = "kind = \"sperling\"\nname = \"W\"\nsignal = \"a\"";
        let q: QoiSpec = toml::from_str(base).unwrap();
        // Defaults are not serialized: studies written before keep their hash.
        let json = serde_json::to_value(&q).unwrap();
        assert!(json.get("window").is_none() && json.get("statistic").is_none());
        // ... but the definition states them.
        let d = q.definition();
        assert_eq!(d.kind, "sperling");
        assert_eq!(d.settings["window"], "none");
        assert_eq!(d.settings["statistic"], "max");
        assert_eq!(d.settings["segment"], 5.0);
        assert!(
            d.text
                .contains("5 s segments, no window, the largest segment W"),
            "{}",
            d.text
        );
        let q: QoiSpec = toml::from_str(&format!(
            "{base}\nwindow = \"hann\"\nstatistic = \"mean\"\nsegment = 1.0"
        ))
        .unwrap();
        assert!(q
            .definition()
            .text
            .contains("1 s segments, Hann window, the mean"));
        assert!(toml::from_str::<QoiSpec>(&format!("{base}\nwindow = \"hamming\"")).is_err());
        // The mean of two segments of different amplitude lies below their maximum.
        let dt = 0.01;
        let times: Vec<f64> = (0..1000).map(|k| k as f64 * dt).collect();
        let a: Vec<f64> = times
            .iter()
            .map(|t| {
                let amp = if *t < 5.0 { 0.1 } else { 0.2 };
                amp * (2.0 * std::f64::consts::PI * t).sin()
            })
            .collect();
        let (mean, _) = evaluate(&q, &times, |_| &a[..]).unwrap();
        let q_max: QoiSpec = toml::from_str(&format!("{base}\nwindow = \"hann\"")).unwrap();
        let (max, _) = evaluate(&q_max, &times, |_| &a[..]).unwrap();
        assert!(mean < max, "{mean} {max}");
    }

    #[test]
    fn a_one_letter_signal_is_described_after_its_name_not_inside_a_word() {
        // The description was put after the first "a" of the sentence, the
        // one inside "peak": "pea (Acceleration q'')k-to-peak (max − min) of a over 0.5–2 s".
        let q: QoiSpec = toml::from_str(
            "kind = \"range\"\nname = \"a_range\"\nsignal = \"a\"\nfrom = 0.5\nto = 2.0",
        )
        .unwrap();
        let unit = |v: &str| (v == "a").then(|| "m/s2".to_owned());
        let words = Words {
            description: Some(("a", "Acceleration q''")),
            unit: Some(&unit),
        };
        assert_eq!(
            q.definition_with(&words).text,
            "peak-to-peak (max − min) of a (Acceleration q'') over 0.5–2 s"
        );
        assert_eq!(
            q.definition().text,
            "peak-to-peak (max − min) of a over 0.5–2 s"
        );
        // `x` sits inside "max"; `V` and `Y` beside other capitals.
        let q: QoiSpec =
            toml::from_str("kind = \"max_abs\"\nname = \"x_max\"\nsignal = \"x\"").unwrap();
        let words = Words {
            description: Some(("x", "track position")),
            unit: None,
        };
        assert_eq!(
            q.definition_with(&words).text,
            "largest |x (track position)| from 0 s to the end"
        );
        let q: QoiSpec = toml::from_str(
            "kind = \"critical_speed\"\nname = \"v_cr\"\nsignal = \"a\"\nspeed = \"V\"",
        )
        .unwrap();
        let unit = |v: &str| Some(if v == "V" { "m/s" } else { "m" }.to_owned());
        let words = Words {
            description: Some(("a", "lateral displacement")),
            unit: Some(&unit),
        };
        assert_eq!(
            q.definition_with(&words).text,
            "critical speed (speed-ramp estimate, the paper's method): the V at which the \
             largest |a (lateral displacement)| over a sliding 1 s window last exceeds 0.0001 m"
        );
    }
}
