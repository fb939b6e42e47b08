//! Sparse pseudo-spectral projection (Conrad & Marzouk, SIAM J. Sci. Comput. 35, 2013).
//!
//! For every full-tensor term `l` of a sparse grid (see [`super::smolyak`]) the model
//! values at its nodes are projected onto the largest tensor polynomial space that this
//! tensor rule integrates exactly against itself: per dimension the degree `p_i` with
//! `2 p_i <= exactness_i`. Each such projection is exact on its own space; the
//! coefficients are then combined with the combination coefficients. For a downward
//! closed level set the result reproduces *every* polynomial in the union of the tensor
//! spaces exactly, whereas projecting with the merged Smolyak weights aliases (shown in the
//! tests).
//!
//! The basis is orthonormal on the rules' germs: Hermite for Genz–Keister /
//! Gauss–Hermite dimensions, Legendre for Clenshaw–Curtis / Gauss–Patterson /
//! Gauss–Legendre dimensions.

use std::collections::HashMap;

use nalgebra::DMatrix;

use super::smolyak::{LevelSet, SparseGrid, TensorTerm};
use crate::uq::pce::askey::Family;
use crate::uq::pce::basis::{Basis, BasisError, MultiIndexSet};
use crate::uq::pce::Pce;

/// Errors of the projection.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ProjectionError {
    /// The value matrix does not have one row per merged grid point.
    #[error("{rows} rows of model values for a sparse grid of {points} points")]
    Rows {
        /// Rows given.
        rows: usize,
        /// Points of the grid.
        points: usize,
    },
    /// Building the multi-index set failed.
    #[error(transparent)]
    Basis(#[from] BasisError),
    /// Building the coarser grid failed.
    #[error(transparent)]
    Grid(#[from] super::smolyak::SmolyakError),
    /// A point of the coarser grid is not a point of the finer one.
    #[error("the coarser sparse grid is not nested in the finer one (point {0:?} missing)")]
    NotNested(Vec<f64>),
}

/// Per-dimension maximal degree of the tensor projection of a term.
fn term_degrees(term: &TensorTerm) -> Vec<usize> {
    term.exactness.iter().map(|&e| e / 2).collect()
}

/// Sparse pseudo-spectral projection of `values` (one row per merged point of `grid`,
/// one column per output).
pub fn sparse_pseudo_spectral(
    grid: &SparseGrid,
    values: &DMatrix<f64>,
) -> Result<Pce, ProjectionError> {
    if values.nrows() != grid.len() {
        return Err(ProjectionError::Rows {
            rows: values.nrows(),
            points: grid.len(),
        });
    }
    let fams: Vec<Family> = grid.rules.iter().map(|r| r.family()).collect();
    let nout = values.ncols();
    let d = fams.len();
    let mut acc: HashMap<Vec<usize>, Vec<f64>> = HashMap::new();
    for term in &grid.terms {
        let degs = term_degrees(term);
        let rules: Vec<_> = term
            .levels
            .iter()
            .zip(&grid.rules)
            .map(|(&l, r)| r.rule(l).expect("rule existed when the grid was built"))
            .collect();
        // 1-D tables: tab[i][node][k] = p_k(node).
        let tab: Vec<Vec<Vec<f64>>> = (0..d)
            .map(|i| {
                rules[i]
                    .nodes
                    .iter()
                    .map(|&x| {
                        let mut v = vec![0.0; degs[i] + 1];
                        fams[i].eval_all(x, &mut v);
                        v
                    })
                    .collect()
            })
            .collect();
        let alphas = tensor_indices(&degs);
        let mut local = vec![0.0; alphas.len() * nout];
        let sizes: Vec<usize> = rules.iter().map(|r| r.nodes.len()).collect();
        let mut idx = vec![0usize; d];
        for (j, &pid) in term.point_ids.iter().enumerate() {
            let w = term.weights[j];
            for (a, alpha) in alphas.iter().enumerate() {
                let psi: f64 = (0..d).map(|i| tab[i][idx[i]][alpha[i]]).product();
                for o in 0..nout {
                    local[a * nout + o] += w * psi * values[(pid, o)];
                }
            }
            for i in (0..d).rev() {
                idx[i] += 1;
                if idx[i] < sizes[i] {
                    break;
                }
                idx[i] = 0;
            }
        }
        let c = term.coeff as f64;
        for (a, alpha) in alphas.into_iter().enumerate() {
            let e = acc.entry(alpha).or_insert_with(|| vec![0.0; nout]);
            for o in 0..nout {
                e[o] += c * local[a * nout + o];
            }
        }
    }
    let mut entries: Vec<(Vec<usize>, Vec<f64>)> = acc.into_iter().collect();
    entries.sort_by(|a, b| {
        let (sa, sb): (usize, usize) = (a.0.iter().sum(), b.0.iter().sum());
        sa.cmp(&sb).then_with(|| b.0.cmp(&a.0))
    });
    let mut coeffs = DMatrix::<f64>::zeros(entries.len(), nout);
    for (k, (_, c)) in entries.iter().enumerate() {
        for o in 0..nout {
            coeffs[(k, o)] = c[o];
        }
    }
    let set = MultiIndexSet::from_indices(d, entries.into_iter().map(|e| e.0).collect())?;
    Ok(Pce {
        basis: Basis::new(fams, set)?,
        coeffs,
    })
}

/// The direct projection `c_alpha = sum_j w_j f(x_j) Psi_alpha(x_j)` with the merged
/// Smolyak weights, onto the given set. Serves the tests, which compare it with
/// [`sparse_pseudo_spectral`]: it aliases.
#[cfg(test)]
pub(crate) fn smolyak_weight_projection(
    grid: &SparseGrid,
    values: &DMatrix<f64>,
    set: &MultiIndexSet,
) -> Result<DMatrix<f64>, ProjectionError> {
    if values.nrows() != grid.len() {
        return Err(ProjectionError::Rows {
            rows: values.nrows(),
            points: grid.len(),
        });
    }
    let fams: Vec<Family> = grid.rules.iter().map(|r| r.family()).collect();
    let basis = Basis::new(fams, set.clone())?;
    let psi = basis.design_matrix(&grid.points);
    let mut wf = values.clone();
    for (j, w) in grid.weights.iter().enumerate() {
        wf.row_mut(j).scale_mut(*w);
    }
    Ok(psi.transpose() * wf)
}

/// [`level_difference_from`], projecting the fine chaos itself. Serves the tests.
#[cfg(test)]
pub(crate) fn level_difference(
    grid: &SparseGrid,
    values: &DMatrix<f64>,
    coarse: &LevelSet,
) -> Result<Vec<f64>, ProjectionError> {
    let fine = sparse_pseudo_spectral(grid, values)?;
    level_difference_from(&fine, grid, values, coarse)
}

/// Truncation-error estimate from two nested levels: the projections on `grid` (with
/// `values`; `fine`, already projected from them) and on the coarser level set `coarse` (its
/// points must be among the grid's, as for nested rules and `coarse` a subset of the grid's
/// level set; no new model runs) are compared. Returns, per output,
/// `sum_alpha (c_fine - c_coarse)^2 / Var_fine` — the relative mean-square difference of the
/// two chaoses (a pessimistic estimate of the coarse chaos's error, a usual stand-in for the
/// fine one's).
pub fn level_difference_from(
    fine: &Pce,
    grid: &SparseGrid,
    values: &DMatrix<f64>,
    coarse: &LevelSet,
) -> Result<Vec<f64>, ProjectionError> {
    let (cgrid, cvals) = restrict(grid, values, coarse)?;
    let coarse_pce = sparse_pseudo_spectral(&cgrid, &cvals)?;
    Ok(relative_difference(fine, &coarse_pce))
}

/// The grid of the coarser level set `coarse` (its points among `grid`'s, as for nested rules)
/// with its rows of `values` (one row per point of `grid`).
pub fn restrict(
    grid: &SparseGrid,
    values: &DMatrix<f64>,
    coarse: &LevelSet,
) -> Result<(SparseGrid, DMatrix<f64>), ProjectionError> {
    let cgrid = SparseGrid::new(&grid.rules, coarse)?;
    let index: HashMap<Vec<i64>, usize> = grid
        .points
        .iter()
        .enumerate()
        .map(|(i, p)| (point_key(p), i))
        .collect();
    let mut cvals = DMatrix::<f64>::zeros(cgrid.len(), values.ncols());
    for (j, p) in cgrid.points.iter().enumerate() {
        let i = *index
            .get(&point_key(p))
            .ok_or_else(|| ProjectionError::NotNested(p.clone()))?;
        cvals.set_row(j, &values.row(i));
    }
    Ok((cgrid, cvals))
}

/// Per output, `Σ (c_fine − c_coarse)² / Var_fine` over the union of the two bases.
fn relative_difference(fine: &Pce, coarse_pce: &Pce) -> Vec<f64> {
    let mut out = Vec::with_capacity(fine.outputs());
    for o in 0..fine.outputs() {
        let mut diff = 0.0;
        let mut var = 0.0;
        let mut mean = 0.0;
        for (k, a) in fine.basis.set().indices().iter().enumerate() {
            let cf = fine.coeffs[(k, o)];
            let cc = coarse_pce
                .basis
                .set()
                .position(a)
                .map_or(0.0, |m| coarse_pce.coeffs[(m, o)]);
            diff += (cf - cc).powi(2);
            if a.iter().any(|&x| x > 0) {
                var += cf * cf;
            } else {
                mean = cf;
            }
        }
        // Coarse terms absent from the fine set (none for nested level sets).
        for (m, a) in coarse_pce.basis.set().indices().iter().enumerate() {
            if fine.basis.set().position(a).is_none() {
                diff += coarse_pce.coeffs[(m, o)].powi(2);
            }
        }
        // A variance at the rounding level of the mean (a constant output) counts as none,
        // and so does a difference at that level.
        let negligible = (64.0 * f64::EPSILON * mean).powi(2);
        out.push(if var > negligible {
            diff / var
        } else if diff <= negligible {
            0.0
        } else {
            f64::INFINITY
        });
    }
    out
}

fn point_key(p: &[f64]) -> Vec<i64> {
    p.iter()
        .map(|&x| (x * 1_099_511_627_776.0).round() as i64)
        .collect()
}

/// All `alpha` with `alpha_i <= degs[i]`, last dimension fastest.
fn tensor_indices(degs: &[usize]) -> Vec<Vec<usize>> {
    let mut out = vec![vec![]];
    for &p in degs {
        out = out
            .into_iter()
            .flat_map(|a| {
                (0..=p).map(move |k| {
                    let mut b = a.clone();
                    b.push(k);
                    b
                })
            })
            .collect();
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::uq::hd::rules::RuleKind;
    use crate::uq::hd::smolyak::LevelSet;

    /// A deterministic pseudo-random coefficient in [-1, 1] for index k.
    fn coef(k: usize) -> f64 {
        let x = ((k as f64 + 1.0) * 0.618_033_988_749_895).fract();
        2.0 * x - 1.0
    }

    fn check_recovers_union_polynomial(kind: RuleKind, d: usize, level: usize) -> f64 {
        let grid = SparseGrid::new(&vec![kind; d], &LevelSet::total(d, level).unwrap()).unwrap();
        // The union of the tensor spaces, from a first projection of zeros.
        let zeros = DMatrix::<f64>::zeros(grid.len(), 1);
        let target = sparse_pseudo_spectral(&grid, &zeros).unwrap();
        let set = target.basis.set().clone();
        let truth: Vec<f64> = (0..set.len()).map(coef).collect();
        // Model values: the polynomial evaluated directly, basis by basis in the test.
        let fam = kind.family();
        let values = DMatrix::from_fn(grid.len(), 1, |j, _| {
            set.indices()
                .iter()
                .zip(&truth)
                .map(|(a, c)| {
                    c * a
                        .iter()
                        .zip(&grid.points[j])
                        .map(|(&ai, &x)| fam.eval(ai, x))
                        .product::<f64>()
                })
                .sum()
        });
        let pce = sparse_pseudo_spectral(&grid, &values).unwrap();
        assert_eq!(pce.basis.set(), &set);
        for (k, t) in truth.iter().enumerate() {
            assert!(
                (pce.coeffs[(k, 0)] - t).abs() < 1e-12,
                "{kind:?} d={d} L={level}: coefficient {:?}: {} vs {t}",
                set.indices()[k],
                pce.coeffs[(k, 0)],
            );
        }
        // The direct Smolyak-weight projection onto the same set aliases.
        let direct = smolyak_weight_projection(&grid, &values, &set).unwrap();
        (0..set.len())
            .map(|k| (direct[(k, 0)] - truth[k]).abs())
            .fold(0.0, f64::max)
    }

    #[test]
    fn pseudo_spectral_recovers_polynomials_where_smolyak_weights_alias() {
        for (kind, d, level) in [
            (RuleKind::GenzKeister, 2, 2),
            (RuleKind::GenzKeister, 3, 3),
            (RuleKind::ClenshawCurtis, 3, 3),
            (RuleKind::GaussPatterson, 2, 3),
            (RuleKind::GaussLegendre, 3, 3),
            (RuleKind::Gauss(Family::Laguerre { shape: 2.5 }), 2, 3),
            (RuleKind::Gauss(Family::Jacobi { a: 2.0, b: 3.5 }), 3, 2),
        ] {
            let alias = check_recovers_union_polynomial(kind, d, level);
            if kind.is_nested() {
                assert!(
                    alias > 1e-3,
                    "{kind:?} d={d} L={level}: direct projection error only {alias}"
                );
            }
        }
    }

    #[test]
    fn pseudo_spectral_mean_and_variance_of_a_smooth_function() {
        // f(t) = exp(0.3 t1 + 0.2 t2) with t ~ N(0, I): mean exp(0.065),
        // variance exp(0.13) (exp(0.13) - 1).
        let grid =
            SparseGrid::new(&[RuleKind::GenzKeister; 2], &LevelSet::total(2, 3).unwrap()).unwrap();
        let values = DMatrix::from_fn(grid.len(), 1, |j, _| {
            (0.3 * grid.points[j][0] + 0.2 * grid.points[j][1]).exp()
        });
        let pce = sparse_pseudo_spectral(&grid, &values).unwrap();
        let st = crate::uq::pce::basis::ChaosStats::new(
            pce.basis.set(),
            pce.coeffs.column(0).as_slice(),
        );
        let m = 0.065f64.exp();
        let v = 0.13f64.exp() * (0.13f64.exp() - 1.0);
        assert!((st.mean - m).abs() < 1e-10, "{} vs {m}", st.mean);
        assert!((st.variance - v).abs() < 1e-7 * v, "{} vs {v}", st.variance);
    }

    #[test]
    fn mixed_rules_project_onto_mixed_families() {
        // t1 ~ N(0,1) (Genz–Keister), t2 ~ U(-1,1) (Gauss–Patterson):
        // f = 1 + 2 t1 + t1^2 t2 + 0.5 t2^3: mean 1 + 0 = 1,
        // Var = 4 + E[t1^4 t2^2] + 0.25 E[t2^6] + 2 * 0.5 E[t1^2] E[t2^4]
        //     = 4 + 3/3 + 0.25/7 + 1/5.
        let grid = SparseGrid::new(
            &[RuleKind::GenzKeister, RuleKind::GaussPatterson],
            &LevelSet::total(2, 3).unwrap(),
        )
        .unwrap();
        let values = DMatrix::from_fn(grid.len(), 1, |j, _| {
            let (a, b) = (grid.points[j][0], grid.points[j][1]);
            1.0 + 2.0 * a + a * a * b + 0.5 * b.powi(3)
        });
        let pce = sparse_pseudo_spectral(&grid, &values).unwrap();
        assert_eq!(pce.basis.families(), &[Family::Hermite, Family::Legendre]);
        let st = crate::uq::pce::basis::ChaosStats::new(
            pce.basis.set(),
            pce.coeffs.column(0).as_slice(),
        );
        let var = 4.0 + 1.0 + 0.25 / 7.0 + 0.2;
        assert!((st.mean - 1.0).abs() < 1e-13);
        assert!(
            (st.variance - var).abs() < 1e-12,
            "{} vs {var}",
            st.variance
        );
    }

    #[test]
    fn level_difference_vanishes_when_the_coarse_level_is_exact_and_tracks_the_error() {
        // A polynomial in the union space of level 1 (GK: degree 2 per dimension).
        let grid =
            SparseGrid::new(&[RuleKind::GenzKeister; 2], &LevelSet::total(2, 3).unwrap()).unwrap();
        let poly = DMatrix::from_fn(grid.len(), 1, |j, _| {
            let (a, b) = (grid.points[j][0], grid.points[j][1]);
            1.0 + a * a - 0.5 * b
        });
        let d = level_difference(&grid, &poly, &LevelSet::total(2, 1).unwrap()).unwrap();
        assert!(d[0] < 1e-25, "{}", d[0]);
        // A smooth non-polynomial: the estimate falls with the level, like the true error.
        let f = |a: f64, b: f64| (0.7 * a).sin() * (0.5 * b).exp();
        let mut prev = f64::INFINITY;
        for level in 2..=4 {
            let g = SparseGrid::new(
                &[RuleKind::GenzKeister; 2],
                &LevelSet::total(2, level).unwrap(),
            )
            .unwrap();
            let v = DMatrix::from_fn(g.len(), 1, |j, _| f(g.points[j][0], g.points[j][1]));
            let e = level_difference(&g, &v, &LevelSet::total(2, level - 1).unwrap()).unwrap()[0];
            assert!(e < prev / 10.0, "level {level}: {e} vs {prev}");
            prev = e;
        }
        // Gauss–Legendre is not nested: the 2-point nodes of level 1 are not among the
        // fine grid's (3-point rule in x, 2-point in y only on the axis): refused.
        let fine_set =
            LevelSet::from_levels(2, vec![vec![0, 0], vec![1, 0], vec![2, 0], vec![0, 1]]).unwrap();
        let g = SparseGrid::new(&[RuleKind::GaussLegendre; 2], &fine_set).unwrap();
        let v = DMatrix::<f64>::zeros(g.len(), 1);
        assert!(matches!(
            level_difference(&g, &v, &LevelSet::total(2, 1).unwrap()),
            Err(ProjectionError::NotNested(_))
        ));
    }

    #[test]
    fn wrong_value_count_is_refused() {
        let grid = SparseGrid::new(
            &[RuleKind::ClenshawCurtis; 2],
            &LevelSet::total(2, 1).unwrap(),
        )
        .unwrap();
        let v = DMatrix::<f64>::zeros(3, 1);
        assert!(matches!(
            sparse_pseudo_spectral(&grid, &v),
            Err(ProjectionError::Rows { rows: 3, points: 5 })
        ));
    }
}
