//! What the polynomial-chaos methods (SCM, sparse grids, regression chaos) share: the choice
//! of the chaos basis (`chaos = "askey" | "hermite"`) and the refusal of discrete inputs.

use serde::{Deserialize, Serialize};

use super::error::InvalidSettings;
use super::estimate::{ChaosError, ChaosErrorKind};
use super::traits::Problem;
use crate::uq::distributions::{Germ, RandomParameter};
use crate::uq::pce::{Family, Pce};

/// `chaos = "askey" | "hermite"` of a chaos method's `[method]` table.
///
/// - `askey` (default): each input expanded in the family of its own law in the Askey
///   scheme, through an affine map: Hermite for a normal input, Legendre for a uniform one,
///   Jacobi for a Beta input, Laguerre for a Gamma input; the others (log-normal, truncated
///   normal, Weibull) through the isoprobabilistic map to a standard normal (Hermite);
/// - `hermite`: every input through the isoprobabilistic map to a standard normal, one
///   Hermite chaos (the paper's stochastic collocation; `kind = "scm"` follows `askey` by
///   default too).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ChaosBasis {
    /// The Askey family of each input (default).
    #[default]
    Askey,
    /// Hermite for every input, through the normal map.
    Hermite,
}

impl ChaosBasis {
    /// Whether this is the default, [`ChaosBasis::Askey`].
    pub fn is_askey(&self) -> bool {
        *self == ChaosBasis::Askey
    }

    /// Whether some input has an Askey family of its own other than Hermite (uniform,
    /// Beta, Gamma): there the `askey` and `hermite` designs differ.
    pub fn some_own_family(parameters: &[RandomParameter]) -> bool {
        ChaosBasis::Askey
            .families(parameters)
            .iter()
            .any(|f| *f != Family::Hermite)
    }

    /// The germ family of each input: its own Askey family (Hermite where it has none, the
    /// input then mapped through the normal), or Hermite for all.
    pub fn families(self, parameters: &[RandomParameter]) -> Vec<Family> {
        parameters
            .iter()
            .map(|p| match self {
                ChaosBasis::Hermite => Family::Hermite,
                ChaosBasis::Askey => Family::of(&p.distribution).unwrap_or(Family::Hermite),
            })
            .collect()
    }

    /// The standard space designs are built in.
    pub fn germ(self) -> Germ {
        match self {
            ChaosBasis::Askey => Germ::Askey,
            ChaosBasis::Hermite => Germ::Normal,
        }
    }
}

/// Refuses discrete inputs: a polynomial chaos needs continuous inputs (an integer input
/// takes a handful of values; a polynomial in it is fitted to steps).
pub(crate) fn continuous_inputs(problem: &Problem, kind: &str) -> Result<(), InvalidSettings> {
    match problem
        .parameters
        .iter()
        .find(|p| p.distribution.is_discrete())
    {
        Some(p) => Err(InvalidSettings(format!(
            "'{}' is an integer_uniform input, which a polynomial chaos ({kind}) cannot expand; \
             use a sampling method (mc, lhs, qmc) for discrete inputs",
            p.name
        ))),
        None => Ok(()),
    }
}

/// The order difference of a total-order chaos: per column, the variance share of its
/// terms of the highest degree `p` (the mean-square difference between the order-`p` chaos
/// and its order-`p - 1` truncation, relative to the variance; 0 without variance). `None`
/// for order 0.
pub(crate) fn order_difference(pce: &Pce) -> Option<ChaosError> {
    let p = pce.set().order();
    if p == 0 {
        return None;
    }
    let top: Vec<bool> = pce
        .set()
        .indices()
        .iter()
        .map(|k| k.iter().sum::<usize>() == p)
        .collect();
    let means = pce.mean();
    let values = (0..pce.outputs())
        .map(|col| {
            let c = pce.coeffs.column(col);
            let var: f64 = pce
                .set()
                .indices()
                .iter()
                .zip(c.iter())
                .filter(|(k, _)| k.iter().any(|&x| x > 0))
                .map(|(_, v)| v * v)
                .sum();
            let high: f64 = top
                .iter()
                .zip(c.iter())
                .filter(|(t, _)| **t)
                .map(|(_, v)| v * v)
                .sum();
            let mean = means[col];
            // A variance at the rounding level of the mean (a constant output) counts as none.
            if var > (64.0 * f64::EPSILON * mean).powi(2) {
                high / var
            } else {
                0.0
            }
        })
        .collect();
    Some(ChaosError {
        kind: ChaosErrorKind::OrderDifference,
        values,
        check: None,
    })
}
