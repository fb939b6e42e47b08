//! uq-driver: load FMI 2.0 Co-Simulation FMUs through their C ABI and propagate
//! uncertainty through them (Monte Carlo, Latin hypercube, stochastic collocation).
//!
//! Modules by concept:
//! - [`fmu`]: import of `.fmu` archives (safe unzip, modelDescription, dlopen, instances);
//! - [`uq`]: distributions, random streams, sampling, quadrature, polynomial chaos;
//! - [`qoi`]: statistics and quantities of interest computed from ensembles of runs;
//! - [`study`]: study files, the parallel runner and the resumable results store;
//! - [`report`]: CSV/JSON writers, plots and the HTML index.

pub mod fmu;
pub mod qoi;
pub mod report;
pub mod study;
pub mod uq;
