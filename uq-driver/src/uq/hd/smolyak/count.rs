//! Sizes of the isotropic Smolyak grid `{l : l_1 + ... + l_d <= L}` counted without building
//! it (a study is checked before its design is made): the merged points (model runs), the
//! nodes of its tensor terms, and the chaos terms of its pseudo-spectral projection.
//!
//! **Points.** The combination has the non-zero coefficients of the levels with
//! `L - d < |l| <= L` (`c_l = (-1)^(L - |l|) C(d - 1, L - |l|)`), and the merged grid is the
//! union of their tensor grids. A point `x` is in the tensor grid of `l` when each coordinate
//! `x_i` is a node of the rule of level `l_i`. So, per dimension, every distinct node (the
//! coordinates are told apart as in [`super::SparseGrid::new`]) is labelled with the set of
//! levels `S(x_i)` whose rule has it (for nested rules all levels from the first that has
//! it; for Gauss rules one level, or every level with an odd count for the centre of a
//! symmetric rule), and `x` is a point of the grid exactly when some sum `l_1 + ... + l_d`
//! with `l_i` in `S(x_i)` lies in `(L - d, L]`. The count runs over the dimensions keeping,
//! for every set of reachable sums (within `0..=L`; larger sums can only grow), how many
//! partial points reach it: a few states per dimension, not the points.
//!
//! **Tensor nodes**: `sum_{l : L - d < |l| <= L} prod_i n_i(l_i)` (the nodes the
//! construction visits, before merging), a truncated product of polynomials.
//!
//! **Chaos terms**: the projection of the term `l` fills the box of degrees
//! `k_i <= p_i(l_i) = exactness_i(l_i) / 2`; the degrees grow with the level, so the union
//! over the set is the multi-indices `k` whose least levels `m_i(k_i)` sum to at most `L`:
//! with `a_i(j) = p_i(j) - p_i(j - 1)` multi-indices first reached at level `j`, the count is
//! the sum of the coefficients of degree `<= L` of `prod_i sum_j a_i(j) t^j`.

use std::collections::HashMap;

use super::super::rules::RuleKind;
use super::{key, SmolyakError};

/// The sizes of an isotropic sparse grid (floats: they may be beyond any integer type).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridSize {
    /// Merged points (model runs).
    pub points: f64,
    /// Nodes of the tensor terms with a non-zero coefficient, before merging.
    pub tensor_nodes: f64,
    /// Tensor terms with a non-zero coefficient.
    pub tensor_terms: f64,
    /// Terms of the chaos of the sparse pseudo-spectral projection.
    pub chaos_terms: f64,
}

/// The sizes of the level-`level` isotropic grid with `rules[i]` in dimension `i`, counted
/// without building it (see the module documentation). Errors as the grid would: no
/// dimension, or a level beyond a rule's table.
pub fn total_level_size(rules: &[RuleKind], level: usize) -> Result<GridSize, SmolyakError> {
    let d = rules.len();
    if d == 0 {
        return Err(SmolyakError::Dimension(vec![], 0));
    }
    // The 1-D facts of every distinct rule.
    let mut kinds: Vec<(RuleKind, OneD)> = Vec::new();
    for r in rules {
        if !kinds.iter().any(|(k, _)| k == r) {
            kinds.push((*r, OneD::new(*r, level)?));
        }
    }
    let of = |r: &RuleKind| &kinds.iter().find(|(k, _)| k == r).expect("listed").1;
    let lowest = (level + 1).saturating_sub(d);
    let ones = vec![1.0; level + 1];
    let mut sizes = vec![1.0];
    let mut nodes = vec![1.0];
    let mut terms = vec![1.0];
    for r in rules {
        let one = of(r);
        sizes = truncated_product(&sizes, &ones, level);
        nodes = truncated_product(&nodes, &one.points, level);
        terms = truncated_product(&terms, &one.new_degrees, level);
    }
    let in_set = |p: &[f64]| -> f64 { p[lowest.min(p.len())..].iter().sum() };
    Ok(GridSize {
        points: merged_points(rules.iter().map(|r| &of(r).groups), level, lowest),
        tensor_nodes: in_set(&nodes),
        tensor_terms: in_set(&sizes),
        chaos_terms: terms.iter().sum(),
    })
}

/// What the count needs of one rule, levels `0..=level`.
struct OneD {
    /// Nodes per level.
    points: Vec<f64>,
    /// Degrees first projected at each level: `p(j) - p(j - 1)`, `p(-1) = -1`.
    new_degrees: Vec<f64>,
    /// Distinct nodes grouped by the set of levels that have them: (levels, nodes).
    groups: Vec<(Vec<bool>, f64)>,
}

impl OneD {
    fn new(kind: RuleKind, level: usize) -> Result<OneD, SmolyakError> {
        let mut points = Vec::with_capacity(level + 1);
        let mut new_degrees = Vec::with_capacity(level + 1);
        let mut levels_of: HashMap<i64, Vec<bool>> = HashMap::new();
        let mut previous: i64 = -1;
        for l in 0..=level {
            let rule = kind.rule(l)?;
            points.push(rule.nodes.len() as f64);
            let p = (rule.exactness / 2) as i64;
            new_degrees.push((p - previous).max(0) as f64);
            previous = previous.max(p);
            for &x in &rule.nodes {
                levels_of
                    .entry(key(x))
                    .or_insert_with(|| vec![false; level + 1])[l] = true;
            }
        }
        let mut groups: Vec<(Vec<bool>, f64)> = Vec::new();
        for set in levels_of.into_values() {
            match groups.iter_mut().find(|(s, _)| *s == set) {
                Some((_, n)) => *n += 1.0,
                None => groups.push((set, 1.0)),
            }
        }
        Ok(OneD {
            points,
            new_degrees,
            groups,
        })
    }
}

/// `a · b` with the terms of degree above `max` dropped (coefficients by degree).
fn truncated_product(a: &[f64], b: &[f64], max: usize) -> Vec<f64> {
    let len = (a.len() + b.len() - 1).min(max + 1);
    let mut out = vec![0.0; len];
    for (i, x) in a.iter().enumerate() {
        for (j, y) in b.iter().enumerate().take(len.saturating_sub(i)) {
            out[i + j] += x * y;
        }
    }
    out
}

/// The points whose coordinates' level sets (one list of groups per dimension) reach a sum
/// of levels in `lowest..=level`.
fn merged_points<'a>(
    dims: impl Iterator<Item = &'a Vec<(Vec<bool>, f64)>>,
    level: usize,
    lowest: usize,
) -> f64 {
    // Reachable sums (within 0..=level) -> partial points reaching exactly those.
    let mut states: HashMap<Vec<bool>, f64> = HashMap::new();
    let mut start = vec![false; level + 1];
    start[0] = true;
    states.insert(start, 1.0);
    for groups in dims {
        let mut next: HashMap<Vec<bool>, f64> = HashMap::new();
        for (sums, count) in &states {
            for (levels, nodes) in groups {
                let mut reach = vec![false; level + 1];
                for (s, _) in sums.iter().enumerate().filter(|(_, &b)| b) {
                    for (j, _) in levels.iter().enumerate().filter(|(_, &b)| b) {
                        if s + j <= level {
                            reach[s + j] = true;
                        }
                    }
                }
                if reach.iter().any(|&b| b) {
                    *next.entry(reach).or_insert(0.0) += count * nodes;
                }
            }
        }
        states = next;
    }
    states
        .iter()
        .filter(|(sums, _)| sums[lowest..].iter().any(|&b| b))
        .map(|(_, n)| n)
        .sum()
}

#[cfg(test)]
mod tests {
    use super::super::{LevelSet, SparseGrid};
    use super::*;
    use crate::uq::hd::pseudo_spectral::sparse_pseudo_spectral;
    use crate::uq::pce::askey::Family;
    use nalgebra::DMatrix;

    /// The sizes of the grid as built.
    fn built(rules: &[RuleKind], level: usize) -> GridSize {
        let grid = SparseGrid::new(rules, &LevelSet::total(rules.len(), level).unwrap()).unwrap();
        let values = DMatrix::<f64>::zeros(grid.len(), 1);
        let pce = sparse_pseudo_spectral(&grid, &values).unwrap();
        GridSize {
            points: grid.len() as f64,
            tensor_nodes: grid.terms.iter().map(|t| t.point_ids.len()).sum::<usize>() as f64,
            tensor_terms: grid.terms.len() as f64,
            chaos_terms: pce.basis.len() as f64,
        }
    }

    #[test]
    fn counted_sizes_equal_those_of_the_built_grid() {
        let gamma = RuleKind::Gauss(Family::Laguerre { shape: 2.5 });
        let beta = RuleKind::Gauss(Family::Jacobi { a: 2.0, b: 3.0 });
        let symmetric_beta = RuleKind::Gauss(Family::Jacobi { a: 2.0, b: 2.0 });
        let all = [
            RuleKind::GenzKeister,
            RuleKind::GaussPatterson,
            RuleKind::ClenshawCurtis,
            RuleKind::GaussLegendre,
            RuleKind::GaussHermite,
            gamma,
            beta,
            symmetric_beta,
        ];
        let mut checked = 0;
        for kind in all {
            for d in [1, 2, 3, 5, 8] {
                for level in 0..=4 {
                    if d >= 5 && level > 3 {
                        continue;
                    }
                    let rules = vec![kind; d];
                    assert_eq!(
                        total_level_size(&rules, level).unwrap(),
                        built(&rules, level),
                        "{kind:?} d = {d}, level {level}"
                    );
                    checked += 1;
                }
            }
        }
        // Mixed rules (a normal, a uniform, a gamma and a beta input, as a study gives them).
        let mixed = [
            RuleKind::GenzKeister,
            RuleKind::GaussPatterson,
            gamma,
            beta,
            RuleKind::GaussLegendre,
            symmetric_beta,
        ];
        for d in 1..=mixed.len() {
            for level in 0..=4 {
                let rules = &mixed[..d];
                assert_eq!(
                    total_level_size(rules, level).unwrap(),
                    built(rules, level),
                    "{rules:?}, level {level}"
                );
                checked += 1;
            }
        }
        assert!(checked > 150);
    }

    #[test]
    fn the_counts_of_large_grids_are_instant() {
        // 30 uniform inputs, Gauss–Patterson: nested, Σ_{|l| <= L} Π new(l_i) with
        // new = 1, 2, 4, 8, 16, 32 (the count for level 5: 9 600 513 points).
        let rules = vec![RuleKind::GaussPatterson; 30];
        fn nested(new: &[f64], d: usize, budget: usize) -> f64 {
            if d == 0 {
                return 1.0;
            }
            (0..=budget.min(new.len() - 1))
                .map(|j| new[j] * nested(new, d - 1, budget - j))
                .sum()
        }
        let new = [1.0, 2.0, 4.0, 8.0, 16.0, 32.0];
        for (level, want) in [(3, 41_601.0), (4, 696_321.0), (5, 9_600_513.0)] {
            assert_eq!(nested(&new, 30, level), want);
            assert_eq!(total_level_size(&rules, level).unwrap().points, want);
        }
        // Far beyond any grid that could be built.
        let huge = total_level_size(&vec![RuleKind::GenzKeister; 500], 4).unwrap();
        assert!(huge.points > 1e10, "{}", huge.points);
        assert!(total_level_size(&[], 2).is_err());
        assert!(total_level_size(&[RuleKind::GenzKeister], 5).is_err());
    }
}
