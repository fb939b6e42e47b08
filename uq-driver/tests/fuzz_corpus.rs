//! Runs the fuzz targets' checks (`uq-driver/fuzz/src/checks.rs`) on the seed corpora and on
//! every input saved under `uq-driver/fuzz/regressions/`, so that an input the fuzzer once
//! broke the code with stays fixed. The fuzzing itself is `make fuzz`.

// The fuzz crate's own file: the fuzz crate is a workspace of its own (libFuzzer), so the
// checks are compiled here from its source. `cargo fmt` follows the path and formats it.
#[path = "../fuzz/src/checks.rs"]
mod checks;

use std::path::Path;

fn inputs(target: &str) -> Vec<std::path::PathBuf> {
    let fuzz = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz");
    let mut files = Vec::new();
    for dir in ["corpus", "regressions"] {
        let Ok(entries) = std::fs::read_dir(fuzz.join(dir).join(target)) else {
            continue;
        };
        for e in entries {
            let path = e.unwrap().path();
            if path.is_file() && path.file_name().is_some_and(|n| n != ".keep") {
                files.push(path);
            }
        }
    }
    files.sort();
    files
}

fn run(target: &str, check: fn(&[u8])) {
    let files = inputs(target);
    assert!(!files.is_empty(), "no seeds for {target}");
    for f in files {
        let data = std::fs::read(&f).unwrap();
        if let Err(e) = std::panic::catch_unwind(|| check(&data)) {
            let why = e
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| e.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_default();
            panic!("{}: {why}", f.display());
        }
    }
}

#[test]
fn model_description_corpus_and_regressions_pass_the_fuzz_checks() {
    run("model_description", checks::model_description);
}

#[test]
fn store_reader_corpus_and_regressions_pass_the_fuzz_checks() {
    run("store_reader", checks::store_reader);
}

#[test]
fn study_file_corpus_and_regressions_pass_the_fuzz_checks() {
    run("study_file", checks::study_file);
}
