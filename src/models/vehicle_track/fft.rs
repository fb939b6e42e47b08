//! Radix-2 complex FFT, and the discrete sine transform DST-I built on it.
//!
//! The rail of the vehicle–track model is expanded in the modes `sin(kπx/l)` of a simply
//! supported beam; at the evenly spaced sleepers `x_i = i l/(N+1)` the matrix
//! `sin(kπ i/(N+1))` is a DST-I, which [`DstI`] applies in O(N log N) instead of O(N²):
//!
//! ```text
//! S_i = Σ_{k=1}^{N} b_k sin(π k i / n),   i = 1..N,   n = N + 1 a power of two.
//! ```
//!
//! Algorithm (the classical one, e.g. Press et al., *Numerical Recipes*, §12.3 "sinft"):
//! form `y_j = sin(jπ/n)(b_j + b_{n−j}) + ½(b_j − b_{n−j})`, take its real DFT
//! `R_k − i I_k = Σ_j y_j e^{−2πijk/n}` (a complex FFT of length n/2 plus one twiddle pass),
//! then `S_{2k} = I_k`, `S_1 = R_0/2`, `S_{2k+1} = S_{2k−1} + R_k`. The DST-I matrix is
//! symmetric and `D·D = (n/2) I`, so the same routine maps modes to sleepers and sleeper
//! forces back to modal forces, and `(2/n) D` inverts it.
//!
//! [`DstI`] runs the complex FFT of the rustfft crate (planned once, with its scratch); the
//! own radix-2 [`Fft`] serves the irregularity generator and [`PlainDstI`], the plain
//! reference the fast transform is tested against. Nothing here allocates per transform.
#![forbid(unsafe_code)]

use std::f64::consts::PI;
use std::sync::Arc;

/// A complex number (no arithmetic traits: the few operations needed are written out).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Complex {
    /// Real part.
    pub re: f64,
    /// Imaginary part.
    pub im: f64,
}

impl Complex {
    /// `re + i im`.
    pub const fn new(re: f64, im: f64) -> Self {
        Self { re, im }
    }
    #[inline]
    fn mul(self, o: Self) -> Self {
        Self::new(
            self.re * o.re - self.im * o.im,
            self.re * o.im + self.im * o.re,
        )
    }
    #[inline]
    fn conj(self) -> Self {
        Self::new(self.re, -self.im)
    }
}

/// In-place iterative radix-2 FFT plan of a fixed power-of-two length.
#[derive(Clone, Debug)]
pub struct Fft {
    n: usize,
    /// Twiddles of every stage, contiguous: for the stage of half-length h (h = 2, 4, ..,
    /// n/2), `e^{−iπk/h}`, k = 0..h, starting at offset h − 2.
    twiddles: Vec<Complex>,
    /// Bit-reversed index of each position.
    bitrev: Vec<u32>,
}

impl Fft {
    /// Plans an FFT of length `n` (a power of two, ≥ 1).
    pub fn new(n: usize) -> Result<Self, String> {
        if n == 0 || !n.is_power_of_two() || n > (1 << 30) {
            return Err(format!(
                "FFT length {n} must be a power of two between 1 and 2^30"
            ));
        }
        let mut twiddles = Vec::with_capacity(n);
        let mut h = 2;
        while h < n {
            for k in 0..h {
                let a = -PI * k as f64 / h as f64;
                twiddles.push(Complex::new(a.cos(), a.sin()));
            }
            h *= 2;
        }
        let bits = n.trailing_zeros();
        let bitrev = (0..n as u32)
            .map(|i| {
                if bits == 0 {
                    0
                } else {
                    i.reverse_bits() >> (32 - bits)
                }
            })
            .collect();
        Ok(Self {
            n,
            twiddles,
            bitrev,
        })
    }

    /// The planned length.
    pub fn len(&self) -> usize {
        self.n
    }

    /// Whether the planned length is zero (never: kept for the `len` convention).
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// `X_k = Σ_j x_j e^{−2πijk/n}` in place (no normalisation).
    pub fn forward(&self, data: &mut [Complex]) {
        let n = self.n;
        assert_eq!(data.len(), n, "FFT buffer length");
        for i in 0..n {
            let j = self.bitrev[i] as usize;
            if i < j {
                data.swap(i, j);
            }
        }
        if n < 2 {
            return;
        }
        // Stage h = 1: butterflies without twiddles.
        for pair in data.chunks_exact_mut(2) {
            let (a, b) = (pair[0], pair[1]);
            pair[0] = Complex::new(a.re + b.re, a.im + b.im);
            pair[1] = Complex::new(a.re - b.re, a.im - b.im);
        }
        let mut half = 2;
        while half < n {
            let tw = &self.twiddles[half - 2..2 * half - 2];
            for block in data.chunks_exact_mut(2 * half) {
                let (lo, hi) = block.split_at_mut(half);
                for ((a, b), w) in lo.iter_mut().zip(hi.iter_mut()).zip(tw) {
                    let t = b.mul(*w);
                    let u = *a;
                    *a = Complex::new(u.re + t.re, u.im + t.im);
                    *b = Complex::new(u.re - t.re, u.im - t.im);
                }
            }
            half *= 2;
        }
    }

    /// `x_j = Σ_k X_k e^{+2πijk/n}` in place (no 1/n factor).
    pub fn backward(&self, data: &mut [Complex]) {
        for z in data.iter_mut() {
            *z = z.conj();
        }
        self.forward(data);
        for z in data.iter_mut() {
            *z = z.conj();
        }
    }
}

/// Which complex FFT of rustfft a [`DstI`] runs on. rustfft selects its instruction set at
/// run time ([`FftPath::Auto`]: AVX, else SSE4.1, else scalar); the others force one path,
/// so that tests can check every path the machine has.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum FftPath {
    /// rustfft's own choice for this CPU.
    #[default]
    Auto,
    /// Portable scalar code.
    Scalar,
    /// SSE4.1 (x86_64 only).
    Sse,
    /// AVX and FMA (x86_64 only).
    Avx,
}

impl FftPath {
    /// The paths this machine can run (always `Auto` and `Scalar`).
    pub fn available() -> Vec<FftPath> {
        let mut v = vec![FftPath::Auto, FftPath::Scalar];
        if rustfft::FftPlannerSse::<f64>::new().is_ok() {
            v.push(FftPath::Sse);
        }
        if rustfft::FftPlannerAvx::<f64>::new().is_ok() {
            v.push(FftPath::Avx);
        }
        v
    }

    /// The instruction set this path runs on here, as recorded in the model's
    /// `solver.kernel`: `Auto` resolved as rustfft's planner resolves it (AVX with FMA, else
    /// SSE4.1, else Neon, else scalar).
    pub fn isa_name(self) -> &'static str {
        match self {
            FftPath::Auto if rustfft::FftPlannerAvx::<f64>::new().is_ok() => "avx+fma",
            FftPath::Auto if rustfft::FftPlannerSse::<f64>::new().is_ok() => "sse4.1",
            FftPath::Auto if rustfft::FftPlannerNeon::<f64>::new().is_ok() => "neon",
            FftPath::Auto | FftPath::Scalar => "scalar",
            FftPath::Sse => "sse4.1",
            FftPath::Avx => "avx+fma",
        }
    }

    fn plan(self, len: usize) -> Result<Arc<dyn rustfft::Fft<f64>>, String> {
        let dir = rustfft::FftDirection::Forward;
        let unsupported = || format!("FFT path {self:?} is not supported by this CPU");
        Ok(match self {
            FftPath::Auto => rustfft::FftPlanner::new().plan_fft(len, dir),
            FftPath::Scalar => rustfft::FftPlannerScalar::new().plan_fft(len, dir),
            FftPath::Sse => rustfft::FftPlannerSse::new()
                .map_err(|()| unsupported())?
                .plan_fft(len, dir),
            FftPath::Avx => rustfft::FftPlannerAvx::new()
                .map_err(|()| unsupported())?
                .plan_fft(len, dir),
        })
    }
}

type C64 = rustfft::num_complex::Complex<f64>;

/// DST-I plan of size `N` (with `N + 1` a power of two), see the module documentation: the
/// same algorithm as [`PlainDstI`], on rustfft's complex FFT, with the passes before and
/// after it written as straight loops the compiler vectorizes.
#[derive(Clone)]
pub struct DstI {
    size: usize,
    n: usize,
    fft: Arc<dyn rustfft::Fft<f64>>,
    path: FftPath,
    /// `sin(jπ/n)`, j = 0..n.
    sin_j: Vec<f64>,
    /// Re and Im of `e^{−2πik/n}`, k = 0..n/2.
    w_re: Vec<f64>,
    w_im: Vec<f64>,
    /// Scratch: I_k, k = 0..n/2.
    y: Vec<f64>,
    /// Scratch: the packed sequence, and rustfft's scratch.
    z: Vec<C64>,
    scratch: Vec<C64>,
    /// Scratch: R_k, k = 0..n/2.
    r: Vec<f64>,
}

impl std::fmt::Debug for DstI {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("DstI")
            .field("size", &self.size)
            .field("path", &self.path)
            .finish_non_exhaustive()
    }
}

impl DstI {
    /// Plans a DST-I of `size` points on rustfft's choice of instruction set; `size + 1`
    /// must be a power of two ≥ 2.
    pub fn new(size: usize) -> Result<Self, String> {
        Self::with_path(size, FftPath::Auto)
    }

    /// Plans a DST-I of `size` points on the FFT path `path`.
    pub fn with_path(size: usize, path: FftPath) -> Result<Self, String> {
        let n = dst_points(size)?;
        let m = n / 2;
        let fft = path.plan(m)?;
        let scratch = vec![C64::default(); fft.get_inplace_scratch_len()];
        let w = |k: usize| -2.0 * PI * k as f64 / n as f64;
        Ok(Self {
            size,
            n,
            fft,
            path,
            sin_j: (0..n).map(|j| (PI * j as f64 / n as f64).sin()).collect(),
            w_re: (0..m).map(|k| w(k).cos()).collect(),
            w_im: (0..m).map(|k| w(k).sin()).collect(),
            y: vec![0.0; m],
            z: vec![C64::default(); m],
            scratch,
            r: vec![0.0; m],
        })
    }

    /// The FFT path this plan runs on.
    pub fn path(&self) -> FftPath {
        self.path
    }

    /// The number of points N.
    pub fn len(&self) -> usize {
        self.size
    }

    /// Whether N is zero (never).
    pub fn is_empty(&self) -> bool {
        self.size == 0
    }

    /// `out[i−1] = Σ_{k=1}^{N} input[k−1] sin(π k i/(N+1))`, i = 1..N. No allocation.
    ///
    /// The passes around the FFT are straight indexed loops over slices of their exact length
    /// (one exit, no bounds checks, no branch), which the compiler vectorizes; an index
    /// running backwards is a lane permutation.
    #[inline(always)]
    pub fn transform(&mut self, input: &[f64], out: &mut [f64]) {
        let (n, size) = (self.n, self.size);
        assert!(
            input.len() == size && out.len() == size,
            "DST-I buffer length"
        );
        let m = n / 2;
        if m == 1 {
            out[0] = input[0];
            return;
        }
        // y_j = sin(jπ/n)(b_j + b_{n−j}) + ½(b_j − b_{n−j}), j = 1..n−1, y_0 = 0, b_j = input[j − 1],
        // written straight into the FFT buffer: z_p = y_{2p} + i y_{2p+1} is y in memory.
        let y: &mut [f64] = bytemuck::cast_slice_mut(&mut self.z[..m]);
        y[0] = 0.0;
        let len = n - 1;
        let (inp, sin_j, y) = (&input[..len], &self.sin_j[1..n], &mut y[1..n]);
        for t in 0..len {
            let (bj, bc) = (inp[t], inp[len - 1 - t]);
            y[t] = sin_j[t] * (bj + bc) + 0.5 * (bj - bc);
        }
        self.fft
            .process_with_scratch(&mut self.z, &mut self.scratch);
        // Real DFT Y_k = R_k − i I_k = E_k + w_k O_k of y, with E_k = (Z_k + conj Z_{m−k})/2 and
        // O_k = (Z_k − conj Z_{m−k})/(2i), k = 1..m−1: I_k and R_k into two arrays. With
        // a ± c of the real and imaginary parts of Z_k = a_r + i a_i and Z_{m−k} = c_r + i c_i,
        //   R_k =  ½ ((a_r + c_r) + w_r (a_i + c_i) + w_i (a_r − c_r)),
        //   I_k = −½ ((a_i − c_i) − w_r (a_r − c_r) + w_i (a_i + c_i)):
        // the halves taken once at the end instead of on each of E and O (a factor ½ is exact
        // barring subnormal numbers, so these are the same bits), 14 operations per k, not 17.
        let z = &self.z[..m];
        let (odd, r) = (&mut self.y[..m], &mut self.r[..m]);
        let terms = z[1..]
            .iter()
            .zip(z[1..].iter().rev())
            .zip(self.w_re[1..m].iter().zip(&self.w_im[1..m]));
        for ((o, r), ((a, c), (&wr, &wi))) in odd[1..].iter_mut().zip(&mut r[1..]).zip(terms) {
            let (sr, dr) = (a.re + c.re, a.re - c.re);
            let (si, di) = (a.im + c.im, a.im - c.im);
            *r = 0.5 * (sr + wr * si + wi * dr);
            *o = -0.5 * (di - wr * dr + wi * si);
        }
        // S_1 = R_0/2, S_{2k+1} = S_{2k−1} + R_k: a prefix sum in place, in four blocks run
        // side by side (independent chains); each block is offset by the sums of the blocks
        // before it as it is written out (one pass less). S_{2k} = I_k, S_{2k+1} = prefix_k.
        r[0] = 0.5 * (z[0].re + z[0].im);
        out[0] = r[0];
        if m < 8 {
            for k in 1..m {
                r[k] += r[k - 1];
            }
            for (o, (&i, &s)) in out[1..]
                .chunks_exact_mut(2)
                .zip(odd[1..].iter().zip(&r[1..]))
            {
                o[0] = i;
                o[1] = s;
            }
            return;
        }
        let q = m / 4;
        let (b0, rest) = r.split_at_mut(q);
        let (b1, rest) = rest.split_at_mut(q);
        let (b2, b3) = rest.split_at_mut(q);
        let mut acc = [0.0; 4];
        for (((v0, v1), v2), v3) in b0
            .iter_mut()
            .zip(b1.iter_mut())
            .zip(b2.iter_mut())
            .zip(b3.iter_mut())
        {
            acc[0] += *v0;
            *v0 = acc[0];
            acc[1] += *v1;
            *v1 = acc[1];
            acc[2] += *v2;
            *v2 = acc[2];
            acc[3] += *v3;
            *v3 = acc[3];
        }
        let (o1, o2) = (acc[0], acc[0] + acc[1]);
        let o3 = o2 + acc[2];
        // Block 0 as it is (k = 1..q−1, pairs out[2k−1], out[2k]), then blocks 1..3 with their
        // offsets (k = cq..cq+q−1).
        let (first, rest) = out[1..].split_at_mut(2 * (q - 1));
        for (o, (&i, &s)) in first
            .chunks_exact_mut(2)
            .zip(odd[1..q].iter().zip(&b0[1..]))
        {
            o[0] = i;
            o[1] = s;
        }
        let blocks = [(&*b1, o1), (&*b2, o2), (&*b3, o3)];
        for ((c, (blk, off)), part) in (1..).zip(blocks).zip(rest.chunks_exact_mut(2 * q)) {
            for (o, (&i, &s)) in part
                .chunks_exact_mut(2)
                .zip(odd[c * q..(c + 1) * q].iter().zip(blk))
            {
                o[0] = i;
                o[1] = s + off;
            }
        }
    }
}

/// n = N + 1 of a DST-I of N = `size` points, or why it cannot be planned: `size + 1` must
/// be a power of two ≥ 2.
fn dst_points(size: usize) -> Result<usize, String> {
    let n = size + 1;
    if size == 0 || !n.is_power_of_two() {
        return Err(format!(
            "DST-I size {size}: size + 1 must be a power of two (e.g. 63, 127, 255, 511)"
        ));
    }
    Ok(n)
}

/// The plain DST-I on the own radix-2 [`Fft`]: the reference implementation the fast
/// [`DstI`] is tested against (and what the plain kernel of the track uses).
#[derive(Clone, Debug)]
pub struct PlainDstI {
    /// N, the number of interior points.
    size: usize,
    /// n = N + 1.
    n: usize,
    /// Complex FFT of length n/2 (the real FFT of length n).
    fft: Fft,
    /// `sin(jπ/n)`, j = 0..n.
    sin_j: Vec<f64>,
    /// `e^{−2πik/n}`, k = 0..n/2 (real-FFT post-processing).
    w: Vec<Complex>,
    /// Scratch: the packed real sequence.
    z: Vec<Complex>,
}

impl PlainDstI {
    /// Plans a DST-I of `size` points; `size + 1` must be a power of two ≥ 2.
    pub fn new(size: usize) -> Result<Self, String> {
        let n = dst_points(size)?;
        let m = n / 2;
        Ok(Self {
            size,
            n,
            fft: Fft::new(m)?,
            sin_j: (0..n).map(|j| (PI * j as f64 / n as f64).sin()).collect(),
            w: (0..m)
                .map(|k| {
                    let a = -2.0 * PI * k as f64 / n as f64;
                    Complex::new(a.cos(), a.sin())
                })
                .collect(),
            z: vec![Complex::default(); m],
        })
    }

    /// The number of points N.
    pub fn len(&self) -> usize {
        self.size
    }

    /// Whether N is zero (never).
    pub fn is_empty(&self) -> bool {
        self.size == 0
    }

    /// `out[i−1] = Σ_{k=1}^{N} input[k−1] sin(π k i/(N+1))`, i = 1..N. No allocation.
    pub fn transform(&mut self, input: &[f64], out: &mut [f64]) {
        let (n, size) = (self.n, self.size);
        assert!(
            input.len() == size && out.len() == size,
            "DST-I buffer length"
        );
        let m = n / 2;
        if m == 1 {
            // n = 2, N = 1: S_1 = b_1 sin(π/2).
            out[0] = input[0];
            return;
        }
        // y_j = sin(jπ/n)(b_j + b_{n−j}) + ½(b_j − b_{n−j}), y_0 = 0, with b_j = input[j − 1];
        // packed as z_p = y_{2p} + i y_{2p+1}.
        let y = |j: usize| {
            let (bj, bc) = (input[j - 1], input[n - j - 1]);
            self.sin_j[j] * (bj + bc) + 0.5 * (bj - bc)
        };
        self.z[0] = Complex::new(0.0, y(1));
        for p in 1..m {
            self.z[p] = Complex::new(y(2 * p), y(2 * p + 1));
        }
        self.fft.forward(&mut self.z);
        // Real DFT Y_k = R_k − i I_k = E_k + w_k O_k of y, with E_k = (Z_k + conj Z_{m−k})/2 and
        // O_k = (Z_k − conj Z_{m−k})/(2i); then S_1 = R_0/2, S_{2k} = I_k, S_{2k+1} = S_{2k−1} + R_k.
        let z0 = self.z[0];
        let mut s_odd = 0.5 * (z0.re + z0.im); // R_0 = Re Z_0 + Im Z_0
        out[0] = s_odd;
        for k in 1..m {
            let zk = self.z[k];
            let zc = self.z[m - k];
            let (er, ei) = (0.5 * (zk.re + zc.re), 0.5 * (zk.im - zc.im));
            let (or, oi) = (0.5 * (zk.im + zc.im), -0.5 * (zk.re - zc.re));
            let w = self.w[k];
            let r = er + w.re * or - w.im * oi;
            let i = -(ei + w.re * oi + w.im * or);
            out[2 * k - 1] = i;
            s_odd += r;
            out[2 * k] = s_odd;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The fast transform as it was before its passes were rewritten (the post-processing with
    /// the halves on E and O, the block offsets in a pass of their own): the new passes must
    /// give the very same bits.
    fn previous_transform(d: &mut DstI, input: &[f64], out: &mut [f64]) {
        let (n, size) = (d.n, d.size);
        assert!(input.len() == size && out.len() == size);
        let m = n / 2;
        if m == 1 {
            out[0] = input[0];
            return;
        }
        let y: &mut [f64] = bytemuck::cast_slice_mut(&mut d.z[..m]);
        let (inp, sin_j) = (&input[..n - 1], &d.sin_j[..n]);
        y[0] = 0.0;
        for (((y, &s), &bj), &bc) in y[1..]
            .iter_mut()
            .zip(&sin_j[1..])
            .zip(inp)
            .zip(inp.iter().rev())
        {
            *y = s * (bj + bc) + 0.5 * (bj - bc);
        }
        d.fft.process_with_scratch(&mut d.z, &mut d.scratch);
        let z = &d.z[..m];
        let (odd, r) = (&mut d.y[..m], &mut d.r[..m]);
        let terms = z[1..]
            .iter()
            .zip(z[1..].iter().rev())
            .zip(d.w_re[1..m].iter().zip(&d.w_im[1..m]));
        for ((o, r), ((zk, zc), (&wr, &wi))) in odd[1..].iter_mut().zip(&mut r[1..]).zip(terms) {
            let (er, ei) = (0.5 * (zk.re + zc.re), 0.5 * (zk.im - zc.im));
            let (or, oi) = (0.5 * (zk.im + zc.im), -0.5 * (zk.re - zc.re));
            *r = er + wr * or - wi * oi;
            *o = -(ei + wr * oi + wi * or);
        }
        r[0] = 0.5 * (z[0].re + z[0].im);
        if m < 8 {
            for k in 1..m {
                r[k] += r[k - 1];
            }
        } else {
            let q = m / 4;
            let (b0, rest) = r.split_at_mut(q);
            let (b1, rest) = rest.split_at_mut(q);
            let (b2, b3) = rest.split_at_mut(q);
            let mut acc = [0.0; 4];
            for (((v0, v1), v2), v3) in b0
                .iter_mut()
                .zip(b1.iter_mut())
                .zip(b2.iter_mut())
                .zip(b3.iter_mut())
            {
                acc[0] += *v0;
                *v0 = acc[0];
                acc[1] += *v1;
                *v1 = acc[1];
                acc[2] += *v2;
                *v2 = acc[2];
                acc[3] += *v3;
                *v3 = acc[3];
            }
            let (o1, o2) = (acc[0], acc[0] + acc[1]);
            let o3 = o2 + acc[2];
            for (blk, off) in [(b1, o1), (b2, o2), (b3, o3)] {
                blk.iter_mut().for_each(|v| *v += off);
            }
        }
        out[0] = r[0];
        for (o, (&i, &s)) in out[1..]
            .chunks_exact_mut(2)
            .zip(odd[1..].iter().zip(&r[1..]))
        {
            o[0] = i;
            o[1] = s;
        }
    }

    /// The rewritten passes give the bits of the ones they replaced, on every FFT path and
    /// instruction set of this machine, and match a direct O(N²) sum.
    #[test]
    fn vectorized_passes_give_the_bits_of_the_previous_transform() {
        use crate::solver::simd::{Job, Simd};
        struct Both<'a> {
            new: &'a mut DstI,
            old: &'a mut DstI,
            b: &'a [f64],
            out: (Vec<f64>, Vec<f64>),
        }
        impl Job for Both<'_> {
            #[inline(always)]
            fn run(&mut self) {
                self.new.transform(self.b, &mut self.out.0);
                previous_transform(self.old, self.b, &mut self.out.1);
            }
        }
        for &size in &[1usize, 3, 7, 15, 31, 63, 127, 255, 511, 1023] {
            for path in FftPath::available() {
                for simd in Simd::available() {
                    for seed in 0..3 {
                        let b = pseudo_random(size, 31 * size as u64 + seed);
                        let (mut new, mut old) = (
                            DstI::with_path(size, path).unwrap(),
                            DstI::with_path(size, path).unwrap(),
                        );
                        let mut job = Both {
                            new: &mut new,
                            old: &mut old,
                            b: &b,
                            out: (vec![0.0; size], vec![0.0; size]),
                        };
                        simd.dispatch(&mut job);
                        let (a, p) = &job.out;
                        for i in 0..size {
                            assert_eq!(
                                a[i].to_bits(),
                                p[i].to_bits(),
                                "size {size}, {path:?}, {:?}, entry {i}: {} vs {}",
                                simd.isa(),
                                a[i],
                                p[i]
                            );
                        }
                        if size <= 255 {
                            let reference = direct_dst(&b);
                            let err = a
                                .iter()
                                .zip(&reference)
                                .map(|(x, r)| (x - r).abs())
                                .fold(0.0, f64::max);
                            assert!(err < 1e-12 * size as f64, "size {size}: {err:e}");
                        }
                    }
                }
            }
        }
    }

    fn direct_dst(b: &[f64]) -> Vec<f64> {
        let n = b.len() + 1;
        (1..n)
            .map(|i| {
                (1..n)
                    .map(|k| b[k - 1] * (PI * (k * i) as f64 / n as f64).sin())
                    .sum()
            })
            .collect()
    }

    fn pseudo_random(len: usize, seed: u64) -> Vec<f64> {
        let mut s = seed;
        (0..len)
            .map(|_| {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
            })
            .collect()
    }

    #[test]
    fn fft_matches_direct_dft() {
        for &n in &[1usize, 2, 4, 8, 64, 256] {
            let re = pseudo_random(n, 1);
            let im = pseudo_random(n, 2);
            let mut data: Vec<Complex> = re
                .iter()
                .zip(&im)
                .map(|(&a, &b)| Complex::new(a, b))
                .collect();
            Fft::new(n).unwrap().forward(&mut data);
            for k in 0..n {
                let (mut sr, mut si) = (0.0, 0.0);
                for j in 0..n {
                    let a = -2.0 * PI * (j * k) as f64 / n as f64;
                    sr += re[j] * a.cos() - im[j] * a.sin();
                    si += re[j] * a.sin() + im[j] * a.cos();
                }
                assert!((data[k].re - sr).abs() < 1e-12 * n as f64, "n={n} k={k}");
                assert!((data[k].im - si).abs() < 1e-12 * n as f64, "n={n} k={k}");
            }
        }
        assert!(Fft::new(12).is_err());
    }

    #[test]
    fn fast_dst_matches_direct_sum() {
        for &size in &[1usize, 3, 7, 15, 63, 255, 1023] {
            let b = pseudo_random(size, size as u64);
            let mut out = vec![0.0; size];
            let mut plan = DstI::new(size).unwrap();
            plan.transform(&b, &mut out);
            let reference = direct_dst(&b);
            let err = out
                .iter()
                .zip(&reference)
                .map(|(a, r)| (a - r).abs())
                .fold(0.0, f64::max);
            assert!(err < 1e-12 * size as f64, "size {size}: max error {err:e}");
        }
    }

    #[test]
    fn dst_is_its_own_inverse_up_to_n_over_2() {
        let size = 127;
        let b = pseudo_random(size, 9);
        let mut plan = DstI::new(size).unwrap();
        let (mut s, mut back) = (vec![0.0; size], vec![0.0; size]);
        plan.transform(&b, &mut s);
        plan.transform(&s, &mut back);
        for (x, y) in b.iter().zip(&back) {
            assert!((x - y * 2.0 / 128.0).abs() < 1e-13);
        }
    }

    #[test]
    fn dst_refuses_sizes_without_power_of_two() {
        assert!(DstI::new(0).is_err());
        assert!(DstI::new(100).is_err());
        assert!(DstI::new(127).is_ok());
    }
}
