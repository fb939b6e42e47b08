//! Regression chaos with degree adaptivity: for each total degree `p` in a range, the
//! hyperbolic (q-norm) basis of that degree is fitted by hybrid LARS (sparse), and the
//! degree with the smallest corrected relative leave-one-out error is kept (as UQLab and OpenTURNS do). Scanning stops after two
//! degrees in a row without improvement.
//!
//! Points are given in germ space (see [`crate::uq::pce::askey`]): one coordinate per input, in
//! the germ of that input's family.

use std::ops::RangeInclusive;
use std::sync::{Arc, OnceLock};

use nalgebra::DMatrix;

use super::lars::{sparse_regression_on, PathDesign, PathKind, SupportCache};
use super::regression::RegressionError;
use crate::uq::pce::askey::Family;
use crate::uq::pce::basis::{Basis, BasisError, ChaosStats, MultiIndexSet};
use crate::uq::pce::{Pce, PceError};

/// Errors of the chaos fit.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ChaosFitError {
    /// Basis construction failed.
    #[error(transparent)]
    Basis(#[from] BasisError),
    /// Every degree failed; the error of the lowest degree.
    #[error(transparent)]
    Regression(#[from] RegressionError),
    /// The fitted coefficients do not match the basis.
    #[error(transparent)]
    Chaos(#[from] PceError),
    /// Empty degree range or no points.
    #[error("a chaos fit needs points and a non-empty degree range")]
    Empty,
}

/// How the coefficients are fitted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FitKind {
    /// Sparse: the path algorithm, then selection by corrected LOO.
    Sparse(PathKind),
}

/// A fitted chaos.
#[derive(Clone, Debug, PartialEq)]
pub struct ChaosFit {
    /// The chaos (one column), on the selected basis (only the retained terms for a sparse
    /// fit).
    pub pce: Pce,
    /// Corrected relative leave-one-out error of the selected model.
    pub loo: f64,
    /// Selected total degree.
    pub degree: usize,
    /// `(degree, corrected relative LOO)` for every degree tried.
    pub tried: Vec<(usize, f64)>,
}

impl ChaosFit {
    /// Mean, variance and Sobol' indices.
    pub fn stats(&self) -> ChaosStats {
        self.pce.stats(0)
    }

    /// Evaluates the chaos at a germ point. Serves the tests.
    #[cfg(test)]
    pub(crate) fn eval(&self, t: &[f64]) -> f64 {
        self.pce.eval_column(0, t)
    }
}

/// Fits `y` at germ points `points` with degree adaptivity over `degrees`.
pub fn fit_chaos(
    families: &[Family],
    points: &[Vec<f64>],
    y: &[f64],
    degrees: RangeInclusive<usize>,
    q: f64,
    kind: FitKind,
) -> Result<ChaosFit, ChaosFitError> {
    Candidates::new(families, points, degrees, q)?.fit(y, kind)
}

/// The candidate bases of a degree-adaptive fit with their design matrices, built once for
/// any number of responses at the same points.
#[derive(Clone, Debug)]
pub struct Candidates {
    /// `(degree, basis, design matrix)` by increasing degree.
    levels: Vec<(usize, Basis, DMatrix<f64>)>,
    /// Per degree, what every sparse fit needs of the design (built by the first one) and the
    /// refits shared between responses.
    sparse: Vec<(OnceLock<PathDesign>, Arc<SupportCache>)>,
    families: Vec<Family>,
}

impl Candidates {
    /// The hyperbolic (q-norm) bases of every degree in `degrees` at `points`.
    pub fn new(
        families: &[Family],
        points: &[Vec<f64>],
        degrees: RangeInclusive<usize>,
        q: f64,
    ) -> Result<Candidates, ChaosFitError> {
        if points.is_empty() || degrees.is_empty() {
            return Err(ChaosFitError::Empty);
        }
        let d = families.len();
        let levels: Vec<(usize, Basis, DMatrix<f64>)> = degrees
            .map(|p| {
                let set = MultiIndexSet::hyperbolic(d, p, q)?;
                let basis = Basis::new(families.to_vec(), set)?;
                let psi = basis.design_matrix(points);
                Ok((p, basis, psi))
            })
            .collect::<Result<_, ChaosFitError>>()?;
        Ok(Candidates {
            sparse: levels.iter().map(|_| Default::default()).collect(),
            levels,
            families: families.to_vec(),
        })
    }

    /// Fits `y` (one value per point): each degree in turn, keeping the smallest corrected
    /// relative LOO error; stops after two degrees in a row without improvement, or at the
    /// first degree that cannot be fitted (the error of the first degree is returned when
    /// none fits).
    pub fn fit(&self, y: &[f64], kind: FitKind) -> Result<ChaosFit, ChaosFitError> {
        let mut best: Option<ChaosFit> = None;
        let mut tried = Vec::new();
        let mut first_err = None;
        let mut worse = 0;
        let FitKind::Sparse(path) = kind;
        for ((p, basis, psi), (design, cache)) in self.levels.iter().zip(&self.sparse) {
            let design = design.get_or_init(|| PathDesign::new(psi, Some(0)));
            let result = sparse_regression_on(design, psi, y, path, Some(cache)).map(|f| {
                let loo = f.fit.corrected_relative_loo();
                let sub = basis.set().select(&f.columns).expect("distinct columns");
                let b = Basis::new(self.families.clone(), sub).expect("same families");
                (b, f.fit.coeffs, loo)
            });
            let (b, coeffs, loo) = match result {
                Ok(r) => r,
                Err(e) => {
                    first_err.get_or_insert(e);
                    break;
                }
            };
            tried.push((*p, loo));
            let improves = match &best {
                None => true,
                Some(b) => loo < b.loo,
            };
            if improves {
                let n = coeffs.len();
                best = Some(ChaosFit {
                    pce: Pce::new(b, DMatrix::from_vec(n, 1, coeffs))?,
                    loo,
                    degree: *p,
                    tried: vec![],
                });
                worse = 0;
            } else {
                worse += 1;
                if worse >= 2 {
                    break;
                }
            }
        }
        match best {
            Some(mut b) => {
                b.tried = tried;
                Ok(b)
            }
            None => Err(first_err.map_or(ChaosFitError::Empty, ChaosFitError::Regression)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::uq::hd::sobol_seq::Sobol;

    #[test]
    fn degree_adaptivity_finds_the_degree_of_a_polynomial() {
        // f = t1^3 - 2 t1 t2 + 0.5 t2^2 on U(-1,1)^2: degree 3.
        let pts: Vec<Vec<f64>> = Sobol::scrambled(2, 1, 0)
            .unwrap()
            .points(0, 64)
            .unwrap()
            .into_iter()
            .map(|p| p.iter().map(|u| 2.0 * u - 1.0).collect())
            .collect();
        let y: Vec<f64> = pts
            .iter()
            .map(|t| t[0].powi(3) - 2.0 * t[0] * t[1] + 0.5 * t[1] * t[1])
            .collect();
        let kind = FitKind::Sparse(PathKind::Lars);
        let fit = fit_chaos(&[Family::Legendre; 2], &pts, &y, 1..=6, 1.0, kind).unwrap();
        assert_eq!(fit.degree, 3, "{:?}", fit.tried);
        assert!(fit.loo < 1e-20);
        // Mean: E[t1^3] - 2 E[t1 t2] + 0.5 E[t2^2] = 1/6.
        assert!((fit.stats().mean - 1.0 / 6.0).abs() < 1e-13);
        assert!((fit.eval(&[0.3, -0.4]) - (0.027 + 0.24 + 0.08)).abs() < 1e-12);
    }
}
