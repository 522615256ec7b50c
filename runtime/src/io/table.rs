//! A run as numbers instead of CSV: the rows `lagc run` prints at the
//! requested times, bit for bit (the same preparation, `cli::prepare`, and
//! the same run and samples, `driver::run`), for callers in another
//! language (the Python module of `lagc build --python`); a failure keeps
//! the rows before it, as the CLI's CSV does. [`tabulate_many`] runs many
//! requests on threads (parameter sweeps), and [`rhs_at`]/[`jacobian_at`]
//! evaluate the reduced system in the regime a state is in.

use crate::failure::Failure;
use crate::io::cli::{prepare_driven, Invocation, Prepared};
use crate::io::output::sample_times;
use crate::io::summary::Summary;
use crate::linalg::Matrix;
use crate::model::{DynModel, Regime};
use crate::run::inputs::{drive, Schedule, Signal};
use crate::run::options::Options;
use crate::run::regime::{best_mode, initial_branches};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::Instant;

/// One run: param overrides and initial values by index, the options, the
/// output times (`None`: 101 evenly spaced over the model's span, the
/// CLI's default) and the inputs' signals.
#[derive(Clone, Debug, PartialEq)]
pub struct Request {
    /// `(param index, value)`, as `--param`.
    pub params: Vec<(usize, f64)>,
    /// `(state index, value)`, as `--init`.
    pub inits: Vec<(usize, f64)>,
    pub options: Options,
    pub times: Option<Vec<f64>>,
    /// `(input index, signal)`, as `--input`; the other inputs hold their
    /// defaults.
    pub inputs: Vec<(usize, Signal)>,
}

impl Request {
    /// The model's own run: its params, initial values, default options.
    pub fn new() -> Request {
        Request {
            params: Vec::new(),
            inits: Vec::new(),
            options: Options::default(),
            times: None,
            inputs: Vec::new(),
        }
    }
}

impl Default for Request {
    fn default() -> Self {
        Request::new()
    }
}

/// The rows of a run: the CSV's columns as numbers, row-major.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Table {
    pub t: Vec<f64>,
    /// `t.len()` rows of the state's `N` components.
    pub states: Vec<f64>,
    /// `t.len()` rows of the output columns.
    pub outputs: Vec<f64>,
}

/// A finished run: its rows and the summary `--summary json` prints.
#[derive(Clone, Debug, PartialEq)]
pub struct Tabulated {
    pub table: Table,
    pub summary: Summary,
}

/// Why a request gave no finished run.
#[derive(Clone, Debug, PartialEq)]
pub enum TableError {
    /// The request itself is wrong (the CLI's exit status 2 for usage): a
    /// time outside the span, times not increasing, a bad tolerance, a
    /// signal for a model without inputs.
    Usage(String),
    /// The run failed; the rows before the failure.
    Failed(Box<Failed>),
}

/// A failed run: the failure and the rows before it.
#[derive(Clone, Debug, PartialEq)]
pub struct Failed {
    pub failure: Failure,
    pub table: Table,
}

/// Checks what the CLI's argument parser checks of the same request.
fn check_request(request: &Request) -> Result<(), String> {
    let tol = request.options.tol;
    if !(tol.rtol > 0.0 && tol.rtol < 1.0) {
        return Err(format!(
            "rtol {}: a relative tolerance must be between 0 and 1",
            tol.rtol
        ));
    }
    if !(tol.atol > 0.0 && tol.atol.is_finite()) {
        return Err(format!(
            "atol {}: an absolute tolerance must be positive",
            tol.atol
        ));
    }
    if let Some(times) = &request.times {
        if let Some(t) = times.iter().find(|t| !t.is_finite()) {
            return Err(format!("the time {t} is not finite"));
        }
        if times.is_empty() || times.windows(2).any(|w| w[1] <= w[0]) {
            return Err("give increasing times".to_string());
        }
    }
    Ok(())
}

/// A request made ready to run: the model with the request's params (in
/// the regime of its start, under the inputs there), its initial state
/// checked as the CLI checks it, the output times, the time the run ends
/// and the inputs' schedule (`None` for a model without inputs).
pub struct Ready {
    pub model: Box<dyn DynModel>,
    pub options: Options,
    pub t0: f64,
    pub x0: Vec<f64>,
    pub times: Vec<f64>,
    /// The model's end time.
    pub end: f64,
    pub schedule: Option<Schedule>,
}

/// The schedule of `model`'s inputs with these signals, as the CLI's
/// `--input` makes it: `None` for a model without inputs (signals for one
/// are a usage error), else every input, the unsignalled at their
/// defaults.
fn schedule(model: &dyn DynModel, signals: &[(usize, Signal)]) -> Result<Option<Schedule>, String> {
    let n = model.input_names().len();
    if n == 0 {
        return match signals.is_empty() {
            true => Ok(None),
            false => Err("the model has no inputs".to_string()),
        };
    }
    let mut schedule = Schedule {
        signals: vec![None; n],
    };
    for (i, signal) in signals {
        let slot = schedule
            .signals
            .get_mut(*i)
            .ok_or_else(|| format!("no input has the index {i}"))?;
        *slot = Some(signal.clone());
    }
    Ok(Some(schedule))
}

/// Makes `request` ready on `prototype`'s model (its params the file's),
/// with the checks of the CLI (`cli::prepare_driven`, and `--times`
/// within the span: a time past the model's end is refused, as the CLI
/// refuses it, not run to silently).
pub fn ready(prototype: &dyn DynModel, request: &Request) -> Result<Ready, TableError> {
    check_request(request).map_err(TableError::Usage)?;
    let schedule = schedule(prototype, &request.inputs).map_err(TableError::Usage)?;
    let invocation = Invocation {
        options: Options {
            progress: false,
            ..request.options.clone()
        },
        params: request.params.clone(),
        inits: request.inits.clone(),
        samples: 101,
        times: request.times.clone(),
        estimate_error: false,
        plot: None,
        repeat: 1,
        quiet: true,
        json: true,
        ensemble: None,
        spread: 0.1,
        sensitivity: false,
        output: None,
        warnings: Vec::new(),
        inputs: Vec::new(),
        interpolation: crate::run::inputs::Interpolation::Hold,
    };
    let prepared = prepare_driven(prototype, &invocation, schedule.as_ref());
    let Prepared { model, t0, t1, x0 } = prepared.map_err(|failure| {
        TableError::Failed(Box::new(Failed {
            failure,
            table: Table::default(),
        }))
    })?;
    let times = match &request.times {
        Some(times) => {
            if let Some(t) = times.iter().find(|&&t| t < t0) {
                return Err(TableError::Usage(format!(
                    "the time {t} is before the start of the time span, {t0}"
                )));
            }
            if let Some(t) = times.iter().find(|&&t| t > t1) {
                return Err(TableError::Usage(format!(
                    "the time {t} is past the end of the time span, {t1} (the model's `time` \
                     statement)"
                )));
            }
            times.clone()
        }
        None => sample_times(t0, t1, 101),
    };
    Ok(Ready {
        model,
        options: invocation.options,
        t0,
        x0,
        times,
        end: t1,
        schedule,
    })
}

/// The forward sensitivities of `request`'s run at its times (each row
/// `S` column by column, [`crate::run::sensitivity::sample`]); a usage error
/// where they are not computed.
pub fn sensitivities(
    prototype: &dyn DynModel,
    request: &Request,
) -> Result<Vec<Vec<f64>>, TableError> {
    use crate::run::sensitivity::{sample, unsupported, Start};
    let Ready {
        model,
        options,
        t0,
        x0,
        times,
        end,
        ..
    } = ready(prototype, request)?;
    if !request.inputs.is_empty() {
        return Err(TableError::Usage(
            "sensitivities do not combine with driven inputs yet".to_string(),
        ));
    }
    if let Some(message) = unsupported(&*model) {
        return Err(TableError::Usage(message));
    }
    let mut overrides = vec![None; prototype.param_names().len()];
    for &(i, v) in &request.params {
        overrides[i] = Some(v);
    }
    let mut given = vec![None; model.dim()];
    for &(i, v) in &request.inits {
        if model.initial_kinds().get(i) == Some(&crate::model::Initial::Given) {
            given[i] = Some(v);
        }
    }
    let start = Start {
        prototype,
        overrides: &overrides,
        given: &given,
    };
    sample(&start, &*model, &options, t0, end, &x0, &times)
        .map(|(rows, _)| rows)
        .map_err(|failure| {
            TableError::Failed(Box::new(Failed {
                failure,
                table: Table::default(),
            }))
        })
}

/// Runs `request` on `prototype`'s model (its params the file's): the
/// rows at the requested times and the summary, the CLI's run step for
/// step (its inputs' too: `inputs::drive`).
pub fn tabulate(prototype: &dyn DynModel, request: &Request) -> Result<Tabulated, TableError> {
    let Ready {
        mut model,
        options,
        t0,
        x0,
        times,
        end: t_end,
        schedule,
    } = ready(prototype, request)?;
    let (n, m) = (model.dim(), model.output_names().len());
    let mut table = Table {
        t: Vec::with_capacity(times.len()),
        states: Vec::with_capacity(times.len() * n),
        outputs: Vec::with_capacity(times.len() * m),
    };
    let mut outputs = vec![0.0; m];
    // As the CLI: the exact lines hold for the model's own initial values.
    let mut exact_error: Option<f64> =
        (model.states_exact() && request.inits.is_empty()).then_some(0.0);
    let mut exact = vec![None; n];
    let start = Instant::now();
    let ran = drive(
        &mut *model,
        &options,
        schedule.as_ref(),
        t0,
        t_end,
        &x0,
        &times,
        |model: &dyn DynModel, t, x| {
            model.outputs(t, x, &mut outputs);
            table.t.push(t);
            table.states.extend_from_slice(x);
            table.outputs.extend_from_slice(&outputs);
            if let Some(largest) = exact_error.as_mut() {
                model.exact(t, &mut exact);
                for (value, truth) in x.iter().zip(&exact) {
                    if let Some(truth) = truth {
                        *largest = largest.max((value - truth).abs() / truth.abs().max(1.0));
                    }
                }
            }
            Ok(())
        },
    );
    let wall_time = start.elapsed();
    match ran {
        Ok(outcome) => Ok(Tabulated {
            table,
            summary: Summary {
                outcome,
                wall_time,
                runs: 1,
                exact_error,
                estimated_error: None,
            },
        }),
        Err(failure) => Err(TableError::Failed(Box::new(Failed { failure, table }))),
    }
}

/// [`tabulate`] of every request, on `threads` threads (at least one),
/// each making its own model with `make` (models are not shared between
/// threads); results in the order of the requests.
pub fn tabulate_many(
    make: &(dyn Fn() -> Box<dyn DynModel> + Sync),
    requests: &[Request],
    threads: usize,
) -> Vec<Result<Tabulated, TableError>> {
    let results: Vec<Mutex<Option<Result<Tabulated, TableError>>>> =
        requests.iter().map(|_| Mutex::new(None)).collect();
    let next = AtomicUsize::new(0);
    let work = || {
        let prototype = make();
        loop {
            let i = next.fetch_add(1, Ordering::Relaxed);
            let Some(request) = requests.get(i) else {
                break;
            };
            let result = tabulate(&*prototype, request);
            *results[i].lock().unwrap_or_else(|e| e.into_inner()) = Some(result);
        }
    };
    let threads = threads.clamp(1, requests.len().max(1));
    std::thread::scope(|scope| {
        for _ in 1..threads {
            scope.spawn(work);
        }
        work();
    });
    results
        .into_iter()
        .map(|slot| {
            slot.into_inner()
                .unwrap_or_else(|e| e.into_inner())
                .expect("every request is taken by a thread")
        })
        .collect()
}

/// Puts `model` in the regime a run started at `(t, x)` would be in: the
/// best candidates of implicit constraints, the branches of the switches.
fn settle_regime(model: &mut dyn DynModel, t: f64, x: &[f64]) {
    let regime = Regime {
        mode: best_mode(model, t, x).0,
        branches: initial_branches(model, t, x),
    };
    model.set_regime(&regime);
}

/// `X(t, x)`, the right side of the reduced system (7), in the regime of
/// `(t, x)`.
pub fn rhs_at(model: &mut dyn DynModel, t: f64, x: &[f64]) -> Result<Vec<f64>, Failure> {
    settle_regime(model, t, x);
    let mut dx = vec![0.0; x.len()];
    model.rhs(t, x, &mut dx)?;
    Ok(dx)
}

/// `∂X/∂x (t, x)`, in the regime of `(t, x)`.
pub fn jacobian_at(model: &mut dyn DynModel, t: f64, x: &[f64]) -> Result<Matrix, Failure> {
    settle_regime(model, t, x);
    let mut jac = Matrix::zeros(x.len(), x.len());
    model.jacobian(t, x, &mut jac)?;
    Ok(jac)
}
