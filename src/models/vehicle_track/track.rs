//! Ballasted track under one rail (Zhai): an Euler–Bernoulli rail, simply supported over the
//! computing length l, by modal superposition; discrete rail pads, half sleepers, ballast
//! blocks coupled in shear, and subgrade springs.
//!
//! ```text
//! Z_k(x) = √(2/(m_r l)) sin(kπx/l), k = 1..NM,        Zr(x) = Σ_k Z_k(x) q_k
//! q_k'' + (EI/m_r)(kπ/l)⁴ q_k = −Σ_i F_rsi Z_k(x_i) + Σ_j P_j Z_k(x_wj)
//! F_rsi = Kp (Zr(x_i) − Z_si) + Cp (Zr'(x_i) − Z_si')                         rail pad
//! Ms Z_si'' = F_rsi − F_bi,   F_bi = Kb (Z_si − Z_bi) + Cb (Z_si' − Z_bi')    half sleeper
//! Mb Z_bi'' = F_bi − Kf Z_bi − Cf Z_bi' − Kw (2Z_bi − Z_b,i−1 − Z_b,i+1)
//!             − Cw (2Z_bi' − Z_b,i−1' − Z_b,i+1')  (end blocks: one neighbour)  ballast
//! ```
//!
//! N sleepers sit at x_i = i·l_s, i = 1..N, l = (N+1) l_s, so Z_k(x_i) ∝ sin(kπi/(N+1)): the
//! maps modes → sleepers and sleeper forces → modal forces are DST-I's of size N
//! ([`super::fft::DstI`], N + 1 a power of two), O(N log N) per step. Modes k > N alias onto
//! the sleeper grid (sin(kπi/n) = ± sin(k'πi/n)), which a fold of the modal vector handles,
//! so any NM ≤ 2N + 1 works. The wheels sit anywhere: their mode values come from blocked
//! complex rotations ([`Track::set_wheels`]), never stored: the two passes that use them run
//! over the blocks.
//!
//! Two kernels compute the same equations ([`Kernel`]): the fast one (default) and the plain
//! reference ([`super::plain`]) it is tested against; the fast one's stepping loop runs
//! compiled for AVX2 where the CPU has it ([`crate::solver::simd`]).
//!
//! Track state layout (one slice): `[q_1..q_NM | Z_s1..Z_sN | Z_b1..Z_bN]`.
//! Displacements are measured from the unloaded track (self-weight not modelled).
#![forbid(unsafe_code)]

use super::fft::{DstI, FftPath};
use super::plain::{self, Plain};
use crate::solver::simd::{Isa, Simd};
use std::f64::consts::PI;

/// Track data (SI units).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrackParams {
    /// Rail mass per length m_r (kg/m).
    pub mr: f64,
    /// Rail bending stiffness EI (N·m²).
    pub ei: f64,
    /// Half-sleeper mass Ms (kg).
    pub ms: f64,
    /// Ballast block mass Mb (kg).
    pub mb: f64,
    /// Pad stiffness Kp (N/m).
    pub kp: f64,
    /// Pad damping Cp (N·s/m).
    pub cp: f64,
    /// Ballast stiffness Kb (N/m).
    pub kb: f64,
    /// Ballast damping Cb (N·s/m).
    pub cb: f64,
    /// Subgrade stiffness Kf (N/m).
    pub kf: f64,
    /// Subgrade damping Cf (N·s/m).
    pub cf: f64,
    /// Ballast shear stiffness Kw (N/m).
    pub kw: f64,
    /// Ballast shear damping Cw (N·s/m).
    pub cw: f64,
    /// Sleeper spacing l_s (m).
    pub ls: f64,
    /// Number of sleepers N (N + 1 a power of two).
    pub n_sleepers: usize,
    /// Number of rail modes NM (1..=2N+1).
    pub n_modes: usize,
}

/// Which implementation computes the track's accelerations.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Kernel {
    /// The fast kernel (the default) on the widest instruction set of this CPU and
    /// rustfft's own choice of FFT.
    #[default]
    Fast,
    /// The fast kernel on a given instruction set and FFT path (tests, benchmarks); refused
    /// at initialization if this CPU lacks them.
    Custom {
        /// Instruction set of the kernel's loops.
        isa: Isa,
        /// Instruction set of the FFT.
        fft: FftPath,
    },
    /// The plain reference implementation ([`super::plain`]).
    Plain,
}

impl Kernel {
    /// Every kernel this machine can run: each instruction set of the loops with each FFT
    /// path, and the plain one.
    pub fn available() -> Vec<Kernel> {
        let mut v = Vec::new();
        for simd in Simd::available() {
            for fft in FftPath::available() {
                v.push(Kernel::Custom {
                    isa: simd.isa(),
                    fft,
                });
            }
        }
        v.push(Kernel::Plain);
        v
    }

    /// What this kernel runs on here, as the FMU's `solver.kernel` reports it: the
    /// architecture, the instruction set of the stepping loops (the one
    /// [`crate::solver::simd::Simd::dispatch`] calls: `avx2+fma` or, on x86-64 without them,
    /// `sse2`) and that of the FFT, e.g. `x86_64: loops avx2+fma, FFT avx+fma`; the plain
    /// reference: `x86_64: plain reference kernel`. AVX2 and SSE2 loops agree to about 1e-13
    /// only, so a result is reproduced bit for bit on the same kernel.
    pub fn describe(self) -> String {
        let arch = std::env::consts::ARCH;
        let (isa, fft) = match self {
            Kernel::Fast => (Simd::best().isa(), FftPath::Auto),
            Kernel::Custom { isa, fft } => (isa, fft),
            Kernel::Plain => return format!("{arch}: plain reference kernel"),
        };
        let loops = match isa {
            Isa::Avx2 => "avx2+fma",
            Isa::Baseline if cfg!(target_arch = "x86_64") => "sse2",
            Isa::Baseline => "baseline",
        };
        format!("{arch}: loops {loops}, FFT {}", fft.isa_name())
    }
}

/// Modes per block of the wheels' mode shapes (see [`Track::set_wheels`]).
const BLOCK: usize = 16;

/// The track: parameters, transforms and scratch (allocated once).
#[derive(Clone, Debug)]
pub struct Track {
    /// Parameters.
    pub p: TrackParams,
    /// N.
    pub n: usize,
    /// NM.
    pub nm: usize,
    /// Computing length l = (N + 1) l_s (m).
    pub length: f64,
    /// √(2/(m_r l)) (1/√kg): amplitude of the mass-normalised modes.
    pub scale: f64,
    /// ω_k² = (EI/m_r)(kπ/l)⁴ (1/s²).
    pub(super) omega2: Vec<f64>,
    /// Sleeper-grid bin (0-based) of mode k, or `usize::MAX` when it vanishes at every sleeper.
    pub(super) fold_bin: Vec<usize>,
    /// Sign of the fold.
    pub(super) fold_sign: Vec<f64>,
    dst: DstI,
    dst_fine: DstI,
    bins: Vec<f64>,
    r: Vec<f64>,
    frs: Vec<f64>,
    /// Ballast shear forces per unit mass between blocks i−1 and i, i = 0..=N (ends 0).
    shear: Vec<f64>,
    fine: Vec<f64>,
    fine_out: Vec<f64>,
    /// The wheels' mode shapes, in blocks of [`BLOCK`] modes (see [`Track::set_wheels`]):
    /// `t_re[j][i] + i t_im[j][i]` = e^{i(i+1)a_j}, a_j = πx_j/l.
    t_re: [[f64; BLOCK]; 4],
    t_im: [[f64; BLOCK]; 4],
    /// Block rotations e^{ibBa_j}, one per block b, the four wheels side by side.
    u_re: Vec<[f64; 4]>,
    u_im: Vec<[f64; 4]>,
    /// Per wheel j: the position difference x_0 − x_j (m) the next two rotations belong to,
    /// and e^{−iδ_j}, e^{−iBδ_j}, δ_j = π(x_0 − x_j)/l (cos, sin, cos, sin).
    offsets: [(f64, [f64; 4]); 4],
    kernel: Kernel,
    simd: Simd,
    /// The plain kernel's scratch, when it is selected.
    pub(super) plain: Option<Plain>,
}

impl Track {
    /// Builds the track (validates N and NM) with the fast kernel.
    pub fn new(p: TrackParams) -> Result<Self, String> {
        Self::with_kernel(p, Kernel::Fast)
    }

    /// Builds the track with the given kernel.
    pub fn with_kernel(p: TrackParams, kernel: Kernel) -> Result<Self, String> {
        let (n, nm) = (p.n_sleepers, p.n_modes);
        let (simd, path) = match kernel {
            Kernel::Fast => (Simd::best(), FftPath::Auto),
            Kernel::Custom { isa, fft } => (
                Simd::new(isa).ok_or_else(|| format!("this CPU does not run {isa:?}"))?,
                fft,
            ),
            Kernel::Plain => (Simd::baseline(), FftPath::Auto),
        };
        let dst = DstI::with_path(n, path).map_err(|e| format!("n_sleepers = {n}: {e}"))?;
        if nm == 0 || nm > 2 * n + 1 {
            return Err(format!(
                "n_modes = {nm} must be between 1 and 2 n_sleepers + 1 = {}",
                2 * n + 1
            ));
        }
        let dst_fine = DstI::with_path(2 * n + 1, path)?;
        let length = (n + 1) as f64 * p.ls;
        let blocks = nm.div_ceil(BLOCK);
        let period = 2 * (n + 1);
        let (mut fold_bin, mut fold_sign) = (Vec::with_capacity(nm), Vec::with_capacity(nm));
        for k in 1..=nm {
            let r = k % period;
            if r == 0 || r == n + 1 {
                fold_bin.push(usize::MAX);
                fold_sign.push(0.0);
            } else if r <= n {
                fold_bin.push(r - 1);
                fold_sign.push(1.0);
            } else {
                fold_bin.push(period - r - 1);
                fold_sign.push(-1.0);
            }
        }
        Ok(Self {
            p,
            n,
            nm,
            length,
            scale: (2.0 / (p.mr * length)).sqrt(),
            omega2: (1..=nm)
                .map(|k| p.ei / p.mr * (k as f64 * PI / length).powi(4))
                .collect(),
            fold_bin,
            fold_sign,
            dst,
            dst_fine,
            bins: vec![0.0; n],
            r: vec![0.0; n],
            frs: vec![0.0; n],
            shear: vec![0.0; n + 1],
            fine: vec![0.0; 2 * n + 1],
            fine_out: vec![0.0; 2 * n + 1],
            t_re: [[0.0; BLOCK]; 4],
            t_im: [[0.0; BLOCK]; 4],
            u_re: vec![[0.0; 4]; blocks],
            u_im: vec![[0.0; 4]; blocks],
            offsets: [(0.0, [1.0, 0.0, 1.0, 0.0]); 4],
            kernel,
            simd,
            plain: match kernel {
                Kernel::Plain => Some(Plain::new(n, nm)?),
                _ => None,
            },
        })
    }

    /// The kernel in use.
    pub fn kernel(&self) -> Kernel {
        self.kernel
    }

    /// The instruction set the stepping loop runs on.
    pub fn simd(&self) -> Simd {
        self.simd
    }

    /// Length of the track part of the state: NM + 2N.
    pub fn dim(&self) -> usize {
        self.nm + 2 * self.n
    }

    /// Highest natural frequency of a rail mode (rad/s).
    pub fn max_rail_omega(&self) -> f64 {
        self.omega2[self.nm - 1].sqrt()
    }

    /// Zr at the sleepers, `out[i] = Σ_k Z_k(x_{i+1}) q_k`.
    fn synthesize(dst: &mut DstI, scale: f64, q: &[f64], bins: &mut [f64], out: &mut [f64]) {
        fold(q, bins);
        dst.transform(bins, out);
        out.iter_mut().for_each(|v| *v *= scale);
    }

    /// Adds `factor · Σ_i Z_k(x_i) f_i` to `out[k]` for every mode (the transpose map).
    fn analyze_add(&mut self, factor: f64, out: &mut [f64]) {
        self.dst.transform(&self.frs, &mut self.bins);
        let c = factor * self.scale;
        let (low, high) = out.split_at_mut(self.nm.min(self.n));
        for (o, &b) in low.iter_mut().zip(&self.bins) {
            *o += c * b;
        }
        // Mode N + 1 has a node at every sleeper; modes N + 2 … fold back with a sign.
        for (o, &b) in high.iter_mut().skip(1).zip(self.bins.iter().rev()) {
            *o += -c * b;
        }
    }

    /// Sets the wheels at local positions `x` (m, 0 < x < l) for the mode shapes
    /// sin(kπx_j/l), k = 1..NM, which the fast kernel never stores: with a = πx/l and the
    /// modes in blocks of B = 16, mode k = bB + i + 1 is
    ///
    /// ```text
    /// sin(kπx/l) = Im(e^{ibBa} e^{i(i+1)a}) = Im(U_b) Re(T_i) + Re(U_b) Im(T_i)
    /// ```
    ///
    /// from a table T_i = e^{i(i+1)a}, i < B, and block rotations U_b = e^{ibBa}, each by
    /// repeated complex multiplication. Only wheel 0 calls `sin_cos` (of a and Ba): the others
    /// are rotated from it by their fixed distances to wheel 0, whose rotations are kept.
    /// Rotations keep the error at a few tens of ulps, without the 1/sin(a) growth of a
    /// three-term recurrence; the consumers ([`Track::rail_at_wheels`], the modal wheel forces)
    /// run over the blocks as vector loops.
    #[inline(always)]
    pub fn set_wheels(&mut self, x: &[f64; 4]) {
        if let Some(pl) = self.plain.as_mut() {
            pl.set_wheels(self.length, x);
            return;
        }
        let a0 = PI * x[0] / self.length;
        let (s1, c1) = a0.sin_cos();
        let (sb, cb) = (BLOCK as f64 * a0).sin_cos();
        let mut one = [(0.0, 0.0); 4];
        let mut big = [(0.0, 0.0); 4];
        for j in 0..4 {
            let d = x[0] - x[j];
            if (d - self.offsets[j].0).abs() > 1e-12 * d.abs().max(1.0) {
                self.offsets[j] = Self::offset_rotations(d, self.length);
            }
            let r = self.offsets[j].1;
            // e^{ia_j} = e^{ia_0} e^{−iδ_j}, likewise for Ba.
            one[j] = (c1 * r[0] + s1 * r[1], s1 * r[0] - c1 * r[1]);
            big[j] = (cb * r[2] + sb * r[3], sb * r[2] - cb * r[3]);
        }
        let (mut pr, mut pi) = ([0.0; 4], [0.0; 4]);
        for j in 0..4 {
            (pr[j], pi[j]) = one[j];
        }
        for i in 0..BLOCK {
            for j in 0..4 {
                self.t_re[j][i] = pr[j];
                self.t_im[j][i] = pi[j];
                let (c, s) = one[j];
                (pr[j], pi[j]) = (pr[j] * c - pi[j] * s, pi[j] * c + pr[j] * s);
            }
        }
        let (mut ur, mut ui) = ([1.0; 4], [0.0; 4]);
        for (re, im) in self.u_re.iter_mut().zip(self.u_im.iter_mut()) {
            *re = ur;
            *im = ui;
            for j in 0..4 {
                let (c, s) = big[j];
                (ur[j], ui[j]) = (ur[j] * c - ui[j] * s, ui[j] * c + ur[j] * s);
            }
        }
    }

    /// e^{−iδ}, e^{−iBδ} of δ = πd/l for wheels a distance `d` (m) behind wheel 0.
    #[cold]
    fn offset_rotations(d: f64, length: f64) -> (f64, [f64; 4]) {
        let delta = PI * d / length;
        let (s, c) = delta.sin_cos();
        let (sb, cb) = (BLOCK as f64 * delta).sin_cos();
        (d, [c, s, cb, sb])
    }

    /// Rail displacement Zr (m) under each wheel (after [`Track::set_wheels`]) from modal `q`:
    /// Σ_k sin(kπx_j/l) q_k = Σ_i [Re T_i Σ_b Im U_b q_{bB+i} + Im T_i Σ_b Re U_b q_{bB+i}].
    #[inline(always)]
    pub fn rail_at_wheels(&self, q: &[f64]) -> [f64; 4] {
        if let Some(pl) = &self.plain {
            return pl.rail_at_wheels(self.scale, q);
        }
        let q = &q[..self.nm];
        let blocks = q.chunks_exact(BLOCK);
        let tail = blocks.remainder();
        let mut out = [0.0; 4];
        for j in 0..4 {
            let (mut vr, mut vi) = ([0.0; BLOCK], [0.0; BLOCK]);
            for ((qb, ur), ui) in blocks.clone().zip(&self.u_re).zip(&self.u_im) {
                let (ur, ui) = (ur[j], ui[j]);
                for ((r, i), &qk) in vr.iter_mut().zip(vi.iter_mut()).zip(qb) {
                    *r += ui * qk;
                    *i += ur * qk;
                }
            }
            let last = q.len() / BLOCK;
            for ((r, i), &qk) in vr.iter_mut().zip(vi.iter_mut()).zip(tail) {
                *r += self.u_im[last][j] * qk;
                *i += self.u_re[last][j] * qk;
            }
            let mut sum = [0.0; 4];
            for (l, ((&tr, &ti), (&r, &i))) in self.t_re[j]
                .iter()
                .zip(&self.t_im[j])
                .zip(vr.iter().zip(&vi))
                .enumerate()
            {
                sum[l % 4] += tr * r + ti * i;
            }
            out[j] = ((sum[0] + sum[1]) + (sum[2] + sum[3])) * self.scale;
        }
        out
    }

    /// Value of mode shape sin(kπx_j/l) at wheel j (after [`Track::set_wheels`]), k ≥ 1.
    pub fn wheel_sine(&self, j: usize, k: usize) -> f64 {
        match &self.plain {
            Some(pl) => pl.wheel_sine(j, k),
            None => {
                let (b, i) = ((k - 1) / BLOCK, (k - 1) % BLOCK);
                self.u_im[b][j] * self.t_re[j][i] + self.u_re[b][j] * self.t_im[j][i]
            }
        }
    }

    /// Track accelerations `acc` from positions `y`, velocities `yd` (track layout) and the
    /// wheel–rail forces `p` (N) at the wheels set by [`Track::set_wheels`]. No allocation.
    ///
    /// The fast kernel: two sine transforms ([`DstI`]) and straight loops over zipped slices
    /// (no bounds checks, vectorized); the modal forces of pads, stiffness and wheels in one
    /// pass; the ballast shear through a scratch array instead of a loop-carried update.
    #[inline(always)]
    pub fn accelerations(&mut self, y: &[f64], yd: &[f64], p: &[f64; 4], acc: &mut [f64]) {
        if self.plain.is_some() {
            plain::accelerations(self, y, yd, p, acc);
            return;
        }
        let (n, nm, scale) = (self.n, self.nm, self.scale);
        let t = self.p;
        let (q, rest) = y[..nm + 2 * n].split_at(nm);
        let (zs, zb) = rest.split_at(n);
        let (qd, rest) = yd[..nm + 2 * n].split_at(nm);
        let (zsd, zbd) = rest.split_at(n);
        let (acc_q, rest) = acc[..nm + 2 * n].split_at_mut(nm);
        let (acc_s, acc_b) = rest.split_at_mut(n);
        // The pads only see Kp Zr + Cp Zr' at the sleepers: one transform of Kp q + Cp q'.
        if nm <= n {
            for ((b, &a), &ad) in self.bins.iter_mut().zip(q).zip(qd) {
                *b = t.kp * a + t.cp * ad;
            }
            self.bins[nm..].fill(0.0);
        } else {
            // Folded as it is computed (the same sums as `fold` of the modal vector, one pass,
            // no modal scratch): bin j of the sleeper grid gets mode j + 1, less mode
            // 2N + 1 − j (its mirror beyond mode N + 1) where NM reaches it.
            let folded = nm - n - 1;
            let plain = n - folded;
            let (bins_plain, bins_folded) = self.bins.split_at_mut(plain);
            for ((b, &a), &ad) in bins_plain.iter_mut().zip(q).zip(qd) {
                *b = t.kp * a + t.cp * ad;
            }
            // Bin plain + u (u = 0..folded) takes mode plain + u + 1 and mode 2N + 1 − plain − u
            // (0-based 2N − plain − u: descending from nm − 1 to n + 1).
            let (q_mid, q_mirror) = (&q[plain..n], &q[n + 1..nm]);
            let (qd_mid, qd_mirror) = (&qd[plain..n], &qd[n + 1..nm]);
            for u in 0..folded {
                let v = folded - 1 - u;
                let own = t.kp * q_mid[u] + t.cp * qd_mid[u];
                let mirror = t.kp * q_mirror[v] + t.cp * qd_mirror[v];
                bins_folded[u] = own - mirror;
            }
        }
        self.dst.transform(&self.bins, &mut self.r);
        let (inv_ms, inv_mb) = (1.0 / t.ms, 1.0 / t.mb);
        let sleepers = self
            .r
            .iter()
            .zip(&mut self.frs)
            .zip(zs.iter().zip(zsd))
            .zip(zb.iter().zip(zbd))
            .zip(acc_s.iter_mut().zip(acc_b.iter_mut()));
        for ((((&r, f), (&s, &sd)), (&b, &bd)), (a_s, a_b)) in sleepers {
            let frs = r * scale - t.kp * s - t.cp * sd;
            let fb = t.kb * (s - b) + t.cb * (sd - bd);
            *f = frs;
            *a_s = (frs - fb) * inv_ms;
            *a_b = (fb - t.kf * b - t.cf * bd) * inv_mb;
        }
        // Ballast shear: Kw, Cw between neighbouring blocks (end blocks have one neighbour).
        let (kw, cw) = (t.kw * inv_mb, t.cw * inv_mb);
        let pairs = zb.windows(2).zip(zbd.windows(2));
        for (sh, (b, bd)) in self.shear[1..n].iter_mut().zip(pairs) {
            *sh = kw * (b[0] - b[1]) + cw * (bd[0] - bd[1]);
        }
        self.shear[0] = 0.0;
        self.shear[n] = 0.0;
        for (a, sh) in acc_b.iter_mut().zip(self.shear.windows(2)) {
            *a = (*a + sh[0]) - sh[1];
        }
        // Modal forces: stiffness, pads (the transposed map), wheels.
        self.dst.transform(&self.frs, &mut self.bins);
        let c = -scale;
        if nm <= n {
            let modes = acc_q
                .iter_mut()
                .zip(q)
                .zip(&self.omega2)
                .zip(&self.bins[..nm]);
            for (((a, &qk), &w2), &b) in modes {
                *a = -w2 * qk + c * b;
            }
        } else {
            // Two contiguous loops: modes 1 … N read bin k - 1; mode N + 1 (a node at every
            // sleeper) none; modes N + 2 … NM read bins N - 1, N - 2, … with the sign flipped.
            let (a_low, a_high) = acc_q.split_at_mut(n);
            let (q_low, q_high) = q.split_at(n);
            let (w_low, w_high) = self.omega2.split_at(n);
            let low = a_low.iter_mut().zip(q_low).zip(w_low).zip(&self.bins);
            for (((a, &qk), &w2), &b) in low {
                *a = -w2 * qk + c * b;
            }
            a_high[0] = -w_high[0] * q_high[0];
            let high = a_high[1..]
                .iter_mut()
                .zip(&q_high[1..])
                .zip(&w_high[1..])
                .zip(self.bins.iter().rev());
            for (((a, &qk), &w2), &b) in high {
                *a = -w2 * qk + -c * b;
            }
        }
        let cw: [f64; 4] = std::array::from_fn(|j| scale * p[j]);
        self.add_wheel_forces(&cw, acc_q);
    }

    /// `acc_q[k] += Σ_j cw_j sin((k+1)πx_j/l)`, block by block: within block b the wheel
    /// term is Σ_j (cw_j Im U_b) Re T_i + (cw_j Re U_b) Im T_i.
    #[inline(always)]
    fn add_wheel_forces(&self, cw: &[f64; 4], acc_q: &mut [f64]) {
        let (tr, ti) = (&self.t_re, &self.t_im);
        let term = |a: &[f64; 4], b: &[f64; 4], i: usize| {
            ((a[0] * tr[0][i] + b[0] * ti[0][i]) + (a[1] * tr[1][i] + b[1] * ti[1][i]))
                + ((a[2] * tr[2][i] + b[2] * ti[2][i]) + (a[3] * tr[3][i] + b[3] * ti[3][i]))
        };
        let coefficients = |blk: usize| -> ([f64; 4], [f64; 4]) {
            let (ur, ui) = (&self.u_re[blk], &self.u_im[blk]);
            (
                std::array::from_fn(|j| cw[j] * ui[j]),
                std::array::from_fn(|j| cw[j] * ur[j]),
            )
        };
        let mut blocks = acc_q.chunks_exact_mut(BLOCK);
        for (blk, out) in (&mut blocks).enumerate() {
            let (a, b) = coefficients(blk);
            let out: &mut [f64; BLOCK] = out.try_into().expect("a whole block");
            for (i, o) in out.iter_mut().enumerate() {
                *o += term(&a, &b, i);
            }
        }
        let tail = blocks.into_remainder();
        if !tail.is_empty() {
            let (a, b) = coefficients(self.nm / BLOCK);
            for (i, o) in tail.iter_mut().enumerate() {
                *o += term(&a, &b, i);
            }
        }
    }

    /// Static stiffness product `out = K y` (track layout).
    fn stiffness_product(&mut self, y: &[f64], out: &mut [f64]) {
        let (n, nm) = (self.n, self.nm);
        let t = self.p;
        let (q, zs, zb) = (&y[..nm], &y[nm..nm + n], &y[nm + n..]);
        Self::synthesize(&mut self.dst, self.scale, q, &mut self.bins, &mut self.r);
        let (out_q, rest) = out.split_at_mut(nm);
        let (out_s, out_b) = rest.split_at_mut(n);
        for i in 0..n {
            let f = t.kp * (self.r[i] - zs[i]);
            let fb = t.kb * (zs[i] - zb[i]);
            let mut dz = 0.0;
            if i > 0 {
                dz += zb[i] - zb[i - 1];
            }
            if i + 1 < n {
                dz += zb[i] - zb[i + 1];
            }
            self.frs[i] = f;
            out_s[i] = -f + fb;
            out_b[i] = -fb + t.kf * zb[i] + t.kw * dz;
        }
        for ((o, &w2), &qk) in out_q.iter_mut().zip(&self.omega2).zip(q) {
            *o = w2 * qk;
        }
        self.analyze_add(1.0, out_q);
    }

    /// Static deflection of the track under wheel loads `p` (N) at the wheels set by
    /// [`Track::set_wheels`], by Jacobi-preconditioned conjugate gradients on the symmetric
    /// positive definite stiffness. Writes the track positions into `y`; returns the
    /// number of iterations.
    pub fn static_solve(&mut self, p: &[f64; 4], y: &mut [f64]) -> Result<usize, String> {
        let (n, nm, dim) = (self.n, self.nm, self.dim());
        let t = self.p;
        let mut b = vec![0.0; dim];
        for (k, bk) in b[..nm].iter_mut().enumerate() {
            *bk = self.scale
                * (0..4)
                    .map(|j| p[j] * self.wheel_sine(j, k + 1))
                    .sum::<f64>();
        }
        let half = (n + 1) as f64 / 2.0;
        let mut diag = vec![0.0; dim];
        for k in 0..nm {
            let sup = if k == n {
                0.0
            } else {
                t.kp * self.scale * self.scale * half
            };
            diag[k] = self.omega2[k] + sup;
        }
        for i in 0..n {
            let deg = (i > 0) as usize + (i + 1 < n) as usize;
            diag[nm + i] = t.kp + t.kb;
            diag[nm + n + i] = t.kb + t.kf + t.kw * deg as f64;
        }
        y.iter_mut().for_each(|v| *v = 0.0);
        let mut r = b.clone();
        let mut z: Vec<f64> = r.iter().zip(&diag).map(|(r, d)| r / d).collect();
        let mut d = z.clone();
        let mut kd = vec![0.0; dim];
        let norm_b = b.iter().map(|v| v * v).sum::<f64>().sqrt();
        if norm_b == 0.0 {
            return Ok(0);
        }
        let mut rz: f64 = r.iter().zip(&z).map(|(a, b)| a * b).sum();
        let max_iter = 50 * dim + 100;
        for it in 1..=max_iter {
            self.stiffness_product(&d, &mut kd);
            let dkd: f64 = d.iter().zip(&kd).map(|(a, b)| a * b).sum();
            let alpha = rz / dkd;
            for i in 0..dim {
                y[i] += alpha * d[i];
                r[i] -= alpha * kd[i];
            }
            let norm_r = r.iter().map(|v| v * v).sum::<f64>().sqrt();
            if norm_r <= 1e-13 * norm_b {
                return Ok(it);
            }
            for i in 0..dim {
                z[i] = r[i] / diag[i];
            }
            let rz_new: f64 = r.iter().zip(&z).map(|(a, b)| a * b).sum();
            let beta = rz_new / rz;
            rz = rz_new;
            for i in 0..dim {
                d[i] = z[i] + beta * d[i];
            }
        }
        Err(format!(
            "static track deflection: conjugate gradients did not converge in {max_iter} iterations"
        ))
    }

    /// Moves the computing window forward by `m` sleepers for one state array `y` (track
    /// layout): a point at local x moves to x − m l_s. Sleepers and ballast shift by m
    /// entries (new ones ahead start at rest); the rail is sampled on the half-spacing grid
    /// (a DST-I of size 2N+1, exact for NM ≤ 2N+1), shifted, and projected back on the NM modes.
    pub fn shift(&mut self, m: usize, y: &mut [f64]) {
        let (n, nm) = (self.n, self.nm);
        let nf = 2 * n + 1;
        self.fine.iter_mut().for_each(|v| *v = 0.0);
        self.fine[..nm].copy_from_slice(&y[..nm]);
        self.dst_fine.transform(&self.fine, &mut self.fine_out);
        for j in 0..nf {
            self.fine[j] = if j + 2 * m < nf {
                self.fine_out[j + 2 * m]
            } else {
                0.0
            };
        }
        self.dst_fine.transform(&self.fine, &mut self.fine_out);
        let c = 2.0 / (nf + 1) as f64;
        for k in 0..nm {
            y[k] = c * self.fine_out[k];
        }
        for part in y[nm..nm + 2 * n].chunks_mut(n) {
            for i in 0..n {
                part[i] = if i + m < n { part[i + m] } else { 0.0 };
            }
        }
    }
}

/// Folds modal amplitudes onto the N sleeper bins of the sine transform (NM ≤ 2N + 1):
/// sin(kπi/(N+1)) for k = N + 1 + r equals −sin((N + 1 − r)πi/(N+1)), so mode k ≤ N goes to
/// bin k − 1, mode N + 1 (a node at every sleeper) nowhere, and mode N + 1 + r to bin N − r
/// with the sign flipped. Two contiguous loops, no index table.
fn fold(modal: &[f64], bins: &mut [f64]) {
    let n = bins.len();
    let (low, high) = modal.split_at(modal.len().min(n));
    bins[..low.len()].copy_from_slice(low);
    bins[low.len()..].fill(0.0);
    for (b, &w) in bins.iter_mut().rev().zip(high.iter().skip(1)) {
        *b -= w;
    }
}

#[cfg(test)]
pub(crate) mod tests;
