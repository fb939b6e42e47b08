//! Uncertainty-quantification numerics.
//!
//! One concept per module:
//! - [`special`]: error function and normal CDF / survival / quantile, accurate in the tails;
//! - [`rng`]: one reproducible ChaCha20 stream per sample index;
//! - [`distributions`]: input distributions and their isoprobabilistic maps;
//! - [`sampling`]: Monte Carlo and Latin hypercube designs on the open unit cube;
//! - [`quadrature`]: Gauss–Hermite rules and tensor grids in standard-normal space;
//! - [`pce`]: Hermite polynomial chaos (pseudo-spectral projection, moments, Sobol' indices);
//! - [`hd`]: high-dimensional building blocks (sparse grids, Askey chaos, QMC, LARS, copula).

pub mod distributions;
pub mod galerkin;
pub mod hd;
pub mod pce;
pub mod quadrature;
pub mod rng;
pub mod sampling;
pub mod special;

pub use distributions::{Distribution, DistributionError};
pub use pce::{MultiIndexSet, Pce, PceError};
pub use quadrature::{gauss_hermite, tensor_grid, QuadratureError, TensorGrid};
pub use sampling::{latin_hypercube, monte_carlo};
