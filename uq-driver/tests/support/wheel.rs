//! The wheel of the paper's §3 (m q'' + c q' + k q = 0, m = 10, q(0) = 0.1, K ~ N(100, 10²),
//! C ~ N(20, 2²)) solved independently of the code under test: the closed-form response
//! integrated over (K, C) on a 40 × 40 Gauss–Hermite grid whose nodes are computed here
//! (Golub–Welsch, `benchmarks.rs`).

use std::path::{Path, PathBuf};

use super::benchmarks::gauss_hermite;
use super::csv::Csv;

/// `Wheel.fmu` (panics with a hint when it has not been built).
pub fn wheel_fmu() -> PathBuf {
    super::built_fmu("Wheel")
}

/// The wheel's time grid in the paper: 0–5 s, step 0.01 s.
pub const EXPERIMENT: &str = "start = 0.0\nstop = 5.0\nstep = 0.01";

/// The text of a study of the wheel (K ~ N(100, 10²), C ~ N(20, 2²) written as `cov = 0.1`,
/// output `q`) with the `[experiment]` keys `experiment`, the `[method]` keys `method` and
/// `extra` at the end.
pub fn study_text(name: &str, seed: u64, experiment: &str, method: &str, extra: &str) -> String {
    format!(
        r#"{head}[method]
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
        head = super::study_head(name, &wheel_fmu(), seed, experiment)
    )
}

/// [`study_text`] written to `DIR/<file>.toml`.
pub fn write_study(
    dir: &Path,
    file: &str,
    name: &str,
    seed: u64,
    experiment: &str,
    method: &str,
    extra: &str,
) -> PathBuf {
    super::write_toml(
        dir,
        file,
        &study_text(name, seed, experiment, method, extra),
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

/// A CSV file of numbers with a header (every field must be a number).
pub fn read_csv(path: &Path) -> Csv {
    Csv::read(path).numeric()
}
