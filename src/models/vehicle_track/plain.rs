//! The plain track kernel: the straightforward implementation of the track's equations (the
//! code before the fast kernel of [`super::track`]), kept as the reference the fast kernel is
//! tested and benchmarked against. Same equations, same state layout: the wheels' mode shapes
//! by the three-term recurrence sin((k+1)a) = 2 cos a sin(ka) − sin((k−1)a) re-seeded every
//! 128 modes, the sine transforms on the own radix-2 FFT ([`PlainDstI`]), one indexed loop per
//! term. Selected with [`super::track::Kernel::Plain`].
#![forbid(unsafe_code)]

use super::fft::PlainDstI;
use super::track::Track;
use std::f64::consts::PI;

/// Scratch of the plain kernel (allocated once).
#[derive(Clone, Debug)]
pub struct Plain {
    dst: PlainDstI,
    bins: Vec<f64>,
    r: Vec<f64>,
    modal: Vec<f64>,
    frs: Vec<f64>,
    /// sin(kπ x_wj / l) for the four wheels, row-major NM × 4.
    wheel_sin: Vec<f64>,
}

impl Plain {
    /// Scratch for N sleepers and NM modes.
    pub fn new(n: usize, nm: usize) -> Result<Self, String> {
        Ok(Plain {
            dst: PlainDstI::new(n)?,
            bins: vec![0.0; n],
            r: vec![0.0; n],
            modal: vec![0.0; nm],
            frs: vec![0.0; n],
            wheel_sin: vec![0.0; 4 * nm],
        })
    }

    /// Stores sin(kπx/l), k = 1..NM, for the wheels at local positions `x` (m), by the
    /// three-term recurrence (the four wheels interleaved), re-seeded every 128 modes.
    pub fn set_wheels(&mut self, length: f64, x: &[f64; 4]) {
        let a: [f64; 4] = std::array::from_fn(|j| PI * x[j] / length);
        let sc: [(f64, f64); 4] = std::array::from_fn(|j| a[j].sin_cos());
        let c2: [f64; 4] = std::array::from_fn(|j| 2.0 * sc[j].1);
        const CHUNK: usize = 128;
        for (chunk_no, chunk) in self.wheel_sin.chunks_mut(4 * CHUNK).enumerate() {
            let k0 = chunk_no * CHUNK; // first mode of the chunk is k0 + 1
            let mut prev = [0.0; 4];
            let mut cur = [0.0; 4];
            for j in 0..4 {
                let (s0, c0) = if k0 == 0 {
                    (0.0, 1.0)
                } else {
                    (k0 as f64 * a[j]).sin_cos()
                };
                prev[j] = s0;
                cur[j] = s0 * sc[j].1 + c0 * sc[j].0;
            }
            for row in chunk.chunks_exact_mut(4) {
                for j in 0..4 {
                    row[j] = cur[j];
                    let next = c2[j] * cur[j] - prev[j];
                    prev[j] = cur[j];
                    cur[j] = next;
                }
            }
        }
    }

    /// sin(kπx_j/l), k ≥ 1.
    pub fn wheel_sine(&self, j: usize, k: usize) -> f64 {
        self.wheel_sin[4 * (k - 1) + j]
    }

    /// Rail displacement (m) under each wheel from modal `q`.
    pub fn rail_at_wheels(&self, scale: f64, q: &[f64]) -> [f64; 4] {
        let mut out = [0.0; 4];
        for (row, &qk) in self.wheel_sin.chunks_exact(4).zip(q) {
            for j in 0..4 {
                out[j] += row[j] * qk;
            }
        }
        out.map(|v| v * scale)
    }
}

/// Track accelerations by the plain kernel (see [`Track::accelerations`]).
pub fn accelerations(t: &mut Track, y: &[f64], yd: &[f64], p: &[f64; 4], acc: &mut [f64]) {
    let (n, nm, scale) = (t.n, t.nm, t.scale);
    let tp = t.p;
    let Some(pl) = t.plain.as_mut() else {
        unreachable!("the plain kernel has its scratch")
    };
    let (q, zs, zb) = (&y[..nm], &y[nm..nm + n], &y[nm + n..nm + 2 * n]);
    let (qd, zsd, zbd) = (&yd[..nm], &yd[nm..nm + n], &yd[nm + n..nm + 2 * n]);
    for k in 0..nm {
        pl.modal[k] = tp.kp * q[k] + tp.cp * qd[k];
    }
    // Zr at the sleepers: fold the modes onto the sleeper grid, transform, scale.
    if nm <= n {
        pl.bins[..nm].copy_from_slice(&pl.modal);
        pl.bins[nm..].iter_mut().for_each(|b| *b = 0.0);
    } else {
        pl.bins.iter_mut().for_each(|b| *b = 0.0);
        for k in 0..nm {
            if t.fold_bin[k] != usize::MAX {
                pl.bins[t.fold_bin[k]] += t.fold_sign[k] * pl.modal[k];
            }
        }
    }
    pl.dst.transform(&pl.bins, &mut pl.r);
    pl.r.iter_mut().for_each(|v| *v *= scale);
    let (inv_ms, inv_mb) = (1.0 / tp.ms, 1.0 / tp.mb);
    let (acc_q, rest) = acc.split_at_mut(nm);
    let (acc_s, acc_b) = rest.split_at_mut(n);
    for i in 0..n {
        let frs = pl.r[i] - tp.kp * zs[i] - tp.cp * zsd[i];
        let fb = tp.kb * (zs[i] - zb[i]) + tp.cb * (zsd[i] - zbd[i]);
        pl.frs[i] = frs;
        acc_s[i] = (frs - fb) * inv_ms;
        acc_b[i] = (fb - tp.kf * zb[i] - tp.cf * zbd[i]) * inv_mb;
    }
    let (kw, cw) = (tp.kw * inv_mb, tp.cw * inv_mb);
    for i in 0..n - 1 {
        let f = kw * (zb[i] - zb[i + 1]) + cw * (zbd[i] - zbd[i + 1]);
        acc_b[i] -= f;
        acc_b[i + 1] += f;
    }
    for k in 0..nm {
        acc_q[k] = -t.omega2[k] * q[k];
    }
    // Modal forces of the pads (the transposed map) and of the wheels.
    pl.dst.transform(&pl.frs, &mut pl.bins);
    let c = -scale;
    for k in 0..nm {
        let b = t.fold_bin[k];
        if nm <= n {
            acc_q[k] += c * pl.bins[k];
        } else if b != usize::MAX {
            acc_q[k] += c * t.fold_sign[k] * pl.bins[b];
        }
    }
    let cw: [f64; 4] = std::array::from_fn(|j| scale * p[j]);
    for k in 0..nm {
        let row = &pl.wheel_sin[4 * k..4 * k + 4];
        acc_q[k] += cw[0] * row[0] + cw[1] * row[1] + cw[2] * row[2] + cw[3] * row[3];
    }
}
