//! The generated binary's command line: one function, [`main`], that a
//! generated crate's `main` hands over to. Arguments are parsed by hand
//! (the runtime has no dependencies); `lagc run` calls [`parse`] too, so
//! that bad usage is reported before anything is built.
//!
//! Exit status: 0 success, 2 bad usage (including overrides that make the
//! model inconsistent), 3 a numerical failure.

use crate::failure::{Failure, FailureKind, USAGE_EXIT_STATUS};
use crate::field::Anchor;
use crate::method::{IntegratorChoice, Method};
use crate::model::{DynModel, Initial, Model};
use crate::output::{sample_times, write_header, write_row};
use crate::plot::{write_plot, PlotRequest};
use crate::run::options::{Ending, Options};
use crate::run::run;
use crate::summary::{json_string, Summary};
use std::io::Write;
use std::process::ExitCode;
use std::time::{Duration, Instant};

/// The most samples a run may print: beyond it the request is surely a
/// mistake (the CSV alone would be tens of gigabytes).
pub const MAX_SAMPLES: usize = 100_000_000;

pub const USAGE: &str = "\
usage: MODEL [OPTIONS]

  --method field|direct  the field method (default) or direct integration
  --integrator auto|explicit|stiff|magnus
                         auto (default): DOP853, direct integration switching
                         to RODAS4 where DOP853 detects stiffness; explicit:
                         DOP853; stiff: RODAS4; magnus: the field's Magnus
                         integrator for linear coefficient systems; the
                         model's `integrator` statement is the default
  --stiff                the same as `--integrator stiff`
  --param NAME=VALUE     override a param (params computed from it follow)
  --init NAME=VALUE      override an initial value (`q1`, \"q1'\"); values the
                         constraints fix are checked against them
  --rtol R, --atol A     the per-step tolerance (default 1e-10, 1e-12): each
                         step's local error is kept below atol + rtol·|x|;
                         the global error is usually a modest multiple of it
                         (see --estimate-error)
  --samples N            N evenly spaced output times over the span
                         (default 101; 1 prints the final state only);
                         output times never change the steps
  --times T1,T2,...      output at these times instead
  --estimate-error       also run at a 100× tighter tolerance and report the
                         largest difference (an estimate of the global error;
                         like the error against `exact` lines, relative:
                         |a − b| / max(|b|, 1) over samples and components)
  --anchor VALUE         field: every free anchor value c_A (default 0)
  --no-reanchor          field: stop where the conditions (13) degrade
                         instead of re-anchoring
  --max-steps N          the work budget: steps of every kind (default 1e6)
  --plot FILE.svg        draw the columns against time into FILE.svg
  --phase X,Y            with --plot: draw column Y against column X
  --ensemble K           K initial states around the model's (spread by
                         --spread, default 0.1 of each value) through one
                         field, against K direct integrations: times and
                         the largest difference (exact for affine motions,
                         first order in the spread otherwise)
  --spread S             the ensemble's relative spread
  --repeat N             solve N times (after a warm-up) and report the
                         smallest wall time
  --quiet                no CSV on stdout
  --summary text|json    the summary on stderr as text (default) or JSON
  --help                 this text";

/// What the command line asks for.
#[derive(Clone, Debug, PartialEq)]
pub enum Command {
    Help,
    /// Print the model's source hash (lagc checks that a binary belongs to
    /// its model).
    SourceHash,
    Run(Box<Invocation>),
}

/// A run, as the command line describes it.
#[derive(Clone, Debug, PartialEq)]
pub struct Invocation {
    pub options: Options,
    /// `(param index, value)`.
    pub params: Vec<(usize, f64)>,
    /// `(state index, value)`.
    pub inits: Vec<(usize, f64)>,
    pub samples: usize,
    pub times: Option<Vec<f64>>,
    pub estimate_error: bool,
    pub plot: Option<PlotRequest>,
    pub repeat: usize,
    pub quiet: bool,
    pub json: bool,
    pub ensemble: Option<usize>,
    pub spread: f64,
    /// Warnings to print before running (e.g. a tolerance below rounding).
    pub warnings: Vec<String>,
}

fn value<'a>(flag: &str, args: &mut impl Iterator<Item = &'a String>) -> Result<&'a str, String> {
    args.next()
        .map(String::as_str)
        .ok_or_else(|| format!("`{flag}` needs a value"))
}

fn number(flag: &str, text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(format!("`{flag}`: `{text}` is not a finite number")),
    }
}

fn count(flag: &str, text: &str, max: usize) -> Result<usize, String> {
    // Accept `1e6` as well as `1000000`.
    let parsed = text.trim().parse::<usize>().ok().or_else(|| {
        text.trim()
            .parse::<f64>()
            .ok()
            .filter(|v| v.fract() == 0.0 && *v >= 0.0 && *v <= usize::MAX as f64)
            .map(|v| v as usize)
    });
    match parsed {
        Some(n) if (1..=max).contains(&n) => Ok(n),
        Some(n) if n > max => Err(format!(
            "`{flag} {text}`: at most {max} (a larger count is surely a mistake)"
        )),
        _ => Err(format!("`{flag}`: `{text}` is not a count ≥ 1")),
    }
}

fn name_value<'a>(flag: &str, text: &'a str) -> Result<(&'a str, &'a str), String> {
    text.split_once('=')
        .map(|(n, v)| (n.trim(), v.trim()))
        .ok_or_else(|| format!("`{flag} {text}`: expected NAME=VALUE"))
}

/// Parses the arguments (without the program name) for a model with these
/// params, state and output columns.
pub fn parse(
    args: &[String],
    params: &[&str],
    state: &[&str],
    outputs: &[&str],
) -> Result<Command, String> {
    let mut inv = Invocation {
        options: Options {
            progress: true,
            ..Options::default()
        },
        params: Vec::new(),
        inits: Vec::new(),
        samples: 101,
        times: None,
        estimate_error: false,
        plot: None,
        repeat: 1,
        quiet: false,
        json: false,
        ensemble: None,
        spread: 0.1,
        warnings: Vec::new(),
    };
    let mut phase: Option<String> = None;
    let mut args = args.iter();
    while let Some(arg) = args.next() {
        let flag = arg.as_str();
        match flag {
            "--help" | "-h" => return Ok(Command::Help),
            "--lagc-source-hash" => return Ok(Command::SourceHash),
            "--method" => {
                let v = value(flag, &mut args)?;
                inv.options.method = Method::parse(v)
                    .ok_or_else(|| format!("`--method` takes `field` or `direct`, not `{v}`"))?;
            }
            "--stiff" => inv.options.integrator = Some(IntegratorChoice::Stiff),
            "--integrator" => {
                let v = value(flag, &mut args)?;
                let choice = IntegratorChoice::parse(v).ok_or_else(|| {
                    format!(
                        "`--integrator` takes `auto`, `explicit`, `stiff` or `magnus`, not `{v}`"
                    )
                })?;
                inv.options.integrator = Some(choice);
            }
            "--no-reanchor" => inv.options.reanchor = false,
            "--rtol" => {
                let text = value(flag, &mut args)?;
                let r = number(flag, text)?;
                if !(r > 0.0 && r < 1.0) {
                    return Err(format!(
                        "`--rtol {text}`: a relative tolerance must be between 0 and 1"
                    ));
                }
                if r < 1e-14 {
                    inv.warnings.push(format!(
                        "--rtol {r:e} is below the rounding of f64 (about 1e-16 per \
                         operation, accumulated over every step): the run will take \
                         many steps and cannot reach it"
                    ));
                }
                inv.options.tol.rtol = r;
            }
            "--atol" => {
                let text = value(flag, &mut args)?;
                let a = number(flag, text)?;
                if a <= 0.0 {
                    return Err(format!(
                        "`--atol {text}`: an absolute tolerance must be positive"
                    ));
                }
                inv.options.tol.atol = a;
            }
            "--anchor" => {
                let a = number(flag, value(flag, &mut args)?)?;
                inv.options.anchor = Anchor::Given(vec![a; state.len()]);
            }
            "--max-steps" => {
                inv.options.max_steps = count(flag, value(flag, &mut args)?, usize::MAX / 2)?
            }
            "--samples" => inv.samples = count(flag, value(flag, &mut args)?, MAX_SAMPLES)?,
            "--times" => {
                let v = value(flag, &mut args)?;
                let times: Vec<f64> = v
                    .split(',')
                    .map(|t| number(flag, t))
                    .collect::<Result<_, _>>()?;
                if times.is_empty() || times.windows(2).any(|w| w[1] <= w[0]) {
                    return Err(format!("`--times {v}`: give increasing times"));
                }
                if times.len() > MAX_SAMPLES {
                    return Err(format!("`--times`: at most {MAX_SAMPLES} times"));
                }
                inv.times = Some(times);
            }
            "--estimate-error" => inv.estimate_error = true,
            "--ensemble" => inv.ensemble = Some(count(flag, value(flag, &mut args)?, 10_000_000)?),
            "--spread" => {
                let s = number(flag, value(flag, &mut args)?)?;
                if !(s >= 0.0) {
                    return Err(format!("`--spread {s}`: a spread must be ≥ 0"));
                }
                inv.spread = s;
            }
            "--repeat" => inv.repeat = count(flag, value(flag, &mut args)?, 1_000_000)?,
            "--quiet" => inv.quiet = true,
            "--summary" => match value(flag, &mut args)? {
                "text" => inv.json = false,
                "json" => inv.json = true,
                other => return Err(format!("`--summary` takes `text` or `json`, not `{other}`")),
            },
            "--plot" => {
                inv.plot = Some(PlotRequest {
                    file: value(flag, &mut args)?.to_string(),
                    phase: None,
                })
            }
            "--phase" => phase = Some(value(flag, &mut args)?.to_string()),
            "--param" => {
                let (name, v) = name_value(flag, value(flag, &mut args)?)?;
                let index = params.iter().position(|p| *p == name).ok_or_else(|| {
                    if params.is_empty() {
                        format!("`--param {name}`: the model has no params")
                    } else {
                        format!(
                            "`--param`: no param `{name}` (params: {})",
                            params.join(", ")
                        )
                    }
                })?;
                inv.params.push((index, number(flag, v)?));
            }
            "--init" => {
                let (name, v) = name_value(flag, value(flag, &mut args)?)?;
                let index = state.iter().position(|s| *s == name).ok_or_else(|| {
                    format!(
                        "`--init`: `{name}` is not a component of the state (state: {})",
                        state.join(", ")
                    )
                })?;
                inv.inits.push((index, number(flag, v)?));
            }
            other => return Err(format!("unknown argument `{other}`")),
        }
    }
    if let Some(phase) = phase {
        let plot = inv
            .plot
            .as_mut()
            .ok_or("`--phase X,Y` needs `--plot FILE.svg`")?;
        let (x, y) = phase
            .split_once(',')
            .ok_or_else(|| format!("`--phase {phase}`: expected two column names X,Y"))?;
        let columns: Vec<&str> = std::iter::once("t")
            .chain(state.iter().copied())
            .chain(outputs.iter().copied())
            .collect();
        for c in [x, y] {
            if !columns.contains(&c.trim()) {
                return Err(format!(
                    "`--phase`: no column `{c}` (columns: {})",
                    columns.join(", ")
                ));
            }
        }
        plot.phase = Some((x.trim().to_string(), y.trim().to_string()));
    }
    Ok(Command::Run(Box::new(inv)))
}

/// The generated binary's `main`: the model with its file's param values
/// hands over to [`command_line`], compiled once here.
pub fn main<M: Model + 'static>() -> ExitCode {
    command_line(&M::new(&M::parameters(&vec![None; M::PARAMS.len()])))
}

/// The command line of `prototype`'s model (its param values are the
/// file's; `--param` makes another with [`DynModel::with_params`]).
pub fn command_line(prototype: &dyn DynModel) -> ExitCode {
    let model = prototype;
    let args: Vec<String> = std::env::args().skip(1).collect();
    match parse(
        &args,
        model.param_names(),
        model.state_names(),
        model.output_names(),
    ) {
        Err(message) => {
            eprintln!("error: {message}\n\n{USAGE}");
            ExitCode::from(USAGE_EXIT_STATUS)
        }
        Ok(Command::Help) => {
            println!("{USAGE}");
            ExitCode::SUCCESS
        }
        Ok(Command::SourceHash) => {
            println!("{}", model.source_hash());
            ExitCode::SUCCESS
        }
        Ok(Command::Run(invocation)) => execute(prototype, &invocation),
    }
}

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
    let mut overrides = vec![None; prototype.param_names().len()];
    for &(i, v) in &inv.params {
        overrides[i] = Some(v);
    }
    let params = prototype.parameters(&overrides);
    let model = prototype.with_params(&params);
    let (t0, t1) = model.time_span();
    if !(t0.is_finite() && t1.is_finite() && t1 > t0) {
        return Err(Failure::new(t0, FailureKind::BadTimeSpan { t0, t1 }));
    }
    let mut given = vec![None; model.dim()];
    for &(i, v) in &inv.inits {
        if model.initial_kinds().get(i) == Some(&Initial::Given) {
            given[i] = Some(v);
        }
    }
    let x0 = model.initial_state(&given)?;
    for (i, v) in x0.iter().enumerate() {
        if !v.is_finite() {
            return Err(Failure::new(
                t0,
                FailureKind::NonFiniteInitialValue {
                    component: model.state_names()[i].to_string(),
                },
            ));
        }
    }
    // A value the constraints fix may be stated, if it agrees.
    for &(i, stated) in &inv.inits {
        if model.initial_kinds().get(i) != Some(&Initial::Given) {
            let required = x0[i];
            if (stated - required).abs() > 1e-9 * required.abs().max(1.0) {
                return Err(Failure::new(
                    t0,
                    FailureKind::InconsistentInitialValue {
                        component: model.state_names()[i].to_string(),
                        stated,
                        required,
                    },
                ));
            }
        }
    }
    crate::run::regime::check_initial_candidates(&*model, t0, &x0)?;
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

fn fail(json: bool, failure: &Failure) -> ExitCode {
    let message = failure.to_string();
    if json {
        eprintln!("{{\"failed\":true,\"message\":{}}}", json_string(&message));
    }
    eprintln!("error: {message}");
    ExitCode::from(failure.exit_status())
}

fn execute(prototype: &dyn DynModel, inv: &Invocation) -> ExitCode {
    for warning in &inv.warnings {
        eprintln!("warning: {warning}");
    }
    let Prepared {
        mut model,
        t0,
        t1,
        x0,
    } = match prepare(prototype, inv) {
        Ok(prepared) => prepared,
        Err(failure) => return fail(inv.json, &failure),
    };
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
    if let Some(count) = inv.ensemble {
        return ensemble(&mut *model, inv, t0, t1, &x0, &times, count);
    }
    eprintln!("{}", plan(&*model, &inv.options));
    let stdout = std::io::stdout();
    let mut out = std::io::BufWriter::new(stdout.lock());
    let columns = model.dim() + model.output_names().len();
    let mut written: Result<(), std::io::Error> = Ok(());
    if !inv.quiet {
        written = write_header(&mut out, model.state_names(), model.output_names());
    }
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
    let first = run(
        &mut *model,
        &inv.options,
        t0,
        t1,
        &x0,
        &times,
        |model: &dyn DynModel, t, x| {
            model.outputs(t, x, &mut outputs);
            if written.is_ok() && !inv.quiet {
                written = write_row(&mut out, t, x, &outputs);
            }
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
    let outcome = match first {
        Ok(outcome) => outcome,
        Err(failure) => return fail(inv.json, &failure),
    };
    let mut fastest = first_time;
    if inv.repeat > 1 {
        fastest = Duration::MAX;
        for _ in 0..inv.repeat {
            let start = Instant::now();
            let quiet = Options {
                progress: false,
                ..inv.options.clone()
            };
            if let Err(failure) = run(&mut *model, &quiet, t0, t1, &x0, &times, |_, _, _| Ok(())) {
                return fail(inv.json, &failure);
            }
            fastest = fastest.min(start.elapsed());
        }
    }
    let estimated_error = if inv.estimate_error {
        match estimate(&mut *model, inv, t0, t1, &x0, &plotted) {
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
        eprintln!("{}", summary.json());
    } else {
        eprintln!("{}", summary.text());
    }
    if let Ending::Stopped(_) = summary.outcome.ending {
        // The run ended where the model said: a success.
    }
    ExitCode::SUCCESS
}

/// The largest difference (relative to `max(|x|, 1)`) between the samples
/// of the run and those of a run at a 100× tighter tolerance.
fn estimate(
    model: &mut dyn DynModel,
    inv: &Invocation,
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
    run(model, &options, t0, t1, x0, &times, |_, t, x| {
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

/// Member `k` of an ensemble: the model's initial state for `k = 0`,
/// otherwise each component moved by up to `spread·max(|x0_i|, 1)` along a
/// Weyl sequence (deterministic, well spread). The moved states are states
/// of the reduced system (7), put back on the constraints by the caller.
pub fn ensemble_member(x0: &[f64], k: usize, spread: f64) -> Vec<f64> {
    x0.iter()
        .enumerate()
        .map(|(i, &x)| {
            if k == 0 {
                return x;
            }
            // Square roots of primes: rationally independent increments.
            let step = [2.0_f64, 3.0, 5.0, 7.0, 11.0, 13.0, 17.0, 19.0][i % 8].sqrt();
            let u = (k as f64 * step + i as f64 / 8.0).fract() * 2.0 - 1.0;
            x + spread * x.abs().max(1.0) * u
        })
        .collect()
}

/// `--ensemble K`: one field for K initial states against K direct
/// integrations, each timed as the smallest of `--repeat` runs.
fn ensemble(
    model: &mut dyn DynModel,
    inv: &Invocation,
    t0: f64,
    t1: f64,
    x0: &[f64],
    times: &[f64],
    count: usize,
) -> ExitCode {
    use crate::run::run_ensemble;
    // Moved states are put back on the constraints, as every state of a
    // run is: a member off them would be projected by its direct run and
    // not by the field.
    let mut keeper = crate::keep::Keeper::new(model, inv.options.tol);
    let mut members: Vec<Vec<f64>> = Vec::with_capacity(count);
    for k in 0..count {
        let mut member = ensemble_member(x0, k, inv.spread);
        if let Some(keeper) = keeper.as_mut() {
            if let Err(failure) = keeper.put_on(model, 0, t0, &mut member) {
                return fail(inv.json, &failure);
            }
        }
        members.push(member);
    }
    let n = x0.len();
    let quiet = Options {
        progress: false,
        ..inv.options.clone()
    };
    let direct_options = Options {
        method: Method::Direct,
        ..quiet.clone()
    };
    let field_options = Options {
        method: Method::Field,
        ..quiet
    };
    let solves = inv.repeat.max(1);
    let (mut field_time, mut one_time, mut direct_time) =
        (Duration::MAX, Duration::MAX, Duration::MAX);
    let mut field_states = vec![0.0; times.len() * count * n];
    let mut direct_states = vec![0.0; times.len() * count * n];
    let mut method = String::new();
    let initial = crate::ensemble::States::from_rows(&members);
    for _ in 0..solves {
        let mut kept = Duration::ZERO;
        // The members are handed over, so each solve gets its own copy
        // (made before the clock starts, as the direct runs' are).
        let handed = initial.clone();
        let start = Instant::now();
        let mut i = 0;
        let outcome = run_ensemble(model, &field_options, t0, t1, handed, times, |_, states| {
            // Keeping the states for the comparison is this harness's
            // work, not the field's: its time is taken off.
            let copying = Instant::now();
            let block = count * n;
            field_states[i * block..(i + 1) * block].copy_from_slice(&states.data);
            i += 1;
            kept += copying.elapsed();
        });
        match outcome {
            Ok(outcome) => method = outcome.report.method,
            Err(failure) => {
                if failure.kind == FailureKind::NotAffine {
                    eprintln!(
                        "error: `--ensemble` needs a model without events or implicit \
                         constraints"
                    );
                    return ExitCode::from(USAGE_EXIT_STATUS);
                }
                return fail(inv.json, &failure);
            }
        }
        field_time = field_time.min(start.elapsed().saturating_sub(kept));
        let start = Instant::now();
        if let Err(failure) = run(model, &field_options, t0, t1, x0, times, |_, _, _| Ok(())) {
            return fail(inv.json, &failure);
        }
        one_time = one_time.min(start.elapsed());
        let start = Instant::now();
        for (k, x) in members.iter().enumerate() {
            let mut i = 0;
            let solved = run(model, &direct_options, t0, t1, x, times, |_, _, state| {
                let at = (i * count + k) * n;
                direct_states[at..at + n].copy_from_slice(state);
                i += 1;
                Ok(())
            });
            if let Err(failure) = solved {
                return fail(inv.json, &failure);
            }
        }
        direct_time = direct_time.min(start.elapsed());
    }
    let difference = field_states
        .iter()
        .zip(&direct_states)
        .fold(0.0_f64, |m, (f, d)| m.max((f - d).abs() / d.abs().max(1.0)));
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    if inv.json {
        eprintln!(
            "{{\"ensemble\":{count},\"method\":{},\"spread\":{},\"ensemble_field_s\":{},\
             \"one_field_s\":{},\"direct_s\":{},\"largest_difference\":{},\"runs\":{}}}",
            json_string(&method),
            crate::summary::json_number(Some(inv.spread)),
            crate::summary::json_number(Some(field_time.as_secs_f64())),
            crate::summary::json_number(Some(one_time.as_secs_f64())),
            crate::summary::json_number(Some(direct_time.as_secs_f64())),
            crate::summary::json_number(Some(difference)),
            solves,
        );
    } else {
        eprintln!(
            "ensemble of {count} initial states (spread {}), {} samples: one field ({method}) \
             for all: {:.3} ms; the field for one: {:.3} ms; {count} direct integrations: \
             {:.3} ms; largest difference: {difference:.3e}",
            inv.spread,
            times.len(),
            ms(field_time),
            ms(one_time),
            ms(direct_time),
        );
    }
    ExitCode::SUCCESS
}
