//! A rigid contact table made fit for spline interpolation: a short moving average in y.
//!
//! A table of one rigid contact point per wheel has jumps: where another local minimum of the
//! gap between wheel and rail becomes the lowest, the contact point jumps across the profile,
//! and the contact angle δ, the rolling radius r and the contact position aw jump with it
//! (S1002 on UIC60 at 1:40: across the nearly conformal tread at |y| = 0.22 mm, to the flange
//! root at 5.0 mm and onto the flange flank at 6.3 mm). A natural cubic spline through a jump
//! overshoots on both sides (by some 10 % of the jump, the error shrinking by 2 − √3 per row),
//! which puts contact angles and radii into the dynamics that no wheel has.
//!
//! An elastic contact patch does not jump: while the gaps at two candidate points differ by
//! less than the elastic approach (q0, some 0.07 mm), both carry load, and the resultant moves
//! from one to the other over a range of wheelset displacements. [`smoothed`] stands in for
//! that with a moving average of every column over a short range of y: three passes of a
//! centred box of `2m + 1` rows (m = the half-width over the step, rounded), i.e. a bell-shaped
//! kernel (a discrete quadratic B-spline) spanning `6m + 1` rows. Each smoothed value is a
//! convex combination of the rows around it, so it stays within their range (positive
//! semi-axes, radii and penetrations stay positive), and the jumps become smooth S-shaped
//! transitions through which the spline does not overshoot. Near the ends of the table the box
//! shrinks symmetrically (a centred window keeps linear trends unchanged); the first and last
//! rows stay as they are.
//!
//! The centred kernel keeps the table's symmetry (the right wheel reads the row at −y).

use super::table::{ContactTable, TableRow};

/// `table` with every column but y averaged over a bell-shaped window of three passes of a
/// centred box of half-width `half_width` (m; rounded to whole rows of the table's step; 0
/// returns the table unchanged). See the module documentation.
pub fn smoothed(table: &ContactTable, half_width: f64) -> ContactTable {
    let rows = table.rows();
    let n = rows.len();
    let step = (rows[n - 1].y - rows[0].y) / (n - 1) as f64;
    let m = (half_width / step).round().max(0.0) as usize;
    if m == 0 {
        return table.clone();
    }
    let mut values: Vec<[f64; 12]> = rows.iter().map(TableRow::values).collect();
    for _ in 0..3 {
        values = box_pass(&values, m);
    }
    let out = values
        .iter()
        .zip(rows)
        .map(|(v, r)| {
            let mut v = *v;
            v[0] = r.y;
            TableRow::from_values(v)
        })
        .collect();
    ContactTable::from_rows(out).expect("convex combinations of valid rows are valid")
}

/// One pass of a centred box of `2m + 1` rows, shrunk symmetrically near the ends (row i
/// averages rows i − k ..= i + k with k = min(m, i, n − 1 − i)), by running sums.
fn box_pass(values: &[[f64; 12]], m: usize) -> Vec<[f64; 12]> {
    let n = values.len();
    // prefix[i] = sum of rows 0..i.
    let mut prefix = vec![[0.0; 12]; n + 1];
    for i in 0..n {
        for c in 0..12 {
            prefix[i + 1][c] = prefix[i][c] + values[i][c];
        }
    }
    (0..n)
        .map(|i| {
            let k = m.min(i).min(n - 1 - i);
            let (lo, hi) = (i - k, i + k + 1);
            let w = (hi - lo) as f64;
            std::array::from_fn(|c| {
                // The running sums lose a little to rounding: clamp to the window's range, so
                // that the result is a convex combination exactly as the module promises.
                let mean = (prefix[hi][c] - prefix[lo][c]) / w;
                let (mut a, mut b) = (f64::INFINITY, f64::NEG_INFINITY);
                for v in &values[lo..hi] {
                    a = a.min(v[c]);
                    b = b.max(v[c]);
                }
                mean.clamp(a, b)
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::table::ContactSpline;

    fn row(y: f64, delta: f64, r: f64) -> TableRow {
        TableRow {
            y,
            n0: 66_600.0,
            delta,
            a: 6e-3,
            b: 4e-3,
            aw: 0.75,
            r,
            c11: 4.0,
            c22: 3.5,
            c23: 1.5,
            zc: 0.0,
            q0: 1e-4,
        }
    }

    /// A table with a jump of δ and r at y = 0.5 mm and linear trends on either side.
    fn stepped() -> ContactTable {
        let rows = (0..=400)
            .map(|i| {
                let y = -2e-3 + i as f64 * 1e-5;
                let jump = if y > 0.5e-3 { 1.0 } else { 0.0 };
                row(
                    y,
                    0.02 + 10.0 * y + 0.9 * jump,
                    0.425 + 0.05 * y + 0.01 * jump,
                )
            })
            .collect();
        ContactTable::from_rows(rows).unwrap()
    }

    #[test]
    fn linear_columns_are_unchanged_and_the_ends_are_kept() {
        let rows: Vec<TableRow> = (0..=300)
            .map(|i| {
                let y = -1.5e-3 + i as f64 * 1e-5;
                row(y, 0.02 + 7.0 * y, 0.425 + 0.1 * y)
            })
            .collect();
        let t = ContactTable::from_rows(rows).unwrap();
        let s = smoothed(&t, 0.2e-3);
        for (a, b) in t.rows().iter().zip(s.rows()) {
            assert_eq!(a.y, b.y);
            assert!((a.delta - b.delta).abs() < 1e-14, "{} {}", a.delta, b.delta);
            assert!((a.r - b.r).abs() < 1e-14);
            assert_eq!(a.n0, b.n0);
        }
        assert_eq!(s.rows()[0], t.rows()[0]);
        assert_eq!(s.rows()[300], t.rows()[300]);
        assert_eq!(smoothed(&t, 0.0), t);
    }

    #[test]
    fn a_jump_becomes_a_monotone_transition_over_the_kernels_width() {
        let t = stepped();
        let s = smoothed(&t, 0.1e-3);
        // Three boxes of 21 rows: the kernel spans 61 rows, 0.3 mm either side of a row.
        let delta = |tab: &ContactTable, y: f64| {
            tab.rows()
                .iter()
                .find(|r| (r.y - y).abs() < 5e-9)
                .unwrap()
                .delta
        };
        // Outside the kernel's reach the linear trend is untouched.
        for y in [0.19e-3, 0.81e-3] {
            assert!((delta(&s, y) - delta(&t, y)).abs() < 1e-12, "{y}");
        }
        // Inside it, monotone: the jump is spread, not removed.
        let mid: Vec<f64> = s
            .rows()
            .iter()
            .filter(|r| (0.2e-3..0.8e-3).contains(&r.y))
            .map(|r| r.delta)
            .collect();
        assert!(mid.windows(2).all(|w| w[1] >= w[0]));
        // Halfway up at the jump (the kernel is symmetric).
        let at = delta(&s, 0.5e-3);
        assert!((at - (0.02 + 10.0 * 0.5e-3 + 0.45)).abs() < 0.02, "{at}");
    }

    /// Largest excursion of the spline through `t` outside the range of the four rows around
    /// each interval (column `col`), sampled at 9 points per interval.
    fn overshoot(t: &ContactTable, col: usize) -> f64 {
        let sp = ContactSpline::new(t);
        let rows = t.rows();
        let mut worst = 0.0f64;
        for i in 1..rows.len() - 2 {
            let near = &rows[i - 1..=i + 2];
            let lo = near
                .iter()
                .map(|r| r.values()[col])
                .fold(f64::INFINITY, f64::min);
            let hi = near
                .iter()
                .map(|r| r.values()[col])
                .fold(f64::NEG_INFINITY, f64::max);
            for k in 1..10 {
                let y = rows[i].y + (rows[i + 1].y - rows[i].y) * k as f64 / 10.0;
                let v = sp.left(y).unwrap().values()[col];
                worst = worst.max(lo - v).max(v - hi);
            }
        }
        worst
    }

    #[test]
    fn the_spline_overshoots_a_jump_but_not_its_smoothed_transition() {
        let t = stepped();
        // δ jumps by 0.9 rad: the spline through the raw rows overshoots by some 10 %.
        assert!(overshoot(&t, 2) > 0.05, "{}", overshoot(&t, 2));
        let s = smoothed(&t, 0.1e-3);
        assert!(overshoot(&s, 2) < 1e-6 * 0.9, "{}", overshoot(&s, 2));
        assert!(overshoot(&s, 6) < 1e-6 * 0.01, "{}", overshoot(&s, 6));
    }
}
