//! `--ensemble K`: K initial states at once (through one field for an
//! affine motion, as deviations on shared steps otherwise). With `-o FILE`
//! the members' states are written there as CSV (`member,t,<state…>`,
//! member by member); without it, the ensemble is timed against K direct
//! integrations (a benchmark harness) and their largest difference shown.

use super::args::Invocation;
use super::exit::fail;
use crate::choice::Method;
use crate::failure::{FailureKind, USAGE_EXIT_STATUS};
use crate::io::summary::json_string;
use crate::model::DynModel;
use crate::run::options::Options;
use crate::run::run;
use std::process::ExitCode;
use std::time::{Duration, Instant};

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

/// Why member `k` (the start moved by up to `spread`) cannot start: the
/// constraints' failure, with what moved and what the user can do.
fn member_refused(
    model: &dyn DynModel,
    k: usize,
    spread: f64,
    failure: &crate::failure::Failure,
) -> crate::failure::Failure {
    let member = if k == 0 {
        "member 0 (the model's own start)".to_string()
    } else {
        format!(
            "member {k} (the start with each of {} moved by up to --spread {spread} of its \
             size)",
            model.state_names().join(", ")
        )
    };
    crate::failure::Failure::new(
        failure.time,
        FailureKind::Unsupported {
            message: format!(
                "--ensemble: {member} cannot be put on the constraints: {failure}. Where \
                 the start is near a singular point of the constraints (a dependent's \
                 pivot vanishing, as a pendulum in x, y released level with its pivot), \
                 moved members may have no state on them nearby: give a smaller --spread, \
                 or a start away from the singular point (--init)"
            ),
        },
    )
}

/// `--ensemble K`: K initial states at once against K direct
/// integrations, each timed as the smallest of `--repeat` runs.
pub(crate) fn ensemble(
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
    let mut keeper = crate::run::keep::Keeper::new(model, inv.options.tol);
    let mut members: Vec<Vec<f64>> = Vec::with_capacity(count);
    for k in 0..count {
        let mut member = ensemble_member(x0, k, inv.spread);
        if let Some(keeper) = keeper.as_mut() {
            // In the mode the member starts in, as a run's start is: the
            // first candidate's (mode 0) is singular where the run starts
            // on another (a pendulum in x, y released level with its
            // pivot, y' = −x x'/y = 0/0), and every member, the model's
            // own start too, was refused there naming no cause.
            let mode = crate::run::regime::best_mode(model, t0, &member).0;
            if let Err(failure) = keeper.put_on(model, mode, t0, &mut member) {
                return fail(inv.json, &member_refused(model, k, inv.spread, &failure));
            }
        }
        members.push(member);
    }
    if let Some(file) = &inv.output {
        return write_ensemble(model, inv, (t0, t1), times, members, file);
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
    let mut counts = (count, 0, None);
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
            Ok(outcome) => {
                method = outcome.outcome.report.method;
                counts = (
                    outcome.along_field,
                    outcome.on_their_own,
                    outcome.largest_estimate,
                );
            }
            Err(failure) => return refuse(inv, &failure),
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
    let (along, own, estimate) = counts;
    if inv.json {
        eprintln!(
            "{{\"ensemble\":{count},\"method\":{},\"spread\":{},\"ensemble_field_s\":{},\
             \"one_field_s\":{},\"direct_s\":{},\"largest_difference\":{},\"runs\":{},\
             \"along_field\":{along},\"on_their_own\":{own},\"largest_estimate\":{}}}",
            json_string(&method),
            crate::io::summary::json_number(Some(inv.spread)),
            crate::io::summary::json_number(Some(field_time.as_secs_f64())),
            crate::io::summary::json_number(Some(one_time.as_secs_f64())),
            crate::io::summary::json_number(Some(direct_time.as_secs_f64())),
            crate::io::summary::json_number(Some(difference)),
            solves,
            crate::io::summary::json_number(estimate),
        );
    } else {
        eprintln!(
            "ensemble of {count} initial states (spread {}), {} samples: the ensemble ({method}) \
             for all: {:.3} ms; one field run, for scale: {:.3} ms; {count} direct integrations: \
             {:.3} ms; largest difference: {difference:.3e}; {}",
            inv.spread,
            times.len(),
            ms(field_time),
            ms(one_time),
            ms(direct_time),
            members_line(along, own, estimate),
        );
    }
    ExitCode::SUCCESS
}

/// How the members were followed, for the summary.
fn members_line(along: usize, own: usize, estimate: Option<f64>) -> String {
    match estimate {
        None => format!("{along} members exact through the field (an affine motion)"),
        Some(e) => format!(
            "{along} members corrected on shared steps (largest local error {e:.2} of the \
             tolerance), {own} integrated on their own"
        ),
    }
}

/// The ensemble refused: a model it cannot follow, or a failure.
fn refuse(inv: &Invocation, failure: &crate::failure::Failure) -> ExitCode {
    if failure.kind == FailureKind::NotAffine {
        eprintln!(
            "error: `--ensemble` needs a model without events or implicit constraints (its \
             members share one regime, which a switch or a change of candidate would split); \
             run the members one by one (`--init`), or write the constraint explicitly \
             (`constraint y' = …`) where one candidate serves the whole run"
        );
        return ExitCode::from(USAGE_EXIT_STATUS);
    }
    fail(inv.json, failure)
}

/// `--ensemble K -o FILE`: the members' states as CSV, `member,t,<state…>`,
/// member by member (member 0 is the model's own initial state); the
/// summary on stderr.
fn write_ensemble(
    model: &mut dyn DynModel,
    inv: &Invocation,
    (t0, t1): (f64, f64),
    times: &[f64],
    members: Vec<Vec<f64>>,
    file: &str,
) -> ExitCode {
    use crate::run::run_ensemble;
    use std::io::Write;
    let count = members.len();
    let n = members.first().map_or(0, Vec::len);
    let options = Options {
        progress: false,
        ..inv.options.clone()
    };
    let start = Instant::now();
    let mut sampled: Vec<(f64, Vec<f64>)> = Vec::with_capacity(times.len());
    let initial = crate::ensemble::States::from_rows(&members);
    let outcome = run_ensemble(model, &options, t0, t1, initial, times, |t, states| {
        sampled.push((t, states.data.clone()))
    });
    let outcome = match outcome {
        Ok(outcome) => outcome,
        Err(failure) => return refuse(inv, &failure),
    };
    let elapsed = start.elapsed();
    let write = || -> std::io::Result<()> {
        let mut out = std::io::BufWriter::new(std::fs::File::create(file)?);
        write!(out, "member,t")?;
        for name in model.state_names() {
            write!(out, ",{name}")?;
        }
        writeln!(out)?;
        for m in 0..count {
            for (t, data) in &sampled {
                write!(out, "{m},")?;
                crate::io::output::write_row(&mut out, *t, &data[m * n..(m + 1) * n], &[])?;
            }
        }
        out.flush()
    };
    if let Err(error) = write() {
        eprintln!("error: cannot write `{file}`: {error}");
        return ExitCode::from(USAGE_EXIT_STATUS);
    }
    let line = members_line(
        outcome.along_field,
        outcome.on_their_own,
        outcome.largest_estimate,
    );
    if inv.json {
        eprintln!(
            "{{\"ensemble\":{count},\"method\":{},\"spread\":{},\"output\":{},\
             \"seconds\":{},\"along_field\":{},\"on_their_own\":{},\"largest_estimate\":{}}}",
            json_string(&outcome.outcome.report.method),
            crate::io::summary::json_number(Some(inv.spread)),
            json_string(file),
            crate::io::summary::json_number(Some(elapsed.as_secs_f64())),
            outcome.along_field,
            outcome.on_their_own,
            crate::io::summary::json_number(outcome.largest_estimate),
        );
    } else {
        eprintln!(
            "ensemble of {count} initial states (spread {}), {} samples each, written to \
             {file}: {}; {:.3} ms",
            inv.spread,
            sampled.len(),
            line,
            elapsed.as_secs_f64() * 1e3,
        );
    }
    ExitCode::SUCCESS
}
