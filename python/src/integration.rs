//! `Integration`: a run that advances on request (`Model.integration`), over
//! the runtime's `Integration`.

use crate::errors::{failed, unknown};
use crate::kind;
use lagc_runtime::driver::Ending;
use lagc_runtime::integration::{Advance, Integration};
use lagc_runtime::model::Inputs;
use lagc_runtime::summary::Summary;
use numpy::{IntoPyArray, PyArray1};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// A run that advances on request: `it.advance_to(t)` steps only as far as
/// needed (the state at `t` from the continuous extension of the step that
/// covers it), `it.t` and `it.state` are where it stands, `it.restart(t,
/// state)` starts it anew from a given state. Made by `Model.integration`;
/// used from the thread that made it.
#[pyclass(name = "Integration", unsendable)]
pub struct PyIntegration {
    run: Integration<'static>,
    /// The inputs' values, held since the last `set_input`.
    inputs: Vec<f64>,
}

impl PyIntegration {
    pub(crate) fn new(run: Integration<'static>, inputs: Vec<f64>) -> PyIntegration {
        PyIntegration { run, inputs }
    }
}

#[pymethods]
impl PyIntegration {
    /// The time the integration stands at.
    #[getter]
    fn t(&self) -> f64 {
        self.run.t()
    }

    /// The state at `t` (a copy), in the order of `Model.state_names`.
    #[getter]
    fn state<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.run.state().to_vec().into_pyarray(py)
    }

    /// The output columns at `t` by name.
    #[getter]
    fn outputs<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let model = self.run.model();
        let mut values = vec![0.0; model.output_names().len()];
        model.outputs(self.run.t(), self.run.state(), &mut values);
        let dict = PyDict::new(py);
        for (name, value) in model.output_names().iter().zip(values) {
            dict.set_item(name, value)?;
        }
        Ok(dict)
    }

    /// The last time the integration may advance to.
    #[getter]
    fn end(&self) -> f64 {
        self.run.end()
    }

    /// Where `stop when` (or impacts coming to rest) ended the motion;
    /// None while it goes on.
    #[getter]
    fn stopped_at(&self) -> Option<f64> {
        match self.run.finished() {
            Some(Ok(Ending::Stopped(t) | Ending::Rest { at: t, .. })) => Some(*t),
            _ => None,
        }
    }

    /// Advances to `t` (later than `it.t`, at most `it.end`) and returns
    /// the time reached: `t`, or where the motion ended before it
    /// (`it.stopped_at`). Raises IntegrationError when the run fails.
    fn advance_to(&mut self, py: Python<'_>, t: f64) -> PyResult<f64> {
        match self.run.advance_to(t) {
            Ok(Advance::Reached(t)) => Ok(t),
            Ok(Advance::Ended(_)) => Ok(self.run.t()),
            Err(failure) => Err(failed(py, kind(), &failure, Default::default())),
        }
    }

    /// Starts the integration anew from `state` at `t` (from the
    /// integration's start up to its end; the field re-anchored there).
    /// Values the constraints fix are checked against them, as initial
    /// values are (IntegrationError naming the component), or, with
    /// `project=True`, projected onto them first as the run keeps them
    /// (along their normals, which may move every velocity they involve).
    #[pyo3(signature = (t, state, project=false))]
    fn restart(&mut self, py: Python<'_>, t: f64, state: Vec<f64>, project: bool) -> PyResult<()> {
        let n = self.run.state().len();
        if state.len() != n {
            return Err(PyValueError::new_err(format!(
                "the state has {n} components, not {}",
                state.len()
            )));
        }
        let mut state = state;
        let restarted = if project {
            self.run.put_on_constraints(t, &mut state)
        } else {
            Ok(())
        };
        restarted
            .and_then(|()| self.run.restart_from(t, &state))
            .map_err(|failure| failed(py, kind(), &failure, Default::default()))
    }

    /// The inputs' values by name (held since they were last set).
    #[getter]
    fn inputs<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let dict = PyDict::new(py);
        for (name, value) in kind().input_names.iter().zip(&self.inputs) {
            dict.set_item(name, value)?;
        }
        Ok(dict)
    }

    /// Sets input `name` to `value` from `it.t` on (held until set again).
    /// A new value is a discontinuity: the integration restarts at `it.t`
    /// (as `lagc run --input` and the FMU restart at a change), the
    /// components the constraints fix recomputed under it. Setting the
    /// value it has changes nothing. KeyError for an unknown input.
    fn set_input(&mut self, py: Python<'_>, name: &str, value: f64) -> PyResult<()> {
        let kind = kind();
        let index = kind
            .input_names
            .iter()
            .position(|n| *n == name)
            .ok_or_else(|| unknown("input", name, kind.input_names))?;
        if !value.is_finite() {
            return Err(PyValueError::new_err(format!(
                "input `{name}`: {value} is not a finite number"
            )));
        }
        if self.inputs[index] == value {
            return Ok(());
        }
        let mut inputs = self.inputs.clone();
        inputs[index] = value;
        self.run
            .set_inputs(&Inputs::held(&inputs))
            .map_err(|failure| failed(py, kind, &failure, Default::default()))?;
        self.inputs = inputs;
        Ok(())
    }

    /// The work so far, as `lagc run --summary json` reports it.
    #[getter]
    fn stats<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let summary = Summary {
            outcome: self.run.outcome(),
            wall_time: std::time::Duration::ZERO,
            runs: 1,
            exact_error: None,
            estimated_error: None,
        };
        py.import("json")?.call_method1("loads", (summary.json(),))
    }
}
