//! Compiles the C shim that gives FMUs a variadic `fmi2CallbackLogger` (stable Rust cannot
//! define variadic functions).

fn main() {
    println!("cargo:rerun-if-changed=csrc/logger_shim.c");
    cc::Build::new()
        .file("csrc/logger_shim.c")
        .warnings(true)
        .compile("uq_driver_logger_shim");
}
