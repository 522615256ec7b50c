//! The run: one method advancing the model step by step; the output at the
//! requested times from the dense output (so output never constrains the
//! steps); events — a switching function changing sign, located by root
//! finding on the dense output, the integrator (or the field) restarted
//! there in the new regime; implicit constraints switching candidates; and
//! `stop when`. The run's state and its loop are the steppable
//! [`crate::integration::Integration`]; [`run`] and [`solve`] are loops
//! over it, and this module keeps what they share: the options, the
//! outcome, the regime's choice (branches, candidates), the checks and the
//! diagnosis of failures.

use crate::budget::Budget;
use crate::direct::Direct;
use crate::events::SwitchPace;
use crate::failure::{Failure, FailureKind};
use crate::field::affine::AffineField;
use crate::field::quasilinear::QuasilinearField;
use crate::field::{Anchor, FieldOptions};
use crate::integration::{Advance, Integration};
use crate::method::{IntegratorChoice, Method};
use crate::model::{DynModel, Regime};
use crate::solution::Solution;
use crate::solver::{Report, Solver};
use crate::tolerance::Tolerance;

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
/// when` ends the run early, at the stop time: a loop over an
/// [`Integration`].
pub fn run(
    model: &mut dyn DynModel,
    options: &Options,
    t0: f64,
    t1: f64,
    x0: &[f64],
    times: &[f64],
    mut sample: impl FnMut(&dyn DynModel, f64, &[f64]) -> Result<(), Failure>,
) -> Result<Outcome, Failure> {
    let mut integration = Integration::new(model, options, t0, t1, x0);
    // The last sample's time: a run that ends where a sample was written
    // does not write that row twice.
    let mut last: Option<f64> = None;
    for &t in times {
        match integration.advance_to(t)? {
            Advance::Reached(_) => {
                sample(integration.model(), t, integration.state())?;
                last = Some(t);
            }
            Advance::Ended(_) => break,
        }
    }
    let outcome = integration.finish()?;
    if let Ending::Stopped(at) | Ending::Rest { at, .. } = outcome.ending {
        if last != Some(at) {
            sample(integration.model(), at, integration.state())?;
        }
    }
    Ok(outcome)
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
    let mut integration = Integration::new(model, options, t0, t1, x0);
    integration.keep_pieces();
    let outcome = integration.finish()?;
    Ok(Solution {
        t0,
        x0: x0.to_vec(),
        pieces: integration.take_pieces(),
        outcome,
    })
}

/// The switching functions' pace where a solve starts, before any step
/// has shown it: from probes ahead at a hundredth to a millionth of the
/// span, the motion followed to second order (two right sides a probe),
/// the fastest pace any probe shows. One scale is not enough: a
/// millionth is rounding's size for the curvature of `sin(20 t)` near its
/// zero, a hundredth is five periods of `sin(500 t)`. Unpaced, the first
/// step of a force switched by `sin(500 t)` stepped over switches.
pub(crate) fn probe_pace(
    model: &dyn DynModel,
    t: f64,
    x: &[f64],
    span: f64,
    pace: &mut SwitchPace,
) {
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
pub(crate) fn observe_to_event(
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
pub(crate) enum PivotCrossing {
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
pub(crate) fn pivot_crossed(
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
pub(crate) fn switch_candidates(
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
pub(crate) fn near_singular_configuration(
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
pub(crate) fn check_masses(model: &dyn DynModel, t: f64, x: &[f64]) -> Result<(), Failure> {
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
