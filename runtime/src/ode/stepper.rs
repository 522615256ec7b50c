//! The interface of a one-step integrator with dense output.

use crate::failure::{Failure, FailureKind};
use crate::ode::budget::Budget;
use crate::ode::controller::Controller;
use crate::ode::system::System;
use crate::ode::tolerance::{
    first_non_finite, initial_step, step_toward, underflows, Stats, Tolerance,
};

/// Where a one-step integrator is and how long its next step is: the
/// bookkeeping DOP853, RODAS4 and Magnus-4 share, with their step-size
/// controller and counts.
#[derive(Clone, Debug)]
pub struct Clock {
    pub t: f64,
    /// The last accepted step's start and length (`h_old == 0` before the
    /// first).
    pub t_old: f64,
    pub h_old: f64,
    /// The length the next step will try.
    pub h: f64,
    pub controller: Controller,
    pub stats: Stats,
}

impl Clock {
    /// At `t0`, about to try a step of length `h`.
    pub fn new(t0: f64, h: f64, controller: Controller, stats: Stats) -> Clock {
        Clock {
            t: t0,
            t_old: t0,
            h_old: 0.0,
            h,
            controller,
            stats,
        }
    }

    /// The start of an integration at `(t0, y0)` by a method of order
    /// `order`: the state and its rate `slope = X(t0, y0)` checked finite,
    /// and the first step `h0` when given (at most `h_max`), else Hairer's
    /// guess.
    #[allow(clippy::too_many_arguments)]
    pub fn start<S: System + ?Sized>(
        system: &S,
        t0: f64,
        y0: &[f64],
        slope: &mut [f64],
        tol: Tolerance,
        order: i32,
        h_max: f64,
        h0: Option<f64>,
        controller: Controller,
    ) -> Result<Clock, Failure> {
        if let Some(i) = first_non_finite(y0) {
            return Err(Failure::non_finite(t0, system.component_name(i)));
        }
        system.rhs(t0, y0, slope)?;
        if let Some(i) = first_non_finite(slope) {
            return Err(Failure::non_finite_rate(t0, system.rate_name(i)));
        }
        let mut stats = Stats {
            rhs_evaluations: 1,
            ..Stats::default()
        };
        let (h, controller) = match h0 {
            Some(h) if h.is_finite() && h > 0.0 => (h.min(h_max), controller),
            _ => {
                stats.rhs_evaluations += 1;
                let guess = initial_step(system, t0, y0, slope, tol, order, h_max)?;
                (guess, controller.guessed_start())
            }
        };
        Ok(Clock::new(t0, h, controller, stats))
    }

    /// The next attempt toward `t_limit`, drawn from `budget`: its length
    /// and whether it lands on `t_limit`; `stalled(length)` is the failure
    /// when the step underflows short of the limit.
    pub fn attempt(
        &self,
        t_limit: f64,
        budget: &Budget,
        stalled: impl FnOnce(f64) -> Failure,
    ) -> Result<(f64, bool), Failure> {
        budget.draw(self.t)?;
        let (h, reaches_limit) = step_toward(self.t, self.h, t_limit);
        if underflows(self.t, h) && !reaches_limit {
            return Err(stalled(h));
        }
        Ok((h, reaches_limit))
    }

    /// Where an attempt of length `h` ends: exactly on `t_limit` when it
    /// reaches it.
    pub fn end(&self, h: f64, reaches_limit: bool, t_limit: f64) -> f64 {
        if reaches_limit {
            t_limit
        } else {
            self.t + h
        }
    }

    /// Takes the accepted step of length `h` to `t_new`; the next tries
    /// `h_next`, or what was proposed before if longer when the step was
    /// cut short to land on the limit (that says nothing against it).
    pub fn accept(&mut self, h: f64, t_new: f64, h_next: f64, reaches_limit: bool) {
        self.t_old = self.t;
        self.h_old = h;
        self.t = t_new;
        self.h = if reaches_limit {
            h_next.max(self.h)
        } else {
            h_next
        };
        self.stats.accepted_steps += 1;
    }

    /// Rejects an attempt of length `h` with scaled error `err` (infinite
    /// when the attempt was not finite).
    pub fn reject(&mut self, h: f64, err: f64) {
        self.stats.rejected_steps += 1;
        self.h = self.controller.reject(h, err);
    }

    /// Rejects an attempt of length `h` that ended where the rates are not
    /// defined (a force infinite just ahead): a quarter of it next, so that
    /// the motion stops at the boundary, not beyond it.
    pub fn reject_short(&mut self, h: f64) {
        self.stats.rejected_steps += 1;
        self.h = 0.25 * h;
    }

    /// The measure declined the attempt (counted as a rejection; nothing
    /// else changes).
    pub fn decline(&mut self) -> StepOutcome {
        self.stats.rejected_steps += 1;
        StepOutcome::Declined
    }

    /// The last step as [`outside_last_step`] takes it.
    pub fn last_step(&self) -> (f64, f64, f64) {
        (self.t_old, self.t, self.h_old)
    }
}

/// The failure of a step that underflowed at `t` with length `h`: a
/// component that turned non-finite, else a rate that did, else the step
/// size itself.
pub fn stalled<S: System + ?Sized>(
    system: &S,
    t: f64,
    h: f64,
    component: Option<usize>,
    rate: Option<usize>,
) -> Failure {
    match (component, rate) {
        (Some(i), _) => Failure::non_finite(t, system.component_name(i)),
        (None, Some(i)) => Failure::non_finite_rate(t, system.rate_name(i)),
        (None, None) => Failure::new(t, FailureKind::StepSizeUnderflow { step: h }),
    }
}

/// An integrator with a [`Clock`]: its time, last step and proposed step.
pub trait Clocked {
    fn clock(&self) -> &Clock;
    fn clock_mut(&mut self) -> &mut Clock;

    fn time(&self) -> f64 {
        self.clock().t
    }
    /// The time at which the last accepted step started.
    fn previous_time(&self) -> f64 {
        self.clock().t_old
    }
    fn stats(&self) -> Stats {
        self.clock().stats
    }
    /// The length the next step will try.
    fn proposed_step(&self) -> f64 {
        self.clock().h
    }
    /// Replaces the next step's length (e.g. the one that worked before a
    /// restart); ignored unless finite and positive.
    fn propose_step(&mut self, h: f64) {
        if h.is_finite() && h > 0.0 {
            self.clock_mut().h = h;
        }
    }
}

/// A one-step integrator with dense output, as an object: a method holds
/// a `Box<dyn Stepper<S>>` (a [`StepperOf`]) and
/// pays one dynamic call per step. The system `S` is the trait's
/// parameter, not a method's, so that the trait is object-safe and yet
/// each integrator's stage loop is compiled for the system it steps: the
/// right side is called statically inside a step. That matters for direct
/// DOP853 on small models (docs/BENCHMARKS.md §10: its cost per
/// evaluation is one call through the model's vtable and a few
/// nanoseconds of bookkeeping; a `&dyn System` here would add a second
/// indirect call to every evaluation).
pub trait Stepper<S: ?Sized>: Clocked {
    /// The state at [`Clocked::time`].
    fn state(&self) -> &[f64];

    /// Takes one accepted step that does not pass `t_limit` (landing on it
    /// exactly when it is reached), drawing every attempt from `budget`,
    /// under the integrator's own error measure.
    fn step(&mut self, system: &S, t_limit: f64, budget: &Budget) -> Result<(), Failure>;

    /// [`Stepper::step`] under `measure` (the field method measures the
    /// state it recovers from the coefficients); [`StepOutcome::Declined`]
    /// when the measure declines the step (then nothing changed).
    fn step_measured(
        &mut self,
        system: &S,
        t_limit: f64,
        budget: &Budget,
        measure: &mut dyn ErrorMeasure,
    ) -> Result<StepOutcome, Failure>;

    /// The state at `t` in `[previous_time, time]` from the last step's
    /// continuous extension (may cost a few evaluations, once per step).
    fn dense(&mut self, system: &S, t: f64, out: &mut [f64]) -> Result<(), Failure>;

    /// The last step's continuous extension as a value that outlives the
    /// next step; `None` for an integrator without one of its own
    /// (Magnus: its caller reads the state at points of the step).
    fn dense_step(&mut self, system: &S) -> Result<Option<DenseStep>, Failure>;

    /// The time at which an explicit integrator found its step held by
    /// stability rather than accuracy, repeatedly; `None` if it never did or
    /// the method is stiff itself.
    fn stiffness_detected(&self) -> Option<f64> {
        None
    }

    /// The integrator itself, for a caller that keeps one integrator's
    /// steps in a form of its own (the quasilinear field keeps DOP853's
    /// stages and builds the extension only for the steps output asks
    /// for).
    fn as_any(&self) -> &dyn std::any::Any;
    /// The same, to change it (direct integration measures DOP853's local
    /// error by halves for its global error estimate).
    fn as_any_mut(&mut self) -> &mut dyn std::any::Any;
}

/// How an integrator of the registry (`crate::ode::Integrator`) starts.
pub trait Start: Sized + 'static {
    /// Its name in messages and summaries (`DOP853`).
    const NAME: &'static str;

    /// At `(t0, y0)` on `system`; `h_max` bounds the first step's guess,
    /// `h0`, when given, replaces the guess (a restart keeps the step
    /// that worked).
    fn start<S: System + ?Sized>(
        system: &S,
        t0: f64,
        y0: &[f64],
        tol: Tolerance,
        h_max: f64,
        h0: Option<f64>,
    ) -> Result<Self, Failure>;
}

/// The systems a method steps, one for each borrow they are made from
/// (`ModelSystem<'m>` over the model a call is given): a stepper object
/// for all of them ([`StepperOf`]) outlives each borrow.
pub trait Family: 'static {
    type System<'a>: System + ?Sized;
}

/// A stepper for every system of the family `F`, as an object.
pub type StepperOf<F> = Box<dyn for<'a> Stepper<<F as Family>::System<'a>>>;

/// The family of a model's reduced systems, over the model each call
/// borrows: what direct integration steps.
pub struct OfModel;

impl Family for OfModel {
    type System<'a> = crate::ode::system::ModelSystem<'a>;
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
    /// under `tol` (`hairer_error` in `dop853.rs`): the integrator then
    /// computes it in the pass that forms the step instead of calling
    /// [`ErrorMeasure::measure`].
    fn hairer_tolerance(&self) -> Option<crate::ode::tolerance::Tolerance> {
        None
    }
}

/// The RMS norm of an error estimate (per unit step, in `e5`), scaled by
/// the tolerance: RODAS4's and Magnus-4's own measure.
pub struct RmsMeasure(pub Tolerance);

impl ErrorMeasure for RmsMeasure {
    fn measure(
        &mut self,
        _t0: f64,
        h: f64,
        y0: &[f64],
        y1: &[f64],
        _e3: &[f64],
        e5: &[f64],
    ) -> Option<f64> {
        let e: Vec<f64> = e5.iter().map(|v| v * h).collect();
        Some(crate::ode::tolerance::rms_norm(&e, y0, y1, self.0))
    }
}

/// What `step_measured` did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StepOutcome {
    Accepted,
    /// The measure declined the step: nothing changed.
    Declined,
}

pub use crate::ode::dense::DenseStep;
