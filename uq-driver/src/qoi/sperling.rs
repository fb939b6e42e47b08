//! Sperling ride index (Wertungsziffer) of a carbody acceleration record.
//!
//! ```text
//! W_i = 0.896 (A_i³ F(f_i) / f_i)^0.1      A_i in cm/s², f_i in Hz  (= 7.08 (A³F/f)^0.1, A in g)
//! W   = (Σ_i W_i^10)^0.1 = 0.896 (Σ_i A_i³ F(f_i)/f_i)^0.1
//! ```
//!
//! The record is cut into consecutive segments of fixed length (GB/T 5599-2019: 5 s; a
//! trailing piece shorter than a segment is not used). For each segment the single-sided
//! amplitude spectrum `A_i = 2|X_i|/Σ_n w_n`, `X_i = Σ_n w_n a_n e^{−2πi·i·n/N_s}`, is
//! evaluated at every DFT line `f_i = i/(N_s Δt)` in `[f_min, f_max]` (0.5–40 Hz), by a direct
//! real DFT over a cosine/sine table: O(N_s) per line, only the lines that are used.
//!
//! Window `w` ([`Window`]): none (`w_n = 1`, the default, `A_i = 2|X_i|/N_s`) or the periodic
//! Hann window `w_n = ½ (1 − cos 2πn/N_s)` with the amplitude (coherent-gain) correction
//! `Σ w_n = N_s/2`: a sinusoid on a DFT line keeps its amplitude on that line and puts half of
//! it on each neighbouring line; leakage from frequencies between lines falls off as 1/f³
//! instead of 1/f.
//!
//! Frequency weighting F(f):
//! - vertical: 0.325 f² (f < 5.9 Hz), 400/f² (5.9–20 Hz), 1 (f ≥ 20 Hz);
//! - lateral:  0.8 f² (f < 5.4 Hz), 650/f² (5.4–26 Hz), 1 (f ≥ 26 Hz).
//!
//! The result lists W of every segment, their maximum and their mean. "The" W of the record,
//! [`SperlingResult::w`], is the maximum over segments: the conservative reading for a limit
//! check such as W < 2.5 (GB 5599 passenger cars: < 2.5 excellent, 2.5–2.75 good, 2.75–3.0
//! acceptable). The mean is reported beside it.
//!
//! Check: a 1 Hz sinusoid of amplitude 0.1 m/s² gives W = 0.896 (10³ · 0.325)^0.1 = 1.60.

/// Direction of the acceleration (selects the weighting F); `"vertical"` or `"lateral"` in files.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Direction {
    /// Vertical weighting.
    #[default]
    Vertical,
    /// Lateral weighting.
    Lateral,
}

/// Window applied to each segment before its spectrum; `"none"` or `"hann"` in files.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Window {
    /// No window (rectangular), the default.
    #[default]
    None,
    /// Periodic Hann window with amplitude correction.
    Hann,
}

impl Window {
    /// `"none"` or `"hann"`.
    pub fn as_str(self) -> &'static str {
        match self {
            Window::None => "none",
            Window::Hann => "hann",
        }
    }

    /// The weights of an `ns`-sample segment and their sum.
    fn weights(self, ns: usize) -> (Vec<f64>, f64) {
        match self {
            Window::None => (vec![1.0; ns], ns as f64),
            Window::Hann => {
                let w: Vec<f64> = (0..ns)
                    .map(|n| 0.5 - 0.5 * (2.0 * std::f64::consts::PI * n as f64 / ns as f64).cos())
                    .collect();
                // The periodic Hann window sums to exactly N/2.
                (w, 0.5 * ns as f64)
            }
        }
    }
}

/// Which W of the segments is the W of the record; `"max"` or `"mean"` in files.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Statistic {
    /// The largest segment W (the conservative reading for a limit), the default.
    #[default]
    Max,
    /// The mean of the segment W.
    Mean,
}

impl Statistic {
    /// `"max"` or `"mean"`.
    pub fn as_str(self) -> &'static str {
        match self {
            Statistic::Max => "max",
            Statistic::Mean => "mean",
        }
    }
}

/// Evaluation settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SperlingSettings {
    /// Direction.
    pub direction: Direction,
    /// Window of each segment.
    pub window: Window,
    /// Segment length (s); default 5 s (GB/T 5599-2019).
    pub segment_length_s: f64,
    /// Lowest frequency used (Hz); default 0.5.
    pub f_min: f64,
    /// Highest frequency used (Hz); default 40.
    pub f_max: f64,
}

impl Default for SperlingSettings {
    fn default() -> Self {
        Self {
            direction: Direction::Vertical,
            window: Window::None,
            segment_length_s: 5.0,
            f_min: 0.5,
            f_max: 40.0,
        }
    }
}

/// The index of a record.
#[derive(Clone, Debug, PartialEq)]
pub struct SperlingResult {
    /// W of each segment, in order.
    pub per_segment: Vec<f64>,
    /// Largest W over the segments: the W of the record.
    pub w: f64,
    /// Mean W over the segments.
    pub mean: f64,
    /// Samples per segment.
    pub samples_per_segment: usize,
    /// Segment length actually used, samples × Δt (s).
    pub segment_length_s: f64,
    /// Samples at the end of the record that fill no whole segment (not used).
    pub unused_samples: usize,
}

/// Why an index could not be computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SperlingError {
    /// Δt is not finite and positive.
    #[error("sample interval dt = {0} s must be finite and > 0")]
    InvalidStep(f64),
    /// Settings out of range.
    #[error("invalid Sperling settings: {0}")]
    InvalidSettings(String),
    /// The record holds no whole segment.
    #[error(
        "the record has {samples} samples, fewer than one segment of {needed} ({segment_s} s)"
    )]
    TooShort {
        /// Samples in the record.
        samples: usize,
        /// Samples per segment.
        needed: usize,
        /// Segment length (s).
        segment_s: f64,
    },
    /// A sample is NaN or infinite.
    #[error("acceleration sample {index} is not finite ({value})")]
    NonFinite {
        /// Index of the sample.
        index: usize,
        /// Its value.
        value: f64,
    },
    /// f_max lies above the Nyquist frequency of the record.
    #[error("f_max = {f_max} Hz is above the Nyquist frequency {nyquist} Hz of dt; sample faster")]
    AboveNyquist {
        /// Requested upper frequency (Hz).
        f_max: f64,
        /// 1/(2 dt) (Hz).
        nyquist: f64,
    },
}

/// Sperling weighting F(f) at frequency `f` (Hz).
pub fn weighting(direction: Direction, f: f64) -> f64 {
    match direction {
        Direction::Vertical => {
            if f < 5.9 {
                0.325 * f * f
            } else if f < 20.0 {
                400.0 / (f * f)
            } else {
                1.0
            }
        }
        Direction::Lateral => {
            if f < 5.4 {
                0.8 * f * f
            } else if f < 26.0 {
                650.0 / (f * f)
            } else {
                1.0
            }
        }
    }
}

/// Checks the record and the settings; returns the samples per segment.
fn samples_per_segment(
    accel: &[f64],
    dt: f64,
    s: &SperlingSettings,
) -> Result<usize, SperlingError> {
    if !(dt.is_finite() && dt > 0.0) {
        return Err(SperlingError::InvalidStep(dt));
    }
    if !(s.segment_length_s.is_finite() && s.segment_length_s > 0.0) {
        return Err(SperlingError::InvalidSettings(format!(
            "segment_length_s = {} must be finite and > 0",
            s.segment_length_s
        )));
    }
    if !(s.f_min.is_finite() && s.f_max.is_finite() && s.f_min > 0.0 && s.f_max > s.f_min) {
        return Err(SperlingError::InvalidSettings(format!(
            "need 0 < f_min < f_max, got f_min = {} Hz, f_max = {} Hz",
            s.f_min, s.f_max
        )));
    }
    let nyquist = 0.5 / dt;
    if s.f_max > nyquist * (1.0 + 1e-12) {
        return Err(SperlingError::AboveNyquist {
            f_max: s.f_max,
            nyquist,
        });
    }
    if let Some((index, &value)) = accel.iter().enumerate().find(|(_, a)| !a.is_finite()) {
        return Err(SperlingError::NonFinite { index, value });
    }
    let ns = (s.segment_length_s / dt).round() as usize;
    if ns < 2 || accel.len() < ns {
        return Err(SperlingError::TooShort {
            samples: accel.len(),
            needed: ns.max(2),
            segment_s: s.segment_length_s,
        });
    }
    Ok(ns)
}

/// The DFT lines `i_lo..=i_hi` of one segment and their spacing `df` (Hz).
struct Lines {
    i_lo: usize,
    i_hi: usize,
    df: f64,
    /// cos and sin of 2π m / N_s, m = 0..N_s.
    table: Vec<(f64, f64)>,
    /// Window weights and their sum.
    window: Vec<f64>,
    window_sum: f64,
}

impl Lines {
    fn new(ns: usize, dt: f64, s: &SperlingSettings) -> Lines {
        let df = 1.0 / (ns as f64 * dt);
        let tol = 1e-9 * df;
        let table = (0..ns)
            .map(|m| {
                let a = 2.0 * std::f64::consts::PI * m as f64 / ns as f64;
                (a.cos(), a.sin())
            })
            .collect();
        let (window, window_sum) = s.window.weights(ns);
        Lines {
            i_lo: ((s.f_min - tol) / df).ceil().max(1.0) as usize,
            i_hi: (((s.f_max + tol) / df).floor() as usize).min(ns / 2),
            df,
            table,
            window,
            window_sum,
        }
    }

    /// W of one segment of `table.len()` samples.
    fn segment_w(&self, seg: &[f64], direction: Direction) -> f64 {
        let ns = self.table.len();
        let windowed: Vec<f64> = seg.iter().zip(&self.window).map(|(a, w)| a * w).collect();
        let mut sum = 0.0;
        for i in self.i_lo..=self.i_hi {
            let (mut re, mut im) = (0.0, 0.0);
            let mut idx = 0usize;
            for &a in &windowed {
                let (c, sn) = self.table[idx];
                re += a * c;
                im -= a * sn;
                idx += i;
                if idx >= ns {
                    idx -= ns;
                }
            }
            let scale = if 2 * i == ns { 1.0 } else { 2.0 };
            let amp_cm = 100.0 * scale * (re * re + im * im).sqrt() / self.window_sum;
            let f = i as f64 * self.df;
            sum += amp_cm.powi(3) * weighting(direction, f) / f;
        }
        0.896 * sum.powf(0.1)
    }
}

/// Sperling index of the acceleration record `accel` (m/s²) sampled every `dt` (s).
pub fn sperling_index(
    accel: &[f64],
    dt: f64,
    settings: &SperlingSettings,
) -> Result<SperlingResult, SperlingError> {
    let ns = samples_per_segment(accel, dt, settings)?;
    let lines = Lines::new(ns, dt, settings);
    let n_seg = accel.len() / ns;
    let per_segment: Vec<f64> = accel
        .chunks_exact(ns)
        .map(|seg| lines.segment_w(seg, settings.direction))
        .collect();
    let w = per_segment.iter().copied().fold(0.0, f64::max);
    let mean = per_segment.iter().sum::<f64>() / n_seg as f64;
    Ok(SperlingResult {
        per_segment,
        w,
        mean,
        samples_per_segment: ns,
        segment_length_s: ns as f64 * dt,
        unused_samples: accel.len() - n_seg * ns,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn sine(f: f64, amp: f64, dt: f64, t_end: f64, phase: f64) -> Vec<f64> {
        let n = (t_end / dt).round() as usize;
        (0..n)
            .map(|k| amp * (2.0 * PI * f * k as f64 * dt + phase).sin())
            .collect()
    }

    /// W of one sinusoid by hand: 0.896 (A_cm³ F / f)^0.1.
    fn by_hand(amp_ms2: f64, f: f64, weight: f64) -> f64 {
        0.896 * ((100.0 * amp_ms2).powi(3) * weight / f).powf(0.1)
    }

    #[test]
    fn one_hertz_check_of_models_md() {
        let r =
            sperling_index(&sine(1.0, 0.1, 0.01, 10.0, 0.3), 0.01, &Default::default()).unwrap();
        assert_eq!(r.per_segment.len(), 2);
        assert_eq!(r.samples_per_segment, 500);
        assert!((r.w - 1.60).abs() < 0.005, "W = {}", r.w);
        let exact = 0.896 * (1000.0f64 * 0.325).powf(0.1);
        for w in &r.per_segment {
            assert!((w - exact).abs() < 1e-9, "{w} vs {exact}");
        }
        // The same with A in g and the 7.08 constant (g = 9.81 m/s²), to 0.1 %.
        let in_g = 7.08 * ((0.1f64 / 9.81).powi(3) * 0.325 / 1.0).powf(0.1);
        assert!((r.w / in_g - 1.0).abs() < 1e-3);
        assert_eq!(r.mean, r.w);
    }

    #[test]
    fn single_frequencies_by_hand() {
        let dt = 0.002;
        let cases = [
            // (direction, f, amplitude, F(f) by hand)
            (Direction::Vertical, 10.0, 0.5, 400.0 / 100.0),
            (Direction::Vertical, 30.0, 0.3, 1.0),
            (Direction::Vertical, 3.0, 0.2, 0.325 * 9.0),
            (Direction::Lateral, 2.0, 0.15, 0.8 * 4.0),
            (Direction::Lateral, 10.0, 0.2, 650.0 / 100.0),
            (Direction::Lateral, 30.0, 0.2, 1.0),
        ];
        for (direction, f, amp, weight) in cases {
            let settings = SperlingSettings {
                direction,
                ..Default::default()
            };
            let r = sperling_index(&sine(f, amp, dt, 5.0, 1.0), dt, &settings).unwrap();
            let expected = by_hand(amp, f, weight);
            assert!(
                (r.w - expected).abs() < 1e-9 * expected,
                "{direction:?} {f} Hz: {} vs {expected}",
                r.w
            );
        }
    }

    /// The sum of two signals, sample by sample.
    fn added(a: &[f64], b: &[f64]) -> Vec<f64> {
        a.iter().zip(b).map(|(x, y)| x + y).collect()
    }

    #[test]
    fn two_lines_combine_as_the_tenth_power_sum() {
        let dt = 0.005;
        let a = added(&sine(1.0, 0.1, dt, 5.0, 0.0), &sine(8.0, 0.3, dt, 5.0, 0.5));
        let r = sperling_index(&a, dt, &Default::default()).unwrap();
        let (w1, w2) = (by_hand(0.1, 1.0, 0.325), by_hand(0.3, 8.0, 400.0 / 64.0));
        let expected = (w1.powi(10) + w2.powi(10)).powf(0.1);
        assert!((r.w - expected).abs() < 1e-9, "{} vs {expected}", r.w);
    }

    #[test]
    fn lines_outside_the_band_do_not_count() {
        let dt = 0.005;
        // 0.4 Hz is below f_min, 45 Hz above f_max: nothing is left.
        let a = added(
            &sine(0.4, 1.0, dt, 5.0, 0.0),
            &sine(45.0, 1.0, dt, 5.0, 0.0),
        );
        let r = sperling_index(&a, dt, &Default::default()).unwrap();
        assert!(r.w < 1e-3, "{}", r.w);
    }

    #[test]
    fn zero_signal_gives_zero_and_segments_are_reported() {
        let r = sperling_index(&vec![0.0; 1234], 0.01, &Default::default()).unwrap();
        assert_eq!(r.w, 0.0);
        assert_eq!(r.per_segment, vec![0.0, 0.0]);
        assert_eq!(r.unused_samples, 234);
        assert!((r.segment_length_s - 5.0).abs() < 1e-12);
    }

    #[test]
    fn the_worst_segment_is_the_record_w() {
        let dt = 0.01;
        let mut a = sine(1.0, 0.1, dt, 5.0, 0.0);
        a.extend(sine(1.0, 0.2, dt, 5.0, 0.0));
        let r = sperling_index(&a, dt, &Default::default()).unwrap();
        assert!(r.per_segment[1] > r.per_segment[0]);
        assert_eq!(r.w, r.per_segment[1]);
        assert!((r.mean - 0.5 * (r.per_segment[0] + r.per_segment[1])).abs() < 1e-12);
    }

    #[test]
    fn wrong_inputs_are_errors() {
        let s = SperlingSettings::default();
        let a = vec![0.0; 1000];
        assert!(matches!(
            sperling_index(&a, 0.0, &s),
            Err(SperlingError::InvalidStep(_))
        ));
        assert!(matches!(
            sperling_index(&a, f64::NAN, &s),
            Err(SperlingError::InvalidStep(_))
        ));
        assert!(matches!(
            sperling_index(&a, 0.001, &s),
            Err(SperlingError::TooShort { needed: 5000, .. })
        ));
        assert!(matches!(
            sperling_index(&[], 0.01, &s),
            Err(SperlingError::TooShort { .. })
        ));
        let mut bad = a.clone();
        bad[7] = f64::NAN;
        assert!(matches!(
            sperling_index(&bad, 0.01, &s),
            Err(SperlingError::NonFinite { index: 7, .. })
        ));
        assert!(matches!(
            sperling_index(&a, 0.02, &s),
            Err(SperlingError::AboveNyquist { .. })
        ));
        for bad in [
            SperlingSettings { f_min: 0.0, ..s },
            SperlingSettings { f_min: 50.0, ..s },
            SperlingSettings {
                segment_length_s: -1.0,
                ..s
            },
        ] {
            assert!(matches!(
                sperling_index(&a, 0.001, &bad),
                Err(SperlingError::InvalidSettings(_))
            ));
        }
    }

    /// W of a record by the definition: every line's amplitude from a direct DFT of the
    /// windowed segment (angles computed afresh, no table), written out here.
    fn by_definition(a: &[f64], dt: f64, window: Window) -> f64 {
        let ns = a.len();
        let w: Vec<f64> = (0..ns)
            .map(|n| match window {
                Window::None => 1.0,
                Window::Hann => (PI * n as f64 / ns as f64).sin().powi(2),
            })
            .collect();
        let gain: f64 = w.iter().sum();
        let df = 1.0 / (ns as f64 * dt);
        let mut sum = 0.0;
        for i in 1..=ns / 2 {
            let f = i as f64 * df;
            if !(0.5 - 1e-9..=40.0 + 1e-9).contains(&f) {
                continue;
            }
            let (mut re, mut im) = (0.0, 0.0);
            for n in 0..ns {
                let phi = 2.0 * PI * (i * n) as f64 / ns as f64;
                re += w[n] * a[n] * phi.cos();
                im -= w[n] * a[n] * phi.sin();
            }
            let amp_cm = 100.0 * 2.0 * (re * re + im * im).sqrt() / gain;
            sum += amp_cm.powi(3) * weighting(Direction::Vertical, f) / f;
        }
        0.896 * sum.powf(0.1)
    }

    #[test]
    fn hann_window_on_a_sinusoid() {
        let dt = 0.01;
        let hann = SperlingSettings {
            window: Window::Hann,
            ..Default::default()
        };
        // 3 Hz in 5 s segments is line 15 (df = 0.2 Hz): the Hann window keeps the amplitude
        // on that line and puts half of it on lines 14 and 16, in closed form.
        let a = sine(3.0, 0.2, dt, 5.0, 0.4);
        let r = sperling_index(&a, dt, &hann).unwrap();
        let term = |amp: f64, f: f64| (100.0 * amp).powi(3) * 0.325 * f * f / f;
        let expected = 0.896 * (term(0.2, 3.0) + term(0.1, 2.8) + term(0.1, 3.2)).powf(0.1);
        assert!((r.w - expected).abs() < 1e-9, "{} vs {expected}", r.w);
        let plain = sperling_index(&a, dt, &Default::default()).unwrap();
        assert!((plain.w - by_hand(0.2, 3.0, 0.325 * 9.0)).abs() < 1e-9);
        // Between two lines (3.1 Hz): the rectangular window leaks into every line, the Hann
        // window much less; both equal the direct definition.
        let a = sine(3.1, 0.2, dt, 5.0, 0.4);
        let r_hann = sperling_index(&a, dt, &hann).unwrap().w;
        let r_none = sperling_index(&a, dt, &Default::default()).unwrap().w;
        assert!((r_hann - by_definition(&a, dt, Window::Hann)).abs() < 1e-9);
        assert!((r_none - by_definition(&a, dt, Window::None)).abs() < 1e-9);
        // The rectangular window scatters the line over many small ones (W counts cubes),
        // the Hann window keeps most of it on the two nearest lines.
        assert!(r_hann > r_none, "{r_none} {r_hann}");
    }

    #[test]
    fn statistic_and_window_names() {
        assert_eq!(Window::Hann.as_str(), "hann");
        assert_eq!(Statistic::Mean.as_str(), "mean");
        assert_eq!(Window::default(), Window::None);
        assert_eq!(Statistic::default(), Statistic::Max);
    }
}
