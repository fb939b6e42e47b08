//! uq-driver: load FMI 2.0 Co-Simulation FMUs through their C ABI and propagate
//! uncertainty through them (Monte Carlo, Latin hypercube, stochastic collocation, the
//! stochastic Galerkin method).
//!
//! Modules by concept, each using only those above it in this list:
//! - [`fmu`]: import of `.fmu` archives (safe unzip, modelDescription, dlopen, instances);
//! - [`uq`]: distributions, random streams, sampling, quadrature, polynomial chaos, moments,
//!   and the UQ methods ([`uq::method`], one module per method: design + estimator);
//! - [`qoi`]: quantities of interest evaluated on runs (critical speed, Sperling index, …),
//!   kernel densities;
//! - [`spec`]: the study file, typed and validated;
//! - [`results`]: typed results and the summaries written to `summary.json`;
//! - [`report`]: CSV/JSON writers, plots, the HTML pages of a study and of a suite;
//! - [`study`]: running a study: the parallel runner, the resumable results store, the
//!   statistics, shards for a cluster, suites;
//! - [`suggest`]: "did you mean" for misspelt names.

pub mod fmu;
pub mod out_file;
pub mod qoi;
pub mod report;
pub mod results;
pub mod spec;
pub mod study;
pub mod suggest;
pub mod uq;
