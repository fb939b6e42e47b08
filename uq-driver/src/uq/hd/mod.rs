//! High-dimensional UQ building blocks: pure numerics, no FMU.
//!
//! One concept per module (the Askey families and the orthonormal bases over multi-index
//! sets are in [`crate::uq::pce`]; the input families in [`crate::uq::distributions`]):
//! - [`rules`]: nested and non-nested one-dimensional rules by level (Genz–Keister,
//!   Clenshaw–Curtis, Gauss–Patterson, Gauss–Legendre, Gauss–Hermite);
//! - [`smolyak`]: admissible level sets, combination coefficients, sparse grids;
//! - [`pseudo_spectral`]: the sparse pseudo-spectral projection (Conrad & Marzouk 2013);
//! - [`copula`]: the Gaussian (Nataf) copula for correlated inputs;
//! - [`sobol_seq`]: Sobol' points (Joe–Kuo direction numbers) with Owen scrambling;
//! - [`regression`]: least squares with the closed-form leave-one-out error;
//! - [`lars`]: least-angle regression with hybrid LOO basis selection;
//! - [`sparse_chaos`]: regression chaos (full or sparse) with degree adaptivity by LOO;
//! - [`sensitivity`]: pick-freeze Sobol' estimators (Saltelli / Jansen) with bootstrap,
//!   and replicated-design estimators.
//!
//! Germ conventions used throughout: "normal" germ = N(0, 1); "uniform" germ =
//! U(-1, 1) (density 1/2); "gamma" germ with shape `k` = Gamma(k, 1) on `[0, inf)`;
//! "beta" germ with shapes `(a, b)` = the Beta(a, b) law mapped to `[-1, 1]`.
//! Quadrature weights always sum to 1 (they integrate against the germ's probability
//! measure) and polynomial bases are orthonormal for that measure.

pub mod copula;
pub mod lars;
pub mod pseudo_spectral;
pub mod regression;
pub mod rules;
pub mod sensitivity;
pub mod smolyak;
pub mod sobol_seq;
pub mod sparse_chaos;
