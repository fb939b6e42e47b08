//! Fuzz target: `ModelDescription::parse` (see `src/checks.rs`).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| uq_driver_fuzz::checks::model_description(data));
