//! The field method proper, for reduced systems affine in the state: the
//! model's symbolic coefficient system integrated window by window, each
//! window anchored where the last one's conditions degraded.

use super::coefficients::{
    Augmented, FieldSystem, Iterate, LinearizationScratch, ProjectiveCoefficients,
    SymbolicCoefficients,
};
use super::global_error::FieldError;
use super::window::{StepperKind, Window, WindowStep};
use super::{FieldOptions, MAX_SHORTENINGS};
use crate::ensemble::States;
use crate::failure::Failure;
use crate::method::solver::{Keeping, Report, Solver};
use crate::model::DynModel;
use crate::ode::budget::Budget;
use crate::ode::dop853::{dense_step_between_measured_into, eval_between, one_step};
use crate::ode::system::ModelSystem;
use crate::ode::tolerance::Tolerance;
use crate::ode::tolerance::{rms_norm, underflows, Stats};
use std::cell::RefCell;

pub struct AffineField {
    method: &'static str,
    options: FieldOptions,
    h_max: f64,
    window: Window,
    /// Work of the closed windows.
    done: Stats,
    reanchorings: usize,
    largest_condition: f64,
    /// Ensemble members' states at the current window's anchor time.
    members: Option<States>,
    /// The linearisation's buffers, lent to the field system built at
    /// every step.
    scratch: RefCell<LinearizationScratch>,
    /// The output between the last step's ends, once asked for: one DOP853
    /// step of the motion between the two recovered states, or the
    /// coefficients' extension where that step is too long.
    between: Option<Between>,
    /// Storage of the output between steps, kept from sample to sample
    /// (four allocations a sample before): the motion step's extension
    /// (`dense_step_between_measured_into`), and the motion step and the
    /// difference at the step's middle, and the half step that judges
    /// the two there.
    motion: Vec<f64>,
    by_step: Vec<f64>,
    difference: Vec<f64>,
    half: Vec<f64>,
    /// The global error estimate carried along the run.
    error: FieldError,
    /// Storage of `advance`: the state before the step, and the step's
    /// local error.
    x_old: Vec<f64>,
    local: Vec<f64>,
}

/// [`AffineField`]'s output for the step `[t_old, t_new]`.
struct Between {
    t_old: f64,
    t_new: f64,
    /// Whether one DOP853 step of the motion between the step's recovered
    /// states (its extension in `AffineField::motion`) meets the tolerance
    /// at the step's end (`miss ≤ 1`).
    motion: bool,
    /// Whether the motion step is the output between the steps (else the
    /// coefficients' extension, with the motion step where the conditions
    /// fail).
    preferred: bool,
    /// Whether `motion` was computed (in RODAS4's and Magnus' steps only
    /// where the conditions fail).
    motion_tried: bool,
}

/// One DOP853 step of the motion between the window's last two recovered
/// states, its extension into `cont`: whether it meets the tolerance at
/// the step's end.
fn motion_step(
    model: &dyn DynModel,
    window: &Window,
    tol: Tolerance,
    cont: &mut Vec<f64>,
) -> Result<bool, Failure> {
    let (t_old, t_new) = (window.previous_time(), window.time());
    let miss = dense_step_between_measured_into(
        &ModelSystem(model),
        t_old,
        t_new - t_old,
        window.previous_state(),
        window.state(),
        Some(tol),
        cont,
    )?;
    Ok(miss <= 1.0)
}

impl AffineField {
    pub fn new(
        model: &dyn DynModel,
        options: FieldOptions,
        t0: f64,
        x0: &[f64],
        h_max: f64,
    ) -> Result<AffineField, Failure> {
        let kind = if options.magnus {
            StepperKind::Magnus
        } else if options.stiff {
            StepperKind::Stiff
        } else {
            StepperKind::Explicit
        };
        let magnus = options.magnus;
        let options_rtol = options.tol.rtol;
        let global_error = options.global_error;
        let scratch = LinearizationScratch::new(model.dim());
        let window = with_system(model, magnus, &scratch, |system| {
            Window::open(system, &options, t0, x0, None, h_max, kind)
        })?;
        Ok(AffineField {
            method: if model.coefficients_linear() {
                "field (linear coefficient system, DOP853)"
            } else {
                "field (Riccati coefficient system in projective form, DOP853)"
            },
            options,
            h_max,
            window,
            done: Stats::default(),
            reanchorings: 0,
            largest_condition: 1.0,
            members: None,
            scratch,
            between: None,
            motion: Vec::new(),
            by_step: Vec::new(),
            difference: Vec::new(),
            half: Vec::new(),
            error: FieldError::new(x0.len(), options_rtol).made_if(global_error),
            x_old: Vec::new(),
            local: Vec::new(),
        })
    }
}

impl Solver for AffineField {
    fn time(&self) -> f64 {
        self.window.time()
    }

    fn previous_time(&self) -> f64 {
        self.window.previous_time()
    }

    fn state(&self) -> &[f64] {
        self.window.state()
    }

    fn advance(
        &mut self,
        model: &dyn DynModel,
        t_limit: f64,
        budget: &Budget,
    ) -> Result<(), Failure> {
        self.error.feed(model, f64::INFINITY);
        // The state before, in storage kept from advance to advance.
        let mut x_old = std::mem::take(&mut self.x_old);
        x_old.clear();
        x_old.extend_from_slice(self.window.state());
        let t_old = self.window.time();
        let (window, options, h_max) = (&mut self.window, &self.options, self.h_max);
        let (mut done, mut reanchorings, mut largest) =
            (Stats::default(), 0, self.largest_condition);
        let members = &mut self.members;
        let result = with_system(model, options.magnus, &self.scratch, |system| {
            advance_window(
                system,
                window,
                options,
                h_max,
                t_limit,
                budget,
                &mut done,
                &mut reanchorings,
                &mut largest,
                members,
            )
        });
        self.done += done;
        self.reanchorings += reanchorings;
        self.largest_condition = largest;
        // The step's local error is read by the estimate alone.
        if result.is_ok() && self.error.is_on() {
            let local = &mut self.local;
            local.resize(x_old.len(), 0.0);
            let estimated = self.window.local_error(self.options.tol, local);
            self.error.step(
                model,
                (t_old, &x_old),
                (self.window.time(), self.window.state()),
                estimated.then_some(&local[..]),
            );
        }
        self.x_old = x_old;
        result.map_err(|f| super::explain(model, f, self.window.time(), self.window.state()))
    }

    fn dense(&mut self, model: &dyn DynModel, t: f64, out: &mut [f64]) -> Result<(), Failure> {
        let window = &mut self.window;
        let (t_old, t_new) = (window.previous_time(), window.time());
        let inside = t > t_old && t < t_new && window.steps() > 0;
        if !inside {
            return with_system(model, self.options.magnus, &self.scratch, |system| {
                window.dense(system, t, out)
            });
        }
        let current = self
            .between
            .as_ref()
            .is_some_and(|b| b.t_old == t_old && b.t_new == t_new);
        if !current {
            // One DOP853 step of the motion between the two recovered
            // states, as the quasilinear field does, where that step is
            // short enough for the motion (its own end within the
            // tolerance of the recovered one): as accurate between the
            // steps as direct DOP853's output, where the coefficients'
            // extension, recovered through the conditions, was not (a
            // raindrop, M ∝ t⁶, at rtol 1e-10: 1.7e-8 at 191 samples,
            // 1.3e-12 at the steps' ends). The field's steps follow its
            // coefficients and can be longer than the motion allows (the
            // paper's, over 100 s): there, and in RODAS4's and Magnus'
            // steps, the coefficients' extension.
            let explicit = window.kind() == StepperKind::Explicit;
            let motion = if explicit {
                motion_step(model, window, self.options.tol, &mut self.motion)?
            } else {
                false
            };
            // Which of the two is right between the steps: measured at
            // the step's middle against one DOP853 step of the motion of
            // half the length from the step's start (12 evaluations; its
            // own error about 1/512 of the whole step's miss), the motion
            // step where it is at least twice as near as the coefficients'
            // extension, else the coefficients' (the field's own output;
            // two extensions about as far off at the middle say nothing of
            // which is the better over the step: on the vertical rocket at
            // rtol 1e-10, 0.9 times as far, the motion step's samples were
            // 0.93 rtol off where the coefficients' were 0.59). Each can
            // be the worse: on the paper's 100 s the coefficients'
            // extension (6e-12 against 1.5e-10), on Cayley's raindrop the
            // motion step. The rule before, the coefficients' extension
            // wherever the two agreed to three tolerances, kept it on the
            // raindrop where it was 2 tolerances off and the motion step
            // exact (its motion is a quadratic in t): samples 1e5 times
            // direct's (docs/BENCHMARKS.md §10p). And the motion step
            // where the conditions fail at the middle.
            let mut preferred = false;
            if motion {
                let t_mid = 0.5 * (t_old + t_new);
                let by_step = &mut self.by_step;
                by_step.clear();
                by_step.resize(out.len(), 0.0);
                eval_between(&self.motion, t_old, t_new - t_old, t_mid, by_step);
                let extension = with_system(model, self.options.magnus, &self.scratch, |system| {
                    window.dense(system, t_mid, out)
                });
                let tol = self.options.tol;
                preferred = match extension {
                    Ok(()) => {
                        let difference = &mut self.difference;
                        difference.clear();
                        difference.extend(out.iter().zip(by_step.iter()).map(|(a, b)| a - b));
                        // The two within a tenth of a tolerance of each
                        // other: the coefficients' extension, at most that
                        // much worse, and no half step (with one at every
                        // output step the paper and the vertical rocket took
                        // +4–9 % instructions a solve at 101 samples, and
                        // event location, which reads this output, moved
                        // bouncing_ball's events).
                        if rms_norm(difference, out, by_step, tol) <= 0.1 {
                            false
                        } else {
                            let half = &mut self.half;
                            half.clear();
                            half.resize(out.len(), 0.0);
                            let stepped = one_step(
                                &ModelSystem(model),
                                t_old,
                                window.previous_state(),
                                t_mid - t_old,
                                half,
                            );
                            let mut off = |x: &[f64]| {
                                difference.clear();
                                difference.extend(x.iter().zip(half.iter()).map(|(a, b)| a - b));
                                rms_norm(difference, x, half, tol)
                            };
                            // A half step that fails or is not finite (into
                            // a singularity): the coefficients' extension.
                            stepped.is_ok() && 2.0 * off(by_step) < off(out)
                        }
                    }
                    Err(_) => true,
                };
            }
            self.between = Some(Between {
                t_old,
                t_new,
                motion,
                preferred,
                motion_tried: explicit,
            });
        }
        let between = self.between.as_mut().expect("made current above");
        let h = t_new - t_old;
        if between.preferred && between.motion {
            eval_between(&self.motion, t_old, h, t, out);
            return Ok(());
        }
        let extension = with_system(model, self.options.magnus, &self.scratch, |system| {
            window.dense(system, t, out)
        });
        // The conditions singular at `t` inside a step (a Riccati
        // coefficient's pole, crossed in projective form; an oscillator's
        // `x' = 0` there, where an output's `if x' > 0` was located): the
        // motion step, if it meets the tolerance. Before, the run stopped,
        // exit 3.
        if extension.is_err() && !between.motion_tried {
            between.motion = motion_step(model, window, self.options.tol, &mut self.motion)?;
            between.motion_tried = true;
        }
        match (extension, between.motion) {
            (Err(_), true) => {
                eval_between(&self.motion, t_old, h, t, out);
                Ok(())
            }
            (result, _) => result,
        }
    }

    fn cut(&mut self, model: &dyn DynModel, t: f64, x: &[f64]) {
        self.error.cut(model, t, x);
    }

    fn carry_error_through_event(
        &mut self,
        jump: &mut dyn FnMut(&mut [f64]) -> Result<(), Failure>,
    ) {
        // The event's saltation (`FieldError::jump`).
        self.error.jump(jump);
    }

    fn retake(&mut self, model: &dyn DynModel, t: f64, x: &[f64]) -> Result<(), Failure> {
        // The window from `t` is not the motion's (`FieldError::retake`).
        self.error.retake(t);
        self.restart(model, t, x)
    }

    fn restart(&mut self, model: &dyn DynModel, t: f64, x: &[f64]) -> Result<(), Failure> {
        // The steps before (all of them but after an event's cut).
        self.error.feed(model, f64::INFINITY);
        // A restart may follow a change of the model (an input's):
        // linearise afresh.
        self.scratch.borrow_mut().forget();
        let h = self.window.proposed_step();
        self.done += self.window.stats();
        self.between = None;
        let (options, h_max, kind) = (&self.options, self.h_max, self.window.kind());
        self.window = with_system(model, options.magnus, &self.scratch, |system| {
            Window::open(system, options, t, x, Some(h), h_max, kind)
        })?;
        Ok(())
    }

    fn segments(
        &mut self,
        model: &dyn DynModel,
    ) -> Result<Vec<crate::method::segment::Segment>, Failure> {
        let window = &mut self.window;
        with_system(model, self.options.magnus, &self.scratch, |system| {
            window.segment(system)
        })
        .map(|s| vec![s])
    }

    fn track_members(&mut self, members: States, _tol: crate::ode::tolerance::Tolerance) -> bool {
        self.members = Some(members);
        true
    }

    fn members_at(
        &mut self,
        model: &dyn DynModel,
        t: f64,
        out: &mut States,
    ) -> Result<(), Failure> {
        let (window, options) = (&mut self.window, &self.options);
        let empty = States::default();
        let anchors = self.members.as_ref().unwrap_or(&empty);
        with_system(model, options.magnus, &self.scratch, |system| {
            window.members_at(system, options, t, anchors, out)
        })
    }

    fn keep_on_constraints(&mut self, model: &dyn DynModel, keeping: &mut dyn Keeping) {
        // The carried error projected as the state is (`FieldError::keep`).
        self.error.keep(model, keeping);
    }

    fn report(&self) -> Report {
        Report {
            method: match self.window.kind() {
                StepperKind::Stiff => self.method.replace("DOP853", "RODAS4"),
                StepperKind::Magnus => self.method.replace("DOP853", "Magnus-4").replace(
                    "linear coefficient system",
                    "coefficient system in projective form",
                ),
                StepperKind::Explicit => self.method.to_string(),
            },
            stats: {
                let mut stats = self.done + self.window.stats();
                // The estimate's measures are the run's work too.
                stats.rhs_evaluations += self.error.evaluations();
                stats
            },
            largest_condition: Some(self.largest_condition),
            reanchorings: Some(self.reanchorings),
            global_error: self.error.report(),
            ..Report::default()
        }
    }
}

/// The affine parts `A(t)`, `b(t)` of an affine model do not depend on the
/// state: any iterate will do.
struct AnyState;

impl Iterate for AnyState {
    fn eval(&self, _t: f64, out: &mut [f64]) -> Result<(), Failure> {
        out.fill(0.0);
        Ok(())
    }

    fn is_origin(&self) -> bool {
        true
    }
}

/// Runs `body` on the field system of `model`: the symbolic coefficient
/// system when it is linear (it has no poles), its projective form when
/// it is of Riccati type or the Magnus integrator is asked for (which
/// needs the linear projective form).
fn with_system<R>(
    model: &dyn DynModel,
    magnus: bool,
    scratch: &RefCell<LinearizationScratch>,
    body: impl FnOnce(&dyn FieldSystem) -> R,
) -> R {
    if model.coefficients_linear() && !magnus {
        let source = SymbolicCoefficients::new(model);
        body(&Augmented(&source))
    } else {
        // Every system of this field is built from the same model at the
        // origin: an autonomous model's linearisation is kept from step to
        // step (`restart` forgets it).
        let projective = ProjectiveCoefficients::with_kept_scratch(model, &AnyState, scratch);
        body(&projective)
    }
}

#[allow(clippy::too_many_arguments)]
fn advance_window(
    system: &dyn FieldSystem,
    window: &mut Window,
    options: &FieldOptions,
    h_max: f64,
    t_limit: f64,
    budget: &Budget,
    done: &mut Stats,
    reanchorings: &mut usize,
    largest_condition: &mut f64,
    members: &mut Option<States>,
) -> Result<(), Failure> {
    let mut shortenings = 0;
    loop {
        match window.step(system, options, t_limit, budget)? {
            WindowStep::Accepted => {
                *largest_condition = largest_condition.max(window.recovered().condition);
                return Ok(());
            }
            WindowStep::Ended if window.steps() == 0 => {
                // Already degraded one step after a fresh anchor: shorten
                // that step.
                shortenings += 1;
                let h = 0.25 * window.proposed_step();
                let t = window.time();
                if shortenings > MAX_SHORTENINGS || underflows(t, h) {
                    return Err(window.degraded());
                }
                window.propose_step(h);
            }
            WindowStep::Ended => {
                let (t, x) = (window.time(), window.state().to_vec());
                let h = window.proposed_step();
                // DOP853 found the coefficients stiff: continue with RODAS4.
                let kind = if options.auto_stiff && window.stiffness_detected() {
                    StepperKind::Stiff
                } else {
                    window.kind()
                };
                if let Some(anchors) = members.as_mut() {
                    let mut ends = States::default();
                    window.members(system, options, anchors, &mut ends)?;
                    *anchors = ends;
                }
                *done += window.stats();
                window.reopen(system, options, t, &x, Some(h), h_max, kind)?;
                *reanchorings += 1;
            }
        }
    }
}
