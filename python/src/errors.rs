//! Errors as a Python user meets them: `IntegrationError` for a run that
//! fails (one class for every model's module, so that `except
//! lagc.IntegrationError` catches all of them), `KeyError` for an unknown
//! name, naming the known ones.

use crate::solution::PySolution;
use crate::Kind;
use lagc_runtime::failure::Failure;
use lagc_runtime::table::Table;
use pyo3::exceptions::{PyKeyError, PyRuntimeError};
use pyo3::prelude::*;
use pyo3::types::{PyModule, PyType};

const DOC: &std::ffi::CStr =
    c"A run of a lagc model failed: the message `lagc run` prints (`str(e)`, \
`e.message`), the time `e.t`, the quantity `e.quantity` (a mass, a state component, a \
constraint as written, or the method's quantity such as `mass matrix`), and the rows computed \
before the failure, `e.solution` (a Solution) and `e.rows` (an array with the CSV's columns, \
`e.columns`).";

/// `lagc.IntegrationError`: the class of the module `lagc` when one is
/// importable (a model imported before made it), else made now, with a
/// module `lagc` in `sys.modules` holding it, so that every model's
/// module raises one class.
pub(crate) fn integration_error(py: Python<'_>) -> PyResult<Py<PyType>> {
    let lagc = match py.import("lagc") {
        Ok(module) => module,
        Err(_) => {
            let module = PyModule::new(py, "lagc")?;
            module.setattr(
                "__doc__",
                "What every Python module built by `lagc build --python` shares: \
                 IntegrationError.",
            )?;
            py.import("sys")?
                .getattr("modules")?
                .set_item("lagc", &module)?;
            module
        }
    };
    if let Ok(existing) = lagc.getattr("IntegrationError") {
        if let Ok(class) = existing.cast_into::<PyType>() {
            return Ok(class.unbind());
        }
    }
    let base = py.get_type::<PyRuntimeError>();
    let class = PyErr::new_type(py, c"lagc.IntegrationError", Some(DOC), Some(&base), None)?;
    lagc.setattr("IntegrationError", class.bind(py))?;
    Ok(class)
}

/// The `IntegrationError` of `failure`, with the rows of `table` before it.
pub(crate) fn failed(py: Python<'_>, kind: &Kind, failure: &Failure, table: Table) -> PyErr {
    match build_failed(py, kind, failure, table) {
        Ok(error) => error,
        Err(error) => error,
    }
}

fn build_failed(py: Python<'_>, kind: &Kind, failure: &Failure, table: Table) -> PyResult<PyErr> {
    let message = failure.to_string();
    let error = kind.error.bind(py).call1((message.clone(),))?;
    let solution = PySolution::from_table(py, kind, table, None, None);
    error.setattr("message", message)?;
    error.setattr("t", failure.time)?;
    error.setattr("quantity", failure.quantity())?;
    error.setattr("columns", solution.columns())?;
    error.setattr("rows", solution.rows(py)?)?;
    error.setattr("solution", Py::new(py, solution)?)?;
    Ok(PyErr::from_value(error))
}

/// `KeyError: no param `x`; the params are: M0, alpha`.
pub(crate) fn unknown(what: &str, name: &str, known: &[&str]) -> PyErr {
    let known = if known.is_empty() {
        format!("the model has no {what}s")
    } else {
        format!("the {what}s are: {}", known.join(", "))
    };
    PyKeyError::new_err(format!("no {what} `{name}`; {known}"))
}
