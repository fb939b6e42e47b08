//! Excitations of the vehicle–track model: the rail profile Z0(x) (m, positive downward, a
//! dip or a low spot of the rail) seen by a wheel at track position x (m).
//!
//! ```text
//! Z0(x) = w(x) · z_irr(x) + z_dip(x)
//! z_dip(x) = (d/2)(1 − cos(2π(x − x0)/L))  for x0 ≤ x ≤ x0 + L, else 0        (rail defect)
//! z_irr(x) = Σ_k √(2 S(f_k) Δf) cos(2π f_k x + θ_k),  f_k = k Δf ∈ [1/λmax, 1/λmin],
//!            Δf = 1/L_s, θ_k ~ U(0, 2π) from SplitMix64(seed)                  (random track)
//! w(x)     = ramp from 0 to 1 as ½(1 − cos(π (x − x_r)/L_r)) over L_r after x_r
//! ```
//!
//! The random sample is periodic with the sample length L_s; it is evaluated once on a grid
//! of spacing ≤ λmin/32 by one FFT (values and slopes), and read by cubic Hermite
//! interpolation (relative error ≈ 4e-6 at λmin). It depends only on (spectrum, λmin, λmax,
//! L_s, seed): the same seed gives the same track in every run of a UQ study.
//!
//! One-sided spectra S(f) in m²/(1/m), f in cycles per metre:
//! - 1, Chinese high-speed ballastless track, TB/T 3352-2014, vertical profile:
//!   S = A f^−k mm²/(1/m) on four bands split at 0.0187, 0.0474, 0.1533 1/m, with
//!   A = 1.0544e-5, 3.5588e-3, 1.9784e-2, 3.9488e-4 and k = 3.3891, 1.9271, 1.3643, 3.4516.
//! - 2, 3, German low / high interference (ORE B176):
//!   S(Ω) = Av Ωc² / ((Ω² + Ωr²)(Ω² + Ωc²)) m²/(rad/m), Ωc = 0.8246, Ωr = 0.0206 rad/m,
//!   Av = 4.032e-7 (low), 1.080e-6 (high) m·rad; S(f) = 2π S(2πf).
//! - 4..9, US FRA track classes 1..6, vertical profile:
//!   S(Ω) = k Av Ωc² / (Ω² (Ω² + Ωc²)) cm²/(rad/m), k = 0.25, Ωc = 0.8245 rad/m,
//!   Av = 1.2107, 1.0181, 0.6816, 0.5376, 0.2095, 0.0339 cm²·rad/m (classes 1..6);
//!   S(f) = 2π · 10⁻⁴ S(2πf). Source: the table of Garg & Dukkipati, *Dynamics of Railway
//!   Vehicle Systems* (1984), after Hamid & Yang (1981), as reproduced in the vehicle–track
//!   literature; the formula and its cm²/(rad/m) unit were confirmed in a public SIMPACK
//!   user forum thread (3dswym.3dexperience.3ds.com, "Track irregularity input for SIMPACK"),
//!   and class 5's Av = 2.095e-5 m²·rad/m in public rail-dynamics code; the whole class
//!   table was not found in a public source reachable here ([lit], from the textbook).
//!   The German and FRA spectra are used as one-sided, as is usual in vehicle dynamics.
//! - 10, a measured profile: CSV of `x [m], z [m]`, linearly interpolated.
#![forbid(unsafe_code)]

use super::fft::{Complex, Fft};
use crate::contact::table::fields;
use crate::models::data_file::{read_data_file, resolve};
use std::f64::consts::PI;
use std::path::Path;
use std::sync::Arc;

/// SplitMix64 (Steele, Lea & Flood 2014; the seeding generator of `java.util.SplittableRandom`):
/// a 64-bit counter advanced by the golden-ratio increment and passed through a mixing function.
#[derive(Clone, Debug)]
pub struct SplitMix64(u64);

impl SplitMix64 {
    /// A generator with the given seed.
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }
    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1) with 53 random bits.
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
}

/// A named one-sided vertical-profile spectrum.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Spectrum {
    /// TB/T 3352-2014 Chinese high-speed ballastless track.
    ChineseBallastless,
    /// German low-interference track.
    GermanLow,
    /// German high-interference track.
    GermanHigh,
    /// US FRA class 1..=6.
    Fra(u8),
}

/// The choice of the Integer variable `irregularity`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum IrregularityKind {
    /// 0: perfect track.
    None,
    /// 1..9: a random sample of a named spectrum.
    Spectrum(Spectrum),
    /// 10: a measured profile read from `profile_file`.
    Measured,
}

impl IrregularityKind {
    /// From the Integer code 0..=10.
    pub fn from_code(code: i32) -> Option<Self> {
        Some(match code {
            0 => Self::None,
            1 => Self::Spectrum(Spectrum::ChineseBallastless),
            2 => Self::Spectrum(Spectrum::GermanLow),
            3 => Self::Spectrum(Spectrum::GermanHigh),
            4..=9 => Self::Spectrum(Spectrum::Fra((code - 3) as u8)),
            10 => Self::Measured,
            _ => return None,
        })
    }
}

const CHINESE_BREAKS: [f64; 3] = [0.0187, 0.0474, 0.1533];
const CHINESE_A: [f64; 4] = [1.0544e-5, 3.5588e-3, 1.9784e-2, 3.9488e-4];
const CHINESE_K: [f64; 4] = [3.3891, 1.9271, 1.3643, 3.4516];
const FRA_AV: [f64; 6] = [1.2107, 1.0181, 0.6816, 0.5376, 0.2095, 0.0339];

impl Spectrum {
    /// One-sided S(f) in m²/(1/m) at spatial frequency `f` > 0 (1/m).
    pub fn psd(&self, f: f64) -> f64 {
        let om = 2.0 * PI * f;
        match *self {
            Spectrum::ChineseBallastless => {
                let band = CHINESE_BREAKS.iter().filter(|&&b| f >= b).count();
                CHINESE_A[band] * f.powf(-CHINESE_K[band]) * 1e-6
            }
            Spectrum::GermanLow | Spectrum::GermanHigh => {
                let av = if *self == Spectrum::GermanLow {
                    4.032e-7
                } else {
                    1.080e-6
                };
                let (oc, or) = (0.8246f64, 0.0206f64);
                2.0 * PI * av * oc * oc / ((om * om + or * or) * (om * om + oc * oc))
            }
            Spectrum::Fra(class) => {
                let av = FRA_AV[(class.clamp(1, 6) - 1) as usize];
                let oc = 0.8245f64;
                2.0 * PI * 1e-4 * 0.25 * av * oc * oc / (om * om * (om * om + oc * oc))
            }
        }
    }
}

/// The parameters a random sample is built from (equal keys give identical samples).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampleKey {
    /// Spectrum.
    pub spectrum: Spectrum,
    /// Shortest wavelength (m).
    pub lambda_min: f64,
    /// Longest wavelength (m).
    pub lambda_max: f64,
    /// Sample length = period (m).
    pub length: f64,
    /// Seed of the phases.
    pub seed: i32,
}

/// A random profile sampled on a periodic grid (values and slopes).
#[derive(Clone, Debug)]
pub struct RandomProfile {
    /// What it was built from.
    pub key: SampleKey,
    /// Grid spacing (m).
    pub h: f64,
    /// z at x = j h (m).
    pub z: Vec<f64>,
    /// dz/dx at x = j h (1).
    pub dz: Vec<f64>,
    /// Number of cosines in the sum.
    pub n_components: usize,
}

impl RandomProfile {
    /// Builds the sample: amplitudes √(2 S(f_k) Δf), phases from SplitMix64(seed) in order of k.
    pub fn generate(key: SampleKey) -> Result<Self, String> {
        let SampleKey {
            spectrum,
            lambda_min,
            lambda_max,
            length,
            seed,
        } = key;
        if !(lambda_min > 0.0 && lambda_max > lambda_min && length >= lambda_max) {
            return Err(format!(
                "need 0 < lambda_min ({lambda_min} m) < lambda_max ({lambda_max} m) <= irregularity_length ({length} m)"
            ));
        }
        let k_lo = (length / lambda_max - 1e-9).ceil().max(1.0) as usize;
        let k_hi = (length / lambda_min + 1e-9).floor() as usize;
        if k_hi < k_lo {
            return Err(format!(
                "no wavelength of the sample (multiples of 1/{length} 1/m) lies in [{lambda_min}, {lambda_max}] m"
            ));
        }
        let m = ((length * 32.0 / lambda_min).ceil() as usize).next_power_of_two();
        if m > 1 << 23 {
            return Err(format!(
                "irregularity_length / lambda_min = {} is too large (at most 2^18): shorten the sample or raise lambda_min",
                length / lambda_min
            ));
        }
        let df = 1.0 / length;
        let mut rng = SplitMix64::new(seed as i64 as u64);
        let mut spec = vec![Complex::default(); m];
        for k in k_lo..=k_hi {
            let f = k as f64 * df;
            let amp = (2.0 * spectrum.psd(f) * df).sqrt();
            let theta = 2.0 * PI * rng.next_f64();
            let (c_re, c_im) = (amp * theta.cos(), amp * theta.sin());
            let u = 2.0 * PI * f;
            // Hermitian pair so that Re y = z and Im y = z' (see the module documentation).
            spec[k] = Complex::new(0.5 * (1.0 - u) * c_re, 0.5 * (1.0 - u) * c_im);
            spec[m - k] = Complex::new(0.5 * (1.0 + u) * c_re, -0.5 * (1.0 + u) * c_im);
        }
        Fft::new(m)?.backward(&mut spec);
        Ok(Self {
            key,
            h: length / m as f64,
            z: spec.iter().map(|c| c.re).collect(),
            dz: spec.iter().map(|c| c.im).collect(),
            n_components: k_hi + 1 - k_lo,
        })
    }

    /// z(x) (m) by cubic Hermite interpolation; periodic in x with the sample length.
    #[inline]
    pub fn eval(&self, x: f64) -> f64 {
        let m = self.z.len();
        let s = x.rem_euclid(self.key.length) / self.h;
        let j = (s.floor() as usize).min(m - 1);
        let t = s - j as f64;
        let j1 = if j + 1 == m { 0 } else { j + 1 };
        let (t2, t3) = (t * t, t * t * t);
        (2.0 * t3 - 3.0 * t2 + 1.0) * self.z[j]
            + (t3 - 2.0 * t2 + t) * self.h * self.dz[j]
            + (3.0 * t2 - 2.0 * t3) * self.z[j1]
            + (t3 - t2) * self.h * self.dz[j1]
    }
}

/// A measured profile: points (x, z) with x strictly increasing.
#[derive(Clone, Debug)]
pub struct MeasuredProfile {
    /// Where it was read from.
    pub source: String,
    /// Positions (m).
    pub x: Vec<f64>,
    /// Irregularity (m, positive down).
    pub z: Vec<f64>,
}

impl MeasuredProfile {
    /// Parses CSV text: two numbers per line (`,`, `;`, tab or space separated); blank lines
    /// and lines starting with `#` are skipped, and so is one header line before the data.
    ///
    /// Errors name `source` and the line, never the line's contents or its numbers: a wrong
    /// path may name a file that is not ours to show in a log.
    pub fn parse(text: &str, source: &str) -> Result<Self, String> {
        let (mut x, mut z) = (Vec::new(), Vec::new());
        let mut header_allowed = true;
        for (no, line) in text.lines().enumerate() {
            let line = line.trim();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            let nums: Option<Vec<f64>> = fields(line).iter().map(|s| s.parse().ok()).collect();
            match nums {
                Some(v) if v.len() >= 2 => {
                    if !(v[0].is_finite() && v[1].is_finite()) {
                        return Err(format!("{source}: line {}: non-finite value", no + 1));
                    }
                    if x.last().is_some_and(|&last| v[0] <= last) {
                        return Err(format!(
                            "{source}: line {}: x does not increase (each x [m] must be \
                             greater than the one on the line before)",
                            no + 1
                        ));
                    }
                    x.push(v[0]);
                    z.push(v[1]);
                }
                _ if header_allowed && x.is_empty() => {}
                _ => {
                    return Err(format!(
                        "{source}: line {}: expected two numbers 'x [m], z [m]' (separated by \
                         ',', ';', a tab or spaces)",
                        no + 1
                    ))
                }
            }
            header_allowed = false;
        }
        if x.len() < 2 {
            return Err(format!("{source}: a profile needs at least two points"));
        }
        Ok(Self {
            source: source.to_string(),
            x,
            z,
        })
    }

    /// Reads `path` (a regular file of at most 64 MiB, by the rules of
    /// [`read_data_file`](crate::models::data_file::read_data_file)); a relative path is taken
    /// relative to `resource_dir` when given.
    pub fn read(path: &str, resource_dir: Option<&Path>) -> Result<Self, String> {
        if path.is_empty() {
            return Err(
                "irregularity = 10 (measured) needs profile_file, a CSV of x [m], z [m]".into(),
            );
        }
        let text = read_data_file("profile_file", path, resource_dir)?;
        let full = resolve(path, resource_dir);
        Self::parse(&text, &full.display().to_string()).map_err(|e| format!("profile_file {e}"))
    }

    /// Range of x covered (m).
    pub fn range(&self) -> (f64, f64) {
        (self.x[0], self.x[self.x.len() - 1])
    }

    /// z(x) (m) by linear interpolation (held constant outside the range).
    pub fn eval(&self, x: f64) -> f64 {
        let n = self.x.len();
        if x <= self.x[0] {
            return self.z[0];
        }
        if x >= self.x[n - 1] {
            return self.z[n - 1];
        }
        let i = self.x.partition_point(|&xi| xi <= x) - 1;
        let t = (x - self.x[i]) / (self.x[i + 1] - self.x[i]);
        self.z[i] + t * (self.z[i + 1] - self.z[i])
    }
}

/// A cosine dip of the rail (a local defect).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dip {
    /// Start position (m).
    pub x0: f64,
    /// Length L (m).
    pub length: f64,
    /// Depth d (m); 0 means no dip.
    pub depth: f64,
}

impl Dip {
    /// z_dip(x) (m).
    #[inline]
    pub fn eval(&self, x: f64) -> f64 {
        if self.depth == 0.0 || x < self.x0 || x > self.x0 + self.length {
            0.0
        } else {
            0.5 * self.depth * (1.0 - (2.0 * PI * (x - self.x0) / self.length).cos())
        }
    }
}

/// The track irregularity source.
#[derive(Clone, Debug)]
pub enum Irregularity {
    /// Perfect track.
    None,
    /// A random sample (shared between clones).
    Random(Arc<RandomProfile>),
    /// A measured profile.
    Measured(Arc<MeasuredProfile>),
}

/// Everything the wheels see: irregularity (with its start ramp) plus the dip.
#[derive(Clone, Debug)]
pub struct Excitation {
    /// Irregularity.
    pub irregularity: Irregularity,
    /// Rail defect.
    pub dip: Dip,
    /// Position where the irregularity ramp starts (m).
    pub ramp_start: f64,
    /// Ramp length (m); 0 = no ramp.
    pub ramp_length: f64,
}

impl Excitation {
    /// The irregularity alone, with its ramp (m).
    #[inline]
    pub fn irregularity_at(&self, x: f64) -> f64 {
        let z = match &self.irregularity {
            Irregularity::None => return 0.0,
            Irregularity::Random(r) => r.eval(x),
            Irregularity::Measured(m) => m.eval(x),
        };
        z * self.ramp(x)
    }

    /// Ramp weight w(x) in [0, 1].
    #[inline]
    fn ramp(&self, x: f64) -> f64 {
        if self.ramp_length <= 0.0 || x >= self.ramp_start + self.ramp_length {
            1.0
        } else if x <= self.ramp_start {
            0.0
        } else {
            0.5 * (1.0 - (PI * (x - self.ramp_start) / self.ramp_length).cos())
        }
    }

    /// Z0(x) (m): irregularity plus dip.
    #[inline]
    pub fn z0(&self, x: f64) -> f64 {
        self.irregularity_at(x) + self.dip.eval(x)
    }

    /// Checks that a measured profile covers [x_lo, x_hi] (m) where the ramp weight is > 0.
    pub fn check_range(&self, x_lo: f64, x_hi: f64) -> Result<(), String> {
        if let Irregularity::Measured(m) = &self.irregularity {
            let lo = if self.ramp_length > 0.0 {
                x_lo.max(self.ramp_start)
            } else {
                x_lo
            };
            let (a, b) = m.range();
            if lo < a || x_hi > b {
                return Err(format!(
                    "the wheels reach x = {lo:.3} .. {x_hi:.3} m but profile_file '{}' covers only {a} .. {b} m",
                    m.source
                ));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key(seed: i32) -> SampleKey {
        SampleKey {
            spectrum: Spectrum::ChineseBallastless,
            lambda_min: 2.0,
            lambda_max: 200.0,
            length: 1024.0,
            seed,
        }
    }

    #[test]
    fn splitmix64_reference_values() {
        // First outputs for seed 0 (reference implementation by S. Vigna).
        let mut r = SplitMix64::new(0);
        assert_eq!(r.next_u64(), 0xE220_A839_7B1D_CDAF);
        assert_eq!(r.next_u64(), 0x6E78_9E6A_A1B9_65F4);
        let mut r = SplitMix64::new(1);
        let mean = (0..100_000).map(|_| r.next_f64()).sum::<f64>() / 1e5;
        assert!((mean - 0.5).abs() < 0.005);
    }

    #[test]
    fn chinese_spectrum_is_continuous_at_its_breaks() {
        let s = Spectrum::ChineseBallastless;
        for b in CHINESE_BREAKS {
            let (lo, hi) = (s.psd(b * (1.0 - 1e-9)), s.psd(b));
            assert!((lo - hi).abs() < 0.01 * hi, "break {b}: {lo:e} vs {hi:e}");
        }
        // 1e-6 · 3.9488e-4 · 0.2^−3.4516 at f = 0.2 1/m.
        assert!((s.psd(0.2) - 3.9488e-10 * 0.2f64.powf(-3.4516)).abs() < 1e-18);
    }

    #[test]
    fn german_and_fra_unit_conversions() {
        // German high: S(Ω) at Ω = 1 rad/m, times 2π.
        let (oc, or, av) = (0.8246f64, 0.0206f64, 1.080e-6);
        let s_om = av * oc * oc / ((1.0 + or * or) * (1.0 + oc * oc));
        let f = 1.0 / (2.0 * PI);
        assert!((Spectrum::GermanHigh.psd(f) - 2.0 * PI * s_om).abs() < 1e-20);
        // FRA class 6 at Ω = 1 rad/m: 0.25 · 0.0339 · Ωc² / (1 + Ωc²) cm²/(rad/m).
        let s_cm = 0.25 * 0.0339 * 0.8245f64.powi(2) / (1.0 + 0.8245f64.powi(2));
        assert!((Spectrum::Fra(6).psd(f) - 2.0 * PI * 1e-4 * s_cm).abs() < 1e-18);
        // Higher class = better track = smaller spectrum.
        for c in 1..6u8 {
            assert!(Spectrum::Fra(c).psd(0.1) > Spectrum::Fra(c + 1).psd(0.1));
        }
        assert_eq!(
            IrregularityKind::from_code(9),
            Some(IrregularityKind::Spectrum(Spectrum::Fra(6)))
        );
        assert_eq!(IrregularityKind::from_code(11), None);
    }

    /// One-sided periodogram of `z` sampled at spacing `h` over one period: S(f_k), f_k = k/(n h).
    fn periodogram(z: &[f64], h: f64) -> Vec<f64> {
        let n = z.len();
        let mut c: Vec<Complex> = z.iter().map(|&v| Complex::new(v, 0.0)).collect();
        Fft::new(n).unwrap().forward(&mut c);
        let df = 1.0 / (n as f64 * h);
        c.iter()
            .take(n / 2)
            .map(|x| 2.0 * (x.re * x.re + x.im * x.im) / (n as f64 * n as f64) / df)
            .collect()
    }

    fn octave_bands() -> Vec<(f64, f64)> {
        let mut b = Vec::new();
        let mut lo = 0.005 * 1.001;
        while lo * 2.0 <= 0.5 {
            b.push((lo, lo * 2.0));
            lo *= 2.0;
        }
        b
    }

    #[test]
    fn sample_has_the_target_spectrum_over_one_period() {
        let r = RandomProfile::generate(key(1)).unwrap();
        // Sample what the model sees (the interpolant) on a grid shifted off the FFT grid.
        let (n, h) = (16_384usize, 1024.0 / 16_384.0);
        let z: Vec<f64> = (0..n).map(|j| r.eval((j as f64 + 0.37) * h)).collect();
        let p = periodogram(&z, h);
        let s = Spectrum::ChineseBallastless;
        for (lo, hi) in octave_bands() {
            let ks: Vec<usize> = (1..n / 2)
                .filter(|&k| (lo..hi).contains(&(k as f64 / 1024.0)))
                .collect();
            let est: f64 = ks.iter().map(|&k| p[k]).sum::<f64>() / ks.len() as f64;
            let target: f64 =
                ks.iter().map(|&k| s.psd(k as f64 / 1024.0)).sum::<f64>() / ks.len() as f64;
            assert!(
                (est / target - 1.0).abs() < 0.01,
                "band {lo:.4}-{hi:.4} 1/m: {est:e} vs {target:e}"
            );
        }
        // Nothing outside the wavelength range.
        let outside: f64 = (1..n / 2)
            .filter(|&k| k as f64 / 1024.0 > 0.51)
            .map(|k| p[k])
            .sum();
        assert!(outside < 1e-6 * p.iter().sum::<f64>());
    }

    #[test]
    fn welch_estimate_is_within_statistical_bounds() {
        // Hann-windowed segments of 128 m, 50 % overlap, over one 1024 m period: the band
        // averages of the estimate scatter around the target by ~1/√(bins·segments).
        let r = RandomProfile::generate(key(7)).unwrap();
        let (seg, h) = (1024usize, 0.125);
        let win: Vec<f64> = (0..seg)
            .map(|i| 0.5 * (1.0 - (2.0 * PI * i as f64 / seg as f64).cos()))
            .collect();
        let u: f64 = win.iter().map(|w| w * w).sum::<f64>() / seg as f64;
        let mut acc = vec![0.0; seg / 2];
        let mut count = 0.0;
        for s in 0..15 {
            let z: Vec<f64> = (0..seg)
                .map(|i| r.eval((s * seg / 2 + i) as f64 * h) * win[i])
                .collect();
            for (a, p) in acc.iter_mut().zip(periodogram(&z, h)) {
                *a += p / u;
            }
            count += 1.0;
        }
        let df = 1.0 / (seg as f64 * h);
        let spec = Spectrum::ChineseBallastless;
        for (lo, hi) in octave_bands()
            .into_iter()
            .filter(|b| b.0 > 0.03 && b.1 < 0.45)
        {
            let ks: Vec<usize> = (1..seg / 2)
                .filter(|&k| (lo..hi).contains(&(k as f64 * df)))
                .collect();
            let est = ks.iter().map(|&k| acc[k] / count).sum::<f64>() / ks.len() as f64;
            let target = ks.iter().map(|&k| spec.psd(k as f64 * df)).sum::<f64>() / ks.len() as f64;
            let bound = 3.0 / ((ks.len() as f64) * 7.5).sqrt() + 0.1;
            assert!(
                (est / target - 1.0).abs() < bound,
                "band {lo:.3}-{hi:.3}: ratio {} (bound {bound})",
                est / target
            );
        }
    }

    #[test]
    fn same_seed_same_sample_other_seed_other_sample() {
        let (a, b, c) = (
            RandomProfile::generate(key(1)).unwrap(),
            RandomProfile::generate(key(1)).unwrap(),
            RandomProfile::generate(key(2)).unwrap(),
        );
        assert_eq!(a.z, b.z);
        let rms = (a.z.iter().map(|v| v * v).sum::<f64>() / a.z.len() as f64).sqrt();
        let diff =
            a.z.iter()
                .zip(&c.z)
                .map(|(x, y)| (x - y).abs())
                .fold(0.0, f64::max);
        assert!(diff > 0.5 * rms, "seeds 1 and 2 give nearly the same track");
        // Variance = ∫S df (Parseval): about 1.2 mm rms for this spectrum and band.
        let var: f64 = (6..=512)
            .map(|k| 2.0 * Spectrum::ChineseBallastless.psd(k as f64 / 1024.0) / 1024.0 / 2.0)
            .sum();
        assert!(
            (rms * rms / var - 1.0).abs() < 1e-6,
            "{} vs {var}",
            rms * rms
        );
        assert!((0.8e-3..1.6e-3).contains(&rms), "rms {rms}");
    }

    #[test]
    fn measured_profile_parsing_and_interpolation() {
        let p = MeasuredProfile::parse("x,z\n0, 0\n# comment\n1.0; 1e-3\n3 -1e-3\n", "t").unwrap();
        assert_eq!(p.range(), (0.0, 3.0));
        assert!((p.eval(0.5) - 0.5e-3).abs() < 1e-15);
        assert!((p.eval(2.0) - 0.0).abs() < 1e-15);
        assert!(MeasuredProfile::parse("0,0\n0,1\n", "t").is_err());
        assert!(MeasuredProfile::parse("0,0\nfoo\n", "t").is_err());
        assert!(MeasuredProfile::parse("0,0\n", "t").is_err());
        assert!(MeasuredProfile::read("", None).is_err());
        let e =
            MeasuredProfile::read("no_such_file.csv", Some(Path::new("/nonexistent"))).unwrap_err();
        assert!(e.contains("/nonexistent/no_such_file.csv"), "{e}");
    }

    /// profile_file = "/etc/shadow" failed with a message quoting its second line (kept with
    /// the failed point in points.csv); a FIFO hung the run, /dev/zero grew to ~2 GB.
    #[test]
    fn a_profile_file_error_never_quotes_the_file_and_special_files_are_refused() {
        let e = MeasuredProfile::parse("root:x:0:0\nsecret:$6$abc:1\n", "p").unwrap_err();
        assert_eq!(
            e,
            "p: line 2: expected two numbers 'x [m], z [m]' (separated by ',', ';', a tab or \
             spaces)"
        );
        let e = MeasuredProfile::parse("x,z\n1234,1\n999,2\n", "p").unwrap_err();
        assert!(!e.contains("1234") && !e.contains("999"), "{e}");
        assert!(e.contains("line 3: x does not increase"), "{e}");
        #[cfg(unix)]
        {
            let e = MeasuredProfile::read("/dev/zero", None).unwrap_err();
            assert!(e.contains("is a device; a regular file is expected"), "{e}");
            let dir = std::env::temp_dir().join(format!("railuq-fifo-{}", std::process::id()));
            std::fs::create_dir_all(&dir).unwrap();
            let fifo = dir.join("profile.csv");
            let made = std::process::Command::new("mkfifo").arg(&fifo).status();
            if matches!(made, Ok(s) if s.success()) {
                let (tx, rx) = std::sync::mpsc::channel();
                let path = fifo.to_str().unwrap().to_owned();
                std::thread::spawn(move || {
                    let _ = tx.send(MeasuredProfile::read(&path, None).map(|_| ()));
                });
                let r = rx
                    .recv_timeout(std::time::Duration::from_secs(10))
                    .expect("reading a FIFO must not block");
                assert!(r.unwrap_err().contains("is a FIFO (named pipe)"));
            }
            std::fs::remove_dir_all(dir).unwrap();
        }
    }

    #[test]
    fn dip_shape_and_ramp() {
        let d = Dip {
            x0: 10.0,
            length: 0.5,
            depth: 4e-4,
        };
        assert_eq!(d.eval(9.99), 0.0);
        assert!((d.eval(10.25) - 4e-4).abs() < 1e-18);
        assert_eq!(d.eval(10.51), 0.0);
        let e = Excitation {
            irregularity: Irregularity::Random(Arc::new(RandomProfile::generate(key(1)).unwrap())),
            dip: Dip { depth: 0.0, ..d },
            ramp_start: 5.0,
            ramp_length: 20.0,
        };
        assert_eq!(e.z0(4.0), 0.0);
        assert!(e.z0(30.0) != 0.0);
    }
}
