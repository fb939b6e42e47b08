//! Probabilists' Hermite polynomials: exact norms `n!` and Galerkin triple products (and, for
//! the tests, their values).

/// Probabilists' Hermite polynomial `He_n(x)` by the three-term recurrence.
///
/// Serves the tests: the reference the chaos's Hermite basis, norms and triple products are
/// checked against.
#[cfg(test)]
pub(crate) fn hermite_he(n: usize, x: f64) -> f64 {
    let (mut prev, mut cur) = (0.0, 1.0);
    for k in 0..n {
        let next = x * cur - k as f64 * prev;
        prev = cur;
        cur = next;
    }
    cur
}

/// `n!` as an integer while it fits in a `u128` (n <= 34).
fn factorial_u128(n: usize) -> Option<u128> {
    (1..=n as u128).try_fold(1u128, |acc, k| acc.checked_mul(k))
}

/// `n!` as `f64`: exact integer arithmetic up to 34!, then floating products
/// (infinite beyond 170!).
fn factorial_f64(n: usize) -> f64 {
    const EXACT: usize = 34;
    if n <= EXACT {
        return factorial_u128(n).map_or(f64::INFINITY, |v| v as f64);
    }
    let mut f = factorial_u128(EXACT).map_or(f64::INFINITY, |v| v as f64);
    for k in EXACT + 1..=n {
        f *= k as f64;
    }
    f
}

/// `E[He_n(Z)^2] = n!` for `Z ~ N(0, 1)` (exact up to 34!, correctly rounded
/// from the integer; then rounded products).
pub fn hermite_norm_sq(n: usize) -> f64 {
    factorial_f64(n)
}

/// Exact integer `i! j! k! / ((s-i)! (s-j)! (s-k)!)` as `u128`, if it fits.
fn triple_u128(i: usize, j: usize, a: usize, b: usize, k: usize) -> Option<u128> {
    // = C(i, b) * j! / a! * k!  with i = b + c, j = a + c, k = a + b.
    let mut binom: u128 = 1;
    for m in 0..b as u128 {
        // C(i, m+1) = C(i, m) (i - m) / (m + 1), exact at every step.
        binom = binom.checked_mul(i as u128 - m)? / (m + 1);
    }
    let mut falling: u128 = 1;
    for m in a + 1..=j {
        falling = falling.checked_mul(m as u128)?;
    }
    binom.checked_mul(falling)?.checked_mul(factorial_u128(k)?)
}

/// Galerkin triple product `E[He_i He_j He_k]`:
/// `i! j! k! / ((s-i)! (s-j)! (s-k)!)` when `i + j + k = 2s` is even and
/// `s >= i, j, k`, else 0. Computed in exact integer arithmetic when the value
/// fits in a `u128` (then correctly rounded to `f64`), else in floating point.
pub fn hermite_triple(i: usize, j: usize, k: usize) -> f64 {
    let total = i + j + k;
    if total % 2 == 1 {
        return 0.0;
    }
    let s = total / 2;
    if s < i || s < j || s < k {
        return 0.0;
    }
    let (a, b) = (s - i, s - j);
    if let Some(v) = triple_u128(i, j, a, b, k) {
        return v as f64;
    }
    let mut binom = 1.0;
    for m in 0..b {
        binom *= (i - m) as f64 / (m + 1) as f64;
    }
    let mut falling = 1.0;
    for m in a + 1..=j {
        falling *= m as f64;
    }
    binom * falling * factorial_f64(k)
}
