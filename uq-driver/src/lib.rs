//! uq-driver: load FMI 2.0 Co-Simulation FMUs through their C ABI and propagate
//! uncertainty through them (Monte Carlo, Latin hypercube, stochastic collocation, the
//! stochastic Galerkin method).
//!
//! The `uq-driver` command line is a thin layer over this library; everything it does is
//! reachable from Rust.
//!
//! # Start here
//!
//! ## A study of an FMU: [`spec::Study::parse`] → [`study::run_study`] → [`study::StudyResult`]
//!
//! A study is described in TOML (the same file `uq-driver run` takes; see [`spec`] and the
//! user guide's study-file reference, `docs/src/reference/study-file.md`, for every key), run
//! with [`study::run_study`] into an output folder, and its statistics come back typed:
//!
//! ```no_run
//! use std::path::Path;
//! use uq_driver::spec::Study;
//! use uq_driver::study::{run_study, Outcome, RunOptions};
//!
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let toml = r#"
//! name = "wheel-sobol"
//! fmu = "/path/to/Wheel.fmu"
//! seed = 42
//! [experiment]
//! start = 0.0
//! stop = 2.0
//! step = 0.01                      # communication step (s)
//! [[parameters]]
//! name = "K"                       # stiffness (N/m)
//! distribution = "normal"
//! mean = 100.0
//! std = 10.0
//! [[parameters]]
//! name = "C"                       # damping (N.s/m)
//! distribution = "normal"
//! mean = 20.0
//! std = 2.0
//! [outputs]
//! variables = ["q"]                # displacement (m)
//! [method]
//! kind = "sobol_sampling"
//! samples = 256
//! "#;
//! // `base`: the folder a relative `fmu` path starts from.
//! let study = Study::parse(toml, "inline", None)?;
//! let opts = RunOptions::default().with_threads(2).with_no_report(true);
//! let Outcome::Study(result) = run_study(&study, Path::new("out/wheel-sobol"), &opts)? else {
//!     unreachable!("a study without [[variants]] is not a suite");
//! };
//! let q = &result.outputs[0]; // one entry per output variable
//! let k = q.times.iter().position(|&t| (t - 1.0).abs() < 1e-9).unwrap();
//! println!("q(1 s): mean {} m, Std {} m", q.mean[k], q.std[k]);
//! if let Some(sobol) = &q.sobol {
//!     println!("first-order Sobol' indices (K, C) at 1 s: {:?}", sobol.first[k]);
//! }
//! # Ok(()) }
//! ```
//!
//! What [`study::run_study`] does besides computing, so that a host application knows:
//! - it writes into the output folder (the resumable results store `store/`, `summary.json`,
//!   the CSV files and, unless [`study::RunOptions::no_report`], the plots and `index.html`),
//!   and resumes what an earlier run there finished ([`study::RunOptions::fresh`] discards it);
//! - it holds a lock on that folder while it runs (two studies into one folder are refused);
//! - it runs the points on its own thread pool of [`study::RunOptions::threads`] threads;
//! - it checks the study again ([`spec::Study::check`]: its fields are public) and refuses
//!   an empty `out_dir` and options that do not fit together, with typed errors;
//! - process-wide behaviour is off unless the host opts in with
//!   [`study::install_process_guards`], as the command line does: signal handlers, an
//!   `atexit` check that reports an FMU calling `exit()`, and ending the process when an
//!   in-process run overruns [`study::RunOptions::timeout_per_run`]. Without it a host's own
//!   `exit()` and signals are its own, and `timeout_per_run` needs
//!   [`study::RunOptions::isolate`] (each run in a worker process, killed after the limit;
//!   the worker is this program started as `<exe> worker`, see `uq-driver worker`): the
//!   safe way to run an FMU that may crash, hang or call `exit()`.
//!
//! One simulation without a study: [`study::simulate`]; the FMU itself, call by
//! call: [`fmu::Fmu`] and [`fmu::Instance`].
//!
//! ## UQ on a plain Rust function: design → simulate → estimate
//!
//! The methods of [`uq::method`] need no FMU: a [`uq::method::Sampling`] method builds a
//! design for the random inputs, you evaluate your model at its points (in any order, on
//! any threads), and the method's estimator turns the results into moments and Sobol'
//! indices:
//!
//! ```
//! use uq_driver::nalgebra::DMatrix; // re-exported: no `nalgebra` in your Cargo.toml
//! use uq_driver::uq::distributions::{Distribution, RandomParameter};
//! use uq_driver::uq::method::{scm::Scm, ChaosBasis, Sampling};
//! use uq_driver::uq::RandomInputs;
//!
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! // y = x1 + 2 x2 with x1, x2 ~ N(0, 1): mean 0, variance 5, S1 = (1/5, 4/5).
//! let model = |x: &[f64]| x[0] + 2.0 * x[1];
//! let inputs = RandomInputs::independent(vec![
//!     RandomParameter { name: "x1".into(), distribution: Distribution::normal(0.0, 1.0)? },
//!     RandomParameter { name: "x2".into(), distribution: Distribution::normal(0.0, 1.0)? },
//! ]);
//! let method = Scm { nodes: 4, order: Some(3), chaos: ChaosBasis::Askey };
//! let design = method.design(&inputs, 42)?; // seed: same seed, same design
//! // One row per design point (physical values in `design.values`), one column per
//! // output value (a time step or a scalar quantity).
//! let data = DMatrix::from_fn(design.len(), 1, |i, _| model(&design.values[i]));
//! let rows: Vec<usize> = (0..design.len()).collect(); // the design points `data` holds
//! let e = method.estimate(&design, &rows, &data)?;
//! assert!(e.mean[0].abs() < 1e-12);
//! assert!((e.std[0] * e.std[0] - 5.0).abs() < 1e-10);
//! let s = e.sobol.expect("a chaos gives Sobol' indices");
//! assert!((s.first[0][0] - 0.2).abs() < 1e-10 && (s.first[0][1] - 0.8).abs() < 1e-10);
//! # Ok(()) }
//! ```
//!
//! Points that failed may be left out of `rows` (and `data`) for the methods that allow it
//! (unweighted designs); `design` checks the inputs and the settings, and `estimate`
//! refuses `rows` and `data` that do not match the design, with typed errors
//! ([`uq::method::MethodError`]).
//!
//! # Modules
//!
//! Modules by concept, bottom first, each using only those before it in this list (a test,
//! `layers`, reads every file's imports and fails on one against this order, and on two files
//! that import each other):
//! - `text` (crate-internal): CSV fields, numbers as text, file names;
//! - `suggest` (crate-internal): "did you mean" for misspelt names;
//! - `sys` (crate-internal): process-level system calls behind safe functions;
//! - [`fmu`]: import of `.fmu` archives (safe unzip, modelDescription, dlopen, instances);
//! - [`uq`]: distributions, random streams, sampling, quadrature, polynomial chaos, moments,
//!   and the UQ methods ([`uq::method`], one module per method: design + estimator);
//! - [`qoi`]: quantities of interest evaluated on runs (critical speed, Sperling index, …),
//!   kernel densities;
//! - [`spec`]: the study file, typed and validated;
//! - [`results`]: typed results and the summaries written to `summary.json`;
//! - `report` (crate-internal): CSV/JSON writers, plots, the HTML pages of a study and of a
//!   suite;
//! - [`study`]: running a study: planning it (`plan`), running its points (`run`, the one
//!   place that runs them), the resumable results store (`store`), the statistics
//!   (`analysis`), shards for a cluster, suites;
//! - [`prelude`]: the types most programs need;
//! - `cli` (feature `cli`, on by default): the `uq-driver` command line.
//!
//! `unsafe` code is confined to the FMI import layer ([`fmu`]) and `sys`; every other module
//! is `#![forbid(unsafe_code)]`.

/// The linear-algebra crate of the public API (a design's results are a
/// [`nalgebra::DMatrix`], estimates and chaos coefficients too), re-exported so that a
/// program uses the very version uq-driver was built with.
pub use nalgebra;

#[cfg(feature = "cli")]
pub mod cli;
pub mod fmu;
#[cfg(test)]
mod layers;
pub mod prelude;
pub mod qoi;
pub(crate) mod report;
pub mod results;
pub mod spec;
pub mod study;
pub(crate) mod suggest;
pub(crate) mod sys;
pub(crate) mod text;
pub mod uq;

/// Not part of the API: the fuzz targets' and the integration tests' access to internals; may
/// change at any release.
#[doc(hidden)]
pub mod internals {
    pub use crate::study::plan::fingerprint::study_hash;
    pub use crate::study::run::run_points;
    pub use crate::uq::hd::lars::PathKind;
    pub use crate::uq::hd::sensitivity::pick_freeze_bootstrap;
    pub use crate::uq::hd::sobol_seq::Sobol;
    pub use crate::uq::hd::sparse_chaos::{fit_chaos, FitKind};
    pub use crate::uq::pce::askey::Family;

    /// The results store: its reader and writer, the record format, the folder lock.
    pub mod store {
        pub use crate::study::store::format::{decode, MAGIC};
        pub use crate::study::store::lock::FolderLock;
        pub use crate::study::store::{encode, Format, Manifest, Record, Store};
    }
}
