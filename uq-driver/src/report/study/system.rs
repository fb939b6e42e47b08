//! The section of an SGM page that shows the system the method solved.

use crate::report::{Section, Table};
use crate::results::numbers::{as_written, written};
use crate::uq::galerkin::system::{Coefficient, SystemSpec};

/// The section that shows the system an intrusive method (SGM) solved, from `[system]` of the
/// study file: `M q̈ + C q̇ + K q = f` with its constant parts and how each random parameter
/// enters.
pub fn system_section(sys: &SystemSpec) -> Section {
    let vector = |v: &[f64]| format!("[{}]", as_written(v).join(", "));
    let matrix = |m: &[Vec<f64>]| {
        let rows: Vec<String> = m.iter().map(|r| vector(r)).collect();
        format!("[{}]", rows.join(", "))
    };
    let n = sys.dofs.len();
    let or_zeros = |v: &[f64]| {
        if v.is_empty() {
            vector(&vec![0.0; n])
        } else {
            vector(v)
        }
    };
    let mut rows = vec![
        vec!["degrees of freedom q".to_string(), sys.dofs.join(", ")],
        vec!["M (constant part)".into(), matrix(&sys.m)],
        vec!["C (constant part)".into(), matrix(&sys.c)],
        vec!["K (constant part)".into(), matrix(&sys.k)],
        vec!["q0 (constant part)".into(), or_zeros(&sys.q0)],
        vec!["v0 (constant part)".into(), or_zeros(&sys.v0)],
        vec!["f (constant load)".into(), or_zeros(&sys.force)],
    ];
    for d in &sys.dependence {
        let part = serde_json::to_value(d.matrix)
            .ok()
            .and_then(|v| v.as_str().map(str::to_owned))
            .unwrap_or_default();
        let coefficient = match &d.d {
            Coefficient::Matrix(m) => matrix(m),
            Coefficient::Vector(v) => vector(v),
        };
        rows.push(vec![
            format!("{part} depends on {}", d.parameter),
            format!("{part} += {} · {coefficient}", d.parameter),
        ]);
    }
    Section {
        heading: "System".into(),
        text: format!(
            "The system the stochastic Galerkin method solved ([system] of the study file): \
             M q̈ + C q̇ + K q = f, q(0) = q0, q̇(0) = v0, each of M, C, K, q0, v0 its \
             constant part plus each random parameter times its coefficient (below). \
             Integrated by RK4 with steps of at most {} s. No unit is declared.",
            written(sys.step)
        ),
        images: vec![],
        table: Some(Table::new(&["part", "value"], rows)),
    }
}
