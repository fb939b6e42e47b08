//! The study file (TOML): which FMU, which random parameters, which method, which outputs.
//!
//! ```toml
//! name = "wheel-scm"
//! fmu = "Wheel.fmu"            # relative to the study file, or found in the FMU folder
//! seed = 42
//! [experiment]
//! start = 0.0
//! stop = 5.0
//! step = 0.01                  # communication step (s)
//! [method]
//! kind = "scm"                 # a method of crate::uq::method, with its own keys
//! nodes = 6                    # SCM: Gauss–Hermite nodes per dimension
//! order = 5                    # SCM: total order of the Hermite chaos (default nodes − 1)
//! [[parameters]]
//! name = "K"
//! level = "inner"              # nested studies: "outer" (the outer design) or "inner"
//! distribution = "normal"      # "normal" | "lognormal" | "uniform" | "truncated_normal" |
//!                              # "beta" | "gamma" | "weibull" | "integer_uniform"
//! mean = 100.0
//! std = 10.0                   # or cov = 0.1
//! [fixed]                      # deterministic values: numbers, true/false, "texts"
//! h = 0.001
//! [inputs]                     # optional: time-varying inputs
//! file = "signal.csv"          # time column, then one column per input variable
//! [outputs]
//! variables = ["q"]
//! ```
//!
//! [`Study::parse`] reads the file into [`StudyFile`] (serde: tagged enums for the method,
//! the distributions and the quantities of interest, unknown keys refused) and validates it
//! in one place (`load.rs`) into a [`Study`]. Errors carry the origin and, where the
//! file has them, the line and column.

#![forbid(unsafe_code)]

mod builtins;
mod error;
mod file;
mod load;
mod overrides;
mod parameter;
mod study;

pub use crate::fmu::FixedValue;
pub use builtins::{builtin, BUILTINS};
pub use error::{Location, StudyError};
pub use file::{
    quantile_column, Analysis, CorrelationSpec, Experiment, Functional, Inputs, InvalidExperiment,
    Outputs, PaperValue, StudyFile, Variant,
};
pub use load::{add_fmu_dir, fmu_candidates, fmu_search_path};
pub use parameter::{DistributionSpec, InvalidParameter, Level, ParameterSpec};
pub use study::{Study, Suite};

#[cfg(test)]
mod tests;
