//! Importance sampling around a centre in standard normal space (the FORM design point).
//!
//! Samples `u_i = c + z_i`, `z_i ~ N(0, I)` (the density `phi(u - c)`), weights
//!
//! `w_i = phi(u_i) / phi(u_i - c) = exp(-c . z_i - |c|^2 / 2)`,
//!
//! `P^ = (1/N) sum_i 1{g(u_i) <= 0} w_i` (unbiased), its variance
//! `Var(P^) = (1/(N(N-1))) sum_i (1{g_i <= 0} w_i - P^)^2` and `CoV = sqrt(Var) / P^`.
//! The 95 % interval is on the log scale, `P^ exp(-+1.96 s)` with `s^2 = ln(1 + CoV^2)`:
//! never negative, and skewed upwards like the estimator's own distribution when few
//! samples fail.
//!
//! Centred at the design point of a limit state with a single design point, `N` samples
//! give `CoV^2 ~ (e^(beta^2) Phi(-2 beta) / Phi(-beta)^2 - 1) / N` for a linear `g`: about
//! 3.5/N at `P = 1e-3`, 4.2/N at `1e-4`, 5.4/N at `1e-6` (so CoV 5 % takes 1 400, 1 700 and
//! 2 150 runs).
//!
//! Calibration (400 seeds, linear limit state in 8 dimensions at 1e-3 and 1e-5, target CoV
//! 0.1 and 0.05): the rms relative error matches the mean reported CoV within 3 %, and the
//! 95 % interval holds the exact value in 94-95 % of the seeds.
//!
//! A limit state with several design points (a series system, `|q| > limit`) loses the
//! failure domain around the others when sampled around one: the estimate is then low, with a
//! small CoV that says nothing of it. Given the design points `c_j` that a multi-start FORM
//! found, the sampling density is the mixture `h(u) = Σ_j π_j φ(u − c_j)`, `π_j ∝ Φ(−β_j)`:
//! sample `i` takes component `j` with probability `π_j` (from its own stream, after its
//! normals), and its weight is `φ(u_i)/h(u_i) = 1 / Σ_j π_j exp(c_j·u_i − |c_j|²/2)`
//! (summed on the log scale). The estimator and its variance are those above, unbiased for
//! the whole failure domain (Melchers 1990; Au & Beck 1999). With one centre the samples and
//! weights are those of the single-centre formula, to the bit.
//!
//! Runs go in batches of `batch` samples until the CoV reaches `target_cov` (with at least
//! [`MIN_FAILURES`] failing samples) or `max_runs` are spent. Sample `i` draws from its own
//! stream (index `1 << 56 | i`): the same seed gives the same samples,
//! whatever the batch size.

use serde::{Deserialize, Serialize};

use super::error::ReliabilityError;
use super::model::{LimitState, OnFailure, Runs};
use super::{dot, log_interval, normals, positive, stream, Purpose};
use crate::uq::rng::{self, ChaCha20};

/// Failing samples needed before the CoV may stop the sampling (below it the CoV estimate
/// itself is unreliable).
pub const MIN_FAILURES: usize = 10;

/// Importance-sampling settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ImportanceSampling {
    /// Stop when the estimated coefficient of variation is at or below this.
    pub target_cov: f64,
    /// Stop after this many runs at most.
    pub max_runs: usize,
    /// Samples per batch (evaluated in parallel).
    pub batch: usize,
    /// What a failed run counts as.
    pub on_failure: OnFailure,
}

impl Default for ImportanceSampling {
    fn default() -> Self {
        ImportanceSampling {
            target_cov: 0.05,
            max_runs: 2000,
            batch: 100,
            on_failure: OnFailure::Error,
        }
    }
}

/// The estimate after one batch.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ImportanceStep {
    /// Runs so far.
    pub runs: u64,
    /// `P^` so far.
    pub probability: f64,
    /// Its CoV so far (`None` while no sample failed).
    pub cov: Option<f64>,
}

/// A component of a mixture sampling density: the standard normal moved to `centre`, drawn
/// with probability `weight`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MixtureComponent {
    /// Its centre in standard normal space.
    pub centre: Vec<f64>,
    /// Its probability (the weights sum to 1).
    pub weight: f64,
}

/// What importance sampling found.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ImportanceSamplingResult {
    /// `P^`.
    pub probability: f64,
    /// Its coefficient of variation (`None` when no sample failed).
    pub cov: Option<f64>,
    /// 95 % interval on the log scale (`None` when no sample failed).
    pub interval: Option<[f64; 2]>,
    /// Model runs.
    pub runs: u64,
    /// Samples in the failure domain.
    pub failures: usize,
    /// The centre of the sampling density (of its first component when it is a mixture).
    pub centre: Vec<f64>,
    /// The components of the sampling density when it is a mixture around several design
    /// points (empty for one centre).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub mixture: Vec<MixtureComponent>,
    /// Whether `target_cov` was reached.
    pub reached_target: bool,
    /// The estimate after each batch.
    pub history: Vec<ImportanceStep>,
    /// The run index after the last run.
    pub next_run: u64,
    /// For the user.
    pub warnings: Vec<String>,
}

/// Importance sampling of `model` around `centre`, runs numbered from `first_run` (the
/// mixture of one component; the studies call [`importance_sampling_mixture`]).
#[cfg(test)]
pub(crate) fn importance_sampling(
    model: &mut dyn LimitState,
    settings: &ImportanceSampling,
    centre: &[f64],
    seed: u64,
    first_run: u64,
) -> Result<ImportanceSamplingResult, ReliabilityError> {
    let one = [MixtureComponent {
        centre: centre.to_vec(),
        weight: 1.0,
    }];
    importance_sampling_mixture(model, settings, &one, seed, first_run)
}

/// Importance sampling of `model` from the mixture of standard normals around the centres of
/// `components` (see the module), runs numbered from `first_run`. The weights need not sum
/// to 1 (they are normalised); one component is [`importance_sampling`].
pub fn importance_sampling_mixture(
    model: &mut dyn LimitState,
    settings: &ImportanceSampling,
    components: &[MixtureComponent],
    seed: u64,
    first_run: u64,
) -> Result<ImportanceSamplingResult, ReliabilityError> {
    let mut runs = Runs::starting_at(model, first_run)?;
    let d = runs.dim();
    let Some(first) = components.first() else {
        return Err(ReliabilityError::Invalid(
            "importance sampling needs at least one centre".into(),
        ));
    };
    for c in components {
        if c.centre.len() != d || c.centre.iter().any(|v| !v.is_finite()) {
            return Err(ReliabilityError::Invalid(format!(
                "the importance-sampling centre must have {d} finite coordinates (got {:?})",
                c.centre
            )));
        }
    }
    let total: f64 = components.iter().map(|c| c.weight).sum();
    if components.iter().any(|c| !positive(c.weight)) || !total.is_finite() {
        return Err(ReliabilityError::Invalid(format!(
            "the weights of an importance-sampling mixture must be positive and finite (got \
             {:?})",
            components.iter().map(|c| c.weight).collect::<Vec<_>>()
        )));
    }
    let density = Mixture::new(components, total);
    let centre = &first.centre;
    if !positive(settings.target_cov) || settings.max_runs < 2 || settings.batch == 0 {
        return Err(ReliabilityError::Invalid(format!(
            "importance sampling needs target_cov > 0, max_runs >= 2 and batch >= 1 (got {}, \
             {}, {})",
            settings.target_cov, settings.max_runs, settings.batch
        )));
    }
    let mut sum = 0.0;
    let mut sum_sq = 0.0;
    let mut n = 0usize;
    let mut failures = 0usize;
    let mut history = Vec::new();
    let mut reached_target = false;
    let estimate = |sum: f64, sum_sq: f64, n: usize| {
        let nf = n as f64;
        let p = sum / nf;
        let var = ((sum_sq / nf - p * p).max(0.0)) / (nf - 1.0);
        (p, (p > 0.0).then(|| var.sqrt() / p))
    };
    while n < settings.max_runs {
        let size = settings.batch.min(settings.max_runs - n);
        let draws: Vec<(usize, Vec<f64>)> = (n..n + size)
            .map(|i| density.draw(&mut stream(seed, Purpose::ImportanceSample, i as u64), d))
            .collect();
        let points = draws.iter().map(|(k, z)| density.point(*k, z)).collect();
        let g = runs.eval(points, settings.on_failure)?;
        for ((k, z), gi) in draws.iter().zip(g) {
            if gi <= 0.0 {
                let w = density.weight(*k, z);
                sum += w;
                sum_sq += w * w;
                failures += 1;
            }
        }
        n += size;
        if n < 2 {
            continue;
        }
        let (p, cov) = estimate(sum, sum_sq, n);
        history.push(ImportanceStep {
            runs: n as u64,
            probability: p,
            cov,
        });
        if failures >= MIN_FAILURES && cov.is_some_and(|c| c <= settings.target_cov) {
            reached_target = true;
            break;
        }
    }
    let (probability, cov) = estimate(sum, sum_sq, n);
    let mut warnings = Vec::new();
    if failures == 0 {
        warnings.push(format!(
            "no sample of {n} around the centre failed: no estimate (the limit may never be \
             reached, or the centre is not a design point)"
        ));
    } else if !reached_target {
        warnings.push(format!(
            "the CoV {:.4} did not reach the target {} in {n} runs ({failures} failing samples)",
            cov.unwrap_or(f64::NAN),
            settings.target_cov
        ));
    }
    Ok(ImportanceSamplingResult {
        probability,
        interval: cov.and_then(|c| log_interval(probability, c)),
        cov,
        runs: n as u64,
        failures,
        centre: centre.to_vec(),
        mixture: match components.len() {
            1 => Vec::new(),
            _ => density.components(),
        },
        reached_target,
        history,
        next_run: runs.count(),
        warnings,
    })
}

/// The sampling density: one standard normal moved to a centre, or a mixture of them.
struct Mixture {
    /// Centres `c_j`.
    centres: Vec<Vec<f64>>,
    /// `|c_j|² / 2`.
    half_squares: Vec<f64>,
    /// Probabilities `π_j`, summing to 1.
    weights: Vec<f64>,
}

impl Mixture {
    /// The mixture of `components`, their weights divided by `total`.
    fn new(components: &[MixtureComponent], total: f64) -> Mixture {
        Mixture {
            centres: components.iter().map(|c| c.centre.clone()).collect(),
            half_squares: components
                .iter()
                .map(|c| 0.5 * dot(&c.centre, &c.centre))
                .collect(),
            weights: components.iter().map(|c| c.weight / total).collect(),
        }
    }

    /// A sample `(j, z)`: `d` standard normals `z`, then (for a mixture) the component `j`
    /// from the same stream; the point is `c_j + z`.
    fn draw(&self, rng: &mut ChaCha20, d: usize) -> (usize, Vec<f64>) {
        let z = normals(rng, d);
        if self.centres.len() == 1 {
            return (0, z);
        }
        let mut v = rng::uniform_open01(rng);
        let last = self.weights.len() - 1;
        let j = self
            .weights
            .iter()
            .position(|&w| {
                v -= w;
                v < 0.0
            })
            .unwrap_or(last);
        (j, z)
    }

    /// The point `c_j + z`.
    fn point(&self, j: usize, z: &[f64]) -> Vec<f64> {
        z.iter().zip(&self.centres[j]).map(|(a, b)| a + b).collect()
    }

    /// The weight `φ(u)/h(u)` of the point `u = c_j + z`.
    fn weight(&self, j: usize, z: &[f64]) -> f64 {
        if self.centres.len() == 1 {
            // exp(−c·z − |c|²/2), as it always was.
            return (-dot(&self.centres[0], z) - self.half_squares[0]).exp();
        }
        let u = self.point(j, z);
        let logs: Vec<f64> = self
            .centres
            .iter()
            .zip(&self.half_squares)
            .zip(&self.weights)
            .map(|((c, h), w)| w.ln() + dot(c, &u) - h)
            .collect();
        let top = logs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let sum: f64 = logs.iter().map(|l| (l - top).exp()).sum();
        (-(top + sum.ln())).exp()
    }

    /// The components, for the result.
    fn components(&self) -> Vec<MixtureComponent> {
        self.centres
            .iter()
            .zip(&self.weights)
            .map(|(c, &weight)| MixtureComponent {
                centre: c.clone(),
                weight,
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::super::fixtures::*;
    use super::super::form::{form, Form};
    use super::super::model::FnLimitState;
    use super::*;

    #[test]
    fn after_form_on_a_linear_limit_state() {
        // Figures: CoV 5 % needs about 1 400 / 1 700 / 2 150 runs at 1e-3 / 1e-4 / 1e-6.
        for (p, max_cov) in [(1e-3, 0.05), (1e-4, 0.05), (1e-6, 0.055)] {
            let lin = Linear::new(8, p);
            let mut m = lin.model();
            let f = form(&mut m, &Form::default(), 0).unwrap();
            let r = sampling_at_design_point(&mut m, &f, 3, f.next_run);
            let err = (r.probability - p).abs() / p;
            let cov = r.cov.unwrap();
            println!(
                "linear P = {p}: IS error {err:.3}, CoV {cov:.4}, {} runs",
                r.runs
            );
            assert!(err < 0.10, "P = {p}: IS {} ({err:.3})", r.probability);
            assert!(
                cov <= max_cov && r.runs <= 2000,
                "P = {p}: CoV {cov} in {} runs",
                r.runs
            );
            let [lo, hi] = r.interval.unwrap();
            assert!(lo < r.probability && r.probability < hi);
        }
    }

    #[test]
    fn intervals_cover_the_exact_value_over_seeds() {
        for p in [1e-3, 1e-5] {
            let lin = Linear::new(8, p);
            let centre: Vec<f64> = lin.direction.iter().map(|a| a * lin.beta).collect();
            let settings = ImportanceSampling {
                target_cov: 0.1,
                ..ImportanceSampling::default()
            };
            let covered = (0..20)
                .filter(|&seed| {
                    let r =
                        importance_sampling(&mut lin.model(), &settings, &centre, seed, 0).unwrap();
                    let [lo, hi] = r.interval.unwrap();
                    lo <= p && p <= hi
                })
                .count();
            println!("IS coverage at P = {p}: {covered} of 20");
            assert!(covered >= 18, "P = {p}: {covered} of 20");
        }
    }

    #[test]
    fn two_design_points_sampled_around_one_miss_a_quarter_and_a_mixture_does_not() {
        // g = min(3.6 − u1, 3.9 + u1) in 4 dimensions: the failure domain is u1 ≥ 3.6 or
        // u1 ≤ −3.9, P = Φ(−3.6) + Φ(−3.9) = 2.07e-4, 23 % of it at the second point.
        use crate::uq::special::norm_sf;
        let exact = norm_sf(3.6) + norm_sf(3.9);
        let g = |u: &[f64]| Ok((3.6 - u[0]).min(3.9 + u[0]));
        let at = |x: f64| {
            let mut c = vec![0.0; 4];
            c[0] = x;
            c
        };
        let settings = ImportanceSampling {
            target_cov: 0.05,
            ..ImportanceSampling::default()
        };
        // Around the first design point alone: about Φ(−3.6), its interval excluding P.
        let mut m = FnLimitState::new(4, g);
        let one = importance_sampling(&mut m, &settings, &at(3.6), 2, 0).unwrap();
        let [_, hi] = one.interval.unwrap();
        assert!(hi < exact, "{} [.., {hi}] vs {exact}", one.probability);
        // The mixture: each interval covers P in at least 18 of 20 seeds.
        let components =
            [(3.6, norm_sf(3.6)), (-3.9, norm_sf(3.9))].map(|(x, w)| MixtureComponent {
                centre: at(x),
                weight: w,
            });
        let mut covered = 0;
        for seed in 0..20 {
            let mut m = FnLimitState::new(4, g);
            let r = importance_sampling_mixture(&mut m, &settings, &components, seed, 0).unwrap();
            let [lo, hi] = r.interval.unwrap();
            covered += usize::from(lo <= exact && exact <= hi);
            assert_eq!(r.mixture.len(), 2);
            assert!((r.mixture[0].weight - norm_sf(3.6) / exact).abs() < 1e-12);
        }
        assert!(covered >= 18, "{covered} of 20");
    }

    #[test]
    fn one_centre_as_a_mixture_gives_the_same_bits() {
        let lin = Linear::new(3, 1e-4);
        let centre: Vec<f64> = lin.direction.iter().map(|a| a * lin.beta).collect();
        let s = ImportanceSampling {
            max_runs: 300,
            ..ImportanceSampling::default()
        };
        let a = importance_sampling(&mut lin.model(), &s, &centre, 4, 0).unwrap();
        let one = [MixtureComponent {
            centre: centre.clone(),
            weight: 3.0,
        }];
        let b = importance_sampling_mixture(&mut lin.model(), &s, &one, 4, 0).unwrap();
        assert_eq!(a, b);
        assert!(a.mixture.is_empty());
        // Weights must be positive.
        let bad = [MixtureComponent {
            centre,
            weight: 0.0,
        }];
        let e = importance_sampling_mixture(&mut lin.model(), &s, &bad, 4, 0).unwrap_err();
        assert!(e.to_string().contains("positive"), "{e}");
    }

    #[test]
    fn no_failing_sample_is_said_without_nan() {
        let mut m = FnLimitState::new(3, |u: &[f64]| Ok(2.0 + u[0].tanh()));
        let settings = ImportanceSampling {
            max_runs: 300,
            ..ImportanceSampling::default()
        };
        let r = importance_sampling(&mut m, &settings, &[3.0, 0.0, 0.0], 1, 0).unwrap();
        assert_eq!(r.probability, 0.0);
        assert_eq!((r.cov, r.interval), (None, None));
        assert_eq!(r.runs, 300);
        assert!(r.warnings[0].contains("no sample"));
    }

    #[test]
    fn batch_size_does_not_change_the_estimate() {
        let lin = Linear::new(5, 1e-4);
        let centre: Vec<f64> = lin.direction.iter().map(|a| a * lin.beta).collect();
        let run = |batch| {
            let s = ImportanceSampling {
                batch,
                target_cov: 1e-9,
                max_runs: 600,
                ..ImportanceSampling::default()
            };
            importance_sampling(&mut lin.model(), &s, &centre, 9, 0).unwrap()
        };
        let (a, b) = (run(100), run(37));
        assert_eq!(a.probability.to_bits(), b.probability.to_bits());
        assert_eq!(a.cov.unwrap().to_bits(), b.cov.unwrap().to_bits());
    }
}
