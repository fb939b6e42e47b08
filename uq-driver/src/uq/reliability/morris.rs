//! Morris screening (Morris 1991) with the spread trajectories of Campolongo, Cariboni &
//! Saltelli (2007): a design and an estimator (not adaptive: every run in one batch).
//!
//! Each input's coordinate is a *probability level* on a grid of `p` (even) levels at the
//! cell centres `q_k = (k + 1/2) / p`, `k = 0..p-1`, mapped to the input's value by its
//! inverse CDF (`RandomInputs::to_physical` with `Germ::Uniform`, which honours a Gaussian
//! copula: with correlated inputs the steps are steps of the independent coordinates).
//! A trajectory is `d + 1` points: a base point, then one input at a time (in a random
//! order) moved by `Delta = p / 2` levels, i.e. `Delta_q = 1/2` in probability, up or
//! down (random sign; the base is drawn among the levels from which that move stays on the
//! grid, so every level is equally likely). The elementary effect of input `i` is
//!
//! `EE_i = s_i (y(after) - y(before)) / Delta_q`,  `s_i = +-1` the move's direction,
//!
//! per unit of probability level (for a uniform input on `[0, 1]` that is `dy/dx`). Over `r`
//! trajectories: `mu_i = mean EE_i`, `mu*_i = mean |EE_i|` (the importance ranking),
//! `sigma_i` their standard deviation (non-linearity and interactions).
//!
//! Spread (Campolongo et al. 2007): from `M` random candidate trajectories, `r` are kept
//! that maximise `D = sqrt(sum_{pairs} d_ml^2)`, `d_ml = sum_{i,j} |X_i^(m) - X_j^(l)|` the
//! summed distances between the points of two trajectories. Campolongo et al. search all
//! `C(M, r)` subsets; here the trajectory whose removal keeps the largest `D` is removed
//! until `r` remain (the greedy variant of Ruano et al. 2012). Cost `O(M^2 d^3)`.
//!
//! Run `t (d + 1) + j` is point `j` of trajectory `t`; candidate `m` draws from its own
//! stream (index `4 << 56 | m`).

use serde::{Deserialize, Serialize};

use super::error::ReliabilityError;
use super::model::Outcome;
use super::{stream, Purpose};
#[cfg(test)]
use crate::uq::distributions::Germ;
#[cfg(test)]
use crate::uq::random_inputs::RandomInputs;
use crate::uq::rng;

/// Morris settings: `kind = "morris"` of a study file.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Morris {
    /// Trajectories `r` (runs: `r (d + 1)`).
    pub trajectories: usize,
    /// Grid levels `p` (even).
    pub levels: usize,
    /// Random candidate trajectories `M` the `r` are chosen from (at most `r`: no selection).
    pub candidates: usize,
}

impl Default for Morris {
    fn default() -> Self {
        Morris {
            trajectories: 10,
            levels: 4,
            candidates: 50,
        }
    }
}

/// One trajectory.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Trajectory {
    /// The inputs in the order they are moved.
    pub order: Vec<usize>,
    /// `+1` (up) or `-1` (down) per input.
    pub signs: Vec<f64>,
    /// The `d + 1` points, as probability levels.
    pub points: Vec<Vec<f64>>,
}

/// A Morris design.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MorrisDesign {
    /// Inputs.
    pub dim: usize,
    /// The trajectories kept.
    pub trajectories: Vec<Trajectory>,
    /// Campolongo's spread `D` of the kept trajectories.
    pub spread: f64,
}

/// Screening measures per input.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MorrisResult {
    /// Mean elementary effect.
    pub mu: Vec<f64>,
    /// Mean absolute elementary effect (the ranking measure).
    pub mu_star: Vec<f64>,
    /// Standard deviation of the elementary effects (`n - 1`; 0 with one effect).
    pub sigma: Vec<f64>,
    /// Elementary effects per input (fewer than `r` where a run failed).
    pub effects: Vec<usize>,
    /// Inputs by decreasing `mu_star`.
    pub ranking: Vec<usize>,
    /// For the user.
    pub warnings: Vec<String>,
}

/// Probability step of a move.
const DELTA_Q: f64 = 0.5;

impl MorrisDesign {
    /// The design for `dim` inputs.
    pub fn new(dim: usize, settings: &Morris, seed: u64) -> Result<MorrisDesign, ReliabilityError> {
        let (r, p) = (settings.trajectories, settings.levels);
        if dim == 0 {
            return Err(ReliabilityError::NoInputs);
        }
        if r < 2 || p < 2 || p % 2 != 0 {
            return Err(ReliabilityError::Invalid(format!(
                "Morris needs at least 2 trajectories and an even number of levels (got r = {r}, \
                 p = {p})"
            )));
        }
        let m = settings.candidates.max(r);
        let candidates: Vec<Trajectory> =
            (0..m as u64).map(|k| trajectory(dim, p, seed, k)).collect();
        let dist: Vec<Vec<f64>> = (0..m)
            .map(|a| {
                (0..m)
                    .map(|b| {
                        if a == b {
                            0.0
                        } else {
                            distance(&candidates[a], &candidates[b])
                        }
                    })
                    .collect()
            })
            .collect();
        // Greedy removal: drop the trajectory with the smallest sum of squared distances to
        // the others kept (its removal keeps the largest D); ties to the later index.
        let mut kept: Vec<usize> = (0..m).collect();
        while kept.len() > r {
            let loss = |a: usize| kept.iter().map(|&b| dist[a][b].powi(2)).sum::<f64>();
            let (pos, _) = kept
                .iter()
                .enumerate()
                .min_by(|x, y| loss(*x.1).total_cmp(&loss(*y.1)).then(y.0.cmp(&x.0)))
                .expect("non-empty");
            kept.remove(pos);
        }
        let mut spread = 0.0;
        for (i, &a) in kept.iter().enumerate() {
            for &b in &kept[i + 1..] {
                spread += dist[a][b].powi(2);
            }
        }
        Ok(MorrisDesign {
            dim,
            trajectories: kept.into_iter().map(|k| candidates[k].clone()).collect(),
            spread: spread.sqrt(),
        })
    }

    /// Every point as probability levels, in run order.
    pub fn points(&self) -> Vec<Vec<f64>> {
        self.trajectories
            .iter()
            .flat_map(|t| t.points.iter().cloned())
            .collect()
    }

    /// Every point as physical values of `inputs`, in run order.
    #[cfg(test)]
    pub fn physical(&self, inputs: &RandomInputs) -> Vec<Vec<f64>> {
        self.points()
            .iter()
            .map(|q| inputs.to_physical(Germ::Uniform, q))
            .collect()
    }

    /// The screening measures from the value at every point (run order); an elementary
    /// effect that needs a failed run is left out.
    pub fn estimate(&self, values: &[Outcome]) -> Result<MorrisResult, ReliabilityError> {
        let d = self.dim;
        if values.len() != self.trajectories.len() * (d + 1) {
            return Err(ReliabilityError::BatchSize {
                expected: self.trajectories.len() * (d + 1),
                got: values.len(),
            });
        }
        let mut ee: Vec<Vec<f64>> = vec![Vec::new(); d];
        let mut failed = 0usize;
        for (t, traj) in self.trajectories.iter().enumerate() {
            let y = &values[t * (d + 1)..(t + 1) * (d + 1)];
            failed += y
                .iter()
                .filter(|v| !matches!(v, Ok(x) if x.is_finite()))
                .count();
            for (j, &i) in traj.order.iter().enumerate() {
                if let (Ok(a), Ok(b)) = (&y[j], &y[j + 1]) {
                    if a.is_finite() && b.is_finite() {
                        ee[i].push(traj.signs[i] * (b - a) / DELTA_Q);
                    }
                }
            }
        }
        let mut warnings = Vec::new();
        if failed > 0 {
            warnings.push(format!(
                "{failed} run(s) failed; the elementary effects next to them are left out"
            ));
        }
        let mean = |v: &[f64]| {
            if v.is_empty() {
                f64::NAN
            } else {
                v.iter().sum::<f64>() / v.len() as f64
            }
        };
        let mu: Vec<f64> = ee.iter().map(|e| mean(e)).collect();
        let mu_star: Vec<f64> = ee
            .iter()
            .map(|e| mean(&e.iter().map(|x| x.abs()).collect::<Vec<_>>()))
            .collect();
        let sigma: Vec<f64> = ee
            .iter()
            .zip(&mu)
            .map(|(e, m)| {
                if e.len() < 2 {
                    0.0
                } else {
                    (e.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (e.len() - 1) as f64).sqrt()
                }
            })
            .collect();
        let none: Vec<usize> = (0..d).filter(|&i| ee[i].is_empty()).collect();
        if !none.is_empty() {
            warnings.push(format!("no elementary effect for inputs {none:?}"));
        }
        let mut ranking: Vec<usize> = (0..d).collect();
        ranking.sort_by(|&a, &b| {
            let key = |i: usize| {
                if mu_star[i].is_nan() {
                    -1.0
                } else {
                    mu_star[i]
                }
            };
            key(b).total_cmp(&key(a)).then(a.cmp(&b))
        });
        Ok(MorrisResult {
            mu,
            mu_star,
            sigma,
            effects: ee.iter().map(Vec::len).collect(),
            ranking,
            warnings,
        })
    }
}

/// Candidate trajectory `k`: order, signs, base levels from its stream.
fn trajectory(d: usize, p: usize, seed: u64, k: u64) -> Trajectory {
    let mut rng = stream(seed, Purpose::Morris, k);
    let mut order: Vec<usize> = (0..d).collect();
    for i in (1..d).rev() {
        let j = rng::uniform_below(&mut rng, i as u64 + 1) as usize;
        order.swap(i, j);
    }
    let half = (p / 2) as u64;
    let signs: Vec<f64> = (0..d)
        .map(|_| {
            if rng::uniform_below(&mut rng, 2) == 0 {
                1.0
            } else {
                -1.0
            }
        })
        .collect();
    // Base level: in the lower half for an upward move, the upper half for a downward one.
    let mut level: Vec<u64> = signs
        .iter()
        .map(|&s| {
            let k = rng::uniform_below(&mut rng, half);
            if s > 0.0 {
                k
            } else {
                k + half
            }
        })
        .collect();
    let q = |level: &[u64]| -> Vec<f64> {
        level.iter().map(|&k| (k as f64 + 0.5) / p as f64).collect()
    };
    let mut points = vec![q(&level)];
    for &i in &order {
        level[i] = if signs[i] > 0.0 {
            level[i] + half
        } else {
            level[i] - half
        };
        points.push(q(&level));
    }
    Trajectory {
        order,
        signs,
        points,
    }
}

/// Campolongo's distance: the sum of the Euclidean distances between all pairs of points.
fn distance(a: &Trajectory, b: &Trajectory) -> f64 {
    let mut s = 0.0;
    for x in &a.points {
        for y in &b.points {
            s += x
                .iter()
                .zip(y)
                .map(|(u, v)| (u - v).powi(2))
                .sum::<f64>()
                .sqrt();
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::uq::distributions::{Distribution, RandomParameter};
    use crate::uq::special::norm_ppf;

    fn inputs(dists: Vec<Distribution>) -> RandomInputs {
        RandomInputs::independent(
            dists
                .into_iter()
                .enumerate()
                .map(|(i, distribution)| RandomParameter::new(format!("x{i}"), distribution))
                .collect(),
        )
    }

    fn screen(inputs: &RandomInputs, settings: &Morris, f: impl Fn(&[f64]) -> f64) -> MorrisResult {
        let design = MorrisDesign::new(inputs.len(), settings, 11).unwrap();
        let y: Vec<Outcome> = design.physical(inputs).iter().map(|x| Ok(f(x))).collect();
        design.estimate(&y).unwrap()
    }

    #[test]
    fn linear_plus_interaction_on_uniform_inputs() {
        // y = 3 x0 + x1 + 0 x2 + 4 x3 x4, x_i ~ U(0, 1): EE_0 = 3, EE_1 = 1 exactly, EE_2 = 0.
        let ins = inputs(vec![Distribution::uniform(0.0, 1.0).unwrap(); 5]);
        let r = screen(&ins, &Morris::default(), |x| {
            3.0 * x[0] + x[1] + 4.0 * x[3] * x[4]
        });
        for (i, want) in [(0, 3.0), (1, 1.0), (2, 0.0)] {
            assert!(
                (r.mu[i] - want).abs() < 1e-12 && r.sigma[i] < 1e-12,
                "{i}: {r:?}"
            );
        }
        // The interacting inputs: mu = 4 E[x_other], sigma > 0.
        for i in [3, 4] {
            assert!(r.mu_star[i] > 0.5 && r.sigma[i] > 0.1, "{i}: {r:?}");
        }
        assert_eq!(r.effects, vec![10; 5]);
        assert_eq!(r.ranking[4], 2);
    }

    #[test]
    fn normal_inputs_step_through_their_quantiles() {
        // y = 2 x, x ~ N(5, 3): every move spans q = 1/8 -> 5/8 or 3/8 -> 7/8, the same width
        // 3 (Phi^-1(5/8) - Phi^-1(1/8)) by symmetry, so EE = 2 * that / (1/2).
        let ins = inputs(vec![Distribution::normal(5.0, 3.0).unwrap(); 2]);
        let r = screen(&ins, &Morris::default(), |x| 2.0 * x[0]);
        let width = 3.0 * (norm_ppf(5.0 / 8.0) - norm_ppf(1.0 / 8.0));
        assert!((r.mu[0] - 2.0 * width / 0.5).abs() < 1e-9, "{r:?}");
        assert!(r.sigma[0] < 1e-9);
    }

    #[test]
    fn sobol_g_function_ranks_its_inputs() {
        // g = prod (|4 x_i - 2| + a_i) / (1 + a_i): importance falls with a_i.
        let a = [0.0, 1.0, 4.5, 9.0, 99.0, 99.0, 99.0, 99.0];
        let ins = inputs(vec![Distribution::uniform(0.0, 1.0).unwrap(); 8]);
        let settings = Morris {
            trajectories: 20,
            levels: 6,
            candidates: 100,
        };
        let r = screen(&ins, &settings, |x| {
            x.iter()
                .zip(a)
                .map(|(x, a)| ((4.0 * x - 2.0).abs() + a) / (1.0 + a))
                .product()
        });
        assert_eq!(&r.ranking[..4], &[0, 1, 2, 3], "{r:?}");
        for i in 4..8 {
            assert!(r.mu_star[i] < 0.05 * r.mu_star[0], "{r:?}");
        }
    }

    #[test]
    fn selection_spreads_the_trajectories_and_is_deterministic() {
        let plain = Morris {
            candidates: 0,
            ..Morris::default()
        };
        let a = MorrisDesign::new(6, &plain, 3).unwrap();
        let b = MorrisDesign::new(6, &Morris::default(), 3).unwrap();
        assert!(b.spread > a.spread, "{} vs {}", b.spread, a.spread);
        assert_eq!(b, MorrisDesign::new(6, &Morris::default(), 3).unwrap());
        // Every trajectory moves each input once by half the probability range.
        for t in &b.trajectories {
            let mut sorted = t.order.clone();
            sorted.sort_unstable();
            assert_eq!(sorted, (0..6).collect::<Vec<_>>());
            for (j, &i) in t.order.iter().enumerate() {
                let step = t.points[j + 1][i] - t.points[j][i];
                assert_eq!(step, 0.5 * t.signs[i]);
                assert!(t.points[j + 1].iter().all(|q| *q > 0.0 && *q < 1.0));
            }
        }
    }

    #[test]
    fn failed_runs_drop_their_effects() {
        let design = MorrisDesign::new(3, &Morris::default(), 1).unwrap();
        let mut y: Vec<Outcome> = design.points().iter().map(|q| Ok(q[0] + q[1])).collect();
        y[1] = Err("crashed".into());
        let r = design.estimate(&y).unwrap();
        // Run 1 ends the first move and starts the second: two effects lost.
        assert_eq!(r.effects.iter().sum::<usize>(), 30 - 2);
        assert!(r.warnings[0].contains("1 run(s) failed"));
        assert!(design.estimate(&y[1..]).is_err());
    }
}
