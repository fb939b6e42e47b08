//! The points of a sampling method: coordinates in a standard space, physical values and,
//! for quadrature designs, weights.

use nalgebra::DMatrix;
use serde::Serialize;

use super::error::MethodError;
use crate::uq::distributions::Germ;
use crate::uq::pce::Family;
use crate::uq::random_inputs::RandomInputs;
use crate::uq::Distribution;

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
    /// copula where the study correlates inputs). Which inputs must stay positive is not known
    /// here (the FMU says it): the study reports those that reach values <= 0.
    pub fn mapped(
        germ: Germ,
        points: Vec<Vec<f64>>,
        weights: Option<Vec<f64>>,
        inputs: &RandomInputs,
    ) -> Design {
        let values = points.iter().map(|t| inputs.to_physical(germ, t)).collect();
        Design {
            germ,
            points,
            values,
            weights,
            warnings: Vec::new(),
            inputs: inputs.clone(),
        }
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

    /// Checks that results fit this design: `rows` distinct points of the design, one row of
    /// `data` per entry of `rows`.
    pub fn check_results(&self, rows: &[usize], data: &DMatrix<f64>) -> Result<(), MethodError> {
        if rows.len() != data.nrows() {
            return Err(MethodError::ResultsMismatch(format!(
                "{} rows named but data has {} rows (one row of data per entry of `rows`)",
                rows.len(),
                data.nrows()
            )));
        }
        let mut seen = vec![false; self.len()];
        for &r in rows {
            match seen.get_mut(r) {
                None => {
                    return Err(MethodError::ResultsMismatch(format!(
                        "row {r} is not a point of the design (it has {} points, 0 to {})",
                        self.len(),
                        self.len().saturating_sub(1)
                    )))
                }
                Some(true) => {
                    return Err(MethodError::ResultsMismatch(format!(
                        "point {r} of the design is given twice in `rows`"
                    )))
                }
                Some(s) => *s = true,
            }
        }
        Ok(())
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

    /// One warning per positive-mean normal parameter that must stay positive (`positive(j)`
    /// for the `j`-th input: the caller knows, e.g. from the FMU's declared minimum or unit)
    /// and that some points set to a value <= 0, with the probability weight of those points.
    /// Only a normal input warns: its support (the whole real line) was not chosen by the
    /// user, whereas every other family's support is declared (bounds, or positive by
    /// construction), so values <= 0 there are intended.
    pub(crate) fn sign_warnings(&self, positive: impl Fn(usize) -> bool) -> Vec<String> {
        let mut warnings = Vec::new();
        for (j, p) in self.inputs.iter().enumerate() {
            if !positive(j) {
                continue;
            }
            let Distribution::Normal { mean, .. } = p.distribution else {
                continue;
            };
            if mean <= 0.0 {
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
                 probability weight {:.3e}); they are run as drawn (any that fail count as failed points) \
                 — consider a lognormal or truncated_normal input",
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
    use crate::uq::RandomParameter;

    #[test]
    fn negative_values_of_a_positive_parameter_are_reported_with_their_weight() {
        let params = RandomInputs::independent(vec![RandomParameter::new(
            "k",
            Distribution::normal(1.0, 1.0).unwrap(),
        )]);
        // z = -2 maps to k = -1; weight 0.25.
        let d = Design::mapped(
            Germ::Normal,
            vec![vec![-2.0], vec![0.0], vec![2.0]],
            Some(vec![0.25, 0.5, 0.25]),
            &params,
        );
        assert_eq!(d.values, vec![vec![-1.0], vec![1.0], vec![3.0]]);
        let w = d.sign_warnings(|_| true);
        assert_eq!(w.len(), 1);
        assert!(w[0].starts_with("1 of 3 points have k <= 0"));
        assert!(w[0].contains("2.500e-1"), "{}", w[0]);
        assert!(d.sign_warnings(|_| false).is_empty());
        let u = Design::mapped(Germ::Uniform, vec![vec![0.5]], None, &params);
        assert_eq!(u.values, vec![vec![1.0]]);
        assert!(u.sign_warnings(|_| true).is_empty());
    }

    /// The "positive-mean Gaussian" warning fired for uniform [−1, 2], a normal truncated
    /// at −0.5 and integers −2..5, whose declared support includes x <= 0 by the user's choice.
    #[test]
    fn sign_warning_only_for_normal_inputs_not_for_families_whose_support_includes_zero() {
        let families = [
            Distribution::uniform(-1.0, 2.0).unwrap(),
            Distribution::truncated_normal(1.0, 1.0, -0.5, f64::INFINITY).unwrap(),
            Distribution::integer_uniform(-2, 5).unwrap(),
        ];
        // Unit-cube points 0.05, 0.5, 0.95: the first maps to x < 0 in every family
        // (uniform: −1 + 3·0.05 = −0.85; truncated normal: just above −0.5; integers: −2).
        let cube = vec![vec![0.05], vec![0.5], vec![0.95]];
        for d in families {
            assert!(d.mean() > 0.0, "{d:?}");
            let inputs = RandomInputs::independent(vec![RandomParameter::new("a", d.clone())]);
            let design = Design::mapped(Germ::Uniform, cube.clone(), None, &inputs);
            assert!(design.values[0][0] <= 0.0, "{d:?}: {:?}", design.values);
            let w = design.sign_warnings(|_| true);
            assert!(w.is_empty(), "{d:?}: {w:?}");
        }
        // A normal input still warns, and its text no longer claims that failed points are run.
        let normal = RandomInputs::independent(vec![RandomParameter::new(
            "k",
            Distribution::normal(1.0, 1.0).unwrap(),
        )]);
        let d = Design::mapped(Germ::Uniform, cube, None, &normal);
        let w = d.sign_warnings(|_| true);
        assert_eq!(w.len(), 1);
        assert!(w[0].starts_with("1 of 3 points have k <= 0"));
        assert!(!w[0].contains("not dropped"), "{}", w[0]);
    }
}
