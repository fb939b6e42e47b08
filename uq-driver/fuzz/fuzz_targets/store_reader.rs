//! Fuzz target: the results store reader (see `src/checks.rs`).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| uq_driver_fuzz::checks::store_reader(data));
