//! Linear combinations of columns for the LARS path, summed in the same order and with
//! the same roundings as nalgebra's matrix-vector product and `axpy` (so the path stays
//! the same, bit for bit), but a block of rows at a time in registers instead of one
//! pass over the output per column. The products and the Gram-Schmidt step are
//! also compiled for AVX2 and AVX-512 and chosen at run time: the same operations lane by
//! lane (no fused multiply-add), so the same bits on every machine.

use multiversion::multiversion;
use nalgebra::DMatrix;

/// How the sum starts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Start {
    /// With the first term, as nalgebra's `gemv` (`y = a_0 v_0`, then `y = a_j v_j + y`).
    FirstTerm,
    /// With zero, as repeated `axpy` into a zeroed vector (`y = 0 + a_0 v_0 + ...`).
    Zero,
}

/// `out = sum_t coef_t * column_t` over the terms, each column of `out.len()` entries,
/// in term order; `out` is zero when there are no terms.
#[inline(always)]
pub(super) fn combine<'a>(
    out: &mut [f64],
    start: Start,
    terms: impl Iterator<Item = (&'a [f64], f64)> + Clone,
) {
    // Blocks of 16 rows keep 8 independent sums in flight, then 8, 4, 2 and 1.
    let i = blocks::<16, _>(out, 0, start, &terms);
    let i = blocks::<8, _>(out, i, start, &terms);
    let i = blocks::<4, _>(out, i, start, &terms);
    let i = blocks::<2, _>(out, i, start, &terms);
    blocks::<1, _>(out, i, start, &terms);
}

/// [`combine`] on the rows from `i` on, `B` at a time while `B` remain; the next row.
#[inline(always)]
fn blocks<'a, const B: usize, I>(out: &mut [f64], mut i: usize, start: Start, terms: &I) -> usize
where
    I: Iterator<Item = (&'a [f64], f64)> + Clone,
{
    while i + B <= out.len() {
        let mut acc = [0.0; B];
        let mut terms = terms.clone();
        if start == Start::FirstTerm {
            if let Some((col, w)) = terms.next() {
                let col: &[f64; B] = col[i..i + B].try_into().expect("block");
                for t in 0..B {
                    acc[t] = col[t] * w;
                }
            }
        }
        for (col, w) in terms {
            let col: &[f64; B] = col[i..i + B].try_into().expect("block");
            for t in 0..B {
                acc[t] += col[t] * w;
            }
        }
        out[i..i + B].copy_from_slice(&acc);
        i += B;
    }
    i
}

/// `out = sum_i coef_i x_{cols_i}` (`x` column-major with `out.len()` rows), as repeated
/// nalgebra `axpy` into a zeroed vector; compiled as [`mat_vec_slices`].
#[multiversion(targets("x86_64+avx512f+avx512vl+avx2+avx+sse4.2", "x86_64+avx2+avx+sse4.2"))]
pub(super) fn combine_columns(x: &[f64], cols: &[usize], coef: &[f64], out: &mut [f64]) {
    let n = out.len();
    let terms = cols
        .iter()
        .zip(coef)
        .map(|(&j, &w)| (&x[j * n..(j + 1) * n], w));
    combine(out, Start::Zero, terms);
}

/// `out = a v` (`a` column-major), as `&a * &v` in nalgebra.
pub(super) fn mat_vec(a: &DMatrix<f64>, v: &[f64], out: &mut [f64]) {
    let m = a.nrows();
    debug_assert_eq!((a.ncols(), out.len()), (v.len(), m));
    if m == 0 {
        return;
    }
    mat_vec_slices(a.as_slice(), m, v, out);
}

/// [`mat_vec`] on the column-major entries, compiled for the baseline and for wider vector
/// units, chosen at run time (the same sums, so the same bits, in every version: no fused
/// multiply-add).
#[multiversion(targets("x86_64+avx512f+avx512vl+avx2+avx+sse4.2", "x86_64+avx2+avx+sse4.2"))]
fn mat_vec_slices(a: &[f64], m: usize, v: &[f64], out: &mut [f64]) {
    let cols = a.chunks_exact(m).zip(v.iter().copied());
    combine(out, Start::FirstTerm, cols);
}

/// `a . b` summed as nalgebra's `dot`: eight running sums over the rows in blocks of
/// eight, combined as `((s0 + s4) + (s1 + s5)) ...`, then the remaining rows one by one.
#[multiversion(targets("x86_64+avx512f+avx512vl+avx2+avx+sse4.2", "x86_64+avx2+avx+sse4.2"))]
pub(super) fn dot(a: &[f64], b: &[f64]) -> f64 {
    debug_assert_eq!(a.len(), b.len());
    let mut acc = [0.0; 8];
    let blocks = a.len() / 8 * 8;
    for (x, y) in a[..blocks].chunks_exact(8).zip(b[..blocks].chunks_exact(8)) {
        for t in 0..8 {
            acc[t] += x[t] * y[t];
        }
    }
    finish(acc, &a[blocks..], &b[blocks..])
}

/// nalgebra's way of ending a dot product: the eight sums, then the remaining products.
#[inline(always)]
fn finish(acc: [f64; 8], a: &[f64], b: &[f64]) -> f64 {
    let mut res = 0.0;
    res += acc[0] + acc[4];
    res += acc[1] + acc[5];
    res += acc[2] + acc[6];
    res += acc[3] + acc[7];
    for (x, y) in a.iter().zip(b) {
        res += x * y;
    }
    res
}

/// `v = alpha x + v` (as nalgebra's `axpy(alpha, x, 1)`), then `next . v` (as [`dot`]),
/// in one pass over `v`.
#[multiversion(targets("x86_64+avx512f+avx512vl+avx2+avx+sse4.2", "x86_64+avx2+avx+sse4.2"))]
pub(super) fn axpy_dot(v: &mut [f64], alpha: f64, x: &[f64], next: &[f64]) -> f64 {
    debug_assert!(v.len() == x.len() && v.len() == next.len());
    let mut acc = [0.0; 8];
    let blocks = v.len() / 8 * 8;
    let (vb, vt) = v.split_at_mut(blocks);
    for ((vc, xc), nc) in vb
        .chunks_exact_mut(8)
        .zip(x[..blocks].chunks_exact(8))
        .zip(next[..blocks].chunks_exact(8))
    {
        for t in 0..8 {
            vc[t] += alpha * xc[t];
            acc[t] += nc[t] * vc[t];
        }
    }
    for (vi, &xi) in vt.iter_mut().zip(&x[blocks..]) {
        *vi += alpha * xi;
    }
    finish(acc, &next[blocks..], vt)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::DVector;

    /// Awkward numbers: signed zeros, values of many magnitudes, sums that cancel.
    fn value(i: usize, j: usize) -> f64 {
        let v = ((i * 7919 + j * 104_729) % 1000) as f64 / 7.0 - 70.0;
        match (i + 3 * j) % 11 {
            0 => 0.0,
            1 => -0.0,
            2 => v * 1e-12,
            3 => v * 1e9,
            _ => v.sin() / 3.0,
        }
    }

    #[test]
    fn the_blocked_product_equals_nalgebras_bit_for_bit() {
        for (m, n) in [(0, 3), (3, 0), (1, 1), (7, 5), (8, 9), (17, 30), (90, 100)] {
            let a = DMatrix::from_fn(m, n, value);
            let v = DVector::from_fn(n, |j, _| value(j + 5, 2 * j));
            let want = &a * &v;
            let mut got = vec![f64::NAN; m];
            mat_vec(&a, v.as_slice(), &mut got);
            for (g, w) in got.iter().zip(want.iter()) {
                assert_eq!(g.to_bits(), w.to_bits(), "{m} x {n}");
            }
        }
    }

    #[test]
    fn the_fused_axpy_and_dot_equal_nalgebras_bit_for_bit() {
        for n in [0, 1, 7, 8, 9, 16, 100, 103] {
            let x = DVector::from_fn(n, |i, _| value(i, 1));
            let next = DVector::from_fn(n, |i, _| value(i + 3, 7));
            let v0 = DVector::from_fn(n, |i, _| value(2 * i, 5));
            assert_eq!(
                dot(x.as_slice(), v0.as_slice()).to_bits(),
                x.dot(&v0).to_bits()
            );
            let alpha = -value(4, 4) - 0.3;
            let mut want = v0.clone();
            want.axpy(alpha, &x, 1.0);
            let want_dot = next.dot(&want);
            let mut got = v0.clone();
            let got_dot = axpy_dot(got.as_mut_slice(), alpha, x.as_slice(), next.as_slice());
            assert_eq!(got_dot.to_bits(), want_dot.to_bits(), "{n}");
            for (g, w) in got.iter().zip(want.iter()) {
                assert_eq!(g.to_bits(), w.to_bits(), "{n}");
            }
        }
    }

    #[test]
    fn the_blocked_combination_equals_repeated_axpy_bit_for_bit() {
        for (n, k) in [(1, 1), (5, 0), (9, 4), (100, 37)] {
            let x = DMatrix::from_fn(n, 2 * k + 1, value);
            let picks: Vec<(usize, f64)> = (0..k).map(|i| (2 * i + 1, value(i, 3))).collect();
            let mut want = DVector::<f64>::zeros(n);
            for &(j, w) in &picks {
                want.axpy(w, &x.column(j), 1.0);
            }
            let mut got = vec![f64::NAN; n];
            let terms = picks
                .iter()
                .map(|&(j, w)| (&x.as_slice()[j * n..(j + 1) * n], w));
            combine(&mut got, Start::Zero, terms);
            for (g, w) in got.iter().zip(want.iter()) {
                assert_eq!(g.to_bits(), w.to_bits(), "{n} x {k}");
            }
            let (cols, coef): (Vec<usize>, Vec<f64>) = picks.iter().copied().unzip();
            let mut by_cols = vec![f64::NAN; n];
            combine_columns(x.as_slice(), &cols, &coef, &mut by_cols);
            let bits = |v: &[f64]| v.iter().map(|e| e.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&by_cols), bits(&got), "{n} x {k}");
        }
    }
}
