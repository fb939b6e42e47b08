//! `railuq._railuq`: the extension module of the Python package, a thin layer over the
//! uq-driver library's public API. Everything a user sees is in the Python package
//! (`python/railuq/`), which wraps these functions and classes: the conversions to numpy and
//! pandas, the progress display and the logging are Python; the studies, the runs, the
//! statistics and the error messages are the library's.
//!
//! Errors become the exceptions of `railuq._errors` with the command line's text
//! ([`uq_driver::cli::error_message`]); long calls release the GIL; a study runs on its own
//! thread while the calling thread keeps checking for Ctrl-C ([`study::PyStudy::run`]).

mod convert;
mod study;
mod surrogate;

use std::path::PathBuf;
use std::sync::Mutex;

use pyo3::prelude::*;
use uq_driver::fmu::FixedValue;

/// The library's messages (notes and warnings) since the Python layer last took them.
static MESSAGES: Mutex<Vec<String>> = Mutex::new(Vec::new());

/// Takes the library's messages queued since the last call.
#[pyfunction]
fn take_messages() -> Vec<String> {
    std::mem::take(&mut *MESSAGES.lock().unwrap_or_else(|e| e.into_inner()))
}

/// The exception `kind` of `railuq._errors` (`StudyError`, `FmuError`, `RunError`,
/// `Incomplete`, `SurrogateError`) carrying the command line's text for `e`.
pub(crate) fn error(py: Python<'_>, kind: &str, e: anyhow::Error) -> PyErr {
    let message = uq_driver::cli::error_message(&e);
    let class = py.import("railuq._errors").and_then(|m| m.getattr(kind));
    match class.and_then(|c| c.call1((message.clone(),))) {
        Ok(exc) => PyErr::from_value(exc),
        Err(_) => pyo3::exceptions::PyRuntimeError::new_err(message),
    }
}

/// Adds the folder of the FMUs the package ships to the library's FMU search path.
#[pyfunction]
fn add_fmu_dir(dir: PathBuf) {
    uq_driver::spec::add_fmu_dir(dir);
}

/// The built-in studies: (name, TOML text).
#[pyfunction]
fn builtins() -> Vec<(&'static str, &'static str)> {
    uq_driver::spec::BUILTINS.to_vec()
}

/// The command line with `args` (the first names the program); returns the exit status.
#[pyfunction]
fn cli_main(py: Python<'_>, args: Vec<String>) -> i32 {
    let code = py.detach(move || uq_driver::cli::main_with(args));
    if code == std::process::ExitCode::SUCCESS {
        0
    } else {
        1
    }
}

/// What [`simulate`] returns: the recorded variables' names, the times, a series per name, and
/// the FMU's String calculated parameters (name, value) read after the run.
type Series = (Vec<String>, Vec<f64>, Vec<Vec<f64>>, Vec<(String, String)>);

/// One run of an FMU, as `uq-driver simulate`: (names, times, series per name, calculated
/// strings).
#[pyfunction]
#[pyo3(signature = (fmu, set, outputs, start=None, stop=None, step=None))]
fn simulate(
    py: Python<'_>,
    fmu: PathBuf,
    set: Vec<(String, Bound<'_, PyAny>)>,
    outputs: Vec<String>,
    start: Option<f64>,
    stop: Option<f64>,
    step: Option<f64>,
) -> PyResult<Series> {
    let set: Vec<(String, FixedValue)> = set
        .into_iter()
        .map(|(name, v)| Ok((name.clone(), convert::fixed_value(&name, &v)?)))
        .collect::<PyResult<_>>()?;
    let sim = py
        .detach(|| uq_driver::cli::simulate(&fmu, &set, &outputs, start, stop, step))
        .map_err(|e| error(py, kind_of(&e), e))?;
    Ok((sim.names, sim.times, sim.series, sim.calculated_strings))
}

/// The exception class for an error of the library (by its type, looking through the
/// context the command line adds).
pub(crate) fn kind_of(e: &anyhow::Error) -> &'static str {
    use uq_driver::study::{RunError, StudyRunError};
    for cause in e.chain() {
        if cause.is::<uq_driver::spec::StudyError>() {
            return "StudyError";
        }
        if cause.is::<uq_driver::fmu::FmuError>() {
            return "FmuError";
        }
        if let Some(r) = cause.downcast_ref::<RunError>() {
            return run_error_kind(r);
        }
        if let Some(s) = cause.downcast_ref::<StudyRunError>() {
            return match s {
                StudyRunError::Study(_) | StudyRunError::Size(_) => "StudyError",
                StudyRunError::Run(r) => run_error_kind(r),
                StudyRunError::Incomplete { .. } => "Incomplete",
                _ => "RunError",
            };
        }
        if cause.is::<uq_driver::uq::surrogate::SurrogateError>() {
            return "SurrogateError";
        }
    }
    "RunError"
}

fn run_error_kind(r: &uq_driver::study::RunError) -> &'static str {
    use uq_driver::study::RunError;
    match r {
        RunError::Fmu(_) => "FmuError",
        RunError::Interface(_) => "StudyError",
        _ => "RunError",
    }
}

/// The extension module of the `railuq` package (see the package's documentation).
#[pymodule]
fn _railuq(m: &Bound<'_, PyModule>) -> PyResult<()> {
    uq_driver::study::set_message_sink(Some(Box::new(|line| {
        MESSAGES
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .push(line.to_owned());
    })));
    m.add_function(wrap_pyfunction!(take_messages, m)?)?;
    m.add_function(wrap_pyfunction!(add_fmu_dir, m)?)?;
    m.add_function(wrap_pyfunction!(builtins, m)?)?;
    m.add_function(wrap_pyfunction!(cli_main, m)?)?;
    m.add_function(wrap_pyfunction!(simulate, m)?)?;
    m.add_function(wrap_pyfunction!(convert::toml_from_dict, m)?)?;
    m.add_class::<study::PyStudy>()?;
    m.add_class::<surrogate::PySurrogate>()?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
