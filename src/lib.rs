//! railuq: railway vehicle–track models as FMI 2.0 Co-Simulation FMUs.
//!
//! - [`contact`]: wheel–rail contact geometry (tables, profiles);
//! - [`models`]: the physics (pure Rust, no FMI types);
//! - [`solver`]: fixed-step integrators;
//! - [`fmi2`]: the FMI 2.0 Co-Simulation export layer (the `fmi2*` C functions).
//!
//! Packaging (`.fmu` archives, model descriptions, icons) lives in the `railuq-fmu` binary
//! (`src/bin/railuq-fmu/`), so that the FMU's own shared library carries none of it.

pub mod contact;
pub mod fmi2;
pub mod models;
pub mod solver;
