//! `railuq._railuq.Study`: a validated study ([`uq_driver::spec::Study`]) and its run.

use std::path::PathBuf;
use std::sync::{Arc, Condvar, Mutex};
use std::time::Duration;

use anyhow::Context;
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use uq_driver::spec::Study;
use uq_driver::study::{run_study, Outcome, RunControl, RunOptions, StudyResult};

use crate::{convert, error, kind_of, take_messages};

/// How often the calling thread wakes up while a study runs: to check for Ctrl-C, pass the
/// progress and the library's messages to Python.
const TICK: Duration = Duration::from_millis(100);

/// A study, parsed and validated by the library.
#[pyclass(name = "Study", module = "railuq._railuq", frozen)]
pub(crate) struct PyStudy {
    inner: Study,
}

/// Set once the study's thread is done; the calling thread waits on it with the GIL released.
#[derive(Default)]
struct Done {
    done: Mutex<bool>,
    cv: Condvar,
}

impl Done {
    fn set(&self) {
        *self.done.lock().unwrap_or_else(|e| e.into_inner()) = true;
        self.cv.notify_all();
    }

    /// Waits up to `t`; whether the study is done.
    fn wait(&self, t: Duration) -> bool {
        let g = self.done.lock().unwrap_or_else(|e| e.into_inner());
        let (g, _) = self
            .cv
            .wait_timeout_while(g, t, |d| !*d)
            .unwrap_or_else(|e| e.into_inner());
        *g
    }
}

#[pymethods]
impl PyStudy {
    /// A study file, or `builtin:NAME` (as `uq-driver run` takes them).
    #[staticmethod]
    fn load(py: Python<'_>, spec: &str) -> PyResult<PyStudy> {
        let inner = Study::load(spec).map_err(|e| error(py, "StudyError", e.into()))?;
        Ok(PyStudy { inner })
    }

    /// A study from its TOML text; `origin` names it in messages, relative paths start from
    /// `base`.
    #[staticmethod]
    #[pyo3(signature = (text, origin, base=None))]
    fn parse(py: Python<'_>, text: &str, origin: &str, base: Option<PathBuf>) -> PyResult<PyStudy> {
        let inner = Study::parse(text, origin, base.as_deref())
            .map_err(|e| error(py, "StudyError", e.into()))?;
        Ok(PyStudy { inner })
    }

    #[getter]
    fn name(&self) -> &str {
        &self.inner.name
    }

    #[getter]
    fn description(&self) -> &str {
        &self.inner.description
    }

    #[getter]
    fn origin(&self) -> &str {
        &self.inner.origin
    }

    /// The TOML text.
    #[getter]
    fn source(&self) -> &str {
        &self.inner.source
    }

    #[getter]
    fn fmu(&self) -> Option<PathBuf> {
        self.inner.fmu_path.clone()
    }

    #[getter]
    fn parameters(&self) -> Vec<String> {
        self.inner
            .parameters
            .iter()
            .map(|p| p.name.clone())
            .collect()
    }

    #[getter]
    fn outputs(&self) -> Vec<String> {
        self.inner.outputs.clone()
    }

    #[getter]
    fn quantities(&self) -> Vec<String> {
        self.inner.qoi.iter().map(|q| q.name().to_owned()).collect()
    }

    /// The method, in words.
    #[getter]
    fn method(&self) -> String {
        self.inner.method().label(self.inner.parameters.len())
    }

    #[getter]
    fn seed(&self) -> u64 {
        self.inner.seed
    }

    /// `(start, stop, step)` of the experiment (s).
    #[getter]
    fn experiment(&self) -> (f64, f64, f64) {
        let e = &self.inner.experiment;
        (e.start, e.stop, e.step)
    }

    /// The variants' names, for a suite (else None).
    #[getter]
    fn variants(&self) -> Option<Vec<String>> {
        self.inner
            .suite
            .as_ref()
            .map(|s| s.variants.iter().map(|v| v.name.clone()).collect())
    }

    /// The checks of `uq-driver run` before it runs: every FMU is found (else an error
    /// listing where it was looked for); `cov` values that look like percentages warned about.
    fn check(&self, py: Python<'_>) -> PyResult<()> {
        uq_driver::cli::check_study(&self.inner).map_err(|e| error(py, kind_of(&e), e))
    }

    /// Runs the study into `out` on a thread of its own, the GIL released, and returns its
    /// result as plain objects: for a study a dict (see `convert::result`), for a suite a
    /// list of `(variant, dict)`. `callback(done, total, messages)` is called every tick
    /// (progress and the library's messages). Ctrl-C (or an exception raised by the
    /// callback) stops the study as the command line's Ctrl-C does: no point starts after
    /// it, the finished points are kept in the results store, a run into `out` resumes; then
    /// the KeyboardInterrupt (or the callback's exception) is raised.
    #[pyo3(signature = (out, threads=None, fresh=false, allow_failures=false, report=true, yes=false, callback=None))]
    #[expect(
        clippy::too_many_arguments,
        reason = "the keyword arguments of Study.run in Python, each optional"
    )]
    fn run(
        &self,
        py: Python<'_>,
        out: PathBuf,
        threads: Option<usize>,
        fresh: bool,
        allow_failures: bool,
        report: bool,
        yes: bool,
        callback: Option<Bound<'_, PyAny>>,
    ) -> PyResult<Py<PyAny>> {
        self.check(py)?;
        let control = Arc::new(RunControl::default());
        let mut opts = RunOptions::default()
            .with_fresh(fresh)
            .with_allow_failures(allow_failures)
            .with_no_report(!report)
            .with_yes(yes)
            .with_control(Arc::clone(&control));
        if let Some(t) = threads {
            opts = opts.with_threads(t);
        }
        let study = &self.inner;
        let done = Done::default();
        let (joined, stop_reason) = std::thread::scope(|scope| {
            let worker = scope.spawn(|| {
                let r = run_study(study, &out, &opts);
                done.set();
                r
            });
            let mut stop_reason: Option<PyErr> = None;
            loop {
                let finished = py.detach(|| done.wait(TICK));
                let tick = || -> PyResult<()> {
                    if let Some(cb) = &callback {
                        let (n, total) = control.progress();
                        cb.call1((n, total, take_messages()))?;
                    }
                    py.check_signals()
                };
                if let Err(e) = tick() {
                    // The first reason to stop wins; a second Ctrl-C while the points in
                    // flight finish changes nothing.
                    control.stop();
                    stop_reason.get_or_insert(e);
                }
                if finished {
                    break;
                }
            }
            (worker.join(), stop_reason)
        });
        let outcome = joined.map_err(|p| {
            let what = p
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| p.downcast_ref::<String>().cloned())
                .unwrap_or_default();
            PyRuntimeError::new_err(format!(
                "internal error: the study's thread panicked: {what}"
            ))
        })?;
        if let Some(e) = stop_reason {
            return Err(e);
        }
        let outcome = outcome
            .with_context(|| format!("study {}", study.origin))
            .map_err(|e| error(py, kind_of(&e), e))?;
        let names = |s: &Study| s.parameters.iter().map(|p| p.name.clone()).collect();
        match outcome {
            Outcome::Study(r) => Ok(convert::result(py, &r, names(study))?.into_any().unbind()),
            Outcome::Suite(s) => {
                let variants = study.suite.as_ref().map(|s| &s.variants[..]).unwrap_or(&[]);
                let items = s
                    .variants
                    .iter()
                    .zip(variants)
                    .map(|(r, v): (&StudyResult, &Study)| {
                        Ok((v.name.clone(), convert::result(py, r, names(v))?))
                    })
                    .collect::<PyResult<Vec<(String, Bound<'_, PyDict>)>>>()?;
                Ok(items.into_pyobject(py)?.into_any().unbind())
            }
            _ => Err(PyRuntimeError::new_err(
                "internal error: a kind of study result this version of the package does not know",
            )),
        }
    }

    fn __repr__(&self) -> String {
        format!("<railuq.Study {} ({})>", self.inner.name, self.inner.origin)
    }
}
