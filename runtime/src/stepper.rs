//! The interface of a one-step integrator with dense output.

use crate::budget::Budget;
use crate::failure::Failure;
use crate::system::System;
use crate::tolerance::Stats;

/// A one-step integrator holding its current time and state, and the dense
/// output of its last step.
pub trait Stepper {
    fn time(&self) -> f64;
    fn state(&self) -> &[f64];
    /// The time at which the last accepted step started.
    fn previous_time(&self) -> f64;
    fn stats(&self) -> Stats;
    /// The length the next step will try.
    fn proposed_step(&self) -> f64;
    /// Replaces the next step's length (e.g. the one that worked before a
    /// restart).
    fn propose_step(&mut self, h: f64);

    /// Takes one accepted step that does not pass `t_limit` (landing on it
    /// exactly when it is reached), drawing every attempt from `budget`.
    fn step<S: System + ?Sized>(
        &mut self,
        system: &S,
        t_limit: f64,
        budget: &Budget,
    ) -> Result<(), Failure>;

    /// The state at `t` in `[previous_time, time]` from the last step's
    /// continuous extension (may cost a few evaluations, once per step).
    fn dense<S: System + ?Sized>(
        &mut self,
        system: &S,
        t: f64,
        out: &mut [f64],
    ) -> Result<(), Failure>;

    /// The time at which an explicit integrator found its step held by
    /// stability rather than accuracy, repeatedly; `None` if it never did or
    /// the method is stiff itself.
    fn stiffness_detected(&self) -> Option<f64> {
        None
    }
}
