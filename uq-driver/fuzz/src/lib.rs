//! Checks shared by the fuzz targets and by `uq-driver/tests/fuzz_corpus.rs`, which runs the
//! seed corpora and every saved regression input through them on `cargo test`.

pub mod checks;
