//! `railuq._railuq.Surrogate`: a study's chaos surrogate ([`uq_driver::uq::surrogate`]),
//! evaluated at many points per call (float64 bytes in and out, which the package views as
//! numpy arrays).

use std::path::PathBuf;

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyBytes;
use uq_driver::uq::surrogate::{Surrogate, SurrogateValues};

use crate::error;

/// A surrogate read from a study's folder (`surrogate.json`).
#[pyclass(name = "Surrogate", module = "railuq._railuq", frozen)]
pub(crate) struct PySurrogate {
    inner: Surrogate,
}

impl PySurrogate {
    /// Output or quantity `which` (outputs first, then quantities) of `v`, appended to `out`.
    fn pick(&self, v: &SurrogateValues, which: usize, out: &mut Vec<f64>) {
        let n_out = v.outputs.len();
        if which < n_out {
            out.extend_from_slice(&v.outputs[which]);
        } else {
            out.push(v.quantities[which - n_out]);
        }
    }

    fn check_which(&self, which: usize) -> PyResult<()> {
        let n = self.inner.file.outputs.len() + self.inner.file.quantities.len();
        if which >= n {
            return Err(PyValueError::new_err(format!(
                "the surrogate has {n} outputs and quantities, not {}",
                which + 1
            )));
        }
        Ok(())
    }
}

fn bytes<'py>(py: Python<'py>, v: &[f64]) -> Bound<'py, PyBytes> {
    PyBytes::new(py, bytemuck::cast_slice(v))
}

#[pymethods]
impl PySurrogate {
    /// Reads `DIR/surrogate.json` (or the file itself).
    #[staticmethod]
    fn load(py: Python<'_>, path: PathBuf) -> PyResult<PySurrogate> {
        let inner = Surrogate::load(&path).map_err(|e| error(py, "SurrogateError", e.into()))?;
        Ok(PySurrogate { inner })
    }

    /// The inputs' names, in the order of a point's values.
    #[getter]
    fn inputs(&self) -> Vec<String> {
        self.inner.inputs.iter().map(|p| p.name.clone()).collect()
    }

    /// `(name, times or None)` of every output, then every quantity (times None).
    #[getter]
    fn columns(&self) -> Vec<(String, Option<Vec<f64>>)> {
        let f = &self.inner.file;
        f.outputs
            .iter()
            .map(|c| (c.name.clone(), c.times.clone()))
            .chain(f.quantities.iter().map(|c| (c.name.clone(), None)))
            .collect()
    }

    /// The physical values of every input from `(name, value)` pairs; the others nominal.
    fn point(&self, py: Python<'_>, at: Vec<(String, f64)>) -> PyResult<Vec<f64>> {
        self.inner
            .point(&at)
            .map_err(|e| error(py, "SurrogateError", e.into()))
    }

    /// Column `which` at `n` points (`x`: n × inputs float64, row-major): n × its values.
    fn eval<'py>(
        &self,
        py: Python<'py>,
        x: &[u8],
        n: usize,
        which: usize,
    ) -> PyResult<Bound<'py, PyBytes>> {
        self.check_which(which)?;
        let d = self.inner.inputs.len();
        let x: Vec<f64> = x
            .chunks_exact(8)
            .map(|b| f64::from_ne_bytes(b.try_into().unwrap_or([0; 8])))
            .collect();
        if x.len() != n * d {
            return Err(PyValueError::new_err(format!(
                "{} values for {n} points of {d} inputs",
                x.len()
            )));
        }
        let values = py.detach(|| {
            let mut out = Vec::new();
            for row in x.chunks_exact(d.max(1)).take(n) {
                self.pick(&self.inner.eval(row), which, &mut out);
            }
            out
        });
        Ok(bytes(py, &values))
    }

    /// `n` random points of the inputs' joint law (point `i` from the stream `(seed, i)`, as
    /// `uq-driver surrogate sample`) and column `which` there: (n × inputs, n × values).
    fn sample<'py>(
        &self,
        py: Python<'py>,
        n: usize,
        seed: u64,
        which: usize,
    ) -> PyResult<(Bound<'py, PyBytes>, Bound<'py, PyBytes>)> {
        self.check_which(which)?;
        let (x, y) = py.detach(|| {
            let (mut x, mut y) = (Vec::new(), Vec::new());
            for (p, v) in self.inner.sample(n, seed) {
                x.extend_from_slice(&p);
                self.pick(&v, which, &mut y);
            }
            (x, y)
        });
        Ok((bytes(py, &x), bytes(py, &y)))
    }
}
