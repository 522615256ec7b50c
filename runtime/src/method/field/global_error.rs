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
//! included. Past the bound every step's error is carried along the
//! motion with its sign (`global_error::growth`), by a reference stepped
//! alongside the run from `x − e` (`Growth::step_alongside`, 24
//! evaluations a step: the step's error and the propagation of the error
//! before it in one, where a measure from the step's start and the
//! step's derivative cost 48). The steps of stiff and Magnus windows are
//! not counted (the estimate then says it is partial).
//!
//! A model without constraints whose motion is not affine carries its
//! errors so from its first step, not from the bound: a chaotic double
//! pendulum at rtol 1e-9 ended 11.2 rtol off saying 0.75, its calibrated
//! sum never near the bound, the motion amplifying its errors about
//! 15-fold unseen; carried from the first step, 11.4 (docs/BENCHMARKS.md
//! §10o; +15 … 31 % instructions on such runs). And the last window's
//! steps, which no advance feeds, are fed when the run reaches its end
//! ([`FieldError::finish`]): before, they were summed with their
//! estimates unscaled, a whole run in one window estimated at 12–24 rtol
//! for errors of 0.2–0.5 (a spherical pendulum, rtol 1e-9 … 1e-12).
//!
//! A model with constraints carries its errors along the motion, each
//! step's with its sign, propagated through the window and projected at
//! each window's anchor as the run projects the state there. Without the
//! projection the reduced system's drift off the constraints grows the
//! carried error without bound; without the carrying, a slider-crank
//! whose period depends on its energy ended 154 rtol off at rtol 1e-6
//! saying "within" (its windows' summed errors were 3 rtol: the phase
//! error grows with time), and the same four-bar loop kept by velocity
//! constraints (`four_bar_velocity`) was estimated 100× below its error.
//!
//! A model without switches carries them from its first step, by a
//! reference stepped alongside the run from `x − e` (two DOP853
//! half-steps a step, 24 evaluations) and put on the constraints at each
//! window's anchor as the state is, the carried error being the run's
//! state less the reference (`Growth::step_alongside`): the measure and
//! the propagation in one. From the first step, not from a threshold of
//! the windows' summed errors (as before, and as a model with switches
//! still does): errors made before a threshold are not carried, and a
//! motion that amplifies them leaves the sum far below the error. A 3-D
//! rolling disk at rtol 1e-11 ended 43 rtol off saying "within" (0.8):
//! its first window's 0.006 rtol, amplified about 5,000-fold over 9 s,
//! was most of it, and the sum (its unmeasured windows scaled by the
//! first's ratio of measure to estimate, 0.005) never reached the
//! threshold; carried from the first step, estimated 43 rtol. The cost:
//! 24 evaluations of the reduced system a step, on the runs that
//! carried nothing before (those whose sum stayed under the threshold).
//!
//! A model with switches measures its errors on windows first: a window
//! of at most `CALIBRATION_STRIDE` steps is added to the sum as one, its
//! error at its end measured against a reference carried along it from
//! its anchor (`FieldError::feed_window`), and a longer window's steps as
//! above; it carries them from the window in which the calibrated sum
//! passes `FROM_DIRECT`·rtol (as direct integration's), each step
//! measured when its window is taken (`measure_signed`) and differenced
//! when carried (`carry`): its window's steps after the first are carried
//! when added, after the driver may have changed its regime, while the
//! measure must be the window's (see `alongside`).
//!
//! Once carried, a constrained model's estimate is the sum at the start
//! of the carrying (the errors before it, not carried; none for a model
//! without switches) plus the largest carried error, no longer the sum of
//! the windows' errors: that sum is a bound only where errors neither
//! cancel nor grow, and a knife edge circling at constant speed (whose
//! errors of position go round with it and cancel) summed 22 rtol
//! against an error of 1.0 rtol at rtol 1e-6.

use crate::failure::Failure;
use crate::method::solver::{GlobalErrorEstimate, Keeping};
use crate::model::DynModel;
use crate::ode::dop853::global_error::growth::{past_bound, Growth, Keep, Project, FROM_DIRECT};
use crate::ode::dop853::global_error::{relative, GlobalError, Swings, CALIBRATION_STRIDE};
use crate::ode::dop853::step_by_halves;
use crate::ode::system::ModelSystem;

/// After the first, a window is measured once this many times its steps
/// have been added since the last measure.
const WINDOW_SHARE: usize = 4;

/// One accepted step of a window, not yet added.
#[derive(Clone, Debug)]
struct Unfed {
    t0: f64,
    x0: Vec<f64>,
    t1: f64,
    x1: Vec<f64>,
    /// `None`: a step whose error is not estimated.
    local: Option<Vec<f64>>,
    /// Constrained models: the step's measure, taken when its window was
    /// accepted (`feed_window`).
    measured: Measured,
    /// Constrained models: the step is one of a window too long to be
    /// measured whole (`measure_steps`), added step by step.
    alone: bool,
    /// Constrained models, once their errors are carried: the step's
    /// error with its sign, against a reference from its start.
    signed: Option<Vec<f64>>,
    /// Constrained models: the step was carried already (a window's
    /// first, at the projection before it: `FieldError::keep`).
    carried: bool,
}

/// A constrained model's step, measured (relative errors).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Measured {
    No,
    /// The state at the step's end against a reference carried along its
    /// window from the anchor.
    InWindow(f64),
    /// Against a reference from the step's start (a long window's step).
    Alone(f64),
}

/// The carried estimate of one field run.
#[derive(Clone, Debug)]
pub struct FieldError {
    /// Whether the estimate is made at all (`Options::global_error`):
    /// off, every method returns at once and the report has no estimate.
    on: bool,
    rtol: f64,
    global: GlobalError,
    /// The components' swings, for the estimate's reading where they pass
    /// zero (`global_error::Swings`).
    swings: Swings,
    /// The run carries its errors from its first step: the swing's sum is
    /// not kept (`feed`).
    swings_off: bool,
    /// Set at the first step from the model: whether it has constraints,
    /// whose windows are added as wholes to the sum (`feed_window`) and
    /// whose carried error is projected as the state is (`keep`).
    constrained: Option<bool>,
    /// The errors carried along the motion.
    growth: Growth,
    /// Evaluations of the reference steps.
    evaluations: usize,
    unfed: Vec<Unfed>,
    /// Steps added already, their storage kept for the next ones (the
    /// affine field adds one step at every advance: three vectors a
    /// step were allocated and freed, 9 % of an oscillator's field).
    spare: Vec<Unfed>,
    /// A constrained model's windows (`feed_window`).
    windows: Windows,
    /// The estimate when the carrying started: the errors before it, not
    /// carried (`estimate`).
    before_carrying: Option<f64>,
    /// The last measured window's end and its error there, with its sign:
    /// where the carrying starts at that end, the error it starts from.
    window_end: Option<(f64, Vec<f64>)>,
    /// Where the last window's carrying began: its first step's start,
    /// the carried error and the estimate before it, for a window taken
    /// again from there ([`FieldError::retake`]).
    before_window: Option<(f64, Growth, Option<f64>)>,
}

/// A constrained model's windows, each added as one (`feed_window`).
#[derive(Clone, Debug, Default)]
struct Windows {
    /// Whether a window was measured.
    measured: bool,
    /// The measured windows' errors at their ends (relative), summed, and
    /// their steps' estimates, summed.
    ends: f64,
    ends_estimated: f64,
    /// The other windows' steps' estimates, summed.
    unmeasured: f64,
    /// Steps added since the last measured window.
    since_measure: usize,
    /// Steps of long windows since the last step measured alone.
    since_alone: usize,
    /// The largest error inside a measured window on top of the windows
    /// before it.
    peak: f64,
}

impl Windows {
    /// What the measured windows' ends are of their estimates, at most 1
    /// (as direct integration's `κ`; summed over the measures, for one
    /// window's ratio is no other's: on knife_edge_circling they ranged
    /// over 1e-3 … 0.3).
    fn ratio(&self) -> f64 {
        if self.ends_estimated > 0.0 {
            (self.ends / self.ends_estimated).min(1.0)
        } else {
            1.0
        }
    }

    /// The estimated error at the last window's end.
    fn sum(&self) -> f64 {
        self.ends + self.ratio() * self.unmeasured
    }
}

impl FieldError {
    /// For a run of `n` components at relative tolerance `rtol`.
    pub fn new(n: usize, rtol: f64) -> FieldError {
        FieldError {
            on: true,
            rtol,
            global: GlobalError::new(),
            swings: Swings::default(),
            swings_off: false,
            constrained: None,
            growth: Growth::new(n),
            evaluations: 0,
            unfed: Vec::new(),
            spare: Vec::new(),
            windows: Windows::default(),
            before_carrying: None,
            window_end: None,
            before_window: None,
        }
    }

    /// The estimate made only if `on` (`Options::global_error`): off,
    /// nothing is measured, kept or carried.
    pub fn made_if(mut self, on: bool) -> FieldError {
        self.on = on;
        self
    }

    /// Whether the estimate is made: the field skips the steps' local
    /// errors, which only it reads, when it is not.
    pub fn is_on(&self) -> bool {
        self.on
    }

    fn constrained(&mut self, model: &dyn DynModel) -> bool {
        if self.constrained.is_none() {
            self.constrained = Some(!model.constraints().is_empty() || model.keeps_constraints());
        }
        self.constrained == Some(true)
    }

    /// Whether a constrained model's errors are carried along the motion
    /// from the window whose steps start at `first` (once measured): from
    /// the window in which the calibrated sum passes [`FROM_DIRECT`]·rtol,
    /// as direct integration's from the step (see there why not from the
    /// bound). The window's own steps are carried too: a particle in a
    /// cone's four windows of 7.5 s each, carried from the second, were
    /// estimated 11× below their error.
    fn carries_constrained(&self, first: usize) -> bool {
        if self.growth.started() {
            return true;
        }
        let steps = &self.unfed[first..];
        let mut calibrated = self.windows.measured || self.global.calibrated();
        // The window's part: its end's measure, its steps' own measures
        // scaling their estimates, or its estimates as the windows' are
        // scaled.
        let own = match steps.last().map(|s| s.measured) {
            Some(Measured::InWindow(end)) => {
                calibrated = true;
                end
            }
            _ => {
                let (mut measured, mut estimated_measured) = (0.0, 0.0);
                for step in steps {
                    if let (Measured::Alone(m), Some(local)) = (step.measured, &step.local) {
                        measured += m;
                        estimated_measured += relative(local, &step.x1);
                    }
                }
                let ratio = if estimated_measured > 0.0 {
                    calibrated = true;
                    (measured / estimated_measured).min(1.0)
                } else {
                    self.windows.ratio()
                };
                ratio * estimated(steps)
            }
        };
        calibrated && self.windows.sum() + self.global.estimate() + own > FROM_DIRECT * self.rtol
    }

    /// A window accepted from `(t, x)`: its steps' ends `ends` with their
    /// states and local errors (`None` where not estimated).
    pub fn window(
        &mut self,
        model: &dyn DynModel,
        (t, x): (f64, &[f64]),
        ends: &[f64],
        states: &[Vec<f64>],
        errors: &[Option<Vec<f64>>],
    ) {
        if !self.on {
            return;
        }
        let first = self.unfed.len();
        let (mut t0, mut x0) = (t, x);
        for ((&t1, x1), local) in ends.iter().zip(states).zip(errors) {
            self.push((t0, x0), (t1, x1), local.as_deref());
            (t0, x0) = (t1, x1);
        }
        self.added(model, first);
    }

    /// [`FieldError::window`] of one step from `(t0, x0)` to `(t1, x1)`,
    /// its local error `local`: the affine field's, at every advance,
    /// without allocating.
    pub fn step(
        &mut self,
        model: &dyn DynModel,
        (t0, x0): (f64, &[f64]),
        (t1, x1): (f64, &[f64]),
        local: Option<&[f64]>,
    ) {
        if !self.on {
            return;
        }
        let first = self.unfed.len();
        self.push((t0, x0), (t1, x1), local);
        self.added(model, first);
    }

    /// One step waiting to be added, in a spare step's storage.
    fn push(&mut self, (t0, x0): (f64, &[f64]), (t1, x1): (f64, &[f64]), local: Option<&[f64]>) {
        let mut step = self.spare.pop().unwrap_or_else(|| Unfed {
            t0,
            x0: Vec::new(),
            t1,
            x1: Vec::new(),
            local: None,
            measured: Measured::No,
            alone: false,
            signed: None,
            carried: false,
        });
        step.t0 = t0;
        step.x0.clear();
        step.x0.extend_from_slice(x0);
        step.t1 = t1;
        step.x1.clear();
        step.x1.extend_from_slice(x1);
        step.local = local.map(|l| {
            let mut v = step.local.take().unwrap_or_default();
            v.clear();
            v.extend_from_slice(l);
            v
        });
        step.measured = Measured::No;
        step.alone = false;
        step.signed = None;
        step.carried = false;
        self.unfed.push(step);
    }

    /// After the steps from `first` on were pushed: a constrained model's
    /// window measured and carried.
    fn added(&mut self, model: &dyn DynModel, first: usize) {
        // A constrained model's window is measured now, in the model's
        // regime of the window (the driver may change the candidates
        // before the window is added).
        if !self.constrained(model) {
            return;
        }
        if alongside(model) {
            // Carried by a reference alongside the run from the first
            // step (the module's comment: why not from a threshold of the
            // sum): no window is measured, nothing would read its measure.
            return;
        }
        let system = ModelSystem(model);
        let count = self.unfed.len() - first;
        if count > CALIBRATION_STRIDE {
            for step in &mut self.unfed[first..] {
                step.alone = true;
            }
            self.measure_steps(&system, first);
        } else if self.wants_window_measure(&self.unfed[first..]) {
            self.evaluations += 24 * count;
            let end = self.unfed[self.unfed.len() - 1].t1;
            self.window_end = measure_window(&system, &mut self.unfed[first..]).map(|e| (end, e));
        }
        if from_first_step(model) || self.carries_constrained(first) {
            self.measure_signed(&system, first);
        }
    }

    /// A window too long to measure whole (its measure would cost more
    /// than the run: a ball on a turntable's one window of 49 steps, 2.8x
    /// its evaluations): some of its steps, each against a reference from
    /// its start, as direct integration's steps are, once the sum passes
    /// `FROM_DIRECT`·rtol and every `CALIBRATION_STRIDE` steps after.
    fn measure_steps(&mut self, system: &ModelSystem<'_>, first: usize) {
        let mut sum = self.windows.sum() + self.global.estimate();
        let mut calibrated = self.global.calibrated();
        for step in &mut self.unfed[first..] {
            let Some(local) = &step.local else {
                continue;
            };
            let estimated = relative(local, &step.x1);
            let w = &mut self.windows;
            // As direct integration's `wants_measure`: the sum before the
            // step past `FROM_DIRECT`·rtol, where the errors may start to
            // be carried (`carries_constrained`), which needs a
            // calibrated sum.
            let measures = if calibrated {
                w.since_alone >= CALIBRATION_STRIDE
            } else {
                sum > FROM_DIRECT * self.rtol
            };
            sum += estimated;
            w.since_alone += 1;
            if !measures {
                continue;
            }
            w.since_alone = 0;
            self.evaluations += 24;
            let mut reference = vec![0.0; step.x1.len()];
            if let Ok(true) =
                step_by_halves(system, step.t0, &step.x0, step.t1 - step.t0, &mut reference)
            {
                for (r, x) in reference.iter_mut().zip(&step.x1) {
                    *r = x - *r;
                }
                step.measured = Measured::Alone(relative(&reference, &step.x1));
            }
            // The sum is calibrated from this measure on (when added).
            calibrated = true;
        }
    }

    /// A constrained model's steps from `first` on, each against a
    /// reference from its start (24 evaluations), with their signs: what
    /// is carried along the motion.
    fn measure_signed(&mut self, system: &ModelSystem<'_>, first: usize) {
        for step in &mut self.unfed[first..] {
            if step.local.is_none() {
                continue;
            }
            self.evaluations += 24;
            let mut reference = vec![0.0; step.x1.len()];
            if let Ok(true) =
                step_by_halves(system, step.t0, &step.x0, step.t1 - step.t0, &mut reference)
            {
                for (r, x) in reference.iter_mut().zip(&step.x1) {
                    *r = x - *r;
                }
                step.signed = Some(reference);
            }
        }
    }

    /// After a constrained model's advance, before the run projects its
    /// state: the error carried so far, propagated to the last window's
    /// anchor, is projected there as the state was (`keeping`'s
    /// derivative of the projection), and the window's steps are carried.
    /// A model with switches has only the window's first step carried now,
    /// its others when they are added (`feed`): an event found in the
    /// window cuts them.
    pub fn keep(&mut self, model: &dyn DynModel, keeping: &mut dyn Keeping) {
        if !self.on {
            return;
        }
        if !self.constrained(model) {
            return;
        }
        self.carry_steps(model, f64::INFINITY, model.switches() > 0, Some(keeping));
    }

    /// Carries the steps not yet carried that start before `t` (only the
    /// first of them if `first_only`), the error before them projected at
    /// the first's start as `keeping` projects the state (a model carried
    /// by a reference alongside: the reference put on the constraints;
    /// otherwise the projection's derivative applied to the error).
    fn carry_steps(
        &mut self,
        model: &dyn DynModel,
        t: f64,
        first_only: bool,
        keeping: Option<&mut dyn Keeping>,
    ) {
        // A window is taken again from its start where it crossed a
        // constraint's pivot (`retake`: a constraint of several
        // candidates), or cut at an event (switches): what is carried
        // before it, kept (a copy of the carried error a window, which
        // the other models, the affine field's a step, need not pay).
        let taken_again =
            model.switches() > 0 || model.constraints().iter().any(|c| c.names.len() > 1);
        if let (true, Some(first)) = (
            taken_again,
            self.unfed.iter().find(|s| s.t0 < t && !s.carried),
        ) {
            let before = (first.t0, self.growth.clone(), self.before_carrying);
            self.before_window = Some(before);
        }
        let system = ModelSystem(model);
        let alongside = alongside(model);
        if alongside {
            let mut project = keeping.map(|k| move |t: f64, x: &mut [f64]| k.project(t, x));
            let project = project.as_mut().map(|p| p as &mut Project<'_>);
            return self.carry_steps_alongside(&system, t, project);
        }
        let mut keep = keeping.map(|k| move |t: f64, x: &[f64], d: &mut [f64]| k.tangent(t, x, d));
        let mut keep = keep.as_mut().map(|k| k as &mut Keep<'_>);
        let summed = self.summed();
        let (growth, window_end) = (&mut self.growth, &self.window_end);
        for step in self.unfed.iter_mut().filter(|s| s.t0 < t && !s.carried) {
            step.carried = true;
            if let (false, Some(_), Some((end, error))) =
                (growth.started(), &step.signed, window_end)
            {
                if *end == step.t0 {
                    // The carrying starts at a measured window's end: the
                    // error there is carried too (a ball on a turntable in
                    // Euler angles at rtol 1e-8 amplified its first
                    // window's 0.5 rtol 70-fold, estimated 1.5 rtol for an
                    // error of 35).
                    let keep = keep.as_mut().map(|k| (&mut **k, step.t0, &step.x0[..]));
                    growth.seed(error, keep);
                }
            }
            carry(growth, &system, step, keep.take());
            if first_only {
                break;
            }
        }
        self.note_start(summed);
    }

    /// [`FieldError::carry_steps`] of a model without switches (all the
    /// steps not yet carried), by a reference alongside the run
    /// (`Growth::step_alongside`), put on the constraints at the first
    /// step's start by `project`: every step from the run's first (a step
    /// not estimated too: its error is in the reference's difference).
    fn carry_steps_alongside(
        &mut self,
        system: &ModelSystem<'_>,
        t: f64,
        mut project: Option<&mut Project<'_>>,
    ) {
        let summed = self.summed();
        let growth = &mut self.growth;
        for step in self.unfed.iter_mut().filter(|s| s.t0 < t && !s.carried) {
            step.carried = true;
            growth.step_alongside(
                system,
                (step.t0, &step.x0),
                (step.t1, &step.x1),
                project.take(),
            );
        }
        self.note_start(summed);
    }

    /// The sum of the errors added so far (a constrained model's), the
    /// largest inside a measured window included.
    fn summed(&self) -> f64 {
        (self.windows.sum() + self.global.estimate()).max(self.windows.peak)
    }

    /// After a step was carried: the sum before it, `summed`, if it was
    /// the first (what the estimate adds to the carried error).
    fn note_start(&mut self, summed: f64) {
        if self.growth.started() && self.before_carrying.is_none() {
            self.before_carrying = Some(summed);
        }
    }

    /// Whether a constrained model's window of `steps` is measured (see
    /// `feed_window`).
    fn wants_window_measure(&self, steps: &[Unfed]) -> bool {
        if self.windows.measured {
            // A measured window costs 24 evaluations a step: at most a
            // fifth of the steps are measured (a window of 49 steps,
            // measured whole each time, was 2.8x the run's evaluations).
            return self.windows.since_measure
                >= (WINDOW_SHARE * steps.len()).max(CALIBRATION_STRIDE);
        }
        self.windows.sum() + self.global.estimate() + estimated(steps) > FROM_DIRECT * self.rtol
    }

    /// Adds the steps that start before `t` (all: `f64::INFINITY`).
    pub fn feed(&mut self, model: &dyn DynModel, t: f64) {
        if !self.on {
            return;
        }
        if self.constrained(model) {
            self.carry_steps(model, t, false, None);
            self.feed_window(t);
            return;
        }
        let system = ModelSystem(model);
        let mut steps = std::mem::take(&mut self.unfed);
        for step in &steps {
            if step.t0 >= t {
                break;
            }
            let Some(local) = &step.local else {
                self.global.skip();
                continue;
            };
            let h = step.t1 - step.t0;
            let estimated = relative(local, &step.x1);
            // A non-affine motion's errors are carried from the first
            // step (the module's comment: errors made before a threshold
            // are summed, not amplified); an affine one's from the bound.
            let carried = self.growth.started()
                || !model.affine()
                || from_first_step(model)
                || past_bound(&self.global, self.rtol);
            // The step's error against the reference, where the sum is
            // calibrated (every `CALIBRATION_STRIDE` steps, as direct
            // integration's: see there why not at every step); a
            // reference that fails leaves the estimate as it is (the
            // estimate never fails the run).
            let calibrates = self.global.wants_measure(self.rtol);
            let mut measured = None;
            if calibrates {
                self.evaluations += 24;
                let mut reference = vec![0.0; step.x1.len()];
                if let Ok(true) = step_by_halves(&system, step.t0, &step.x0, h, &mut reference) {
                    for (r, x) in reference.iter_mut().zip(&step.x1) {
                        *r = x - *r;
                    }
                    measured = Some(relative(&reference, &step.x1));
                }
            }
            let added = match measured {
                Some(m) => self.global.add_measured(estimated, m, h),
                None => self.global.add(estimated, h),
            };
            // A run carried from its first step keeps no swing's sum
            // (direct integration's `sum_into`: the carried error holds
            // every step's error with its sign).
            self.swings_off = !model.affine() || from_first_step(model);
            let swung = if self.swings_off { 0.0 } else { added };
            let ends = (&step.x0[..], &step.x1[..]);
            self.global
                .swing(&mut self.swings, local, ends, estimated, swung);
            if carried {
                // Carried by a reference stepped alongside the run from
                // `x0 − e` (`Growth::step_alongside`, 24 evaluations): the
                // step's error with its sign and the error before it
                // carried by the flow, in one. A measure from `x0` and
                // the step's derivative (two new DOP853 steps) took 48
                // evaluations a step for the same: an undamped
                // oscillator over 159 periods at rtol 1e-8 spent 49 % of
                // its field's instructions there, 3.6x plain DOP853's
                // whole run (docs/BENCHMARKS.md §0, h-affine2). For an
                // affine motion the two differ only by the propagators'
                // own truncation (the flow of `x0 − e` is the flow of
                // `x0` less the linear flow of `e`) and by the measure's
                // cap at the step's estimate (`at_most_estimated`), which
                // the reference's difference does not apply.
                self.growth
                    .step_alongside(&system, (step.t0, &step.x0), (step.t1, &step.x1), None);
            }
        }
        // All of them added or dropped (those from `t` on are not the
        // motion's): their storage kept for the next.
        self.spare.append(&mut steps);
        self.unfed = steps;
    }

    /// A constrained model's window (its steps that start before `t`),
    /// added as one: its error at its end, not the sum of its steps'.
    ///
    /// Why: inside a window the field's state is recovered from
    /// coefficients integrated from the anchor, and its error is their
    /// error mapped through the conditions at that time, which rises and
    /// falls along the window: the step-to-step changes of that error
    /// (what a step's error is, against a reference from the step's
    /// start) cancel. Measured on knife_edge_circling at rtol 1e-8: steps
    /// of 0.63 each 3.9e-9 off (Hairer's mapped estimate 9.4e-9; the
    /// two-half-step reference's own error 2e-13), the state 2.4e-9 off
    /// in mid-window and 1.2e-11 at the window's end; 852 such steps
    /// summed to 1.4e-6 against a largest error of 6e-9 (2.4e-9 at the
    /// samples). Carried with their signs (`growth`, from
    /// `FROM_DIRECT`·rtol on, projected at the windows' anchors), they
    /// cancel; summed, they do not.
    ///
    /// The window's error is measured against a reference carried along
    /// the window from its anchor (two DOP853 half-steps a step, 24
    /// evaluations) when it is accepted (`window`), once the sum of the
    /// estimates passes `FROM_DIRECT`·rtol (a calibrated sum decides
    /// where the carrying starts), and then once `CALIBRATION_STRIDE`
    /// steps and four times its own have been added since the last; the
    /// measured windows' end errors over their steps' estimates, both
    /// summed, scale the other windows' estimates (`Windows::ratio`), as
    /// direct integration's Richardson measure scales its steps'. The
    /// largest error inside a measured window, on top of the sum before
    /// it, is kept too (the run's samples are taken there). A window of
    /// more steps is added step by step, some measured alone
    /// (`measure_steps`).
    fn feed_window(&mut self, t: f64) {
        let mut steps = std::mem::take(&mut self.unfed);
        steps.retain(|s| s.t0 < t);
        if steps.is_empty() {
            return;
        }
        if steps.iter().any(|s| s.local.is_none()) {
            self.global.skip();
        }
        if steps[0].alone {
            // A long window's steps (all, or those before an event), as
            // direct integration's.
            for step in &steps {
                let Some(local) = &step.local else {
                    continue;
                };
                let (estimated, h) = (relative(local, &step.x1), step.t1 - step.t0);
                match step.measured {
                    Measured::Alone(m) => self.global.add_measured(estimated, m, h),
                    _ => self.global.add(estimated, h),
                };
            }
            return;
        }
        let estimated = estimated(&steps);
        self.windows.since_measure += steps.len();
        let measured = steps
            .iter()
            .map(|s| match s.measured {
                Measured::InWindow(e) => Some(e),
                _ => None,
            })
            .collect::<Option<Vec<f64>>>()
            .map(|errors| {
                let inside = errors.iter().fold(0.0_f64, |m, &e| m.max(e));
                (errors[errors.len() - 1], inside)
            });
        let w = &mut self.windows;
        match measured {
            Some((end, inside)) => {
                w.measured = true;
                w.since_measure = 0;
                w.ends += end;
                w.ends_estimated += estimated;
                w.peak = w.peak.max(self.global.estimate() + w.sum() - end + inside);
            }
            None => w.unmeasured += estimated,
        }
    }

    /// At the run's end: the last window's steps, which no advance
    /// feeds, added as the others are (measured where the sum is
    /// calibrated, carried where the errors are), and the last carried
    /// step's error added to the carried error. Without it the last
    /// window's steps were only summed, with their estimates unscaled: a
    /// spherical pendulum run in one window (rtol 1e-10) said 14.7 rtol
    /// for an error of 0.2, and a chaotic double pendulum whose error
    /// grew from 3 to 11 rtol in its last window said what it was before
    /// it. A constrained model's windows are left as they were.
    pub fn finish(&mut self, model: &dyn DynModel) {
        if !self.on || self.constrained(model) {
            return;
        }
        self.feed(model, f64::INFINITY);
        self.growth.finish(&ModelSystem(model));
    }

    /// The window from `t` is taken again (the driver went back to its
    /// start, in a better mode: `run::regime::pivot_crossed`): its steps
    /// are not the motion's, neither added nor carried. Without this a
    /// constant-speed particle's window across its apex, carried and then
    /// taken again, was carried twice, its reference restarted from the
    /// window's start with the error of its end: an estimate of 1.8
    /// (absolute) for an error of 3e-9.
    pub fn retake(&mut self, t: f64) {
        if !self.on {
            return;
        }
        self.back_to_window_start(|start| start == t);
        // The steps are in time order: the window's are the last ones.
        let from = self.unfed.iter().position(|s| s.t0 >= t);
        if let Some(from) = from {
            self.spare.extend(self.unfed.drain(from..));
        }
        if self.window_end.as_ref().is_some_and(|(end, _)| *end > t) {
            self.window_end = None;
        }
    }

    /// An event at `t`, the run going on from `x`: the steps before it
    /// are the motion's.
    pub fn cut(&mut self, model: &dyn DynModel, t: f64, x: &[f64]) {
        if !self.on {
            return;
        }
        self.uncarry_past(t);
        self.feed(model, t);
        self.growth.cut(&ModelSystem(model), t, x);
    }

    /// After an event's cut, before the restart: the carried error
    /// through the event's time and the impact's reset (`jump`,
    /// `run::saltation::through_event`; `Solver::carry_error_through_event`).
    pub fn jump(&mut self, jump: &mut dyn FnMut(&mut [f64]) -> Result<(), Failure>) {
        if self.on {
            self.growth.jump(jump);
        }
    }

    /// Before an event at `t` inside a window whose steps were carried
    /// already (at `keep`, after the advance): the carried error goes back
    /// to where that window's carrying began, for its steps before `t` to
    /// be carried again, the last one only to `t` (`Growth::cut` takes
    /// back the last step alone: a particle on a circle whose window was
    /// carried whole, 4.25 to 6.16, and then cut at its start, compared
    /// the state at 4.25 with the reference at 6.16, found by h-stephalf).
    fn uncarry_past(&mut self, t: f64) {
        if !self.unfed.iter().any(|s| s.carried && s.t1 > t) {
            return;
        }
        if let Some(start) = self.back_to_window_start(|start| start <= t) {
            for step in self.unfed.iter_mut().filter(|s| s.t0 >= start) {
                step.carried = false;
            }
        }
    }

    /// The carried error and the estimate before it as they were where
    /// the last window's carrying began, if that start is `wanted`: the
    /// start, then.
    fn back_to_window_start(&mut self, wanted: impl Fn(f64) -> bool) -> Option<f64> {
        let (start, growth, before) = self.before_window.take()?;
        if !wanted(start) {
            return None;
        }
        self.growth = growth;
        self.before_carrying = before;
        Some(start)
    }

    /// The right-side evaluations the estimate cost.
    pub fn evaluations(&self) -> usize {
        self.evaluations + self.growth.evaluations()
    }

    /// For the summary: the estimate, if one is made.
    pub fn report(&self) -> Option<GlobalErrorEstimate> {
        self.on.then(|| self.estimate())
    }

    /// For the summary: the steps added so far (and those waiting,
    /// summed).
    fn estimate(&self) -> GlobalErrorEstimate {
        if self.constrained == Some(true) {
            let partial = self.unfed.iter().any(|s| s.local.is_none());
            let complete = self.global.complete() && !partial;
            if let Some(before) = self.before_carrying {
                // Carried: the errors before the carrying, and the carried
                // error (the module's comment: why not the windows' sum),
                // and the steps not carried yet (a model with switches: the
                // last window's after its first), summed.
                let waiting: f64 = self
                    .unfed
                    .iter()
                    .filter(|s| !s.carried)
                    .filter_map(|s| s.local.as_ref().map(|l| relative(l, &s.x1)))
                    .sum();
                return GlobalErrorEstimate {
                    largest: before + self.growth.largest() + self.windows.ratio() * waiting,
                    rtol: self.rtol,
                    complete,
                };
            }
            // The window not yet added: a long one's steps scaled as the
            // steps are, a short one by the windows' ratio.
            let w = &self.windows;
            let mut global = self.global.clone();
            let mut pending = 0.0;
            for step in &self.unfed {
                if let Some(local) = &step.local {
                    let estimated = relative(local, &step.x1);
                    if step.alone {
                        global.add(estimated, step.t1 - step.t0);
                    } else {
                        pending += w.ratio() * estimated;
                    }
                }
            }
            return GlobalErrorEstimate {
                largest: (w.sum() + global.estimate() + pending)
                    .max(w.peak)
                    .max(self.growth.largest()),
                rtol: self.rtol,
                complete,
            };
        }
        let (mut global, mut swings) = (self.global.clone(), self.swings.clone());
        for step in &self.unfed {
            match &step.local {
                Some(local) => {
                    let estimated = relative(local, &step.x1);
                    let added = global.add(estimated, step.t1 - step.t0);
                    let ends = (&step.x0[..], &step.x1[..]);
                    let swung = if self.swings_off { 0.0 } else { added };
                    global.swing(&mut swings, local, ends, estimated, swung);
                }
                None => global.skip(),
            }
        }
        GlobalErrorEstimate {
            largest: global.read().max(self.growth.largest()),
            rtol: self.rtol,
            complete: global.complete(),
        }
    }
}

/// A constrained model's step carried along the motion: its signed
/// error where it was measured (at most its estimate, as the other
/// models' steps), none where not (it was taken before the carrying
/// started, or not estimated: the carried error is still propagated over
/// it), the error carried before it projected at its start by `keep`.
fn carry(growth: &mut Growth, system: &ModelSystem<'_>, step: &Unfed, keep: Option<&mut Keep<'_>>) {
    let local = match (&step.signed, &step.local) {
        (Some(signed), Some(local)) => at_most_estimated(signed, local, &step.x1),
        _ if !growth.started() => return,
        _ => vec![0.0; step.x1.len()],
    };
    growth.step_kept(system, (step.t0, &step.x0), step.t1, &local, keep, None);
}

/// Whether a constrained model's errors, once carried, are carried by a
/// reference alongside the run (`Growth::step_alongside`: 24 evaluations
/// a step, where a step measured and differenced costs 48): a model
/// without switching functions, whose steps are all carried right after
/// their window was taken (`FieldError::keep`), in the window's regime
/// (the driver changes a constraint's candidate after that: the knife
/// edges' pivots). A model with switching functions has its window's
/// steps after the first carried when they are added, after the driver
/// may have changed its regime: its steps are measured when their window
/// is taken (`measure_signed`) and differenced when carried, as before.
fn alongside(model: &dyn DynModel) -> bool {
    model.switches() == 0
}

/// Whether a model's errors are carried from its first step (and so
/// through every event, [`FieldError::jump`]) for its impacts, as direct
/// integration's (`method::direct::carried_from_first_step`): each
/// bounce turns a height error into a time error and that into a
/// velocity error, 1/v larger as the bounces shrink. A ball bouncing on
/// an inclined floor (`examples/incline_bounce.lag`, affine: carried
/// before only past the bound) ended where its bounces accumulate 108
/// and 1.4e4 rtol off at rtol 1e-10 and 1e-12 (against the closed form)
/// saying 1e-4 and 0.007: carried from the first step and through the
/// bounces, 45.5 and 2.5e4; either change alone left them as they were
/// (docs/BENCHMARKS.md §10w).
fn from_first_step(model: &dyn DynModel) -> bool {
    !model.impacts().is_empty()
}

/// A step's measured error `measured` (with its sign), scaled down to
/// the size of its estimate `local` where it is larger (relative to
/// `x1`): what is carried along the motion, at most the calibration's
/// bound.
fn at_most_estimated(measured: &[f64], local: &[f64], x1: &[f64]) -> Vec<f64> {
    let (size, estimated) = (relative(measured, x1), relative(local, x1));
    let k = if size > estimated && size > 0.0 {
        estimated / size
    } else {
        1.0
    };
    measured.iter().map(|v| k * v).collect()
}

/// The steps' estimates summed (relative; the steps not estimated left
/// out).
fn estimated(steps: &[Unfed]) -> f64 {
    steps
        .iter()
        .filter_map(|s| s.local.as_ref().map(|l| relative(l, &s.x1)))
        .sum()
}

/// Each step's error against a reference carried along the window's
/// steps from the first one's start (two DOP853 half-steps a step), into
/// `measured` (relative); left `None` from where the reference fails.
fn measure_window(system: &ModelSystem<'_>, steps: &mut [Unfed]) -> Option<Vec<f64>> {
    let first = steps.first()?;
    let mut reference = first.x0.clone();
    let mut next = vec![0.0; reference.len()];
    let mut difference = vec![0.0; reference.len()];
    for step in steps {
        match step_by_halves(system, step.t0, &reference, step.t1 - step.t0, &mut next) {
            Ok(true) => {}
            _ => return None,
        }
        std::mem::swap(&mut reference, &mut next);
        for ((d, x), r) in difference.iter_mut().zip(&step.x1).zip(&reference) {
            *d = x - r;
        }
        step.measured = Measured::InWindow(relative(&difference, &step.x1));
    }
    Some(difference)
}
