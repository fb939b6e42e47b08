//! The bootstrap replicates of up to [`LANES`] outputs at once (one SIMD lane each), every
//! sum in the order of [`estimate_rows`](super::estimate_rows) so the numbers are the same
//! bit for bit.
//!
//! Speed: a few replicates are summed in lock step (independent chains of additions, so
//! the additions' latency is hidden), and the loop is compiled for the baseline and for
//! wider vector units, chosen at run time (`multiversion`). Every operation is an IEEE
//! addition, subtraction, multiplication or division of two `f64` (Rust never contracts
//! `a * b + c` into a fused multiply-add), so every version gives the same bits.

use std::ops::Range;

use multiversion::multiversion;

/// Outputs evaluated together (one lane each).
pub(super) const LANES: usize = 4;

/// Replicates summed in lock step.
const IN_STEP: usize = 2;

/// Sums per pass over the rows (their accumulators stay in registers).
const FIELDS_PER_PASS: usize = 3;

/// The per-row summands of [`estimate_rows`](super::estimate_rows) for up to `LANES`
/// outputs (one lane each, unused lanes hold zeros), computed by the same operations, in one
/// table per pass over the rows (row-major, the lanes innermost): the sums
/// `f(A)_j + f(B)_j` with the first statistics' summands, then the other statistics'
/// summands a few at a time, then `f(A)_j`, `f(B)_j` for the variance. The statistics are
/// `f(B)_j (f(AB_i)_j - f(A)_j)` for each `i`, then `(f(A)_j - f(AB_i)_j)^2` for each `i`.
pub(super) struct Lanes {
    n: usize,
    d: usize,
    /// Per pass: the first statistic, the number of statistics, the table.
    passes: Vec<(usize, usize, Vec<[f64; LANES]>)>,
    /// `f(A)_j`, `f(B)_j`.
    ab: Vec<[f64; LANES]>,
}

/// First-order then total estimates of one replicate, per lane.
type Stats = Vec<[f64; LANES]>;

impl Lanes {
    /// The tables of `columns` (at most [`LANES`], each `N (d + 2)` values).
    pub(super) fn new<V: AsRef<[f64]>>(columns: &[V], n: usize, d: usize) -> Lanes {
        // Pass 0: the sum and statistics 0..2; then statistics k..k + 3.
        let mut bounds = vec![(0, 2.min(2 * d))];
        let mut k = 2.min(2 * d);
        while k < 2 * d {
            let len = (2 * d - k).min(FIELDS_PER_PASS);
            bounds.push((k, len));
            k += len;
        }
        let mut passes: Vec<(usize, usize, Vec<[f64; LANES]>)> = bounds
            .iter()
            .enumerate()
            .map(|(p, &(k, len))| {
                let width = len + usize::from(p == 0);
                (k, len, vec![[0.0; LANES]; n * width])
            })
            .collect();
        let mut ab = vec![[0.0; LANES]; 2 * n];
        let mut stat = vec![0.0; 2 * d];
        for (lane, col) in columns.iter().enumerate() {
            let values = col.as_ref();
            let (fa, fb) = (&values[..n], &values[n..2 * n]);
            for j in 0..n {
                for i in 0..d {
                    let fab = values[(2 + i) * n + j];
                    stat[i] = fb[j] * (fab - fa[j]);
                    stat[d + i] = (fa[j] - fab).powi(2);
                }
                for (p, (k, len, table)) in passes.iter_mut().enumerate() {
                    let width = *len + usize::from(p == 0);
                    let row = &mut table[j * width..(j + 1) * width];
                    let mut f = 0;
                    if p == 0 {
                        row[0][lane] = fa[j] + fb[j];
                        f = 1;
                    }
                    for (r, v) in row[f..].iter_mut().zip(&stat[*k..*k + *len]) {
                        r[lane] = *v;
                    }
                }
                ab[2 * j][lane] = fa[j];
                ab[2 * j + 1][lane] = fb[j];
            }
        }
        Lanes { n, d, passes, ab }
    }

    /// The estimates of resamples `ks` (the rows of resample `ks.start + b` at
    /// `rows[b n..(b + 1) n]`) in every lane: statistic `s` of resample `k` into
    /// `reps[lane][k + resamples * s]`.
    pub(super) fn replicates(
        &self,
        rows: &[usize],
        ks: Range<usize>,
        resamples: usize,
        reps: &mut [Vec<f64>],
    ) {
        replicates(self, rows, ks, resamples, reps);
    }

    /// Sums of the `K` fields of `table` over the rows of each of `R` resamples, field `k`
    /// from `init[k]`, in row order, every lane and resample on its own.
    #[inline(always)]
    fn sums<const K: usize, const R: usize>(
        table: &[[f64; LANES]],
        rows: [&[usize]; R],
        init: [f64; K],
    ) -> [[[f64; LANES]; K]; R] {
        let mut acc = [init.map(|v| [v; LANES]); R];
        let n = rows[0].len();
        let rows = rows.map(|r| &r[..n]);
        for t in 0..n {
            for (acc, rows) in acc.iter_mut().zip(&rows) {
                let j = rows[t];
                let fields: &[[f64; LANES]; K] = table[j * K..(j + 1) * K]
                    .try_into()
                    .expect("K fields per row");
                for (a, v) in acc.iter_mut().zip(fields) {
                    for (a, v) in a.iter_mut().zip(v) {
                        *a += *v;
                    }
                }
            }
        }
        acc
    }

    /// `sum_j (f(A)_j - mean)^2 + (f(B)_j - mean)^2` over the rows of each resample, from
    /// -0.0 (as `Sum`).
    #[inline(always)]
    fn squares<const R: usize>(
        &self,
        rows: [&[usize]; R],
        mean: [[f64; LANES]; R],
    ) -> [[f64; LANES]; R] {
        let mut acc = [[-0.0f64; LANES]; R];
        let n = rows[0].len();
        let rows = rows.map(|r| &r[..n]);
        for t in 0..n {
            for ((acc, rows), mean) in acc.iter_mut().zip(&rows).zip(&mean) {
                let j = rows[t];
                let [a, b]: &[[f64; LANES]; 2] = self.ab[2 * j..2 * j + 2]
                    .try_into()
                    .expect("two values per row");
                for l in 0..LANES {
                    acc[l] += (a[l] - mean[l]).powi(2) + (b[l] - mean[l]).powi(2);
                }
            }
        }
        acc
    }

    /// The indices of `R` resamples in every lane, into `stats` (the arithmetic of
    /// `estimate_rows`, lane by lane).
    #[inline(always)]
    fn replicate<const R: usize>(&self, rows: [&[usize]; R], stats: &mut [Stats]) {
        let d = self.d;
        let m = rows[0].len() as f64;
        // The sum for the mean (`Sum` of f64 folds from -0.0), the statistics' sums from 0.
        let mut sum = [[0.0; LANES]; R];
        for (p, (k, len, table)) in self.passes.iter().enumerate() {
            let (k, len) = (*k, *len);
            let mut put = |q: usize, v: &[[f64; LANES]]| {
                stats[q][k..k + len].copy_from_slice(v);
            };
            match (p, len) {
                (0, 0) => {
                    let r = Self::sums::<1, R>(table, rows, [-0.0]);
                    sum = r.map(|[s]| s);
                }
                (0, _) => {
                    let r = Self::sums::<3, R>(table, rows, [-0.0, 0.0, 0.0]);
                    for (q, [s, v0, v1]) in r.into_iter().enumerate() {
                        sum[q] = s;
                        put(q, &[v0, v1]);
                    }
                }
                (_, 1) => {
                    let r = Self::sums::<1, R>(table, rows, [0.0]);
                    r.iter().enumerate().for_each(|(q, v)| put(q, v));
                }
                (_, 2) => {
                    let r = Self::sums::<2, R>(table, rows, [0.0; 2]);
                    r.iter().enumerate().for_each(|(q, v)| put(q, v));
                }
                _ => {
                    let r = Self::sums::<3, R>(table, rows, [0.0; 3]);
                    r.iter().enumerate().for_each(|(q, v)| put(q, v));
                }
            }
        }
        let mean = sum.map(|s| s.map(|a| a / (2.0 * m)));
        let squares = self.squares(rows, mean);
        for (stats, squares) in stats.iter_mut().zip(squares) {
            let variance = squares.map(|v| v / (2.0 * m - 1.0));
            for (i, s) in stats.iter_mut().enumerate() {
                for l in 0..LANES {
                    s[l] = if i < d {
                        s[l] / m / variance[l]
                    } else {
                        s[l] / (2.0 * m) / variance[l]
                    };
                }
            }
        }
    }
}

/// [`Lanes::replicates`], compiled for the baseline and for wider vector units.
#[multiversion(targets("x86_64+avx2+avx+sse4.2"))]
fn replicates(
    lanes: &Lanes,
    rows: &[usize],
    ks: Range<usize>,
    resamples: usize,
    reps: &mut [Vec<f64>],
) {
    let n = lanes.n;
    let mut stats: Vec<Stats> = vec![vec![[0.0; LANES]; 2 * lanes.d]; IN_STEP];
    let mut b = 0;
    while b < ks.len() {
        let step = if b + IN_STEP <= ks.len() { IN_STEP } else { 1 };
        if step == IN_STEP {
            let rs: [&[usize]; IN_STEP] =
                std::array::from_fn(|q| &rows[(b + q) * n..(b + q + 1) * n]);
            lanes.replicate(rs, &mut stats);
        } else {
            lanes.replicate([&rows[b * n..(b + 1) * n]], &mut stats[..1]);
        }
        for (q, stats) in stats[..step].iter().enumerate() {
            let k = ks.start + b + q;
            for (lane, r) in reps.iter_mut().enumerate() {
                for (s, acc) in stats.iter().enumerate() {
                    r[k + resamples * s] = acc[lane];
                }
            }
        }
        b += step;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Deterministic, irregular values (with a large mean in one lane).
    fn columns(n: usize, d: usize, lanes: usize) -> Vec<Vec<f64>> {
        (0..lanes)
            .map(|c| {
                (0..n * (d + 2))
                    .map(|k| {
                        let x = (k as f64 * 0.618_033_988_7 + c as f64 * 0.3).fract();
                        (1.0 + c as f64) * (6.0 * x).sin() + 1e4 * f64::from(c == 2 && k % 3 == 0)
                    })
                    .collect()
            })
            .collect()
    }

    /// Resample rows from a simple generator (any rows in `0..n` will do here).
    fn rows(n: usize, resamples: usize) -> Vec<usize> {
        let mut s = 12345u64;
        (0..n * resamples)
            .map(|_| {
                s = s.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
                ((s >> 33) % n as u64) as usize
            })
            .collect()
    }

    #[test]
    fn resamples_in_lock_step_and_wider_vectors_give_the_baseline_bits() {
        // Regression: the replicates are summed two at a time and dispatched to a version
        // compiled for wider vector units. Each must give, bit for bit, what one resample at
        // a time in the baseline build gives, for every pass layout (d = 1: no second pass;
        // d = 2: a pass of two; d = 4: passes of three and three) and an odd resample count.
        for (n, d, resamples) in [(37, 1, 5), (64, 2, 7), (29, 4, 3)] {
            let cols = columns(n, d, 3);
            let lanes = Lanes::new(&cols, n, d);
            let rows = rows(n, resamples);
            let mut got = vec![vec![0.0; 2 * d * resamples]; 3];
            lanes.replicates(&rows, 0..resamples, resamples, &mut got);
            let mut stats = vec![vec![[0.0; LANES]; 2 * d]];
            for k in 0..resamples {
                lanes.replicate([&rows[k * n..(k + 1) * n]], &mut stats);
                for (lane, g) in got.iter().enumerate() {
                    for (s, acc) in stats[0].iter().enumerate() {
                        assert_eq!(
                            g[k + resamples * s].to_bits(),
                            acc[lane].to_bits(),
                            "n {n}, d {d}, resample {k}, statistic {s}, lane {lane}"
                        );
                    }
                }
            }
        }
    }
}
