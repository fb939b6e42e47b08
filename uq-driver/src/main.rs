//! `uq-driver`: the command line, [`uq_driver::cli`].
#![forbid(unsafe_code)]

fn main() -> std::process::ExitCode {
    uq_driver::cli::main()
}
