//! Plot axes: finite data ranges, 1-2-5 tick steps, linear and logarithmic axes with labels.

/// Approximate advance of one character of 11 px sans-serif text (tick labels).
pub(super) const TICK_CHAR_W: f64 = 6.4;
/// Values beyond this magnitude are clamped when choosing axis ranges.
const HUGE: f64 = 1e300;
/// Most intervals between major ticks on a plot axis (5–8 ticks in practice).
const AXIS_INTERVALS: usize = 8;

/// (min, max) of the finite values (positive only if `positive`), clamped to ±1e300.
pub(crate) fn finite_range(
    values: impl IntoIterator<Item = f64>,
    positive: bool,
) -> Option<(f64, f64)> {
    values
        .into_iter()
        .filter(|v| v.is_finite() && (!positive || *v > 0.0))
        .map(|v| v.clamp(-HUGE, HUGE))
        .fold(None, |acc, v| match acc {
            None => Some((v, v)),
            Some((a, b)) => Some((v.min(a), v.max(b))),
        })
}

/// Widens an empty or zero-width linear range to something drawable.
fn widen_linear(range: Option<(f64, f64)>) -> (f64, f64) {
    match range {
        None => (0.0, 1.0),
        Some((lo, hi)) if hi - lo <= lo.abs().max(hi.abs()) * 1e-12 => {
            let h = if lo == 0.0 { 1.0 } else { lo.abs() * 0.1 };
            (lo - h, hi + h)
        }
        Some(r) => r,
    }
}

/// A 1-2-5 step `mantissa × 10^exp`.
#[derive(Debug, Clone, Copy)]
struct Step {
    mantissa: f64,
    exp: i32,
}

impl Step {
    fn value(self) -> f64 {
        scale10(self.mantissa, self.exp)
    }

    /// Multiples of the step within `[lo, hi]` (with a small tolerance).
    fn ticks(self, lo: f64, hi: f64) -> Vec<f64> {
        let step = self.value();
        let eps = 1e-9;
        let k0 = (lo / step - eps).ceil();
        let k1 = (hi / step + eps).floor();
        if !(k0.is_finite() && k1.is_finite()) || k1 < k0 || k1 - k0 > 1000.0 {
            return Vec::new();
        }
        let mut out = Vec::new();
        let mut k = k0;
        while k <= k1 {
            // k × mantissa is an exact small integer; one scaling by 10^exp rounds once.
            out.push(scale10(k * self.mantissa, self.exp) + 0.0);
            k += 1.0;
        }
        out
    }

    /// Decimal places needed to print multiples of this step.
    fn decimals(self) -> usize {
        if self.exp >= 0 {
            0
        } else {
            (-self.exp) as usize
        }
    }
}

/// `m × 10^e`, rounded once when `|e| <= 22` (powers of ten up to 1e22 are exact).
fn scale10(m: f64, e: i32) -> f64 {
    if (0..=22).contains(&e) {
        m * 10f64.powi(e)
    } else if (-22..0).contains(&e) {
        m / 10f64.powi(-e)
    } else {
        m * 10f64.powi(e)
    }
}

fn nice_step(lo: f64, hi: f64, max_intervals: usize) -> Option<Step> {
    let range = (hi - lo).abs();
    if !range.is_finite() || range <= 0.0 {
        return None;
    }
    let raw = range / max_intervals.max(1) as f64;
    let mut exp = raw.log10().floor() as i32;
    let norm = raw / 10f64.powi(exp);
    let mantissa = if norm <= 1.0 + 1e-9 {
        1.0
    } else if norm <= 2.0 + 1e-9 {
        2.0
    } else if norm <= 5.0 + 1e-9 {
        5.0
    } else {
        exp += 1;
        1.0
    };
    Some(Step { mantissa, exp })
}

/// One axis of a plot: a data range mapped to a pixel range, with labelled major ticks.
#[derive(Debug, Clone)]
pub(crate) struct Axis {
    pub lo: f64,
    pub hi: f64,
    pub log: bool,
    pub ticks: Vec<f64>,
    pub labels: Vec<String>,
    /// Unlabelled minor ticks (log axes).
    pub minor: Vec<f64>,
}

impl Axis {
    /// A linear axis over exactly the data range.
    pub fn linear_exact(range: Option<(f64, f64)>) -> Self {
        let (lo, hi) = widen_linear(range);
        Self::linear(lo, hi)
    }

    /// A linear axis over the data range padded by 5 % at each end (a bound at 0 stays).
    pub fn linear_padded(range: Option<(f64, f64)>) -> Self {
        let (lo, hi) = widen_linear(range);
        let pad = 0.05 * (hi - lo);
        let lo = if lo == 0.0 { lo } else { lo - pad };
        let hi = if hi == 0.0 { hi } else { hi + pad };
        Self::linear(lo, hi)
    }

    pub(super) fn linear(lo: f64, hi: f64) -> Self {
        let step = nice_step(lo, hi, AXIS_INTERVALS);
        let ticks = step.map(|s| s.ticks(lo, hi)).unwrap_or_default();
        let labels = match step {
            Some(s) => format_linear_labels(&ticks, s),
            None => Vec::new(),
        };
        Self {
            lo,
            hi,
            log: false,
            ticks,
            labels,
            minor: Vec::new(),
        }
    }

    /// A linear axis of whole numbers over the data range, half a unit beyond each end: a
    /// tick at every integer (at most 20, else at 1-2-5 multiples), labelled without decimals.
    pub fn integers(range: Option<(f64, f64)>) -> Self {
        let (lo, hi) = range.unwrap_or((0.0, 1.0));
        let (lo, hi) = (lo.floor() - 0.5, hi.ceil() + 0.5);
        let mut axis = Self::linear(lo, hi);
        let every = nice_step(0.0, hi - lo, 20).map_or(1.0, |s| s.value().max(1.0).round());
        let (first, last) = (lo.ceil() as i64, hi.floor() as i64);
        let every = every as i64;
        axis.ticks = (first..=last)
            .filter(|t| t.rem_euclid(every) == 0)
            .map(|t| t as f64)
            .collect();
        axis.labels = axis.ticks.iter().map(|t| format!("{t:.0}")).collect();
        axis.minor.clear();
        axis
    }

    /// A log10 axis over a positive range; `extend` widens it to whole decades.
    pub fn log(range: Option<(f64, f64)>, extend: bool) -> Self {
        let (mut lo, mut hi) = range.unwrap_or((1.0, 10.0));
        if !(lo > 0.0 && hi > 0.0) {
            (lo, hi) = (1.0, 10.0);
        }
        if hi / lo < 1.0 + 1e-9 {
            (lo, hi) = (lo / 10.0, hi * 10.0);
        }
        let (e0, e1) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
        if extend {
            lo = scale10(1.0, e0);
            hi = scale10(1.0, e1);
        }
        let decades = (e1 - e0).max(1);
        let every = (decades + 7) / 8;
        // Plain decimals if every decade label is short, else 1eN for all.
        let plain = e0 >= -4 && e1 <= 5;
        let in_range = |v: f64| v >= lo * (1.0 - 1e-9) && v <= hi * (1.0 + 1e-9);
        let mut ticks = Vec::new();
        let mut labels = Vec::new();
        let mut minor = Vec::new();
        for e in e0..=e1 {
            let v = scale10(1.0, e);
            if (e - e0) % every == 0 && in_range(v) {
                ticks.push(v);
                labels.push(if plain {
                    format!("{v}")
                } else {
                    format!("1e{e}")
                });
            }
            if decades <= 6 {
                minor.extend((2..10).map(|m| m as f64 * v).filter(|&m| in_range(m)));
            }
        }
        if ticks.len() < 2 {
            // Less than a decade: linear 1-2-5 ticks placed on the log scale.
            let lin = Self::linear(lo, hi);
            for (t, l) in lin.ticks.into_iter().zip(lin.labels) {
                if t > 0.0 && !ticks.contains(&t) {
                    ticks.push(t);
                    labels.push(l);
                }
            }
            minor.clear();
        }
        Self {
            lo,
            hi,
            log: true,
            ticks,
            labels,
            minor,
        }
    }

    /// Position of `v` on the axis as a fraction of its length (0 at `lo`, 1 at `hi`).
    pub fn frac(&self, v: f64) -> f64 {
        if self.log {
            let (a, b) = (self.lo.log10(), self.hi.log10());
            (v.log10() - a) / (b - a)
        } else {
            (v - self.lo) / (self.hi - self.lo)
        }
    }

    /// Whether `v` can be placed on this axis.
    pub fn accepts(&self, v: f64) -> bool {
        v.is_finite() && (!self.log || v > 0.0)
    }

    /// Width in characters of the longest tick label.
    pub fn label_chars(&self) -> usize {
        self.labels
            .iter()
            .map(|l| l.chars().count())
            .max()
            .unwrap_or(1)
    }
}

fn format_linear_labels(ticks: &[f64], step: Step) -> Vec<String> {
    let max = ticks.iter().fold(0.0f64, |m, t| m.max(t.abs()));
    let sci = step.exp < -4 || max >= 1e6;
    ticks
        .iter()
        .map(|&t| {
            if t == 0.0 {
                "0".to_string()
            } else if sci {
                format!("{t:e}")
            } else {
                format!("{t:.*}", step.decimals())
            }
        })
        .collect()
}

/// (Tests) Tick positions with a 1-2-5 step covering `[lo, hi]` with at most `max_intervals`
/// intervals (at least 1), e.g. `(0, 5, 6)` → 0, 1, …, 5 and `(0, 0.1, 6)` → 0, 0.02, …, 0.1.
/// Ticks are the nearest doubles to the decimal values. Non-finite bounds or a zero-width
/// range give the bounds themselves (deduplicated, finite only).
#[cfg(test)]
pub(crate) fn nice_ticks(lo: f64, hi: f64, max_intervals: usize) -> Vec<f64> {
    nice_step(lo, hi, max_intervals)
        .map(|s| s.ticks(lo.min(hi), lo.max(hi)))
        .unwrap_or_else(|| {
            let mut v: Vec<f64> = [lo.min(hi), lo.max(hi)]
                .into_iter()
                .filter(|v| v.is_finite())
                .collect();
            v.dedup();
            v
        })
}
