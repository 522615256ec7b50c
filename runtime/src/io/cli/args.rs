//! The generated binary's arguments, parsed by hand (the runtime has no
//! dependencies); `lagc run` calls [`parse`] too, so that bad usage is
//! reported before anything is built.

use crate::choice::{IntegratorChoice, Method};
use crate::io::plot::PlotRequest;
use crate::method::field::Anchor;
use crate::run::inputs::Interpolation;
use crate::run::options::Options;

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
  --input NAME=FILE.csv  drive input NAME by the columns `t,NAME` of the file
                         (repeatable); a change restarts the integration
  --input-interp hold|linear
                         between the file's rows: hold each value (default)
                         or interpolate linearly
  --rtol R, --atol A     the per-step tolerance (default 1e-10, 1e-12): each
                         step's local error is kept below atol + rtol·|x|;
                         the global error is usually a modest multiple of it
                         (see --estimate-error)
  --samples N            N evenly spaced output times over the span
                         (default 101; 1 prints the final state only);
                         output times never change the steps
  --times T1,T2,...      output at these times instead
  --step-to-times        cut the steps to land on every output time (a stop
                         time, as SUNDIALS and GSL's driver do): the samples
                         carry the step's error instead of the continuous
                         extension's, and the steps depend on the output
  --estimate-error       also run at a 100× tighter tolerance and report the
                         largest difference (an estimate of the global error;
                         like the error against `exact` lines, relative:
                         |a − b| / max(|b|, 1) over samples and components)
  --no-global-error      do not estimate the global error along the run
                         (the summary's `global error` line, which costs
                         up to a third of a short run); the states are the
                         same bit for bit
  --anchor VALUE         field: every free anchor value c_A (default 0)
  --no-reanchor          field: stop where the conditions (13) degrade
                         instead of re-anchoring
  --max-steps N          the work budget: steps of every kind (default 1e6)
  --plot FILE.svg        draw the columns against time into FILE.svg
  --phase X,Y            with --plot: draw column Y against column X
  --ensemble K           K initial states around the model's (spread by
                         --spread, default 0.1 of each value), against K
                         direct integrations: times and the largest
                         difference (an affine motion: all through one
                         field, exactly; otherwise each member's deviation
                         from the first on steps shared by all, to the
                         tolerance, or on its own where it needs far
                         shorter steps)
  --spread S             the ensemble's relative spread
  --sensitivity          also write dX(t)/dY0 for every initial value the
                         model states and dX(t)/dP for every param, as the
                         columns `d(X)/d(Y0)`, `d(X)/d(P)` (the variational
                         equations integrated with the motion by the direct
                         method, inside its error control, with their jumps
                         at events, across changes of candidates, kept
                         on holonomic constraints by the projection's
                         derivative)
  -o FILE                write the CSV to FILE instead of stdout; with
                         --ensemble, the members' states (member,t,<state...>,
                         member by member) instead of timing them against
                         direct integrations
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
    /// `--sensitivity`: the forward sensitivities as extra columns.
    pub sensitivity: bool,
    /// `-o FILE`: the CSV (a run's samples, or the ensemble's states) is
    /// written there instead of stdout.
    pub output: Option<String>,
    /// Warnings to print before running (e.g. a tolerance below rounding).
    pub warnings: Vec<String>,
    /// `--input NAME=FILE`: `(name, file)`, checked against the model's
    /// inputs and read when the run starts.
    pub inputs: Vec<(String, String)>,
    pub interpolation: Interpolation,
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
        sensitivity: false,
        spread: 0.1,
        output: None,
        warnings: Vec::new(),
        inputs: Vec::new(),
        interpolation: Interpolation::Hold,
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
            "--sensitivity" => inv.sensitivity = true,
            "--step-to-times" => inv.options.step_to_times = true,
            "--no-global-error" => inv.options.global_error = false,
            "--ensemble" => inv.ensemble = Some(count(flag, value(flag, &mut args)?, 10_000_000)?),
            "--spread" => {
                let s = number(flag, value(flag, &mut args)?)?;
                if !(s >= 0.0) {
                    return Err(format!("`--spread {s}`: a spread must be ≥ 0"));
                }
                inv.spread = s;
            }
            "-o" | "--output" => inv.output = Some(value(flag, &mut args)?.to_string()),
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
            "--input" => {
                let (name, file) = name_value(flag, value(flag, &mut args)?)?;
                inv.inputs.push((name.to_string(), file.to_string()));
            }
            "--input-interp" => {
                inv.interpolation = match value(flag, &mut args)? {
                    "hold" => Interpolation::Hold,
                    "linear" => Interpolation::Linear,
                    other => {
                        return Err(format!(
                            "`--input-interp {other}`: expected `hold` or `linear`"
                        ))
                    }
                }
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
