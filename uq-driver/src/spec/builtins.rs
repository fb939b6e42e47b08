//! The built-in studies, embedded in the binary (`uq-driver list`, `run builtin:NAME`).

use super::error::StudyError;

/// The built-in studies, embedded in the binary: (name, TOML).
pub const BUILTINS: &[(&str, &str)] = &[
    ("wheel-scm", include_str!("../../studies/wheel-scm.toml")),
    (
        "wheel-lhs-1000",
        include_str!("../../studies/wheel-lhs-1000.toml"),
    ),
    (
        "wheel-lhs-10000",
        include_str!("../../studies/wheel-lhs-10000.toml"),
    ),
    (
        "wheel-lhs-50000",
        include_str!("../../studies/wheel-lhs-50000.toml"),
    ),
    ("wheel-mc", include_str!("../../studies/wheel-mc.toml")),
    ("wheel-qmc", include_str!("../../studies/wheel-qmc.toml")),
    (
        "wheel-sobol-sampling",
        include_str!("../../studies/wheel-sobol-sampling.toml"),
    ),
    ("wheel-sgm", include_str!("../../studies/wheel-sgm.toml")),
    (
        "wheel-sparse",
        include_str!("../../studies/wheel-sparse.toml"),
    ),
    (
        "wheel-pce-lars",
        include_str!("../../studies/wheel-pce-lars.toml"),
    ),
    (
        "paper-wheel",
        include_str!("../../studies/paper-wheel.toml"),
    ),
    (
        "bogie-nominal",
        include_str!("../../studies/bogie-nominal.toml"),
    ),
    ("bogie-scm", include_str!("../../studies/bogie-scm.toml")),
    (
        "bogie-lhs-500",
        include_str!("../../studies/bogie-lhs-500.toml"),
    ),
    (
        "bogie-lhs-20000",
        include_str!("../../studies/bogie-lhs-20000.toml"),
    ),
    (
        "paper-bogie",
        include_str!("../../studies/paper-bogie.toml"),
    ),
    (
        "bogie-instability-probability",
        include_str!("../../studies/bogie-instability-probability.toml"),
    ),
    (
        "vehicle-track-nominal",
        include_str!("../../studies/vehicle-track-nominal.toml"),
    ),
    (
        "vehicle-track-scm-cov10",
        include_str!("../../studies/vehicle-track-scm-cov10.toml"),
    ),
    (
        "vehicle-track-scm-cov20",
        include_str!("../../studies/vehicle-track-scm-cov20.toml"),
    ),
    (
        "vehicle-track-scm-cov30",
        include_str!("../../studies/vehicle-track-scm-cov30.toml"),
    ),
    (
        "vehicle-track-defect",
        include_str!("../../studies/vehicle-track-defect.toml"),
    ),
    (
        "vehicle-track-sleeper-passing",
        include_str!("../../studies/vehicle-track-sleeper-passing.toml"),
    ),
    (
        "vehicle-track-8d-pce",
        include_str!("../../studies/vehicle-track-8d-pce.toml"),
    ),
    (
        "vehicle-track-8d-lhs",
        include_str!("../../studies/vehicle-track-8d-lhs.toml"),
    ),
    (
        "paper-vehicle-track",
        include_str!("../../studies/paper-vehicle-track.toml"),
    ),
    (
        "paper-vehicle-track-tracks",
        include_str!("../../studies/paper-vehicle-track-tracks.toml"),
    ),
    (
        "vehicle-nominal",
        include_str!("../../studies/vehicle-nominal.toml"),
    ),
    (
        "vehicle-critical-speed",
        include_str!("../../studies/vehicle-critical-speed.toml"),
    ),
    (
        "vehicle-curve-safety",
        include_str!("../../studies/vehicle-curve-safety.toml"),
    ),
    (
        "vehicle-curve-derailment-probability",
        include_str!("../../studies/vehicle-curve-derailment-probability.toml"),
    ),
    (
        "vehicle-curve-derailment-lhs",
        include_str!("../../studies/vehicle-curve-derailment-lhs.toml"),
    ),
];

/// The text of a built-in study.
pub fn builtin(name: &str) -> Result<&'static str, StudyError> {
    BUILTINS
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, text)| *text)
        .ok_or_else(|| StudyError::UnknownBuiltin(name.to_owned()))
}
