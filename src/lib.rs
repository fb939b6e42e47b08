//! railuq: railway vehicle–track models as FMI 2.0 Co-Simulation FMUs.
//!
//! - [`models`]: the physics (pure Rust, no FMI types);
//! - [`solver`]: fixed-step integrators;
//! - [`fmi2`]: the FMI 2.0 Co-Simulation export layer (the `fmi2*` C functions);
//! - [`package`]: writes `.fmu` archives and model descriptions.

pub mod fmi2;
pub mod models;
pub mod package;
pub mod solver;
