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

/// How a an integrator step's error estimates become one scaled error (≤ 1
/// accepts). The field method measures the error of the state it recovers
/// from the coefficients rather than of the coefficients themselves.
/// The state at `t` when `t` is not inside the last step `(t_old, t_new)`
/// (or there was none: `h_old == 0`): the step's end state at or after
/// its end, its start state at or before its start. `None` inside, where
/// a stepper's own continuous extension answers.
pub fn outside_last_step<'a>(
    t: f64,
    (t_old, t_new, h_old): (f64, f64, f64),
    y_old: &'a [f64],
    y: &'a [f64],
) -> Option<&'a [f64]> {
    if h_old == 0.0 || t >= t_new {
        Some(y)
    } else if t <= t_old {
        Some(y_old)
    } else {
        None
    }
}

pub trait ErrorMeasure {
    /// The scaled error of the step from `(t0, y0)` to `(t0 + h, y1)`, with
    /// the step's error estimates `e3`, `e5` per unit step (DOP853: Hairer's 3rd- and 5th-order ones; RODAS4: its one estimate, twice);
    /// `None` declines the step: it must not be taken at any length that
    /// reaches this far (the field's conditions degraded).
    fn measure(
        &mut self,
        t0: f64,
        h: f64,
        y0: &[f64],
        y1: &[f64],
        e3: &[f64],
        e5: &[f64],
    ) -> Option<f64>;

    /// `Some(tol)` when the measure is Hairer's norm of the step itself
    /// under `tol` ([`crate::dop853::hairer_error`]): the integrator then
    /// computes it in the pass that forms the step instead of calling
    /// [`ErrorMeasure::measure`].
    fn hairer_tolerance(&self) -> Option<crate::tolerance::Tolerance> {
        None
    }
}

/// What `step_measured` did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StepOutcome {
    Accepted,
    /// The measure declined the step: nothing changed.
    Declined,
}

/// One step's continuous extension, detached from its integrator.
#[derive(Clone, Debug)]
pub struct DenseStep {
    pub t_old: f64,
    pub t_new: f64,
    pub(crate) h: f64,
    pub(crate) kind: DenseKind,
}

#[derive(Clone, Debug)]
pub(crate) enum DenseKind {
    /// DOP853's order-7 extension (Hairer's `contd8` coefficients).
    Dop853 { cont: Vec<f64> },
    /// RODAS4's order-3 extension.
    Rodas4 {
        y_old: Vec<f64>,
        y: Vec<f64>,
        d2: Vec<f64>,
        d3: Vec<f64>,
    },
}

impl DenseStep {
    /// The state at `t` (clamped to the step).
    pub fn eval(&self, t: f64, out: &mut [f64]) {
        let s = if self.h > 0.0 {
            ((t - self.t_old) / self.h).clamp(0.0, 1.0)
        } else {
            1.0
        };
        match &self.kind {
            DenseKind::Dop853 { cont } => crate::dop853::eval_contd8(cont, s, out),
            DenseKind::Rodas4 { y_old, y, d2, d3 } => {
                crate::rodas4::eval_dense(y_old, y, d2, d3, s, out)
            }
        }
    }
}
