//! Sobol' points with Joe–Kuo direction numbers and Owen's nested uniform scrambling.
//!
//! Direction numbers: `new-joe-kuo-6.21201` (S. Joe and F. Y. Kuo, SIAM J. Sci. Comput.
//! 30, 2008), first 1000 dimensions, embedded as the published text table
//! (`data/new-joe-kuo-6.1000.txt`). Dimension 1 is the van der Corput sequence. Points
//! are 32-bit: index `i` (from 0) is `x_i = XOR_k [bit k of gray(i)] V_k`, with
//! `gray(i) = i ^ (i >> 1)`; the unscrambled sequence starts at the origin, and every
//! prefix of `2^m` points is a `(t, m, s)`-net.
//!
//! Owen's nested uniform scrambling: bit `k` (from the most significant) of a coordinate
//! is flipped by a random bit that depends on the dimension's key and on the `k` bits
//! above it — the random tree of Owen (1995), realised lazily by a keyed hash
//! (64-bit finaliser of `key ^ node`). 52 bits are scrambled (the unscrambled bits below
//! the 32nd are zero), so scrambled points are uniform on (0, 1) at double precision,
//! never exactly 0 or 1. Keys come from the study seed and the replicate: dimension `j`
//! of replicate `r` uses the `j`-th word of the ChaCha20 stream `rng::stream(seed, r)`.
//! Independent replicates give an unbiased estimator and an honest standard error.

use rand::RngCore;

use crate::uq::rng::stream;

/// The Joe–Kuo table (header line, then `d s a m_1 .. m_s` for d = 2..=1000).
const JOE_KUO: &str = include_str!("data/new-joe-kuo-6.1000.txt");

/// Largest dimension supported.
pub const MAX_DIM: usize = 1000;
/// Number of bits of the unscrambled points (and largest `log2` of the point count).
pub const BITS: usize = 32;

/// Errors of the Sobol' generator.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum SobolError {
    /// Dimension 0 or above [`MAX_DIM`].
    #[error("Sobol' points are available in 1..={MAX_DIM} dimensions (got {0})")]
    Dimension(usize),
    /// More than 2^32 points.
    #[error("at most 2^32 Sobol' points per sequence (requested up to index {0})")]
    TooMany(u64),
}

/// A Sobol' sequence, optionally scrambled.
#[derive(Clone, Debug)]
pub struct Sobol {
    /// `dirs[j][k]` = V_{k+1} of dimension j.
    dirs: Vec<[u32; BITS]>,
    /// Scrambling key per dimension (`None`: unscrambled).
    keys: Option<Vec<u64>>,
}

fn direction_numbers(dim: usize) -> Vec<[u32; BITS]> {
    let mut out = Vec::with_capacity(dim);
    let mut first = [0u32; BITS];
    for (k, v) in first.iter_mut().enumerate() {
        *v = 1u32 << (BITS - 1 - k);
    }
    out.push(first);
    for line in JOE_KUO.lines().skip(1).take(dim.saturating_sub(1)) {
        let f: Vec<u64> = line
            .split_whitespace()
            .map(|t| t.parse().expect("embedded Joe–Kuo table is numeric"))
            .collect();
        let (s, a) = (f[1] as usize, f[2] as u32);
        let m = &f[3..3 + s];
        let mut v = [0u32; BITS];
        for k in 0..BITS {
            if k < s {
                v[k] = (m[k] as u32) << (BITS - 1 - k);
            } else {
                let mut x = v[k - s] ^ (v[k - s] >> s);
                for j in 1..s {
                    if (a >> (s - 1 - j)) & 1 == 1 {
                        x ^= v[k - j];
                    }
                }
                v[k] = x;
            }
        }
        out.push(v);
    }
    out
}

/// 64-bit finaliser (MurmurHash3 fmix64).
fn fmix64(mut k: u64) -> u64 {
    k ^= k >> 33;
    k = k.wrapping_mul(0xff51_afd7_ed55_8ccd);
    k ^= k >> 33;
    k = k.wrapping_mul(0xc4ce_b9fe_1a85_ec53);
    k ^= k >> 33;
    k
}

/// Owen's nested uniform scramble of the top 52 bits of `x` (a 64-bit binary fraction).
fn owen_scramble(x: u64, key: u64) -> u64 {
    let mut y = 0u64;
    for k in 0..52 {
        // Node of the binary tree: the k bits above bit k, with a leading marker bit.
        let prefix = if k == 0 { 0 } else { x >> (64 - k) };
        let node = (1u64 << k) | prefix;
        let flip = fmix64(key ^ node.wrapping_mul(0x9e37_79b9_7f4a_7c15)) >> 63;
        let bit = (x >> (63 - k)) & 1;
        y |= (bit ^ flip) << (63 - k);
    }
    y
}

impl Sobol {
    /// Unscrambled Sobol' points in `dim` dimensions.
    pub fn new(dim: usize) -> Result<Self, SobolError> {
        if dim == 0 || dim > MAX_DIM {
            return Err(SobolError::Dimension(dim));
        }
        Ok(Sobol {
            dirs: direction_numbers(dim),
            keys: None,
        })
    }

    /// Owen-scrambled Sobol' points for `(seed, replicate)`.
    pub fn scrambled(dim: usize, seed: u64, replicate: u64) -> Result<Self, SobolError> {
        let mut s = Self::new(dim)?;
        let mut rng = stream(seed, replicate);
        s.keys = Some((0..dim).map(|_| rng.next_u64()).collect());
        Ok(s)
    }

    /// The 32-bit integer coordinates of unscrambled point `index`.
    fn raw(&self, index: u64) -> Vec<u32> {
        let g = index ^ (index >> 1);
        self.dirs
            .iter()
            .map(|v| {
                let mut x = 0u32;
                for (k, vk) in v.iter().enumerate() {
                    if (g >> k) & 1 == 1 {
                        x ^= vk;
                    }
                }
                x
            })
            .collect()
    }

    /// Point `index` (from 0) in `[0, 1)^dim` (scrambled: in `(0, 1)^dim`), computed directly.
    /// Serves the tests: the reference for the recurrence of [`Sobol::points`].
    #[cfg(test)]
    pub(crate) fn point(&self, index: u64) -> Result<Vec<f64>, SobolError> {
        if index >= 1u64 << BITS {
            return Err(SobolError::TooMany(index));
        }
        Ok(self.finish(&self.raw(index)))
    }

    fn finish(&self, raw: &[u32]) -> Vec<f64> {
        match &self.keys {
            None => raw
                .iter()
                .map(|&x| f64::from(x) * (1.0 / 4_294_967_296.0))
                .collect(),
            Some(keys) => raw
                .iter()
                .zip(keys)
                .map(|(&x, &key)| {
                    let y = owen_scramble(u64::from(x) << 32, key) >> 12;
                    (y as f64 + 0.5) * (1.0 / 4_503_599_627_370_496.0)
                })
                .collect(),
        }
    }

    /// Points `start..start + count` (Gray-code recurrence after the first).
    pub fn points(&self, start: u64, count: usize) -> Result<Vec<Vec<f64>>, SobolError> {
        let end = start + count as u64;
        if end > 1u64 << BITS {
            return Err(SobolError::TooMany(end - 1));
        }
        let mut out = Vec::with_capacity(count);
        if count == 0 {
            return Ok(out);
        }
        let mut x = self.raw(start);
        out.push(self.finish(&x));
        for i in start + 1..end {
            // gray(i) = gray(i-1) ^ (1 << c), c = trailing zeros of i.
            let c = i.trailing_zeros() as usize;
            for (xj, v) in x.iter_mut().zip(&self.dirs) {
                *xj ^= v[c];
            }
            out.push(self.finish(&x));
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn first_points_match_the_published_sequence() {
        // Bratley & Fox / Joe & Kuo, dimensions 1-3, first 8 points.
        let want = [
            [0.0, 0.0, 0.0],
            [0.5, 0.5, 0.5],
            [0.75, 0.25, 0.25],
            [0.25, 0.75, 0.75],
            [0.375, 0.375, 0.625],
            [0.875, 0.875, 0.125],
            [0.625, 0.125, 0.875],
            [0.125, 0.625, 0.375],
        ];
        let s = Sobol::new(3).unwrap();
        let pts = s.points(0, 8).unwrap();
        for (p, w) in pts.iter().zip(want) {
            assert_eq!(p.as_slice(), w.as_slice());
        }
        // Direct index computation agrees with the Gray-code recurrence.
        let s = Sobol::new(40).unwrap();
        let seq = s.points(1000, 50).unwrap();
        for (k, p) in seq.iter().enumerate() {
            assert_eq!(p, &s.point(1000 + k as u64).unwrap());
        }
    }

    #[test]
    fn direction_numbers_are_odd_multiples_and_table_is_complete() {
        let d = direction_numbers(MAX_DIM);
        assert_eq!(d.len(), MAX_DIM);
        for (j, v) in d.iter().enumerate() {
            for (k, vk) in v.iter().enumerate() {
                // V_k = m_k 2^(32-k) with m_k odd and < 2^k.
                let m = vk >> (BITS - 1 - k);
                assert_eq!(vk & ((1u32 << (BITS - 1 - k)) - 1), 0, "dim {j} k {k}");
                assert_eq!(m & 1, 1, "dim {j} k {k}");
            }
        }
    }

    /// For a prefix of 2^m points, the counts in every elementary interval of the 2-D
    /// projection (j1, j2) with q1 + q2 = m - t: all equal 2^t?
    fn is_net(pts: &[Vec<f64>], j1: usize, j2: usize, m: usize, t: usize) -> bool {
        for q1 in 0..=(m - t) {
            let q2 = m - t - q1;
            let mut counts = vec![0usize; 1 << (m - t)];
            for p in pts {
                let a = (p[j1] * (1u64 << q1) as f64).floor() as usize;
                let b = (p[j2] * (1u64 << q2) as f64).floor() as usize;
                counts[(a << q2) | b] += 1;
            }
            if counts.iter().any(|&c| c != 1 << t) {
                return false;
            }
        }
        true
    }

    #[test]
    fn scrambled_prefixes_keep_the_net_stratification() {
        let m = 10;
        let n = 1usize << m;
        let plain = Sobol::new(8).unwrap().points(0, n).unwrap();
        let scr = Sobol::scrambled(8, 2024, 3).unwrap().points(0, n).unwrap();
        // 1-D: one point per interval of length 2^-m, for every prefix 2^k.
        for pts in [&plain, &scr] {
            for j in 0..8 {
                for k in 0..=m {
                    let mut seen = vec![false; 1 << k];
                    for p in &pts[..1 << k] {
                        let c = (p[j] * (1u64 << k) as f64).floor() as usize;
                        assert!(!seen[c], "dim {j}, 2^{k} points: interval {c} twice");
                        seen[c] = true;
                    }
                }
            }
        }
        // 2-D: the scrambled points have the t-value of the unscrambled net.
        for j1 in 0..8 {
            for j2 in j1 + 1..8 {
                let t = (0..=m)
                    .find(|&t| is_net(&plain, j1, j2, m, t))
                    .expect("t = m always holds");
                assert!(t <= 3, "({j1},{j2}): t = {t}");
                assert!(is_net(&scr, j1, j2, m, t), "({j1},{j2}) t={t}");
                if (j1, j2) == (0, 1) {
                    assert_eq!(t, 0);
                }
            }
        }
        // Scrambled points lie strictly inside the cube.
        assert!(scr.iter().flatten().all(|&x| x > 0.0 && x < 1.0));
    }

    #[test]
    fn scrambling_is_reproducible_and_replicates_differ() {
        let a = Sobol::scrambled(5, 42, 0).unwrap().points(0, 64).unwrap();
        let b = Sobol::scrambled(5, 42, 0).unwrap().points(0, 64).unwrap();
        let c = Sobol::scrambled(5, 42, 1).unwrap().points(0, 64).unwrap();
        assert_eq!(a, b);
        assert_ne!(a, c);
        // Chunked generation gives the same points (thread-count independence).
        let s = Sobol::scrambled(5, 42, 0).unwrap();
        let mut chunks = s.points(0, 20).unwrap();
        chunks.extend(s.points(20, 44).unwrap());
        assert_eq!(chunks, a);
    }

    #[test]
    fn scrambled_qmc_error_falls_faster_than_monte_carlo() {
        // f = prod_{i<5} (1 + (x_i^2 - 1/3)), E f = 1.
        let f = |x: &[f64]| -> f64 { x.iter().map(|&xi| 1.0 + (xi * xi - 1.0 / 3.0)).product() };
        let rmse = |n: usize| -> f64 {
            let reps = 16;
            let s: f64 = (0..reps)
                .map(|r| {
                    let pts = Sobol::scrambled(5, 9, r).unwrap().points(0, n).unwrap();
                    let m = pts.iter().map(|p| f(p)).sum::<f64>() / n as f64;
                    (m - 1.0).powi(2)
                })
                .sum();
            (s / reps as f64).sqrt()
        };
        let (e1, e2) = (rmse(256), rmse(4096));
        // Var f = (1 + 4/45)^5 - 1; MC error at n = 4096 = sqrt(Var / n).
        let mc = (((1.0f64 + 4.0 / 45.0).powi(5) - 1.0) / 4096.0).sqrt();
        assert!(e1 / e2 > 12.0, "rmse 256: {e1}, 4096: {e2}");
        assert!(e2 < mc / 10.0, "rmse {e2} vs MC {mc}");
    }

    #[test]
    fn bad_requests_are_refused() {
        assert_eq!(Sobol::new(0).unwrap_err(), SobolError::Dimension(0));
        assert!(Sobol::new(1001).is_err());
        assert!(Sobol::new(2).unwrap().point(1u64 << 32).is_err());
        assert!(Sobol::new(2).unwrap().points(u32::MAX as u64, 2).is_err());
    }
}
