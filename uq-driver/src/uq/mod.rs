//! Uncertainty-quantification numerics.
//!
//! One concept per module:
//! - [`special`]: error function and normal CDF / survival / quantile, accurate in the tails;
//! - [`rng`]: one reproducible ChaCha20 stream per sample index;
//! - [`distributions`]: input distributions and their maps to and from a standard space;
//! - [`sampling`]: Monte Carlo and Latin hypercube designs on the open unit cube;
//! - [`quadrature`]: Gauss–Hermite rules and tensor grids in standard-normal space;
//! - [`pce`]: Hermite polynomial chaos (pseudo-spectral projection, moments, Sobol' indices);
//! - [`galerkin`]: the stochastic Galerkin system of a linear second-order model;
//! - [`moments`]: sample and quadrature moments, quantiles, exceedance probabilities;
//! - [`method`]: the UQ methods, one module each (design + estimator);
//! - [`hd`]: high-dimensional building blocks (sparse grids, Askey chaos, QMC, LARS, copula).

pub mod distributions;
pub mod galerkin;
pub mod hd;
pub mod method;
pub mod moments;
pub mod pce;
pub mod quadrature;
pub mod rng;
pub mod sampling;
pub mod special;

pub use distributions::{Distribution, DistributionError, Germ, RandomParameter};
pub use method::{Design, Estimate, Method, MethodError, MethodSpec};
pub use pce::{MultiIndexSet, Pce, PceError};
pub use quadrature::{gauss_hermite, tensor_grid, QuadratureError, TensorGrid};
pub use sampling::{latin_hypercube, monte_carlo};
