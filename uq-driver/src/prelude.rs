//! The types most programs need, in one `use uq_driver::prelude::*;`: a study from TOML, run
//! into a folder with options, its typed results; one simulation of an FMU; the FMU itself;
//! and UQ on a plain Rust function (inputs, a method's design and estimate).
#![forbid(unsafe_code)]

pub use crate::fmu::{FixedValue, Fmu, FmuError, Instance};
pub use crate::results::{OutputStats, ScalarStats, Summary};
pub use crate::spec::{Study, StudyError};
pub use crate::study::run::{simulate, Simulation};
pub use crate::study::{
    run_study, Outcome, RunError, RunOptions, StudyResult, StudyRunError, SuiteResult,
};
pub use crate::uq::method::{Design, Estimate, Method, MethodError, MethodSpec, Sampling};
pub use crate::uq::surrogate::Surrogate;
pub use crate::uq::{Distribution, RandomInputs, RandomParameter};
