//! Python values to the library's and back: a study as a dict to TOML text, a parameter's
//! value, a study's result as plain Python objects (the package makes numpy arrays of them).

use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use uq_driver::fmu::FixedValue;
use uq_driver::results::OutputStats;
use uq_driver::study::StudyResult;

/// A study given as a dict (the schema of the TOML file) as TOML text: tables are dicts,
/// arrays lists or tuples, values bool, int, float or str (numpy scalars and arrays too).
#[pyfunction]
pub(crate) fn toml_from_dict(d: &Bound<'_, PyAny>) -> PyResult<String> {
    let toml::Value::Table(t) = value("", d)? else {
        return Err(PyTypeError::new_err(format!(
            "a study is a dict (the tables and keys of the TOML file), not {}",
            type_name(d)
        )));
    };
    toml::to_string(&t).map_err(|e| PyTypeError::new_err(format!("the study as TOML: {e}")))
}

fn type_name(v: &Bound<'_, PyAny>) -> String {
    v.get_type()
        .name()
        .map(|n| n.to_string())
        .unwrap_or_else(|_| "?".into())
}

/// `v` at key path `at` as a TOML value.
fn value(at: &str, v: &Bound<'_, PyAny>) -> PyResult<toml::Value> {
    let key = |k: &str| {
        if at.is_empty() {
            k.to_owned()
        } else {
            format!("{at}.{k}")
        }
    };
    if v.is_instance_of::<PyBool>() {
        return Ok(toml::Value::Boolean(v.extract()?));
    }
    if v.is_instance_of::<PyString>() {
        return Ok(toml::Value::String(v.extract()?));
    }
    if v.is_instance_of::<PyFloat>() {
        return Ok(toml::Value::Float(v.extract()?));
    }
    if v.is_instance_of::<PyInt>() {
        return v.extract::<i64>().map(toml::Value::Integer).map_err(|_| {
            PyTypeError::new_err(format!("'{at}': the integer {v} does not fit in 64 bits"))
        });
    }
    if let Ok(d) = v.cast::<PyDict>() {
        let mut t = toml::Table::new();
        for (k, item) in d.iter() {
            let Ok(k) = k.extract::<String>() else {
                return Err(PyTypeError::new_err(format!(
                    "'{at}': the keys of a table are strings, not {}",
                    type_name(&k)
                )));
            };
            if item.is_none() {
                // TOML has no null: a key set to None is left out.
                continue;
            }
            let val = value(&key(&k), &item)?;
            t.insert(k, val);
        }
        return Ok(toml::Value::Table(t));
    }
    if v.is_instance_of::<PyList>() || v.is_instance_of::<PyTuple>() {
        let items = v
            .try_iter()?
            .enumerate()
            .map(|(i, item)| value(&format!("{at}[{i}]"), &item?))
            .collect::<PyResult<Vec<_>>>()?;
        return Ok(toml::Value::Array(items));
    }
    // numpy: arrays and scalars have tolist() (to Python lists and numbers).
    if v.hasattr("tolist")? {
        let plain = v.call_method0("tolist")?;
        if !plain.is(v) && !plain.hasattr("tolist")? {
            return value(at, &plain);
        }
    }
    if v.is_none() {
        return Err(PyTypeError::new_err(format!(
            "'{at}': None has no TOML value (leave the key out)"
        )));
    }
    Err(PyTypeError::new_err(format!(
        "'{at}': a {} has no TOML value (use a dict, list, bool, int, float or str)",
        type_name(v)
    )))
}

/// A parameter's value for `simulate(set=...)`: a bool, a number, or a text (as `--set`).
pub(crate) fn fixed_value(name: &str, v: &Bound<'_, PyAny>) -> PyResult<FixedValue> {
    if v.is_instance_of::<PyBool>() {
        return Ok(FixedValue::Bool(v.extract()?));
    }
    if v.is_instance_of::<PyString>() {
        return Ok(FixedValue::Text(v.extract()?));
    }
    if let Ok(x) = v.extract::<f64>() {
        return Ok(FixedValue::Number(x));
    }
    Err(PyTypeError::new_err(format!(
        "set['{name}']: a {} is not a value of a variable (bool, number or str)",
        type_name(v)
    )))
}

/// One output's statistics over time as a dict of lists (see `railuq.Results`).
fn output<'py>(py: Python<'py>, o: &OutputStats) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("name", &o.name)?;
    d.set_item("unit", &o.unit)?;
    d.set_item("times", &o.times)?;
    d.set_item("mean", &o.mean)?;
    d.set_item("std", &o.std)?;
    d.set_item("lower_3sigma", &o.lower_3sigma)?;
    d.set_item("upper_3sigma", &o.upper_3sigma)?;
    d.set_item("quantiles", &o.quantiles)?;
    d.set_item("std_pce", &o.std_pce)?;
    d.set_item("std_error_mean", &o.std_error_mean)?;
    let sobol = match &o.sobol {
        None => None,
        Some(s) => {
            let sd = PyDict::new(py);
            sd.set_item("first", &s.first)?;
            sd.set_item("total", &s.total)?;
            if let Some(ci) = &s.intervals {
                sd.set_item("level", ci.level)?;
                sd.set_item("first_ci", &ci.first)?;
                sd.set_item("total_ci", &ci.total)?;
            }
            Some(sd)
        }
    };
    d.set_item("sobol", sobol)?;
    Ok(d)
}

/// A study's result: `outputs` (a dict per output), `quantities` (the JSON of
/// `summary.json`'s quantities, exactly), `parameters` (names, in study order) and the
/// `warnings` not yet printed.
pub(crate) fn result<'py>(
    py: Python<'py>,
    r: &StudyResult,
    parameters: Vec<String>,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let outputs = r
        .outputs
        .iter()
        .map(|o| output(py, o))
        .collect::<PyResult<Vec<_>>>()?;
    d.set_item("outputs", outputs)?;
    let quantities = serde_json::to_string(&r.quantities)
        .map_err(|e| PyTypeError::new_err(format!("quantities as JSON: {e}")))?;
    d.set_item("quantities_json", quantities)?;
    d.set_item("parameters", parameters)?;
    d.set_item(
        "warnings",
        r.summary
            .warnings
            .iter()
            .skip(r.warnings_shown)
            .collect::<Vec<_>>(),
    )?;
    Ok(d)
}
