//! Fuzz target: `Study::parse` on study files (see `src/checks.rs`).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| uq_driver_fuzz::checks::study_file(data));
