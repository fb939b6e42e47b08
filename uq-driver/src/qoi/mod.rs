//! Statistics and quantities of interest computed from ensembles of runs.
//!
//! - [`moments`]: sample and quadrature moments, quantiles, summaries, exceedance probabilities;
//! - [`kde`]: Gaussian kernel density estimates.

pub mod critical_speed;
pub mod kde;
pub mod moments;
pub mod scalar;
pub mod sperling;

pub use kde::{auto_grid, gaussian_kde, silverman_bandwidth};
pub use moments::{
    column_quantiles, exceedance_probability, quantile, sample_mean_std, weighted_mean_std,
    ScalarSummary,
};
