//! Rank correlations of an output with each input, from given data: Spearman's coefficient
//! (the Pearson correlation of the mid-ranks) and the partial rank correlation coefficient
//! (PRCC: the correlation of the output's and the input's ranks once the linear effect of the
//! other inputs' ranks is removed from both).
//!
//! PRCC from the inverse `P` of the rank correlation matrix of (inputs, output):
//! `PRCC_i = −P_iy / sqrt(P_ii P_yy)`. The inputs' block `A = C_xx⁻¹` is computed once for
//! all outputs; per output, with `c` the inputs' rank correlations with it and `s = 1 − cᵀ A c`
//! (Schur complement), `P_yy = 1/s`, `P_iy = −(A c)_i / s`, `P_ii = A_ii + (A c)_i² / s`.
//!
//! Both are measures of monotone association, on the physical values as sampled (correlated
//! inputs included: Spearman then also reflects what an input shares with the inputs it is
//! correlated with; PRCC removes the others' linear effect on the ranks).

use nalgebra::DMatrix;

use super::given_data::mid_ranks;

/// The ranks of a sample's inputs, prepared for any number of outputs.
#[derive(Clone, Debug)]
pub(crate) struct RankInputs {
    /// Standardised mid-ranks of every input (`[input][run]`, mean 0, norm 1), `None` for
    /// an input without spread.
    ranks: Vec<Option<Vec<f64>>>,
    /// The inverse of the inputs' rank correlation matrix, where it is invertible.
    inverse: Option<DMatrix<f64>>,
}

/// Mid-ranks centred and scaled to unit norm, `None` when all are equal.
fn standardised_ranks(v: &[f64]) -> Option<Vec<f64>> {
    let mut r = mid_ranks(v);
    let n = r.len() as f64;
    let mean = r.iter().sum::<f64>() / n;
    r.iter_mut().for_each(|x| *x -= mean);
    let norm = r.iter().map(|x| x * x).sum::<f64>().sqrt();
    (norm > 0.0).then(|| r.iter().map(|x| x / norm).collect())
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

impl RankInputs {
    /// The ranks of `inputs[i][j]` (input `i`, run `j`).
    pub(crate) fn of(inputs: &[Vec<f64>]) -> RankInputs {
        let ranks: Vec<Option<Vec<f64>>> = inputs.iter().map(|x| standardised_ranks(x)).collect();
        let d = ranks.len();
        let inverse = ranks.iter().all(Option::is_some).then(|| {
            let r: Vec<&Vec<f64>> = ranks.iter().flatten().collect();
            DMatrix::from_fn(d, d, |i, k| dot(r[i], r[k]))
        });
        let inverse = inverse.and_then(|c| {
            // A near-singular matrix (an input a monotone function of the others, or
            // fewer runs than inputs) has no partial correlations.
            let inv = c.clone().try_inverse()?;
            let cond = c.norm() * inv.norm();
            (cond.is_finite() && cond < 1e10).then_some(inv)
        });
        RankInputs { ranks, inverse }
    }

    /// Spearman's coefficient and the PRCC of every input with the output `y` (one value
    /// per run), NaN where undefined (no spread, or a singular rank correlation matrix).
    pub(crate) fn of_output(&self, y: &[f64]) -> (Vec<f64>, Vec<f64>) {
        let d = self.ranks.len();
        let nan = || vec![f64::NAN; d];
        let Some(ry) = standardised_ranks(y) else {
            return (nan(), nan());
        };
        let spearman: Vec<f64> = self
            .ranks
            .iter()
            .map(|r| r.as_ref().map_or(f64::NAN, |r| dot(r, &ry)))
            .collect();
        let prcc = match &self.inverse {
            None => nan(),
            Some(a) => {
                let c = nalgebra::DVector::from_column_slice(&spearman);
                let ac = a * &c;
                let s = 1.0 - c.dot(&ac);
                if s <= 1e-12 {
                    // The output's ranks are a linear function of the inputs' ranks.
                    (0..d).map(|i| ac[i].signum()).collect()
                } else {
                    (0..d)
                        .map(|i| {
                            let p_iy = -ac[i] / s;
                            let p_ii = a[(i, i)] + ac[i] * ac[i] / s;
                            (-p_iy / (p_ii / s).sqrt()).clamp(-1.0, 1.0)
                        })
                        .collect()
                }
            }
        };
        (spearman, prcc)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::uq::{rng, sampling, special::norm_ppf};
    use std::f64::consts::PI;

    #[test]
    fn spearman_of_a_linear_function_of_normals_is_the_closed_form() {
        // (x_i, y) bivariate normal with correlation rho_i = a_i s_i / s_y: Spearman's
        // coefficient is (6 / pi) asin(rho_i / 2).
        let (a, s) = ([1.0, -2.0, 0.5], [1.0, 0.5, 2.0]);
        let n = 20_000;
        let pts = sampling::latin_hypercube(n, 3, 4);
        let x: Vec<Vec<f64>> = (0..3)
            .map(|i| pts.iter().map(|p| s[i] * norm_ppf(p[i])).collect())
            .collect();
        let y: Vec<f64> = (0..n)
            .map(|j| (0..3).map(|i| a[i] * x[i][j]).sum())
            .collect();
        let sy = (0..3).map(|i| (a[i] * s[i]).powi(2)).sum::<f64>().sqrt();
        let (spearman, prcc) = RankInputs::of(&x).of_output(&y);
        for i in 0..3 {
            let exact = 6.0 / PI * (a[i] * s[i] / sy / 2.0).asin();
            assert!(
                (spearman[i] - exact).abs() < 0.01,
                "{i}: {} vs {exact}",
                spearman[i]
            );
            // Partial on the ranks: the others' linear effect on the ranks removed (the ranks
            // of normals are not linear in them: about 0.915 here).
            assert!(
                prcc[i].abs() > 0.85 && prcc[i].signum() == a[i].signum(),
                "{prcc:?}"
            );
        }
    }

    #[test]
    fn prcc_is_the_correlation_of_rank_residuals_computed_by_least_squares() {
        // Independent route: regress the ranks of x_i and of y on the other inputs' ranks
        // (with an intercept), correlate the residuals.
        let n = 300;
        let mut stream = rng::stream(8, 0);
        let x: Vec<Vec<f64>> = (0..3)
            .map(|_| (0..n).map(|_| rng::uniform_open01(&mut stream)).collect())
            .collect();
        let y: Vec<f64> = (0..n)
            .map(|j| x[0][j].exp() - 2.0 * x[1][j] + 0.3 * rng::standard_normal(&mut stream))
            .collect();
        let (_, prcc) = RankInputs::of(&x).of_output(&y);
        let ranks = |v: &[f64]| mid_ranks(v);
        let rx: Vec<Vec<f64>> = x.iter().map(|v| ranks(v)).collect();
        let ry = ranks(&y);
        for i in 0..3 {
            let others: Vec<usize> = (0..3).filter(|&k| k != i).collect();
            let design =
                DMatrix::from_fn(n, 3, |j, c| if c == 0 { 1.0 } else { rx[others[c - 1]][j] });
            let resid = |v: &[f64]| {
                let b = nalgebra::DVector::from_column_slice(v);
                let svd = design.clone().svd(true, true);
                let coef = svd.solve(&b, 1e-12).unwrap();
                (b - &design * coef).iter().copied().collect::<Vec<f64>>()
            };
            let (ex, ey) = (resid(&rx[i]), resid(&ry));
            let want = dot(&ex, &ey) / (dot(&ex, &ex) * dot(&ey, &ey)).sqrt();
            assert!((prcc[i] - want).abs() < 1e-9, "{i}: {} vs {want}", prcc[i]);
        }
    }

    #[test]
    fn a_constant_input_or_output_has_no_rank_correlation() {
        let x = vec![vec![1.0, 2.0, 3.0, 4.0], vec![5.0; 4]];
        let (s, p) = RankInputs::of(&x).of_output(&[1.0, 3.0, 2.0, 4.0]);
        assert!((s[0] - 0.8).abs() < 1e-12 && s[1].is_nan());
        assert!(p.iter().all(|v| v.is_nan()));
        let (s, _) = RankInputs::of(&x).of_output(&[2.0; 4]);
        assert!(s.iter().all(|v| v.is_nan()));
    }
}
