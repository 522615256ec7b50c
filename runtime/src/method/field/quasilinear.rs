//! The field method for reduced systems that are not affine in the state
//! (SPEC §1.5): quasilinearisation (Newton–Kantorovich) on windows.
//!
//! On a window from the anchor `(t_r, x_r)` the motion is linearised along
//! an iterate `x^0(t)`, `x' = A(t) x + b(t)` with `A = ∂X/∂x (t, x^0)` and
//! `b = X(t, x^0) − A x^0` — exactly the class the field method solves —
//! and that time-varying affine system's field gives the next iterate
//! `x^1`. Newton's method converges quadratically, so a good `x^0` makes
//! one pass enough: `x^0` is a predictor, DOP853 at a looser tolerance
//! (about the square root of the requested one), run lazily as far as the
//! field asks for it. The field is then integrated by DOP853 with the
//! recovered state's error controlled at the requested tolerance, so its
//! error is that of an 8th-order integration, not of the linearisation.
//!
//! Newton's remaining error is watched directly: the defect of `x^1` in
//! the true equations, `r = X(t, x^1) − X(t, x^0) − A (x^1 − x^0)`
//! (`≈ ½ X_xx (x^1 − x^0)²`), integrated along the window bounds it. A
//! window ends where that bound would pass a fraction of the tolerance,
//! where the conditions (13) degrade, or at the end of the span; the next
//! window is anchored at its end.

use super::coefficients::{
    FieldSystem, Iterate, LinearizationScratch, LinearizedMotion, ProjectiveCoefficients,
};
use super::conditions::recover_state;
use super::global_error::FieldError;
use super::middle::{refined, MiddleScratch};
use super::window::{StepperKind, StoredStep, Window, WindowStep};
use super::{FieldOptions, MAX_SHORTENINGS};
use crate::failure::{Failure, FailureKind};
use crate::linalg::Matrix;
use crate::method::solver::{Keeping, Report, Solver};
use crate::model::{DomainKind, DynModel};
use crate::ode::budget::Budget;
use crate::ode::dop853::dense_steps_between;
use crate::ode::stepper::DenseStep;
use crate::ode::stepper::{OfModel, StepperOf};
use crate::ode::system::ModelSystem;
use crate::ode::tolerance::{underflows, Stats, Tolerance};
use crate::ode::Integrator;
use std::cell::{Cell, RefCell};

/// Newton's error bound a window may reach, in units of the tolerance.
const DEFECT_LIMIT: f64 = 0.2;
/// Near the end of a constraint's branch, Newton's error may move the
/// branch's argument by at most this fraction of its value...
const DOMAIN_FRACTION: f64 = 0.1;
/// ... but the bound is not cut below this fraction of `DEFECT_LIMIT`
/// (where the branch truly ends, the windows stay finite and the run
/// stops there, named).
const DOMAIN_FLOOR: f64 = 1e-3;
/// The most field steps one window keeps (its steps are stored until it
/// is accepted).
const MAX_WINDOW_STEPS: usize = 400;
/// The predictor's tolerance over the requested one, at most and at least.
const MAX_PREDICTOR_RATIO: f64 = 1e6;
const MIN_PREDICTOR_RATIO: f64 = 1.0;
/// A stiff motion whose linearisation's |trace| is below this fraction of
/// its 1-norm vibrates rather than decays (`found_stiff`).
const OSCILLATORY: f64 = 0.01;

/// The predictor: DOP853 on the motion at a looser tolerance, extended
/// step by step as the field asks for later times.
struct Predictor<'a> {
    model: &'a dyn DynModel,
    budget: &'a Budget,
    t0: f64,
    x0: Vec<f64>,
    stepper: RefCell<StepperOf<OfModel>>,
    steps: RefCell<Vec<DenseStep>>,
    cursor: Cell<usize>,
    /// The time the predictor has reached: asked at every stage of the
    /// field, it spares the stepper's borrow and two dynamic calls where
    /// no step is needed (most stages).
    reached: Cell<f64>,
    /// The first failure of the predictor (reported by the window).
    failure: RefCell<Option<Failure>>,
}

impl<'a> Predictor<'a> {
    #[allow(clippy::too_many_arguments)]
    fn new(
        model: &'a dyn DynModel,
        budget: &'a Budget,
        t0: f64,
        x0: &[f64],
        tol: Tolerance,
        h_max: f64,
        h0: Option<f64>,
        integrator: Integrator,
    ) -> Result<Self, Failure> {
        let stepper = integrator.start::<OfModel>(&ModelSystem(model), t0, x0, tol, h_max, h0)?;
        Ok(Predictor {
            model,
            budget,
            t0,
            x0: x0.to_vec(),
            stepper: RefCell::new(stepper),
            steps: RefCell::new(Vec::new()),
            cursor: Cell::new(0),
            reached: Cell::new(t0),
            failure: RefCell::new(None),
        })
    }

    fn extend_to(&self, t: f64, t_limit: f64) -> Result<(), Failure> {
        if t <= self.reached.get() {
            // Reached already: the loop below would not step.
            return Ok(());
        }
        let mut stepper = self.stepper.borrow_mut();
        let system = ModelSystem(self.model);
        while stepper.time() < t && stepper.time() < t_limit {
            stepper.step(&system, t_limit, self.budget)?;
            self.reached.set(stepper.time());
            // Every registered integrator has a continuous extension of
            // its own (only Magnus, which is not registered, has none).
            if let Some(dense) = stepper.dense_step(&system)? {
                self.steps.borrow_mut().push(dense);
            }
        }
        Ok(())
    }

    fn stats(&self) -> Stats {
        self.stepper.borrow().stats()
    }

    fn proposed_step(&self) -> f64 {
        self.stepper.borrow().proposed_step()
    }

    /// DOP853 found the motion stiff while predicting.
    fn stiffness_detected(&self) -> bool {
        self.stepper.borrow().stiffness_detected().is_some()
    }
}

/// The predictor, frozen after its window: its steps cover the window.
struct PredictorPath {
    t0: f64,
    x0: Vec<f64>,
    steps: Vec<DenseStep>,
    cursor: Cell<usize>,
}

fn eval_steps(steps: &[DenseStep], cursor: &Cell<usize>, t: f64, out: &mut [f64]) -> bool {
    if steps.is_empty() {
        return false;
    }
    let mut i = cursor.get().min(steps.len() - 1);
    while i > 0 && t < steps[i].t_old {
        i -= 1;
    }
    while i + 1 < steps.len() && t > steps[i].t_new {
        i += 1;
    }
    cursor.set(i);
    steps[i].eval(t, out);
    true
}

impl Iterate for PredictorPath {
    fn eval(&self, t: f64, out: &mut [f64]) -> Result<(), Failure> {
        if t <= self.t0 || !eval_steps(&self.steps, &self.cursor, t, out) {
            out.copy_from_slice(&self.x0);
        }
        Ok(())
    }
}

/// A window's span of time for the lazily extended predictor.
struct LivePath<'p, 'a> {
    predictor: &'p Predictor<'a>,
    t_limit: f64,
}

impl Iterate for LivePath<'_, '_> {
    fn eval(&self, t: f64, out: &mut [f64]) -> Result<(), Failure> {
        let p = self.predictor;
        if t <= p.t0 {
            out.copy_from_slice(&p.x0);
            return Ok(());
        }
        if let Err(failure) = p.extend_to(t, self.t_limit) {
            p.failure.borrow_mut().get_or_insert(failure.clone());
            return Err(failure);
        }
        let steps = p.steps.borrow();
        if !eval_steps(&steps, &p.cursor, t, out) {
            out.copy_from_slice(&p.x0);
        }
        Ok(())
    }
}

/// The accepted window, kept for dense output of its steps.
struct AcceptedWindow {
    anchor_x: Vec<f64>,
    path: PredictorPath,
    steps: Vec<StoredStep>,
    prepared: Vec<Option<DenseStep>>,
    /// The recovered state at the end of each step.
    states: Vec<Vec<f64>>,
    /// The state's continuous extension over each step, in one or more
    /// pieces, built when output asks for it (see `dense`).
    outputs: Vec<Option<Vec<DenseStep>>>,
}

impl AcceptedWindow {
    /// The window's coefficients `y` at `t` inside its step `i` that is not
    /// explicit: the step's own continuous extension (RODAS4), or a Magnus
    /// step from the step's start. Returns the linearisations it took.
    fn coefficients_at(
        &mut self,
        model: &dyn DynModel,
        i: usize,
        t: f64,
        y: &mut [f64],
    ) -> Result<usize, Failure> {
        let source = ProjectiveCoefficients::new(model, &self.path);
        if !self.steps[i].exponential_at(&source, t, y)? {
            if self.prepared[i].is_none() {
                self.prepared[i] = self.steps[i].prepare(&source)?;
            }
            if let Some(dense) = &self.prepared[i] {
                dense.eval(t, y);
            }
        }
        Ok(source.linearizations())
    }

    /// The state at `t` inside step `i` that is not explicit: the
    /// coefficients there, then the conditions. Returns the linearisations
    /// it took.
    fn state_in_step(
        &mut self,
        model: &dyn DynModel,
        i: usize,
        t: f64,
        out: &mut [f64],
    ) -> Result<usize, Failure> {
        let n = self.anchor_x.len();
        let mut y = vec![0.0; n * (n + 1)];
        let used = self.coefficients_at(model, i, t, &mut y)?;
        let source = ProjectiveCoefficients::new(model, &self.path);
        let (mut f, mut s) = (vec![0.0; n], vec![0.0; n * n]);
        let defined = source.field(&y, &mut f, &mut s).is_some();
        match recover_state(&f, &s, &self.anchor_x).filter(|_| defined) {
            Some(state) => out.copy_from_slice(&state),
            // The conditions were regular at both ends of this step;
            // between them fall back to the nearer end.
            None => out.copy_from_slice(&self.states[i]),
        }
        Ok(used)
    }

    /// The state's continuous extension over explicit step `i`: DOP853 on
    /// the motion linearised along the window's predictor, between the two
    /// recovered states, in as many pieces as meet the later one within
    /// `tol` (`dop853::dense_steps_between`). Returns the linearisations it
    /// took.
    fn build_output(
        &mut self,
        model: &dyn DynModel,
        i: usize,
        tol: Tolerance,
        scratch: &RefCell<LinearizationScratch>,
        middle: &mut MiddleScratch,
    ) -> Result<usize, Failure> {
        if self.outputs[i].is_some() {
            return Ok(0);
        }
        let t_old = self.steps[i].t_old();
        let h = self.steps[i].t_new() - t_old;
        let x_old = if i == 0 {
            &self.anchor_x
        } else {
            &self.states[i - 1]
        };
        let motion = LinearizedMotion::with_scratch(model, &self.path, scratch);
        let dense = dense_steps_between(&motion, t_old, h, x_old, &self.states[i], tol)
            .map(|(pieces, _)| refined(&motion, pieces, &self.states[i], tol, middle));
        let used = motion.linearizations();
        self.outputs[i] = Some(dense?);
        Ok(used)
    }
}

/// A run without constraints, as [`Solver::advance_kept`] sees it: no
/// state drifts from them, nothing to keep.
struct Unconstrained;

impl Keeping for Unconstrained {
    fn kept_part(&mut self, _x: &[f64], _d: &mut [f64]) -> Result<(), Failure> {
        Ok(())
    }
    fn tangent(&mut self, _t: f64, _x: &[f64], _d: &mut [f64]) -> Result<(), Failure> {
        Ok(())
    }
    fn project(&mut self, _t: f64, _x: &mut [f64]) -> Result<(), Failure> {
        Ok(())
    }
    fn drifted(&mut self, _t: f64, _x: &[f64]) -> bool {
        false
    }
}

/// Why a window ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum WindowEnd {
    Span,
    Conditioning,
    Defect,
    Length,
    /// A step's end drifted from the constraints (`Solver::advance_kept`).
    Drift,
    /// The work budget ran out inside the window: its steps so far are
    /// kept (their output is written), and the run fails after them.
    Budget,
}

pub struct QuasilinearField {
    options: FieldOptions,
    h_max: f64,
    t: f64,
    t_prev: f64,
    x: Vec<f64>,
    /// The predictor's tolerance over the requested one.
    predictor_ratio: f64,
    predictor_h: Option<f64>,
    field_h: Option<f64>,
    accepted: Option<AcceptedWindow>,
    stats: Stats,
    predictor_stats: Stats,
    windows: usize,
    passes: usize,
    linearizations: usize,
    largest_condition: f64,
    /// Storage of past windows' steps, reused.
    pool: Vec<StoredStep>,
    state_pool: Vec<Vec<f64>>,
    /// The motion or the windows' coefficients were found stiff.
    stiff: bool,
    /// ... by a fast vibration (not a fast decay): see `found_stiff`.
    oscillatory: bool,
    /// The failure that ended the last accepted window's pass (the work
    /// budget): reported by the next advance.
    pending: Option<Failure>,
    /// The global error estimate carried along the run.
    error: FieldError,
    /// The linearisation's buffers of the output between steps
    /// (`AcceptedWindow::build_output`), lent to each step's motion.
    output_scratch: RefCell<LinearizationScratch>,
    /// The buffers of the output's middle check (`middle::refined`).
    middle_scratch: MiddleScratch,
    /// The last pass's window, reopened by the next (`Window::reopen`:
    /// its DOP853 and buffers without a dozen allocations a window).
    spare_window: Option<Window>,
    /// The buffers of Newton's defect (`QuasilinearField::defect`).
    defect_scratch: Option<DefectScratch>,
}

impl QuasilinearField {
    pub fn new(options: FieldOptions, t0: f64, x0: &[f64], h_max: f64) -> QuasilinearField {
        // Newton's error after one pass is about K·δ² with δ the
        // predictor's error: a predictor near the square root of the
        // tolerance leaves it well below the tolerance.
        let ratio = (0.1 / options.tol.rtol.sqrt()).clamp(MIN_PREDICTOR_RATIO, MAX_PREDICTOR_RATIO);
        let stiff = options.stiff;
        let error = FieldError::new(x0.len(), options.tol.rtol).made_if(options.global_error);
        QuasilinearField {
            options,
            h_max,
            t: t0,
            t_prev: t0,
            x: x0.to_vec(),
            predictor_ratio: ratio,
            predictor_h: None,
            field_h: None,
            accepted: None,
            pending: None,
            stats: Stats::default(),
            predictor_stats: Stats::default(),
            windows: 0,
            passes: 0,
            linearizations: 0,
            largest_condition: 1.0,
            pool: Vec::new(),
            state_pool: Vec::new(),
            stiff,
            oscillatory: false,
            error,
            output_scratch: LinearizationScratch::new(x0.len()),
            middle_scratch: MiddleScratch::new(x0.len()),
            spare_window: None,
            defect_scratch: None,
        }
    }

    /// [`QuasilinearField::new`] in the storage of an earlier solve's
    /// field (`Integration::into_spare`, for solves repeated on one model,
    /// as direct integration's solver is kept): its last window reopened
    /// by the first pass (`Window::reopen`, as between windows), its step
    /// pools, the output's and Newton's buffers; every value as `new`
    /// sets it (the buffers forget what they held). The set-up and the
    /// drop were 5 % of rocket_mass's solve at rtol 1e-6 (h-gt7).
    pub fn renewed(
        self: Box<Self>,
        options: FieldOptions,
        t0: f64,
        x0: &[f64],
        h_max: f64,
    ) -> Box<QuasilinearField> {
        if self.x.len() != x0.len() {
            return Box::new(QuasilinearField::new(options, t0, x0, h_max));
        }
        let old = *self;
        let ratio = (0.1 / options.tol.rtol.sqrt()).clamp(MIN_PREDICTOR_RATIO, MAX_PREDICTOR_RATIO);
        let stiff = options.stiff;
        let error = FieldError::new(x0.len(), options.tol.rtol).made_if(options.global_error);
        let (mut pool, mut state_pool) = (old.pool, old.state_pool);
        if let Some(accepted) = old.accepted {
            pool.extend(accepted.steps);
            state_pool.extend(accepted.states);
        }
        let output_scratch = old.output_scratch;
        output_scratch.borrow_mut().forget();
        let mut middle_scratch = old.middle_scratch;
        middle_scratch.reset();
        let mut x = old.x;
        x.copy_from_slice(x0);
        Box::new(QuasilinearField {
            options,
            h_max,
            t: t0,
            t_prev: t0,
            x,
            predictor_ratio: ratio,
            predictor_h: None,
            field_h: None,
            accepted: None,
            pending: None,
            stats: Stats::default(),
            predictor_stats: Stats::default(),
            windows: 0,
            passes: 0,
            linearizations: 0,
            largest_condition: 1.0,
            pool,
            state_pool,
            stiff,
            oscillatory: false,
            error,
            output_scratch,
            middle_scratch,
            spare_window: old.spare_window,
            defect_scratch: old.defect_scratch,
        })
    }

    fn predictor_tolerance(&self) -> Tolerance {
        let tol = self.options.tol.scaled(self.predictor_ratio);
        Tolerance {
            rtol: tol.rtol.min(1e-3),
            atol: tol.atol.min(1e-5),
        }
    }

    /// The defect of `x1` at `t` in tolerance units (RMS); with
    /// `linearized`, `X(t, x0)` and `A` at `x0` are in the scratch already.
    fn defect(
        &self,
        model: &dyn DynModel,
        t: f64,
        x0: &[f64],
        x1: &[f64],
        linearized: bool,
        scratch: &mut DefectScratch,
    ) -> Result<f64, Failure> {
        let n = x1.len();
        if !linearized {
            scratch.a.fill(0.0);
            model.linearize(t, x0, &mut scratch.rate0, &mut scratch.a)?;
        }
        model.rhs(t, x1, &mut scratch.rate1)?;
        for i in 0..n {
            scratch.dx[i] = x1[i] - x0[i];
        }
        scratch.a.mul_vec(&scratch.dx, &mut scratch.lin);
        let tol = self.options.tol;
        let mut sum = 0.0;
        for i in 0..n {
            let r = scratch.rate1[i] - scratch.rate0[i] - scratch.lin[i];
            let scale = tol.atol + tol.rtol * x1[i].abs();
            sum += (r / scale).powi(2);
        }
        Ok((sum / n as f64).sqrt())
    }

    /// Newton's error bound a window may reach at `(t, x)`, in units of
    /// the tolerance: [`DEFECT_LIMIT`], less where the state is within
    /// that much error of the end of a constraint's branch (the argument
    /// `a` of a square root, logarithm, arcsine, …, whose 0 ends it). An
    /// error of one tolerance in component `i` moves `a` by `δa_i`; the
    /// bound keeps `Σ δa_i` times it below a tenth of `a`. Why: the
    /// tolerance is no measure of the distance to a branch's end. A
    /// constant-speed particle near the top of its arc (`y' = sqrt(c^2 -
    /// x'^2)`, examples/nonlinear_constraint_near_branch.lag, rtol 1e-6)
    /// is 1.4e-8 from the end in `x'` at t = 0.9998 with a tolerance of
    /// 1e-6 there: a window's Newton error of 0.14 tolerances, within the
    /// bound, carried the state onto the end (`c^2 - x'^2` = 3e-15) and
    /// the run stopped at t = 0.99984, where direct integration, whose
    /// errors the motion damps there, went on to the span's end.
    fn defect_limit(
        &self,
        model: &dyn DynModel,
        t: f64,
        x: &[f64],
        scratch: &mut DefectScratch,
    ) -> f64 {
        let domains = model.domains();
        if domains.is_empty() {
            return DEFECT_LIMIT;
        }
        let m = domains.len();
        scratch.domains.resize(5 * m, 0.0);
        let (values, rest) = scratch.domains.split_at_mut(2 * m);
        let (moved, trial) = rest.split_at_mut(m);
        model.domain_values(t, x, values);
        moved.fill(0.0);
        let tol = self.options.tol;
        let mut y = x.to_vec();
        for i in 0..x.len() {
            y[i] = x[i] + tol.atol + tol.rtol * x[i].abs();
            model.domain_values(t, &y, trial);
            y[i] = x[i];
            for d in 0..m {
                moved[d] += (trial[2 * d] - values[2 * d]).abs();
            }
        }
        let mut limit = DEFECT_LIMIT;
        for (d, domain) in domains.iter().enumerate() {
            let ends = matches!(
                domain.kind,
                DomainKind::Root
                    | DomainKind::Power
                    | DomainKind::Logarithm
                    | DomainKind::Arcsine
                    | DomainKind::Arccosine
            );
            let (a, da) = (values[2 * d], moved[d]);
            if ends && a > 0.0 && da > 0.0 && da.is_finite() {
                limit = limit.min(DOMAIN_FRACTION * a / da);
            }
        }
        limit.max(DOMAIN_FLOOR * DEFECT_LIMIT)
    }
}

struct DefectScratch {
    a: Matrix,
    rate0: Vec<f64>,
    rate1: Vec<f64>,
    dx: Vec<f64>,
    lin: Vec<f64>,
    x0: Vec<f64>,
    /// The constraints' domain values (`defect_limit`).
    domains: Vec<f64>,
}

impl DefectScratch {
    fn new(n: usize) -> Self {
        DefectScratch {
            a: Matrix::zeros(n, n),
            rate0: vec![0.0; n],
            rate1: vec![0.0; n],
            dx: vec![0.0; n],
            lin: vec![0.0; n],
            x0: vec![0.0; n],
            domains: Vec::new(),
        }
    }
}

/// One pass over a window, before it is accepted.
struct Pass {
    steps: Vec<StoredStep>,
    states: Vec<Vec<f64>>,
    /// Each step's local error in the state, where estimated.
    errors: Vec<Option<Vec<f64>>>,
    end: WindowEnd,
    stats: Stats,
    largest_condition: f64,
    field_h: f64,
    /// Why the window could not take its first step at all (the
    /// conditions degraded on every shortening), if it could not.
    start_failed: Option<Failure>,
}

impl Solver for QuasilinearField {
    /// Kept for the next solve ([`QuasilinearField::renewed`]).
    fn into_reusable(self: Box<Self>) -> Option<Box<dyn std::any::Any>> {
        Some(self)
    }

    fn time(&self) -> f64 {
        self.t
    }

    fn previous_time(&self) -> f64 {
        self.t_prev
    }

    fn state(&self) -> &[f64] {
        &self.x
    }

    fn advance(
        &mut self,
        model: &dyn DynModel,
        t_limit: f64,
        budget: &Budget,
    ) -> Result<(), Failure> {
        self.advance_kept(model, t_limit, budget, &mut Unconstrained)
    }

    fn advance_kept(
        &mut self,
        model: &dyn DynModel,
        t_limit: f64,
        budget: &Budget,
        keeping: &mut dyn Keeping,
    ) -> Result<(), Failure> {
        let n = self.x.len();
        if let Some(failure) = self.pending.take() {
            return Err(failure);
        }
        self.error.feed(model, f64::INFINITY);
        let mut retries = 0;
        let mut t_limit = t_limit;
        loop {
            let predictor = Predictor::new(
                model,
                budget,
                self.t,
                &self.x,
                self.predictor_tolerance(),
                self.h_max,
                self.predictor_h,
                if self.stiff && !self.oscillatory {
                    Integrator::Stiff
                } else {
                    Integrator::Explicit
                },
            )?;
            let live = LivePath {
                predictor: &predictor,
                t_limit,
            };
            let pass = self.pass(model, &live, t_limit, budget, keeping);
            self.predictor_stats += predictor.stats();
            self.predictor_h = Some(predictor.proposed_step());
            // A stiff motion: predict with RODAS4 and integrate the
            // windows' coefficients with RODAS4 from the next window on.
            if self.options.auto_stiff && predictor.stiffness_detected() {
                self.found_stiff(model);
            }
            let failure = predictor.failure.borrow_mut().take();
            let pass = match (failure, pass) {
                (None, Ok(pass)) => pass,
                // The budget ran out past the steps the window kept: they
                // are good (the predictor's failure came after them), and
                // the pass has set the failure to report next.
                (Some(_), Ok(pass)) if pass.end == WindowEnd::Budget => pass,
                (failure, pass) => {
                    let failure = failure.or(pass.err()).expect("a failure");
                    // A loose predictor can leave the motion's domain where
                    // the motion itself does not (a square root near its
                    // branch point): predict more tightly before giving up.
                    // The window may also end halfway to where it failed:
                    // ahead of a switch the predictor follows the branch the
                    // window started on (a burning rocket's mass law,
                    // `M0 − μ t`, long after its burnout, to where it
                    // vanishes), which the motion leaves at the switch.
                    let shorter = failure.time > self.t && failure.time < t_limit;
                    let retry = matches!(
                        failure.kind,
                        FailureKind::NonFiniteRate { .. }
                            | FailureKind::NonFiniteState { .. }
                            | FailureKind::StepSizeUnderflow { .. }
                            | FailureKind::NewtonNonConvergence { .. }
                            | FailureKind::SingularMassMatrix { .. }
                    ) && (self.predictor_ratio > MIN_PREDICTOR_RATIO || shorter)
                        && retries < 12;
                    if !retry {
                        return Err(super::explain(model, failure, self.t, &self.x));
                    }
                    retries += 1;
                    self.predictor_ratio = (self.predictor_ratio * 0.01).max(MIN_PREDICTOR_RATIO);
                    if shorter {
                        t_limit = self.t + 0.5 * (failure.time - self.t);
                    }
                    continue;
                }
            };
            self.passes += 1;
            self.stats += pass.stats;
            if pass.steps.is_empty() {
                // Even the first step's Newton error was too large, or its
                // coefficients were not finite: the predictor is too loose
                // for this motion, or its step too long for the
                // linearisation. Both are shortened: the predictor's first
                // step was kept from the last window, and a tighter
                // predictor accepted the same step again (the particle on a
                // circle at rtol 1e-8: one step from x = -0.45 onto the
                // pole x = 0 of its candidate's equations, accurate at its
                // end and 1e8 off in its middle, twelve times).
                retries += 1;
                self.predictor_ratio = (self.predictor_ratio * 0.1).max(MIN_PREDICTOR_RATIO);
                self.field_h = match pass.start_failed {
                    // Its shortenings ran down to nothing.
                    Some(_) => self.field_h.map(|h| 0.25 * h),
                    None => Some(0.25 * pass.field_h),
                };
                let first = predictor.steps.borrow().first().map(|s| s.t_new - s.t_old);
                if let Some(h) = first {
                    self.predictor_h = Some(0.25 * h);
                }
                if retries > 12 {
                    return Err(pass.start_failed.unwrap_or_else(|| {
                        Failure::new(
                            self.t,
                            FailureKind::FieldNotConverging {
                                correction: DEFECT_LIMIT,
                            },
                        )
                    }));
                }
                continue;
            }
            // Adapt the predictor: windows cut short by Newton's error ask
            // for a better one; windows limited by the conditions with a
            // small defect can do with a cheaper one.
            match pass.end {
                WindowEnd::Defect => {
                    self.predictor_ratio = (self.predictor_ratio * 0.25).max(MIN_PREDICTOR_RATIO)
                }
                WindowEnd::Conditioning | WindowEnd::Length => {
                    self.predictor_ratio = (self.predictor_ratio * 1.5).min(MAX_PREDICTOR_RATIO)
                }
                WindowEnd::Span | WindowEnd::Drift | WindowEnd::Budget => {}
            }
            self.field_h = Some(pass.field_h);
            self.largest_condition = self.largest_condition.max(pass.largest_condition);
            let end_state = pass
                .states
                .last()
                .cloned()
                .unwrap_or_else(|| self.x.clone());
            let end_time = pass.steps.last().map_or(self.t, StoredStep::t_new);
            let frozen = PredictorPath {
                t0: predictor.t0,
                x0: predictor.x0.clone(),
                steps: predictor.steps.take(),
                cursor: Cell::new(0),
            };
            let count = pass.steps.len();
            let ends: Vec<f64> = pass.steps.iter().map(StoredStep::t_new).collect();
            self.error
                .window(model, (self.t, &self.x), &ends, &pass.states, &pass.errors);
            if let Some(old) = self.accepted.take() {
                self.pool.extend(old.steps);
                self.state_pool.extend(old.states);
            }
            self.accepted = Some(AcceptedWindow {
                anchor_x: std::mem::replace(&mut self.x, end_state),
                path: frozen,
                steps: pass.steps,
                prepared: vec![None; count],
                states: pass.states,
                outputs: vec![None; count],
            });
            self.t_prev = self.t;
            self.t = end_time;
            self.windows += 1;
            debug_assert_eq!(self.x.len(), n);
            return Ok(());
        }
    }

    fn step_ends(&self, out: &mut Vec<f64>) {
        out.clear();
        if let Some(window) = &self.accepted {
            out.extend(
                window
                    .steps
                    .iter()
                    .map(|s| s.t_new())
                    .filter(|&t| t > self.t_prev && t < self.t),
            );
        }
        out.push(self.t);
    }

    fn dense(&mut self, model: &dyn DynModel, t: f64, out: &mut [f64]) -> Result<(), Failure> {
        let Some(window) = self.accepted.as_mut() else {
            out.copy_from_slice(&self.x);
            return Ok(());
        };
        if t >= self.t {
            out.copy_from_slice(&self.x);
            return Ok(());
        }
        if t <= self.t_prev {
            out.copy_from_slice(&window.anchor_x);
            return Ok(());
        }
        let i = window
            .steps
            .iter()
            .position(|s| t <= s.t_new())
            .unwrap_or(window.steps.len() - 1);
        if window.steps[i].is_explicit() {
            // One DOP853 step of the linearised motion between the two
            // recovered states: as accurate between the steps as direct
            // DOP853's output, where the coefficients' extension, recovered
            // through the conditions, lost up to their condition number
            // (the rocket with drag at rtol 1e-9, 101 samples: 1.8e-9 →
            // 3.3e-10, direct 1.2e-10). A stiff window's steps are too long
            // for an explicit step: there the coefficients' extension.
            self.linearizations += window.build_output(
                model,
                i,
                self.options.tol,
                &self.output_scratch,
                &mut self.middle_scratch,
            )?;
            if let Some(pieces) = &window.outputs[i] {
                let piece = pieces
                    .iter()
                    .find(|p| t <= p.t_new)
                    .unwrap_or(&pieces[pieces.len() - 1]);
                piece.eval(t, out);
            }
            return Ok(());
        }
        self.linearizations += window.state_in_step(model, i, t, out)?;
        Ok(())
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

    fn finish(&mut self, model: &dyn DynModel) {
        // The last window's steps (`FieldError::finish`).
        self.error.finish(model);
    }

    fn restart(&mut self, model: &dyn DynModel, t: f64, x: &[f64]) -> Result<(), Failure> {
        // The steps before (all of them but after an event's cut).
        self.error.feed(model, f64::INFINITY);
        self.t = t;
        self.t_prev = t;
        self.x = x.to_vec();
        self.accepted = None;
        // An event changes the regime: the step sizes learnt on the old
        // one say nothing of the new (Hairer's codes restart a
        // discontinuity with a fresh first step). Kept, a free flight's
        // 2.5 s became the first step into a soft wall (ω = 7): DOP853 far
        // past its stability on the coefficients, accepted, the velocity
        // lost, and the run ended at exit 0 with x' = -4e6 where it is 1
        // (tests/data/v2/soft_walls.lag).
        self.field_h = None;
        self.predictor_h = None;
        Ok(())
    }

    fn retake(&mut self, model: &dyn DynModel, t: f64, x: &[f64]) -> Result<(), Failure> {
        // The window from `t` is not the motion's (`FieldError::retake`).
        self.error.retake(t);
        self.restart(model, t, x)
    }

    fn restart_smooth(&mut self, model: &dyn DynModel, t: f64, x: &[f64]) -> Result<(), Failure> {
        // The new regime's rate varies on no shorter scale than the old
        // one's, and the state did not jump: the steps learnt on the old
        // regime fit the new one as well (a pendulum under a switching
        // torque restarted fresh at each of its 1,591 switches: 6,368
        // field steps, now 4,777 in its 4,776 windows). Half the proposed
        // step: the whole one cost accuracy after the kink (Coulomb
        // friction at rtol 1e-8: 2.2e-9 → 3.3e-9; with half, unchanged).
        let (field_h, predictor_h) = (self.field_h, self.predictor_h);
        self.restart(model, t, x)?;
        self.field_h = field_h.map(|h| 0.5 * h);
        self.predictor_h = predictor_h;
        Ok(())
    }

    fn project(&mut self, model: &dyn DynModel, t: f64, x: &[f64]) -> Result<(), Failure> {
        // A projection onto the constraints is no change of regime: the
        // step sizes learnt go on.
        self.error.feed(model, f64::INFINITY);
        self.t = t;
        self.t_prev = t;
        self.x = x.to_vec();
        self.accepted = None;
        Ok(())
    }

    fn segments(
        &mut self,
        model: &dyn DynModel,
    ) -> Result<Vec<crate::method::segment::Segment>, Failure> {
        let Some(window) = self.accepted.as_mut() else {
            return Ok(Vec::new());
        };
        let mut out = Vec::with_capacity(window.steps.len());
        for i in 0..window.steps.len() {
            // The same output as `dense`: the state's own extension over
            // explicit steps, the coefficients' over stiff ones.
            if window.steps[i].is_explicit() {
                self.linearizations += window.build_output(
                    model,
                    i,
                    self.options.tol,
                    &self.output_scratch,
                    &mut self.middle_scratch,
                )?;
                if let Some(pieces) = &window.outputs[i] {
                    out.extend(
                        pieces
                            .iter()
                            .map(|d| crate::method::segment::Segment::State(d.clone())),
                    );
                }
                continue;
            }
            if !matches!(window.steps[i], StoredStep::Exponential { .. })
                && window.prepared[i].is_none()
            {
                let source = ProjectiveCoefficients::new(model, &window.path);
                window.prepared[i] = window.steps[i].prepare(&source)?;
            }
            if let Some(y) = &window.prepared[i] {
                out.push(crate::method::segment::Segment::Projective {
                    y: y.clone(),
                    anchor: window.anchor_x.clone(),
                });
                continue;
            }
            // A Magnus step has no continuous extension of its own: the
            // state at the step's Chebyshev points.
            let (a, b) = (window.steps[i].t_old(), window.steps[i].t_new());
            let (mut ts, mut xs) = (Vec::with_capacity(8), Vec::with_capacity(8));
            for k in 0..8 {
                let c = 0.5 - 0.5 * (std::f64::consts::PI * k as f64 / 7.0).cos();
                let tk = a + c * (b - a);
                let mut state = vec![0.0; window.anchor_x.len()];
                self.linearizations += window.state_in_step(model, i, tk, &mut state)?;
                ts.push(tk);
                xs.push(state);
            }
            out.push(crate::method::segment::Segment::Points { t: ts, x: xs });
        }
        Ok(out)
    }

    fn keep_on_constraints(&mut self, model: &dyn DynModel, keeping: &mut dyn Keeping) {
        // The carried error projected as the state is (`FieldError::keep`).
        self.error.keep(model, keeping);
    }

    fn report(&self) -> Report {
        Report {
            method: match self.window_kind() {
                StepperKind::Stiff => "field (quasilinear, RODAS4)",
                StepperKind::Magnus => "field (quasilinear, Magnus)",
                StepperKind::Explicit => "field (quasilinear, DOP853)",
            }
            .to_string(),
            stats: Stats {
                // The estimate's propagation is the run's work too.
                rhs_evaluations: self.stats.rhs_evaluations + self.error.evaluations(),
                ..self.stats
            },
            largest_condition: Some(self.largest_condition),
            reanchorings: Some(self.windows.saturating_sub(1)),
            windows: Some(self.windows),
            passes: Some(self.passes),
            predictor: Some(self.predictor_stats),
            linearizations: self.linearizations,
            global_error: self.error.report(),
            notes: Vec::new(),
        }
    }
}

impl QuasilinearField {
    /// DOP853 found the motion or the coefficients stiff: from the next
    /// window on, RODAS4 for both; but where the stiffness is a fast
    /// vibration rather than a fast decay, the Magnus integrator for the
    /// coefficients and DOP853 for the predictor (see `window_kind`).
    /// Which of the two: the linearisation's trace is the sum of its
    /// eigenvalues' real parts, about 0 for an undamped vibration
    /// however fast and about −|λ| for a fast decaying mode; against its
    /// size (the 1-norm, at least the spectral radius) it tells them
    /// apart (stiff_joint.lag: trace/size about 1e-5; x'' + 1000x' + x:
    /// about 1).
    fn found_stiff(&mut self, model: &dyn DynModel) {
        if self.stiff {
            return;
        }
        self.stiff = true;
        let n = self.x.len();
        let (mut rate, mut a) = (vec![0.0; n], Matrix::zeros(n, n));
        if model.linearize(self.t, &self.x, &mut rate, &mut a).is_ok() {
            let trace: f64 = (0..n).map(|i| a[(i, i)]).sum();
            let size = a.one_norm();
            self.oscillatory = size.is_finite() && trace.abs() <= OSCILLATORY * size;
        }
    }

    /// The integrator of the windows' coefficients: DOP853 until the
    /// motion or the coefficients are found stiff; then RODAS4, or the
    /// Magnus integrator where the stiffness is a fast vibration (auto;
    /// or always with `--integrator magnus`). Why Magnus: the projective
    /// coefficient system is linear, and an exponential integrator
    /// follows its fast modes exactly where they are constant, so a stiff
    /// joint's vibration (k/m = 1e5, about 450 rad/s) does not hold its
    /// step; RODAS4 (order 4, damping what it cannot resolve, an LU of
    /// the N(N+1) system a step) took 7,049 steps and 287 ms on
    /// tests/data/stiff_joint.lag at rtol 1e-6 (error 1.1e-4), Magnus
    /// windows with a DOP853 predictor 470 steps and 4.9–9.5 ms under
    /// load (1.25e-4; direct DOP853 1.1 ms, 1.1e-4).
    fn window_kind(&self) -> StepperKind {
        if self.options.magnus || (self.stiff && self.oscillatory && self.options.auto_stiff) {
            StepperKind::Magnus
        } else if self.stiff {
            StepperKind::Stiff
        } else {
            StepperKind::Explicit
        }
    }

    /// One pass of the field along `iterate` from the current anchor,
    /// until the window ends.
    fn pass<I: Iterate>(
        &mut self,
        model: &dyn DynModel,
        iterate: &I,
        t_limit: f64,
        budget: &Budget,
        keeping: &mut dyn Keeping,
    ) -> Result<Pass, Failure> {
        let n = self.x.len();
        let source = ProjectiveCoefficients::new(model, iterate);
        let kind = self.window_kind();
        let mut window = match self.spare_window.take() {
            Some(mut window) => {
                let (t, x) = (self.t, &self.x);
                window.reopen(&source, &self.options, t, x, self.field_h, self.h_max, kind)?;
                window
            }
            None => Window::open(
                &source,
                &self.options,
                self.t,
                &self.x,
                self.field_h,
                self.h_max,
                kind,
            )?,
        };
        let mut steps: Vec<StoredStep> = Vec::new();
        let mut states: Vec<Vec<f64>> = Vec::new();
        let mut errors: Vec<Option<Vec<f64>>> = Vec::new();
        let mut scratch = match self.defect_scratch.take() {
            Some(scratch) if scratch.rate0.len() == n => scratch,
            _ => DefectScratch::new(n),
        };
        let mut bound = 0.0;
        let (mut t_last, mut defect_last) = (self.t, 0.0);
        let mut shortenings = 0;
        let mut largest_condition = 1.0_f64;
        // The last step kept: its time and the budget's draws by then.
        let mut kept_at = (self.t, budget.used());
        let mut start_failed = None;
        let end = loop {
            if window.time() >= t_limit {
                break WindowEnd::Span;
            }
            if steps.len() >= MAX_WINDOW_STEPS {
                break WindowEnd::Length;
            }
            let step = match window.step(&source, &self.options, t_limit, budget) {
                Err(failure)
                    if !steps.is_empty()
                        && matches!(failure.kind, FailureKind::StepBudgetExhausted { .. }) =>
                {
                    self.pending = Some(budget_spent_in_window(failure, kept_at, budget));
                    break WindowEnd::Budget;
                }
                step => step?,
            };
            match step {
                WindowStep::Accepted => {
                    let t = window.time();
                    // The step's last stage linearised at its end.
                    let s = &mut scratch;
                    let linearized = source.linearization_at(t, &mut s.x0, &mut s.rate0, &mut s.a);
                    if !linearized {
                        iterate.eval(t, &mut scratch.x0)?;
                    }
                    let x0 = std::mem::take(&mut scratch.x0);
                    let state = window.state();
                    let defect = self.defect(model, t, &x0, state, linearized, &mut scratch);
                    scratch.x0 = x0;
                    let defect = defect?;
                    let grown = bound + 0.5 * (defect + defect_last) * (t - t_last);
                    if grown > self.defect_limit(model, t, window.state(), &mut scratch) {
                        break WindowEnd::Defect;
                    }
                    bound = grown;
                    t_last = t;
                    defect_last = defect;
                    largest_condition = largest_condition.max(window.recovered().condition);
                    // Reuse the storage of the last window's steps.
                    let mut stored = self.pool.pop().unwrap_or_default();
                    window.store_step(&source, &mut stored)?;
                    steps.push(stored);
                    let mut state = self.state_pool.pop().unwrap_or_default();
                    state.clear();
                    state.extend_from_slice(window.state());
                    states.push(state);
                    // The local error is read by the estimate alone.
                    errors.push(
                        self.error
                            .is_on()
                            .then(|| {
                                let mut local = vec![0.0; n];
                                window
                                    .local_error(self.options.tol, &mut local)
                                    .then_some(local)
                            })
                            .flatten(),
                    );
                    kept_at = (t, budget.used());
                    // A step off holonomic constraints ends the window:
                    // the run projects its end as it projects a step's,
                    // where a window carried it on, its drift growing
                    // unchecked (a double pendulum in Cartesian
                    // coordinates, two rods as holonomic constraints, at
                    // rtol 1e-7: a rod's velocity residual 4e-8 → 6e-5
                    // over one window of 41 steps, the run 1,600 rtol off
                    // at its end; BENCHMARKS §10z3). Velocity constraints
                    // alone are left to the window's end: ended on their
                    // drift, the circling knife edge went 0.3–0.9 → 7–13
                    // rtol off at rtol 1e-6 … 1e-9 and Chaplygin's sleigh
                    // 1.0–1.3 → 3–4 (measured, not understood).
                    if model.keeps_positions() && keeping.drifted(t, window.state()) {
                        break WindowEnd::Drift;
                    }
                }
                WindowStep::Ended if window.steps() == 0 => {
                    shortenings += 1;
                    let h = 0.25 * window.proposed_step();
                    if shortenings > MAX_SHORTENINGS || underflows(self.t, h) {
                        // Retried from a shorter predictor step (`advance`)
                        // before it is reported.
                        start_failed = Some(window.degraded());
                        break WindowEnd::Conditioning;
                    }
                    window.propose_step(h);
                }
                WindowStep::Ended => break WindowEnd::Conditioning,
            }
        };
        self.linearizations += source.linearizations();
        if self.options.auto_stiff && window.stiffness_detected() {
            self.found_stiff(model);
        }
        let pass = Pass {
            steps,
            states,
            errors,
            end,
            stats: window.stats(),
            largest_condition,
            field_h: window.proposed_step(),
            start_failed,
        };
        self.spare_window = Some(window);
        self.defect_scratch = Some(scratch);
        Ok(pass)
    }
}

/// The work budget's failure inside a window whose steps are kept up to
/// `(t, draws)`: stalled there if no step was kept in the budget's second
/// half (the predictor chattered on past a point where the motion is not
/// smooth), else as the budget judged the run. (The driver reports it at
/// the time the solution stands.)
fn budget_spent_in_window(failure: Failure, (t, draws): (f64, usize), budget: &Budget) -> Failure {
    let FailureKind::StepBudgetExhausted { steps, stalled } = failure.kind else {
        return failure;
    };
    let stalled = if draws <= budget.limit() / 2 {
        Some((t, t))
    } else {
        stalled
    };
    Failure::new(
        failure.time,
        FailureKind::StepBudgetExhausted { steps, stalled },
    )
}
