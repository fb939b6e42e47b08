//! The random inputs of a study: their marginal distributions and, when some are
//! correlated, the Gaussian copula (Nataf transformation) that joins them.
//!
//! Designs are built in an *independent* standard space ([`Germ`]); [`RandomInputs::to_physical`]
//! is the map from a design point to the inputs' values:
//! - an uncorrelated input takes its own isoprobabilistic (or Askey) map of its coordinate;
//! - correlated inputs take the standard-normal scores `u` of their coordinates
//!   ([`Distribution::normal_score`]), correlate them, `z = L u` (`R_z = L L^T` the
//!   normal-space correlation solved by [`GaussianCopula`] so that the *physical* Pearson
//!   correlations are the requested ones), and map `z_i` through `F_i^-1(Phi(.))`.
//!
//! [`Distribution::normal_score`]: crate::uq::distributions::Distribution::normal_score
//!
//! So every method that maps its points through [`RandomInputs::to_physical`] (all do, through
//! [`crate::uq::method::Design::mapped`]) honours the correlation, and a chaos built on the
//! design's coordinates is a chaos in independent germs.

use std::ops::Deref;

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

use crate::uq::distributions::{Germ, RandomParameter};
use crate::uq::hd::copula::{CopulaError, GaussianCopula};

/// A requested correlation between two inputs (`[[correlation]]` of a study file).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CorrelationPair {
    /// The two inputs, by name.
    pub between: [String; 2],
    /// Pearson correlation of their physical values.
    pub rho: f64,
}

/// Why a correlation is refused.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CorrelationError {
    /// A name that is not a random input.
    #[error("correlation between '{0}' and '{1}': '{2}' is not a random parameter")]
    UnknownName(String, String, String),
    /// An input correlated with itself.
    #[error("correlation of '{0}' with itself")]
    SameInput(String),
    /// A pair given twice.
    #[error("the correlation between '{0}' and '{1}' is given twice")]
    Repeated(String, String),
    /// A coefficient outside (-1, 1).
    #[error("correlation between '{0}' and '{1}': rho = {2} must lie strictly between -1 and 1")]
    OutOfRange(String, String, f64),
    /// A discrete input cannot be correlated by a Gaussian copula.
    #[error(
        "'{0}' is an integer_uniform input; a Gaussian copula correlates continuous inputs only"
    )]
    Discrete(String),
    /// The copula could not be built (not positive definite, not attainable).
    #[error("{0}")]
    Copula(String),
}

/// Correlated inputs: the requested pairs and the copula solved from them.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Correlation {
    /// The pairs as requested.
    pub pairs: Vec<CorrelationPair>,
    /// The normal-space correlation matrix `R_z` (one row per input, study order).
    #[serde(serialize_with = "rows")]
    pub normal_correlation: DMatrix<f64>,
    /// Lower Cholesky factor `L` of `R_z`.
    #[serde(skip)]
    pub cholesky: DMatrix<f64>,
    /// Whether each input is in some pair.
    #[serde(skip)]
    pub correlated: Vec<bool>,
}

fn rows<S: serde::Serializer>(m: &DMatrix<f64>, s: S) -> Result<S::Ok, S::Error> {
    let v: Vec<Vec<f64>> = m.row_iter().map(|r| r.iter().copied().collect()).collect();
    v.serialize(s)
}

impl Correlation {
    /// The copula of `parameters` with the requested `pairs`; `None` for no pairs.
    pub fn new(
        parameters: &[RandomParameter],
        pairs: Vec<CorrelationPair>,
    ) -> Result<Option<Correlation>, CorrelationError> {
        if pairs.is_empty() {
            return Ok(None);
        }
        let d = parameters.len();
        let index = |name: &str, p: &CorrelationPair| {
            parameters
                .iter()
                .position(|q| q.name == name)
                .ok_or_else(|| {
                    CorrelationError::UnknownName(
                        p.between[0].clone(),
                        p.between[1].clone(),
                        name.to_owned(),
                    )
                })
        };
        let mut target = DMatrix::<f64>::identity(d, d);
        let mut correlated = vec![false; d];
        for p in &pairs {
            let (i, j) = (index(&p.between[0], p)?, index(&p.between[1], p)?);
            if i == j {
                return Err(CorrelationError::SameInput(p.between[0].clone()));
            }
            if target[(i, j)] != 0.0 {
                return Err(CorrelationError::Repeated(
                    p.between[0].clone(),
                    p.between[1].clone(),
                ));
            }
            if !(p.rho > -1.0 && p.rho < 1.0) {
                return Err(CorrelationError::OutOfRange(
                    p.between[0].clone(),
                    p.between[1].clone(),
                    p.rho,
                ));
            }
            for k in [i, j] {
                if parameters[k].distribution.is_discrete() {
                    return Err(CorrelationError::Discrete(parameters[k].name.clone()));
                }
                correlated[k] = true;
            }
            // A zero coefficient is a pair too (kept so that repeats are caught).
            target[(i, j)] = p.rho;
            target[(j, i)] = p.rho;
        }
        let marginals = parameters.iter().map(|p| p.distribution.clone()).collect();
        let copula = GaussianCopula::new(marginals, &target).map_err(|e| {
            CorrelationError::Copula(match e {
                CopulaError::NotAttainable { i, j, rho, lo, hi } => format!(
                    "correlation {rho} between '{}' and '{}' cannot be reached with their \
                     distributions through a Gaussian copula (attainable {lo:.4} to {hi:.4})",
                    parameters[i].name, parameters[j].name
                ),
                other => format!(
                    "{other} (inputs in study order: {})",
                    parameters
                        .iter()
                        .map(|p| p.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            })
        })?;
        Ok(Some(Correlation {
            pairs,
            normal_correlation: copula.normal_correlation().clone(),
            cholesky: copula.cholesky().clone(),
            correlated,
        }))
    }
}

/// The random inputs of a study (marginals in study order) and their correlation.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RandomInputs {
    /// The random parameters.
    pub parameters: Vec<RandomParameter>,
    /// The Gaussian copula of correlated inputs, if any.
    pub correlation: Option<Correlation>,
}

impl Deref for RandomInputs {
    type Target = [RandomParameter];

    fn deref(&self) -> &[RandomParameter] {
        &self.parameters
    }
}

impl RandomInputs {
    /// Independent inputs.
    pub fn independent(parameters: Vec<RandomParameter>) -> RandomInputs {
        RandomInputs {
            parameters,
            correlation: None,
        }
    }

    /// The physical values of the design point `t` (one coordinate per input) of the
    /// independent standard space `germ`.
    pub fn to_physical(&self, germ: Germ, t: &[f64]) -> Vec<f64> {
        let mut x: Vec<f64> = self
            .parameters
            .iter()
            .zip(t)
            .map(|(p, &ti)| p.distribution.from_germ(germ, ti))
            .collect();
        if let Some(c) = &self.correlation {
            let u: Vec<f64> = self
                .parameters
                .iter()
                .zip(t)
                .zip(&c.correlated)
                .map(|((p, &ti), &cor)| {
                    if cor {
                        p.distribution.normal_score(germ, ti)
                    } else {
                        0.0
                    }
                })
                .collect();
            for (i, p) in self.parameters.iter().enumerate() {
                if c.correlated[i] {
                    let z: f64 = (0..=i).map(|k| c.cholesky[(i, k)] * u[k]).sum();
                    x[i] = p.distribution.from_standard_normal(z);
                }
            }
        }
        x
    }

    /// The importance of each input at a design point whose unit direction in the independent
    /// standard normal space is `alpha`: `gamma_i^2` (sum 1), with
    /// `gamma = L^-T alpha / |L^-T alpha|` and `L` the Cholesky factor of the normal-space
    /// correlation (Der Kiureghian 2005, the importance vector: `alpha^T J_{u,x} D`, where
    /// the marginal maps' slopes cancel). With independent inputs `gamma = alpha` exactly.
    /// Unlike `alpha_i^2`, which credits an input with what it shares with the inputs before
    /// it, `gamma_i^2` ranks the inputs themselves: for a linear quantity of correlated
    /// normal inputs `gamma_i` is proportional to `c_i sigma_i`, whatever the correlation.
    pub(crate) fn importance(&self, alpha: &[f64]) -> Vec<f64> {
        let Some(c) = &self.correlation else {
            return alpha.iter().map(|a| a * a).collect();
        };
        // L^T w = alpha; L has a positive diagonal (the Cholesky factor of a positive definite
        // matrix), so the solve exists.
        let w = c
            .cholesky
            .tr_solve_lower_triangular(&DVector::from_column_slice(alpha))
            .expect("a Cholesky factor has a positive diagonal");
        let n2 = w.norm_squared();
        w.iter().map(|v| v * v / n2).collect()
    }

    /// The design coordinates in `germ` of the physical values `x` (the inverse of
    /// [`RandomInputs::to_physical`]).
    pub fn to_germ(&self, germ: Germ, x: &[f64]) -> Vec<f64> {
        let mut t: Vec<f64> = self
            .parameters
            .iter()
            .zip(x)
            .map(|(p, &xi)| p.distribution.to_germ(germ, xi))
            .collect();
        if let Some(c) = &self.correlation {
            // z_i = Phi^-1(F_i(x_i)); u = L^-1 z (forward substitution); t_i = G^-1(Phi(u_i)).
            let d = self.parameters.len();
            let mut u = vec![0.0; d];
            for i in 0..d {
                if !c.correlated[i] {
                    continue;
                }
                let p = &self.parameters[i].distribution;
                let z = p.to_germ(Germ::Normal, x[i]);
                let s: f64 = (0..i).map(|k| c.cholesky[(i, k)] * u[k]).sum();
                u[i] = (z - s) / c.cholesky[(i, i)];
                let law_value = p.from_standard_normal(u[i]);
                t[i] = match germ {
                    Germ::Normal => u[i],
                    _ => p.to_germ(germ, law_value),
                };
            }
        }
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::uq::distributions::Distribution;

    fn params() -> Vec<RandomParameter> {
        [
            ("a", Distribution::normal(10.0, 2.0).unwrap()),
            ("b", Distribution::gamma(2.0, 1.5).unwrap()),
            ("c", Distribution::uniform(-1.0, 3.0).unwrap()),
        ]
        .into_iter()
        .map(|(n, d)| RandomParameter::new(n, d))
        .collect()
    }

    fn pair(a: &str, b: &str, rho: f64) -> CorrelationPair {
        CorrelationPair {
            between: [a.into(), b.into()],
            rho,
        }
    }

    #[test]
    fn uncorrelated_inputs_keep_their_own_maps_and_round_trip() {
        let c = Correlation::new(&params(), vec![pair("a", "b", 0.6)])
            .unwrap()
            .unwrap();
        assert_eq!(c.correlated, vec![true, true, false]);
        let inputs = RandomInputs {
            parameters: params(),
            correlation: Some(c),
        };
        for germ in [Germ::Normal, Germ::Uniform, Germ::Askey] {
            let t = match germ {
                Germ::Uniform => vec![0.3, 0.8, 0.1],
                Germ::Askey => vec![0.4, 1.7, -0.6],
                Germ::Normal => vec![-0.7, 0.9, 1.1],
            };
            let x = inputs.to_physical(germ, &t);
            // The uncorrelated input maps alone.
            assert_eq!(x[2], params()[2].distribution.from_germ(germ, t[2]));
            let back = inputs.to_germ(germ, &x);
            for (a, b) in t.iter().zip(&back) {
                assert!((a - b).abs() < 1e-9, "{germ:?}: {t:?} -> {x:?} -> {back:?}");
            }
        }
    }

    #[test]
    fn bad_correlations_are_refused_by_name() {
        let p = params();
        let e = Correlation::new(&p, vec![pair("a", "zz", 0.5)]).unwrap_err();
        assert!(
            e.to_string().contains("'zz' is not a random parameter"),
            "{e}"
        );
        assert!(matches!(
            Correlation::new(&p, vec![pair("a", "a", 0.5)]),
            Err(CorrelationError::SameInput(_))
        ));
        assert!(matches!(
            Correlation::new(&p, vec![pair("a", "b", 0.5), pair("b", "a", 0.1)]),
            Err(CorrelationError::Repeated(..))
        ));
        assert!(matches!(
            Correlation::new(&p, vec![pair("a", "b", 1.0)]),
            Err(CorrelationError::OutOfRange(..))
        ));
        let e = Correlation::new(
            &p,
            vec![
                pair("a", "b", 0.9),
                pair("b", "c", 0.9),
                pair("a", "c", -0.9),
            ],
        )
        .unwrap_err();
        assert!(e.to_string().contains("not positive definite"), "{e}");
        assert!(e.to_string().contains("a, b, c"), "{e}");
        let mut q = params();
        q[2].distribution = Distribution::integer_uniform(1, 4).unwrap();
        assert!(matches!(
            Correlation::new(&q, vec![pair("a", "c", 0.2)]),
            Err(CorrelationError::Discrete(_))
        ));
        assert_eq!(Correlation::new(&p, vec![]), Ok(None));
    }
}
