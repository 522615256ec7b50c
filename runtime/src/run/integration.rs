//! A steppable integration: one object that holds a run's state — the
//! method's solver, the regime (modes and branches), events and impacts,
//! the constraint keeper and watch, the work budget — and advances it to
//! any time asked for, hands back the state there, and restarts from a
//! state the caller gives. Every run is a loop over it: the command line,
//! `solve`, the report, the ensemble's direct runs ([`crate::run::run`]).
//!
//! Where the caller stops does not change the steps. The steps are limited
//! only by the end of the span given when the integration is made (and by
//! the switching functions' pace), never by the times asked for: a time
//! inside a step is read from that step's continuous extension, as the
//! command line's output always was. So `advance_to(t1); advance_to(t2)`
//! takes the steps `advance_to(t2)` takes, to the bit
//! (`runtime/tests/integration.rs`).
//!
//! A step is handled in two halves, and the second waits for the caller.
//! The first takes the step, looks for events in it, and settles how far
//! its continuous extension is the solution (to the step's end, to an
//! event, or to where a constraint's branch ended). The second — the
//! event's resets and restart, the projection onto the constraints, a
//! change of candidates — changes the solver's state, after which the
//! step's continuous extension is gone: it runs only when the caller asks
//! for a time past the step. Samples within a step are thus read before
//! its end is acted on, exactly as the run loop this object replaces
//! read them.

use crate::choice::{IntegratorChoice, Method};
use crate::failure::{Failure, FailureKind};
use crate::linalg::Matrix;
use crate::method::direct::Direct;
use crate::method::field::affine::AffineField;
use crate::method::field::quasilinear::QuasilinearField;
use crate::method::field::FieldOptions;
use crate::method::solver::{Keeping, Report, Solver};
use crate::model::{DynModel, Regime};
use crate::ode::budget::Budget;
use crate::ode::tolerance::Tolerance;
use crate::run::diagnosis::{check_masses, diagnose, near_singular_configuration, MassScale};
use crate::run::events::{locate, SwitchPace};
use crate::run::impacts::{AtEvent, Impacts};
use crate::run::keep::Keeper;
use crate::run::options::{Ending, Options, Outcome};
use crate::run::progress::Progress;
use crate::run::regime::{
    best_mode, check_initial_candidates, initial_branches, pivot_crossed, pivot_volumes,
    switch_candidates, PivotCrossing,
};
use crate::run::solution::Piece;
use crate::run::watch::ConstraintWatch;

/// Why [`Integration::advance_to`] returned.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Advance {
    /// The integration stands at this time (the one asked for);
    /// [`Integration::state`] is the state there.
    Reached(f64),
    /// The motion ended before the time asked for: `stop when` became
    /// true, or impacts left it on their boundary. [`Integration::t`] and
    /// [`Integration::state`] are where it ended (after the impact's
    /// reset); asking again gives the same answer.
    Ended(Ending),
}

/// The model an integration works on: the caller's, or its own.
enum Held<'m> {
    Borrowed(&'m mut dyn DynModel),
    Owned(Box<dyn DynModel>),
}

impl Held<'_> {
    fn get(&self) -> &dyn DynModel {
        match self {
            Held::Borrowed(m) => &**m,
            Held::Owned(m) => &**m,
        }
    }

    fn get_mut(&mut self) -> &mut dyn DynModel {
        match self {
            Held::Borrowed(m) => &mut **m,
            Held::Owned(m) => &mut **m,
        }
    }
}

/// What a run that can step holds (made at the start and at every
/// restart).
struct Stepping {
    solver: Box<dyn Solver>,
    watch: ConstraintWatch,
    /// The mass matrix's scale at the start when computed up front (a
    /// regime that may change), else computed when a failure asks.
    early_scale: Option<MassScale>,
    g_now: Vec<f64>,
    x_event: Vec<f64>,
    step_ends: Vec<f64>,
    pace: SwitchPace,
    /// After a step across a vanishing pivot: how far the retry may reach.
    pivot_limit: Option<f64>,
    /// The functions at the last step's start and quarters, for the pace.
    g_quarters: Vec<Vec<f64>>,
    impacts: Impacts,
}

/// What a finished integration leaves for the next solve of the same
/// model ([`Integration::into_spare`], [`Integration::new_reusing`]): its
/// storage, not its state. A solve made in it is the solve
/// [`Integration::new`] makes, bit for bit; a short solve (the paper's 6
/// steps and 11 samples at rtol 1e-3) spent about a sixth of its
/// instructions setting up and dropping, more than half of that making
/// and freeing this storage (docs/BENCHMARKS.md §10i).
#[derive(Default)]
pub struct Spare {
    keeper: Option<Keeper>,
    solver: Option<Box<Direct>>,
    field: Option<Box<QuasilinearField>>,
    x_start: Vec<f64>,
    x: Vec<f64>,
    x_event: Vec<f64>,
    g_quarters: Vec<Vec<f64>>,
}

/// The parts of [`Spare`] that [`Integration::start`] makes anew.
#[derive(Default)]
struct SpareStepping {
    solver: Option<Box<Direct>>,
    field: Option<Box<QuasilinearField>>,
    x_event: Vec<f64>,
    g_quarters: Vec<Vec<f64>>,
}

/// What the second half of a step does.
enum Then {
    /// The event located at `t_event` (searched from `t_from`).
    Event {
        t_from: f64,
        t_event: f64,
        switches: Vec<usize>,
    },
    /// An ordinary step: keep the constraints, change candidates.
    Step,
    /// A constraint's branch ended within the step: the run stops.
    Fail(Box<Failure>),
}

/// A step whose first half is done: its continuous extension is the
/// solution up to `until`.
struct Pending {
    until: f64,
    /// The step's end.
    tb: f64,
    /// A failure to read a sample is diagnosed as a failure of the step
    /// (ordinary steps), or passed on as it is (steps that end in an
    /// event), as the run loop did.
    diagnose: bool,
    then: Then,
}

/// A run that advances on request. See the module's documentation.
pub struct Integration<'m> {
    model: Held<'m>,
    options: Options,
    end: f64,
    /// Where the integration last started or restarted.
    t_start: f64,
    /// Where it was made: a restart may go back as far as here (an FMU's
    /// saved state from before a later restart).
    t_first: f64,
    x_start: Vec<f64>,
    budget: Budget,
    regime: Regime,
    keeper: Option<Keeper>,
    volumes: Vec<f64>,
    stepping: Option<Stepping>,
    pending: Option<Pending>,
    /// The run is over: the span's end, `stop when`, or a failure.
    done: Option<Result<Ending, Failure>>,
    events: usize,
    /// Where the caller stands, and the state there.
    t: f64,
    x: Vec<f64>,
    progress: Progress,
    /// The time the caller last asked for: with `step_to_times`, no step
    /// passes it.
    target: f64,
    pieces: Option<Vec<Piece>>,
    /// The work of the solvers before the last restart.
    earlier: Option<Report>,
}

impl<'m> Integration<'m> {
    /// An integration of `model` (whose regime it sets as it goes) from
    /// `(t0, x0)` over the span up to `end`. Problems of the start (a mass
    /// at or below zero, a constraint undefined there, a method that
    /// cannot start) are reported by the first advance past `t0`, as a
    /// run reports them after its first row.
    pub fn new(
        model: &'m mut dyn DynModel,
        options: &Options,
        t0: f64,
        end: f64,
        x0: &[f64],
    ) -> Integration<'m> {
        Integration::with(
            Held::Borrowed(model),
            options,
            t0,
            end,
            x0,
            Spare::default(),
        )
    }

    /// [`Integration::new`] in the storage an earlier integration left
    /// ([`Integration::into_spare`]): the same integration, its buffers
    /// (the solver's, the keeper's, the states') reused instead of
    /// allocated. For solves repeated on one model.
    pub fn new_reusing(
        model: &'m mut dyn DynModel,
        options: &Options,
        t0: f64,
        end: f64,
        x0: &[f64],
        spare: Spare,
    ) -> Integration<'m> {
        Integration::with(Held::Borrowed(model), options, t0, end, x0, spare)
    }

    /// The storage this integration holds, for the next solve
    /// ([`Integration::new_reusing`]).
    pub fn into_spare(mut self) -> Spare {
        let (solver, field, x_event, g_quarters) = match self.stepping.take() {
            Some(s) => {
                // Direct integration's solver and the quasilinear field
                // are kept for the next solve (the field's set-up and drop
                // were 5 % of rocket_mass's solve at rtol 1e-6, h-gt7).
                let (solver, field) = match s.solver.into_reusable() {
                    Some(any) => match any.downcast::<Direct>() {
                        Ok(direct) => (Some(direct), None),
                        Err(any) => (None, any.downcast::<QuasilinearField>().ok()),
                    },
                    None => (None, None),
                };
                (solver, field, s.x_event, s.g_quarters)
            }
            None => (None, None, Vec::new(), Vec::new()),
        };
        Spare {
            keeper: self.keeper.take(),
            solver,
            field,
            x_start: std::mem::take(&mut self.x_start),
            x: std::mem::take(&mut self.x),
            x_event,
            g_quarters,
        }
    }

    fn with(
        model: Held<'m>,
        options: &Options,
        t0: f64,
        end: f64,
        x0: &[f64],
        spare: Spare,
    ) -> Integration<'m> {
        let budget = Budget::new(options.max_steps);
        budget.accepted_to(t0);
        let Spare {
            keeper,
            solver,
            field,
            x_start,
            x,
            x_event,
            g_quarters,
        } = spare;
        let mut integration = Integration {
            keeper: Keeper::new_reusing(model.get(), options.tol, keeper),
            model,
            options: options.clone(),
            end,
            t_start: t0,
            t_first: t0,
            // Both set by `start`.
            x_start,
            budget,
            regime: Regime::default(),
            volumes: Vec::new(),
            stepping: None,
            pending: None,
            done: None,
            events: 0,
            t: t0,
            x,
            progress: Progress::new(false, t0, end),
            target: end,
            pieces: None,
            earlier: None,
        };
        integration.start_in(
            t0,
            x0,
            SpareStepping {
                solver,
                field,
                x_event,
                g_quarters,
            },
        );
        integration
    }

    /// Sets the regime at `(t0, x0)` and makes the method's solver there.
    fn start(&mut self, t0: f64, x0: &[f64]) {
        self.start_in(t0, x0, SpareStepping::default());
    }

    /// [`Integration::start`], its solver and buffers made in `spare`'s
    /// storage (the same values).
    fn start_in(&mut self, t0: f64, x0: &[f64], spare: SpareStepping) {
        let model = self.model.get_mut();
        let span = self.end - t0;
        let h_max = if span > 0.0 { span } else { 1.0 };
        let mode = best_mode(model, t0, x0).0;
        let mut branches = initial_branches(model, t0, x0);
        let guards = crate::run::impacts::touching_at_start(model, mode, t0, x0, &mut branches);
        self.regime = Regime { mode, branches };
        model.set_regime(&self.regime);
        self.volumes = pivot_volumes(model, t0, x0);
        (self.t_start, self.t) = (t0, t0);
        self.x_start.clear();
        self.x_start.extend_from_slice(x0);
        self.x.clear();
        self.x.extend_from_slice(x0);
        self.pending = None;
        self.done = None;
        self.stepping = None;
        if model.switches() > 0 && model.stop(&self.regime.branches) {
            self.done = Some(Ok(Ending::Stopped(t0)));
            return;
        }
        let model = &*model;
        let started = (|| {
            check_masses(model, t0, x0)?;
            let watch = ConstraintWatch::start(model, t0, x0)?;
            // The mass matrix's scale at the start, which only the
            // diagnosis of a failure reads: an LU and a norm estimate,
            // computed up front only when the regime (on which the mass
            // matrix may depend) can change during the run, else when a
            // failure asks for it (a tenth of a small model's solve).
            let regime_may_change = model.switches() > 0 || !model.constraints().is_empty();
            let early_scale = regime_may_change.then(|| MassScale::at(model, t0, x0));
            let SpareStepping {
                solver,
                field,
                mut x_event,
                mut g_quarters,
            } = spare;
            let solver = make_solver_reusing(model, &self.options, t0, x0, h_max, solver, field);
            let solver = solver.map_err(|f| {
                let scale = early_scale.unwrap_or_else(|| MassScale::at(model, t0, x0));
                watch.diagnose(model, diagnose(model, f, x0, &scale), t0, x0)
            })?;
            let mut pace = SwitchPace::default();
            probe_pace(model, t0, x0, self.end - t0, &mut pace);
            let g_now = vec![0.0; model.switches()];
            // `vec![g_now.clone(); 4]` and `vec![0.0; n]`, in storage kept.
            g_quarters.resize_with(4, Vec::new);
            for g in &mut g_quarters {
                g.clear();
                g.resize(g_now.len(), 0.0);
            }
            x_event.clear();
            x_event.resize(x0.len(), 0.0);
            Ok(Stepping {
                solver,
                watch,
                early_scale,
                g_quarters,
                g_now,
                x_event,
                step_ends: Vec::new(),
                pace,
                pivot_limit: None,
                impacts: Impacts::starting_on_boundaries(model, guards),
            })
        })();
        match started {
            Ok(stepping) => {
                self.progress = Progress::new(self.options.progress, t0, self.end);
                self.stepping = Some(stepping);
            }
            Err(failure) => self.done = Some(Err(failure)),
        }
    }

    /// Keeps every step's continuous extension (for
    /// [`crate::run::solution::Solution`]; memory grows with the steps).
    pub fn keep_pieces(&mut self) {
        self.pieces.get_or_insert_with(Vec::new);
    }

    /// The pieces kept since [`Integration::keep_pieces`].
    pub fn take_pieces(&mut self) -> Vec<Piece> {
        self.pieces.take().unwrap_or_default()
    }

    /// The model in its current regime (for outputs at the state).
    pub fn model(&self) -> &dyn DynModel {
        self.model.get()
    }

    /// The time the integration stands at.
    pub fn t(&self) -> f64 {
        self.t
    }

    /// The state at [`Integration::t`], on the constraints.
    pub fn state(&self) -> &[f64] {
        &self.x
    }

    /// The end of the span the steps are limited to.
    pub fn end(&self) -> f64 {
        self.end
    }

    /// Whether the run is over (the span's end, an ending, a failure).
    pub fn finished(&self) -> Option<&Result<Ending, Failure>> {
        self.done.as_ref()
    }

    /// Advances to `t` (from where the integration stands up to the end
    /// of its span), stepping only as far as needed: the state at `t` is
    /// read from the continuous extension of the step that covers it.
    pub fn advance_to(&mut self, t: f64) -> Result<Advance, Failure> {
        // A failure stands before any question of where `t` lies: a run that
        // could not start (a singular mass matrix at t0) reports why, not
        // that t0 is "outside" its span.
        if let Some(Err(failure)) = &self.done {
            return Err(failure.clone());
        }
        if t == self.t {
            return Ok(Advance::Reached(t));
        }
        if !(t > self.t && t <= self.end) {
            return Err(Failure::new(
                t,
                FailureKind::OutsideSpan {
                    from: self.t,
                    to: self.end,
                },
            ));
        }
        self.target = t;
        loop {
            match &self.done {
                Some(Ok(Ending::End)) => return Ok(Advance::Reached(self.t)),
                Some(Ok(ending)) => return Ok(Advance::Ended(*ending)),
                Some(Err(failure)) => return Err(failure.clone()),
                None => {}
            }
            let result = match &self.pending {
                Some(p) if t <= p.until => {
                    let sampled = self.sample(t);
                    if sampled.is_ok() {
                        return Ok(Advance::Reached(t));
                    }
                    sampled
                }
                Some(_) => self.finish_step(),
                None if self.solver().time() >= self.end => {
                    self.reach_end();
                    Ok(())
                }
                None => self.step(),
            };
            if let Err(failure) = result {
                self.progress.finish();
                self.done = Some(Err(failure));
            }
        }
    }

    /// Runs to the end of the span (or the motion's end), and returns what
    /// the run did.
    pub fn finish(&mut self) -> Result<Outcome, Failure> {
        while self.done.is_none() {
            let result = if self.pending.is_some() {
                self.finish_step()
            } else if self.solver().time() >= self.end {
                self.reach_end();
                Ok(())
            } else {
                self.step()
            };
            if let Err(failure) = result {
                self.progress.finish();
                self.done = Some(Err(failure));
            }
        }
        match &self.done {
            Some(Err(failure)) => Err(failure.clone()),
            _ => Ok(self.outcome()),
        }
    }

    /// The work so far, and how the run ended (`Ending::End` while it
    /// goes on).
    pub fn outcome(&self) -> Outcome {
        let report = match &self.stepping {
            Some(s) => s.solver.report(),
            None => Report {
                // The summary names the method even when it took no step.
                method: format!(
                    "{} (no step: stopped at the start)",
                    self.options.method.name()
                ),
                ..Report::default()
            },
        };
        Outcome {
            report: match &self.earlier {
                Some(earlier) => merged(earlier, report),
                None => report,
            },
            ending: match self.done {
                Some(Ok(ending)) => ending,
                _ => Ending::End,
            },
            events: self.events,
            budget_used: self.budget.used(),
            kept: self.keeper.as_ref().map(|k| k.kept()),
        }
    }

    /// Goes on from `(t, x)`, a state the caller gives (the motion changed
    /// from outside): the regime is chosen there afresh, the method starts
    /// there (the field re-anchored at `x`), events and impacts are armed
    /// again, as a new run from `(t, x)` would; the budget, the counts and
    /// the constraints' record go on. `x` is checked as `--init` values
    /// are: finite, on the constraints (the components they fix within
    /// 1e-9 of the values they require), and every constraint's first
    /// candidate determined. [`Integration::put_on_constraints`] makes a
    /// state satisfy them. Panics when `x` is not of the model's dimension.
    pub fn restart_from(&mut self, t: f64, x: &[f64]) -> Result<(), Failure> {
        if !(t >= self.t_first && t <= self.end) {
            return Err(Failure::new(
                t,
                FailureKind::OutsideSpan {
                    from: self.t_first,
                    to: self.end,
                },
            ));
        }
        self.check_state(t, x)?;
        if let Some(s) = &self.stepping {
            let report = s.solver.report();
            self.earlier = Some(match &self.earlier {
                Some(earlier) => merged(earlier, report),
                None => report,
            });
        }
        if let Some(pieces) = self.pieces.as_mut() {
            pieces.retain(|p| p.segment.t_old() < t);
            if let Some(last) = pieces.last_mut() {
                last.until = last.until.min(t);
            }
        }
        self.budget.accepted_to(t);
        self.start(t, x);
        match &self.done {
            Some(Err(failure)) => Err(failure.clone()),
            _ => Ok(()),
        }
    }

    /// Sets the model's inputs where the integration stands (issue 26): a
    /// discontinuity, so the run restarts there
    /// ([`Integration::restart_with_inputs`]).
    pub fn set_inputs(&mut self, inputs: &crate::model::Inputs) -> Result<(), Failure> {
        let (t, x) = (self.t, self.x.clone());
        self.restart_with_inputs(t, &x, inputs)
    }

    /// [`Integration::restart_from`] `(t, x)` with the model's inputs set
    /// to `inputs`: the components of `x` the constraints fix are
    /// recomputed under them, the others carried over.
    pub fn restart_with_inputs(
        &mut self,
        t: f64,
        x: &[f64],
        inputs: &crate::model::Inputs,
    ) -> Result<(), Failure> {
        let model = self.model.get_mut();
        model.set_inputs(inputs);
        let mut fixed = x.to_vec();
        model.constrained(t, x, &mut fixed)?;
        self.restart_from(t, &fixed)
    }

    /// [`Integration::restart_with_inputs`] on `model` from now on, in
    /// place of the model the integration held: the same model with other
    /// param values (a param tuned between steps, issue 26), a change as
    /// discontinuous as an input's. The integration owns `model` after.
    pub fn restart_with_model(
        &mut self,
        model: Box<dyn DynModel>,
        t: f64,
        x: &[f64],
        inputs: &crate::model::Inputs,
    ) -> Result<(), Failure> {
        self.model = Held::Owned(model);
        self.restart_with_inputs(t, x, inputs)
    }

    /// Moves `x` onto the constraints at `t` (the velocities along the
    /// constraints' normals, the smallest correction; holonomic positions
    /// by Gauss–Newton), in the mode whose candidates are best there.
    pub fn put_on_constraints(&mut self, t: f64, x: &mut [f64]) -> Result<(), Failure> {
        let model = self.model.get();
        let mode = best_mode(model, t, x).0;
        match self.keeper.as_mut() {
            Some(keeper) => keeper.put_on(model, mode, t, x),
            None => Ok(()),
        }
    }

    /// The checks of a state given from outside (see
    /// [`Integration::restart_from`]).
    fn check_state(&mut self, t: f64, x: &[f64]) -> Result<(), Failure> {
        let model = self.model.get_mut();
        assert_eq!(x.len(), model.dim(), "a state has one value per component");
        if let Some(i) = x.iter().position(|v| !v.is_finite()) {
            return Err(Failure::new(
                t,
                FailureKind::NonFiniteInitialValue {
                    component: model.state_names()[i].to_string(),
                },
            ));
        }
        if model.keeps_constraints() || model.keeps_positions() {
            let mode = best_mode(model, t, x).0;
            model.set_regime(&Regime {
                mode,
                branches: initial_branches(model, t, x),
            });
            let mut required = x.to_vec();
            if model.keeps_positions() {
                // Along the normals: a state on the constraints is its own
                // projection either way, and this one is only compared.
                model.project_closure(t, &mut required, None)?;
            }
            let mut kept = required.clone();
            model.constrained(t, &required, &mut kept)?;
            for (i, (&stated, &required)) in x.iter().zip(&kept).enumerate() {
                if (stated - required).abs() > 1e-9 * required.abs().max(1.0) {
                    return Err(Failure::new(
                        t,
                        FailureKind::InconsistentInitialValue {
                            component: model.state_names()[i].to_string(),
                            stated,
                            required,
                        },
                    ));
                }
            }
            model.set_regime(&self.regime);
        }
        check_initial_candidates(model, t, x)
    }

    fn solver(&self) -> &dyn Solver {
        &*self.stepping.as_ref().expect("a run that steps").solver
    }

    /// The run has reached the end of its span: the state there, on the
    /// constraints.
    fn reach_end(&mut self) {
        let model = self.model.get();
        let s = self.stepping.as_mut().expect("a run that steps");
        s.solver.finish(model);
        self.t = s.solver.time();
        self.x.copy_from_slice(s.solver.state());
        self.progress.finish();
        self.done = Some(Ok(Ending::End));
    }

    /// The state at `t` within the pending step, on the constraints.
    fn sample(&mut self, t: f64) -> Result<(), Failure> {
        let model = self.model.get();
        let s = self.stepping.as_mut().expect("a run that steps");
        let pending = self.pending.as_ref().expect("a pending step");
        // A step cut to land on `t` holds its own state there, not the
        // continuous extension's reading of it.
        let on_step_end = self.options.step_to_times && t == s.solver.time();
        let mut read = || -> Result<(), Failure> {
            if on_step_end {
                self.x.copy_from_slice(s.solver.state());
            } else {
                s.solver.dense(model, t, &mut self.x)?;
            }
            // No output is off the constraints.
            if let Some(keeper) = self.keeper.as_mut() {
                keeper.project(model, self.regime.mode, t, &mut self.x)?;
            }
            Ok(())
        };
        match read() {
            Ok(()) => {
                self.t = t;
                Ok(())
            }
            Err(failure) if pending.diagnose => {
                let x = s.solver.state().to_vec();
                let failure = near_singular_configuration(model, failure, &x, &self.volumes);
                if matches!(failure.kind, FailureKind::SingularConfiguration { .. }) {
                    return Err(failure);
                }
                Err(s.watch.diagnose(model, failure, pending.tb, &x))
            }
            Err(failure) => Err(failure),
        }
    }

    /// The first half of a step: take it, look for events in it, and
    /// settle how far its continuous extension is the solution.
    fn step(&mut self) -> Result<(), Failure> {
        let model = self.model.get_mut();
        let s = self.stepping.as_mut().expect("a run that steps");
        let Stepping {
            solver,
            watch,
            early_scale,
            g_now,
            x_event,
            step_ends,
            pace,
            pivot_limit,
            g_quarters,
            impacts,
        } = s;
        let budget = &self.budget;
        let regime = &mut self.regime;
        let n = self.x.len();
        // Where the solution stands: after the last step, or where an
        // event restarted it. Read once (each read is two dynamic calls:
        // the solver's and its stepper's; BENCHMARKS §10r).
        let t_now = solver.time();
        budget.accepted_to(t_now);
        let mut t_limit = pace.limit(t_now, self.end);
        if let Some(t) = pivot_limit.take() {
            t_limit = t_limit.min(t);
        }
        if self.options.step_to_times && self.target > t_now {
            t_limit = t_limit.min(self.target);
        }
        let advanced = match self.keeper.as_mut() {
            Some(keeper) => {
                let mut keeping = Kept {
                    keeper,
                    model,
                    mode: regime.mode,
                    t: t_now,
                };
                solver.advance_kept(model, t_limit, budget, &mut keeping)
            }
            None => solver.advance(model, t_limit, budget),
        };
        if let Err(mut failure) = advanced {
            if matches!(failure.kind, FailureKind::StepBudgetExhausted { .. }) {
                // Where the solution stands (after the last step and any
                // event's restart), not where the field's predictor or a
                // window's steps had run ahead to.
                failure.time = solver.time();
            }
            let x = solver.state().to_vec();
            self.progress.finish();
            let scale =
                early_scale.unwrap_or_else(|| MassScale::at(&*model, self.t_start, &self.x_start));
            let failure = diagnose(model, failure, &x, &scale);
            let failure = near_singular_configuration(model, failure, &x, &self.volumes);
            if matches!(failure.kind, FailureKind::SingularConfiguration { .. }) {
                return Err(failure);
            }
            return Err(watch.diagnose(model, failure, solver.time(), &x));
        }
        let (ta, tb) = (solver.previous_time(), solver.time());
        self.progress.update(tb);
        if let Some(keeper) = self.keeper.as_mut() {
            let mut keeping = Kept {
                keeper,
                model,
                mode: regime.mode,
                t: tb,
            };
            solver.keep_on_constraints(model, &mut keeping);
        }
        if let Some(pieces) = self.pieces.as_mut() {
            for segment in solver.segments(model)? {
                pieces.push(Piece {
                    until: segment.t_new(),
                    segment,
                });
            }
        }
        // A switch whose function changed sign against its branch.
        let mut event: Option<(f64, f64, Vec<usize>)> = None;
        if model.switches() > 0 {
            // In each of the integrator's steps (one for direct
            // integration, a window's for the field), the step's end and
            // three points inside it: a function that crosses zero and back
            // within one step is seen at one of them unless both crossings
            // fall between two neighbours. The search for the crossing
            // starts at the beginning of the first step where one is seen.
            solver.step_ends(step_ends);
            let (mut t_check, mut t_from) = (tb, ta);
            let mut changed: Vec<usize> = Vec::new();
            let mut start = ta;
            'scan: for &end in step_ends.iter() {
                for fraction in [0.25, 0.5, 0.75, 1.0] {
                    let t = if fraction == 1.0 {
                        end
                    } else {
                        start + fraction * (end - start)
                    };
                    if t == tb {
                        model.switching_functions(tb, solver.state(), g_now);
                    } else {
                        solver.dense(model, t, x_event)?;
                        model.switching_functions(t, x_event, g_now);
                    }
                    changed = (0..model.switches())
                        .filter(|&k| {
                            let g = impacts.as_seen(k, g_now[k], regime.branches[k]);
                            (g > 0.0) != regime.branches[k]
                        })
                        .collect();
                    if !changed.is_empty() {
                        (t_check, t_from) = (t, start);
                        break 'scan;
                    }
                    if fraction < 1.0 {
                        g_quarters[(4.0 * fraction) as usize].copy_from_slice(g_now);
                    }
                }
                if end == tb {
                    solver.dense(model, start, x_event)?;
                    model.switching_functions(start, x_event, &mut g_quarters[0]);
                    let g = &*g_quarters;
                    pace.observe(end - start, [&g[0], &g[1], &g[2], &g[3], &g_now[..]]);
                }
                start = end;
            }
            let (ta, tb) = (t_from, t_check);
            if !changed.is_empty() {
                let mut roots = Vec::with_capacity(changed.len());
                for &k in &changed {
                    let mut x = vec![0.0; n];
                    let mut g = vec![0.0; model.switches()];
                    let positive = regime.branches[k];
                    let model = &*model;
                    let mut phi = |t: f64| -> Result<f64, Failure> {
                        solver.dense(model, t, &mut x)?;
                        model.switching_functions(t, &x, &mut g);
                        Ok(impacts.as_seen(k, g[k], positive))
                    };
                    let g_a = {
                        let v = phi(ta)?;
                        // At the step's start the function is on its
                        // branch's side (or exactly zero there).
                        if regime.branches[k] {
                            v.max(f64::MIN_POSITIVE)
                        } else {
                            v.min(-f64::MIN_POSITIVE)
                        }
                    };
                    let root = locate(ta, g_a, tb, g_now[k], &mut phi)?;
                    roots.push((k, root));
                }
                let t_event = roots.iter().map(|&(_, r)| r).fold(f64::INFINITY, f64::min);
                let width = 8.0 * f64::EPSILON * t_event.abs().max(1.0);
                let at: Vec<usize> = roots
                    .iter()
                    .filter(|&&(_, r)| r <= t_event + width)
                    .map(|&(k, _)| k)
                    .collect();
                event = Some((ta, t_event, at));
            }
        }
        self.pending = Some(match event {
            Some((t_from, t_event, switches)) => {
                if let Some(pieces) = self.pieces.as_mut() {
                    // The event ends this step's pieces early.
                    pieces.retain(|p| p.segment.t_old() < t_event);
                    if let Some(last) = pieces.last_mut() {
                        last.until = last.until.min(t_event);
                    }
                }
                // A constraint's branch that ended within the step stops
                // the run there, its rows written up to where it ended.
                let ended = watch.step(model, solver.as_mut(), ta, t_event)?;
                Pending {
                    until: ended.as_ref().map_or(t_event, |f| f.time),
                    tb,
                    diagnose: false,
                    then: match ended {
                        Some(failure) => Then::Fail(Box::new(failure)),
                        None => Then::Event {
                            t_from,
                            t_event,
                            switches,
                        },
                    },
                }
            }
            None => {
                // A step across a vanishing pivot is not a solution: it is
                // taken again with another candidate, or the run stops.
                if !model.constraints().is_empty() {
                    match pivot_crossed(model, regime, solver.as_mut(), (ta, tb), &self.volumes)? {
                        PivotCrossing::None => {}
                        crossing => {
                            if let Some(pieces) = self.pieces.as_mut() {
                                // The step is taken again from its start.
                                pieces.retain(|p| p.segment.t_old() < ta);
                                if let Some(last) = pieces.last_mut() {
                                    last.until = last.until.min(ta);
                                }
                            }
                            if let PivotCrossing::Retry(t) = crossing {
                                *pivot_limit = Some(t);
                            }
                            return Ok(());
                        }
                    }
                }
                // A constraint's branch that ended within the step stops
                // the run there, its rows written up to where it ended.
                let ended = watch.step(model, solver.as_mut(), ta, tb)?;
                Pending {
                    until: ended.as_ref().map_or(tb, |f| f.time),
                    tb,
                    diagnose: true,
                    then: match ended {
                        Some(failure) => Then::Fail(Box::new(failure)),
                        None => Then::Step,
                    },
                }
            }
        });
        Ok(())
    }

    /// The second half of the pending step: the event's resets and
    /// restart, or the projection onto the constraints and a change of
    /// candidates.
    fn finish_step(&mut self) -> Result<(), Failure> {
        let pending = self.pending.take().expect("a pending step");
        let model = self.model.get_mut();
        let s = self.stepping.as_mut().expect("a run that steps");
        let regime = &mut self.regime;
        match pending.then {
            Then::Fail(failure) => Err(*failure),
            Then::Event {
                t_from,
                t_event,
                mut switches,
            } => {
                let x_event = &mut s.x_event;
                s.solver.dense(model, t_event, x_event)?;
                s.solver.cut(model, t_event, x_event);
                if let Some(keeper) = self.keeper.as_mut() {
                    keeper.project(model, regime.mode, t_event, x_event)?;
                }
                observe_to_event(
                    model,
                    s.solver.as_mut(),
                    (t_from, t_event),
                    x_event,
                    &switches,
                    &mut s.pace,
                )?;
                let before = regime.branches.clone();
                // What a system carrying more than the motion needs at the
                // event (`DynModel::event_jump`).
                let x_before = x_event.clone();
                let scale_before = rate_scale(model, t_event, &x_before);
                for &k in &switches {
                    regime.branches[k] = !regime.branches[k];
                }
                self.events += 1;
                let mut ending = model
                    .stop(&regime.branches)
                    .then_some(Ending::Stopped(t_event));
                let mut reset = false;
                if ending.is_none() && !model.impacts().is_empty() {
                    // A `when` whose condition became true resets the
                    // state; after it `stop when` may hold.
                    let at = s.impacts.at_event(
                        model,
                        regime,
                        &before,
                        &mut switches,
                        t_event,
                        x_event,
                        self.options.tol,
                    )?;
                    reset = matches!(at, AtEvent::Reset);
                    ending = match at {
                        AtEvent::Stop(end) => Some(end),
                        AtEvent::Reset if model.stop(&regime.branches) => {
                            Some(Ending::Stopped(t_event))
                        }
                        AtEvent::Reset | AtEvent::None => None,
                    };
                }
                model.set_regime(regime);
                // An impact's resets recompute what the constraints fix by
                // their own rules (`run::impacts`).
                if ending.is_none() && !reset && !switches.is_empty() {
                    if let Some(keeper) = self.keeper.as_mut() {
                        jump_onto_new_branch(
                            keeper,
                            model,
                            regime.mode,
                            t_event,
                            x_event,
                            self.options.tol,
                        )?;
                    }
                }
                if ending.is_none() {
                    // A mass law that jumps at a switch (a stage dropped,
                    // `if z < H then … else …`) to zero or below never
                    // crosses zero along a step, where a vanishing mass is
                    // otherwise caught: checked, a staged rocket whose
                    // second piece was negative flew on with M = -140 and
                    // exit 0.
                    check_masses(model, t_event, x_event)?;
                    let before = Regime {
                        mode: regime.mode,
                        branches: before,
                    };
                    model.event_jump(&before, &switches, t_event, &x_before, x_event)?;
                    // The error carried along the motion, through the
                    // event's time and the impact's reset.
                    let model = &*model;
                    s.solver.carry_error_through_event(&mut |e| {
                        crate::run::saltation::through_event(
                            model, &before, &switches, t_event, &x_before, x_event, e,
                        )
                    });
                }
                if let Some(ending) = ending {
                    self.t = t_event;
                    self.x.copy_from_slice(x_event);
                    self.progress.finish();
                    self.done = Some(Ok(ending));
                    return Ok(());
                }
                // Where the state did not jump and the new regime's rate
                // varies on no shorter scale than the old one's (its
                // Jacobian's norm at most twice the old), the step sizes
                // learnt go on (`Solver::restart_smooth`).
                let smooth = x_before == *x_event
                    && scale_before.is_some_and(|before| {
                        rate_scale(model, t_event, x_event)
                            .is_some_and(|after| after <= 2.0 * before)
                    });
                if smooth {
                    s.solver.restart_smooth(model, t_event, x_event)
                } else {
                    s.solver.restart(model, t_event, x_event)
                }
            }
            Then::Step => {
                let tb = pending.tb;
                let solver = &mut s.solver;
                if let Some(keeper) = self.keeper.as_mut() {
                    // A state off its constraint near a pole or an end
                    // of one is named after it. The state is read in
                    // place (a copy a step was most of a constrained
                    // run's allocations, docs/BENCHMARKS.md §10h).
                    let kept = match keeper.after_step(model, regime.mode, tb, solver.state()) {
                        Ok(None) => Ok(()),
                        Ok(Some(x)) => solver.project(model, tb, x),
                        Err(f) => Err(f),
                    };
                    if let Err(failure) = kept {
                        let (solver, watch) = (&**solver, &s.watch);
                        return Err(not_kept(model, solver, watch, &self.volumes, failure, tb));
                    }
                }
                if !model.constraints().is_empty() {
                    switch_candidates(model, regime, solver.as_mut(), tb, &self.volumes)?;
                }
                Ok(())
            }
        }
    }
}

impl Integration<'static> {
    /// An integration that owns its model (for callers that keep it, such
    /// as a Python object or a co-simulation slave).
    pub fn owned(
        model: Box<dyn DynModel>,
        options: &Options,
        t0: f64,
        end: f64,
        x0: &[f64],
    ) -> Integration<'static> {
        Integration::with(Held::Owned(model), options, t0, end, x0, Spare::default())
    }
}

/// A state after a step at `tb` that could not be kept on the constraints:
/// named as a singular configuration where it is near one, else after a
/// pole or an end of a constraint near it. Out of line and cold: the
/// step's second half stays small (it runs at every step).
#[cold]
#[inline(never)]
fn not_kept(
    model: &dyn DynModel,
    solver: &dyn Solver,
    watch: &ConstraintWatch,
    volumes: &[f64],
    failure: Failure,
    tb: f64,
) -> Failure {
    let x = solver.state().to_vec();
    let failure = near_singular_configuration(model, failure, &x, volumes);
    if matches!(failure.kind, FailureKind::SingularConfiguration { .. }) {
        return failure;
    }
    watch.diagnose(model, failure, tb, &x)
}

/// The work of two solvers in one run (before and after a restart).
fn merged(earlier: &Report, later: Report) -> Report {
    let mut stats = earlier.stats;
    stats += later.stats;
    let sum = |a: Option<usize>, b: Option<usize>| match (a, b) {
        (Some(a), Some(b)) => Some(a + b),
        (a, b) => a.or(b),
    };
    let mut notes = earlier.notes.clone();
    notes.extend(
        later
            .notes
            .into_iter()
            .filter(|n| !earlier.notes.contains(n)),
    );
    Report {
        method: later.method,
        stats,
        largest_condition: match (earlier.largest_condition, later.largest_condition) {
            (Some(a), Some(b)) => Some(a.max(b)),
            (a, b) => a.or(b),
        },
        reanchorings: sum(earlier.reanchorings, later.reanchorings),
        windows: sum(earlier.windows, later.windows),
        passes: sum(earlier.passes, later.passes),
        predictor: match (earlier.predictor, later.predictor) {
            (Some(mut a), Some(b)) => {
                a += b;
                Some(a)
            }
            (a, b) => a.or(b),
        },
        linearizations: earlier.linearizations + later.linearizations,
        notes,
        global_error: crate::method::solver::GlobalErrorEstimate::sum(
            earlier.global_error,
            later.global_error,
        ),
    }
}

/// Makes the solver of `options` for `model` from `(t0, x0)`.
pub fn make_solver(
    model: &dyn DynModel,
    options: &Options,
    t0: f64,
    x0: &[f64],
    h_max: f64,
) -> Result<Box<dyn Solver>, Failure> {
    make_solver_reusing(model, options, t0, x0, h_max, None, None)
}

/// [`make_solver`], direct integration's solver made in the storage of
/// `spare` (an earlier solve's, [`Direct::renew`]).
fn make_solver_reusing(
    model: &dyn DynModel,
    options: &Options,
    t0: f64,
    x0: &[f64],
    h_max: f64,
    spare: Option<Box<Direct>>,
    spare_field: Option<Box<QuasilinearField>>,
) -> Result<Box<dyn Solver>, Failure> {
    let choice = options.integrator_choice(model);
    Ok(match options.method {
        Method::Direct => {
            let mut direct = match spare {
                Some(mut direct) => {
                    direct.renew(model, choice, options.tol, t0, x0, h_max)?;
                    direct
                }
                None => Box::new(Direct::new(model, choice, options.tol, t0, x0, h_max)?),
            };
            if !options.global_error {
                direct.drop_global_error();
            }
            direct
        }
        Method::Field => {
            let field = FieldOptions {
                tol: options.tol,
                anchor: options.anchor.clone(),
                reanchor: options.reanchor,
                stiff: choice == IntegratorChoice::Stiff,
                auto_stiff: choice == IntegratorChoice::Auto,
                magnus: choice == IntegratorChoice::Magnus,
                global_error: options.global_error,
                ..FieldOptions::default()
            };
            if model.affine() {
                Box::new(AffineField::new(model, field, t0, x0, h_max)?)
            } else {
                match spare_field {
                    Some(old) => old.renewed(field, t0, x0, h_max),
                    None => Box::new(QuasilinearField::new(field, t0, x0, h_max)),
                }
            }
        }
    })
}

/// The switching functions' pace where a solve starts, before any step
/// has shown it: from probes ahead at a hundredth to a millionth of the
/// span, the motion followed to second order (two right sides a probe),
/// the fastest pace any probe shows. One scale is not enough: a
/// millionth is rounding's size for the curvature of `sin(20 t)` near its
/// zero, a hundredth is five periods of `sin(500 t)`. Unpaced, the first
/// step of a force switched by `sin(500 t)` stepped over switches.
fn probe_pace(model: &dyn DynModel, t: f64, x: &[f64], span: f64, pace: &mut SwitchPace) {
    let k = model.switches();
    if k == 0 {
        return;
    }
    let n = x.len();
    let (mut slope, mut slope_ahead) = (vec![0.0; n], vec![0.0; n]);
    if model.rhs(t, x, &mut slope).is_err() {
        return;
    }
    for digits in 2..=6 {
        let h = span.abs() * 10f64.powi(-digits);
        if !(h > 0.0) || t + h == t {
            continue;
        }
        let euler: Vec<f64> = x.iter().zip(&slope).map(|(x, s)| x + h * s).collect();
        if model.rhs(t + h, &euler, &mut slope_ahead).is_err() {
            continue;
        }
        // x(t + s) = x + s f + s²/(2h) (f(t + h) − f): second order, so
        // that a coordinate's curvature (its acceleration) is seen.
        let at = |fraction: f64| -> Vec<f64> {
            let s = fraction * h;
            let state: Vec<f64> = (0..n)
                .map(|i| x[i] + s * slope[i] + s * s / (2.0 * h) * (slope_ahead[i] - slope[i]))
                .collect();
            let mut g = vec![0.0; k];
            model.switching_functions(t + s, &state, &mut g);
            g
        };
        let g: Vec<Vec<f64>> = (0..5).map(|i| at(0.25 * i as f64)).collect();
        let mut probe = SwitchPace::default();
        probe.observe(h, [&g[0], &g[1], &g[2], &g[3], &g[4]]);
        pace.at_least(&probe);
    }
}

/// The scale on which the rate varies with the state at `(t, x)` in the
/// model's current regime: the 1-norm of its Jacobian (None where it is not
/// finite or cannot be evaluated).
fn rate_scale(model: &dyn DynModel, t: f64, x: &[f64]) -> Option<f64> {
    let mut jac = Matrix::zeros(x.len(), x.len());
    model.jacobian(t, x, &mut jac).ok()?;
    let norm = jac.one_norm();
    norm.is_finite().then_some(norm)
}

/// The pace where an event at `t_event` restarts the solution, learnt
/// from the part `[t_from, t_event]` of the step before it (its dense
/// output). Every step under a fast clock ends in an event: without this
/// no step's end was ever observed, and a force switched by
/// `sign(sin(500 t))` was stepped over by both methods (9 and 1573 of 1591
/// switches located, exit 0).
fn observe_to_event(
    model: &dyn DynModel,
    solver: &mut dyn Solver,
    (t_from, t_event): (f64, f64),
    x_event: &[f64],
    switched: &[usize],
    pace: &mut SwitchPace,
) -> Result<(), Failure> {
    let k = model.switches();
    let h = t_event - t_from;
    if !(h > 0.0) {
        return Ok(());
    }
    let mut x = vec![0.0; x_event.len()];
    let mut values = |fraction: f64| -> Result<Vec<f64>, Failure> {
        let t = t_from + fraction * h;
        solver.dense(model, t, &mut x)?;
        let mut g = vec![0.0; k];
        model.switching_functions(t, &x, &mut g);
        Ok(g)
    };
    let g = [values(0.0)?, values(0.25)?, values(0.5)?, values(0.75)?];
    let mut at_event = vec![0.0; k];
    model.switching_functions(t_event, x_event, &mut at_event);
    pace.observe_to_event(h, [&g[0], &g[1], &g[2], &g[3], &at_event], switched);
    Ok(())
}

/// The run's keeper as a solver sees it after an advance ending at `t`
/// in `mode` ([`Solver::keep_on_constraints`]).
struct Kept<'a> {
    keeper: &'a mut Keeper,
    model: &'a dyn DynModel,
    mode: usize,
    t: f64,
}

impl Keeping for Kept<'_> {
    fn kept_part(&mut self, x: &[f64], d: &mut [f64]) -> Result<(), Failure> {
        self.keeper.kept_part(self.model, self.t, x, d)
    }
    fn tangent(&mut self, t: f64, x: &[f64], d: &mut [f64]) -> Result<(), Failure> {
        self.keeper.tangent(self.model, self.mode, t, x, d)
    }
    fn project(&mut self, t: f64, x: &mut [f64]) -> Result<(), Failure> {
        self.keeper.put_on(self.model, self.mode, t, x)
    }
    fn drifted(&mut self, t: f64, x: &[f64]) -> bool {
        self.keeper
            .drifted(self.model, self.mode, t, x)
            .unwrap_or(true)
    }
}

/// A constraint whose right side switches (`y' = if y < 1 then 1 else 0`,
/// a fuel tank that empties: `m' = if m > 0 then -mu else 0`) fixes
/// another value on the new branch: the state is put on the new regime's
/// constraints at the event, as after a reset (lagc recomputes the
/// components the constraints fix, the others kept). Before, the next
/// step found the constraint left by the whole jump and the run stopped
/// (exit 3), naming a root's branch. A position constraint with a kink
/// (a yo-yo's string `y = -L + r*abs(psi)` at its end) would make its
/// velocity jump too, an impulse the model does not say how to take (kept
/// the independent velocities, a wire bent at unequal slopes would gain
/// energy): that stops the run at the event, named. A switch that changes
/// no constraint's value leaves the state exactly as it was (a
/// projection's rounding would otherwise cost the step sizes kept across a
/// smooth event).
fn jump_onto_new_branch(
    keeper: &mut Keeper,
    model: &dyn DynModel,
    mode: usize,
    t: f64,
    x: &mut [f64],
    tol: Tolerance,
) -> Result<(), Failure> {
    let mut onto = x.to_vec();
    keeper.put_on(model, mode, t, &mut onto)?;
    let jumped = |i: usize| (onto[i] - x[i]).abs() > 0.01 * (tol.atol + tol.rtol * x[i].abs());
    if !(0..x.len()).any(jumped) {
        return Ok(());
    }
    for i in (0..x.len()).filter(|&i| jumped(i)) {
        let name = model.state_names()[i];
        let coordinate = name.trim_end_matches('\'');
        let kinked = model
            .constraints()
            .iter()
            .find(|c| c.names.contains(&coordinate));
        if let Some(constraint) = kinked {
            return Err(Failure::new(
                t,
                FailureKind::ConstraintKink {
                    component: name.to_string(),
                    constraint: constraint.text.to_string(),
                    before: x[i],
                    after: onto[i],
                },
            ));
        }
    }
    x.copy_from_slice(&onto);
    Ok(())
}
