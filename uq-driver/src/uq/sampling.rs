//! Designs on the open unit cube: plain Monte Carlo and Latin hypercube.
//!
//! Point `i` of a design depends only on `(seed, i)` (and, for the Latin
//! hypercube, on `n` through the stratum permutations), never on the number
//! of threads: each point draws from its own stream [`rng::stream`]`(seed, i)`.
//! Map the coordinates to physical values with
//! [`Distribution::inverse_cdf`](crate::uq::distributions::Distribution::inverse_cdf).

use rayon::prelude::*;

use crate::uq::rng;

/// Largest value below 1 (`1 - 2^-53`).
const ONE_MINUS: f64 = 1.0 - f64::EPSILON / 2.0;

/// The `d` uniforms of Monte Carlo point `i`, from `stream(seed, i)` only.
fn mc_point(seed: u64, i: u64, d: usize) -> Vec<f64> {
    let mut r = rng::stream(seed, i);
    (0..d).map(|_| rng::uniform_open01(&mut r)).collect()
}

/// `n` Monte Carlo points of `d` independent uniforms, strictly inside (0, 1).
///
/// Point `i` is drawn only from `rng::stream(seed, i)`, so a design with more
/// points extends one with fewer (same first points) and the result does not
/// depend on the thread count (points are generated in parallel).
pub fn monte_carlo(n: usize, d: usize, seed: u64) -> Vec<Vec<f64>> {
    (0..n as u64)
        .into_par_iter()
        .map(|i| mc_point(seed, i, d))
        .collect()
}

/// Stream index reserved for the stratum permutation of dimension `dim`.
fn permutation_stream(dim: usize) -> u64 {
    u64::MAX - dim as u64
}

/// A uniformly random permutation of `0..n` (Fisher–Yates) from the stream
/// reserved for dimension `dim`.
fn permutation(seed: u64, dim: usize, n: usize) -> Vec<usize> {
    let mut r = rng::stream(seed, permutation_stream(dim));
    let mut p: Vec<usize> = (0..n).collect();
    for i in (1..n).rev() {
        let j = rng::uniform_below(&mut r, i as u64 + 1) as usize;
        p.swap(i, j);
    }
    p
}

/// `n` Latin-hypercube points in `d` dimensions, strictly inside (0, 1):
/// in every dimension each of the `n` strata `[k/n, (k+1)/n)` holds exactly
/// one point.
///
/// Point `i`, dimension `j` is `(perm_j[i] + u_ij) / n`, where `perm_j` is a
/// random permutation drawn from the stream reserved for the design,
/// `rng::stream(seed, u64::MAX - j)`, and the jitter `u_ij` comes from
/// `rng::stream(seed, i)`. The result is a function of `(n, d, seed)` only,
/// whatever the thread count.
pub fn latin_hypercube(n: usize, d: usize, seed: u64) -> Vec<Vec<f64>> {
    let perms: Vec<Vec<usize>> = (0..d)
        .into_par_iter()
        .map(|j| permutation(seed, j, n))
        .collect();
    let scale = 1.0 / n as f64;
    (0..n)
        .into_par_iter()
        .map(|i| {
            let jitter = mc_point(seed, i as u64, d);
            jitter
                .iter()
                .zip(&perms)
                .map(|(u, p)| {
                    let x = (p[i] as f64 + u) * scale;
                    x.clamp(f64::MIN_POSITIVE, ONE_MINUS)
                })
                .collect()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn in_open_unit(points: &[Vec<f64>]) -> bool {
        points.iter().flatten().all(|&x| x > 0.0 && x < 1.0)
    }

    fn column_mean(points: &[Vec<f64>], j: usize) -> f64 {
        points.iter().map(|p| p[j]).sum::<f64>() / points.len() as f64
    }

    #[test]
    fn monte_carlo_shape_range_and_means() {
        let n = 20_000;
        let pts = monte_carlo(n, 3, 11);
        assert_eq!(pts.len(), n);
        assert!(pts.iter().all(|p| p.len() == 3));
        assert!(in_open_unit(&pts));
        let tol = 5.0 * (1.0 / 12.0 / n as f64).sqrt();
        for j in 0..3 {
            assert!((column_mean(&pts, j) - 0.5).abs() < tol);
        }
    }

    #[test]
    fn monte_carlo_point_i_depends_only_on_seed_and_i() {
        let a = monte_carlo(50, 4, 7);
        let b = monte_carlo(200, 4, 7);
        assert_eq!(a[..], b[..50]);
        assert_eq!(a[17], mc_point(7, 17, 4));
        assert_ne!(a, monte_carlo(50, 4, 8));
    }

    #[test]
    fn designs_do_not_depend_on_the_thread_count() {
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let four = rayon::ThreadPoolBuilder::new()
            .num_threads(4)
            .build()
            .unwrap();
        let (m1, l1) = one.install(|| (monte_carlo(500, 3, 5), latin_hypercube(500, 3, 5)));
        let (m4, l4) = four.install(|| (monte_carlo(500, 3, 5), latin_hypercube(500, 3, 5)));
        assert_eq!(m1, m4);
        assert_eq!(l1, l4);
        // The sequential definition gives the same.
        let seq: Vec<Vec<f64>> = (0..500).map(|i| mc_point(5, i, 3)).collect();
        assert_eq!(m1, seq);
    }

    #[test]
    fn latin_hypercube_hits_every_stratum_once() {
        for (n, d) in [(1, 2), (2, 1), (10, 3), (1000, 5)] {
            let pts = latin_hypercube(n, d, 99);
            assert_eq!(pts.len(), n);
            assert!(in_open_unit(&pts));
            for j in 0..d {
                let mut hit = vec![0; n];
                for p in &pts {
                    hit[(p[j] * n as f64).floor() as usize] += 1;
                }
                assert!(hit.iter().all(|&h| h == 1), "n={n} dim {j}");
            }
        }
    }

    #[test]
    fn latin_hypercube_means_are_close_to_one_half() {
        let n = 2000;
        let pts = latin_hypercube(n, 4, 3);
        // Stratification makes the mean error O(1/n).
        for j in 0..4 {
            assert!((column_mean(&pts, j) - 0.5).abs() < 1.0 / n as f64);
        }
    }

    #[test]
    fn latin_hypercube_is_deterministic_and_seeds_differ() {
        assert_eq!(latin_hypercube(64, 3, 1), latin_hypercube(64, 3, 1));
        assert_ne!(latin_hypercube(64, 3, 1), latin_hypercube(64, 3, 2));
        // Dimensions use different permutations.
        let p = latin_hypercube(64, 2, 1);
        let k0: Vec<usize> = p.iter().map(|x| (x[0] * 64.0) as usize).collect();
        let k1: Vec<usize> = p.iter().map(|x| (x[1] * 64.0) as usize).collect();
        assert_ne!(k0, k1);
    }

    #[test]
    fn empty_designs() {
        assert!(monte_carlo(0, 3, 1).is_empty());
        assert!(latin_hypercube(0, 3, 1).is_empty());
        assert!(latin_hypercube(5, 0, 1).iter().all(|p| p.is_empty()));
    }
}
