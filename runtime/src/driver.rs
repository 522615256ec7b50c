//! The run: one method advancing the model step by step; the output at the
//! requested times from the dense output (so output never constrains the
//! steps); events — a switching function changing sign, located by root
//! finding on the dense output, the integrator (or the field) restarted
//! there in the new regime; implicit constraints switching candidates; and
//! `stop when`.

use crate::budget::Budget;
use crate::direct::Direct;
use crate::events::{locate, SwitchPace};
use crate::failure::{Failure, FailureKind};
use crate::field::affine::AffineField;
use crate::field::quasilinear::QuasilinearField;
use crate::field::{Anchor, FieldOptions};
use crate::impacts::{AtEvent, Impacts};
use crate::keep::Keeper;
use crate::method::{IntegratorChoice, Method};
use crate::model::{DynModel, Regime};
use crate::progress::Progress;
use crate::solution::{Piece, Solution};
use crate::solver::{Report, Solver};
use crate::tolerance::Tolerance;
use crate::watch::ConstraintWatch;

/// How to integrate.
#[derive(Clone, Debug, PartialEq)]
pub struct Options {
    pub method: Method,
    /// `None`: the model's `integrator` statement, or `Auto`.
    pub integrator: Option<IntegratorChoice>,
    pub tol: Tolerance,
    pub anchor: Anchor,
    pub reanchor: bool,
    /// The work budget: steps of every kind.
    pub max_steps: usize,
    /// Show progress on stderr (when it is a terminal) for long runs.
    pub progress: bool,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            method: Method::Field,
            integrator: None,
            tol: Tolerance::default(),
            anchor: Anchor::Zero,
            reanchor: true,
            max_steps: crate::budget::DEFAULT_MAX_STEPS,
            progress: false,
        }
    }
}

impl Options {
    /// The integrator choice: the option, else the model's statement,
    /// else `Auto`; with where it came from, in words.
    pub fn choice(&self, model: &dyn DynModel) -> (IntegratorChoice, String) {
        let choice = self.integrator_choice(model);
        match (self.integrator, model.declared_integrator()) {
            (Some(c), _) => (choice, format!("--integrator {}", c.name())),
            (None, Some(c)) => (choice, format!("declared {} in the model", c.name())),
            (None, None) => (choice, "auto, the default".to_string()),
        }
    }

    /// The integrator choice of [`Options::choice`] without the words (no
    /// allocation: every solve asks).
    pub fn integrator_choice(&self, model: &dyn DynModel) -> IntegratorChoice {
        self.integrator
            .or_else(|| model.declared_integrator())
            .unwrap_or(IntegratorChoice::Auto)
    }
}

/// A sample callback: `(model, t, x)`.
type Sample<'a> = dyn FnMut(&dyn DynModel, f64, &[f64]) -> Result<(), Failure> + 'a;

/// Why the run ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Ending {
    /// At the end of the time span.
    End,
    /// `stop when` became true at this time.
    Stopped(f64),
    /// The impacts of the `when` whose condition is `impact` left the
    /// motion on its boundary at `at`: they accumulate at `accumulation`
    /// (a ball with restitution below 1 comes to rest there), or (`None`)
    /// the last one stopped the motion instead of turning it back. The
    /// run ends at `at`, its last row the state after that impact.
    Rest {
        impact: &'static str,
        at: f64,
        accumulation: Option<f64>,
    },
}

/// What a run did.
#[derive(Clone, Debug, PartialEq)]
pub struct Outcome {
    pub report: Report,
    pub ending: Ending,
    /// Events located (switches and candidate changes).
    pub events: usize,
    /// Steps drawn from the budget.
    pub budget_used: usize,
    /// The constraints' residuals and projections (models whose
    /// constraints fix state components).
    pub kept: Option<crate::keep::Kept>,
}

/// The initial regime at `(t0, x0)`: branches from the switching
/// functions' signs (a function exactly zero takes the sign it has a moment
/// later along the initial slope).
pub fn initial_branches(model: &dyn DynModel, t0: f64, x0: &[f64]) -> Vec<bool> {
    let k = model.switches();
    if k == 0 {
        return Vec::new();
    }
    let mut g = vec![0.0; k];
    // A switching function may read another's branch (`stop when
    // abs(x - 1.5) < 0.5` reads the kink's): evaluate them again under the
    // branches found until these settle (at most once per function; a
    // function exactly zero provisionally positive). Under the default
    // branches that stop fired at t0 from x = 0, exit 0.
    let mut model = model.boxed_clone();
    let mode = best_mode(&*model, t0, x0).0;
    let mut branches: Vec<bool> = Vec::new();
    for _ in 0..=k {
        model.switching_functions(t0, x0, &mut g);
        let found: Vec<bool> = g.iter().map(|&v| v >= 0.0).collect();
        if found == branches {
            break;
        }
        branches = found;
        model.set_regime(&Regime {
            mode,
            branches: branches.clone(),
        });
    }
    if g.contains(&0.0) {
        // The right side reads the branches: it has those already known.
        let model = &*model;
        // A moment later along Heun's second-order step, so that a function
        // whose first derivative also vanishes (a rocket at rest on the
        // ground, `stop when z < 0`) takes the sign of its second.
        let mut slope = vec![0.0; x0.len()];
        let mut slope_ahead = vec![0.0; x0.len()];
        let h = 1e-6 * t0.abs().max(1.0);
        if model.rhs(t0, x0, &mut slope).is_ok() {
            let euler: Vec<f64> = x0.iter().zip(&slope).map(|(x, s)| x + h * s).collect();
            let ahead: Vec<f64> = if model.rhs(t0 + h, &euler, &mut slope_ahead).is_ok() {
                x0.iter()
                    .zip(slope.iter().zip(&slope_ahead))
                    .map(|(x, (s, s1))| x + h / 2.0 * (s + s1))
                    .collect()
            } else {
                euler
            };
            let mut g_ahead = vec![0.0; k];
            model.switching_functions(t0 + h, &ahead, &mut g_ahead);
            for (v, a) in g.iter_mut().zip(&g_ahead) {
                if *v == 0.0 {
                    *v = *a;
                }
            }
        }
    }
    g.iter().map(|&v| v > 0.0).collect()
}

/// A pivot of a first candidate below this fraction of its constraint's
/// largest leaves the initial value it fixes undetermined.
const INITIAL_PIVOT_RATIO: f64 = 1e-8;

/// Whether every constraint determines its first candidate at the initial
/// state `(t0, x0)`, which the initial values take as the one it fixes
/// (the model's own values are checked when it compiles, E0011; `--init`
/// values only here: a knife edge started at heading π/2 with x' given
/// computed y' = x' tan(π/2) = 1.6e16 and stopped at t = 5e-14 naming the
/// pivot).
pub fn check_initial_candidates(model: &dyn DynModel, t0: f64, x0: &[f64]) -> Result<(), Failure> {
    crate::keep::check_given_fixed(model, t0, x0)?;
    let constraints = model.constraints();
    if constraints.is_empty() {
        return Ok(());
    }
    let total: usize = constraints.iter().map(|c| c.names.len()).sum();
    let mut pivots = vec![0.0; total];
    model.pivots(t0, x0, &mut pivots);
    let mut at = 0;
    for c in constraints {
        let slice = &pivots[at..at + c.names.len()];
        at += c.names.len();
        let (best, best_pivot) = largest_pivot(slice);
        let ratio = slice[0].abs() / best_pivot;
        if best != 0 && ratio < INITIAL_PIVOT_RATIO {
            return Err(Failure::new(
                t0,
                FailureKind::InitialCandidateVanishes {
                    constraint: c.text.to_string(),
                    candidate: c.names[0].to_string(),
                    better: c.names[best].to_string(),
                    ratio,
                },
            ));
        }
    }
    Ok(())
}

/// The mode whose candidates have the largest pivots at `(t, x)`, with
/// the worst ratio of a chosen pivot to the best of its constraint.
pub fn best_mode(model: &dyn DynModel, t: f64, x: &[f64]) -> (usize, Vec<usize>, f64) {
    let constraints = model.constraints();
    if constraints.is_empty() {
        return (0, Vec::new(), 1.0);
    }
    let total: usize = constraints.iter().map(|c| c.names.len()).sum();
    let mut pivots = vec![0.0; total];
    model.pivots(t, x, &mut pivots);
    let mut at = 0;
    let mut choice = Vec::with_capacity(constraints.len());
    let mut best_pivot = f64::INFINITY;
    for c in constraints {
        let slice = &pivots[at..at + c.names.len()];
        let (j, p) = largest_pivot(slice);
        choice.push(j);
        best_pivot = best_pivot.min(p);
        at += c.names.len();
    }
    (mode_index(model, &choice), choice, best_pivot)
}

/// The candidate with the largest pivot among one constraint's, and that
/// pivot's magnitude (the first of equals).
fn largest_pivot(pivots: &[f64]) -> (usize, f64) {
    pivots
        .iter()
        .enumerate()
        .map(|(j, p)| (j, p.abs()))
        .fold((0, -1.0), |best, c| if c.1 > best.1 { c } else { best })
}

/// The mode of a choice of candidates (mixed radix, first constraint
/// lowest).
pub fn mode_index(model: &dyn DynModel, choice: &[usize]) -> usize {
    let mut mode = 0;
    let mut radix = 1;
    for (c, &j) in model.constraints().iter().zip(choice) {
        mode += j * radix;
        radix *= c.names.len();
    }
    mode
}

fn mode_digits(model: &dyn DynModel, mode: usize) -> Vec<usize> {
    let mut rest = mode;
    model
        .constraints()
        .iter()
        .map(|c| {
            let d = rest % c.names.len();
            rest /= c.names.len();
            d
        })
        .collect()
}

/// A candidate is replaced when its pivot falls below this fraction of the
/// best candidate's.
const POOR_PIVOT: f64 = 0.1;

/// Makes the solver of `options` for `model` from `(t0, x0)`.
pub fn make_solver(
    model: &dyn DynModel,
    options: &Options,
    t0: f64,
    x0: &[f64],
    h_max: f64,
) -> Result<Box<dyn Solver>, Failure> {
    let choice = options.integrator_choice(model);
    Ok(match options.method {
        Method::Direct => Box::new(Direct::new(model, choice, options.tol, t0, x0, h_max)?),
        Method::Field => {
            let field = FieldOptions {
                tol: options.tol,
                anchor: options.anchor.clone(),
                reanchor: options.reanchor,
                stiff: choice == IntegratorChoice::Stiff,
                auto_stiff: choice == IntegratorChoice::Auto,
                magnus: choice == IntegratorChoice::Magnus,
                ..FieldOptions::default()
            };
            if model.affine() {
                Box::new(AffineField::new(model, field, t0, x0, h_max)?)
            } else {
                Box::new(QuasilinearField::new(field, t0, x0, h_max))
            }
        }
    })
}

/// Integrates `model` from `(t0, x0)` to `t1`, calling `sample(t, x)` at
/// every time of `times` (ascending, within `[t0, t1]`) and, when `stop
/// when` ends the run early, at the stop time.
pub fn run(
    model: &mut dyn DynModel,
    options: &Options,
    t0: f64,
    t1: f64,
    x0: &[f64],
    times: &[f64],
    sample: impl FnMut(&dyn DynModel, f64, &[f64]) -> Result<(), Failure>,
) -> Result<Outcome, Failure> {
    run_with(model, options, t0, t1, x0, times, sample, None)
}

/// The whole solution as a value: [`run`], keeping every step's continuous
/// extension (memory grows with the number of steps).
pub fn solve(
    model: &mut dyn DynModel,
    options: &Options,
    t0: f64,
    t1: f64,
    x0: &[f64],
) -> Result<Solution, Failure> {
    let mut pieces = Vec::new();
    let outcome = run_with(
        model,
        options,
        t0,
        t1,
        x0,
        &[],
        |_, _, _| Ok(()),
        Some(&mut pieces),
    )?;
    Ok(Solution {
        t0,
        x0: x0.to_vec(),
        pieces,
        outcome,
    })
}

#[allow(clippy::too_many_arguments)]
fn run_with(
    model: &mut dyn DynModel,
    options: &Options,
    t0: f64,
    t1: f64,
    x0: &[f64],
    times: &[f64],
    mut sample: impl FnMut(&dyn DynModel, f64, &[f64]) -> Result<(), Failure>,
    mut pieces: Option<&mut Vec<Piece>>,
) -> Result<Outcome, Failure> {
    let n = x0.len();
    let budget = Budget::new(options.max_steps);
    budget.accepted_to(t0);
    let span = t1 - t0;
    let h_max = if span > 0.0 { span } else { 1.0 };
    let mut regime = Regime {
        mode: best_mode(model, t0, x0).0,
        branches: initial_branches(model, t0, x0),
    };
    model.set_regime(&regime);
    let mut next_sample = 0;
    let mut events = 0;
    let mut keeper = Keeper::new(model, options.tol);
    let volumes = pivot_volumes(model, t0, x0);
    // The sample buffer, allocated once (emit_until runs after every step).
    let mut x_sample = vec![0.0; n];
    let mut emit_until = |model: &dyn DynModel,
                          solver: &mut dyn Solver,
                          keeper: &mut Option<Keeper>,
                          mode: usize,
                          next: &mut usize,
                          until: f64,
                          sample: &mut Sample<'_>|
     -> Result<(), Failure> {
        let x = &mut x_sample;
        while *next < times.len() && times[*next] <= until {
            let t = times[*next];
            solver.dense(model, t, x)?;
            // No output is off the constraints.
            if let Some(keeper) = keeper.as_mut() {
                keeper.project(model, mode, t, x)?;
            }
            sample(model, t, x)?;
            *next += 1;
        }
        Ok(())
    };
    // Samples at t0 come from the initial state itself.
    while next_sample < times.len() && times[next_sample] <= t0 {
        sample(model, times[next_sample], x0)?;
        next_sample += 1;
    }
    if model.switches() > 0 && model.stop(&regime.branches) {
        // The last row is at the stop time, t0: written above when t0 is a
        // sample time, else now.
        let already = next_sample > 0 && times[next_sample - 1] == t0;
        if !already {
            sample(model, t0, x0)?;
        }
        return Ok(Outcome {
            // The summary names the method even when it took no step (it
            // printed `method: ;`).
            report: Report {
                method: format!("{} (no step: stopped at the start)", options.method.name()),
                ..Report::default()
            },
            ending: Ending::Stopped(t0),
            events,
            budget_used: 0,
            kept: keeper.map(|k| k.kept()),
        });
    }
    check_masses(model, t0, x0)?;
    let watch = ConstraintWatch::start(model, t0, x0)?;
    // The mass matrix's scale at the start, which only the diagnosis of a
    // failure reads: an LU and a norm estimate, computed up front only when
    // the regime (on which the mass matrix may depend) can change during
    // the run, else when a failure asks for it (a tenth of a small model's
    // solve).
    let regime_may_change = model.switches() > 0 || !model.constraints().is_empty();
    let early_scale = regime_may_change.then(|| MassScale::at(model, t0, x0));
    let scale = |model: &dyn DynModel| early_scale.unwrap_or_else(|| MassScale::at(model, t0, x0));
    let mut solver = make_solver(model, options, t0, x0, h_max)
        .map_err(|f| watch.diagnose(model, diagnose(model, f, x0, &scale(model)), t0, x0))?;
    let mut progress = Progress::new(options.progress, t0, t1);
    let mut g_now = vec![0.0; model.switches()];
    let mut x_event = vec![0.0; n];
    let mut step_ends: Vec<f64> = Vec::new();
    let mut pace = SwitchPace::default();
    // After a step across a vanishing pivot: how far the retry may reach.
    let mut pivot_limit: Option<f64> = None;
    // The functions at the last step's start and quarters, for the pace.
    let mut g_quarters = vec![g_now.clone(); 4];
    let mut impacts = Impacts::new(model);
    probe_pace(model, t0, x0, t1 - t0, &mut pace);
    while solver.time() < t1 {
        // Where the solution stands: after the last step, or where an
        // event restarted it.
        budget.accepted_to(solver.time());
        let mut t_limit = pace.limit(solver.time(), t1);
        if let Some(t) = pivot_limit.take() {
            t_limit = t_limit.min(t);
        }
        if let Err(mut failure) = solver.advance(model, t_limit, &budget) {
            if matches!(failure.kind, FailureKind::StepBudgetExhausted { .. }) {
                // Where the solution stands (after the last step and any
                // event's restart), not where the field's predictor or a
                // window's steps had run ahead to.
                failure.time = solver.time();
            }
            let x = solver.state().to_vec();
            progress.finish();
            let failure = diagnose(model, failure, &x, &scale(model));
            let failure = near_singular_configuration(model, failure, &x, &volumes);
            if matches!(failure.kind, FailureKind::SingularConfiguration { .. }) {
                return Err(failure);
            }
            return Err(watch.diagnose(model, failure, solver.time(), &x));
        }
        progress.update(solver.time());
        let (ta, tb) = (solver.previous_time(), solver.time());
        if let Some(pieces) = pieces.as_deref_mut() {
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
            solver.step_ends(&mut step_ends);
            let (mut t_check, mut t_from) = (tb, ta);
            let mut changed: Vec<usize> = Vec::new();
            let mut start = ta;
            'scan: for &end in &step_ends {
                for fraction in [0.25, 0.5, 0.75, 1.0] {
                    let t = if fraction == 1.0 {
                        end
                    } else {
                        start + fraction * (end - start)
                    };
                    if t == tb {
                        model.switching_functions(tb, solver.state(), &mut g_now);
                    } else {
                        solver.dense(model, t, &mut x_event)?;
                        model.switching_functions(t, &x_event, &mut g_now);
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
                        g_quarters[(4.0 * fraction) as usize].copy_from_slice(&g_now);
                    }
                }
                if end == tb {
                    solver.dense(model, start, &mut x_event)?;
                    model.switching_functions(start, &x_event, &mut g_quarters[0]);
                    let g = &g_quarters;
                    pace.observe(end - start, [&g[0], &g[1], &g[2], &g[3], &g_now]);
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
        match event {
            Some((t_from, t_event, switches)) => {
                if let Some(pieces) = pieces.as_deref_mut() {
                    // The event ends this step's pieces early.
                    pieces.retain(|p| p.segment.t_old() < t_event);
                    if let Some(last) = pieces.last_mut() {
                        last.until = last.until.min(t_event);
                    }
                }
                // A constraint's branch that ended within the step stops
                // the run there, its rows written up to where it ended.
                let ended = watch.step(model, solver.as_mut(), ta, t_event)?;
                emit_until(
                    model,
                    solver.as_mut(),
                    &mut keeper,
                    regime.mode,
                    &mut next_sample,
                    ended.as_ref().map_or(t_event, |f| f.time),
                    &mut sample,
                )?;
                if let Some(failure) = ended {
                    progress.finish();
                    return Err(failure);
                }
                solver.dense(model, t_event, &mut x_event)?;
                if let Some(keeper) = keeper.as_mut() {
                    keeper.project(model, regime.mode, t_event, &mut x_event)?;
                }
                observe_to_event(
                    model,
                    solver.as_mut(),
                    (t_from, t_event),
                    &x_event,
                    &switches,
                    &mut pace,
                )?;
                let before = regime.branches.clone();
                for &k in &switches {
                    regime.branches[k] = !regime.branches[k];
                }
                events += 1;
                let mut ending = model
                    .stop(&regime.branches)
                    .then_some(Ending::Stopped(t_event));
                if ending.is_none() && !model.impacts().is_empty() {
                    // A `when` whose condition became true resets the
                    // state; after it `stop when` may hold.
                    let at = impacts.at_event(
                        model,
                        &mut regime,
                        &before,
                        &switches,
                        t_event,
                        &mut x_event,
                        options.tol,
                    )?;
                    ending = match at {
                        AtEvent::Stop(end) => Some(end),
                        AtEvent::Reset if model.stop(&regime.branches) => {
                            Some(Ending::Stopped(t_event))
                        }
                        AtEvent::Reset | AtEvent::None => None,
                    };
                }
                if let Some(ending) = ending {
                    model.set_regime(&regime);
                    let already = next_sample > 0 && times[next_sample - 1] == t_event;
                    if !already {
                        sample(model, t_event, &x_event)?;
                    }
                    progress.finish();
                    return Ok(Outcome {
                        report: solver.report(),
                        ending,
                        events,
                        budget_used: budget.used(),
                        kept: keeper.map(|k| k.kept()),
                    });
                }
                model.set_regime(&regime);
                solver.restart(model, t_event, &x_event)?;
            }
            None => {
                // A step across a vanishing pivot is not a solution: it is
                // taken again with another candidate, or the run stops.
                if !model.constraints().is_empty() {
                    match pivot_crossed(model, &mut regime, solver.as_mut(), (ta, tb), &volumes)? {
                        PivotCrossing::None => {}
                        crossing => {
                            if let Some(pieces) = pieces.as_deref_mut() {
                                // The step is taken again from its start.
                                pieces.retain(|p| p.segment.t_old() < ta);
                                if let Some(last) = pieces.last_mut() {
                                    last.until = last.until.min(ta);
                                }
                            }
                            if let PivotCrossing::Retry(t) = crossing {
                                pivot_limit = Some(t);
                            }
                            continue;
                        }
                    }
                }
                // A constraint's branch that ended within the step stops
                // the run there, its rows written up to where it ended.
                let ended = watch.step(model, solver.as_mut(), ta, tb)?;
                let kept = emit_until(
                    model,
                    solver.as_mut(),
                    &mut keeper,
                    regime.mode,
                    &mut next_sample,
                    ended.as_ref().map_or(tb, |f| f.time),
                    &mut sample,
                );
                let mut kept = kept.map(|()| ended);
                if let Ok(None) = &kept {
                    if let Some(keeper) = keeper.as_mut() {
                        // A state off its constraint near a pole or an end
                        // of one is named after it.
                        let x_b = solver.state().to_vec();
                        kept = match keeper.after_step(model, regime.mode, tb, &x_b) {
                            Ok(Some(x)) => solver.project(model, tb, x).map(|()| None),
                            Ok(None) => Ok(None),
                            Err(f) => Err(f),
                        };
                    }
                }
                match kept {
                    Ok(None) => {}
                    Ok(Some(failure)) => {
                        progress.finish();
                        return Err(failure);
                    }
                    // A state that cannot be kept on the constraints near
                    // a singular configuration is named as that, else
                    // after a pole or an end of a constraint near it.
                    Err(failure) => {
                        let x = solver.state().to_vec();
                        let failure = near_singular_configuration(model, failure, &x, &volumes);
                        if matches!(failure.kind, FailureKind::SingularConfiguration { .. }) {
                            return Err(failure);
                        }
                        return Err(watch.diagnose(model, failure, tb, &x));
                    }
                }
                if !model.constraints().is_empty() {
                    switch_candidates(model, &mut regime, solver.as_mut(), tb, &volumes)?;
                }
            }
        }
    }
    emit_until(
        model,
        solver.as_mut(),
        &mut keeper,
        regime.mode,
        &mut next_sample,
        f64::INFINITY,
        &mut sample,
    )?;
    progress.finish();
    Ok(Outcome {
        report: solver.report(),
        ending: Ending::End,
        events,
        budget_used: budget.used(),
        kept: keeper.map(|k| k.kept()),
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

/// What a step across a vanishing pivot calls for.
enum PivotCrossing {
    /// No current candidate's pivot changed sign within the step.
    None,
    /// Restarted at the step's start in the mode of a better candidate.
    Switched,
    /// Restarted at the step's start in the same mode: the next step may
    /// reach at most this far, so that it ends where the pivot is poor but
    /// not yet zero and [`switch_candidates`] chooses another candidate.
    Retry(f64),
}

/// Whether the current candidate's pivot of some constraint changed sign
/// within the step `[ta, tb]`: then the step divided by a vanishing pivot.
/// With a better candidate at `ta` the run restarts there in that mode.
/// With another candidate that is not better yet (a long step, a field
/// window, crossed both where the candidates' pivots cross and where the
/// current one vanishes), it restarts at `ta` and the next step reaches at
/// most halfway to the pivot's zero. With no other candidate, or the zero
/// closer than rounding can resolve, the run stops, naming the constraint
/// and the time where the pivot vanishes.
fn pivot_crossed(
    model: &mut dyn DynModel,
    regime: &mut Regime,
    solver: &mut dyn Solver,
    (ta, tb): (f64, f64),
    volumes: &[f64],
) -> Result<PivotCrossing, Failure> {
    let total: usize = model.constraints().iter().map(|c| c.names.len()).sum();
    let n = solver.state().len();
    let mut x_a = vec![0.0; n];
    solver.dense(model, ta, &mut x_a)?;
    let x_b = solver.state().to_vec();
    let (mut p_a, mut p_b) = (vec![0.0; total], vec![0.0; total]);
    model.pivots(ta, &x_a, &mut p_a);
    model.pivots(tb, &x_b, &mut p_b);
    let digits = mode_digits(model, regime.mode);
    let mut at = 0;
    for (index, (c, &digit)) in model.constraints().iter().zip(&digits).enumerate() {
        let (a, b) = (p_a[at + digit], p_b[at + digit]);
        if a * b < 0.0 {
            let (best, best_pivot) = largest_pivot(&p_a[at..at + c.names.len()]);
            if best != digit && best_pivot > a.abs() {
                let (mode, _, _) = best_mode(model, ta, &x_a);
                regime.mode = mode;
                model.set_regime(regime);
                solver.restart(model, ta, &x_a)?;
                return Ok(PivotCrossing::Switched);
            }
            // The pivot's zero, by linear interpolation within the step.
            let t_zero = ta + (tb - ta) * a / (a - b);
            let halfway = ta + 0.5 * (t_zero - ta);
            let resolvable = halfway - ta > 64.0 * f64::EPSILON * ta.abs().max(1.0);
            if c.names.len() > 1 && resolvable {
                solver.restart(model, ta, &x_a)?;
                return Ok(PivotCrossing::Retry(halfway));
            }
            // No other choice is better where this one vanishes: every
            // choice vanishes together, a singular configuration.
            if c.names.len() > 1 {
                let now = volumes_of(model.constraints(), &p_b);
                let start = volumes.get(index).copied().unwrap_or(f64::NAN);
                return Err(Failure::new(
                    t_zero,
                    FailureKind::SingularConfiguration {
                        constraint: c.text.to_string(),
                        ratio: now[index] / start,
                    },
                ));
            }
            // The only candidate: the zero located on the dense output
            // (a field window is long, and the pivot far from linear
            // across it: interpolated, a constant-speed particle's apex
            // at t = 0.112 was named at t = 0.348).
            let t_zero = locate_pivot_zero(model, solver, (ta, tb), at + digit, (a, t_zero))?;
            return Err(Failure::new(
                t_zero,
                FailureKind::ConstraintPivotVanishes {
                    constraint: c.text.to_string(),
                    pivot: 0.0,
                },
            ));
        }
        at += c.names.len();
    }
    Ok(PivotCrossing::None)
}

/// Bisection on the solver's dense output for the sign change of pivot
/// `which` within `[ta, tb]` (its value `a` at `ta`); `fallback` when the
/// dense output does not show it.
fn locate_pivot_zero(
    model: &dyn DynModel,
    solver: &mut dyn Solver,
    (ta, tb): (f64, f64),
    which: usize,
    (a, fallback): (f64, f64),
) -> Result<f64, Failure> {
    let total: usize = model.constraints().iter().map(|c| c.names.len()).sum();
    let mut x = vec![0.0; solver.state().len()];
    let mut p = vec![0.0; total];
    let (mut lo, mut hi) = (ta, tb);
    let mut found = false;
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if !(mid > lo && mid < hi) {
            break;
        }
        solver.dense(model, mid, &mut x)?;
        model.pivots(mid, &x, &mut p);
        if !p[which].is_finite() {
            break;
        }
        if p[which] * a > 0.0 {
            lo = mid;
        } else {
            hi = mid;
            found = true;
        }
    }
    Ok(if found { 0.5 * (lo + hi) } else { fallback })
}

/// After a step: when a constraint's current candidate has become poor
/// against its best one, continue with the best (the field re-anchors);
/// when every candidate of a constraint has vanished, stop.
fn switch_candidates(
    model: &mut dyn DynModel,
    regime: &mut Regime,
    solver: &mut dyn Solver,
    t: f64,
    volumes: &[f64],
) -> Result<(), Failure> {
    let x = solver.state().to_vec();
    let total: usize = model.constraints().iter().map(|c| c.names.len()).sum();
    let mut pivots = vec![0.0; total];
    model.pivots(t, &x, &mut pivots);
    singular_configuration(model, t, &pivots, volumes)?;
    let mut digits = mode_digits(model, regime.mode);
    let mut changed = false;
    let mut at = 0;
    for (c, digit) in model.constraints().iter().zip(digits.iter_mut()) {
        let slice = &pivots[at..at + c.names.len()];
        let (best, best_pivot) = largest_pivot(slice);
        let current = slice[*digit].abs();
        let scale = x.iter().fold(1.0_f64, |m, v| m.max(v.abs()));
        if best_pivot <= 1e-12 * scale || !best_pivot.is_finite() {
            return Err(Failure::new(
                t,
                FailureKind::ConstraintPivotVanishes {
                    constraint: c.text.to_string(),
                    pivot: current,
                },
            ));
        }
        if current < POOR_PIVOT * best_pivot {
            *digit = best;
            changed = true;
        }
        at += c.names.len();
    }
    if changed {
        regime.mode = mode_index(model, &digits);
        model.set_regime(regime);
        solver.restart(model, t, &x)?;
    }
    Ok(())
}

/// A group of constraints with several choices of dependents is at a
/// singular configuration when their pivots' volume `sqrt(Σ pivot²)` —
/// by Cauchy–Binet `sqrt(det(J Jᵀ))` of the group's Jacobian in its
/// candidates — has fallen below this fraction of its value at the start:
/// the Jacobian has lost rank, and no choice determines the dependents
/// (a four-bar at its change point, where two branches of motion meet).
const SINGULAR_VOLUME: f64 = 1e-6;

/// Each group's pivot volume `sqrt(Σ pivot²)` at `(t, x)`: below 1e-6 of its
/// value at the start, a singular configuration.
pub fn pivot_volumes(model: &dyn DynModel, t: f64, x: &[f64]) -> Vec<f64> {
    let constraints = model.constraints();
    let total: usize = constraints.iter().map(|c| c.names.len()).sum();
    let mut pivots = vec![0.0; total];
    model.pivots(t, x, &mut pivots);
    volumes_of(constraints, &pivots)
}

fn volumes_of(constraints: &[crate::model::Candidates], pivots: &[f64]) -> Vec<f64> {
    let mut at = 0;
    constraints
        .iter()
        .map(|c| {
            let v = pivots[at..at + c.names.len()]
                .iter()
                .map(|p| p * p)
                .sum::<f64>()
                .sqrt();
            at += c.names.len();
            v
        })
        .collect()
}

/// A failure naming the group whose pivot volume fell below
/// [`SINGULAR_VOLUME`] of `start` (groups with several choices only).
fn singular_configuration(
    model: &dyn DynModel,
    t: f64,
    pivots: &[f64],
    start: &[f64],
) -> Result<(), Failure> {
    let constraints = model.constraints();
    for ((c, &now), &start) in constraints
        .iter()
        .zip(&volumes_of(constraints, pivots))
        .zip(start)
    {
        if c.names.len() > 1 && start > 0.0 && now < SINGULAR_VOLUME * start {
            return Err(Failure::new(
                t,
                FailureKind::SingularConfiguration {
                    constraint: c.text.to_string(),
                    ratio: now / start,
                },
            ));
        }
    }
    Ok(())
}

/// A failure of the integration (a step size that underflows, a value
/// that is not finite) or of keeping the constraints near a singular
/// configuration is named as that: the equations divide by the vanishing
/// determinants there.
fn near_singular_configuration(
    model: &dyn DynModel,
    failure: Failure,
    x: &[f64],
    start: &[f64],
) -> Failure {
    if !matches!(
        failure.kind,
        FailureKind::StepSizeUnderflow { .. }
            | FailureKind::NonFiniteState { .. }
            | FailureKind::NonFiniteRate { .. }
            | FailureKind::ConstraintLeft { .. }
            | FailureKind::ConstraintUndefined { .. }
            | FailureKind::PositionsLeftConstraint { .. }
    ) || model.constraints().is_empty()
        || !x.iter().all(|v| v.is_finite())
    {
        return failure;
    }
    let t = failure.time;
    let now = pivot_volumes(model, t, x);
    for ((c, &now), &start) in model.constraints().iter().zip(&now).zip(start) {
        if c.names.len() > 1 && start > 0.0 && now < 1e-3 * start {
            return Failure::new(
                t,
                FailureKind::SingularConfiguration {
                    constraint: c.text.to_string(),
                    ratio: now / start,
                },
            );
        }
    }
    failure
}

/// A mass law at or below zero at `(t, x)` stops the run (the equations
/// divide by it; a law of the state, `rho * x`, needs the state).
fn check_masses(model: &dyn DynModel, t: f64, x: &[f64]) -> Result<(), Failure> {
    if model.mass_names().is_empty() {
        return Ok(());
    }
    let mut masses = vec![0.0; model.mass_names().len()];
    model.masses(t, x, &mut masses);
    match masses.iter().position(|&m| !(m > 0.0)) {
        Some(i) => Err(Failure::new(
            t,
            FailureKind::MassVanishes {
                mass: model.mass_names()[i].to_string(),
                value: masses[i],
            },
        )),
        None => Ok(()),
    }
}

/// The mass matrix's smallest scale `1/‖M⁻¹‖₁` at the start of a run: a
/// mass matrix is singular where that has shrunk by many orders of
/// magnitude (for one coordinate the condition number is always 1).
#[derive(Clone, Copy)]
pub struct MassScale(Option<f64>);

impl MassScale {
    pub fn at(model: &dyn DynModel, t: f64, x: &[f64]) -> MassScale {
        MassScale(model.mass_matrix(t, x).map(|m| smallest_scale(&m)))
    }
}

fn smallest_scale(m: &crate::linalg::Matrix) -> f64 {
    let lu = crate::linalg::Lu::new(m);
    1.0 / lu.inverse_one_norm_estimate()
}

/// The physical cause of a failure where the model can see it: a mass
/// that reaches zero, a mass matrix that becomes singular — the integrator
/// usually stops first with a step-size underflow or a non-finite value as
/// the motion blows up toward them.
pub fn diagnose(model: &dyn DynModel, failure: Failure, x: &[f64], scale: &MassScale) -> Failure {
    if matches!(
        failure.kind,
        FailureKind::InconsistentInitialValue { .. }
            | FailureKind::BadTimeSpan { .. }
            | FailureKind::StepBudgetExhausted { stalled: None, .. }
            | FailureKind::AnchorCancels { .. }
            | FailureKind::ConstraintPivotVanishes { .. }
            | FailureKind::SingularConfiguration { .. }
            | FailureKind::ConstraintUndefined { .. }
            | FailureKind::ConstraintLeft { .. }
    ) {
        return failure;
    }
    // Steps that stall may stall at a mass reaching zero (a law of the
    // state, `rho * x`, whose motion the field's windows chase to it).
    let t = failure.time;
    if !model.mass_names().is_empty() {
        let mut now = vec![0.0; model.mass_names().len()];
        let mut ahead = vec![0.0; model.mass_names().len()];
        model.masses(t, x, &mut now);
        // The integrator gives up just before the mass reaches zero; a law
        // of the state (`rho * x`) is looked at ahead along the state's
        // rate where that is finite.
        let dt = 1e-6 * t.abs().max(1e-3);
        let mut rate = vec![0.0; x.len()];
        let x_ahead: Vec<f64> = match model.rhs(t, x, &mut rate) {
            Ok(()) if rate.iter().all(|r| r.is_finite()) => {
                x.iter().zip(&rate).map(|(&xi, &ri)| xi + dt * ri).collect()
            }
            _ => x.to_vec(),
        };
        model.masses(t + dt, &x_ahead, &mut ahead);
        // A law of the state is NaN at a state that is not finite: that
        // names the state, not the mass.
        let finite = x.iter().all(|v| v.is_finite());
        let vanishes = |m: f64| !(m > 0.0) && (finite || !m.is_nan());
        for (i, (&m, &a)) in now.iter().zip(&ahead).enumerate() {
            if vanishes(m) || vanishes(a) {
                return Failure::new(
                    t,
                    FailureKind::MassVanishes {
                        mass: model.mass_names()[i].to_string(),
                        value: m,
                    },
                );
            }
        }
    }
    if matches!(
        failure.kind,
        FailureKind::StepSizeUnderflow { .. }
            | FailureKind::NonFiniteState { .. }
            | FailureKind::NonFiniteRate { .. }
            | FailureKind::SingularMassMatrix { .. }
            | FailureKind::SingularConditionMatrix { .. }
            | FailureKind::FieldNotConverging { .. }
    ) && x.iter().all(|v| v.is_finite())
    {
        // A constraint whose value or slope is not finite where the motion
        // stands (the root of `y' = sqrt(c² − x'²)` at its apex, where its
        // slope is infinite and so is the mass matrix): the constraint is
        // the cause, not the matrix it makes singular.
        if let Some(component) = undefined_constraint(model, t, x) {
            return Failure::new(t, FailureKind::ConstraintUndefined { component });
        }
    }
    if matches!(
        failure.kind,
        FailureKind::StepSizeUnderflow { .. }
            | FailureKind::NonFiniteState { .. }
            | FailureKind::NonFiniteRate { .. }
    ) && x.iter().all(|v| v.is_finite())
    {
        if let (Some(m), Some(start)) = (model.mass_matrix(t, x), scale.0) {
            let now = smallest_scale(&m);
            let condition = crate::highest::mass_condition(&m);
            if !(now > 1e-6 * start) || !(condition < 1e12) {
                return Failure::new(
                    t,
                    FailureKind::SingularMassMatrix {
                        condition: condition.max(start / now),
                    },
                );
            }
        }
    }
    failure
}

/// The fixed component whose constrained value, or its slope in the
/// velocities, is not finite at `(t, x)`.
fn undefined_constraint(model: &dyn DynModel, t: f64, x: &[f64]) -> Option<String> {
    if !model.keeps_constraints() {
        return None;
    }
    let n = x.len();
    let mut kept = x.to_vec();
    let mut gradient = crate::linalg::Matrix::zeros(n, n);
    model.constrained(t, x, &mut kept).ok()?;
    model.kept_gradient(t, x, &mut gradient).ok()?;
    let row =
        (0..n).find(|&j| !kept[j].is_finite() || (0..n).any(|i| !gradient[(j, i)].is_finite()))?;
    Some(model.state_names()[row].to_string())
}

/// Integrates `members` (at least one; the first is the reference)
/// through one field: `sample(t, states)` at every time of `times`. Exact
/// for affine models; for the others the members follow the field of the
/// motion linearised along the reference, to first order in their distance
/// from it. The members are taken, not copied, and every sample's states
/// are written into one buffer: with ten thousand members, copies and
/// fresh allocations would cost more than the field.
pub fn run_ensemble(
    model: &mut dyn DynModel,
    options: &Options,
    t0: f64,
    t1: f64,
    members: crate::ensemble::States,
    times: &[f64],
    mut sample: impl FnMut(f64, &crate::ensemble::States),
) -> Result<Outcome, Failure> {
    if model.switches() > 0 || !model.constraints().is_empty() {
        return Err(Failure::new(t0, FailureKind::NotAffine));
    }
    let budget = Budget::new(options.max_steps);
    budget.accepted_to(t0);
    let h_max = (t1 - t0).max(f64::MIN_POSITIVE);
    let field = Options {
        method: Method::Field,
        ..options.clone()
    };
    assert!(!members.is_empty(), "an ensemble has a reference member");
    let mut solver = make_solver(model, &field, t0, members.row(0), h_max)?;
    let mut next = 0;
    while next < times.len() && times[next] <= t0 {
        sample(times[next], &members);
        next += 1;
    }
    let mut states = crate::ensemble::States::default();
    if !solver.track_members(members) {
        return Err(Failure::new(t0, FailureKind::NotAffine));
    }
    while solver.time() < t1 {
        solver.advance(model, t1, &budget)?;
        budget.accepted_to(solver.time());
        while next < times.len() && times[next] <= solver.time() {
            solver.members_at(model, times[next], &mut states)?;
            sample(times[next], &states);
            next += 1;
        }
    }
    Ok(Outcome {
        report: solver.report(),
        ending: Ending::End,
        events: 0,
        budget_used: budget.used(),
        kept: None,
    })
}
