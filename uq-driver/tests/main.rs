//! The integration tests of uq-driver: one module per subject, all in this one test binary,
//! linked once against the crate (not once per file). `support` holds what they share.
//!
//! They all run in this one process, on parallel threads. None of them changes what belongs to
//! the process: the current folder, the environment, signal handlers, `atexit` handlers
//! (`uq_driver::study::install_process_guards` is never called here: the library leaves the
//! host's process alone without it, which `library.rs` checks). What needs a process of its own
//! runs the `uq-driver` executable ([`support::DRIVER`]), with its own environment, or this test
//! binary again (`library.rs`, a host that exits during a study). An FMU loaded in-process is
//! extracted to a folder of its own on each `Fmu::open`, so tests never share its globals.
//!
//! libtest starts the tests in the order of their names, two at a time on two cores: a test of
//! ten seconds or more (the Vehicle's built-in nominal study) sits in a module early in that
//! order, so that it does not run alone at the end while the other thread idles.
//!
//! `autotests = false` (Cargo.toml): a file of `tests/` that is not declared below is not
//! compiled at all, so [`every_file_of_the_tests_folder_is_a_module_of_this_binary`] checks that
//! none is left out.

mod support;

mod analysis_blocks;
mod builtin_vehicle_studies;
mod calculated_strings;
mod chaos_sizes;
mod cli_options;
mod declared_speed_range;
mod description_hardening;
mod fmu_import;
mod fmu_robustness;
mod functional_outputs;
mod fuzz_corpus;
mod given_data_sensitivity;
mod hd_goals;
mod hunting_speed;
mod importer_features;
mod input_files;
mod instance_lifecycle;
mod isolation;
mod large_studies;
mod library;
mod nested_intervals;
mod output_files;
mod qoi_min_max;
mod reliability;
mod report_honest;
mod small_chaos;
mod sobol_sampling_intervals;
mod store_recovery;
mod study_chaos;
mod study_nested;
mod study_sampling;
mod study_wheel;
mod tampered_folders;
mod test_fmus;
mod trust_report;
mod undefined_numbers;

/// The `.rs` files of the folder `dir` (below `tests/`) but `skip`, without their extension.
fn rust_files(dir: &str, skip: &str) -> Vec<String> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(dir);
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "rs"))
        .map(|p| p.file_stem().unwrap().to_string_lossy().into_owned())
        .filter(|n| n != skip)
        .collect();
    names.sort();
    names
}

#[test]
fn every_file_of_the_tests_folder_is_a_module_of_this_binary() {
    for (dir, root, skip) in [
        ("tests", "tests/main.rs", "main"),
        ("tests/support", "tests/support/mod.rs", "mod"),
    ] {
        let files = rust_files(dir, skip);
        assert!(files.len() >= 5, "{dir}: {files:?}");
        let text = support::read(&std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(root));
        for f in files {
            assert!(
                text.lines()
                    .any(|l| l == format!("mod {f};") || l == format!("pub mod {f};")),
                "{dir}/{f}.rs is not declared in {root}: it is not compiled"
            );
        }
    }
}
