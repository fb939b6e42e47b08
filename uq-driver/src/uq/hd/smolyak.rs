//! Smolyak sparse grids by the combination technique.
//!
//! A *level set* `I` is a downward-closed set of level multi-indices `l` (levels from 0,
//! one per dimension). The sparse rule is `Q_I = sum_{l in I} c_l (Q_{l_1} x ... x
//! Q_{l_d})` with the combination coefficients `c_l = sum_{e in {0,1}^d, l+e in I}
//! (-1)^|e|` (most are zero). The classical isotropic Smolyak rule of level `L` is
//! `I = {l : l_1 + ... + l_d <= L}` (the "`|l| <= L + d - 1`" form with levels from 1);
//! level 0 is the single centre point.
//!
//! With nested 1-D rules many tensor nodes coincide; [`SparseGrid`] merges them (nodes
//! identified by their coordinates rounded to 2^-40) and sums their weights. It keeps
//! every tensor term with its point ids, so a pseudo-spectral projection can reuse the
//! model values at the merged points (see [`super::pseudo_spectral`]).

use std::collections::HashMap;

use super::rules::{Rule1d, RuleError, RuleKind};

mod count;

pub use count::{total_level_size, GridSize};

/// Largest number of merged points of a sparse grid.
pub const MAX_SPARSE_POINTS: usize = 5_000_000;

/// Errors of the level sets and sparse grids.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SmolyakError {
    /// The level set is not downward closed (refused by [`LevelSet::from_levels`], which
    /// serves the tests).
    #[cfg(test)]
    #[error("level set is not downward closed: {missing:?} (below {member:?}) is missing")]
    NotDownwardClosed {
        /// A member.
        member: Vec<usize>,
        /// Its missing backward neighbour.
        missing: Vec<usize>,
    },
    /// A level multi-index of the wrong length, or no dimensions.
    #[error("level multi-index {0:?} does not match the dimension {1}")]
    Dimension(Vec<usize>, usize),
    /// The number of rules differs from the dimension.
    #[error("{rules} rules given for a {dim}-dimensional level set")]
    RuleCount {
        /// Rules given.
        rules: usize,
        /// Dimension.
        dim: usize,
    },
    /// A 1-D rule failed (e.g. level beyond its table).
    #[error(transparent)]
    Rule(#[from] RuleError),
    /// The grid would be too large.
    #[error("the sparse grid would have more than {MAX_SPARSE_POINTS} points")]
    TooLarge,
}

/// A downward-closed set of level multi-indices.
#[derive(Clone, Debug, PartialEq)]
pub struct LevelSet {
    dim: usize,
    levels: Vec<Vec<usize>>,
}

impl LevelSet {
    /// The isotropic total-level set `{l : sum l_i <= level}`, `dim >= 1`.
    pub fn total(dim: usize, level: usize) -> Result<Self, SmolyakError> {
        Self::weighted(&vec![1.0; dim], level as f64)
    }

    /// The anisotropic set `{l : sum_i w_i l_i <= level}`, weights `w_i > 0`
    /// (a larger weight means fewer levels in that dimension).
    pub fn weighted(weights: &[f64], level: f64) -> Result<Self, SmolyakError> {
        let dim = weights.len();
        if dim == 0 || weights.iter().any(|w| !(w.is_finite() && *w > 0.0)) {
            return Err(SmolyakError::Dimension(vec![], dim));
        }
        let mut out = Vec::new();
        let mut cur = vec![0usize; dim];
        fn rec(
            i: usize,
            budget: f64,
            w: &[f64],
            cur: &mut Vec<usize>,
            out: &mut Vec<Vec<usize>>,
        ) -> bool {
            if i == w.len() {
                out.push(cur.clone());
                return out.len() <= MAX_SPARSE_POINTS;
            }
            let mut l = 0;
            while (l as f64) * w[i] <= budget + 1e-9 {
                cur[i] = l;
                if !rec(i + 1, budget - l as f64 * w[i], w, cur, out) {
                    return false;
                }
                l += 1;
            }
            cur[i] = 0;
            true
        }
        if !rec(0, level, weights, &mut cur, &mut out) {
            return Err(SmolyakError::TooLarge);
        }
        Ok(LevelSet { dim, levels: out })
    }

    /// A general set; refused unless downward closed. Serves the tests (the studies build
    /// [`LevelSet::total`] and [`LevelSet::weighted`] sets).
    #[cfg(test)]
    pub(crate) fn from_levels(dim: usize, levels: Vec<Vec<usize>>) -> Result<Self, SmolyakError> {
        if dim == 0 {
            return Err(SmolyakError::Dimension(vec![], 0));
        }
        if let Some(bad) = levels.iter().find(|l| l.len() != dim) {
            return Err(SmolyakError::Dimension(bad.clone(), dim));
        }
        let members: std::collections::HashSet<&Vec<usize>> = levels.iter().collect();
        for l in &levels {
            for i in 0..dim {
                if l[i] > 0 {
                    let mut b = l.clone();
                    b[i] -= 1;
                    if !members.contains(&b) {
                        return Err(SmolyakError::NotDownwardClosed {
                            member: l.clone(),
                            missing: b,
                        });
                    }
                }
            }
        }
        let mut levels = levels;
        levels.sort();
        levels.dedup();
        Ok(LevelSet { dim, levels })
    }

    /// Dimension.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// The non-zero combination coefficients `(l, c_l)`, in the set's order.
    ///
    /// The subsets `e` with `l + e` in the set are enumerated depth first, pruned at the
    /// first `l + e` outside the set (downward closedness: no superset can be inside),
    /// so the cost is the number of such subsets, not `2^d`.
    pub fn combination(&self) -> Vec<(Vec<usize>, i64)> {
        let members: std::collections::HashSet<&Vec<usize>> = self.levels.iter().collect();
        let mut out = Vec::new();
        for l in &self.levels {
            let mut probe = l.clone();
            let c = signed_subsets(&members, &mut probe, 0, 0);
            if c != 0 {
                out.push((l.clone(), c));
            }
        }
        out
    }
}

/// `sum (-1)^|e|` over the subsets `e` of the dimensions `from..` (added to `probe`, which
/// already carries `depth` unit increments) with `probe + e` in `members`.
fn signed_subsets(
    members: &std::collections::HashSet<&Vec<usize>>,
    probe: &mut Vec<usize>,
    from: usize,
    depth: usize,
) -> i64 {
    let mut c = if depth & 1 == 0 { 1 } else { -1 };
    for i in from..probe.len() {
        probe[i] += 1;
        if members.contains(probe) {
            c += signed_subsets(members, probe, i + 1, depth + 1);
        }
        probe[i] -= 1;
    }
    c
}

/// One full-tensor term of the combination.
#[derive(Clone, Debug, PartialEq)]
pub struct TensorTerm {
    /// Level per dimension.
    pub levels: Vec<usize>,
    /// Combination coefficient.
    pub coeff: i64,
    /// Ids (into [`SparseGrid::points`]) of the tensor nodes, last dimension fastest.
    pub point_ids: Vec<usize>,
    /// Tensor weights (products of 1-D weights, without the coefficient).
    pub weights: Vec<f64>,
    /// Degree of exactness per dimension of this tensor rule.
    pub exactness: Vec<usize>,
}

/// A sparse grid with merged nodes, in germ space.
#[derive(Clone, Debug, PartialEq)]
pub struct SparseGrid {
    /// The 1-D rule per dimension.
    pub rules: Vec<RuleKind>,
    /// Merged points (one coordinate per dimension), in order of first appearance.
    pub points: Vec<Vec<f64>>,
    /// Merged weights (may be negative), summing to 1.
    pub weights: Vec<f64>,
    /// The tensor terms with non-zero coefficients.
    pub terms: Vec<TensorTerm>,
}

/// Rounding key of a coordinate (2^-40 grid).
fn key(x: f64) -> i64 {
    (x * 1_099_511_627_776.0).round() as i64
}

impl SparseGrid {
    /// The sparse grid of `set` with `rules[i]` in dimension `i`.
    pub fn new(rules: &[RuleKind], set: &LevelSet) -> Result<Self, SmolyakError> {
        if rules.len() != set.dim() {
            return Err(SmolyakError::RuleCount {
                rules: rules.len(),
                dim: set.dim(),
            });
        }
        let d = set.dim();
        let mut cache: HashMap<(usize, usize), Rule1d> = HashMap::new();
        let mut ids: HashMap<Vec<i64>, usize> = HashMap::new();
        let mut points: Vec<Vec<f64>> = Vec::new();
        let mut weights: Vec<f64> = Vec::new();
        let mut terms = Vec::new();
        for (levels, coeff) in set.combination() {
            let mut r1: Vec<&Rule1d> = Vec::with_capacity(d);
            for (i, &l) in levels.iter().enumerate() {
                if let std::collections::hash_map::Entry::Vacant(e) = cache.entry((i, l)) {
                    e.insert(rules[i].rule(l)?);
                }
            }
            for (i, &l) in levels.iter().enumerate() {
                r1.push(&cache[&(i, l)]);
            }
            let count: usize = r1.iter().map(|r| r.nodes.len()).product();
            if points.len() + count > 4 * MAX_SPARSE_POINTS {
                return Err(SmolyakError::TooLarge);
            }
            let mut term = TensorTerm {
                levels: levels.clone(),
                coeff,
                point_ids: Vec::with_capacity(count),
                weights: Vec::with_capacity(count),
                exactness: r1.iter().map(|r| r.exactness).collect(),
            };
            let mut idx = vec![0usize; d];
            for _ in 0..count {
                let x: Vec<f64> = (0..d).map(|i| r1[i].nodes[idx[i]]).collect();
                let w: f64 = (0..d).map(|i| r1[i].weights[idx[i]]).product();
                let k: Vec<i64> = x.iter().map(|&v| key(v)).collect();
                let id = *ids.entry(k).or_insert_with(|| {
                    points.push(x);
                    weights.push(0.0);
                    points.len() - 1
                });
                if points.len() > MAX_SPARSE_POINTS {
                    return Err(SmolyakError::TooLarge);
                }
                weights[id] += coeff as f64 * w;
                term.point_ids.push(id);
                term.weights.push(w);
                // Odometer, last dimension fastest.
                for i in (0..d).rev() {
                    idx[i] += 1;
                    if idx[i] < r1[i].nodes.len() {
                        break;
                    }
                    idx[i] = 0;
                }
            }
            terms.push(term);
        }
        Ok(SparseGrid {
            rules: rules.to_vec(),
            points,
            weights,
            terms,
        })
    }

    /// Number of merged points (model runs).
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// `sum_j w_j f_j` for values at the merged points. Serves the tests.
    #[cfg(test)]
    pub(crate) fn integrate(&self, values: &[f64]) -> f64 {
        self.weights.iter().zip(values).map(|(w, v)| w * v).sum()
    }
}

/// Number of merged points of the isotropic sparse grid of `level` in `dim` dimensions
/// with one rule in every dimension (builds the grid). Serves the tests (the studies count
/// with [`total_level_size`], without building the grid).
#[cfg(test)]
pub(crate) fn sparse_grid_size(
    rule: RuleKind,
    dim: usize,
    level: usize,
) -> Result<usize, SmolyakError> {
    let set = LevelSet::total(dim, level)?;
    Ok(SparseGrid::new(&vec![rule; dim], &set)?.len())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::uq::hd::rules::tests::moment;
    use std::collections::HashSet;

    /// All exponent vectors with total degree <= p.
    fn monomials(d: usize, p: usize) -> Vec<Vec<usize>> {
        if d == 0 {
            return vec![vec![]];
        }
        let mut out = Vec::new();
        for first in 0..=p {
            for mut rest in monomials(d - 1, p - first) {
                rest.insert(0, first);
                out.push(rest);
            }
        }
        out
    }

    #[test]
    fn combination_coefficients_of_the_total_level_set_are_the_binomial_ones() {
        // Classical: c_l = (-1)^(L - |l|) binom(d - 1, L - |l|) for L - d + 1 <= |l| <= L.
        let (d, big_l) = (3, 4);
        let set = LevelSet::total(d, big_l).unwrap();
        let comb = set.combination();
        for l in &set.levels {
            let s: usize = l.iter().sum();
            let k = big_l - s;
            let want: i64 = if k < d {
                let b = (0..k).fold(1i64, |acc, i| acc * (d - 1 - i) as i64 / (i + 1) as i64);
                if k & 1 == 0 {
                    b
                } else {
                    -b
                }
            } else {
                0
            };
            let got = comb.iter().find(|(m, _)| m == l).map(|x| x.1).unwrap_or(0);
            assert_eq!(got, want, "{l:?}");
        }
    }

    #[test]
    fn sparse_rules_integrate_every_polynomial_of_the_stated_total_degree() {
        // Smolyak with nested/Gauss rules of exactness m(l) is exact for total degree
        // m(L) when m(l) >= 2l+1 (all rules here): check degree 2L+1 for every monomial.
        for kind in [
            RuleKind::GenzKeister,
            RuleKind::ClenshawCurtis,
            RuleKind::GaussPatterson,
            RuleKind::GaussLegendre,
            RuleKind::GaussHermite,
        ] {
            for (d, big_l) in [(2, 3), (3, 3), (4, 2)] {
                let grid =
                    SparseGrid::new(&vec![kind; d], &LevelSet::total(d, big_l).unwrap()).unwrap();
                assert!((grid.weights.iter().sum::<f64>() - 1.0).abs() < 1e-13);
                for m in monomials(d, 2 * big_l + 1) {
                    let vals: Vec<f64> = grid
                        .points
                        .iter()
                        .map(|x| {
                            x.iter()
                                .zip(&m)
                                .map(|(xi, &mi)| xi.powi(mi as i32))
                                .product()
                        })
                        .collect();
                    let got = grid.integrate(&vals);
                    let want: f64 = m.iter().map(|&mi| moment(kind, mi)).product();
                    assert!(
                        (got - want).abs() < 1e-11 * want.abs().max(1.0),
                        "{kind:?} d={d} L={big_l} {m:?}: {got} vs {want}"
                    );
                }
            }
        }
    }

    /// Distinct points of the union of all tensor grids with non-zero coefficient,
    /// brute force (independent of the merging in `SparseGrid::new`).
    fn brute_count(kind: RuleKind, d: usize, big_l: usize) -> usize {
        let set = LevelSet::total(d, big_l).unwrap();
        let mut pts: HashSet<Vec<i64>> = HashSet::new();
        for (l, _) in set.combination() {
            let mut acc: Vec<Vec<i64>> = vec![vec![]];
            for &li in &l {
                let r = kind.rule(li).unwrap();
                acc = acc
                    .into_iter()
                    .flat_map(|p| {
                        r.nodes.iter().map(move |&x| {
                            let mut q = p.clone();
                            q.push((x * 1e9).round() as i64);
                            q
                        })
                    })
                    .collect();
            }
            pts.extend(acc);
        }
        pts.len()
    }

    #[test]
    fn sparse_grid_sizes_match_published_counts() {
        // Clenshaw–Curtis (Novak–Ritter) sparse grid sizes, levels 0..=4
        // (Burkardt, sparse_grid_cc): d = 2: 1 5 13 29 65; d = 4: 1 9 41 137 401;
        // d = 8: 1 17 145 849 3937.
        let cc = [
            (2, [1, 5, 13, 29, 65]),
            (4, [1, 9, 41, 137, 401]),
            (8, [1, 17, 145, 849, 3937]),
        ];
        // Gauss–Legendre, l + 1 points (shared nodes merged), levels 0..=4
        // (as tabulated in Elastic ml-cpp's sparse-quadrature test):
        // d = 2: 1 5 13 29 53; d = 4: 1 9 41 137 385; d = 8: 1 17 145 849 3905.
        let gl = [
            (2, [1, 5, 13, 29, 53]),
            (4, [1, 9, 41, 137, 385]),
            (8, [1, 17, 145, 849, 3905]),
        ];
        for (kind, name, table) in [
            (RuleKind::ClenshawCurtis, "CC", cc),
            (RuleKind::GaussLegendre, "GL", gl),
        ] {
            for (d, want) in table {
                for (l, &w) in want.iter().enumerate() {
                    assert_eq!(
                        sparse_grid_size(kind, d, l).unwrap(),
                        w,
                        "{name} d={d} level {l}"
                    );
                }
            }
        }
        // Genz–Keister and Gauss–Patterson: against a brute-force union of the tensor grids.
        for kind in [RuleKind::GenzKeister, RuleKind::GaussPatterson] {
            for d in [2, 4, 8] {
                for l in 0..=3 {
                    assert_eq!(
                        sparse_grid_size(kind, d, l).unwrap(),
                        brute_count(kind, d, l),
                        "{kind:?} d={d} level {l}"
                    );
                }
            }
        }
    }

    #[test]
    fn combination_is_cheap_in_high_dimension() {
        // d = 40, L = 2: the classical coefficients, without visiting 2^40 subsets.
        let set = LevelSet::total(40, 2).unwrap();
        let comb = set.combination();
        for (l, c) in &comb {
            let s: usize = l.iter().sum();
            let want = match 2 - s {
                0 => 1,
                1 => -39,
                _ => 39 * 38 / 2,
            };
            assert_eq!(*c, want, "{l:?}");
        }
        assert_eq!(comb.len(), set.levels.len());
        let grid = SparseGrid::new(&[RuleKind::ClenshawCurtis; 40], &set).unwrap();
        // 1 + 2 d (level 1) + 2 d (level 2 new nodes) + 4 C(d, 2) (pairs).
        assert_eq!(grid.len(), 1 + 4 * 40 + 4 * 40 * 39 / 2);
        assert!((grid.weights.iter().sum::<f64>() - 1.0).abs() < 1e-10);
    }

    #[test]
    fn general_downward_closed_sets_and_refusals() {
        // Anisotropic: 2 levels in x, 1 in y, no mixed term.
        let set =
            LevelSet::from_levels(2, vec![vec![0, 0], vec![1, 0], vec![2, 0], vec![0, 1]]).unwrap();
        let grid = SparseGrid::new(&[RuleKind::ClenshawCurtis; 2], &set).unwrap();
        // Exact for x^5 (level-2 CC: 5 points, degree 5) and y^3, not needed more.
        let f: Vec<f64> = grid
            .points
            .iter()
            .map(|p| p[0].powi(4) + p[1].powi(2))
            .collect();
        assert!((grid.integrate(&f) - (0.2 + 1.0 / 3.0)).abs() < 1e-14);
        assert!(matches!(
            LevelSet::from_levels(2, vec![vec![0, 0], vec![0, 2]]),
            Err(SmolyakError::NotDownwardClosed { .. })
        ));
        assert!(matches!(
            SparseGrid::new(&[RuleKind::GenzKeister; 2], &LevelSet::total(2, 5).unwrap()),
            Err(SmolyakError::Rule(RuleError::LevelTooHigh { .. }))
        ));
        let w = LevelSet::weighted(&[1.0, 2.0], 4.0).unwrap();
        assert!(w.levels.iter().all(|l| l[0] + 2 * l[1] <= 4));
        assert_eq!(w.levels.len(), 5 + 3 + 1);
    }
}
