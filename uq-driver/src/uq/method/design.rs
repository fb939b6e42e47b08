//! The points of a sampling method: coordinates in a standard space, physical values and,
//! for quadrature designs, weights.

use serde::Serialize;

use super::error::MethodError;
use crate::uq::distributions::Germ;
use crate::uq::pce::Family;
use crate::uq::random_inputs::RandomInputs;

/// Where a [`Sampling`](super::Sampling) method runs the model.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Design {
    /// The (independent) standard space of `points`.
    pub germ: Germ,
    /// Coordinates of each point in the standard space, one per random parameter.
    pub points: Vec<Vec<f64>>,
    /// Physical parameter values of each point, in the order of the study's parameters.
    pub values: Vec<Vec<f64>>,
    /// Quadrature weights summing to one (collocation); `None` for equally weighted samples.
    /// A weighted design never drops a point: each failure stops the study.
    pub weights: Option<Vec<f64>>,
    /// Notes for the user (e.g. points where a Gaussian stiffness is negative).
    pub warnings: Vec<String>,
    /// The inputs `points` are mapped to ([`RandomInputs::to_physical`]): marginals and copula.
    pub inputs: RandomInputs,
}

impl Design {
    /// A design whose values are the images of `points` under the inputs' map from `germ`
    /// ([`RandomInputs::to_physical`]: each input's isoprobabilistic map, correlated through the
    /// copula where the study correlates inputs), with a warning per parameter that reaches
    /// non-positive values although its mean is positive.
    pub fn mapped(
        germ: Germ,
        points: Vec<Vec<f64>>,
        weights: Option<Vec<f64>>,
        inputs: &RandomInputs,
    ) -> Design {
        let values = points.iter().map(|t| inputs.to_physical(germ, t)).collect();
        let mut design = Design {
            germ,
            points,
            values,
            weights,
            warnings: Vec::new(),
            inputs: inputs.clone(),
        };
        design.warnings = design.sign_warnings();
        design
    }

    /// The orthonormal family of each coordinate of the standard space (Hermite for a
    /// normal germ, the input's Askey family or Hermite for Askey germs); `None` for the
    /// unit cube of sampling designs.
    pub fn families(&self) -> Option<Vec<Family>> {
        match self.germ {
            Germ::Normal => Some(vec![Family::Hermite; self.inputs.len()]),
            Germ::Askey => Some(
                self.inputs
                    .iter()
                    .map(|p| Family::of(&p.distribution).unwrap_or(Family::Hermite))
                    .collect(),
            ),
            Germ::Uniform => None,
        }
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.values.len()
    }

    /// Whether there are no points.
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }

    /// Whether the points carry quadrature weights (then none may be dropped).
    pub fn is_weighted(&self) -> bool {
        self.weights.is_some()
    }

    /// The weights, if every point has a result (`rows`: the points with one); an estimator
    /// of a weighted design cannot leave a point out.
    pub fn complete_weights(&self, rows: &[usize]) -> Result<&[f64], MethodError> {
        match &self.weights {
            Some(w) if rows.len() == self.len() && w.len() == self.len() => Ok(w),
            _ => Err(MethodError::MissingPoints {
                missing: self.len().saturating_sub(rows.len()),
                total: self.len(),
            }),
        }
    }

    /// One warning per positive-mean parameter that some points set to a value <= 0, with the
    /// probability weight of those points.
    fn sign_warnings(&self) -> Vec<String> {
        let mut warnings = Vec::new();
        for (j, p) in self.inputs.iter().enumerate() {
            if p.distribution.mean() <= 0.0 {
                continue;
            }
            let neg: Vec<usize> = (0..self.len())
                .filter(|&i| self.values[i][j] <= 0.0)
                .collect();
            if neg.is_empty() {
                continue;
            }
            let weight: f64 = match &self.weights {
                Some(w) => neg.iter().map(|&i| w[i]).sum(),
                None => neg.len() as f64 / self.len() as f64,
            };
            warnings.push(format!(
                "{} of {} points have {} <= 0 (a positive-mean Gaussian reaches negative values in its tail; \
                 probability weight {:.3e}); they are run, not dropped — consider a lognormal or truncated_normal input",
                neg.len(),
                self.len(),
                p.name,
                weight
            ));
        }
        warnings
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::uq::{Distribution, RandomParameter};

    #[test]
    fn negative_values_of_a_positive_parameter_are_reported_with_their_weight() {
        let params = RandomInputs::independent(vec![RandomParameter {
            name: "k".into(),
            distribution: Distribution::normal(1.0, 1.0).unwrap(),
        }]);
        // z = -2 maps to k = -1; weight 0.25.
        let d = Design::mapped(
            Germ::Normal,
            vec![vec![-2.0], vec![0.0], vec![2.0]],
            Some(vec![0.25, 0.5, 0.25]),
            &params,
        );
        assert_eq!(d.values, vec![vec![-1.0], vec![1.0], vec![3.0]]);
        assert_eq!(d.warnings.len(), 1);
        assert!(d.warnings[0].starts_with("1 of 3 points have k <= 0"));
        assert!(d.warnings[0].contains("2.500e-1"), "{}", d.warnings[0]);
        let u = Design::mapped(Germ::Uniform, vec![vec![0.5]], None, &params);
        assert_eq!(u.values, vec![vec![1.0]]);
        assert!(u.warnings.is_empty());
    }
}
