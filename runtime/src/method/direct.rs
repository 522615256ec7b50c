//! Direct integration of the reduced system (7) with the user's choice of
//! integrator: `Auto` starts with DOP853 and continues with RODAS4 from the
//! step where Hairer's stiffness test fires; `Explicit` keeps DOP853 and
//! only reports the detection; `Stiff` is RODAS4 throughout.

use crate::choice::IntegratorChoice;
use crate::failure::Failure;
use crate::method::solver::{GlobalErrorEstimate, Keeping, Report, Solver};
use crate::model::DynModel;
use crate::ode::budget::Budget;
use crate::ode::dop853::global_error::growth::{past, Accepted, Growth, Keep, FROM_DIRECT};
use crate::ode::dop853::global_error::{relative, GlobalError, Swings, BOUND};
use crate::ode::dop853::Dop853;
use crate::ode::stepper::{Clocked, OfModel, StepperOf};
use crate::ode::system::ModelSystem;
use crate::ode::tolerance::{Stats, Tolerance};
use crate::ode::Integrator;

pub struct Direct {
    choice: IntegratorChoice,
    tol: Tolerance,
    h_max: f64,
    /// The integrator running now, and its stepper: one dynamic call per
    /// step; inside a step the right side is called statically
    /// (`Stepper`'s comment).
    integrator: Integrator,
    stepper: StepperOf<OfModel>,
    /// Work of the integrators before the current one.
    done: Stats,
    first: Integrator,
    stiffness_detected_at: Option<f64>,
    switched_at: Option<f64>,
    /// DOP853's last step length before the switch, to judge whether
    /// RODAS4 pays (see [`Direct::advance`]).
    explicit_step: f64,
    stiff_steps: usize,
    stiff_distance: f64,
    /// Switched back to DOP853: RODAS4 was not cheaper.
    switched_back_at: Option<f64>,
    /// The global error estimate carried along, and the last step's
    /// local error.
    global: GlobalError,
    /// The estimate before the last step was added ([`Solver::retake`]
    /// drops that step's error).
    global_before_step: GlobalError,
    /// The components' swings, for the estimate's reading where they pass
    /// zero (`global_error::Swings`).
    swings: Swings,
    step_error: StepError,
    /// The steps' errors carried along the motion (`global_error::growth`).
    growth: Growth,
    /// The run keeps constraints: a step's local error waits for
    /// [`Solver::keep_on_constraints`] to remove its part off the
    /// holonomic ones, and the carried error to be projected.
    keeps: bool,
    /// The last probe's ratio of the part of a step's error that the
    /// holonomic constraints keep to the whole, and the steps since.
    kept_ratio: Option<(f64, usize)>,
    /// Whether the global error is estimated (`Options::global_error`).
    estimates: bool,
    /// The longest DOP853 step whose error was probed against Hairer's
    /// estimate ([`blind`]).
    longest_probed: f64,
}

/// A probe's measure this many times Hairer's estimate, and at least
/// [`BLIND_FROM`]`·rtol`, finds the estimate blind ([`blind`]). The
/// calibration takes a measure above the estimate for rounding or a kink
/// and caps it there (`GlobalError::add_measured`); the circling coin's
/// blind steps measured 15× and 180× their estimates.
const BLIND_RATIO: f64 = 10.0;

/// The smallest probed error, in rtol, that finds the estimate blind: a
/// smaller one cannot take the run past the bound, and near rounding a
/// Richardson difference measures nothing.
const BLIND_FROM: f64 = 0.1;

/// Steps between two probes of the part of the error that the holonomic
/// constraints keep ([`Solver::keep_on_constraints`]).
const KEPT_STRIDE: usize = 8;

/// One accepted DOP853 step's local error: Hairer's estimate and, when
/// taken, the Richardson measure, with the state they are relative to.
#[derive(Clone, Default)]
struct StepError {
    estimated: Vec<f64>,
    measured: Option<Vec<f64>>,
    /// The measure calibrates the sum (`GlobalError::wants_measure`);
    /// otherwise it was taken for the carried error alone.
    calibrates: bool,
    x: Vec<f64>,
    h: f64,
    /// The step's start, and its end's time.
    t0: f64,
    x0: Vec<f64>,
    t1: f64,
    /// Not yet added to the global estimate.
    waiting: bool,
    /// A step into a poor pivot was taken again ([`Solver::retake`]):
    /// from there every step's error is measured and carried, and not
    /// capped at Hairer's estimate (see `retake`).
    past_poor_pivot: bool,
    /// A probe found Hairer's estimate blind ([`blind`]):
    /// from there every step's error is measured and carried, uncapped,
    /// as past a poor pivot.
    blind: bool,
    /// The model keeps holonomic constraints or has impacts: every step's
    /// error is measured and carried from the first step
    /// ([`carried_from_first_step`]).
    from_first_step: bool,
}

impl StepError {
    /// Whether the errors are carried before the calibrated sum says so.
    fn carried_early(&self) -> bool {
        self.past_poor_pivot || self.blind || self.from_first_step
    }

    fn scale(&mut self, ratio: f64) {
        self.estimated.iter_mut().for_each(|v| *v *= ratio);
        if let Some(measured) = self.measured.as_mut() {
            measured.iter_mut().for_each(|v| *v *= ratio);
        }
    }

    /// Adds the step's error to the sum, and, once the sum is past the
    /// bound, to the error carried along the motion where there is one
    /// (with the model, to propagate it).
    fn add_to(
        &mut self,
        (global, swings): (&mut GlobalError, &mut Swings),
        rtol: f64,
        growth: Option<(&mut Growth, &dyn DynModel)>,
        keep: Option<&mut Keep<'_>>,
    ) {
        if !std::mem::take(&mut self.waiting) {
            return;
        }
        let propagate = growth
            .as_ref()
            .is_some_and(|(g, _)| carries(global, rtol, g, self.carried_early()));
        let (estimated, added) = self.sum_into(global, swings, self.from_first_step);
        // Past the bound every step's error is measured (see
        // `carry_global_error`) and carried along the motion with its
        // sign, at most Hairer's estimate (the calibration's bound) but
        // in a run past a poor pivot, where that estimate is blind.
        if let (Some((growth, model)), true) = (growth, propagate) {
            let (local, size) = match &self.measured {
                Some(measured) => (measured, relative(measured, &self.x)),
                None => (&self.estimated, estimated),
            };
            let bound = if (self.past_poor_pivot || self.blind) && self.measured.is_some() {
                f64::INFINITY
            } else {
                estimated
            };
            let scale = if size > bound && size > 0.0 {
                bound / size
            } else if self.measured.is_some() {
                1.0
            } else {
                // No measure (a stage not finite): the estimate as the
                // sum counted it.
                if estimated > 0.0 {
                    added / estimated
                } else {
                    0.0
                }
            };
            let local: Vec<f64> = local.iter().map(|v| scale * v).collect();
            // The step DOP853 took from `x0` (the stepper's previous
            // state, a projected one in a run that keeps constraints) to
            // `x`, of length `h`.
            let accepted = Accepted {
                h: self.h,
                end: &self.x,
            };
            growth.step_kept(
                &ModelSystem(model),
                (self.t0, &self.x0),
                self.t1,
                &local,
                keep,
                Some(accepted),
            );
        }
    }
}

impl StepError {
    /// The step's error added to the sum `global` (what
    /// [`StepError::add_to`] does to it): its relative estimate, and what
    /// was added.
    /// In a run `carried` along the motion from its first step the swing's
    /// sum is not kept: the carried error, read over its step, holds every
    /// step's error with its sign (on the bead on a helix the swing's sum of
    /// errors the projections remove read 100 rtol for an error of 0.004).
    /// A run that starts carrying later keeps it whole: the errors before
    /// the carrying are in the sums only (the ball in a cylinder at rtol
    /// 1e-6 read "within" 25 rtol off with the carried steps left out).
    fn sum_into(&self, global: &mut GlobalError, swings: &mut Swings, carried: bool) -> (f64, f64) {
        let estimated = relative(&self.estimated, &self.x);
        // The sum is calibrated as before: a measure every
        // `CALIBRATION_STRIDE` steps scales the estimates between (one at
        // every step would add, at tight tolerances, the rounding the
        // differences measure: rocket_near_burnout at rtol 1e-12, 2.1e-12
        // → 1.7e-11).
        let added = match (&self.measured, self.calibrates) {
            (Some(measured), true) => {
                global.add_measured(estimated, relative(measured, &self.x), self.h)
            }
            _ => global.add(estimated, self.h),
        };
        let swung = if carried { 0.0 } else { added };
        global.swing(
            swings,
            &self.estimated,
            (&self.x0, &self.x),
            estimated,
            swung,
        );
        (estimated, added)
    }
}

/// The integrator a run starts with.
fn first_integrator(choice: IntegratorChoice) -> Integrator {
    match choice {
        IntegratorChoice::Stiff => Integrator::Stiff,
        _ => Integrator::Explicit,
    }
}

/// Whether a step's error is measured and carried along the motion: from
/// where the calibrated sum passes [`FROM_DIRECT`]`·rtol` on, or (`early`)
/// from the first step into a poor pivot taken again (`past_poor_pivot`,
/// [`Solver::retake`]) or from the first step of a model that keeps
/// holonomic constraints or has impacts ([`carried_from_first_step`]);
/// once started, every step is, until the carried
/// error passes the state's own size ([`Growth::saturated`]: nothing more
/// is learned there).
///
/// Why holonomic constraints from the first step: the projection onto
/// them moves an error between components of different sizes, which the
/// sum of relative local errors does not see. A bead sliding down a
/// helix `x = R cos(z/p), y = R sin(z/p)` (R = 0.5, p = 0.2, 5 s): the
/// height z is integrated exactly (z'' is constant) but the projection
/// hands it part of x's and y's truncation errors, a phase error
/// 1e-12 of z's size that the rotation turns into errors of the
/// velocities x', y' 500× larger relative to theirs near a zero: at rtol
/// 1e-9 … 1e-11 it ended 11–30 rtol off saying "within", the sum 10–20×
/// low; carried from the first step, 1.2–4× its error, warned
/// (docs/BENCHMARKS.md §10u).
fn carries(global: &GlobalError, rtol: f64, growth: &Growth, early: bool) -> bool {
    (growth.started() || early || past(global, rtol, FROM_DIRECT)) && !growth.saturated()
}

/// Whether a model's errors are carried from the first step: where its
/// holonomic constraints' projection, or its impacts' resets, move an
/// error between components of different sizes ([`carries`]). An impact
/// turns a height error into a time error and that into a velocity
/// error, 1/v larger as the bounces shrink (`run::saltation`): a ball
/// with quadratic drag bouncing 120 times (e = 0.8) ended 34 rtol off at
/// rtol 1e-8 and 27 at 1e-9 saying "within" (6.5, 5.3): carried from the
/// first step and through each bounce, 1.2× and 0.76× its error, warned;
/// carried from the first step without the bounces' saltation, still
/// "within".
fn carried_from_first_step(model: &dyn DynModel) -> bool {
    model.keeps_positions() || !model.impacts().is_empty()
}

/// Whether a probed step's measure finds Hairer's estimate blind: the
/// Richardson measure [`BLIND_RATIO`] times the estimate and at least
/// [`BLIND_FROM`]`·rtol` (a probe is a step longer than any probed before,
/// `Direct::carry_global_error`).
///
/// Why: Hairer's estimate scales every component's `ε₅` by one factor
/// from the norms of `ε₅` and `ε₃` over the whole state, so a mode the
/// step does not resolve, at rest while the rest of the motion is smooth,
/// hides under the smooth components while the step amplifies it. A coin
/// circling steadily (lean 0.3, precession 3, spin −34.5, read linear in
/// `tests/data/textbook_rolling/`, raised in `tests/data/raised_estimates/`)
/// has a wobble near 48 rad/s that the steady motion leaves at rest: its
/// steps grew to 0.15–0.16 s (`hω` ≈ 7, past DOP853's stability edge near
/// 6 on the imaginary axis, `|R|` ≈ 7.5), and two steps took the lean
/// rate from 3e-11 to 1.6e-9 and 3.3e-8 (33 rtol at rtol 1e-9, atol
/// 1e-11) where Hairer's estimates of it were 2.9e-12 and 1.8e-11; their
/// Richardson measures, 1.5e-9 and 3.2e-8, are 15× and 180× the
/// estimates in the relative norm. The summary said "within" (5.2e-10).
/// Found blind at the first, every step on is measured and carried as
/// past a poor pivot: 6.5e-8 carried, warned (docs/BENCHMARKS.md §10z4).
fn blind(e: &StepError, rtol: f64) -> bool {
    let Some(measured) = &e.measured else {
        return false;
    };
    let measured = relative(measured, &e.x);
    let estimated = relative(&e.estimated, &e.x);
    measured >= BLIND_FROM * rtol && measured > BLIND_RATIO * estimated
}

impl Direct {
    pub fn new(
        model: &dyn DynModel,
        choice: IntegratorChoice,
        tol: Tolerance,
        t0: f64,
        x0: &[f64],
        h_max: f64,
    ) -> Result<Direct, Failure> {
        let first = first_integrator(choice);
        let stepper = first.start::<OfModel>(&ModelSystem(model), t0, x0, tol, h_max, None)?;
        // Every field set here is set again by `renew`.
        Ok(Direct {
            choice,
            tol,
            h_max,
            integrator: first,
            stepper,
            done: Stats::default(),
            first,
            stiffness_detected_at: None,
            switched_at: None,
            explicit_step: 0.0,
            stiff_steps: 0,
            stiff_distance: 0.0,
            switched_back_at: None,
            global: GlobalError::new(),
            global_before_step: GlobalError::new(),
            swings: Swings::default(),
            step_error: StepError {
                estimated: vec![0.0; x0.len()],
                from_first_step: carried_from_first_step(model),
                ..StepError::default()
            },
            // The reduced system of a constrained model drifts off its
            // constraints, and its flow's derivative carries that drift
            // (a propagated error grew without bound on the knife edge and
            // the particle on a circle, `global_error`'s comment): in a run
            // that keeps them, the carried error is projected as the state
            // is (`keep_on_constraints`).
            growth: Growth::new(x0.len()),
            keeps: model.keeps_positions() || model.keeps_constraints(),
            kept_ratio: None,
            estimates: true,
            longest_probed: 0.0,
        })
    }

    /// Makes this solver, an earlier solve's, the one [`Direct::new`]
    /// makes from these arguments, in its own storage: DOP853 restarted
    /// in its buffers ([`Dop853::restart_at`], the stepper `new` makes bit
    /// for bit; another integrator is made anew), the carried error's and
    /// the step error's vectors reused, every other field set as `new`
    /// sets it. A short solve (the paper's 6 steps at rtol 1e-3) spent
    /// about a tenth of its instructions allocating and freeing these
    /// (docs/BENCHMARKS.md §10i). On failure the solver is left unusable
    /// (as `new` makes none).
    pub fn renew(
        &mut self,
        model: &dyn DynModel,
        choice: IntegratorChoice,
        tol: Tolerance,
        t0: f64,
        x0: &[f64],
        h_max: f64,
    ) -> Result<(), Failure> {
        let first = first_integrator(choice);
        let n = x0.len();
        let system = ModelSystem(model);
        let in_place = first == Integrator::Explicit && self.stepper.state().len() == n;
        match self.stepper.as_any_mut().downcast_mut::<Dop853>() {
            Some(dop) if in_place => dop.restart_at(&system, t0, x0, tol, h_max, None)?,
            _ => self.stepper = first.start::<OfModel>(&system, t0, x0, tol, h_max, None)?,
        }
        // Every field named: one added to `Direct` must be renewed too.
        let Direct {
            choice: choice_now,
            tol: tol_now,
            h_max: h_max_now,
            integrator,
            stepper: _,
            done,
            first: first_now,
            stiffness_detected_at,
            switched_at,
            explicit_step,
            stiff_steps,
            stiff_distance,
            switched_back_at,
            global,
            global_before_step,
            swings,
            step_error,
            growth,
            keeps,
            kept_ratio,
            estimates,
            longest_probed,
        } = self;
        *choice_now = choice;
        *tol_now = tol;
        *h_max_now = h_max;
        *integrator = first;
        *done = Stats::default();
        *first_now = first;
        *stiffness_detected_at = None;
        *switched_at = None;
        *explicit_step = 0.0;
        *stiff_steps = 0;
        *stiff_distance = 0.0;
        *switched_back_at = None;
        *global = GlobalError::new();
        *global_before_step = GlobalError::new();
        swings.clear();
        let mut estimated = std::mem::take(&mut step_error.estimated);
        estimated.clear();
        estimated.resize(n, 0.0);
        *step_error = StepError {
            estimated,
            from_first_step: carried_from_first_step(model),
            ..StepError::default()
        };
        growth.renew(n);
        *keeps = model.keeps_positions() || model.keeps_constraints();
        *kept_ratio = None;
        *estimates = true;
        *longest_probed = 0.0;
        Ok(())
    }

    /// A run whose global error is not estimated: no measures, no
    /// carried error (`Options::global_error`).
    pub fn without_global_error(mut self) -> Direct {
        self.drop_global_error();
        self
    }

    /// [`Direct::without_global_error`] in place.
    pub fn drop_global_error(&mut self) {
        self.estimates = false;
    }

    /// The integrator finishing the run.
    pub fn integrator(&self) -> Integrator {
        self.integrator
    }

    fn method_name(&self) -> String {
        if self.switched_back_at.is_some() {
            return "direct (DOP853 → RODAS4 → DOP853)".to_string();
        }
        match self.switched_at {
            Some(_) => format!(
                "direct ({} → {})",
                self.first.name(),
                self.integrator.name()
            ),
            // concat, not format!: every solve's report asks.
            None => ["direct (", self.integrator.name(), ")"].concat(),
        }
    }
}

impl Solver for Direct {
    fn time(&self) -> f64 {
        self.stepper.time()
    }

    fn previous_time(&self) -> f64 {
        self.stepper.previous_time()
    }

    fn state(&self) -> &[f64] {
        self.stepper.state()
    }

    fn advance(
        &mut self,
        model: &dyn DynModel,
        t_limit: f64,
        budget: &Budget,
    ) -> Result<(), Failure> {
        // A switch decided after the last step happens now: the driver has
        // used that step's (DOP853) dense output by the time it asks for
        // the next step.
        self.switch_if_stiff(model)?;
        self.switch_back_if_decided(model)?;
        let system = ModelSystem(model);
        let before = self.stepper.time();
        self.stepper.step(&system, t_limit, budget)?;
        self.carry_global_error(model);
        if self.switched_at.is_some() && self.switched_back_at.is_none() {
            self.judge_the_switch(before);
        }
        if self.stiffness_detected_at.is_none() {
            self.stiffness_detected_at = self.stepper.stiffness_detected();
            let switches = matches!(
                self.choice,
                IntegratorChoice::Auto | IntegratorChoice::Magnus
            );
            if self.stiffness_detected_at.is_some() && switches {
                // The switch happens after this step: its dense output was
                // made by DOP853 and stays valid until the next step.
                self.switched_at = Some(self.stepper.time());
            }
        }
        Ok(())
    }

    fn dense(&mut self, model: &dyn DynModel, t: f64, out: &mut [f64]) -> Result<(), Failure> {
        // DOP853's extension judged before it is read (`dop853::inside`:
        // a settling motion's stability-held steps); RODAS4's as it is.
        match self.stepper.as_any_mut().downcast_mut::<Dop853>() {
            Some(dop) => dop.dense_judged(&ModelSystem(model), t, out),
            None => self.stepper.dense(&ModelSystem(model), t, out),
        }
    }

    fn into_reusable(self: Box<Self>) -> Option<Box<dyn std::any::Any>> {
        Some(self)
    }

    fn restart(&mut self, model: &dyn DynModel, t: f64, x: &[f64]) -> Result<(), Failure> {
        self.restart_at(model, t, x)?;
        // A restart without an event's cut may follow a change of the
        // model's regime (a pivot switch): the last step's derivative is
        // not differenced against the step it took in the old one.
        self.growth.forget_accepted();
        self.kept_ratio = None;
        Ok(())
    }

    fn retakes_steps_into_poor_pivots(&self) -> bool {
        true
    }

    fn retake(&mut self, model: &dyn DynModel, t: f64, x: &[f64]) -> Result<(), Failure> {
        // The step just taken is not the motion: its error is not the
        // run's (counted, the knife edge circling nine times, a step
        // across a poor pivot at each quarter turn, was estimated at 36
        // rtol for an error of 4.5 and carried at twice the cost).
        if self.estimates {
            self.global = self.global_before_step.clone();
            self.step_error.waiting = false;
            self.growth.discard_pending();
            // From here every step's error is measured and carried along
            // the motion, and a measure above Hairer's estimate is kept:
            // near a poor pivot the rate divides by it and the embedded
            // estimate is blind. Chaplygin's sleigh at rtol 1e-11 ended
            // 11 rtol off saying "within" (0.32): its sum's one
            // calibration measure came at t = 15.8, on a straight run,
            // and scaled the spinning phase's errors 30-fold down; those
            // errors, measured, sum to 2.6 rtol (five steps around a
            // retaken one measured 1.2–12× Hairer's estimate, up to 1
            // rtol), and the motion amplifies them about 4-fold as the
            // spin decays into a straight run. Carried from its first
            // step taken again (t = 0.3): 11.0 rtol, its error at the
            // samples 11.0 (docs/BENCHMARKS.md §10s).
            self.step_error.past_poor_pivot = true;
        }
        self.restart(model, t, x)
    }

    fn project(&mut self, model: &dyn DynModel, t: f64, x: &[f64]) -> Result<(), Failure> {
        // A projection moves the state, not the model nor the directions
        // of the errors.
        self.restart_at(model, t, x)
    }

    fn cut(&mut self, model: &dyn DynModel, t: f64, x: &[f64]) {
        self.step_error.add_to(
            (&mut self.global, &mut self.swings),
            self.tol.rtol,
            Some((&mut self.growth, model)),
            None,
        );
        self.growth.cut(&ModelSystem(model), t, x);
    }

    fn carry_error_through_event(
        &mut self,
        jump: &mut dyn FnMut(&mut [f64]) -> Result<(), Failure>,
    ) {
        if self.estimates {
            self.growth.jump(jump);
        }
    }

    fn segments(
        &mut self,
        model: &dyn DynModel,
    ) -> Result<Vec<crate::method::segment::Segment>, Failure> {
        let dense = self.stepper.dense_step(&ModelSystem(model))?;
        Ok(dense
            .into_iter()
            .map(crate::method::segment::Segment::State)
            .collect())
    }

    fn keep_on_constraints(&mut self, model: &dyn DynModel, keeping: &mut dyn Keeping) {
        if !self.estimates {
            return;
        }
        let e = &mut self.step_error;
        // While the sum with this step's whole error stays within the
        // bound, the run is within without the projection. Past it, the
        // part kept is probed every [`KEPT_STRIDE`] steps (two
        // projections cost about a step: one at every step made the
        // Cartesian pendulum's run 1.9× the instructions) and its ratio
        // to the whole scales the steps between; a restart (an event, a
        // change of pivot) probes afresh.
        let within = self.global.estimate() + relative(&e.estimated, &e.x) <= BOUND * self.tol.rtol;
        if e.waiting && !within {
            match &mut self.kept_ratio {
                Some((ratio, since)) if *since < KEPT_STRIDE => {
                    *since += 1;
                    e.scale(*ratio);
                }
                _ => {
                    // A projection that fails leaves the error as
                    // estimated: the estimate never fails the run (the
                    // keeper's own projection after the step reports a
                    // state it cannot keep).
                    let whole = relative(&e.estimated, &e.x);
                    let probed = keeping.kept_part(&e.x, &mut e.estimated).is_ok() && whole > 0.0;
                    let ratio = relative(&e.estimated, &e.x) / whole;
                    if let Some(measured) = e.measured.as_mut() {
                        let _ = keeping.kept_part(&e.x, measured);
                    }
                    self.kept_ratio = (probed && ratio.is_finite()).then_some((ratio, 1));
                }
            }
        }
        // The error carried so far, once propagated to this step's start,
        // is projected as the state was.
        let mut keep = |t: f64, x: &[f64], d: &mut [f64]| keeping.tangent(t, x, d);
        e.add_to(
            (&mut self.global, &mut self.swings),
            self.tol.rtol,
            Some((&mut self.growth, model)),
            Some(&mut keep),
        );
    }

    fn report(&self) -> Report {
        let mut global = self.global.clone();
        // The last step's error, should no projection have come for it
        // (what `add_to` without a carried error does to the sum, without
        // the copy of the step error's four vectors that every solve's
        // report made).
        if self.step_error.waiting {
            self.step_error.sum_into(
                &mut global,
                &mut self.swings.clone(),
                self.step_error.from_first_step,
            );
        }
        let carried = self.growth.largest();
        let mut notes = Vec::new();
        if let Some(t) = self.switched_back_at {
            notes.push(format!(
                "back to DOP853 at t = {t:e}: RODAS4's steps were not long enough to pay \
                 for its cost"
            ));
        }
        match (self.switched_at, self.stiffness_detected_at) {
            (Some(t), _) => notes.push(format!(
                "switched to RODAS4 at t = {t:e} (DOP853 detected stiffness)"
            )),
            (None, Some(t)) => notes.push(format!(
                "the motion looks stiff from t = {t:e} on; RODAS4 may be faster \
                 (--integrator stiff or auto)"
            )),
            (None, None) => {}
        }
        let mut stats = self.done + self.stepper.stats();
        // The propagation's work is the run's too.
        stats.rhs_evaluations += self.growth.evaluations();
        Report {
            method: self.method_name(),
            stats,
            notes,
            global_error: self.estimates.then_some(GlobalErrorEstimate {
                largest: global.read().max(carried),
                rtol: self.tol.rtol,
                complete: global.complete(),
            }),
            ..Report::default()
        }
    }
}

impl Direct {
    /// Goes on from `(t, x)` with a fresh stepper of the same integrator,
    /// the step just taken added to the estimate.
    fn restart_at(&mut self, model: &dyn DynModel, t: f64, x: &[f64]) -> Result<(), Failure> {
        self.step_error.add_to(
            (&mut self.global, &mut self.swings),
            self.tol.rtol,
            Some((&mut self.growth, model)),
            None,
        );
        let h = self.stepper.proposed_step();
        let integrator = self.integrator;
        self.done += self.stepper.stats();
        let system = ModelSystem(model);
        // DOP853 restarts in its own buffers (the same stepper as a new
        // one; a projection after a step restarts it).
        match self.stepper.as_any_mut().downcast_mut::<Dop853>() {
            Some(dop) if integrator == Integrator::Explicit => {
                dop.restart_at(&system, t, x, self.tol, self.h_max, Some(h))?;
            }
            _ => {
                self.stepper =
                    integrator.start::<OfModel>(&system, t, x, self.tol, self.h_max, Some(h))?;
            }
        }
        Ok(())
    }

    /// Adds the step just taken to the global error estimate (see
    /// `dop853::global_error`): DOP853's local error estimate, scaled by
    /// the ratio a Richardson measure of the local error gives where the
    /// sum grows past `rtol`. RODAS4's steps are not accounted for (the
    /// estimate then says it is partial). In a run that keeps
    /// constraints the step's error waits for the part of it the
    /// constraints keep ([`Solver::keep_on_constraints`]).
    fn carry_global_error(&mut self, model: &dyn DynModel) {
        if !self.estimates {
            return;
        }
        let (global, e, swings) = (&mut self.global, &mut self.step_error, &mut self.swings);
        let rtol = self.tol.rtol;
        e.add_to(
            (global, swings),
            rtol,
            Some((&mut self.growth, model)),
            None,
        );
        self.global_before_step = global.clone();
        let Some(dop) = self.stepper.as_any_mut().downcast_mut::<Dop853>() else {
            global.skip();
            return;
        };
        let carried = carries(global, rtol, &self.growth, e.carried_early());
        e.calibrates = global.wants_measure(rtol);
        let (_, _, h) = dop.clock().last_step();
        // A step longer than any probed: its error measured against
        // Hairer's estimate ([`blind`]), unless it is measured and carried
        // already. Only 1.1× longer ones probed, the coin read linear at
        // rtol 1e-9, atol 9.5e-12 stayed 14 rtol off saying "within" (0.33)
        // for about the same evaluations over the constrained examples
        // (docs/BENCHMARKS.md §10z4).
        let probes = !carried && h.abs() > self.longest_probed;
        if probes {
            self.longest_probed = h.abs();
        }
        if !(carried || e.calibrates || probes) {
            // A step whose error is only summed (most steps of most
            // runs): its relative size, as `add_to` would take it, without
            // the vectors (about 200 instructions a step of bookkeeping
            // before, BENCHMARKS §10a). In a run that keeps constraints,
            // only where the sum with the whole of it stays within the
            // bound: there `keep_on_constraints` takes no part of it off
            // (its `within`), and adds it as it is.
            let estimated = dop.local_error_relative();
            if !self.keeps || global.estimate() + estimated <= BOUND * rtol {
                let added = global.add(estimated, h);
                dop.local_error(&mut e.estimated);
                let ends = (dop.previous_state(), dop.current_state());
                global.swing(swings, &e.estimated, ends, estimated, added);
                return;
            }
        }
        dop.local_error(&mut e.estimated);
        e.x.clear();
        e.x.extend_from_slice(dop.current_state());
        (e.t0, e.t1, e.h) = dop.clock().last_step();
        let mut measured = e.measured.take().unwrap_or_default();
        // Past the bound, where the errors are carried along the motion,
        // every step's: the sign and direction of a step's error decide
        // whether it adds to the carried error or cancels it (Hairer's
        // estimate is the difference to a lower-order solution, whose
        // sign is not the error's: added with its own sign it made the
        // soft walls' estimate 1000× their error at rtol 1e-12).
        // The step's start: where its error is carried along the motion,
        // and for the swing's reading of the sum (`GlobalError::swing`,
        // which needs both ends of every step).
        e.x0.clear();
        e.x0.extend_from_slice(dop.previous_state());
        if carried || e.calibrates || probes {
            // A measure that fails (a stage not finite) leaves the estimate
            // unscaled: it never fails the run.
            measured.resize(e.x.len(), 0.0);
            if let Ok(true) = dop.local_error_by_halves(&ModelSystem(model), &mut measured) {
                e.measured = Some(measured);
            }
        }
        if probes {
            e.blind |= blind(e, rtol);
        }
        e.waiting = true;
        if !self.keeps {
            e.add_to(
                (global, swings),
                rtol,
                Some((&mut self.growth, model)),
                None,
            );
        }
    }

    /// After switching to RODAS4 on detected stiffness, whether it pays: a
    /// RODAS4 step costs about as much as a DOP853 step (six evaluations,
    /// a Jacobian and an LU against twelve evaluations), so unless its
    /// steps are clearly longer than DOP853's stability-limited ones, go
    /// back (the mass-loss spring at loose tolerances: stiff by Hairer's
    /// test, yet RODAS4 took ten times the work).
    ///
    /// The switch back is decided here and made at the next step
    /// ([`Direct::switch_back_if_decided`]), as the switch to RODAS4 is:
    /// the driver reads the dense output of the step just taken after this
    /// returns, and a fresh DOP853 has none. Made at once, every sample
    /// inside that RODAS4 step came from the new stepper (the stiff
    /// accretion example at rtol 1e-11: 3.1e-3 off at its samples, exit 0,
    /// where its steps were right to 1e-13).
    fn judge_the_switch(&mut self, before: f64) {
        const TRIAL_STEPS: usize = 20;
        const REQUIRED_GAIN: f64 = 2.0;
        if self.integrator != Integrator::Stiff {
            return;
        }
        self.stiff_steps += 1;
        self.stiff_distance += self.stepper.time() - before;
        if self.stiff_steps == TRIAL_STEPS {
            let mean = self.stiff_distance / TRIAL_STEPS as f64;
            if mean < REQUIRED_GAIN * self.explicit_step {
                self.switched_back_at = Some(self.stepper.time());
            }
        }
    }

    /// Performs a decided switch back to DOP853.
    fn switch_back_if_decided(&mut self, model: &dyn DynModel) -> Result<(), Failure> {
        if self.switched_back_at.is_some() && self.integrator == Integrator::Stiff {
            self.restart_with(model, Integrator::Explicit, self.explicit_step)?;
        }
        Ok(())
    }

    /// Performs a pending switch to RODAS4.
    fn switch_if_stiff(&mut self, model: &dyn DynModel) -> Result<(), Failure> {
        if self.switched_at.is_some()
            && self.switched_back_at.is_none()
            && self.integrator == Integrator::Explicit
            && self.stiff_steps == 0
        {
            self.explicit_step = self.stepper.time() - self.stepper.previous_time();
            let h = self.stepper.proposed_step();
            self.restart_with(model, Integrator::Stiff, h)?;
        }
        Ok(())
    }

    /// Continues from the current state with `integrator`, first step `h`;
    /// the finished stepper's statistics are kept.
    fn restart_with(
        &mut self,
        model: &dyn DynModel,
        integrator: Integrator,
        h: f64,
    ) -> Result<(), Failure> {
        let (t, x) = (self.stepper.time(), self.stepper.state().to_vec());
        self.done += self.stepper.stats();
        self.stepper = integrator.start::<OfModel>(
            &ModelSystem(model),
            t,
            &x,
            self.tol,
            self.h_max,
            Some(h),
        )?;
        self.integrator = integrator;
        Ok(())
    }
}
