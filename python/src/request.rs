//! Python arguments → a run request of the runtime (`table::Request`),
//! names resolved to indices (an unknown one is a `KeyError` naming the
//! known ones), choices checked as the command line checks them.

use crate::errors::unknown;
use crate::Kind;
use lagc_runtime::driver::Options;
use lagc_runtime::inputs::{Interpolation, Signal};
use lagc_runtime::method::{IntegratorChoice, Method};
use lagc_runtime::table::Request;
use numpy::{PyArray1, PyArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// How to run, as `solve` and `solve_batch` take it.
pub(crate) struct RunOptions<'a> {
    pub method: &'a str,
    pub integrator: Option<&'a str>,
    pub rtol: Option<f64>,
    pub atol: Option<f64>,
    pub max_steps: Option<usize>,
    /// `global_error=False`: no global-error estimate (`Options::global_error`).
    pub global_error: bool,
}

impl RunOptions<'_> {
    pub fn options(&self) -> PyResult<Options> {
        let method = Method::parse(self.method).ok_or_else(|| {
            PyValueError::new_err(format!(
                "method `{}`: give \"field\" or \"direct\"",
                self.method
            ))
        })?;
        let mut options = Options {
            method,
            global_error: self.global_error,
            ..Options::default()
        };
        if let Some(text) = self.integrator {
            options.integrator = Some(IntegratorChoice::parse(text).ok_or_else(|| {
                PyValueError::new_err(format!(
                    "integrator `{text}`: give \"auto\", \"explicit\", \"stiff\" or \"magnus\""
                ))
            })?);
        }
        if let Some(rtol) = self.rtol {
            options.tol.rtol = rtol;
        }
        if let Some(atol) = self.atol {
            options.tol.atol = atol;
        }
        if let Some(steps) = self.max_steps {
            if steps == 0 {
                return Err(PyValueError::new_err("max_steps: give at least 1"));
            }
            options.max_steps = steps;
        }
        Ok(options)
    }
}

/// `{name: value}` → `(index, value)` among `names`.
pub(crate) fn by_name(
    what: &str,
    dict: Option<&Bound<'_, PyDict>>,
    names: &[&str],
) -> PyResult<Vec<(usize, f64)>> {
    let Some(dict) = dict else {
        return Ok(Vec::new());
    };
    let mut out = Vec::with_capacity(dict.len());
    for (key, value) in dict.iter() {
        let name: String = key.extract()?;
        let index = names
            .iter()
            .position(|n| *n == name)
            .ok_or_else(|| unknown(what, &name, names))?;
        out.push((index, value.extract::<f64>()?));
    }
    Ok(out)
}

/// Param overrides by name.
pub(crate) fn params(kind: &Kind, dict: Option<&Bound<'_, PyDict>>) -> PyResult<Vec<(usize, f64)>> {
    by_name("param", dict, kind.param_names)
}

/// Initial values by state component name (`"q1'"`).
pub(crate) fn initial(
    kind: &Kind,
    dict: Option<&Bound<'_, PyDict>>,
) -> PyResult<Vec<(usize, f64)>> {
    by_name("state component", dict, kind.state_names)
}

/// Input signals by name: `{"u": (times, values)}`, each a pair of
/// sequences (NumPy arrays or lists; one number each is a signal of one
/// row), held between rows or interpolated linearly (`input_interp`), as
/// `lagc run --input u=FILE.csv [--input-interp linear]` reads them.
pub(crate) fn inputs(
    kind: &Kind,
    dict: Option<&Bound<'_, PyDict>>,
    interpolation: &str,
) -> PyResult<Vec<(usize, Signal)>> {
    let interpolation = match interpolation {
        "hold" => Interpolation::Hold,
        "linear" => Interpolation::Linear,
        other => {
            return Err(PyValueError::new_err(format!(
                "input_interp `{other}`: give \"hold\" or \"linear\""
            )))
        }
    };
    let Some(dict) = dict else {
        return Ok(Vec::new());
    };
    let mut out = Vec::with_capacity(dict.len());
    for (key, value) in dict.iter() {
        let name: String = key.extract()?;
        let index = kind
            .input_names
            .iter()
            .position(|n| *n == name)
            .ok_or_else(|| unknown("input", &name, kind.input_names))?;
        let (t, v): (Bound<'_, PyAny>, Bound<'_, PyAny>) = value.extract().map_err(|_| {
            PyValueError::new_err(format!(
                "input `{name}`: give a pair (times, values) of equal lengths"
            ))
        })?;
        let signal = Signal::new(times(&t)?, times(&v)?, interpolation)
            .map_err(|e| PyValueError::new_err(format!("input `{name}`: {e}")))?;
        out.push((index, signal));
    }
    Ok(out)
}

/// Output times (or any numbers) from a NumPy array, a sequence or one
/// number.
pub(crate) fn times(t: &Bound<'_, PyAny>) -> PyResult<Vec<f64>> {
    if let Ok(array) = t.cast::<PyArray1<f64>>() {
        return Ok(array.readonly().as_array().to_vec());
    }
    if let Ok(value) = t.extract::<f64>() {
        return Ok(vec![value]);
    }
    t.extract::<Vec<f64>>()
}

/// The request of one run: the model's overrides, then the set's.
pub(crate) fn request(
    overrides: &[(usize, f64)],
    set: Vec<(usize, f64)>,
    inits: Vec<(usize, f64)>,
    options: Options,
    times: Option<Vec<f64>>,
    inputs: Vec<(usize, Signal)>,
) -> Request {
    let mut params = overrides.to_vec();
    params.extend(set);
    Request {
        params,
        inits,
        options,
        times,
        inputs,
    }
}
