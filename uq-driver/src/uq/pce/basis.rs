//! Multi-index sets and the multivariate orthonormal (Askey) basis over them.
//!
//! A multi-index `alpha = (alpha_1, ..., alpha_d)` names the basis function
//! `Psi_alpha(t) = prod_i p^(i)_{alpha_i}(t_i)`, where `p^(i)` is the orthonormal family
//! of input `i` on its germ (see [`super::askey`]). The basis is orthonormal for the
//! product germ measure, so a chaos `sum_alpha c_alpha Psi_alpha` has mean `c_0`,
//! variance `sum_{alpha != 0} c_alpha^2`, and Sobol' indices by summing squared
//! coefficients (see [`ChaosStats`]).

use std::collections::HashMap;

use nalgebra::DMatrix;

use super::askey::{AskeyError, Family};

/// Errors of multi-index sets and bases.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum BasisError {
    /// A multi-index of the wrong length.
    #[error("multi-index {index:?} has {got} entries, the set has dimension {dim}")]
    WrongLength {
        /// The multi-index.
        index: Vec<usize>,
        /// Its length.
        got: usize,
        /// Expected dimension.
        dim: usize,
    },
    /// A multi-index appears twice.
    #[error("multi-index {0:?} appears twice")]
    Duplicate(Vec<usize>),
    /// The q-norm is outside (0, 1].
    #[error("the hyperbolic truncation needs 0 < q <= 1 (got {0})")]
    BadQ(f64),
    /// The families do not match the dimension.
    #[error("{families} families for a {dim}-dimensional multi-index set")]
    FamilyCount {
        /// Number of families.
        families: usize,
        /// Dimension of the set.
        dim: usize,
    },
    /// A family has invalid parameters.
    #[error(transparent)]
    Family(#[from] AskeyError),
    /// The set would be too large.
    #[error("the multi-index set would have more than {0} terms")]
    TooLarge(usize),
}

/// Largest number of terms of a generated multi-index set.
pub const MAX_TERMS: usize = 5_000_000;

/// An ordered set of distinct multi-indices of one dimension.
#[derive(Clone, Debug, PartialEq)]
pub struct MultiIndexSet {
    dim: usize,
    indices: Vec<Vec<usize>>,
    lookup: HashMap<Vec<usize>, usize>,
}

impl MultiIndexSet {
    /// A set from explicit multi-indices (kept in the given order).
    pub fn from_indices(dim: usize, indices: Vec<Vec<usize>>) -> Result<Self, BasisError> {
        let mut lookup = HashMap::with_capacity(indices.len());
        for (k, a) in indices.iter().enumerate() {
            if a.len() != dim {
                return Err(BasisError::WrongLength {
                    index: a.clone(),
                    got: a.len(),
                    dim,
                });
            }
            if lookup.insert(a.clone(), k).is_some() {
                return Err(BasisError::Duplicate(a.clone()));
            }
        }
        Ok(MultiIndexSet {
            dim,
            indices,
            lookup,
        })
    }

    /// All `alpha` with `|alpha|_1 <= order`, graded (by total degree, then
    /// lexicographically decreasing), the constant first.
    pub fn total_degree(dim: usize, order: usize) -> Result<Self, BasisError> {
        Self::hyperbolic(dim, order, 1.0)
    }

    /// Terms of [`MultiIndexSet::hyperbolic`] counted without building the set: over the
    /// non-increasing lists of non-zero degrees within the bound, the ways of placing them
    /// among the dimensions. `q = 1` gives `C(dim + order, order)`. The count stops as soon
    /// as it passes `limit` (it then returns a value above `limit`), so that it takes at most
    /// about `limit` steps whatever the order.
    pub fn hyperbolic_count_upto(dim: usize, order: usize, q: f64, limit: f64) -> f64 {
        let bound = (order as f64).powf(q) * (1.0 + 1e-12) + 1e-12;
        struct Counter {
            dim: usize,
            q: f64,
            limit: f64,
            total: f64,
        }
        impl Counter {
            /// Adds the list as it is (`ways` placements), then the longer lists whose next
            /// degree is at most `max` and fits in `budget`.
            fn count(&mut self, max: usize, budget: f64, placed: usize, ways: f64) {
                self.total += ways;
                if placed == self.dim || self.total > self.limit {
                    return;
                }
                for v in 1..=max {
                    let cost = (v as f64).powf(self.q);
                    if cost > budget {
                        break; // larger degrees cost more
                    }
                    // `k` copies of degree `v` (their order among themselves does not count).
                    let mut w = ways;
                    let mut left = budget;
                    for k in 1..=(self.dim - placed) {
                        left -= cost;
                        if left < 0.0 {
                            break;
                        }
                        w *= (self.dim - placed - k + 1) as f64 / k as f64;
                        self.count(v - 1, left, placed + k, w);
                        if self.total > self.limit {
                            return;
                        }
                    }
                }
            }
        }
        let mut c = Counter {
            dim,
            q,
            limit,
            total: 0.0,
        };
        c.count(order, bound, 0, 1.0);
        c.total
    }

    /// Hyperbolic truncation: all `alpha` with `(sum_i alpha_i^q)^(1/q) <= order`,
    /// `0 < q <= 1` (`q = 1` is the total-degree set; smaller `q` drops high-order
    /// interactions). Graded order as in [`MultiIndexSet::total_degree`].
    pub fn hyperbolic(dim: usize, order: usize, q: f64) -> Result<Self, BasisError> {
        if !(q > 0.0 && q <= 1.0) {
            return Err(BasisError::BadQ(q));
        }
        // Counted first: a set over the limit is refused before it is built (30 inputs
        // at order 7 took 2.3 s and 1.4 GB to reach the limit by enumeration).
        if Self::hyperbolic_count_upto(dim, order, q, MAX_TERMS as f64) > MAX_TERMS as f64 {
            return Err(BasisError::TooLarge(MAX_TERMS));
        }
        let bound = (order as f64).powf(q) * (1.0 + 1e-12) + 1e-12;
        // The branches that cannot stay within the bound are cut (see `compositions`); the
        // test of each index is the one of the whole enumeration, so the same set in the
        // same order.
        let cost: Vec<f64> = (0..=order).map(|v| (v as f64).powf(q)).collect();
        let cut = Cut {
            cost: &cost,
            bound: bound * (1.0 + 1e-9) + 1e-9,
        };
        let mut out = Vec::new();
        for deg in 0..=order {
            let mut cur = vec![0; dim];
            compositions(dim, deg, 0, &mut cur, &cut, 0.0, &mut |a| {
                let s: f64 = a.iter().map(|&x| (x as f64).powf(q)).sum();
                if s <= bound {
                    out.push(a.to_vec());
                }
                out.len() <= MAX_TERMS
            });
            if out.len() > MAX_TERMS {
                return Err(BasisError::TooLarge(MAX_TERMS));
            }
        }
        if dim == 0 {
            out = vec![vec![]];
        }
        Self::from_indices(dim, out)
    }

    /// Dimension.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// Number of multi-indices.
    pub fn len(&self) -> usize {
        self.indices.len()
    }

    /// Whether the set is empty.
    pub fn is_empty(&self) -> bool {
        self.indices.is_empty()
    }

    /// The multi-indices in order.
    pub fn indices(&self) -> &[Vec<usize>] {
        &self.indices
    }

    /// Position of `alpha`, if present.
    pub fn position(&self, alpha: &[usize]) -> Option<usize> {
        self.lookup.get(alpha).copied()
    }

    /// Whether every backward neighbour `alpha - e_i` of every member is a member.
    pub fn is_downward_closed(&self) -> bool {
        let mut b = Vec::with_capacity(self.dim);
        self.indices.iter().all(|a| {
            (0..self.dim).all(|i| {
                if a[i] == 0 {
                    return true;
                }
                b.clear();
                b.extend_from_slice(a);
                b[i] -= 1;
                self.lookup.contains_key(&b)
            })
        })
    }

    /// Largest total degree `|alpha|_1` of a member (0 for an empty set).
    pub fn order(&self) -> usize {
        self.indices
            .iter()
            .map(|a| a.iter().sum::<usize>())
            .max()
            .unwrap_or(0)
    }

    /// Largest entry per dimension.
    pub fn max_per_dim(&self) -> Vec<usize> {
        let mut m = vec![0; self.dim];
        for a in &self.indices {
            for (mi, &ai) in m.iter_mut().zip(a) {
                *mi = (*mi).max(ai);
            }
        }
        m
    }

    /// The sub-set of the given positions (in that order).
    pub fn select(&self, positions: &[usize]) -> Result<Self, BasisError> {
        Self::from_indices(
            self.dim,
            positions.iter().map(|&k| self.indices[k].clone()).collect(),
        )
    }
}

/// Which branches of [`compositions`] to leave out: `cost[v] = v^q` (`0 < q <= 1`) and a
/// bound (with a margin above the bound of the set, for rounding) on `sum_i cost[a_i]`.
struct Cut<'a> {
    cost: &'a [f64],
    bound: f64,
}

/// Calls `f` on every `a` with `sum a = remaining` (entries from `pos` on), in
/// lexicographically decreasing order, leaving out those whose `sum_i cost[a_i]` is surely
/// above `cut.bound`; stops when `f` returns false. `spent` is the cost of the entries
/// before `pos`. The entries still to place cost at least `cost[rest]` (`v -> v^q` is
/// concave with `0^q = 0`, so `(a + b)^q <= a^q + b^q`: one entry holding them all is the
/// cheapest): a branch above the bound with that is cut. 20 inputs at order 10 went through
/// 30 million compositions for a few thousand indices.
fn compositions(
    dim: usize,
    remaining: usize,
    pos: usize,
    cur: &mut [usize],
    cut: &Cut<'_>,
    spent: f64,
    f: &mut impl FnMut(&[usize]) -> bool,
) -> bool {
    if dim == 0 {
        return true;
    }
    if pos == dim - 1 {
        cur[pos] = remaining;
        return f(cur);
    }
    for v in (0..=remaining).rev() {
        let here = spent + cut.cost[v];
        let rest = remaining - v;
        if here + cut.cost[rest] > cut.bound {
            continue;
        }
        cur[pos] = v;
        if !compositions(dim, rest, pos + 1, cur, cut, here, f) {
            return false;
        }
    }
    cur[pos] = 0;
    true
}

/// A multivariate orthonormal basis: one family per dimension over a multi-index set.
#[derive(Clone, Debug, PartialEq)]
pub struct Basis {
    families: Vec<Family>,
    set: MultiIndexSet,
    max_deg: Vec<usize>,
}

impl Basis {
    /// The basis of `set` with `families[i]` for dimension `i`.
    pub fn new(families: Vec<Family>, set: MultiIndexSet) -> Result<Self, BasisError> {
        if families.len() != set.dim() {
            return Err(BasisError::FamilyCount {
                families: families.len(),
                dim: set.dim(),
            });
        }
        for f in &families {
            f.validate()?;
        }
        let max_deg = set.max_per_dim();
        Ok(Basis {
            families,
            set,
            max_deg,
        })
    }

    /// The families, one per dimension.
    pub fn families(&self) -> &[Family] {
        &self.families
    }

    /// The multi-index set.
    pub fn set(&self) -> &MultiIndexSet {
        &self.set
    }

    /// Number of basis functions.
    pub fn len(&self) -> usize {
        self.set.len()
    }

    /// Whether the basis is empty.
    pub fn is_empty(&self) -> bool {
        self.set.is_empty()
    }

    /// `out[k] = Psi_k(t)` for every basis function, `t` a germ point.
    ///
    /// The univariate values are computed once per dimension into one table, on the stack
    /// for small bases (this runs once per surrogate draw: millions of times in a nested
    /// study).
    pub fn eval(&self, t: &[f64], out: &mut [f64]) {
        const VALUES: usize = 64;
        const DIMS: usize = 16;
        let total: usize = self.max_deg.iter().map(|m| m + 1).sum();
        let d = self.families.len();
        if total <= VALUES && d <= DIMS {
            let (mut table, mut start) = ([0.0; VALUES], [0usize; DIMS]);
            self.eval_in(t, out, &mut table[..total], &mut start[..d]);
        } else {
            self.eval_in(t, out, &mut vec![0.0; total], &mut vec![0; d]);
        }
    }

    /// [`Self::eval`] with the table of univariate values `p^(i)_k(t_i)` (up to the largest
    /// degree used in dimension `i`) at `table[start[i] + k]`.
    fn eval_in(&self, t: &[f64], out: &mut [f64], table: &mut [f64], start: &mut [usize]) {
        let mut at = 0;
        for (((f, &m), &ti), s) in self
            .families
            .iter()
            .zip(&self.max_deg)
            .zip(t)
            .zip(&mut *start)
        {
            *s = at;
            f.eval_all(ti, &mut table[at..at + m + 1]);
            at += m + 1;
        }
        for (o, a) in out.iter_mut().zip(self.set.indices()) {
            *o = a
                .iter()
                .zip(&*start)
                .map(|(&ai, &s)| table[s + ai])
                .product();
        }
    }

    /// The design matrix `Psi[j][k] = Psi_k(points[j])` (rows: points).
    pub fn design_matrix(&self, points: &[Vec<f64>]) -> DMatrix<f64> {
        let mut m = DMatrix::<f64>::zeros(points.len(), self.len());
        let mut row = vec![0.0; self.len()];
        for (j, p) in points.iter().enumerate() {
            self.eval(p, &mut row);
            for (k, v) in row.iter().enumerate() {
                m[(j, k)] = *v;
            }
        }
        m
    }
}

/// Mean, variance and Sobol' indices of an orthonormal chaos.
#[derive(Clone, Debug, PartialEq)]
pub struct ChaosStats {
    /// Mean (the constant coefficient; 0 when the set has no constant term).
    pub mean: f64,
    /// Variance (sum of the squared non-constant coefficients).
    pub variance: f64,
    /// First-order indices per dimension (NaN when the variance is 0).
    pub first: Vec<f64>,
    /// Total indices per dimension (NaN when the variance is 0).
    pub total: Vec<f64>,
}

impl ChaosStats {
    /// Statistics of `sum_k coeffs[k] Psi_{set[k]}`.
    pub fn new(set: &MultiIndexSet, coeffs: &[f64]) -> Self {
        let d = set.dim();
        let mut mean = 0.0;
        let mut variance = 0.0;
        let mut first = vec![0.0; d];
        let mut total = vec![0.0; d];
        for (a, &c) in set.indices().iter().zip(coeffs) {
            let active: Vec<usize> = (0..d).filter(|&i| a[i] > 0).collect();
            if active.is_empty() {
                mean += c;
                continue;
            }
            let c2 = c * c;
            variance += c2;
            if active.len() == 1 {
                first[active[0]] += c2;
            }
            for &i in &active {
                total[i] += c2;
            }
        }
        let norm = |v: Vec<f64>| -> Vec<f64> {
            v.into_iter()
                .map(|x| {
                    if variance > 0.0 {
                        x / variance
                    } else {
                        f64::NAN
                    }
                })
                .collect()
        };
        ChaosStats {
            mean,
            variance,
            first: norm(first),
            total: norm(total),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_basis_over_the_term_limit_is_refused_from_its_count_before_it_is_built() {
        // 30 inputs at order 7 (C(37, 7) = 10 295 472 terms) took 2.3 s and 1.4 GB of
        // enumeration to reach the limit; the count refuses it at once, and a huge order is
        // counted only up to the limit.
        assert_eq!(
            MultiIndexSet::hyperbolic_count_upto(30, 7, 1.0, f64::INFINITY),
            10_295_472.0
        );
        assert!(matches!(
            MultiIndexSet::hyperbolic(30, 7, 1.0),
            Err(BasisError::TooLarge(MAX_TERMS))
        ));
        let capped = MultiIndexSet::hyperbolic_count_upto(30, 1000, 0.5, 1e6);
        assert!(capped > 1e6 && capped < 1e30, "{capped}");
        assert!(MultiIndexSet::hyperbolic(30, 1000, 0.5).is_err());
        // Under the limit the set is built as before.
        assert_eq!(MultiIndexSet::hyperbolic(30, 3, 1.0).unwrap().len(), 5456);
    }

    fn binom(n: usize, k: usize) -> usize {
        (0..k).fold(1usize, |acc, i| acc * (n - i) / (i + 1))
    }

    #[test]
    fn total_degree_set_has_binomial_size_and_is_graded() {
        for (d, p) in [(1, 5), (2, 4), (3, 3), (8, 3), (5, 0)] {
            let s = MultiIndexSet::total_degree(d, p).unwrap();
            assert_eq!(s.len(), binom(d + p, p), "d={d} p={p}");
            assert!(s.is_downward_closed());
            assert_eq!(s.indices()[0], vec![0; d]);
            let degs: Vec<usize> = s.indices().iter().map(|a| a.iter().sum()).collect();
            assert!(degs.windows(2).all(|w| w[0] <= w[1]));
        }
    }

    #[test]
    fn hyperbolic_truncation_keeps_exactly_the_q_norm_ball() {
        let (d, p, q) = (3, 5, 0.5);
        let s = MultiIndexSet::hyperbolic(d, p, q).unwrap();
        // Brute force over the cube [0, p]^3.
        let mut want = 0;
        for a in 0..=p {
            for b in 0..=p {
                for c in 0..=p {
                    let n: f64 = [a, b, c].iter().map(|&x| (x as f64).powf(q)).sum::<f64>();
                    if n.powf(1.0 / q) <= p as f64 + 1e-9 {
                        want += 1;
                        assert!(s.position(&[a, b, c]).is_some(), "{a} {b} {c}");
                    }
                }
            }
        }
        assert_eq!(s.len(), want);
        assert!(s.is_downward_closed());
        // Pure main effects up to p survive, a (1,1,1) term does not at q = 0.5
        // ((1+1+1)^2 = 9 > 5).
        assert!(s.position(&[5, 0, 0]).is_some());
        assert!(s.position(&[1, 1, 1]).is_none());
        assert!(MultiIndexSet::hyperbolic(2, 3, 1.5).is_err());
    }

    #[test]
    fn hyperbolic_set_cut_short_equals_the_whole_enumeration_in_order() {
        // Regression: the set of 20 inputs at order 10 (q = 0.5) went through every one of
        // the 30 million compositions of the degrees (with 20 powers each) for 3 241 indices,
        // 90 % of a 20-input regression chaos's analysis. Cutting the branches must keep the
        // same indices in the same order: against the whole enumeration, written here.
        fn whole(dim: usize, order: usize, q: f64) -> Vec<Vec<usize>> {
            fn rec(a: &mut Vec<usize>, dim: usize, left: usize, out: &mut Vec<Vec<usize>>) {
                if a.len() == dim - 1 {
                    a.push(left);
                    out.push(a.clone());
                    a.pop();
                    return;
                }
                for v in (0..=left).rev() {
                    a.push(v);
                    rec(a, dim, left - v, out);
                    a.pop();
                }
            }
            let bound = (order as f64).powf(q) * (1.0 + 1e-12) + 1e-12;
            let mut out = Vec::new();
            for deg in 0..=order {
                let mut all = Vec::new();
                rec(&mut Vec::new(), dim, deg, &mut all);
                out.extend(
                    all.into_iter()
                        .filter(|a| a.iter().map(|&x| (x as f64).powf(q)).sum::<f64>() <= bound),
                );
            }
            out
        }
        for (dim, order, q) in [
            (1, 6, 0.5),
            (3, 5, 0.5),
            (4, 6, 1.0),
            (6, 7, 0.6),
            (8, 6, 0.75),
            (12, 5, 0.4),
            (20, 4, 0.5),
        ] {
            let s = MultiIndexSet::hyperbolic(dim, order, q).unwrap();
            assert_eq!(s.indices(), &whole(dim, order, q)[..], "{dim} {order} {q}");
        }
        // 20 inputs, order 10, q = 0.5: 1 + 20·10 univariate, 190·10 pairs ((a, b) with
        // (√a + √b)² ≤ 10: (1,1), (1,2), (2,1), (1,3), (3,1), (1,4), (4,1), (2,2), (2,3),
        // (3,2)) and 1 140 triples (only (1,1,1), whose norm is 9).
        assert_eq!(MultiIndexSet::hyperbolic(20, 10, 0.5).unwrap().len(), 3241);
    }

    #[test]
    fn eval_is_the_product_of_the_univariate_values_on_the_stack_and_on_the_heap() {
        // Two dimensions (the table on the stack) and 20 (on the heap): every basis function
        // against the product of `eval_all` values computed here, one dimension at a time.
        for (d, p) in [(2, 5), (20, 2)] {
            let families: Vec<Family> = (0..d)
                .map(|i| match i % 3 {
                    0 => Family::Hermite,
                    1 => Family::Legendre,
                    _ => Family::Laguerre { shape: 2.5 },
                })
                .collect();
            let set = MultiIndexSet::total_degree(d, p).unwrap();
            let basis = Basis::new(families.clone(), set.clone()).unwrap();
            let t: Vec<f64> = (0..d).map(|i| 0.3 + 0.17 * i as f64).collect();
            let mut out = vec![0.0; basis.len()];
            basis.eval(&t, &mut out);
            for (k, a) in set.indices().iter().enumerate() {
                let want: f64 = a
                    .iter()
                    .zip(&families)
                    .zip(&t)
                    .map(|((&ai, f), &ti)| {
                        let mut v = vec![0.0; ai + 1];
                        f.eval_all(ti, &mut v);
                        v[ai]
                    })
                    .product();
                assert_eq!(out[k], want, "d {d}, index {a:?}");
            }
        }
    }

    #[test]
    fn downward_closedness_and_duplicates_are_detected() {
        let s = MultiIndexSet::from_indices(2, vec![vec![0, 0], vec![0, 2]]).unwrap();
        assert!(!s.is_downward_closed());
        assert!(matches!(
            MultiIndexSet::from_indices(2, vec![vec![0, 0], vec![0, 0]]),
            Err(BasisError::Duplicate(_))
        ));
        assert!(MultiIndexSet::from_indices(2, vec![vec![0]]).is_err());
    }

    #[test]
    fn mixed_basis_is_orthonormal_by_tensor_gauss_quadrature() {
        let fams = vec![
            Family::Hermite,
            Family::Legendre,
            Family::Laguerre { shape: 2.5 },
            Family::Jacobi { a: 2.0, b: 3.0 },
        ];
        let set = MultiIndexSet::total_degree(4, 3).unwrap();
        let basis = Basis::new(fams.clone(), set).unwrap();
        // Tensor Gauss rule with 4 points per dimension (exact to degree 7 >= 6).
        let rules: Vec<_> = fams.iter().map(|f| f.gauss(4).unwrap()).collect();
        let n = basis.len();
        let mut gram = vec![0.0; n * n];
        let mut vals = vec![0.0; n];
        for i0 in 0..4 {
            for i1 in 0..4 {
                for i2 in 0..4 {
                    for i3 in 0..4 {
                        let idx = [i0, i1, i2, i3];
                        let t: Vec<f64> = (0..4).map(|k| rules[k].0[idx[k]]).collect();
                        let w: f64 = (0..4).map(|k| rules[k].1[idx[k]]).product();
                        basis.eval(&t, &mut vals);
                        for a in 0..n {
                            for b in 0..n {
                                gram[a * n + b] += w * vals[a] * vals[b];
                            }
                        }
                    }
                }
            }
        }
        for a in 0..n {
            for b in 0..n {
                let want = if a == b { 1.0 } else { 0.0 };
                assert!((gram[a * n + b] - want).abs() < 1e-12, "({a},{b})");
            }
        }
    }

    #[test]
    fn chaos_stats_of_a_known_expansion() {
        // f = 2 + 3 Psi_(1,0) + 1 Psi_(0,2) + 2 Psi_(1,1): Var = 9 + 1 + 4 = 14.
        let set =
            MultiIndexSet::from_indices(2, vec![vec![0, 0], vec![1, 0], vec![0, 2], vec![1, 1]])
                .unwrap();
        let st = ChaosStats::new(&set, &[2.0, 3.0, 1.0, 2.0]);
        assert_eq!(st.mean, 2.0);
        assert_eq!(st.variance, 14.0);
        assert!((st.first[0] - 9.0 / 14.0).abs() < 1e-15);
        assert!((st.first[1] - 1.0 / 14.0).abs() < 1e-15);
        assert!((st.total[0] - 13.0 / 14.0).abs() < 1e-15);
        assert!((st.total[1] - 5.0 / 14.0).abs() < 1e-15);
    }
}
