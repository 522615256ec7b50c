//! The field method's global error estimate, carried as direct
//! integration carries its own (`ode::dop853::global_error`): each step's
//! local error in the state (the window's coefficient error estimates
//! mapped through the conditions, [`super::window::Window::local_error`])
//! summed relative to `max(|x|, 1)`, and carried along the motion past
//! the summary's bound (`global_error::growth`), for the same summary
//! line and warning.
//!
//! The steps of a window are added when the next advance begins (or the
//! run restarts), or up to an event's time when the driver reports one
//! ([`FieldError::cut`]): the window's steps past an event are not the
//! motion's.
//!
//! The local errors: Hairer's estimates of the windows' coefficient
//! steps, mapped. Once the sum passes the bound, and every
//! `CALIBRATION_STRIDE` steps after, a step's error is measured against
//! a reference, two DOP853 half-steps of the reduced system from the
//! step's start (24 evaluations; the reference's own error is 1/256 of a
//! whole DOP853 step's), and the ratio scales the estimates as direct
//! integration's Richardson measure does (`GlobalError::add_measured`);
//! the measure sees all of the step's error, the Newton iteration's
//! included. Past the bound every step's error is measured, and carried
//! along the motion with its sign (`global_error::growth`). The steps of
//! stiff and Magnus windows are not counted (the estimate then says it is
//! partial).

use crate::method::solver::GlobalErrorEstimate;
use crate::model::DynModel;
use crate::ode::dop853::global_error::growth::{past_bound, Growth};
use crate::ode::dop853::global_error::{relative, GlobalError};
use crate::ode::dop853::step_by_halves;
use crate::ode::system::ModelSystem;

/// One accepted step of a window, not yet added.
#[derive(Clone, Debug)]
struct Unfed {
    t0: f64,
    x0: Vec<f64>,
    t1: f64,
    x1: Vec<f64>,
    /// `None`: a step whose error is not estimated.
    local: Option<Vec<f64>>,
}

/// The carried estimate of one field run.
#[derive(Clone, Debug)]
pub struct FieldError {
    rtol: f64,
    global: GlobalError,
    /// Set at the first step from the model: `None` for a constrained
    /// model, whose reduced system drifts off its constraints (direct
    /// integration's comment).
    growth: Option<Option<Growth>>,
    n: usize,
    /// Evaluations of the reference steps.
    evaluations: usize,
    unfed: Vec<Unfed>,
}

impl FieldError {
    /// For a run of `n` components at relative tolerance `rtol`.
    pub fn new(n: usize, rtol: f64) -> FieldError {
        FieldError {
            rtol,
            global: GlobalError::new(),
            growth: None,
            n,
            evaluations: 0,
            unfed: Vec::new(),
        }
    }

    fn growth(&mut self, model: &dyn DynModel) -> Option<&mut Growth> {
        let n = self.n;
        self.growth
            .get_or_insert_with(|| {
                (model.constraints().is_empty() && !model.keeps_constraints())
                    .then(|| Growth::new(n))
            })
            .as_mut()
    }

    /// A window accepted from `(t, x)`: its steps' ends `ends` with their
    /// states and local errors (`None` where not estimated).
    pub fn window(
        &mut self,
        (t, x): (f64, &[f64]),
        ends: &[f64],
        states: &[Vec<f64>],
        errors: &[Option<Vec<f64>>],
    ) {
        let (mut t0, mut x0) = (t, x);
        for ((&t1, x1), local) in ends.iter().zip(states).zip(errors) {
            self.unfed.push(Unfed {
                t0,
                x0: x0.to_vec(),
                t1,
                x1: x1.clone(),
                local: local.clone(),
            });
            (t0, x0) = (t1, x1);
        }
    }

    /// Adds the steps that start before `t` (all: `f64::INFINITY`).
    pub fn feed(&mut self, model: &dyn DynModel, t: f64) {
        let system = ModelSystem(model);
        self.growth(model);
        for step in std::mem::take(&mut self.unfed) {
            if step.t0 >= t {
                break;
            }
            let Some(local) = step.local else {
                self.global.skip();
                continue;
            };
            let h = step.t1 - step.t0;
            let estimated = relative(&local, &step.x1);
            let started = matches!(&self.growth, Some(Some(g)) if g.started());
            let carried = started || past_bound(&self.global, self.rtol);
            let carrying = carried && matches!(self.growth, Some(Some(_)));
            // The step's error against the reference, where asked for; a
            // reference that fails leaves the estimate as it is (the
            // estimate never fails the run).
            let mut measured = None;
            let calibrates = self.global.wants_measure(self.rtol);
            if carrying || calibrates {
                self.evaluations += 24;
                let mut reference = vec![0.0; step.x1.len()];
                if let Ok(true) = step_by_halves(&system, step.t0, &step.x0, h, &mut reference) {
                    for (r, x) in reference.iter_mut().zip(&step.x1) {
                        *r = x - *r;
                    }
                    measured = Some(reference);
                }
            }
            // The sum is calibrated every `CALIBRATION_STRIDE` steps, as
            // direct integration's (see there why not at every step).
            let added = match (&measured, calibrates) {
                (Some(m), true) => self
                    .global
                    .add_measured(estimated, relative(m, &step.x1), h),
                _ => self.global.add(estimated, h),
            };
            if let (Some(Some(growth)), true) = (self.growth.as_mut(), carried) {
                // The measured error with its sign, at most the estimate.
                let scale = |size: f64, bound: f64| {
                    if size > bound && size > 0.0 {
                        bound / size
                    } else {
                        1.0
                    }
                };
                let local: Vec<f64> = match measured {
                    Some(m) => {
                        let k = scale(relative(&m, &step.x1), estimated);
                        m.iter().map(|v| k * v).collect()
                    }
                    None => {
                        let k = if estimated > 0.0 {
                            added / estimated
                        } else {
                            0.0
                        };
                        local.iter().map(|v| k * v).collect()
                    }
                };
                growth.step(&system, (step.t0, &step.x0), step.t1, &local);
            }
        }
    }

    /// An event at `t`, the run going on from `x`: the steps before it
    /// are the motion's.
    pub fn cut(&mut self, model: &dyn DynModel, t: f64, x: &[f64]) {
        self.feed(model, t);
        if let Some(growth) = self.growth(model) {
            growth.cut(&ModelSystem(model), t, x);
        }
    }

    /// The right-side evaluations the estimate cost.
    pub fn evaluations(&self) -> usize {
        self.evaluations
            + self
                .growth
                .as_ref()
                .and_then(Option::as_ref)
                .map_or(0, Growth::evaluations)
    }

    /// For the summary: the steps added so far (and those waiting,
    /// summed).
    pub fn estimate(&self) -> GlobalErrorEstimate {
        let mut global = self.global.clone();
        for step in &self.unfed {
            match &step.local {
                Some(local) => {
                    global.add(relative(local, &step.x1), step.t1 - step.t0);
                }
                None => global.skip(),
            }
        }
        let carried = self
            .growth
            .as_ref()
            .and_then(Option::as_ref)
            .map_or(0.0, Growth::largest);
        GlobalErrorEstimate {
            largest: global.estimate().max(carried),
            rtol: self.rtol,
            complete: global.complete(),
        }
    }
}
