//! VehicleTrack stepping in detail: µs per substep of each kernel at two resolutions, measured
//! interleaved (round robin, one short episode per kernel per round, so that a noisy machine
//! disturbs every kernel alike), the real-time factors, the arithmetic bound and the fraction
//! of it reached, and the accuracy of the fast kernel against the plain one.
//!
//! Arithmetic bound: [`flops_per_substep`] counts the floating-point operations of one substep
//! of the fast kernel from its loops (a hand count, stated term by term below); the loop
//! throughput is measured on a loop of the shape of most of the substep's loops (a streaming
//! multiply–add `y = a x + b y + c z` over L1-resident arrays of [`TRIAD_LEN`] entries),
//! compiled for each instruction set. The bound is count / throughput; the fraction is
//! bound / measured time. (The FFT runs denser than that loop, and at N = 511 the state no
//! longer fits in L1: the bound is a yardstick, not a hard limit.)

use std::hint::black_box;
use std::time::{Duration, Instant};

use railuq::models::vehicle_track::{
    Kernel, VehicleTrack, VR_DIP_DEPTH, VR_DIP_X0, VR_DT, VR_IRREGULARITY, VR_N_MODES,
    VR_N_SLEEPERS, VR_P1, VR_P2, VR_P3, VR_P4, VR_ZC_ACC, VR_ZC_ACC_FRONT, VR_ZC_ACC_REAR,
};
use railuq::models::{InitContext, Model};
use railuq::solver::simd::{Isa, Job, Simd};

/// A resolution of the model.
struct Resolution {
    name: &'static str,
    /// Sleepers N and modes NM.
    n: i32,
    nm: i32,
    /// Integration step (s).
    dt: f64,
    /// Substeps per timed episode.
    episode: usize,
}

/// The default; the fine resolution; the one that resolves the sleeper-passing force
/// variation (modes beyond the sleeper grid: NM = 2N + 1).
const RESOLUTIONS: [Resolution; 3] = [
    Resolution {
        name: "default (N = 255, NM = 255, dt = 1e-4 s)",
        n: 255,
        nm: 255,
        dt: 1e-4,
        episode: 20,
    },
    Resolution {
        name: "fine (N = 511, NM = 511, dt = 2e-5 s)",
        n: 511,
        nm: 511,
        dt: 2e-5,
        episode: 50,
    },
    Resolution {
        name: "sleeper passing (N = 255, NM = 511, dt = 2e-5 s)",
        n: 255,
        nm: 511,
        dt: 2e-5,
        episode: 50,
    },
];

/// Floating-point operations of one substep of the fast kernel with N sleepers and NM modes.
///
/// Zhai update 14 per state entry (10 + NM + 2N entries); the pads' modal input 3 NM (plus the
/// fold onto the sleeper grid, one subtraction per mode beyond N + 1, when NM > N); each of
/// the two sine transforms 5N before the FFT, 5 m log2 m for the complex FFT of m = (N+1)/2
/// points, 16 m after it (14 per mode pair, the prefix sum and the block offsets); sleepers and ballast 17 N, ballast shear 7 N; modal stiffness and
/// pad forces 3 NM, wheel forces 16 NM; rail under the wheels 16 NM; the wheels' mode tables,
/// vehicle, contact and irregularity about 1 500.
pub fn flops_per_substep(n: usize, nm: usize) -> f64 {
    let (n, nm) = (n as f64, nm as f64);
    let m = (n + 1.0) / 2.0;
    let zhai = 14.0 * (10.0 + nm + 2.0 * n);
    let dst = 5.0 * n + 5.0 * m * m.log2() + 16.0 * m;
    let fold = if nm > n { nm - n - 1.0 } else { 0.0 };
    zhai + 3.0 * nm + fold + 2.0 * dst + 24.0 * n + 3.0 * nm + 16.0 * nm + 16.0 * nm + 1500.0
}

fn model(res: &Resolution, kernel: Kernel) -> VehicleTrack {
    let mut m = VehicleTrack::default();
    m.set_kernel(kernel);
    m.set_integer(VR_N_SLEEPERS, res.n).expect("n_sleepers");
    m.set_integer(VR_N_MODES, res.nm).expect("n_modes");
    m.set_real(VR_DT, res.dt).expect("dt");
    m
}

/// The kernels to time: plain, and fast on each instruction set of this CPU.
fn kernels() -> Vec<(String, Kernel)> {
    let mut v = vec![("plain".to_string(), Kernel::Plain)];
    let best = Simd::best().isa();
    for simd in Simd::available() {
        let isa = simd.isa();
        let name = match isa {
            Isa::Baseline => "fast, baseline x86-64 (SSE2)",
            Isa::Avx2 => "fast, AVX2",
        };
        let mark = if isa == best { " [default here]" } else { "" };
        v.push((
            format!("{name}{mark}"),
            Kernel::Custom {
                isa,
                fft: Default::default(),
            },
        ));
    }
    v
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// A streaming multiply–add `y = a x + b y + c z` (5 flops per entry) as a [`Job`].
struct Triad {
    x: Vec<f64>,
    y: Vec<f64>,
    z: Vec<f64>,
}

impl Job for Triad {
    #[inline(always)]
    fn run(&mut self) {
        let (a, b, c) = black_box((0.999, 1e-3, -1e-3));
        for ((y, &x), &z) in self.y.iter_mut().zip(&self.x).zip(&self.z) {
            *y = a * x + b * *y + c * z;
        }
    }
}

/// Entries of the arrays of the throughput loop (3 × 12 KiB: in L1).
pub const TRIAD_LEN: usize = 512;

/// Best flops per ns of [`Triad`] over arrays of `len` entries on `simd`.
fn throughput(simd: Simd, len: usize) -> f64 {
    let mut job = Triad {
        x: (0..len).map(|i| (i as f64).sin()).collect(),
        y: vec![0.5; len],
        z: (0..len).map(|i| (i as f64).cos()).collect(),
    };
    let reps = 200;
    let mut best = f64::INFINITY;
    for _ in 0..300 {
        let t = Instant::now();
        for _ in 0..reps {
            simd.dispatch(&mut job);
        }
        best = best.min(t.elapsed().as_secs_f64() * 1e9 / reps as f64);
    }
    black_box(&job.y);
    5.0 * len as f64 / best
}

/// Outputs compared between the kernels.
const COMPARED: [u32; 7] = [
    VR_ZC_ACC,
    VR_ZC_ACC_FRONT,
    VR_ZC_ACC_REAR,
    VR_P1,
    VR_P2,
    VR_P3,
    VR_P4,
];

/// Largest |fast − plain| / max |plain| over the compared outputs of a 6 s run (1 ms samples).
fn accuracy(res: &Resolution, dip: bool) -> f64 {
    let trace = |kernel: Kernel| -> Vec<[f64; 7]> {
        let mut m = model(res, kernel);
        if dip {
            m.set_integer(VR_IRREGULARITY, 0).expect("irregularity");
            m.set_real(VR_DIP_DEPTH, 0.3e-3).expect("dip_depth");
            m.set_real(VR_DIP_X0, 100.0).expect("dip_x0");
        }
        m.initialize(&InitContext::default())
            .unwrap_or_else(|e| super::fail(&format!("VehicleTrack: {e}")));
        (0..6000)
            .map(|i| {
                m.do_step(i as f64 * 1e-3, 1e-3)
                    .unwrap_or_else(|e| super::fail(&format!("VehicleTrack: {e}")));
                COMPARED.map(|vr| m.get_real(vr).expect("output"))
            })
            .collect()
    };
    let (fast, plain) = (trace(Kernel::Fast), trace(Kernel::Plain));
    (0..COMPARED.len())
        .map(|c| {
            let scale = plain.iter().fold(0.0f64, |m, r| m.max(r[c].abs()));
            let diff = fast
                .iter()
                .zip(&plain)
                .fold(0.0f64, |m, (a, b)| m.max((a[c] - b[c]).abs()));
            diff / scale
        })
        .fold(0.0, f64::max)
}

/// Runs the measurements, prints them and returns them as JSON.
pub fn run(budget: Duration) -> String {
    let kernels = kernels();
    println!("\nVehicleTrack stepping (Rust API of the same library; interleaved rounds)");
    println!(
        "{:<50} {:<38} {:>9} {:>9} {:>8} {:>10} {:>9}",
        "resolution", "kernel", "best µs", "median µs", "RTF", "bound µs", "of bound"
    );
    let mut rows = Vec::new();
    for res in &RESOLUTIONS {
        let mut models: Vec<VehicleTrack> = kernels
            .iter()
            .map(|(_, k)| {
                let mut m = model(res, *k);
                m.initialize(&InitContext::default())
                    .unwrap_or_else(|e| super::fail(&format!("VehicleTrack: {e}")));
                m
            })
            .collect();
        let h = res.episode as f64 * res.dt;
        let mut per = vec![Vec::new(); kernels.len()];
        let (mut t, mut round) = (0.0, 0);
        let start = Instant::now();
        while round < 30 || (start.elapsed() < 2 * budget && round < 20_000) {
            for (m, samples) in models.iter_mut().zip(per.iter_mut()) {
                let t0 = Instant::now();
                m.do_step(t, h)
                    .unwrap_or_else(|e| super::fail(&format!("VehicleTrack: {e}")));
                samples.push(t0.elapsed().as_secs_f64() * 1e6 / res.episode as f64);
            }
            t += h;
            round += 1;
        }
        let (n, nm) = (res.n as usize, res.nm as usize);
        let flops = flops_per_substep(n, nm);
        for ((name, kernel), samples) in kernels.iter().zip(per) {
            let best = samples.iter().cloned().fold(f64::INFINITY, f64::min);
            let med = median(samples);
            let simd = match kernel {
                Kernel::Custom { isa, .. } => Simd::new(*isa).expect("available"),
                _ => Simd::baseline(),
            };
            let rate = throughput(simd, TRIAD_LEN);
            let bound = flops / rate / 1e3; // µs
            println!(
                "{:<50} {:<38} {:>9.3} {:>9.3} {:>8.1} {:>10.3} {:>8.0}%",
                res.name,
                name,
                best,
                med,
                res.dt * 1e6 / best,
                bound,
                100.0 * bound / best
            );
            rows.push(format!(
                "{{\"resolution\": \"{}\", \"n\": {}, \"nm\": {}, \"dt\": {:e}, \"kernel\": \"{}\", \
                 \"best_us\": {:.4}, \"median_us\": {:.4}, \"rtf_best\": {:.3}, \
                 \"rtf_median\": {:.3}, \"flops\": {:.0}, \"loop_gflops\": {:.3}, \
                 \"bound_us\": {:.4}, \"rounds\": {}}}",
                res.name,
                n,
                nm,
                res.dt,
                name,
                best,
                med,
                res.dt * 1e6 / best,
                res.dt * 1e6 / med,
                flops,
                rate,
                bound,
                round
            ));
        }
    }
    let mut acc = Vec::new();
    for (res, dip, what) in [
        (
            &RESOLUTIONS[0],
            false,
            "default irregularity, default resolution",
        ),
        (&RESOLUTIONS[0], true, "0.3 mm dip, default resolution"),
        (&RESOLUTIONS[1], true, "0.3 mm dip, fine resolution"),
        (
            &RESOLUTIONS[2],
            true,
            "0.3 mm dip, sleeper-passing resolution",
        ),
    ] {
        let r = accuracy(res, dip);
        println!("fast vs plain kernel, 6 s, {what}: largest relative difference {r:.1e}");
        acc.push(format!("{{\"case\": \"{what}\", \"max_rel_diff\": {r:e}}}"));
    }
    format!(
        "{{\"kernels\": [\n  {}\n], \"accuracy\": [\n  {}\n]}}\n",
        rows.join(",\n  "),
        acc.join(",\n  ")
    )
}
