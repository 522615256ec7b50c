//! `Model(**params)`: the model with param values, solved by the runtime.

use crate::errors::failed;
use crate::integration::PyIntegration;
use crate::request::{self, RunOptions};
use crate::solution::PySolution;
use crate::{kind, Kind};
use lagc_runtime::driver::Ending;
use lagc_runtime::integration::Integration;
use lagc_runtime::table::{
    jacobian_at, ready, rhs_at, sensitivities, tabulate, tabulate_many, Request, TableError,
    Tabulated,
};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyTuple};

/// A lagc model with param values: `Model(alpha=2.0)` overrides the params
/// named (params computed from them follow, as with `lagc run --param`);
/// the others keep the file's values.
#[pyclass(name = "Model", frozen)]
pub struct PyModel {
    /// The overrides as given, `(param index, value)`.
    overrides: Vec<(usize, f64)>,
    /// Every param's value.
    values: Vec<f64>,
}

/// A run's result as Python sees it.
fn solution(
    py: Python<'_>,
    kind: &Kind,
    result: Result<Tabulated, TableError>,
) -> PyResult<PySolution> {
    match result {
        Ok(done) => {
            let stopped_at = match done.summary.outcome.ending {
                Ending::End => None,
                Ending::Stopped(t) | Ending::Rest { at: t, .. } => Some(t),
            };
            let stats = done.summary.json();
            Ok(PySolution::from_table(
                py,
                kind,
                done.table,
                Some(stats),
                stopped_at,
            ))
        }
        Err(TableError::Usage(message)) => Err(PyValueError::new_err(message)),
        Err(TableError::Failed(run)) => Err(failed(py, kind, &run.failure, run.table)),
    }
}

impl PyModel {
    fn model(&self) -> Box<dyn lagc_runtime::model::DynModel> {
        (kind().make)(&self.values)
    }

    fn state(&self, x: Vec<f64>) -> PyResult<Vec<f64>> {
        let n = kind().state_names.len();
        if x.len() != n {
            return Err(PyValueError::new_err(format!(
                "the state has {n} components ({}), not {}",
                kind().state_names.join(", "),
                x.len()
            )));
        }
        Ok(x)
    }
}

#[pymethods]
impl PyModel {
    #[new]
    #[pyo3(signature = (**params))]
    fn new(params: Option<&Bound<'_, PyDict>>) -> PyResult<PyModel> {
        let kind = kind();
        let overrides = request::params(kind, params)?;
        let mut given = vec![None; kind.param_names.len()];
        for &(i, v) in &overrides {
            given[i] = Some(v);
        }
        let values = kind.prototype().parameters(&given);
        Ok(PyModel { overrides, values })
    }

    /// Every param's value by name.
    #[getter]
    fn params<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let dict = PyDict::new(py);
        for (name, value) in kind().param_names.iter().zip(&self.values) {
            dict.set_item(name, value)?;
        }
        Ok(dict)
    }

    /// The params' names, in declaration order.
    #[getter]
    fn param_names(&self) -> Vec<&'static str> {
        kind().param_names.to_vec()
    }

    /// The state components' names (the CSV's columns after `t`).
    #[getter]
    fn state_names(&self) -> Vec<&'static str> {
        kind().state_names.to_vec()
    }

    /// The output columns' names.
    #[getter]
    fn output_names(&self) -> Vec<&'static str> {
        kind().output_names.to_vec()
    }

    /// The inputs' names (`input u = 0;`), in declaration order.
    #[getter]
    fn input_names(&self) -> Vec<&'static str> {
        kind().input_names.to_vec()
    }

    /// The model's time span `(t0, t1)` with these params.
    #[getter]
    fn time_span(&self) -> (f64, f64) {
        self.model().time_span()
    }

    /// Solves the model: the state (and outputs) at the times `t` (default:
    /// 101 evenly spaced over the model's span; a time outside the span is
    /// a ValueError, as `lagc run --times` refuses it — `Model.integration`
    /// takes a later end), from the model's initial values with those
    /// `initial` names replaced (`{"q1'": 2.0}`; values the constraints fix
    /// are checked against them). `method` is "field" or "direct",
    /// `integrator` "auto", "explicit", "stiff" or "magnus" (default: the
    /// model's `integrator` statement, or auto), `rtol`/`atol` the per-step
    /// tolerance (default 1e-10, 1e-12), `max_steps` the work budget,
    /// `global_error=False` leaves out the global-error estimate
    /// (`sol.stats["global_error_estimate"]` is then None; the rows are the
    /// same bit for bit, the run cheaper: `lagc run --no-global-error`).
    /// `inputs` drives the model's inputs by name, `{"u": (times, values)}`,
    /// held between the rows or, with `input_interp="linear"`, interpolated
    /// (the others hold their defaults); each change restarts the
    /// integration. The rows are those `lagc run` prints for the same run
    /// (`--input u=FILE.csv`), bit for bit. `sensitivity=True` adds
    /// `sol.sensitivity`, (k, number of state components, number of stated
    /// initial values + number of params): ∂x(t)/∂(y0, p) as `lagc run
    /// --sensitivity` writes it (columns named by `sol.sensitivity_names`).
    /// Raises IntegrationError when the run fails, ValueError where
    /// sensitivities are not computed (with `inputs` among others).
    #[pyo3(signature = (t=None, initial=None, method="field", integrator=None, rtol=None, atol=None, max_steps=None, inputs=None, input_interp="hold", sensitivity=false, global_error=true))]
    #[allow(clippy::too_many_arguments)]
    fn solve(
        &self,
        py: Python<'_>,
        t: Option<&Bound<'_, PyAny>>,
        initial: Option<&Bound<'_, PyDict>>,
        method: &str,
        integrator: Option<&str>,
        rtol: Option<f64>,
        atol: Option<f64>,
        max_steps: Option<usize>,
        inputs: Option<&Bound<'_, PyDict>>,
        input_interp: &str,
        sensitivity: bool,
        global_error: bool,
    ) -> PyResult<PySolution> {
        let kind = kind();
        let options = RunOptions {
            method,
            integrator,
            rtol,
            atol,
            max_steps,
            global_error,
        }
        .options()?;
        let times = t.map(request::times).transpose()?;
        let inits = request::initial(kind, initial)?;
        let signals = request::inputs(kind, inputs, input_interp)?;
        let request = request::request(&self.overrides, Vec::new(), inits, options, times, signals);
        let result = py.detach(|| tabulate(&*kind.prototype(), &request));
        let solved = solution(py, kind, result)?;
        if !sensitivity {
            return Ok(solved);
        }
        let rows = match py.detach(|| sensitivities(&*kind.prototype(), &request)) {
            Ok(rows) => rows,
            Err(TableError::Usage(message)) => return Err(PyValueError::new_err(message)),
            Err(TableError::Failed(run)) => return Err(failed(py, kind, &run.failure, run.table)),
        };
        let names = lagc_runtime::sensitivity::column_names(&*kind.prototype());
        solved.with_sensitivity(py, rows, names)
    }

    /// Solves the model once per dict of `params` (each overriding this
    /// model's params), on `threads` threads (default: every core) with the
    /// GIL released; the other arguments as for `solve`. Returns the
    /// Solutions in order (`inputs` and `input_interp` drive every set). A failure raises the first set's
    /// IntegrationError (`errors="raise"`, after every set ran), or stands
    /// in the list in place of its Solution (`errors="return"`).
    #[pyo3(signature = (t=None, params=None, initial=None, method="field", integrator=None, rtol=None, atol=None, max_steps=None, threads=None, errors="raise", inputs=None, input_interp="hold", global_error=true))]
    #[allow(clippy::too_many_arguments)]
    fn solve_batch<'py>(
        &self,
        py: Python<'py>,
        t: Option<&Bound<'py, PyAny>>,
        params: Option<Vec<Bound<'py, PyDict>>>,
        initial: Option<&Bound<'py, PyDict>>,
        method: &str,
        integrator: Option<&str>,
        rtol: Option<f64>,
        atol: Option<f64>,
        max_steps: Option<usize>,
        threads: Option<usize>,
        errors: &str,
        inputs: Option<&Bound<'py, PyDict>>,
        input_interp: &str,
        global_error: bool,
    ) -> PyResult<Bound<'py, PyList>> {
        let kind = kind();
        let raise = match errors {
            "raise" => true,
            "return" => false,
            other => {
                return Err(PyValueError::new_err(format!(
                    "errors `{other}`: give \"raise\" or \"return\""
                )))
            }
        };
        let options = RunOptions {
            method,
            integrator,
            rtol,
            atol,
            max_steps,
            global_error,
        }
        .options()?;
        let times = t.map(request::times).transpose()?;
        let inits = request::initial(kind, initial)?;
        let signals = request::inputs(kind, inputs, input_interp)?;
        let requests: Vec<Request> = params
            .unwrap_or_default()
            .iter()
            .map(|set| {
                Ok(request::request(
                    &self.overrides,
                    request::params(kind, Some(set))?,
                    inits.clone(),
                    options.clone(),
                    times.clone(),
                    signals.clone(),
                ))
            })
            .collect::<PyResult<_>>()?;
        let threads =
            threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
        if threads == 0 {
            return Err(PyValueError::new_err("threads: give at least 1"));
        }
        let make = || kind.prototype();
        let results = py.detach(|| tabulate_many(&make, &requests, threads));
        let list = PyList::empty(py);
        let mut first_error = None;
        for result in results {
            match solution(py, kind, result) {
                Ok(s) => list.append(Py::new(py, s)?)?,
                Err(error) => {
                    if error.is_instance(py, kind.error.bind(py)) || !raise {
                        list.append(error.value(py))?;
                    }
                    if first_error.is_none() {
                        first_error = Some(error);
                    }
                }
            }
        }
        match first_error {
            Some(error) if raise => Err(error),
            _ => Ok(list),
        }
    }

    /// A run that advances on request (see `Integration`), from the model's
    /// initial values with those `initial` names replaced; it may advance up
    /// to the model's end time, or `t_end` if later. Its inputs hold their
    /// defaults until `Integration.set_input` changes them. The other
    /// arguments as for `solve`.
    #[pyo3(signature = (initial=None, method="field", integrator=None, rtol=None, atol=None, max_steps=None, t_end=None))]
    #[allow(clippy::too_many_arguments)]
    fn integration(
        &self,
        py: Python<'_>,
        initial: Option<&Bound<'_, PyDict>>,
        method: &str,
        integrator: Option<&str>,
        rtol: Option<f64>,
        atol: Option<f64>,
        max_steps: Option<usize>,
        t_end: Option<f64>,
    ) -> PyResult<PyIntegration> {
        let kind = kind();
        let options = RunOptions {
            method,
            integrator,
            rtol,
            atol,
            max_steps,
            global_error: true,
        }
        .options()?;
        let inits = request::initial(kind, initial)?;
        let request = request::request(
            &self.overrides,
            Vec::new(),
            inits,
            options,
            None,
            Vec::new(),
        );
        match ready(&*kind.prototype(), &request) {
            Ok(r) => {
                if let Some(t) = t_end.filter(|&t| !(t >= r.t0 && t.is_finite())) {
                    return Err(PyValueError::new_err(format!(
                        "t_end {t}: give a finite time after the start of the time span, {}",
                        r.t0
                    )));
                }
                let end = t_end.map_or(r.end, |t| t.max(r.end));
                let inputs = r.model.input_defaults().to_vec();
                let run = Integration::owned(r.model, &r.options, r.t0, end, &r.x0);
                Ok(PyIntegration::new(run, inputs))
            }
            Err(TableError::Usage(message)) => Err(PyValueError::new_err(message)),
            Err(TableError::Failed(run)) => Err(failed(py, kind, &run.failure, run.table)),
        }
    }

    /// `X(t, x)`, the right side of the reduced system (7) (the state's
    /// rates), in the regime the state is in.
    fn rhs<'py>(
        &self,
        py: Python<'py>,
        t: f64,
        x: Vec<f64>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let x = self.state(x)?;
        match rhs_at(&mut *self.model(), t, &x) {
            Ok(dx) => Ok(dx.into_pyarray(py)),
            Err(failure) => Err(failed(py, kind(), &failure, Default::default())),
        }
    }

    /// `∂X/∂x (t, x)`, the exact Jacobian of the right side, (N, N):
    /// `J[i, j] = ∂X_i/∂x_j`.
    fn jacobian<'py>(
        &self,
        py: Python<'py>,
        t: f64,
        x: Vec<f64>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let x = self.state(x)?;
        let n = x.len();
        match jacobian_at(&mut *self.model(), t, &x) {
            Ok(jac) => {
                let mut rows = Vec::with_capacity(n * n);
                for i in 0..n {
                    for j in 0..n {
                        rows.push(jac[(i, j)]);
                    }
                }
                rows.into_pyarray(py).reshape([n, n])
            }
            Err(failure) => Err(failed(py, kind(), &failure, Default::default())),
        }
    }

    /// The linearization at a point, as `lagc linearize FILE --at … --format
    /// json` gives it: a dict with `"state"` (A's state: the state without
    /// the components the constraints fix and the ignorable coordinates),
    /// `"ignorable"`, `"A"` (∂f/∂x, exact), `"eigenvalues"` (complex, largest
    /// real part first), `"residual"` (f at the point), `"equilibrium"`,
    /// `"t"`, `"point"`, `"ignorable_values"`, `"fixed"` (the constrained
    /// components' values), `"params"` and `"B_params"` (∂f/∂p, the total
    /// derivative: params computed from a param follow it unless given),
    /// and for a model with inputs `"inputs"` and `"B_inputs"` (∂f/∂u, the
    /// inputs held). `at` gives state components by name (the rest: the
    /// model's initial values), `params` overrides params on top of the
    /// model's, `inputs` the inputs' values (default: their defaults), `t`
    /// the time (default: the start of the span). An unknown name raises
    /// KeyError; a point where A is not defined, or a fixed component given
    /// off its constraint, ValueError.
    #[pyo3(signature = (at=None, params=None, inputs=None, t=None))]
    fn linearize<'py>(
        &self,
        py: Python<'py>,
        at: Option<&Bound<'_, PyDict>>,
        params: Option<&Bound<'_, PyDict>>,
        inputs: Option<&Bound<'_, PyDict>>,
        t: Option<f64>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let kind = kind();
        let at = request::initial(kind, at)?;
        let more = request::params(kind, params)?;
        let given_inputs = request::by_name("input", inputs, kind.input_names)?;
        let mut given = vec![None; kind.param_names.len()];
        for &(i, v) in self.overrides.iter().chain(&more) {
            given[i] = Some(v);
        }
        let overridden = given.iter().map(Option::is_some).collect();
        let values = kind.prototype().parameters(&given);
        let mut input_values = kind.prototype().input_defaults().to_vec();
        for &(i, v) in &given_inputs {
            input_values[i] = v;
        }
        let request = crate::linear::Request {
            at,
            params: values,
            overridden,
            inputs: input_values,
            t,
        };
        let names = kind.state_names;
        let l = (kind.linearize)(&request, names).map_err(PyValueError::new_err)?;
        let matrix = |rows: &[Vec<f64>], cols: usize| -> PyResult<Bound<'py, PyArray2<f64>>> {
            let flat: Vec<f64> = rows.iter().flatten().copied().collect();
            flat.into_pyarray(py).reshape([rows.len(), cols])
        };
        let n = l.state.len();
        let out = PyDict::new(py);
        let named = |ks: &[usize]| ks.iter().map(|&k| names[k]).collect::<Vec<_>>();
        out.set_item("state", named(&l.state))?;
        let ignorable: Vec<usize> = l.ignorable.iter().map(|&(k, _)| k).collect();
        out.set_item("ignorable", named(&ignorable))?;
        out.set_item("A", matrix(&l.a, n)?)?;
        let eigenvalues: Vec<numpy::Complex64> = l
            .eigenvalues
            .iter()
            .map(|&(re, im)| numpy::Complex64::new(re, im))
            .collect();
        out.set_item("eigenvalues", eigenvalues.into_pyarray(py))?;
        out.set_item("residual", l.residual.into_pyarray(py))?;
        out.set_item("equilibrium", l.equilibrium)?;
        out.set_item("t", l.t)?;
        out.set_item("point", l.point.into_pyarray(py))?;
        let values: Vec<f64> = l.ignorable.iter().map(|&(_, v)| v).collect();
        out.set_item("ignorable_values", values.into_pyarray(py))?;
        let fixed = PyDict::new(py);
        for &(k, v) in &l.fixed {
            fixed.set_item(names[k], v)?;
        }
        out.set_item("fixed", fixed)?;
        out.set_item("params", kind.param_names.to_vec())?;
        out.set_item("B_params", matrix(&l.b_params, kind.param_names.len())?)?;
        if !kind.input_names.is_empty() {
            out.set_item("inputs", kind.input_names.to_vec())?;
            out.set_item("B_inputs", matrix(&l.b_inputs, kind.input_names.len())?)?;
        }
        Ok(out)
    }

    /// Pickling (Dask ships models to its workers): the class and the
    /// overrides as given, so that params computed from them follow again.
    fn __reduce__<'py>(
        slf: &Bound<'py, Self>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        let py = slf.py();
        let kwargs = PyDict::new(py);
        for &(i, v) in &slf.get().overrides {
            kwargs.set_item(kind().param_names[i], v)?;
        }
        let partial = py
            .import("functools")?
            .getattr("partial")?
            .call((slf.get_type(),), Some(&kwargs))?;
        Ok((partial, PyTuple::empty(py)))
    }

    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        other.cast::<PyModel>().is_ok_and(|o| {
            let o = o.get();
            o.values == self.values && o.overrides == self.overrides
        })
    }

    fn __repr__(&self) -> String {
        let kind = kind();
        let given: Vec<String> = self
            .overrides
            .iter()
            .map(|&(i, v)| format!("{}={v:?}", kind.param_names[i]))
            .collect();
        format!("{}.Model({})", kind.module, given.join(", "))
    }
}
