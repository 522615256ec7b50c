//! `Integration`: a run that advances on request (`Model.integration`), over
//! the runtime's `Integration`.

use crate::errors::failed;
use crate::kind;
use lagc_runtime::driver::Ending;
use lagc_runtime::integration::{Advance, Integration};
use lagc_runtime::summary::Summary;
use numpy::{IntoPyArray, PyArray1};
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
}

impl PyIntegration {
    pub(crate) fn new(run: Integration<'static>) -> PyIntegration {
        PyIntegration { run }
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
            return Err(pyo3::exceptions::PyValueError::new_err(format!(
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
