//! `Solution`: a run's rows as NumPy arrays, by the model's names.

use crate::errors::unknown;
use crate::Kind;
use lagc_runtime::table::Table;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArray3, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

/// A solved motion at the requested times (the rows `lagc run` prints):
/// `t` (k,), `y` (k, number of state components), a state component by
/// name (`sol["q1'"]`), the outputs by name (`sol.outputs["E"]`), the
/// summary's figures (`sol.stats`, those of `--summary json`) and the time
/// `stop when` (or resting impacts) ended the run, `sol.stopped_at` (None
/// when the run reached its end).
#[pyclass(name = "Solution", frozen)]
pub struct PySolution {
    t: Py<PyArray1<f64>>,
    y: Py<PyArray2<f64>>,
    outputs: Py<PyArray2<f64>>,
    state_names: Vec<String>,
    output_names: Vec<String>,
    /// The summary as `--summary json` prints it (parsed when asked).
    stats: Option<String>,
    stopped_at: Option<f64>,
    /// `solve(..., sensitivity=True)`: (k, N, columns) and the columns'
    /// names.
    sensitivity: Option<Py<PyArray3<f64>>>,
    sensitivity_names: Vec<String>,
}

fn matrix<'py>(
    py: Python<'py>,
    data: Vec<f64>,
    rows: usize,
    columns: usize,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    data.into_pyarray(py).reshape([rows, columns])
}

impl PySolution {
    pub(crate) fn from_table(
        py: Python<'_>,
        kind: &Kind,
        table: Table,
        stats: Option<String>,
        stopped_at: Option<f64>,
    ) -> PySolution {
        let k = table.t.len();
        let (n, m) = (kind.state_names.len(), kind.output_names.len());
        // The runtime fills whole rows: the shapes always fit.
        let y = matrix(py, table.states, k, n).expect("k rows of the state");
        let outputs = matrix(py, table.outputs, k, m).expect("k rows of the outputs");
        PySolution {
            t: table.t.into_pyarray(py).unbind(),
            y: y.unbind(),
            outputs: outputs.unbind(),
            state_names: kind.state_names.iter().map(|s| s.to_string()).collect(),
            output_names: kind.output_names.iter().map(|s| s.to_string()).collect(),
            stats,
            stopped_at,
            sensitivity: None,
            sensitivity_names: Vec::new(),
        }
    }

    /// The solution with its sensitivities: `rows[r][c·N + i]` is
    /// `∂x_i/∂names[c]` at the `r`-th time.
    pub(crate) fn with_sensitivity(
        mut self,
        py: Python<'_>,
        rows: Vec<Vec<f64>>,
        names: Vec<String>,
    ) -> PyResult<PySolution> {
        let (k, n, m) = (self.t.bind(py).len(), self.state_names.len(), names.len());
        if rows.len() != k || rows.iter().any(|r| r.len() != n * m) {
            return Err(pyo3::exceptions::PyRuntimeError::new_err(format!(
                "the sensitivities have {} rows for {k} times (internal)",
                rows.len()
            )));
        }
        let mut data = Vec::with_capacity(k * n * m);
        for row in &rows {
            for i in 0..n {
                data.extend((0..m).map(|c| row[c * n + i]));
            }
        }
        self.sensitivity = Some(data.into_pyarray(py).reshape([k, n, m])?.unbind());
        self.sensitivity_names = names;
        Ok(self)
    }

    /// The CSV's column names: `t`, the state, the outputs.
    pub(crate) fn columns(&self) -> Vec<String> {
        let mut names = vec!["t".to_string()];
        names.extend(self.state_names.iter().cloned());
        names.extend(self.output_names.iter().cloned());
        names
    }

    /// The CSV's rows: `t`, the state, the outputs.
    pub(crate) fn rows<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let t = self.t.bind(py).readonly();
        let y = self.y.bind(py).readonly();
        let outputs = self.outputs.bind(py).readonly();
        let (t, y, outputs) = (t.as_array(), y.as_array(), outputs.as_array());
        let width = 1 + y.ncols() + outputs.ncols();
        let mut data = Vec::with_capacity(t.len() * width);
        for (i, &ti) in t.iter().enumerate() {
            data.push(ti);
            data.extend(y.row(i).iter());
            data.extend(outputs.row(i).iter());
        }
        matrix(py, data, t.len(), width)
    }
}

#[pymethods]
impl PySolution {
    /// Rebuilds a solution from its parts (what pickling stores).
    #[new]
    #[pyo3(signature = (t, y, outputs, state_names, output_names, stats=None, stopped_at=None, sensitivity=None, sensitivity_names=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        t: Bound<'_, PyArray1<f64>>,
        y: Bound<'_, PyArray2<f64>>,
        outputs: Bound<'_, PyArray2<f64>>,
        state_names: Vec<String>,
        output_names: Vec<String>,
        stats: Option<String>,
        stopped_at: Option<f64>,
        sensitivity: Option<Bound<'_, PyArray3<f64>>>,
        sensitivity_names: Option<Vec<String>>,
    ) -> PyResult<PySolution> {
        let rows = t.len();
        let (y_shape, out_shape) = (y.shape().to_vec(), outputs.shape().to_vec());
        if y_shape != [rows, state_names.len()] || out_shape != [rows, output_names.len()] {
            return Err(pyo3::exceptions::PyValueError::new_err(format!(
                "the arrays' shapes {y_shape:?} and {out_shape:?} do not fit {rows} times, \
                 {} state components and {} outputs",
                state_names.len(),
                output_names.len()
            )));
        }
        Ok(PySolution {
            t: t.unbind(),
            y: y.unbind(),
            outputs: outputs.unbind(),
            state_names,
            output_names,
            stats,
            stopped_at,
            sensitivity: sensitivity.map(Bound::unbind),
            sensitivity_names: sensitivity_names.unwrap_or_default(),
        })
    }

    /// `solve(..., sensitivity=True)`: ∂x(t)/∂(y0, p), (k, number of state
    /// components, len(sensitivity_names)); None otherwise.
    #[getter]
    fn sensitivity(&self, py: Python<'_>) -> Option<Py<PyArray3<f64>>> {
        self.sensitivity.as_ref().map(|s| s.clone_ref(py))
    }

    /// The sensitivity's last axis: the stated initial values (`Y0`), then
    /// the params.
    #[getter]
    fn sensitivity_names(&self) -> Vec<String> {
        self.sensitivity_names.clone()
    }

    /// The output times, (k,).
    #[getter]
    fn t(&self, py: Python<'_>) -> Py<PyArray1<f64>> {
        self.t.clone_ref(py)
    }

    /// The state at the output times, (k, number of state components), in
    /// the order of `state_names` (the CSV's columns after `t`).
    #[getter]
    fn y(&self, py: Python<'_>) -> Py<PyArray2<f64>> {
        self.y.clone_ref(py)
    }

    /// The state components' names.
    #[getter]
    fn state_names(&self) -> Vec<String> {
        self.state_names.clone()
    }

    /// The output columns' names.
    #[getter]
    fn output_names(&self) -> Vec<String> {
        self.output_names.clone()
    }

    /// Every output column by name: `{"E": array, ...}`.
    #[getter]
    fn outputs<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let dict = PyDict::new(py);
        let outputs = self.outputs.bind(py).readonly();
        let outputs = outputs.as_array();
        for (j, name) in self.output_names.iter().enumerate() {
            dict.set_item(name, outputs.column(j).to_owned().into_pyarray(py))?;
        }
        Ok(dict)
    }

    /// The run's figures as `lagc run --summary json` prints them (steps,
    /// rejected steps, right-side evaluations, …); None for the rows
    /// before a failure.
    #[getter]
    fn stats<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        match &self.stats {
            None => Ok(None),
            Some(json) => Ok(Some(
                py.import("json")?.call_method1("loads", (json.as_str(),))?,
            )),
        }
    }

    /// Where `stop when` (or impacts coming to rest) ended the run; None
    /// when it reached its end.
    #[getter]
    fn stopped_at(&self) -> Option<f64> {
        self.stopped_at
    }

    /// The CSV's column names: `t`, the state, the outputs.
    #[getter(columns)]
    fn py_columns(&self) -> Vec<String> {
        self.columns()
    }

    /// The CSV's rows as one array: `t`, the state, the outputs.
    #[getter(rows)]
    fn py_rows<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        self.rows(py)
    }

    /// A state component or an output by name, (k,).
    fn __getitem__<'py>(&self, py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyArray1<f64>>> {
        if let Some(i) = self.state_names.iter().position(|s| s == name) {
            let y = self.y.bind(py).readonly();
            return Ok(y.as_array().column(i).to_owned().into_pyarray(py));
        }
        if let Some(j) = self.output_names.iter().position(|s| s == name) {
            let outputs = self.outputs.bind(py).readonly();
            return Ok(outputs.as_array().column(j).to_owned().into_pyarray(py));
        }
        let known: Vec<&str> = self
            .state_names
            .iter()
            .chain(&self.output_names)
            .map(String::as_str)
            .collect();
        Err(unknown("column", name, &known))
    }

    fn __len__(&self, py: Python<'_>) -> usize {
        self.t.bind(py).len()
    }

    fn __repr__(&self, py: Python<'_>) -> String {
        let rows = self.t.bind(py).len();
        let ending = match self.stopped_at {
            Some(t) => format!(", stopped at t = {t}"),
            None => String::new(),
        };
        format!(
            "Solution({rows} times; state {}; outputs {}{ending})",
            self.state_names.join(", "),
            if self.output_names.is_empty() {
                "none".to_string()
            } else {
                self.output_names.join(", ")
            }
        )
    }

    fn __reduce__<'py>(
        slf: &Bound<'py, Self>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        let py = slf.py();
        let this = slf.get();
        let args = (
            this.t.clone_ref(py),
            this.y.clone_ref(py),
            this.outputs.clone_ref(py),
            this.state_names.clone(),
            this.output_names.clone(),
            this.stats.clone(),
            this.stopped_at,
            this.sensitivity.as_ref().map(|s| s.clone_ref(py)),
            this.sensitivity_names.clone(),
        )
            .into_pyobject(py)?;
        Ok((slf.get_type().into_any(), args))
    }
}
