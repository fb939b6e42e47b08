//! The 10-DOF half vehicle of Zhai's vertical model (one rail: masses and inertias of the
//! whole car halved, suspension values per side). Z is positive downward.
//!
//! ```text
//! DOFs  Zc, βc, Zt1, βt1, Zt2, βt2, Zw1..Zw4    (front bogie at Zc − Lc βc, wheel 1 at Zt1 − Lt βt1)
//! Fs1 = Ksz (Zc − Lc βc − Zt1) + Csz (Zc' − Lc βc' − Zt1')     Fs2: +Lc, Zt2
//! Fpj = Kpz (Zt_b ∓ Lt βt_b − Zwj) + Cpz (…)                  − for wheels 1, 3; + for 2, 4
//! Mc Zc''  = Mc g − Fs1 − Fs2          Jc βc''  = Lc (Fs1 − Fs2)
//! Mt Zt1'' = Mt g + Fs1 − Fp1 − Fp2    Jt βt1'' = Lt (Fp1 − Fp2)     (bogie 2: Fs2, Fp3, Fp4)
//! Mw Zwj'' = Mw g + Fpj − Pj
//! ```
//! Wheel 1 leads; along the track the wheels sit at x_c + (Lc + Lt, Lc − Lt, −Lc + Lt, −Lc − Lt).
//! Each body rests on two springs, so the half car is statically determinate: the static
//! suspension and contact forces follow from equilibrium alone ([`HalfVehicle::static_forces`]).
#![forbid(unsafe_code)]

/// Number of vehicle DOFs.
pub const NV: usize = 10;
/// Index of Zc (m).
pub const ZC: usize = 0;
/// Index of βc (rad).
pub const BC: usize = 1;
/// Index of Zt1 (m).
pub const ZT1: usize = 2;
/// Index of βt1 (rad).
pub const BT1: usize = 3;
/// Index of Zt2 (m).
pub const ZT2: usize = 4;
/// Index of βt2 (rad).
pub const BT2: usize = 5;
/// Index of Zw1 (m); Zw2..Zw4 follow.
pub const ZW1: usize = 6;

/// Half-vehicle data as the equations use it (values per rail).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HalfVehicle {
    /// Carbody mass Mc/2 (kg).
    pub mc: f64,
    /// Carbody pitch inertia Jc/2 (kg·m²).
    pub jc: f64,
    /// Bogie mass Mt/2 (kg).
    pub mt: f64,
    /// Bogie pitch inertia Jt/2 (kg·m²).
    pub jt: f64,
    /// Wheelset mass Mw/2 (kg).
    pub mw: f64,
    /// Primary stiffness per wheel (N/m).
    pub kpz: f64,
    /// Primary damping per wheel (N·s/m).
    pub cpz: f64,
    /// Secondary stiffness per bogie side (N/m).
    pub ksz: f64,
    /// Secondary damping per bogie side (N·s/m).
    pub csz: f64,
    /// Half distance between bogie centres (m).
    pub lc: f64,
    /// Half wheelbase (m).
    pub lt: f64,
    /// Gravity (m/s²).
    pub g: f64,
}

/// Static forces of the half car under gravity (N): secondary Fs1, Fs2, primary Fp1..4,
/// contact P1..4.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StaticForces {
    /// Secondary suspension forces (N).
    pub fs: [f64; 2],
    /// Primary suspension forces (N).
    pub fp: [f64; 4],
    /// Wheel–rail forces (N).
    pub p: [f64; 4],
}

impl HalfVehicle {
    /// Positions of the wheels relative to the carbody centre along the track (m), front first.
    pub fn wheel_offsets(&self) -> [f64; 4] {
        let (lc, lt) = (self.lc, self.lt);
        [lc + lt, lc - lt, -lc + lt, -lc - lt]
    }

    /// Accelerations `a` (m/s², rad/s²) of the ten DOFs at displacements `x`, velocities `v`
    /// and wheel–rail forces `p` (N).
    #[inline(always)]
    pub fn accelerations(&self, x: &[f64], v: &[f64], p: &[f64; 4], a: &mut [f64]) {
        let s = self;
        let fs1 = s.ksz * (x[ZC] - s.lc * x[BC] - x[ZT1]) + s.csz * (v[ZC] - s.lc * v[BC] - v[ZT1]);
        let fs2 = s.ksz * (x[ZC] + s.lc * x[BC] - x[ZT2]) + s.csz * (v[ZC] + s.lc * v[BC] - v[ZT2]);
        let prim = |zt: usize, bt: usize, sign: f64, w: usize| {
            s.kpz * (x[zt] + sign * s.lt * x[bt] - x[w])
                + s.cpz * (v[zt] + sign * s.lt * v[bt] - v[w])
        };
        let fp = [
            prim(ZT1, BT1, -1.0, ZW1),
            prim(ZT1, BT1, 1.0, ZW1 + 1),
            prim(ZT2, BT2, -1.0, ZW1 + 2),
            prim(ZT2, BT2, 1.0, ZW1 + 3),
        ];
        a[ZC] = s.g - (fs1 + fs2) / s.mc;
        a[BC] = s.lc * (fs1 - fs2) / s.jc;
        a[ZT1] = s.g + (fs1 - fp[0] - fp[1]) / s.mt;
        a[BT1] = s.lt * (fp[0] - fp[1]) / s.jt;
        a[ZT2] = s.g + (fs2 - fp[2] - fp[3]) / s.mt;
        a[BT2] = s.lt * (fp[2] - fp[3]) / s.jt;
        for j in 0..4 {
            a[ZW1 + j] = s.g + (fp[j] - p[j]) / s.mw;
        }
    }

    /// Static forces under gravity, from equilibrium alone (the half car is determinate).
    pub fn static_forces(&self) -> StaticForces {
        let fs = 0.5 * self.mc * self.g;
        let fp = 0.5 * (self.mt * self.g + fs);
        let p = self.mw * self.g + fp;
        StaticForces {
            fs: [fs; 2],
            fp: [fp; 4],
            p: [p; 4],
        }
    }

    /// Static displacements of the ten DOFs, given the static wheel displacements `zw` (m).
    /// Each spring carries its static force: Fp/Kpz and Fs/Ksz are its compressions.
    pub fn static_displacements(&self, zw: &[f64; 4]) -> [f64; NV] {
        let f = self.static_forces();
        let mut x = [0.0; NV];
        // Bogie b: Zt − Lt βt = Zw_front + Fp/Kpz, Zt + Lt βt = Zw_rear + Fp/Kpz.
        for b in 0..2 {
            let a1 = zw[2 * b] + f.fp[2 * b] / self.kpz;
            let a2 = zw[2 * b + 1] + f.fp[2 * b + 1] / self.kpz;
            x[ZT1 + 2 * b] = 0.5 * (a1 + a2);
            x[BT1 + 2 * b] = (a2 - a1) / (2.0 * self.lt);
        }
        let c1 = x[ZT1] + f.fs[0] / self.ksz;
        let c2 = x[ZT2] + f.fs[1] / self.ksz;
        x[ZC] = 0.5 * (c1 + c2);
        x[BC] = (c2 - c1) / (2.0 * self.lc);
        x[ZW1..ZW1 + 4].copy_from_slice(zw);
        x
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::solver::zhai::Zhai;
    use nalgebra::{DMatrix, SymmetricEigen};
    use std::convert::Infallible;

    /// The paper's vehicle, halved per rail.
    pub(crate) fn paper_half_vehicle() -> HalfVehicle {
        HalfVehicle {
            mc: 46_060.0 / 2.0,
            jc: 1.95e6 / 2.0,
            mt: 2_235.0 / 2.0,
            jt: 1_238.0 / 2.0,
            mw: 1_457.0 / 2.0,
            kpz: 1.773e6,
            cpz: 20e3,
            ksz: 0.8e6,
            csz: 120e3,
            lc: 8.6875,
            lt: 1.25,
            g: 9.8,
        }
    }

    #[test]
    fn static_state_has_zero_acceleration() {
        let hv = paper_half_vehicle();
        let zw = [1e-3, 1.1e-3, 0.9e-3, 1.05e-3];
        let x = hv.static_displacements(&zw);
        let mut a = [1.0; NV];
        hv.accelerations(&x, &[0.0; NV], &hv.static_forces().p, &mut a);
        for (i, ai) in a.iter().enumerate() {
            assert!(ai.abs() < 1e-12, "DOF {i}: {ai:e}");
        }
        // Whole-car masses halved per rail: 69.04 kN per wheel.
        let p = hv.static_forces().p[0];
        let expected = 9.8 * (46_060.0 / 8.0 + 2_235.0 / 4.0 + 1_457.0 / 2.0);
        assert!((p - expected).abs() < 1e-9 && (p - 69_038.6).abs() < 0.1);
    }

    /// The 6×6 mass and stiffness of the half car with the wheels held (rigid track),
    /// written from the energy, independently of [`HalfVehicle::accelerations`].
    fn mk_rigid_track(hv: &HalfVehicle) -> (DMatrix<f64>, DMatrix<f64>) {
        let m = DMatrix::from_diagonal(&nalgebra::DVector::from_vec(vec![
            hv.mc, hv.jc, hv.mt, hv.jt, hv.mt, hv.jt,
        ]));
        // V = ½Ksz Σ (Zc ∓ Lc βc − Zt_b)² + ½Kpz Σ (Zt_b ∓ Lt βt_b)²: stiffness = Σ k e eᵀ.
        let mut k = DMatrix::zeros(6, 6);
        let mut add = |e: [f64; 6], kk: f64| {
            for i in 0..6 {
                for j in 0..6 {
                    k[(i, j)] += kk * e[i] * e[j];
                }
            }
        };
        add([1.0, -hv.lc, -1.0, 0.0, 0.0, 0.0], hv.ksz);
        add([1.0, hv.lc, 0.0, 0.0, -1.0, 0.0], hv.ksz);
        for s in [-1.0, 1.0] {
            add([0.0, 0.0, 1.0, s * hv.lt, 0.0, 0.0], hv.kpz);
            add([0.0, 0.0, 0.0, 0.0, 1.0, s * hv.lt], hv.kpz);
        }
        (m, k)
    }

    /// Frequencies (Hz) and mass-normalised mode shapes of M, K (via M^{−1/2} K M^{−1/2}).
    fn modes(m: &DMatrix<f64>, k: &DMatrix<f64>) -> Vec<(f64, Vec<f64>)> {
        let n = m.nrows();
        let mut s = DMatrix::zeros(n, n);
        for i in 0..n {
            for j in 0..n {
                s[(i, j)] = k[(i, j)] / (m[(i, i)] * m[(j, j)]).sqrt();
            }
        }
        let eig = SymmetricEigen::new(s);
        let mut out: Vec<_> = (0..n)
            .map(|c| {
                let f = eig.eigenvalues[c].sqrt() / (2.0 * std::f64::consts::PI);
                let shape = (0..n)
                    .map(|i| eig.eigenvectors[(i, c)] / m[(i, i)].sqrt())
                    .collect();
                (f, shape)
            })
            .collect();
        out.sort_by(|a, b| a.0.partial_cmp(&b.0).unwrap());
        out
    }

    /// Frequency (Hz) of the free, undamped response of the model's equations started from
    /// `shape` (DOFs Zc..βt2) with the wheels held at zero: period from upward zero crossings.
    fn measured_frequency(hv: &HalfVehicle, shape: &[f64], f_guess: f64) -> f64 {
        let mut hv = *hv;
        hv.cpz = 0.0;
        hv.csz = 0.0;
        hv.g = 0.0;
        let dt = 1.0 / (f_guess * 2000.0);
        let mut z = Zhai::new(NV);
        let scale = 1e-3 / shape.iter().fold(0.0f64, |m, s| m.max(s.abs()));
        for i in 0..6 {
            z.x[i] = shape[i] * scale;
        }
        let f = |x: &[f64], v: &[f64], a: &mut [f64]| -> Result<(), Infallible> {
            hv.accelerations(x, v, &[0.0; 4], a);
            for w in a.iter_mut().skip(ZW1) {
                *w = 0.0; // wheels held by a rigid track
            }
            Ok(())
        };
        z.init_accel(f).unwrap();
        // Follow the largest component of the shape.
        let dof = (0..6)
            .max_by(|&a, &b| shape[a].abs().total_cmp(&shape[b].abs()))
            .unwrap();
        let sign = shape[dof].signum();
        let mut crossings = Vec::new();
        let mut prev = z.x[dof] * sign;
        let mut t = 0.0;
        while crossings.len() < 21 {
            z.step(dt, f).unwrap();
            t += dt;
            let cur = z.x[dof] * sign;
            if prev < 0.0 && cur >= 0.0 {
                crossings.push(t - dt * cur / (cur - prev));
            }
            prev = cur;
        }
        20.0 / (crossings[20] - crossings[0])
    }

    #[test]
    fn natural_frequencies_match_an_independent_eigen_analysis() {
        let hv = paper_half_vehicle();
        let (m, k) = mk_rigid_track(&hv);
        let modes = modes(&m, &k);
        // Carbody bounce and pitch are the two lowest, bogie bounce and pitch the two
        // highest pairs; identify them by their dominant DOF.
        let dominant = |s: &Vec<f64>| {
            let mut kin: Vec<f64> = (0..6).map(|i| m[(i, i)] * s[i] * s[i]).collect();
            kin[2] += kin[4]; // bogie bounce (both bogies)
            kin[4] = 0.0;
            kin[3] += kin[5]; // bogie pitch (both bogies)
            kin[5] = 0.0;
            (0..6).max_by(|&a, &b| kin[a].total_cmp(&kin[b])).unwrap()
        };
        let mut checked = Vec::new();
        for (f, shape) in &modes {
            let d = dominant(shape);
            let name = match d {
                ZC => "carbody bounce",
                BC => "carbody pitch",
                ZT1 => "bogie bounce",
                _ => continue,
            };
            let fm = measured_frequency(&hv, shape, *f);
            let rel = (fm - f).abs() / f;
            assert!(rel < 0.01, "{name}: model {fm:.4} Hz vs eigen {f:.4} Hz");
            checked.push((name, *f));
        }
        for name in ["carbody bounce", "carbody pitch", "bogie bounce"] {
            assert!(
                checked.iter().any(|c| c.0 == name),
                "{name} not found: {checked:?}"
            );
        }
        // Sanity: carbody bounce near 1.2 Hz for these suspensions.
        let fb = checked.iter().find(|c| c.0 == "carbody bounce").unwrap().1;
        assert!((1.0..1.5).contains(&fb), "carbody bounce {fb}");
    }
}
