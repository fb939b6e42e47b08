//! The FMI 2.0 Co-Simulation layer, generic over [`crate::models::Model`]. It knows no physics.
//!
//! - [`types`]: the C ABI types;
//! - [`state`]: the state machine as a table of legal states per function;
//! - [`instance`]: one instance (safe Rust): set/get with causality checks, stepping, FMU state;
//! - `functions`: the 34 exported `fmi2*` functions, the only `extern "C"` code;
//! - [`logger`]: calls into the importer's variadic logger;
//! - [`xml`]: modelDescription.xml, GUID and documentation generated from the variable table.
//!
//! One cdylib serves every model of [`crate::models::registry`]; the GUID passed to
//! `fmi2Instantiate` selects the model. The same binary is packaged once per model, renamed
//! to the model identifier.

mod functions;
pub mod instance;
pub mod logger;
pub mod state;
pub mod types;
pub mod uri;
pub mod xml;

pub use functions::{TEST_PANIC_ENV, TEST_PANIC_VALUE};
