//! Ordinary least squares with the closed-form leave-one-out error.
//!
//! For a design (regression) matrix `Psi` (N rows: samples; P columns: basis functions)
//! and responses `y`, the fit is `c = argmin |Psi c - y|^2` by a thin QR factorisation.
//! The leave-one-out residuals need no refits: with the hat matrix
//! `H = Psi (Psi^T Psi)^-1 Psi^T = Q Q^T`, `y_i - yhat_(-i)(x_i) = (y_i - yhat_i) / (1 - h_i)`.
//!
//! Conventions (as in Blatman & Sudret, J. Comput. Phys. 230, 2011):
//! - `loo_mse = (1/N) sum_i ((y_i - yhat_i) / (1 - h_i))^2`;
//! - the Chapelle correction factor `T(P, N) = N / (N - P) * (1 + tr(C^-1) / N)`, with
//!   `C = Psi^T Psi / N` the empirical Gram matrix, guards against overfitting when
//!   `P` approaches `N`;
//! - relative errors divide by the empirical variance of `y` (denominator `N - 1`).

use nalgebra::{DMatrix, DVector};

/// Errors of the least-squares fits.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum RegressionError {
    /// Fewer samples than unknowns.
    #[error("under-determined least-squares fit: {samples} samples for {terms} basis terms; use a sparse fit (sparse = true) or at least {terms} samples (2-3x more is advisable)")]
    Underdetermined {
        /// Samples N.
        samples: usize,
        /// Basis terms P.
        terms: usize,
    },
    /// The design matrix is (numerically) rank deficient.
    #[error("the design matrix is rank deficient (column {column} depends on the others); the sample points cannot identify this basis")]
    RankDeficient {
        /// First dependent column in the QR order.
        column: usize,
    },
    /// Shapes do not match.
    #[error("{rows} design rows for {responses} responses")]
    Shape {
        /// Design rows.
        rows: usize,
        /// Responses.
        responses: usize,
    },
}

/// A least-squares fit with its leave-one-out errors.
#[derive(Clone, Debug, PartialEq)]
pub struct LeastSquaresFit {
    /// Coefficients, one per column of the design.
    pub coeffs: Vec<f64>,
    /// Leave-one-out mean squared error.
    pub loo_mse: f64,
    /// Chapelle correction factor `T(P, N)`.
    pub correction: f64,
    /// Empirical variance of the responses (denominator N - 1).
    pub response_var: f64,
    /// A variance at or below this is rounding noise of constant responses
    /// ([`negligible_variance`]).
    pub negligible_var: f64,
    /// Leverages `h_i` (hat matrix diagonal).
    pub leverage: Vec<f64>,
}

impl LeastSquaresFit {
    /// Relative LOO error `loo_mse / Var(y)` (infinite when `Var(y) = 0` and the
    /// error is not). Serves the tests (the fits are compared by
    /// [`LeastSquaresFit::corrected_relative_loo`]).
    #[cfg(test)]
    pub(crate) fn relative_loo(&self) -> f64 {
        relative(self.loo_mse, self.response_var, self.negligible_var)
    }

    /// Corrected relative LOO error `T(P, N) loo_mse / Var(y)`.
    pub fn corrected_relative_loo(&self) -> f64 {
        relative(
            self.correction * self.loo_mse,
            self.response_var,
            self.negligible_var,
        )
    }
}

/// `err / var`; responses whose variance is rounding noise (`<= negligible`) count as
/// constant: relative error 0 when `err` is noise too, infinite otherwise.
pub(crate) fn relative(err: f64, var: f64, negligible: f64) -> f64 {
    if var > negligible {
        err / var
    } else if err <= negligible {
        0.0
    } else {
        f64::INFINITY
    }
}

/// The variance below which responses count as constant: `(64 eps max|y|)^2`, the rounding
/// noise of values of that size.
pub fn negligible_variance(y: &[f64]) -> f64 {
    let m = y.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    (64.0 * f64::EPSILON * m).powi(2)
}

/// Empirical variance (denominator `N - 1`; 0 for fewer than 2 values).
pub fn sample_variance(y: &[f64]) -> f64 {
    let n = y.len();
    if n < 2 {
        return 0.0;
    }
    let m = y.iter().sum::<f64>() / n as f64;
    y.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (n - 1) as f64
}

/// Least-squares fit of `y` on the columns of `psi` with LOO errors: [`LeastSquares`] for one
/// response. Serves the tests (the studies factor a design once for all its responses).
#[cfg(test)]
pub(crate) fn least_squares(
    psi: &DMatrix<f64>,
    y: &[f64],
) -> Result<LeastSquaresFit, RegressionError> {
    LeastSquares::new(psi)?.fit(y)
}

/// The QR factorisation of a design, with what the LOO error needs (leverages and the
/// correction factor): fits any number of responses on the same design, one factorisation.
#[derive(Clone, Debug)]
pub struct LeastSquares {
    psi: DMatrix<f64>,
    q: DMatrix<f64>,
    r: DMatrix<f64>,
    leverage: Vec<f64>,
    correction: f64,
}

impl LeastSquares {
    /// Factors `psi` (N rows, P columns): refused when `N < P` or the columns are
    /// (numerically) dependent.
    pub fn new(psi: &DMatrix<f64>) -> Result<LeastSquares, RegressionError> {
        let (n, p) = psi.shape();
        if n < p || p == 0 {
            return Err(RegressionError::Underdetermined {
                samples: n,
                terms: p,
            });
        }
        let qr = psi.clone().qr();
        let r = qr.r();
        let rmax = (0..p).map(|k| r[(k, k)].abs()).fold(0.0, f64::max);
        if let Some(column) =
            (0..p).find(|&k| r[(k, k)].abs() <= 1e-11 * rmax.max(f64::MIN_POSITIVE))
        {
            return Err(RegressionError::RankDeficient { column });
        }
        let q = qr.q();
        let leverage: Vec<f64> = (0..n).map(|i| q.row(i).norm_squared()).collect();
        // tr(C^-1) = N tr((Psi^T Psi)^-1) = N |R^-1|_F^2.
        let correction = if n > p {
            let rinv = r
                .clone()
                .try_inverse()
                .ok_or(RegressionError::RankDeficient { column: 0 })?;
            let tr = n as f64 * rinv.norm_squared();
            n as f64 / (n - p) as f64 * (1.0 + tr / n as f64)
        } else {
            f64::INFINITY
        };
        Ok(LeastSquares {
            psi: psi.clone(),
            q,
            r,
            leverage,
            correction,
        })
    }

    /// The fit of the response `y` (one value per row of the design).
    pub fn fit(&self, y: &[f64]) -> Result<LeastSquaresFit, RegressionError> {
        let n = self.psi.nrows();
        if y.len() != n {
            return Err(RegressionError::Shape {
                rows: n,
                responses: y.len(),
            });
        }
        let yv = DVector::from_column_slice(y);
        let qty = self.q.transpose() * &yv;
        let c = self
            .r
            .solve_upper_triangular(&qty)
            .ok_or(RegressionError::RankDeficient { column: 0 })?;
        let fitted = &self.psi * &c;
        let loo_mse = (0..n)
            .map(|i| {
                let h = self.leverage[i];
                let res = y[i] - fitted[i];
                if h >= 1.0 - 1e-12 {
                    if res == 0.0 {
                        0.0
                    } else {
                        f64::INFINITY
                    }
                } else {
                    (res / (1.0 - h)).powi(2)
                }
            })
            .sum::<f64>()
            / n as f64;
        Ok(LeastSquaresFit {
            coeffs: c.iter().copied().collect(),
            loo_mse,
            correction: self.correction,
            response_var: sample_variance(y),
            negligible_var: negligible_variance(y),
            leverage: self.leverage.clone(),
        })
    }
}

/// The sub-matrix of the given columns.
pub fn columns(psi: &DMatrix<f64>, cols: &[usize]) -> DMatrix<f64> {
    DMatrix::from_fn(psi.nrows(), cols.len(), |i, j| psi[(i, cols[j])])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::uq::rng::{stream, uniform_open01};

    fn random_design(n: usize, p: usize, seed: u64) -> DMatrix<f64> {
        let mut r = stream(seed, 0);
        DMatrix::from_fn(n, p, |_, _| 2.0 * uniform_open01(&mut r) - 1.0)
    }

    #[test]
    fn closed_form_loo_equals_brute_force_refits() {
        let (n, p) = (30, 6);
        let psi = random_design(n, p, 1);
        let mut r = stream(1, 1);
        let y: Vec<f64> = (0..n)
            .map(|i| psi[(i, 0)] * 2.0 - psi[(i, 3)] + 0.3 * (uniform_open01(&mut r) - 0.5))
            .collect();
        let fit = least_squares(&psi, &y).unwrap();
        // Brute force: drop row i, solve the normal equations, predict y_i.
        let mut mse = 0.0;
        for i in 0..n {
            let keep: Vec<usize> = (0..n).filter(|&k| k != i).collect();
            let a = DMatrix::from_fn(n - 1, p, |r, c| psi[(keep[r], c)]);
            let b = DVector::from_iterator(n - 1, keep.iter().map(|&k| y[k]));
            let c = (a.transpose() * &a)
                .lu()
                .solve(&(a.transpose() * b))
                .unwrap();
            let pred: f64 = (0..p).map(|j| psi[(i, j)] * c[j]).sum();
            mse += (y[i] - pred).powi(2);
        }
        mse /= n as f64;
        assert!(
            (fit.loo_mse / mse - 1.0).abs() < 1e-10,
            "{} vs {mse}",
            fit.loo_mse
        );
        // Chapelle factor from an explicit inverse of the Gram matrix.
        let gram_inv = (psi.transpose() * &psi).try_inverse().unwrap();
        let tr = n as f64 * gram_inv.trace();
        let t = n as f64 / (n - p) as f64 * (1.0 + tr / n as f64);
        assert!((fit.correction / t - 1.0).abs() < 1e-10);
        assert!(fit.corrected_relative_loo() > fit.relative_loo());
    }

    #[test]
    fn exact_data_is_fitted_exactly() {
        let psi = random_design(20, 4, 2);
        let truth = [1.0, -2.0, 0.5, 3.0];
        let y: Vec<f64> = (0..20)
            .map(|i| (0..4).map(|j| psi[(i, j)] * truth[j]).sum())
            .collect();
        let fit = least_squares(&psi, &y).unwrap();
        for (c, t) in fit.coeffs.iter().zip(truth) {
            assert!((c - t).abs() < 1e-13);
        }
        assert!(fit.relative_loo() < 1e-25);
    }

    #[test]
    fn underdetermined_and_rank_deficient_fits_are_typed_errors() {
        let psi = random_design(5, 8, 3);
        let err = least_squares(&psi, &[0.0; 5]).unwrap_err();
        assert_eq!(
            err,
            RegressionError::Underdetermined {
                samples: 5,
                terms: 8
            }
        );
        assert!(err.to_string().contains("sparse = true"));
        let mut psi = random_design(10, 3, 4);
        for i in 0..10 {
            psi[(i, 2)] = 2.0 * psi[(i, 0)];
        }
        assert!(matches!(
            least_squares(&psi, &[1.0; 10]),
            Err(RegressionError::RankDeficient { .. })
        ));
        assert!(least_squares(&random_design(10, 3, 5), &[1.0; 9]).is_err());
    }
}
