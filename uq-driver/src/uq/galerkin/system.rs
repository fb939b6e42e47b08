//! The `[system]` table of a study file: a linear second-order system whose matrices (and
//! initial conditions) depend affinely on Gaussian parameters, read into a [`LinearSystem`].

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

use super::{Affine, LinearSystem, Waveform};
use crate::uq::distributions::{Distribution, RandomParameter};

/// A `[system]` that does not describe a valid system for the study's parameters.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct InvalidSystem(pub String);

/// `[system]`: `M q'' + C q' + K q = f`, each matrix affine in the random parameters:
/// `A = A_given + Σ_j p_j · D_j` for each `[[system.dependence]]` (p_j Gaussian).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SystemSpec {
    /// DOF names (outputs refer to them; `<name>_dot` is the velocity).
    pub dofs: Vec<String>,
    /// Mass matrix (constant part), n × n.
    #[serde(rename = "M")]
    pub m: Vec<Vec<f64>>,
    /// Damping matrix (constant part).
    #[serde(rename = "C")]
    pub c: Vec<Vec<f64>>,
    /// Stiffness matrix (constant part).
    #[serde(rename = "K")]
    pub k: Vec<Vec<f64>>,
    /// Initial displacement (constant part).
    pub q0: Vec<f64>,
    /// Initial velocity (constant part; default zeros).
    #[serde(default)]
    pub v0: Vec<f64>,
    /// Constant load vector (default zeros).
    #[serde(default)]
    pub force: Vec<f64>,
    /// Largest RK4 step of the Galerkin system (s).
    #[serde(default = "default_step")]
    pub step: f64,
    /// How the random parameters enter.
    #[serde(default)]
    pub dependence: Vec<Dependence>,
}

fn default_step() -> f64 {
    1e-3
}

/// `matrix += parameter · d`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Dependence {
    /// Name of a random parameter.
    pub parameter: String,
    /// Which part of the system it enters.
    pub matrix: Part,
    /// Coefficient matrix (n × n), or vector (n) for q0/v0.
    pub d: Coefficient,
}

/// A part of the system a parameter can enter.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Part {
    /// Mass matrix.
    M,
    /// Damping matrix.
    C,
    /// Stiffness matrix.
    K,
    /// Initial displacement.
    #[serde(rename = "q0")]
    Q0,
    /// Initial velocity.
    #[serde(rename = "v0")]
    V0,
}

impl Part {
    /// The name as the study file spells it (`M`, `C`, `K`, `q0`, `v0`).
    fn file_name(self) -> &'static str {
        match self {
            Part::M => "M",
            Part::C => "C",
            Part::K => "K",
            Part::Q0 => "q0",
            Part::V0 => "v0",
        }
    }

    fn is_vector(self) -> bool {
        matches!(self, Part::Q0 | Part::V0)
    }
}

/// The `d` of a dependence: a matrix (M, C, K) or a vector (q0, v0).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Coefficient {
    /// Rows of a matrix.
    Matrix(Vec<Vec<f64>>),
    /// A vector.
    Vector(Vec<f64>),
}

fn matrix(name: &str, rows: &[Vec<f64>], n: usize) -> Result<DMatrix<f64>, InvalidSystem> {
    if rows.len() != n || rows.iter().any(|r| r.len() != n) {
        return Err(InvalidSystem(format!("system.{name} must be {n} × {n}")));
    }
    if rows.iter().flatten().any(|v| !v.is_finite()) {
        return Err(InvalidSystem(format!(
            "system.{name} has a non-finite entry"
        )));
    }
    Ok(DMatrix::from_fn(n, n, |i, j| rows[i][j]))
}

fn vector(name: &str, v: &[f64], n: usize) -> Result<DMatrix<f64>, InvalidSystem> {
    if v.is_empty() {
        return Ok(DMatrix::zeros(n, 1));
    }
    if v.len() != n || v.iter().any(|x| !x.is_finite()) {
        return Err(InvalidSystem(format!(
            "system.{name} must have {n} finite entries"
        )));
    }
    Ok(DMatrix::from_column_slice(n, 1, v))
}

fn dependence_value(d: &Dependence, n: usize) -> Result<DMatrix<f64>, InvalidSystem> {
    let shaped = match (&d.d, d.matrix.is_vector()) {
        (Coefficient::Vector(v), true) if !v.is_empty() => vector("d", v, n).ok(),
        (Coefficient::Matrix(rows), false) => matrix("d", rows, n).ok(),
        _ => None,
    };
    shaped.ok_or_else(|| {
        InvalidSystem(format!(
            "system.dependence for '{}' on \"{}\": d must be {}",
            d.parameter,
            d.matrix.file_name(),
            if d.matrix.is_vector() {
                format!("a list of {n} numbers")
            } else {
                format!("a {n} × {n} list of lists")
            }
        ))
    })
}

/// The affine linear system of `[system]`: `A = A_given + Σ_j (μ_j + σ_j ξ_j) D_j`.
pub fn linear_system(
    sys: &SystemSpec,
    params: &[RandomParameter],
) -> Result<LinearSystem, InvalidSystem> {
    let n = sys.dofs.len();
    if n == 0 {
        return Err(InvalidSystem("system.dofs is empty".into()));
    }
    if !(sys.step.is_finite() && sys.step > 0.0) {
        return Err(InvalidSystem("system.step must be > 0".into()));
    }
    let mut m = Affine::constant(matrix("M", &sys.m, n)?);
    let mut c = Affine::constant(matrix("C", &sys.c, n)?);
    let mut k = Affine::constant(matrix("K", &sys.k, n)?);
    let mut q0 = Affine::constant(vector("q0", &sys.q0, n)?);
    let mut v0 = Affine::constant(vector("v0", &sys.v0, n)?);
    for d in &sys.dependence {
        let (l, p) = params
            .iter()
            .enumerate()
            .find(|(_, p)| p.name == d.parameter)
            .ok_or_else(|| {
                InvalidSystem(format!(
                    "system.dependence names '{}', which is not a random parameter",
                    d.parameter
                ))
            })?;
        let Distribution::Normal { mean, std } = p.distribution else {
            return Err(InvalidSystem(format!(
                "SGM needs '{}' to be normal",
                p.name
            )));
        };
        let dm = dependence_value(d, n)?;
        let target = match d.matrix {
            Part::M => &mut m,
            Part::C => &mut c,
            Part::K => &mut k,
            Part::Q0 => &mut q0,
            Part::V0 => &mut v0,
        };
        target.mean += &dm * mean;
        target.terms.push((l, dm * std));
    }
    let force = if sys.force.is_empty() {
        Vec::new()
    } else {
        let f = vector("force", &sys.force, n)?;
        vec![(DVector::from_column_slice(f.as_slice()), Waveform::Constant)]
    };
    Ok(LinearSystem {
        n_germs: params.len(),
        m,
        c,
        k,
        force,
        q0,
        v0,
    })
}

/// (DOF index, is velocity) of an output name: a DOF, or `<dof>_dot`.
pub fn output_dof(sys: &SystemSpec, name: &str) -> Option<(usize, bool)> {
    if let Some(i) = sys.dofs.iter().position(|d| d == name) {
        return Some((i, false));
    }
    let base = name.strip_suffix("_dot")?;
    sys.dofs.iter().position(|d| d == base).map(|i| (i, true))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_misshaped_dependence_names_its_part_as_the_study_file_does() {
        // README audit F18 (alike): `q0` was printed by its Rust name `Q0`.
        let d = Dependence {
            parameter: "x".into(),
            matrix: Part::Q0,
            d: Coefficient::Vector(vec![1.0]),
        };
        let e = dependence_value(&d, 2).unwrap_err();
        assert!(e.0.contains("on \"q0\": d must be a list of 2"), "{}", e.0);
        for p in [Part::M, Part::C, Part::K, Part::Q0, Part::V0] {
            let spelt = serde_json::to_string(&p).unwrap();
            assert_eq!(spelt, format!("\"{}\"", p.file_name()));
        }
    }
}
