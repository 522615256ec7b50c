//! A run from the command line: the model with the invocation's params and
//! initial values (checked as the file's own are), the CSV on stdout as
//! the integration goes, the summary on stderr; `--repeat` and
//! `--estimate-error` run it again.

use super::args::Invocation;
use super::bench::ensemble;
use super::exit::fail;
use crate::choice::{IntegratorChoice, Method};
use crate::failure::{Failure, USAGE_EXIT_STATUS};
use crate::io::output::{sample_times, write_header, write_row};
use crate::io::plot::write_plot;
use crate::io::summary::Summary;
use crate::model::{DynModel, Initial};
use crate::run::inputs::{drive, drive_reusing, Schedule, Signal};
use crate::run::integration::Spare;
use crate::run::options::{Ending, Options};
use std::io::Write;
use std::process::ExitCode;
use std::time::{Duration, Instant};

/// A run made ready: the model with the invocation's params, its span and
/// its initial state.
pub struct Prepared {
    pub model: Box<dyn DynModel>,
    pub t0: f64,
    pub t1: f64,
    pub x0: Vec<f64>,
}

/// The model, its span and initial state for an invocation, with every
/// check the file's own values get.
pub fn prepare(prototype: &dyn DynModel, inv: &Invocation) -> Result<Prepared, Failure> {
    prepare_driven(prototype, inv, None)
}

/// [`prepare`] for a run whose inputs follow `schedule`: the initial state
/// (and its checks) under the inputs at `t0`.
pub fn prepare_driven(
    prototype: &dyn DynModel,
    inv: &Invocation,
    schedule: Option<&Schedule>,
) -> Result<Prepared, Failure> {
    let mut overrides = vec![None; prototype.param_names().len()];
    for &(i, v) in &inv.params {
        overrides[i] = Some(v);
    }
    let params = prototype.parameters(&overrides);
    let mut model = prototype.with_params(&params);
    let (t0, t1) = crate::run::start::time_span(&*model)?;
    if let Some(schedule) = schedule {
        model.set_inputs(&schedule.at(model.input_defaults(), t0));
    }
    let mut given = vec![None; model.dim()];
    for &(i, v) in &inv.inits {
        given[i] = Some(v);
    }
    let x0 = crate::run::start::initial_state(&*model, t0, &given)?;
    Ok(Prepared { model, t0, t1, x0 })
}

/// The line a run prints first: the method and integrator, and why.
pub fn plan(model: &dyn DynModel, options: &Options) -> String {
    let (choice, source) = options.choice(model);
    match options.method {
        Method::Direct => match choice {
            IntegratorChoice::Stiff => format!("direct: RODAS4 ({source})"),
            IntegratorChoice::Explicit => {
                format!("direct: DOP853 ({source}; stiffness is only reported)")
            }
            _ => format!("direct: DOP853, switching to RODAS4 if it detects stiffness ({source})"),
        },
        Method::Field => {
            let integrator = match choice {
                IntegratorChoice::Stiff => "RODAS4",
                IntegratorChoice::Explicit => "DOP853",
                IntegratorChoice::Magnus if model.affine() => "the Magnus integrator",
                _ => "DOP853, switching to RODAS4 if it detects stiffness",
            };
            if model.affine() {
                format!("field: the coefficient system by {integrator} ({source})")
            } else {
                format!(
                    "field: quasilinear windows (the motion linearised along a predictor, each \
                     window's field by {integrator}) ({source})"
                )
            }
        }
    }
}

/// Says where an `--init` value of a component the constraints fix was
/// moved onto them: a dependent position stated in a file is where Newton
/// starts (the compiler's N0003 names the completed value), and `--init y=…`
/// is the same, but the run took `y = -0.5` of a pendulum in `x, y` for
/// `y = -0.8` without a word (h-user20).
fn moved_onto_constraints(model: &dyn DynModel, inv: &Invocation, x0: &[f64]) {
    for &(i, stated) in &inv.inits {
        let started = x0[i];
        if (stated - started).abs() > 1e-9 * started.abs().max(1.0) {
            let name = model.state_names()[i];
            eprintln!(
                "note: --init {name}={stated} is off the constraints, which fix `{name}`: the \
                 run starts from {name} = {started}, the root Newton finds from it (move it by the \
                 values the constraints leave free)"
            );
        }
    }
}

pub(crate) fn execute(prototype: &dyn DynModel, inv: &Invocation) -> ExitCode {
    for warning in &inv.warnings {
        eprintln!("warning: {warning}");
    }
    let schedule = match read_schedule(prototype, inv) {
        Ok(schedule) => schedule,
        Err(message) => {
            eprintln!("error: {message}");
            return ExitCode::from(USAGE_EXIT_STATUS);
        }
    };
    let schedule = schedule.as_ref();
    let Prepared {
        mut model,
        t0,
        t1,
        x0,
    } = match prepare_driven(prototype, inv, schedule) {
        Ok(prepared) => prepared,
        Err(failure) => return fail(inv.json, &failure),
    };
    moved_onto_constraints(&*model, inv, &x0);
    let times = match &inv.times {
        Some(times) => {
            if let Some(t) = times.iter().find(|&&t| t < t0 || t > t1) {
                eprintln!("error: `--times`: {t} is outside the time span {t0} .. {t1}");
                return ExitCode::from(USAGE_EXIT_STATUS);
            }
            times.clone()
        }
        None => sample_times(t0, t1, inv.samples),
    };
    if inv.sensitivity {
        let refused = if inv.ensemble.is_some() {
            Some("`--sensitivity` does not combine with `--ensemble`".to_string())
        } else if !inv.inputs.is_empty() {
            // Undriven inputs hold their defaults, which the sensitivities'
            // run reads as the model holds them; a signal's changes are
            // not followed yet.
            Some("`--sensitivity` does not combine with `--input` yet".to_string())
        } else {
            crate::run::sensitivity::unsupported(&*model)
        };
        if let Some(message) = refused {
            eprintln!("error: {message}");
            return ExitCode::from(USAGE_EXIT_STATUS);
        }
    }
    if let Some(count) = inv.ensemble {
        return ensemble(&mut *model, inv, t0, t1, &x0, &times, count);
    }
    eprintln!("{}", plan(&*model, &inv.options));
    // The sensitivities first, kept per sample: the CSV then streams the
    // state from the run as it is without them, with them beside it.
    // A failure of the sensitivities' run ends the run where it failed:
    // the rows before it are written (with their sensitivities), as a run
    // without them writes its rows up to a failure, and the failure is the
    // run's.
    let mut sensitivity_failure: Option<Failure> = None;
    let found = if inv.sensitivity {
        let (rows, note) = sensitivities(prototype, inv, &*model, t0, t1, &x0, &times);
        match note {
            Ok(note) => Some((rows, note)),
            Err(failure) => {
                sensitivity_failure = Some(failure);
                Some((rows, String::new()))
            }
        }
    } else {
        None
    };
    // `-o FILE` takes the CSV that otherwise goes to stdout.
    let sink: Box<dyn Write> = match &inv.output {
        Some(path) => match std::fs::File::create(path) {
            Ok(file) => Box::new(file),
            Err(error) => {
                eprintln!("error: cannot create `{path}`: {error}");
                return ExitCode::FAILURE;
            }
        },
        None => Box::new(std::io::stdout().lock()),
    };
    let writes_csv = !inv.quiet || inv.output.is_some();
    let mut out = std::io::BufWriter::new(sink);
    let columns = model.dim() + model.output_names().len();
    let mut written: Result<(), std::io::Error> = Ok(());
    if writes_csv {
        let mut extra: Vec<String> = model.output_names().iter().map(|s| s.to_string()).collect();
        if found.is_some() {
            extra.extend(crate::run::sensitivity::headers(&*model));
        }
        let extra: Vec<&str> = extra.iter().map(String::as_str).collect();
        written = write_header(&mut out, model.state_names(), &extra);
    }
    let mut sample_index = 0;
    let mut extra = Vec::new();
    // The exact lines hold for the model's own initial values: after
    // `--init` they measured the distance to another motion (12.9 on a
    // knife edge started at another heading) as an error.
    let mut exact_error: Option<f64> =
        (model.states_exact() && inv.inits.is_empty()).then_some(0.0);
    if model.states_exact() && !inv.inits.is_empty() {
        eprintln!(
            "note: the exact solution is not compared: --init changes the initial values it \
             was written for"
        );
    }
    let mut plotted: Vec<(f64, Vec<f64>)> = Vec::new();
    let mut outputs = vec![0.0; model.output_names().len()];
    let mut exact = vec![None; model.dim()];
    let first_start = Instant::now();
    // The first solve streams the CSV; `--repeat N` then times N more
    // solves without output and reports the fastest.
    let first = drive(
        &mut *model,
        &inv.options,
        schedule,
        t0,
        t1,
        &x0,
        &times,
        |model: &dyn DynModel, t, x| {
            if let (Some(failure), Some((rows, _))) = (&sensitivity_failure, &found) {
                if sample_index >= rows.len() {
                    return Err(failure.clone());
                }
            }
            model.outputs(t, x, &mut outputs);
            if written.is_ok() && writes_csv {
                extra.clear();
                extra.extend_from_slice(&outputs);
                if let Some((rows, _)) = &found {
                    extra.extend_from_slice(rows.get(sample_index).map_or(&[][..], |r| &r[..]));
                }
                written = write_row(&mut out, t, x, &extra);
            }
            sample_index += 1;
            if let Some(largest) = exact_error.as_mut() {
                model.exact(t, &mut exact);
                for (value, truth) in x.iter().zip(&exact) {
                    if let Some(truth) = truth {
                        *largest = largest.max((value - truth).abs() / truth.abs().max(1.0));
                    }
                }
            }
            if inv.plot.is_some() || inv.estimate_error {
                let mut row = x.to_vec();
                row.extend_from_slice(&outputs);
                plotted.push((t, row));
            }
            Ok(())
        },
    );
    let first_time = first_start.elapsed();
    let flushed = written.and_then(|()| out.flush());
    drop(out);
    if let Err(error) = flushed {
        if error.kind() != std::io::ErrorKind::BrokenPipe {
            eprintln!("error: cannot write the trajectory: {error}");
            return ExitCode::FAILURE;
        }
    }
    let mut outcome = match (first, sensitivity_failure) {
        (Err(failure), _) | (Ok(_), Some(failure)) => return fail(inv.json, &failure),
        (Ok(outcome), None) => outcome,
    };
    if let Some((_, note)) = &found {
        outcome.report.notes.push(note.clone());
    }
    let mut fastest = first_time;
    if inv.repeat > 1 {
        fastest = Duration::MAX;
        // Each solve in the storage the one before left (the same solve:
        // `drive_reusing`), as a program solving one model repeatedly
        // through the library would keep it.
        let mut spare = Spare::default();
        for _ in 0..inv.repeat {
            let start = Instant::now();
            let quiet = Options {
                progress: false,
                ..inv.options.clone()
            };
            let quietly = |_: &dyn DynModel, _, _: &[f64]| Ok(());
            let solved = drive_reusing(
                &mut *model,
                &quiet,
                schedule,
                t0,
                t1,
                &x0,
                &times,
                quietly,
                &mut spare,
            );
            if let Err(failure) = solved {
                return fail(inv.json, &failure);
            }
            // With `--sensitivity` a solve is both runs: the time is what
            // the columns cost.
            if inv.sensitivity {
                if let (_, Err(failure)) =
                    sensitivities(prototype, inv, &*model, t0, t1, &x0, &times)
                {
                    return fail(inv.json, &failure);
                }
            }
            fastest = fastest.min(start.elapsed());
        }
    }
    let estimated_error = if inv.estimate_error {
        match estimate(&mut *model, inv, schedule, t0, t1, &x0, &plotted) {
            Ok(e) => Some(e),
            Err(failure) => {
                eprintln!("warning: the error estimate failed: {failure}");
                None
            }
        }
    } else {
        None
    };
    if let Some(request) = &inv.plot {
        let mut names: Vec<&str> = vec!["t"];
        names.extend(model.state_names());
        names.extend(model.output_names());
        if let Err(error) = write_plot(request, model.name(), &names, &plotted) {
            eprintln!("error: cannot write the plot `{}`: {error}", request.file);
            return ExitCode::FAILURE;
        }
    }
    debug_assert!(plotted.iter().all(|(_, r)| r.len() == columns));
    let summary = Summary {
        outcome,
        wall_time: fastest,
        runs: inv.repeat,
        exact_error,
        estimated_error,
    };
    if inv.json {
        if let Some(warning) = summary.global_error_warning() {
            eprintln!("{warning}");
        }
        eprintln!("{}", summary.json());
    } else {
        eprintln!("{}", summary.text());
    }
    if let Ending::Stopped(_) = summary.outcome.ending {
        // The run ended where the model said: a success.
    }
    ExitCode::SUCCESS
}

/// The sensitivities at every sample time and a note for the summary
/// ([`crate::run::sensitivity::sample`]).
#[allow(clippy::too_many_arguments)]
fn sensitivities(
    prototype: &dyn DynModel,
    inv: &Invocation,
    model: &dyn DynModel,
    t0: f64,
    t1: f64,
    x0: &[f64],
    times: &[f64],
) -> (Vec<Vec<f64>>, Result<String, Failure>) {
    use crate::run::sensitivity::{sample_until_failure, Start};
    let mut overrides = vec![None; prototype.param_names().len()];
    for &(i, v) in &inv.params {
        overrides[i] = Some(v);
    }
    let mut given = vec![None; model.dim()];
    for &(i, v) in &inv.inits {
        if model.initial_kinds().get(i) == Some(&Initial::Given) {
            given[i] = Some(v);
        }
    }
    let start = Start {
        prototype,
        overrides: &overrides,
        given: &given,
    };
    sample_until_failure(&start, model, &inv.options, t0, t1, x0, times)
}

/// The largest difference (relative to `max(|x|, 1)`) between the samples
/// of the run and those of a run at a 100× tighter tolerance.
fn estimate(
    model: &mut dyn DynModel,
    inv: &Invocation,
    schedule: Option<&Schedule>,
    t0: f64,
    t1: f64,
    x0: &[f64],
    samples: &[(f64, Vec<f64>)],
) -> Result<f64, Failure> {
    let mut options = inv.options.clone();
    options.tol = options.tol.scaled(0.01);
    options.progress = false;
    let times: Vec<f64> = samples.iter().map(|(t, _)| *t).collect();
    let n = model.dim();
    let mut largest = 0.0_f64;
    let mut i = 0;
    drive(model, &options, schedule, t0, t1, x0, &times, |_, t, x| {
        if let Some((ts, row)) = samples.get(i) {
            if *ts == t {
                for (a, b) in row[..n].iter().zip(x) {
                    largest = largest.max((a - b).abs() / b.abs().max(1.0));
                }
            }
        }
        i += 1;
        Ok(())
    })?;
    Ok(largest)
}

/// The inputs' schedule of a run: `None` for a model without inputs; the
/// `--input` files read (an error in words for an unknown input, a file
/// that cannot be read or a malformed one).
fn read_schedule(model: &dyn DynModel, inv: &Invocation) -> Result<Option<Schedule>, String> {
    let names = model.input_names();
    if names.is_empty() {
        return match inv.inputs.first() {
            Some((name, _)) => Err(format!("`--input {name}`: the model has no inputs")),
            None => Ok(None),
        };
    }
    let mut schedule = Schedule {
        signals: vec![None; names.len()],
    };
    for (name, file) in &inv.inputs {
        let index = names.iter().position(|n| n == name).ok_or_else(|| {
            format!(
                "`--input`: no input `{name}` (inputs: {})",
                names.join(", ")
            )
        })?;
        let text = std::fs::read_to_string(file)
            .map_err(|e| format!("`--input {name}={file}`: cannot read the file: {e}"))?;
        let signal = Signal::from_csv(&text, name, inv.interpolation)
            .map_err(|e| format!("`--input {name}={file}`: {e}"))?;
        schedule.signals[index] = Some(signal);
    }
    Ok(Some(schedule))
}
