//! First-order Sobol' indices from given data: the binning ("Si from scatter") estimator,
//! for any sample of the inputs' law (Monte Carlo, Latin hypercube, quasi-Monte Carlo), with
//! no design of its own.
//!
//! `S_i = Var(E[Y | X_i]) / Var(Y)`. The `n` runs are split, for each input, into `M =
//! round(sqrt(n))` bins of equal probability in the input's empirical distribution (by the
//! mid-rank of its value: tied values share a bin), and `Var(E[Y | X_i])` is the one-way
//! analysis-of-variance estimate of the between-bin variance component, corrected for the
//! noise of the bin means:
//!
//! `S_i = (SSB − (M − 1) · SSW / (n − M)) / SST`,
//!
//! `SSB = Σ_b n_b (ȳ_b − ȳ)²`, `SSW = Σ_b Σ_{j ∈ b} (y_j − ȳ_b)²`, `SST = SSB + SSW` (`M` the
//! non-empty bins). The correction makes the between-bin part unbiased for bins of equal
//! size whatever the within-bin variances; what is left is the discretisation of
//! `E[Y | X_i]` into bins, whose relative loss falls like `1/M²` for a smooth conditional
//! mean. With `M ~ sqrt(n)` the estimator is consistent with the `O(n^(-1/2))` error of a
//! sample variance (Plischke, Borgonovo & Smith 2013; Strong, Oakley & Chilcott 2012).
//! Estimates below 0 (noise around a zero index) are reported as 0, above 1 as 1.
//!
//! The correction `(M − 1) · SSW / (n − M)` is the noise of bin means of independent runs.
//! A quasi-Monte Carlo net spreads the runs of a bin evenly over the other inputs, so its bin
//! means are far less noisy, and the same correction took too much: on the g-function, 8
//! scrambled nets of 2 048 runs gave `S_3` = 0.0166 for 0.0237 (off by about `(M − 1)/n`).
//! Where the design is made of `R >= 2` independent replicates ([`Bins::with_replicates`]),
//! the noise is instead measured from the replicates themselves:
//! `Σ_b n_b Var(ȳ_b) − n Var(ȳ)`, the variance of every bin's mean (and of the overall
//! mean) estimated from the spread of the replicates' own means of that bin, weighted by
//! their counts. That is unbiased whatever the design's stratification, and for independent
//! runs it agrees with the formula above; where a bin holds runs of one replicate only (a
//! tiny design), the formula above is used.
//!
//! The intervals are basic bootstrap intervals: the runs resampled with replacement, each
//! keeping its bin, the estimate recomputed on every resample, its spread about the
//! resamples' own truth (the runs' plain between-bin share) moved to the estimate
//! ([`Bins::intervals`]).
//!
//! The indices are those of the physical inputs as sampled: under correlated inputs,
//! `Var(E[Y | X_i]) / Var(Y)` still holds (the share of the variance that knowing `X_i` alone
//! removes), but it includes what `X_i` carries of the inputs it is correlated with, and the
//! indices need not add up to at most 1.

use rayon::prelude::*;

use crate::uq::rng;

/// Bootstrap resamples of a scalar quantity's intervals.
pub(crate) const RESAMPLES: usize = 500;
/// Confidence level of the intervals.
pub(crate) const LEVEL: f64 = 0.95;

/// The fewest runs an index is estimated from (two bins of two runs).
pub(crate) const MIN_RUNS: usize = 4;

/// The bin of every run for every input.
#[derive(Clone, Debug)]
pub(crate) struct Bins {
    /// `bin[i][j]`: the bin of run `j` for input `i`.
    bin: Vec<Vec<u32>>,
    /// Bins per input.
    count: usize,
    /// `replicate[j]`: the independent replicate of the design that run `j` belongs to
    /// (empty: the runs are not grouped in replicates).
    replicate: Vec<u32>,
    /// Number of replicates (0 when not grouped).
    replicates: usize,
}

/// The number of bins for `n` runs: `round(sqrt(n))`, at least 2.
pub(crate) fn bin_count(n: usize) -> usize {
    ((n as f64).sqrt().round() as usize).max(2)
}

/// Mid-ranks of `v` (0-based, ties get the mean of their ranks).
pub(crate) fn mid_ranks(v: &[f64]) -> Vec<f64> {
    let n = v.len();
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| v[a].total_cmp(&v[b]));
    let mut ranks = vec![0.0; n];
    let mut k = 0;
    while k < n {
        let mut e = k + 1;
        while e < n && v[order[e]] == v[order[k]] {
            e += 1;
        }
        let mid = 0.5 * ((k + e - 1) as f64);
        for &j in &order[k..e] {
            ranks[j] = mid;
        }
        k = e;
    }
    ranks
}

impl Bins {
    /// The bins of the runs whose inputs are `inputs[i][j]` (input `i`, run `j`): run `j` is
    /// in bin `floor((r_j + 1/2) M / n)` of input `i`, `r_j` its mid-rank.
    pub(crate) fn of(inputs: &[Vec<f64>]) -> Bins {
        let n = inputs.first().map_or(0, Vec::len);
        let count = bin_count(n);
        let bin = inputs
            .iter()
            .map(|x| {
                mid_ranks(x)
                    .iter()
                    .map(|r| (((r + 0.5) * count as f64 / n as f64) as usize).min(count - 1) as u32)
                    .collect()
            })
            .collect();
        Bins {
            bin,
            count,
            replicate: Vec::new(),
            replicates: 0,
        }
    }

    /// The same bins, with the noise of the bin means measured from the spread of
    /// independent replicates of the design (see the module): `replicate[j]` is the
    /// replicate of run `j`. Ignored (the independent-runs correction stays) unless there is
    /// one entry per run and at least two replicates.
    pub(crate) fn with_replicates(mut self, replicate: Vec<u32>) -> Bins {
        let replicates = replicate.iter().max().map_or(0, |&r| r as usize + 1);
        if replicate.len() == self.runs() && replicates >= 2 {
            self.replicate = replicate;
            self.replicates = replicates;
        }
        self
    }

    /// Number of runs.
    pub(crate) fn runs(&self) -> usize {
        self.bin.first().map_or(0, Vec::len)
    }

    /// Number of inputs.
    pub(crate) fn inputs(&self) -> usize {
        self.bin.len()
    }

    /// The first-order index of every input for the outputs `y` (one per run), NaN when `y`
    /// has no variance or there are fewer than [`MIN_RUNS`] runs.
    pub(crate) fn first_order(&self, y: &[f64]) -> Vec<f64> {
        let weights = vec![1u32; y.len()];
        self.shares(y, &weights, true)
            .into_iter()
            .map(|(s, _)| s.clamp(0.0, 1.0))
            .collect()
    }

    /// Per input, the corrected share (unclamped) and the plain between-bin share `SSB /
    /// SST`, with run `j` counted `w[j]` times (a bootstrap resample); NaN where undefined.
    /// `by_replicates`: the noise of the bin means from the replicates' spread where the runs
    /// are grouped in replicates (not for a bootstrap resample, whose runs are independent
    /// draws).
    fn shares(&self, y: &[f64], w: &[u32], by_replicates: bool) -> Vec<(f64, f64)> {
        let n = self.runs();
        let nan = vec![(f64::NAN, f64::NAN); self.inputs()];
        if n < MIN_RUNS || y.len() != n {
            return nan;
        }
        let total: f64 = w.iter().map(|&c| f64::from(c)).sum();
        let mean = y.iter().zip(w).map(|(v, &c)| v * f64::from(c)).sum::<f64>() / total;
        let sst: f64 = y
            .iter()
            .zip(w)
            .map(|(v, &c)| f64::from(c) * (v - mean).powi(2))
            .sum();
        if sst <= 0.0 || !sst.is_finite() {
            return nan;
        }
        let mut sum = vec![0.0; self.count];
        let mut cnt = vec![0.0; self.count];
        let replicated = by_replicates && self.replicates >= 2;
        let mut cells = vec![
            (0.0, 0.0);
            if replicated {
                self.count * self.replicates
            } else {
                0
            }
        ];
        self.bin
            .iter()
            .map(|bins| {
                sum.fill(0.0);
                cnt.fill(0.0);
                for ((&b, v), &c) in bins.iter().zip(y).zip(w) {
                    sum[b as usize] += f64::from(c) * (v - mean);
                    cnt[b as usize] += f64::from(c);
                }
                // SSB about the overall mean (the centred sums of each bin).
                let (mut ssb, mut bins_used) = (0.0, 0.0);
                for (s, c) in sum.iter().zip(&cnt) {
                    if *c > 0.0 {
                        ssb += s * s / c;
                        bins_used += 1.0;
                    }
                }
                let ssw = (sst - ssb).max(0.0);
                let dof = total - bins_used;
                let independent = || {
                    if dof > 0.0 {
                        (bins_used - 1.0) * ssw / dof
                    } else {
                        0.0
                    }
                };
                let noise = match replicated {
                    true => self
                        .replicate_noise(bins, y, mean, &mut cells)
                        .unwrap_or_else(independent),
                    false => independent(),
                };
                ((ssb - noise) / sst, ssb / sst)
            })
            .collect()
    }

    /// The noise `Σ_b n_b Var(ȳ_b) − n Var(ȳ)` of the between-bin sum of squares of the runs
    /// binned by `bins`, every variance from the spread of the replicates' means (`y` less
    /// `mean`, summed into `cells[b · R + r]`); `None` where a bin holds runs of fewer than
    /// two replicates.
    fn replicate_noise(
        &self,
        bins: &[u32],
        y: &[f64],
        mean: f64,
        cells: &mut [(f64, f64)],
    ) -> Option<f64> {
        let r_count = self.replicates;
        cells.fill((0.0, 0.0));
        for ((&b, v), &r) in bins.iter().zip(y).zip(&self.replicate) {
            let cell = &mut cells[b as usize * r_count + r as usize];
            cell.0 += v - mean;
            cell.1 += 1.0;
        }
        let mut noise = 0.0;
        let mut overall = vec![(0.0, 0.0); r_count];
        for bin in cells.chunks_exact(r_count) {
            let runs: f64 = bin.iter().map(|c| c.1).sum();
            if runs > 0.0 {
                noise += runs * variance_of_pooled_mean(bin)?;
            }
            for (o, c) in overall.iter_mut().zip(bin) {
                o.0 += c.0;
                o.1 += c.1;
            }
        }
        Some(noise - self.runs() as f64 * variance_of_pooled_mean(&overall)?)
    }

    /// Bootstrap intervals `(low, high)` at `level` of every input's first-order index, from
    /// `resamples` resamples of the runs drawn from the stream of `seed`, clamped to [0, 1].
    ///
    /// A resample is an independent sample of the runs' empirical law, whose own index is
    /// the plain between-bin share `θ = SSB / SST` of the runs (the noise of the bin means
    /// included): the resampled estimates `S*` spread around `θ`, not around the corrected
    /// estimate `S`. The interval is therefore the percentile interval of `S* − θ` moved to
    /// `S` (the basic bootstrap): `[S − (q_hi − θ), S − (q_lo − θ)]`, `q` the percentiles of
    /// `S*`. Percentiles of `S*` themselves would sit about `(M − 1) / n` too high. Where the
    /// runs are grouped in replicates, `S` is corrected by the replicates' spread, and the
    /// interval keeps the width of independent runs: conservative for a quasi-Monte Carlo
    /// design, whose estimate is more precise than that.
    pub(crate) fn intervals(
        &self,
        y: &[f64],
        resamples: usize,
        level: f64,
        seed: u64,
    ) -> Vec<(f64, f64)> {
        let (n, d) = (self.runs(), self.inputs());
        if n < MIN_RUNS || resamples == 0 || y.len() != n {
            return vec![(f64::NAN, f64::NAN); d];
        }
        let ones = vec![1u32; n];
        let here = self.shares(y, &ones, true);
        // Resample k from its own stream (seed, k): in parallel, the same for any thread count.
        let replicates: Vec<Vec<(f64, f64)>> = (0..resamples)
            .into_par_iter()
            .map(|k| {
                let mut stream = rng::stream(seed, k as u64);
                let mut w = vec![0u32; n];
                for _ in 0..n {
                    w[rng::uniform_below(&mut stream, n as u64) as usize] += 1;
                }
                self.shares(y, &w, false)
            })
            .collect();
        let mut draws = vec![Vec::with_capacity(resamples); d];
        for r in replicates {
            for (i, (s, _)) in r.into_iter().enumerate() {
                draws[i].push(s);
            }
        }
        draws
            .into_iter()
            .zip(here)
            .map(|(mut v, (s, theta))| {
                v.retain(|x| x.is_finite());
                if v.is_empty() || !s.is_finite() {
                    return (f64::NAN, f64::NAN);
                }
                v.sort_by(f64::total_cmp);
                let tail = 0.5 * (1.0 - level);
                let at = |p: f64| {
                    let k = (p * (v.len() - 1) as f64).round() as usize;
                    v[k.min(v.len() - 1)]
                };
                let (lo, hi) = (s - (at(1.0 - tail) - theta), s - (at(tail) - theta));
                (lo.clamp(0.0, 1.0), hi.clamp(0.0, 1.0))
            })
            .collect()
    }
}

/// The variance of the pooled mean `Σ s_r / Σ c_r` of groups of `c_r` runs summing to `s_r`,
/// estimated from the spread of the group means `s_r / c_r` about it, each weighted by its
/// share `w_r = c_r / Σ c`: `Σ w_r (s_r / c_r − m)² / (R − 1)` over the `R` groups holding
/// runs, unbiased when a group mean's variance goes as `1 / c_r` (independent runs, whatever
/// the counts) and, with equal counts, the sample variance of the group means over `R`;
/// `None` with fewer than two groups holding runs. (Taking the group means as of equal
/// variance instead overstated it by the spread of the counts: indices about 0.004 low with 4
/// replicates of 250 independent runs.)
fn variance_of_pooled_mean(groups: &[(f64, f64)]) -> Option<f64> {
    let runs: f64 = groups.iter().map(|g| g.1).sum();
    let held = groups.iter().filter(|g| g.1 > 0.0).count();
    if held < 2 {
        return None;
    }
    let pooled = groups.iter().map(|g| g.0).sum::<f64>() / runs;
    let spread: f64 = groups
        .iter()
        .filter(|g| g.1 > 0.0)
        .map(|&(s, c)| c / runs * (s / c - pooled).powi(2))
        .sum();
    Some(spread / (held - 1) as f64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::uq::sampling;
    use std::f64::consts::PI;

    /// `n` Latin-hypercube points mapped to `[lo, hi]` per input, as `inputs[i][j]`.
    fn inputs(n: usize, ranges: &[(f64, f64)], seed: u64) -> Vec<Vec<f64>> {
        let pts = sampling::latin_hypercube(n, ranges.len(), seed);
        ranges
            .iter()
            .enumerate()
            .map(|(i, (lo, hi))| pts.iter().map(|p| lo + (hi - lo) * p[i]).collect())
            .collect()
    }

    fn at(x: &[Vec<f64>], j: usize) -> Vec<f64> {
        x.iter().map(|c| c[j]).collect()
    }

    #[test]
    fn ishigami_first_order_indices_within_0_03_of_the_closed_form_from_8000_runs() {
        // a = 7, b = 0.1, x_i ~ U(-pi, pi): V1 = (1 + b pi^4 / 5)^2 / 2, V2 = a^2 / 8, V3 = 0.
        let (a, b) = (7.0f64, 0.1f64);
        let v = a * a / 8.0 + b * PI.powi(4) / 5.0 + b * b * PI.powi(8) / 18.0 + 0.5;
        let exact = [
            0.5 * (1.0 + b * PI.powi(4) / 5.0).powi(2) / v,
            a * a / 8.0 / v,
            0.0,
        ];
        assert!((exact[0] - 0.3139).abs() < 1e-4 && (exact[1] - 0.4424).abs() < 1e-4);
        // 8 000 runs: the estimator's standard deviation is about 0.007 (0.014 at 2 000).
        let x = inputs(8000, &[(-PI, PI); 3], 11);
        let y: Vec<f64> = (0..8000)
            .map(|j| {
                let p = at(&x, j);
                p[0].sin() + a * p[1].sin().powi(2) + b * p[2].powi(4) * p[0].sin()
            })
            .collect();
        let bins = Bins::of(&x);
        assert_eq!(bins.count, 89);
        let s = bins.first_order(&y);
        let ci = bins.intervals(&y, 200, 0.95, 3);
        assert_within(&s, &exact, 0.03);
        for i in 0..3 {
            assert!(ci[i].0 <= s[i] + 1e-12 && s[i] <= ci[i].1 + 1e-12, "{ci:?}");
            assert!(ci[i].1 - ci[i].0 < 0.15, "{ci:?}");
        }
    }

    #[test]
    fn linear_function_first_order_indices_are_the_variance_shares() {
        // g = Σ a_i x_i, x_i ~ U(0, 1): S_i = a_i² / Σ a_k².
        let a = [1.0, 2.0, 0.5, 0.0, 3.0];
        let x = inputs(4000, &[(0.0, 1.0); 5], 5);
        let y: Vec<f64> = (0..4000)
            .map(|j| at(&x, j).iter().zip(&a).map(|(x, a)| a * x).sum())
            .collect();
        let total: f64 = a.iter().map(|a| a * a).sum();
        let s = Bins::of(&x).first_order(&y);
        for i in 0..5 {
            let exact = a[i] * a[i] / total;
            assert!(
                (s[i] - exact).abs() < 0.02,
                "S{}: {} vs {exact}",
                i + 1,
                s[i]
            );
        }
    }

    #[test]
    fn bootstrap_intervals_cover_the_exact_index_about_95_percent_of_the_time() {
        // g = x1 + 2 x2 + 0.5 x3 on U(0, 1)³, 200 samples of 400 runs each (independent
        // Latin hypercubes): S = (1, 4, 0.25) / 5.25.
        let a = [1.0, 2.0, 0.5];
        let exact: Vec<f64> = a.iter().map(|x| x * x / 5.25).collect();
        let mut covered = [0usize; 3];
        let trials = 200;
        for t in 0..trials {
            let x = inputs(400, &[(0.0, 1.0); 3], 1000 + t);
            let y: Vec<f64> = (0..400)
                .map(|j| at(&x, j).iter().zip(&a).map(|(x, a)| a * x).sum())
                .collect();
            let ci = Bins::of(&x).intervals(&y, 200, 0.95, t);
            for i in 0..3 {
                covered[i] += usize::from(ci[i].0 <= exact[i] && exact[i] <= ci[i].1);
            }
        }
        for (i, c) in covered.iter().enumerate() {
            let rate = *c as f64 / trials as f64;
            assert!(rate >= 0.88, "S{}: covered {rate}", i + 1);
        }
    }

    /// The g-function `Π (|4 x_i − 2| + a_i) / (1 + a_i)` on `R` scrambled Sobol' nets of
    /// `n` points in 8 inputs, as `(inputs[i][j], y[j], replicate[j])`.
    fn g_function_on_nets(r: usize, n: usize, seed: u64) -> (Vec<Vec<f64>>, Vec<f64>, Vec<u32>) {
        let a = [0.0, 1.0, 4.5, 9.0, 99.0, 99.0, 99.0, 99.0];
        let mut x = vec![Vec::new(); 8];
        let (mut y, mut replicate) = (Vec::new(), Vec::new());
        for k in 0..r {
            let net = crate::uq::hd::sobol_seq::Sobol::scrambled(8, seed, k as u64)
                .unwrap()
                .points(0, n)
                .unwrap();
            for p in net {
                y.push(
                    p.iter()
                        .zip(&a)
                        .map(|(x, a)| ((4.0 * x - 2.0).abs() + a) / (1.0 + a))
                        .product(),
                );
                for (c, v) in x.iter_mut().zip(&p) {
                    c.push(*v);
                }
                replicate.push(k as u32);
            }
        }
        (x, y, replicate)
    }

    #[test]
    fn scrambled_nets_are_not_corrected_as_if_their_runs_were_independent() {
        // V_i = 1 / (3 (1 + a_i)²), S_i = V_i / (Π (1 + V_k) − 1): S_3 = 0.02368, S_4 = 0.00716.
        let a = [0.0, 1.0, 4.5, 9.0, 99.0, 99.0, 99.0, 99.0];
        let v: Vec<f64> = a
            .iter()
            .map(|a: &f64| 1.0 / (3.0 * (1.0 + a).powi(2)))
            .collect();
        let total = v.iter().map(|v| 1.0 + v).product::<f64>() - 1.0;
        let exact: Vec<f64> = v.iter().map(|v| v / total).collect();
        assert!((exact[2] - 0.02368).abs() < 1e-5 && (exact[3] - 0.00716).abs() < 1e-5);
        // 8 nets of 512 points: M = 64 bins. The correction for independent runs takes about
        // (M − 1)/n (1 − S_i) = 0.015 too much (measured: S_3 = 0.009, S_4 = 0); from the
        // replicates' spread every index is within 0.003 (measured: 0.0005).
        let (x, y, replicate) = g_function_on_nets(8, 512, 3);
        let independent = Bins::of(&x).first_order(&y);
        assert!(independent[2] < exact[2] - 0.01, "{independent:?}");
        let bins = Bins::of(&x).with_replicates(replicate);
        let s = bins.first_order(&y);
        assert_within(&s, &exact, 0.003);
        // The intervals keep the width of independent runs: they cover.
        let ci = bins.intervals(&y, 200, 0.95, 1);
        for i in 0..8 {
            assert!(
                ci[i].0 <= exact[i] && exact[i] <= ci[i].1,
                "S{}: {:?}",
                i + 1,
                ci[i]
            );
        }
    }

    #[test]
    fn replicates_of_independent_runs_give_the_unbiased_indices_of_the_formula() {
        // Independent runs split into 4 replicates: the noise from the replicates' spread
        // agrees with (M − 1) SSW / (n − M) on average, so the indices stay unbiased (mean of
        // 40 samples of 1 000 runs within 3 standard errors of S = (1, 4, 0.25) / 5.25).
        let a = [1.0, 2.0, 0.5];
        let exact: Vec<f64> = a.iter().map(|x| x * x / 5.25).collect();
        let trials = 40;
        let mut sums = [[0.0; 3]; 2];
        let mut squares = [0.0; 3];
        for t in 0..trials {
            let mut stream = rng::stream(500 + t, 0);
            let x: Vec<Vec<f64>> = (0..3)
                .map(|_| {
                    (0..1000)
                        .map(|_| rng::uniform_open01(&mut stream))
                        .collect()
                })
                .collect();
            let y: Vec<f64> = (0..1000)
                .map(|j| at(&x, j).iter().zip(&a).map(|(x, a)| a * x).sum())
                .collect();
            let replicate = (0..1000).map(|j| (j / 250) as u32).collect();
            let by_formula = Bins::of(&x).first_order(&y);
            let by_spread = Bins::of(&x).with_replicates(replicate).first_order(&y);
            for i in 0..3 {
                sums[0][i] += by_formula[i];
                sums[1][i] += by_spread[i];
                squares[i] += by_spread[i] * by_spread[i];
            }
        }
        let n = trials as f64;
        for i in 0..3 {
            let mean = sums[1][i] / n;
            let se = ((squares[i] / n - mean * mean) / (n - 1.0)).sqrt();
            assert!(
                (mean - exact[i]).abs() < 3.0 * se + 1e-3,
                "S{}: {mean} ± {se}",
                i + 1
            );
            // The bins' counts per replicate differ: weighting the replicate means as of
            // equal variance took about 0.003 too much from S1 and S3.
            let formula = sums[0][i] / n;
            println!(
                "S{}: by the spread {mean:.5}, by the formula {formula:.5}",
                i + 1
            );
            assert!(
                (mean - formula).abs() < 0.0015,
                "S{}: {mean} vs {formula}",
                i + 1
            );
        }
    }

    #[test]
    fn noise_alone_gives_indices_near_zero_thanks_to_the_bias_correction() {
        // y independent of x: the raw between-bin share is about (M - 1) / n = 0.022 for
        // n = 2000; corrected, the indices are 0 up to noise.
        let x = inputs(2000, &[(0.0, 1.0); 4], 7);
        let mut stream = rng::stream(99, 0);
        let y: Vec<f64> = (0..2000)
            .map(|_| rng::standard_normal(&mut stream))
            .collect();
        let s = Bins::of(&x).first_order(&y);
        for v in s {
            assert!(v < 0.01, "{v}");
        }
    }

    #[test]
    fn borehole_like_product_indices_match_a_quadrature_written_here() {
        // y = x1 * (1 + x2²) / (1 + x3) on U(1, 2)³: first-order indices from a tensor
        // Gauss–Legendre rule of the conditional means (computed here, 24 nodes per input;
        // S1 = 0.3016 in closed form: Var x1 (E g E h)² / Var y).
        let f = |x: &[f64]| x[0] * (1.0 + x[1] * x[1]) / (1.0 + x[2]);
        let (nodes, weights) = legendre_on(1.0, 2.0, 24);
        let k = nodes.len();
        let (mut m, mut m2) = (0.0, 0.0);
        let mut cond = vec![vec![0.0; k]; 3];
        for a in 0..k {
            for b in 0..k {
                for c in 0..k {
                    let w = weights[a] * weights[b] * weights[c];
                    let y = f(&[nodes[a], nodes[b], nodes[c]]);
                    m += w * y;
                    m2 += w * y * y;
                    cond[0][a] += weights[b] * weights[c] * y;
                    cond[1][b] += weights[a] * weights[c] * y;
                    cond[2][c] += weights[a] * weights[b] * y;
                }
            }
        }
        let var = m2 - m * m;
        let exact: Vec<f64> = cond
            .iter()
            .map(|c| (c.iter().zip(&weights).map(|(e, w)| w * e * e).sum::<f64>() - m * m) / var)
            .collect();
        // 10 000 runs: the estimator's standard deviation is about 0.006.
        let x = inputs(10_000, &[(1.0, 2.0); 3], 21);
        let y: Vec<f64> = (0..10_000).map(|j| f(&at(&x, j))).collect();
        let s = Bins::of(&x).first_order(&y);
        assert_within(&s, &exact, 0.03);
    }

    /// Each first-order index `s[i]` within `tol` of `exact[i]`.
    fn assert_within(s: &[f64], exact: &[f64], tol: f64) {
        assert_eq!(s.len(), exact.len());
        for (i, (s, e)) in s.iter().zip(exact).enumerate() {
            assert!((s - e).abs() < tol, "S{}: {} vs {}", i + 1, s, e);
        }
    }

    /// Gauss–Legendre nodes and weights (summing to 1) on `[lo, hi]`, by Newton on P_n.
    fn legendre_on(lo: f64, hi: f64, n: usize) -> (Vec<f64>, Vec<f64>) {
        let (mut x, mut w) = (Vec::new(), Vec::new());
        for i in 0..n {
            let mut t = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
            let mut dp = 0.0;
            for _ in 0..100 {
                let (mut p0, mut p1) = (1.0, t);
                for k in 2..=n {
                    let p2 = ((2 * k - 1) as f64 * t * p1 - (k - 1) as f64 * p0) / k as f64;
                    p0 = p1;
                    p1 = p2;
                }
                dp = n as f64 * (t * p1 - p0) / (t * t - 1.0);
                let step = p1 / dp;
                t -= step;
                if step.abs() < 1e-15 {
                    break;
                }
            }
            x.push(lo + (hi - lo) * 0.5 * (t + 1.0));
            w.push(1.0 / ((1.0 - t * t) * dp * dp));
        }
        (x, w)
    }

    #[test]
    fn tied_inputs_share_a_bin_and_constant_outputs_have_no_index() {
        let r = mid_ranks(&[3.0, 1.0, 3.0, 2.0]);
        assert_eq!(r, vec![2.5, 0.0, 2.5, 1.0]);
        let x = vec![vec![0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0, 0.0, 1.0]];
        let bins = Bins::of(&x);
        assert_eq!(bins.count, 3);
        let b = &bins.bin[0];
        assert!(x[0].iter().zip(b).all(|(v, &k)| (*v == 0.0) == (k == b[0])));
        assert!(bins.first_order(&[2.0; 9])[0].is_nan());
        assert!(Bins::of(&[vec![1.0, 2.0, 3.0]]).first_order(&[1.0, 2.0, 4.0])[0].is_nan());
    }
}
