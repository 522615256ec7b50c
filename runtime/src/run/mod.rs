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
pub mod integration;
pub mod options;
pub mod regime;
pub mod solution;

use crate::budget::Budget;
use crate::failure::{Failure, FailureKind};
use crate::method::Method;
use crate::model::DynModel;
use integration::{make_solver, Advance, Integration};
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
    mut sample: impl FnMut(&dyn DynModel, f64, &[f64]) -> Result<(), Failure>,
) -> Result<Outcome, Failure> {
    let mut integration = Integration::new(model, options, t0, t1, x0);
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

/// Integrates `members` (at least one; the first is the reference)
/// through one field: `sample(t, states)` at every time of `times`. Exact
/// for affine models; for the others the members follow the field of the
/// motion linearised along the reference, to first order in their distance
/// from it. The members are taken, not copied, and every sample's states
/// are written into one buffer: with ten thousand members, copies and
/// fresh allocations would cost more than the field.
pub fn run_ensemble(
    model: &mut dyn DynModel,
    options: &Options,
    t0: f64,
    t1: f64,
    members: crate::ensemble::States,
    times: &[f64],
    mut sample: impl FnMut(f64, &crate::ensemble::States),
) -> Result<Outcome, Failure> {
    if model.switches() > 0 || !model.constraints().is_empty() {
        return Err(Failure::new(t0, FailureKind::NotAffine));
    }
    let budget = Budget::new(options.max_steps);
    budget.accepted_to(t0);
    let h_max = (t1 - t0).max(f64::MIN_POSITIVE);
    let field = Options {
        method: Method::Field,
        ..options.clone()
    };
    assert!(!members.is_empty(), "an ensemble has a reference member");
    let mut solver = make_solver(model, &field, t0, members.row(0), h_max)?;
    let mut next = 0;
    while next < times.len() && times[next] <= t0 {
        sample(times[next], &members);
        next += 1;
    }
    let mut states = crate::ensemble::States::default();
    if !solver.track_members(members) {
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
    Ok(Outcome {
        report: solver.report(),
        ending: Ending::End,
        events: 0,
        budget_used: budget.used(),
        kept: None,
    })
}
