//! The run: one method advancing the model step by step; the output at the
//! requested times from the dense output (so output never constrains the
//! steps); events — a switching function changing sign, located by root
//! finding on the dense output, the integrator (or the field) restarted
//! there in the new regime; implicit constraints switching candidates; and
//! `stop when`.
//!
//! | file | what it holds |
//! |---|---|
//! | `integration` | the run's state and its loop, as an object: [`Integration`] |
//! | `options` | what a run is asked ([`Options`]) and what it did ([`Outcome`]) |
//! | `regime` | branches at the start, modes (candidates), singular configurations |
//! | `diagnosis` | a failure named after its physical cause |
//! | `solution` | the whole solution as a value (every step's extension) |
//!
//! This file holds the loops over an [`Integration`]: [`run`] (sampled at
//! given times: the command line, the report), [`solve`] (the whole
//! solution) and the ensemble's [`run_ensemble`].

pub mod diagnosis;
pub mod events;
pub mod impacts;
pub mod inputs;
pub mod integration;
pub mod keep;
pub mod options;
pub mod progress;
pub mod regime;
pub mod saltation;
pub mod sensitivity;
pub mod solution;
pub mod start;
pub mod watch;

use crate::choice::Method;
use crate::failure::{Failure, FailureKind};
use crate::model::DynModel;
use crate::ode::budget::Budget;
use crate::ode::tolerance::Tolerance;
use integration::{make_solver, Advance, Integration, Spare};
use options::{Ending, Options, Outcome};
use solution::Solution;

/// Integrates `model` from `(t0, x0)` to `t1`, calling `sample(t, x)` at
/// every time of `times` (ascending, within `[t0, t1]`) and, when `stop
/// when` ends the run early, at the stop time: a loop over an
/// [`Integration`].
pub fn run(
    model: &mut dyn DynModel,
    options: &Options,
    t0: f64,
    t1: f64,
    x0: &[f64],
    times: &[f64],
    sample: impl FnMut(&dyn DynModel, f64, &[f64]) -> Result<(), Failure>,
) -> Result<Outcome, Failure> {
    run_reusing(
        model,
        options,
        t0,
        t1,
        x0,
        times,
        sample,
        &mut Spare::default(),
    )
}

/// [`run`] in the storage `spare` holds (an earlier run's on the same
/// model, or empty), leaving this run's there for the next: the same
/// run, without allocating its solver, keeper and states again. Solves
/// repeated on one model (`--repeat`, a benchmark's loop) go through it.
#[allow(clippy::too_many_arguments)]
pub fn run_reusing(
    model: &mut dyn DynModel,
    options: &Options,
    t0: f64,
    t1: f64,
    x0: &[f64],
    times: &[f64],
    mut sample: impl FnMut(&dyn DynModel, f64, &[f64]) -> Result<(), Failure>,
    spare: &mut Spare,
) -> Result<Outcome, Failure> {
    let taken = std::mem::take(spare);
    let mut integration = Integration::new_reusing(model, options, t0, t1, x0, taken);
    // The last sample's time: a run that ends where a sample was written
    // does not write that row twice.
    let mut last: Option<f64> = None;
    for &t in times {
        match integration.advance_to(t)? {
            Advance::Reached(_) => {
                sample(integration.model(), t, integration.state())?;
                last = Some(t);
            }
            Advance::Ended(_) => break,
        }
    }
    let outcome = integration.finish()?;
    if let Ending::Stopped(at) | Ending::Rest { at, .. } = outcome.ending {
        if last != Some(at) {
            sample(integration.model(), at, integration.state())?;
        }
    }
    *spare = integration.into_spare();
    Ok(outcome)
}

/// The whole solution as a value: [`run`], keeping every step's continuous
/// extension (memory grows with the number of steps).
pub fn solve(
    model: &mut dyn DynModel,
    options: &Options,
    t0: f64,
    t1: f64,
    x0: &[f64],
) -> Result<Solution, Failure> {
    let mut integration = Integration::new(model, options, t0, t1, x0);
    integration.keep_pieces();
    let outcome = integration.finish()?;
    Ok(Solution {
        t0,
        x0: x0.to_vec(),
        pieces: integration.take_pieces(),
        outcome,
    })
}

/// An ensemble's field's or base's relative tolerance at the least
/// (rounding).
const MIN_RTOL: f64 = 1e-14;

/// What an ensemble run did, beyond the reference's [`Outcome`].
#[derive(Clone, Debug)]
pub struct EnsembleOutcome {
    pub outcome: Outcome,
    /// Members followed through the field: exactly (an affine motion), or
    /// corrected within the tolerance by their estimates.
    pub along_field: usize,
    /// Members the field could not follow within the tolerance, each
    /// integrated on its own (direct, the same tolerance).
    pub on_their_own: usize,
    /// The largest local error estimate among the members kept on the
    /// field, in units of the tolerance (`None`: exact, an affine motion).
    pub largest_estimate: Option<f64>,
}

/// Integrates `members` (at least one; the first is the reference):
/// `sample(t, states)` at every time of `times`. An affine motion's
/// members go through one field, exactly; the members are taken, not
/// copied, and their samples are written into one buffer as they come:
/// with ten thousand members, copies and fresh allocations would cost
/// more than the field. A non-affine motion's members are deviations from
/// the first on shared steps ([`crate::method::deviation`]), and a member
/// that leaves them is integrated on its own: never first order in the
/// spread.
pub fn run_ensemble(
    model: &mut dyn DynModel,
    options: &Options,
    t0: f64,
    t1: f64,
    members: crate::ensemble::States,
    times: &[f64],
    mut sample: impl FnMut(f64, &crate::ensemble::States),
) -> Result<EnsembleOutcome, Failure> {
    use crate::ensemble::States;
    if model.switches() > 0 || !model.constraints().is_empty() {
        return Err(Failure::new(t0, FailureKind::NotAffine));
    }
    // A non-affine motion's members as deviations from the first (exact
    // at any spread, and cheaper than the field's frames were: issue 27,
    // BENCHMARKS §4a; the field's frames that carried them before were
    // removed with this path).
    if !model.affine() {
        return deviations(model, options, t0, t1, members, times, sample);
    }
    let budget = Budget::new(options.max_steps);
    budget.accepted_to(t0);
    let h_max = (t1 - t0).max(f64::MIN_POSITIVE);
    let field = Options {
        method: Method::Field,
        tol: Tolerance {
            rtol: options.tol.rtol.max(MIN_RTOL),
            atol: options.tol.atol,
        },
        ..options.clone()
    };
    assert!(!members.is_empty(), "an ensemble has a reference member");
    let count = members.len();
    let mut solver = make_solver(model, &field, t0, members.row(0), h_max)?;
    let mut next = 0;
    while next < times.len() && times[next] <= t0 {
        sample(times[next], &members);
        next += 1;
    }
    let mut states = States::default();
    if !solver.track_members(members, options.tol) {
        return Err(Failure::new(t0, FailureKind::NotAffine));
    }
    while solver.time() < t1 {
        solver.advance(model, t1, &budget)?;
        budget.accepted_to(solver.time());
        while next < times.len() && times[next] <= solver.time() {
            solver.members_at(model, times[next], &mut states)?;
            sample(times[next], &states);
            next += 1;
        }
    }
    // A method that estimates its members' errors is not exact on them:
    // an affine field's members are (`Solver::member_estimates`).
    if solver.member_estimates().is_some() {
        return Err(Failure::new(t0, FailureKind::NotAffine));
    }
    Ok(EnsembleOutcome {
        outcome: Outcome {
            report: solver.report(),
            ending: Ending::End,
            events: 0,
            budget_used: budget.used(),
            kept: None,
        },
        along_field: count,
        on_their_own: 0,
        largest_estimate: None,
    })
}

/// The base's tolerance over the members' on a non-affine ensemble: a
/// member's error is the base's defect carried along its own motion.
const BASE_MARGIN: f64 = 0.01;

/// A non-affine ensemble: every member as its deviation from the first,
/// integrated on shared steps ([`crate::method::deviation`]) around the
/// first's own tight integration; members that leave the shared steps are
/// integrated on their own.
fn deviations(
    model: &mut dyn DynModel,
    options: &Options,
    t0: f64,
    t1: f64,
    members: crate::ensemble::States,
    times: &[f64],
    mut sample: impl FnMut(f64, &crate::ensemble::States),
) -> Result<EnsembleOutcome, Failure> {
    assert!(!members.is_empty(), "an ensemble has a reference member");
    let count = members.len();
    let base_tol = options.tol.scaled(BASE_MARGIN);
    let base_options = Options {
        method: Method::Direct,
        progress: false,
        tol: Tolerance {
            rtol: base_tol.rtol.max(MIN_RTOL),
            atol: base_tol.atol,
        },
        ..options.clone()
    };
    let base = solve(model, &base_options, t0, t1, members.row(0))?;
    let mut samples: Vec<(f64, crate::ensemble::States)> = times
        .iter()
        .take_while(|&&t| t <= t0)
        .map(|&t| (t, members.clone()))
        .collect();
    let followed = crate::method::deviation::follow(
        model,
        &base,
        options.tol,
        &members,
        (t0, t1),
        times,
        &mut samples,
    )?;
    let mut outcome = base.outcome;
    outcome.report.method = format!("deviations around {}", outcome.report.method);
    outcome.report.notes.push(format!(
        "ensemble members: {} shared steps, {} rejected, {} member steps",
        followed.steps, followed.rejected, followed.member_steps
    ));
    let (on_their_own, largest) = integrate_on_their_own(
        model,
        options,
        (t0, t1),
        (&members, &followed.left),
        &followed.estimates,
        &mut samples,
    )?;
    for (t, states) in &samples {
        sample(*t, states);
    }
    Ok(EnsembleOutcome {
        outcome,
        along_field: count - on_their_own,
        on_their_own,
        largest_estimate: Some(largest),
    })
}

/// The base of a non-affine ensemble: its solution's continuous extension.
impl crate::method::deviation::Base for Solution {
    fn at(&self, t: f64, out: &mut [f64]) {
        if t <= self.t0 || self.pieces.is_empty() {
            out.copy_from_slice(&self.x0);
            return;
        }
        let i = self.pieces.partition_point(|p| p.until < t);
        let piece = &self.pieces[i.min(self.pieces.len() - 1)];
        piece.segment.eval(t, out);
    }

    fn typical_step(&self) -> Option<f64> {
        let mut lengths: Vec<f64> = (0..self.pieces.len())
            .map(|i| {
                let from = if i == 0 {
                    self.t0
                } else {
                    self.pieces[i - 1].until
                };
                self.pieces[i].until - from
            })
            .collect();
        let middle = lengths.len() / 2;
        (!lengths.is_empty()).then(|| *lengths.select_nth_unstable_by(middle, f64::total_cmp).1)
    }
}

/// Each member beyond the tolerance by its estimate (or dropped: infinite,
/// or NaN) integrated on its own (direct, the same tolerance) from where
/// it left the others (`left`; from its initial state where not given),
/// over the samples' times from there, into the samples. Returns how many,
/// and the largest estimate of the others.
fn integrate_on_their_own(
    model: &mut dyn DynModel,
    options: &Options,
    (t0, t1): (f64, f64),
    (initial, left): (&crate::ensemble::States, &[crate::method::deviation::Left]),
    estimates: &[f64],
    samples: &mut [(f64, crate::ensemble::States)],
) -> Result<(usize, f64), Failure> {
    let n = initial.n;
    let direct = Options {
        method: Method::Direct,
        progress: false,
        ..options.clone()
    };
    let sampled: Vec<f64> = samples.iter().map(|(t, _)| *t).collect();
    let mut on_their_own = 0;
    let mut largest: f64 = 0.0;
    for (m, &estimate) in estimates.iter().enumerate() {
        if estimate <= 1.0 {
            largest = largest.max(estimate);
            continue;
        }
        on_their_own += 1;
        let (from, x) = match left.get(m) {
            Some(Some((t, x))) => (*t, x.as_slice()),
            _ => (t0, initial.row(m)),
        };
        // The samples up to where it left are the shared steps'.
        let mut i = if from > t0 {
            sampled.partition_point(|&t| t <= from)
        } else {
            0
        };
        run(model, &direct, from, t1, x, &sampled[i..], |_, _, x| {
            if let Some((_, states)) = samples.get_mut(i) {
                states.data[m * n..(m + 1) * n].copy_from_slice(x);
            }
            i += 1;
            Ok(())
        })?;
    }
    Ok((on_their_own, largest))
}
