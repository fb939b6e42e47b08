//! Uncertainty-quantification numerics.
//!
//! One concept per module (public: [`distributions`], the study's inputs
//! ([`RandomInputs`]), [`method`] and [`surrogate`]; the building blocks are the crate's own):
//! - `special`: error function and normal CDF / survival / quantile, accurate in the tails
//!   ([`norm_cdf`], [`norm_sf`], [`norm_ppf`] are public);
//! - `rng`: one reproducible ChaCha20 stream per sample index;
//! - [`distributions`]: input distributions and their maps to and from a standard space;
//! - `random_inputs`: the inputs of a study with their correlation (Gaussian copula), and the
//!   map from a design's independent standard space to physical values;
//! - `sampling`: Monte Carlo and Latin hypercube designs on the open unit cube;
//! - `quadrature`: Gauss–Hermite rules and tensor grids in standard-normal space;
//! - `pce`: polynomial chaos on the Askey families (projection, moments, Sobol' indices);
//! - `galerkin`: the stochastic Galerkin system of a linear second-order model;
//! - `moments`: sample and quadrature moments, quantiles, exceedance probabilities;
//! - `given_data`: first-order Sobol' indices from any sample of the inputs' law (binning
//!   estimator, bootstrap intervals);
//! - `rank_correlation`: Spearman's and partial rank correlation coefficients from a sample;
//! - [`method`]: the UQ methods, one module each (design + estimator);
//! - `reliability`: small failure probabilities (FORM, SORM, importance sampling, subset
//!   simulation) and Morris screening, on a batch-evaluated limit state in standard space;
//! - [`surrogate`]: the exported chaos surrogate (`surrogate.json`), evaluated and sampled;
//! - `hd`: high-dimensional building blocks (sparse grids, Askey chaos, QMC, LARS, copula).

#![forbid(unsafe_code)]

pub mod distributions;
pub(crate) mod galerkin;
pub(crate) mod given_data;
pub(crate) mod hd;
pub mod method;
pub(crate) mod moments;
pub(crate) mod pce;
pub(crate) mod quadrature;
pub(crate) mod random_inputs;
pub(crate) mod rank_correlation;
pub(crate) mod reliability;
pub(crate) mod rng;
pub(crate) mod sampling;
pub(crate) mod special;
pub mod surrogate;

pub use distributions::{Distribution, DistributionError, Germ, RandomParameter};
pub use random_inputs::{Correlation, CorrelationPair, RandomInputs};
pub use special::{norm_cdf, norm_ppf, norm_sf};
