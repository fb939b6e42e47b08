//! The wheel of the paper's §3 (m q'' + c q' + k q = 0, m = 10, q(0) = 0.1, K ~ N(100, 10²),
//! C ~ N(20, 2²)) solved independently of the code under test: the closed-form response
//! integrated over (K, C) on a 40 × 40 Gauss–Hermite grid whose nodes are computed here
//! (Golub–Welsch). Include it with
//!
//! ```ignore
//! #[path = "support/wheel.rs"]
//! mod wheel;
//! ```
#![allow(dead_code)] // each test crate uses a part of it

use std::path::{Path, PathBuf};

use nalgebra::{DMatrix, SymmetricEigen};

/// The FMU folder: `$RAILUQ_FMU_DIR`, else `target/fmu`.
pub fn fmu_dir() -> PathBuf {
    std::env::var_os("RAILUQ_FMU_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/fmu"))
}

/// `Wheel.fmu` (panics with a hint when it has not been built).
pub fn wheel_fmu() -> PathBuf {
    let p = fmu_dir().join("Wheel.fmu");
    assert!(
        p.is_file(),
        "{} is missing: run `make fmu` first",
        p.display()
    );
    p
}

/// The wheel's time grid in the paper: 0–5 s, step 0.01 s.
pub const EXPERIMENT: &str = "start = 0.0\nstop = 5.0\nstep = 0.01";

/// A study of the wheel (K ~ N(100, 10²), C ~ N(20, 2²) written as `cov = 0.1`, output `q`)
/// with the `[experiment]` keys `experiment`, the `[method]` keys `method` and `extra` at the
/// end, written to `DIR/<file>.toml`.
pub fn write_study(
    dir: &Path,
    file: &str,
    name: &str,
    seed: u64,
    experiment: &str,
    method: &str,
    extra: &str,
) -> PathBuf {
    let text = format!(
        r#"name = "{name}"
fmu = "{fmu}"
seed = {seed}
[experiment]
{experiment}
[method]
{method}
[[parameters]]
name = "K"
mean = 100.0
std = 10.0
[[parameters]]
name = "C"
mean = 20.0
cov = 0.1
[outputs]
variables = ["q"]
{extra}
"#,
        fmu = wheel_fmu().display()
    );
    let p = dir.join(format!("{file}.toml"));
    std::fs::write(&p, text).unwrap();
    p
}

/// Probabilists' Gauss–Hermite rule by Golub–Welsch (weights normalised to 1).
pub fn gauss_hermite(n: usize) -> (Vec<f64>, Vec<f64>) {
    let j = DMatrix::from_fn(n, n, |i, k| {
        if k == i + 1 || i == k + 1 {
            (i.max(k) as f64).sqrt()
        } else {
            0.0
        }
    });
    let e = SymmetricEigen::new(j);
    let mut pairs: Vec<(f64, f64)> = (0..n)
        .map(|i| (e.eigenvalues[i], e.eigenvectors[(0, i)].powi(2)))
        .collect();
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    let s: f64 = pairs.iter().map(|p| p.1).sum();
    (
        pairs.iter().map(|p| p.0).collect(),
        pairs.iter().map(|p| p.1 / s).collect(),
    )
}

/// q(t) of m q'' + c q' + k q = 0, q(0) = q0, q'(0) = 0, every regime.
pub fn closed_form(m: f64, k: f64, c: f64, q0: f64, t: f64) -> f64 {
    let a = -c / (2.0 * m);
    let disc = a * a - k / m;
    if disc < -1e-14 {
        let wd = (-disc).sqrt();
        q0 * (a * t).exp() * ((wd * t).cos() - a / wd * (wd * t).sin())
    } else if disc > 1e-14 {
        let r = disc.sqrt();
        let (s1, s2) = (a + r, a - r);
        (-s2 * q0 * (s1 * t).exp() + s1 * q0 * (s2 * t).exp()) / (s1 - s2)
    } else {
        q0 * (a * t).exp() * (1.0 - a * t)
    }
}

/// q(t) at the 40 × 40 nodes: `(weights of K, weights of C, q[i][j])` for K node i, C node j.
fn grid(t: f64) -> (Vec<f64>, Vec<Vec<f64>>) {
    let (x, w) = gauss_hermite(40);
    let q = x
        .iter()
        .map(|xi| {
            x.iter()
                .map(|xj| closed_form(10.0, 100.0 + 10.0 * xi, 20.0 + 2.0 * xj, 0.1, t))
                .collect()
        })
        .collect();
    (w, q)
}

/// Reference mean and Std of q(t).
pub fn reference(t: f64) -> (f64, f64) {
    let (w, q) = grid(t);
    let mean: f64 = (0..40)
        .flat_map(|i| (0..40).map(move |j| (i, j)))
        .map(|(i, j)| w[i] * w[j] * q[i][j])
        .sum();
    let var: f64 = (0..40)
        .flat_map(|i| (0..40).map(move |j| (i, j)))
        .map(|(i, j)| w[i] * w[j] * (q[i][j] - mean).powi(2))
        .sum();
    (mean, var.sqrt())
}

/// Reference Sobol' indices of q(t): `([S_K, S_C], [ST_K, ST_C])`, from the conditional means
/// on the same grid (two inputs: ST_K = 1 − S_C).
pub fn reference_sobol(t: f64) -> ([f64; 2], [f64; 2]) {
    let (w, q) = grid(t);
    let (mean, std) = reference(t);
    let var = std * std;
    let given_k: Vec<f64> = (0..40)
        .map(|i| (0..40).map(|j| w[j] * q[i][j]).sum())
        .collect();
    let given_c: Vec<f64> = (0..40)
        .map(|j| (0..40).map(|i| w[i] * q[i][j]).sum())
        .collect();
    let s = |cond: &[f64]| -> f64 {
        cond.iter()
            .zip(&w)
            .map(|(c, wi)| wi * (c - mean).powi(2))
            .sum::<f64>()
            / var
    };
    let (sk, sc) = (s(&given_k), s(&given_c));
    ([sk, sc], [1.0 - sc, 1.0 - sk])
}

/// A CSV file of numbers with a header.
pub struct Csv {
    /// Column names.
    pub header: Vec<String>,
    /// Rows.
    pub rows: Vec<Vec<f64>>,
}

/// Reads a CSV file of numbers.
pub fn read_csv(path: &Path) -> Csv {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines();
    let header = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_owned)
        .collect();
    let rows = lines
        .map(|l| l.split(',').map(|x| x.parse::<f64>().unwrap()).collect())
        .collect();
    Csv { header, rows }
}

impl Csv {
    /// Column `col` at time `t` (first column).
    pub fn at(&self, t: f64, col: &str) -> f64 {
        let c = self
            .header
            .iter()
            .position(|h| h == col)
            .unwrap_or_else(|| panic!("no column {col} in {:?}", self.header));
        let r = self.rows.iter().find(|r| (r[0] - t).abs() < 1e-9).unwrap();
        r[c]
    }
}
