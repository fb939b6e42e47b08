//! Studies by the stochastic Galerkin method: the linear system comes from the study file
//! (`[system]`), so a user runs SGM on their own small linear model without writing Rust.
//! The Galerkin system itself is in [`crate::uq::galerkin`].

use nalgebra::{DMatrix, DVector};

use super::spec::{Dependence, RandomParameter, Study, SystemSpec};
use crate::uq::galerkin::{Affine, GalerkinSystem, LinearSystem, Waveform};
use crate::uq::Distribution;

fn matrix(name: &str, rows: &[Vec<f64>], n: usize) -> Result<DMatrix<f64>, String> {
    if rows.len() != n || rows.iter().any(|r| r.len() != n) {
        return Err(format!("system.{name} must be {n} × {n}"));
    }
    if rows.iter().flatten().any(|v| !v.is_finite()) {
        return Err(format!("system.{name} has a non-finite entry"));
    }
    Ok(DMatrix::from_fn(n, n, |i, j| rows[i][j]))
}

fn vector(name: &str, v: &[f64], n: usize) -> Result<DMatrix<f64>, String> {
    if v.is_empty() {
        return Ok(DMatrix::zeros(n, 1));
    }
    if v.len() != n || v.iter().any(|x| !x.is_finite()) {
        return Err(format!("system.{name} must have {n} finite entries"));
    }
    Ok(DMatrix::from_column_slice(n, 1, v))
}

fn dependence_value(d: &Dependence, n: usize) -> Result<DMatrix<f64>, String> {
    let err = || {
        format!(
            "system.dependence for '{}' on {}: d must be {}",
            d.parameter,
            d.matrix,
            if matches!(d.matrix.as_str(), "q0" | "v0") {
                format!("a list of {n} numbers")
            } else {
                format!("a {n} × {n} list of lists")
            }
        )
    };
    let num = |v: &toml::Value| v.as_float().or_else(|| v.as_integer().map(|i| i as f64));
    let arr = d.d.as_array().ok_or_else(err)?;
    match d.matrix.as_str() {
        "q0" | "v0" => {
            let v: Option<Vec<f64>> = arr.iter().map(num).collect();
            let v = v.ok_or_else(err)?;
            vector(&d.matrix, &v, n).map_err(|_| err())
        }
        "M" | "C" | "K" => {
            let rows: Option<Vec<Vec<f64>>> = arr
                .iter()
                .map(|r| r.as_array().and_then(|r| r.iter().map(num).collect()))
                .collect();
            matrix(&d.matrix, &rows.ok_or_else(err)?, n).map_err(|_| err())
        }
        other => Err(format!(
            "system.dependence: unknown matrix '{other}' (M, C, K, q0, v0)"
        )),
    }
}

/// Builds the affine linear system: `A = A_given + Σ_j (μ_j + σ_j ξ_j) D_j`.
pub fn linear_system(sys: &SystemSpec, params: &[RandomParameter]) -> Result<LinearSystem, String> {
    let n = sys.dofs.len();
    if n == 0 {
        return Err("system.dofs is empty".into());
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
                format!(
                    "system.dependence names '{}', which is not a random parameter",
                    d.parameter
                )
            })?;
        let Distribution::Normal { mean, std } = p.distribution else {
            return Err(format!("SGM needs '{}' to be normal", p.name));
        };
        let dm = dependence_value(d, n)?;
        let target = match d.matrix.as_str() {
            "M" => &mut m,
            "C" => &mut c,
            "K" => &mut k,
            "q0" => &mut q0,
            _ => &mut v0,
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
    if !(sys.step.is_finite() && sys.step > 0.0) {
        return Err("system.step must be > 0".into());
    }
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

/// Checks a `[system]` against the parameters and outputs of a study.
pub fn validate(
    sys: &SystemSpec,
    params: &[RandomParameter],
    outputs: &[String],
) -> Result<(), String> {
    linear_system(sys, params)?;
    for o in outputs {
        if output_dof(sys, o).is_none() {
            return Err(format!(
                "output '{o}' is not a DOF of the system (DOFs: {}; velocities: <dof>_dot)",
                sys.dofs.join(", ")
            ));
        }
    }
    Ok(())
}

/// (DOF index, is velocity) of an output name.
pub fn output_dof(sys: &SystemSpec, name: &str) -> Option<(usize, bool)> {
    if let Some(i) = sys.dofs.iter().position(|d| d == name) {
        return Some((i, false));
    }
    let base = name.strip_suffix("_dot")?;
    sys.dofs.iter().position(|d| d == base).map(|i| (i, true))
}

/// Assembles and solves a study's Galerkin system; returns the system and, per output, the
/// chaos coefficients over time (terms × times).
pub fn solve(study: &Study) -> Result<(GalerkinSystem, Vec<DMatrix<f64>>), String> {
    let sys = study.file.system.as_ref().ok_or("no [system]")?;
    let ls = linear_system(sys, &study.parameters)?;
    let order = study.file.method.order.unwrap_or(1);
    let gs = GalerkinSystem::assemble(&ls, order).map_err(|e| e.to_string())?;
    let times = study.file.experiment.times();
    let dofs: Vec<(usize, bool)> = study
        .file
        .outputs
        .variables
        .iter()
        .map(|o| output_dof(sys, o).ok_or_else(|| format!("unknown output {o}")))
        .collect::<Result<_, _>>()?;
    let idx: Vec<usize> = dofs.iter().map(|d| d.0).collect();
    let sol = gs
        .solve(&times, sys.step, &idx)
        .map_err(|e| e.to_string())?;
    let coeffs = dofs
        .iter()
        .zip(sol)
        .map(|(&(_, vel), (q, v))| if vel { v } else { q })
        .collect();
    Ok((gs, coeffs))
}
