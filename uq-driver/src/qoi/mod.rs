//! Quantities of interest computed from runs and ensembles of runs.
//!
//! - [`scalar`]: the `[[qoi]]` of a study file, evaluated on one run's time series;
//! - [`critical_speed`]: the speed at which a hunting oscillation dies out on a speed ramp;
//! - [`hunting_speed`]: the constant-speed critical speed, by bisection over runs at fixed speeds;
//! - [`sperling`]: the Sperling ride index of an acceleration record;
//! - [`kde`]: Gaussian kernel density estimates.

#![forbid(unsafe_code)]

pub mod critical_speed;
pub(crate) mod ended;
pub mod evaluate;
pub mod hunting_speed;
pub mod kde;
pub mod scalar;
pub mod sperling;

pub use kde::{auto_grid, gaussian_kde, silverman_bandwidth};
pub use scalar::{QoiError, QoiSpec};
