//! What an estimator returns: moments per column and, where the method has them, a chaos
//! surrogate, Sobol' indices and standard errors.

use nalgebra::DMatrix;

use crate::uq::hd::sensitivity::replicate_summary;
use crate::uq::moments;
use crate::uq::pce::Pce;

/// Where quantiles and densities are drawn from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Draws {
    /// The successful runs themselves.
    Runs,
    /// A large sample of the chaos surrogate ([`Estimate::chaos`]).
    Chaos,
}

impl Draws {
    /// How densities were obtained, for the report.
    pub fn describe(self) -> &'static str {
        match self {
            Draws::Runs => "kernel density of the runs",
            Draws::Chaos => "kernel density of a large sample of the chaos surrogate",
        }
    }
}

/// How the truncation error of a chaos was estimated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ChaosErrorKind {
    /// Corrected relative leave-one-out error of a regression (Blatman & Sudret 2011):
    /// `T(P, N) · mean((y_i - ŷ_(-i))²) / Var(y)`.
    Loo,
    /// Relative mean-square difference between the chaoses of sparse-grid levels `L` and
    /// `L - 1` (same runs, nested rules): `Σ (c_L - c_(L-1))² / Var_L`.
    LevelDifference,
    /// Relative mean-square difference between the chaoses of orders `p` and `p - 1` (same
    /// runs): the variance share of the terms of degree `p`.
    OrderDifference,
}

impl ChaosErrorKind {
    /// The column name in `<V>.csv` and the `kind` in `summary.json` and `surrogate.json`.
    pub fn name(self) -> &'static str {
        match self {
            ChaosErrorKind::Loo => "loo",
            ChaosErrorKind::LevelDifference => "level_difference",
            ChaosErrorKind::OrderDifference => "order_difference",
        }
    }
}

/// An estimate of a chaos's relative truncation error, one value per column.
#[derive(Clone, Debug, PartialEq)]
pub struct ChaosError {
    /// How it was estimated.
    pub kind: ChaosErrorKind,
    /// Per column (relative to the variance; 0 for a column without variance).
    pub values: Vec<f64>,
    /// Per column, a second estimate where `values` is known to be biased, which the
    /// warnings judge instead: for `level_difference` at a level `L >= 2`, the level
    /// difference extrapolated to level `L` itself (`values` is the error of level `L − 1`);
    /// for `loo` of a sparse (LARS-selected) regression, the larger of it and the k-fold
    /// cross-validation error with the selection redone in each fold (the leave-one-out error
    /// of a selected basis is optimistic).
    pub check: Option<Vec<f64>>,
}

impl ChaosError {
    /// The values the warnings judge: `check` where there is one, else `values`.
    pub fn judged(&self) -> &[f64] {
        self.check.as_deref().unwrap_or(&self.values)
    }
}

/// First-order and total Sobol' indices, each `[column][parameter]`, with confidence
/// intervals where the method estimates them (sampling).
#[derive(Clone, Debug, PartialEq)]
pub struct Sobol {
    /// First-order indices.
    pub first: Vec<Vec<f64>>,
    /// Total indices.
    pub total: Vec<Vec<f64>>,
    /// Confidence intervals of the indices, where the method has them.
    pub intervals: Option<SobolIntervals>,
    /// First-order indices estimated from given data (a sample of the inputs' law, by
    /// binning): `total` is not estimated (NaN, or an empty row per column of a series),
    /// nor are its intervals.
    pub given_data: bool,
}

/// Confidence intervals `(low, high)` of Sobol' indices, each `[column][parameter]`.
#[derive(Clone, Debug, PartialEq)]
pub struct SobolIntervals {
    /// Confidence level (e.g. 0.95).
    pub level: f64,
    /// Intervals of the first-order indices.
    pub first: Vec<Vec<(f64, f64)>>,
    /// Intervals of the total indices.
    pub total: Vec<Vec<(f64, f64)>>,
}

impl Sobol {
    /// Point estimates without intervals.
    pub fn new(first: Vec<Vec<f64>>, total: Vec<Vec<f64>>) -> Sobol {
        Sobol {
            first,
            total,
            intervals: None,
            given_data: false,
        }
    }

    /// The indices of a whole series (generalised, time-integrated Sobol' indices): each
    /// column's index weighted by its variance `std²` and its share of the time axis (the
    /// trapezoid rule over `times`), `S_i = ∫ Var(t) S_i(t) dt / ∫ Var(t) dt`, the share of
    /// the series' integrated variance that parameter `i` causes (alone, or with
    /// interactions for the total index). Columns with zero or non-finite variance or
    /// indices are left out. `None` when no column is left or the lengths disagree.
    pub fn integrated(&self, times: &[f64], std: &[f64]) -> Option<(Vec<f64>, Vec<f64>)> {
        let n = times.len();
        if n == 0 || std.len() != n || self.first.len() != n || self.total.len() != n {
            return None;
        }
        let d = self.first[0].len();
        let (mut first, mut total, mut weight) = (vec![0.0; d], vec![0.0; d], 0.0);
        for k in 0..n {
            // Trapezoid weight of column k (1 for a single column).
            let dt = match (k.checked_sub(1).map(|j| times[j]), times.get(k + 1)) {
                (Some(a), Some(&b)) => 0.5 * (b - a),
                (None, Some(&b)) => 0.5 * (b - times[k]),
                (Some(a), None) => 0.5 * (times[k] - a),
                (None, None) => 1.0,
            };
            let w = dt * std[k] * std[k];
            let (f, t) = (&self.first[k], &self.total[k]);
            let usable = w.is_finite()
                && w > 0.0
                && f.len() == d
                && t.len() == d
                && f.iter().chain(t).all(|x| x.is_finite());
            if !usable {
                continue;
            }
            weight += w;
            for i in 0..d {
                first[i] += w * f[i];
                total[i] += w * t[i];
            }
        }
        // Every weight added is positive: the sum is 0 only when no column was usable.
        if weight == 0.0 {
            return None;
        }
        first
            .iter_mut()
            .chain(&mut total)
            .for_each(|x| *x /= weight);
        Some((first, total))
    }

    /// These indices with those of the columns without variance set to NaN (indices and
    /// intervals): where `std` is zero at the rounding level of `mean` (`no_variance`) the
    /// indices are 0/0, undefined, whatever the estimator computed there.
    pub fn undefined_without_variance(&self, mean: &[f64], std: &[f64]) -> Sobol {
        let mut out = self.clone();
        let constant = |k: usize| match (mean.get(k), std.get(k)) {
            (Some(&m), Some(&s)) => no_variance(m, s),
            _ => false,
        };
        let nan = |rows: &mut [Vec<f64>]| {
            for (k, row) in rows.iter_mut().enumerate() {
                if constant(k) {
                    row.fill(f64::NAN);
                }
            }
        };
        nan(&mut out.first);
        nan(&mut out.total);
        if let Some(iv) = &mut out.intervals {
            for rows in [&mut iv.first, &mut iv.total] {
                for (k, row) in rows.iter_mut().enumerate() {
                    if constant(k) {
                        row.fill((f64::NAN, f64::NAN));
                    }
                }
            }
        }
        out
    }

    /// The indices of every column of a chaos (variance shares of its terms).
    pub fn from_chaos(pce: &Pce) -> Sobol {
        let cols = 0..pce.outputs();
        Sobol::new(
            cols.clone().map(|k| pce.sobol_first(k)).collect(),
            cols.map(|k| pce.sobol_total(k)).collect(),
        )
    }
}

/// A standard deviation at or below this fraction of |mean| is rounding noise, not variance
/// (a chaos of a constant output has coefficients of about 1e-16 |mean|).
pub const ROUNDING_STD: f64 = 1e-12;

/// Whether a column with this mean and standard deviation has no variance: `std` (NaN
/// aside) is at most [`ROUNDING_STD`] · |mean| (exactly 0 for a zero mean).
pub fn no_variance(mean: f64, std: f64) -> bool {
    std.abs() <= ROUNDING_STD * mean.abs()
}

/// Statistics of a results matrix, one value per column (time step or quantity).
#[derive(Clone, Debug)]
pub struct Estimate {
    /// Mean.
    pub mean: Vec<f64>,
    /// Standard deviation.
    pub std: Vec<f64>,
    /// Standard error of the mean, where the method estimates it (sampling).
    pub std_error_mean: Option<Vec<f64>>,
    /// Standard deviation of the chaos surrogate, where it differs from `std` (collocation:
    /// `std` comes from the quadrature, this from the truncated chaos).
    pub std_chaos: Option<Vec<f64>>,
    /// The chaos surrogate of every column.
    pub chaos: Option<Pce>,
    /// Sobol' indices.
    pub sobol: Option<Sobol>,
    /// Where quantiles and densities come from.
    pub draws: Draws,
    /// The estimated truncation error of the chaos, where the method estimates it.
    pub chaos_error: Option<ChaosError>,
}

impl Estimate {
    /// Sample mean, unbiased Std and its standard error `std / sqrt(n)` of equally weighted
    /// runs (`n` rows).
    pub fn from_sample(data: &DMatrix<f64>) -> Estimate {
        let (mean, std) = moments::sample_mean_std(data);
        let root_n = (data.nrows() as f64).sqrt();
        let sem = std.iter().map(|s| s / root_n).collect();
        Estimate {
            mean,
            std,
            std_error_mean: Some(sem),
            ..Estimate::empty(Draws::Runs)
        }
    }

    /// Estimates from `R` independent replicates of an equally weighted design of `n` points
    /// each (point `i` of the design belongs to replicate `i / n`): per column, the mean of
    /// the replicate means and its standard error `sd(replicate means) / sqrt(R)`; the Std
    /// is the unbiased Std of all runs. `rows` are the design indices of the rows of `data`
    /// (failed points left out: a replicate's mean is over its successful runs; a replicate
    /// without any is left out; fewer than two replicates give a NaN standard error).
    pub fn from_replicates(data: &DMatrix<f64>, rows: &[usize], n: usize) -> Estimate {
        let (_, std) = moments::sample_mean_std(data);
        let replicate_of: Vec<usize> = rows.iter().map(|&i| i / n.max(1)).collect();
        let count = replicate_of.iter().max().map_or(0, |&r| r + 1);
        let (mean, sem) = data
            .column_iter()
            .map(|col| {
                let mut sums = vec![(0.0, 0usize); count];
                for (v, &r) in col.iter().zip(&replicate_of) {
                    sums[r].0 += v;
                    sums[r].1 += 1;
                }
                let means: Vec<f64> = sums
                    .iter()
                    .filter(|(_, k)| *k > 0)
                    .map(|(s, k)| s / *k as f64)
                    .collect();
                let r = replicate_summary(&means);
                (r.mean, r.std_error)
            })
            .unzip();
        Estimate {
            mean,
            std,
            std_error_mean: Some(sem),
            ..Estimate::empty(Draws::Runs)
        }
    }

    /// Quadrature mean and Std of weighted runs (one weight per row).
    pub fn from_quadrature(data: &DMatrix<f64>, weights: &[f64]) -> Estimate {
        let (mean, std) = moments::weighted_mean_std(data, weights);
        Estimate {
            mean,
            std,
            ..Estimate::empty(Draws::Runs)
        }
    }

    /// Moments and Sobol' indices of a chaos; densities from samples of it.
    pub fn from_chaos(pce: Pce) -> Estimate {
        Estimate {
            mean: pce.mean(),
            std: pce.std(),
            sobol: Some(Sobol::from_chaos(&pce)),
            chaos: Some(pce),
            ..Estimate::empty(Draws::Chaos)
        }
    }

    fn empty(draws: Draws) -> Estimate {
        Estimate {
            mean: Vec::new(),
            std: Vec::new(),
            std_error_mean: None,
            std_chaos: None,
            chaos: None,
            sobol: None,
            draws,
            chaos_error: None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::uq::pce::{Basis, Family, MultiIndexSet};

    #[test]
    fn sample_estimate_has_the_standard_error() {
        let data = DMatrix::from_column_slice(4, 1, &[1.0, 2.0, 3.0, 4.0]);
        let e = Estimate::from_sample(&data);
        assert_eq!(e.mean, vec![2.5]);
        let std = (5.0f64 / 3.0).sqrt();
        assert!((e.std[0] - std).abs() < 1e-15);
        assert!((e.std_error_mean.unwrap()[0] - std / 2.0).abs() < 1e-15);
        assert_eq!(e.draws, Draws::Runs);
    }

    #[test]
    fn integrated_indices_weigh_each_time_by_its_variance() {
        // Y(t) = t X1 + X2 + 0.5 X1 X2 (X1, X2 independent standard normals): Var = t² + 1.25,
        // S1 = t² / Var, S2 = 1 / Var, ST1 = (t² + 0.25) / Var, ST2 = 1.25 / Var. Over the
        // times 0, 0.5, 2 the trapezoid weights are 0.25, 1, 0.75: ∫Var = 5.75, ∫t² = 3.25,
        // ∫(t² + 0.25) = 3.75, ∫1 = 2, ∫1.25 = 2.5.
        // A fourth column without variance and a fifth with undefined indices add nothing.
        let times = [0.0, 0.5, 2.0, 2.0, 2.0];
        let var = |t: f64| t * t + 1.25;
        let mut first: Vec<Vec<f64>> = times[..3]
            .iter()
            .map(|&t| vec![t * t / var(t), 1.0 / var(t)])
            .collect();
        let mut total: Vec<Vec<f64>> = times[..3]
            .iter()
            .map(|&t| vec![(t * t + 0.25) / var(t), 1.25 / var(t)])
            .collect();
        first.extend([vec![0.3, 0.3], vec![f64::NAN, 0.5]]);
        total.extend([vec![0.3, 0.3], vec![f64::NAN, 0.5]]);
        let mut std: Vec<f64> = times[..3].iter().map(|&t| var(t).sqrt()).collect();
        std.extend([0.0, 1.0]);
        let (s, st) = Sobol::new(first, total).integrated(&times, &std).unwrap();
        let close = |a: f64, b: f64| (a - b).abs() < 1e-14;
        assert!(close(s[0], 3.25 / 5.75) && close(s[1], 2.0 / 5.75), "{s:?}");
        assert!(
            close(st[0], 3.75 / 5.75) && close(st[1], 2.5 / 5.75),
            "{st:?}"
        );
        // No variance anywhere, or lengths that disagree: no indices.
        let flat = Sobol::new(vec![vec![0.5]; 2], vec![vec![0.5]; 2]);
        assert_eq!(flat.integrated(&[0.0, 1.0], &[0.0, 0.0]), None);
        assert_eq!(flat.integrated(&[0.0], &[1.0]), None);
    }

    #[test]
    fn chaos_estimate_reads_moments_and_indices_from_the_coefficients() {
        // f = 1 + 2 z1 + 3 z2: mean 1, variance 13, S1 = 4/13, S2 = 9/13.
        let set = MultiIndexSet::total_degree(2, 1).unwrap();
        let basis = Basis::new(vec![Family::Hermite, Family::Legendre], set).unwrap();
        let coeffs = DMatrix::from_column_slice(3, 1, &[1.0, 2.0, 3.0]);
        let e = Estimate::from_chaos(Pce::new(basis, coeffs).unwrap());
        assert_eq!(e.mean, vec![1.0]);
        assert!((e.std[0] - 13f64.sqrt()).abs() < 1e-15);
        let s = e.sobol.unwrap();
        assert!((s.first[0][0] - 4.0 / 13.0).abs() < 1e-15);
        assert!((s.total[0][1] - 9.0 / 13.0).abs() < 1e-15);
        assert_eq!(e.draws, Draws::Chaos);
    }
}

#[cfg(test)]
mod replicate_tests {
    use super::*;

    #[test]
    fn replicate_estimate_is_the_spread_of_the_replicate_means() {
        // Three replicates of two points: means 1.5, 3.5, 5.5 -> mean 3.5, SE sd/sqrt(3) = 2/sqrt(3).
        let v = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0];
        let data = DMatrix::from_column_slice(6, 1, &v);
        let rows: Vec<usize> = (0..6).collect();
        let e = Estimate::from_replicates(&data, &rows, 2);
        assert_eq!(e.mean, vec![3.5]);
        assert!((e.std_error_mean.as_ref().unwrap()[0] - 2.0 / 3f64.sqrt()).abs() < 1e-15);
        // The Std is that of all runs.
        assert!((e.std[0] - 3.5f64.sqrt()).abs() < 1e-15);
        // A failed point leaves its replicate's mean over the others.
        let data = DMatrix::from_column_slice(5, 1, &[1.0, 2.0, 3.0, 5.0, 6.0]);
        let e = Estimate::from_replicates(&data, &[0, 1, 2, 4, 5], 2);
        assert_eq!(e.mean, vec![(1.5 + 3.0 + 5.5) / 3.0]);
        // One replicate left: no standard error.
        let data = DMatrix::from_column_slice(2, 1, &[1.0, 2.0]);
        let e = Estimate::from_replicates(&data, &[4, 5], 2);
        assert!(e.std_error_mean.unwrap()[0].is_nan());
    }

    /// Where a column has no variance (a fixed initial state at t = 0, a constant
    /// output) its indices are 0/0; they were written as exact 0 with a [0, 0] interval.
    #[test]
    fn sobol_indices_without_variance_are_nan_and_the_whole_series_skips_them() {
        let mut s = Sobol::new(
            vec![
                vec![0.0, 0.0],
                vec![0.25, 0.5],
                vec![0.0, 0.0],
                vec![0.6, 0.3],
            ],
            vec![
                vec![0.0, 0.0],
                vec![0.5, 0.75],
                vec![0.0, 0.0],
                vec![0.7, 0.4],
            ],
        );
        s.intervals = Some(SobolIntervals {
            level: 0.95,
            first: vec![
                vec![(0.0, 0.0); 2],
                vec![(0.2, 0.3); 2],
                vec![(0.0, 0.0); 2],
                vec![(0.5, 0.7); 2],
            ],
            total: vec![
                vec![(0.0, 0.0); 2],
                vec![(0.4, 0.6); 2],
                vec![(0.0, 0.0); 2],
                vec![(0.6, 0.8); 2],
            ],
        });
        // Column 0: mean 0, std 0; column 2: std at the rounding level of the mean 1.79
        // (1.1e-15 relative, a chaos of a constant); -0 counts as 0. Columns 1 and 3 vary.
        let mean = [0.0, 1.0, 1.79, -3.0];
        let std = [-0.0, 2.0, 2.0e-15, 1e-6];
        let d = s.undefined_without_variance(&mean, &std);
        for k in [0, 2] {
            assert!(
                d.first[k].iter().chain(&d.total[k]).all(|x| x.is_nan()),
                "{k}"
            );
            let iv = d.intervals.as_ref().unwrap();
            assert!(iv.first[k]
                .iter()
                .chain(&iv.total[k])
                .all(|(a, b)| a.is_nan() && b.is_nan()));
        }
        for k in [1, 3] {
            assert_eq!(d.first[k], s.first[k]);
            assert_eq!(d.total[k], s.total[k]);
            assert_eq!(
                d.intervals.as_ref().unwrap().first[k],
                s.intervals.as_ref().unwrap().first[k]
            );
        }
        // The whole-series indices skip the NaN columns: over times 0, 1, 2, 3 (trapezoid
        // weights 0.5, 1, 1, 0.5) only columns 1 (weight 1 · 2²) and 3 (0.5 · 1e-12) count.
        let (f, t) = d.integrated(&[0.0, 1.0, 2.0, 3.0], &std).unwrap();
        let (w1, w3) = (4.0, 0.5e-12);
        assert!((f[0] - (w1 * 0.25 + w3 * 0.6) / (w1 + w3)).abs() < 1e-15);
        assert!((t[1] - (w1 * 0.75 + w3 * 0.4) / (w1 + w3)).abs() < 1e-15);
        assert!(no_variance(0.0, 0.0) && !no_variance(0.0, 1e-300) && !no_variance(1.0, f64::NAN));
    }
}
