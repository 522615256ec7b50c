//! The interface between a method (direct integration, the field method)
//! and the run driver: advance one step, interpolate within it, restart at
//! an event, report the work.

use crate::failure::Failure;
use crate::model::DynModel;
use crate::ode::budget::Budget;
use crate::ode::tolerance::Stats;

/// What a method did, for the run summary.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Report {
    /// e.g. `field (DOP853)`, `direct (DOP853 → RODAS4)`.
    pub method: String,
    /// Work of every integrator the method ran (for the field: the
    /// coefficient steps, and the predictor's under `predictor`).
    pub stats: Stats,
    /// Field: the largest condition number of the conditions (13).
    pub largest_condition: Option<f64>,
    /// Field: how many times the field was re-anchored.
    pub reanchorings: Option<usize>,
    /// Quasilinear field: windows accepted, passes over them, and the
    /// predictor's work.
    pub windows: Option<usize>,
    pub passes: Option<usize>,
    pub predictor: Option<Stats>,
    /// Evaluations of `X` with `∂X/∂x` (the field's linearisations).
    pub linearizations: usize,
    /// Lines for the summary (a switch of integrator, a stiffness note).
    pub notes: Vec<String>,
    /// The global error estimate the method carried.
    pub global_error: Option<GlobalErrorEstimate>,
}

/// The global error a method estimated along its run
/// (`dop853::global_error`), for the summary.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GlobalErrorEstimate {
    /// The estimated error at the run's end, relative to `max(|x|, 1)`
    /// component by component (the measure of the error against an exact
    /// solution; a sum of the steps' local estimates, so also the largest
    /// over the run).
    pub largest: f64,
    /// The run's relative tolerance.
    pub rtol: f64,
    /// False when part of the run was not accounted for (RODAS4's steps).
    pub complete: bool,
}

impl GlobalErrorEstimate {
    /// The estimate of a run in two parts (restarted from a state given
    /// from outside): the errors carried into the restart stay, so the
    /// sums add.
    pub fn sum(a: Option<Self>, b: Option<Self>) -> Option<Self> {
        match (a, b) {
            (Some(a), Some(b)) => Some(GlobalErrorEstimate {
                largest: a.largest + b.largest,
                rtol: b.rtol,
                complete: a.complete && b.complete,
            }),
            (a, b) => a.or(b),
        }
    }
}

/// The linearised projections onto the constraints, as
/// [`Solver::keep_on_constraints`] is given them: each replaces a small
/// change `d` of a state `x` in place (and leaves it as it is on failure,
/// which is reported).
pub trait Keeping {
    /// The part of `d` at `x` (the last advance's end) that the holonomic
    /// constraints keep (`run::keep::Keeper::kept_part`).
    fn kept_part(&mut self, x: &[f64], d: &mut [f64]) -> Result<(), Failure>;
    /// The part of `d` at `(t, x)` that the run's whole projection keeps,
    /// velocity constraints included (`run::keep::Keeper::tangent`): what
    /// of an error carried to `x` survives the projections.
    fn tangent(&mut self, t: f64, x: &[f64], d: &mut [f64]) -> Result<(), Failure>;
    /// Projects `x` at `t` onto the constraints in place, as the run's
    /// state is projected (`run::keep::Keeper::put_on`: no distance
    /// recorded): the field's reference carried alongside the run
    /// (`global_error::growth::Growth::step_alongside`).
    fn project(&mut self, t: f64, x: &mut [f64]) -> Result<(), Failure>;
    /// Whether `x` at `t`, a state inside an advance, has drifted from the
    /// holonomic constraints as far as the run projects a step's end
    /// (`run::keep::Keeper::drifted`; a state the measure fails on counts
    /// as drifted, and the run judges it at the advance's end).
    fn drifted(&mut self, t: f64, x: &[f64]) -> bool;
}

/// A method advancing a model's motion step by step.
pub trait Solver {
    /// The time of the last accepted step's end.
    fn time(&self) -> f64;
    /// The time of the last accepted step's start.
    fn previous_time(&self) -> f64;
    /// The state at [`Solver::time`].
    fn state(&self) -> &[f64];
    /// Takes one step (never past `t_limit`, landing on it exactly when
    /// reached), drawing on `budget`.
    fn advance(
        &mut self,
        model: &dyn DynModel,
        t_limit: f64,
        budget: &Budget,
    ) -> Result<(), Failure>;
    /// [`Solver::advance`] in a run that keeps constraints: a method
    /// whose advance takes several steps (the quasilinear field's window)
    /// ends it after a step that `keeping` finds drifted from holonomic
    /// constraints, so that the run projects it as it projects a step's
    /// end (SPEC §2.3).
    fn advance_kept(
        &mut self,
        model: &dyn DynModel,
        t_limit: f64,
        budget: &Budget,
        _keeping: &mut dyn Keeping,
    ) -> Result<(), Failure> {
        self.advance(model, t_limit, budget)
    }
    /// The state at `t` in `[previous_time, time]`.
    fn dense(&mut self, model: &dyn DynModel, t: f64, out: &mut [f64]) -> Result<(), Failure>;
    /// The ends of the integrator's own steps within the last advance, in
    /// order, the last being [`Solver::time`] (into `out`, cleared first).
    /// One advance of the quasilinear field covers a whole window of
    /// steps: the driver looks at the switching functions within each of
    /// them, as it does within a step of direct integration, or an
    /// oscillation inside a window hides its crossings.
    fn step_ends(&self, out: &mut Vec<f64>) {
        out.clear();
        out.push(self.time());
    }
    /// An event at `t` within the last advance, where the run goes on
    /// from `x` (read from [`Solver::dense`]), told before the regime
    /// changes: the advance's motion ends there (a method carrying its
    /// errors along the motion propagates them to `t` only).
    fn cut(&mut self, _model: &dyn DynModel, _t: f64, _x: &[f64]) {}
    /// After [`Solver::cut`] at an event and before the restart: the
    /// error a method carries along the motion, if any, changed by `jump`
    /// (the event time's saltation and an impact's reset,
    /// `run::saltation`). A `jump` that fails leaves it as it was: the
    /// estimate never fails a run.
    fn carry_error_through_event(
        &mut self,
        _jump: &mut dyn FnMut(&mut [f64]) -> Result<(), Failure>,
    ) {
    }
    /// Starts afresh from `(t, x)` (after an event changed the regime).
    fn restart(&mut self, model: &dyn DynModel, t: f64, x: &[f64]) -> Result<(), Failure>;
    /// Starts again from `(t, x)`, the start of the last advance, whose
    /// step is not the motion (a constraint's pivot crossed zero or became
    /// poor within it, `run::regime::pivot_crossed`): a method that
    /// carries a global error estimate drops that step's error.
    fn retake(&mut self, model: &dyn DynModel, t: f64, x: &[f64]) -> Result<(), Failure> {
        self.restart(model, t, x)
    }
    /// Whether a step that took a constraint's pivot from good to poor is
    /// taken again from its start with the better candidate
    /// (`run::regime::pivot_crossed`): where the method's error estimate
    /// cannot see such a step's error. DOP853's embedded estimate cannot
    /// (the rate divides by the falling pivot); the field measures each
    /// window's error against a reference step, and a window retaken
    /// whole restarts its step sizes (a particle on a circle at rtol 1e-10
    /// retaken at every quarter turn ended on a step underflow).
    fn retakes_steps_into_poor_pivots(&self) -> bool {
        false
    }
    /// [`Solver::restart`] after an event that left the state where it was
    /// and the rate's scale (its Jacobian's norm) within twice the old: a
    /// method may keep the step sizes it had learnt.
    fn restart_smooth(&mut self, model: &dyn DynModel, t: f64, x: &[f64]) -> Result<(), Failure> {
        self.restart(model, t, x)
    }
    /// Goes on from `x`, the state at [`Solver::time`] projected onto the
    /// constraints: no discontinuity, so a method may keep what it has
    /// learnt of the step sizes.
    fn project(&mut self, model: &dyn DynModel, t: f64, x: &[f64]) -> Result<(), Failure> {
        self.restart(model, t, x)
    }
    /// Takes the run's projection onto the constraints into account for
    /// the last advance: `keeping` replaces a small change `d` of a state
    /// by the part of it that the constraints keep (the part a projection
    /// does not remove). Called after every advance of a run that keeps
    /// constraints; direct integration passes its steps' local errors
    /// and the error it carries along the motion through it, for a drift
    /// off the constraints is projected away, not carried to the run's
    /// end.
    fn keep_on_constraints(&mut self, _model: &dyn DynModel, _keeping: &mut dyn Keeping) {}
    /// The run reached its end (`run::integration`): a method whose
    /// global error estimate waits for the next advance adds what it
    /// holds.
    fn finish(&mut self, _model: &dyn DynModel) {}
    /// The work so far.
    fn report(&self) -> Report;

    /// The continuous extension of the last advance, as values that outlive
    /// the solver (for [`crate::run::solution::Solution`]).
    fn segments(
        &mut self,
        model: &dyn DynModel,
    ) -> Result<Vec<crate::method::segment::Segment>, Failure>;

    /// Follows other initial states through the same field (an ensemble,
    /// exact for an affine motion's field); `false` when the method
    /// cannot. A method that estimates its members
    /// ([`Solver::member_estimates`]) is not exact on them.
    fn track_members(
        &mut self,
        _members: crate::ensemble::States,
        _tol: crate::ode::tolerance::Tolerance,
    ) -> bool {
        false
    }

    /// Each tracked member's largest local error in units of the
    /// tolerance (infinite: the method could not follow it, and it must be
    /// integrated on its own); `None` where the members are exact (an
    /// affine motion's field).
    fn member_estimates(&self) -> Option<Vec<f64>> {
        None
    }

    /// The tracked members' states at `t` in `[previous_time, time]`, into
    /// `out` (reused from sample to sample: ten thousand members are a
    /// buffer that should not be allocated anew at every output time).
    fn members_at(
        &mut self,
        _model: &dyn DynModel,
        t: f64,
        _out: &mut crate::ensemble::States,
    ) -> Result<(), Failure> {
        Err(Failure::new(t, crate::failure::FailureKind::NotAffine))
    }

    /// The solver as a value whose storage a later solve may reuse (the
    /// run downcasts it to the solvers it can renew: direct integration's);
    /// `None` for the methods that are made anew.
    fn into_reusable(self: Box<Self>) -> Option<Box<dyn std::any::Any>> {
        None
    }
}
