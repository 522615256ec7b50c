//! The regime a run integrates in: the switching functions' branches at
//! the start, the mode (each constraint's candidate dependent) chosen by
//! the largest pivots and changed when the current one becomes poor or
//! is crossed within a step, and the singular configurations where no
//! choice is good.

use crate::failure::{Failure, FailureKind};
use crate::method::solver::Solver;
use crate::model::{DynModel, Regime};

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
    use crate::run::keep::check_given_fixed;
    // Mode 0's candidate without a pivot at the start (a constant-speed
    // particle thrown level, `y' = 0` for `x'^2 + y'^2 = c^2 for y' or
    // x'`): checked in the mode the run starts in, where the constraint
    // allows the start; refused before, "which require y' = NaN".
    let several = model.fixed_components().len() > 1;
    if !check_given_fixed(model, 0, t0, x0, !several)? {
        let mode = best_mode(model, t0, x0).0;
        let mut in_mode = model.boxed_clone();
        in_mode.set_regime(&Regime {
            mode,
            branches: initial_branches(model, t0, x0),
        });
        check_given_fixed(&*in_mode, mode, t0, x0, true)?;
    }
    check_first_candidates(model, t0, x0)
}

/// The pivot part of [`check_initial_candidates`]: also the cause to name
/// first when an initial value the constraints fix is not finite (a
/// Cartesian pendulum started level with its pivot by `--init`, where
/// `y' = -x x'/y` is 0/0), since the pivots of a holonomic constraint
/// need only the positions.
pub fn check_first_candidates(model: &dyn DynModel, t0: f64, x0: &[f64]) -> Result<(), Failure> {
    let constraints = model.constraints();
    if constraints.is_empty() {
        return Ok(());
    }
    let total: usize = constraints.iter().map(|c| c.names.len()).sum();
    let mut pivots = vec![0.0; total];
    model.pivots(t0, x0, &mut pivots);
    let state = model.state_names();
    let mut at = 0;
    for c in constraints {
        let slice = &pivots[at..at + c.names.len()];
        at += c.names.len();
        // A constraint of order two or more fixes a derivative that is not
        // state (`x'*x'' + y'*y'' = 0 for y'' or x''`): it fixes no initial
        // value, and the run starts on its best candidate. Checked, a
        // particle thrown level (y' = 0) stopped at t = 0 asking for a
        // `y''` no initial value can give.
        if !state.contains(&c.names[0]) {
            continue;
        }
        let (best, best_pivot) = largest_pivot(slice);
        let ratio = slice[0].abs() / best_pivot;
        if best != 0 && ratio < INITIAL_PIVOT_RATIO && !completed_by_stated_values(model, t0, x0) {
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

/// Whether the state the first candidates could not complete (their
/// values are not finite there: the model stated the value one of them
/// leaves free, a pendulum in `x, y` released level with `x' = y' = 0`
/// given, where `y' = -x x'/y` is 0/0) is on the constraints as the mode
/// the run starts in solves them: every component that mode fixes as it
/// fixes it, to the agreement required of stated values. A first
/// candidate whose value is finite but huge (a knife edge at heading π/2,
/// `y' = x' tan(π/2)` = 1.6e16) is not such a state: refused as before.
fn completed_by_stated_values(model: &dyn DynModel, t0: f64, x0: &[f64]) -> bool {
    if x0.iter().any(|v| !v.is_finite()) {
        return false;
    }
    let branches = initial_branches(model, t0, x0);
    let fixed_in = |mode: usize, kept: &mut Vec<f64>, fixed: &mut Vec<usize>| {
        let mut model_in_mode = model.boxed_clone();
        model_in_mode.set_regime(&Regime {
            mode,
            branches: branches.clone(),
        });
        kept.clear();
        kept.extend_from_slice(x0);
        crate::run::keep::fixed_components(&*model_in_mode, mode, fixed);
        model_in_mode.constrained(t0, x0, kept).is_ok()
    };
    let (mut kept, mut fixed) = (Vec::new(), Vec::new());
    let first = mode_index(model, &vec![0; model.constraints().len()]);
    let first_completes =
        fixed_in(first, &mut kept, &mut fixed) && fixed.iter().all(|&j| kept[j].is_finite());
    if first_completes {
        return false;
    }
    let best = best_mode(model, t0, x0).0;
    fixed_in(best, &mut kept, &mut fixed)
        && fixed
            .iter()
            .all(|&j| (kept[j] - x0[j]).abs() <= 1e-9 * x0[j].abs().max(1.0))
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

/// What a step across a vanishing pivot calls for.
pub enum PivotCrossing {
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
pub fn pivot_crossed(
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
        let candidates_a = &p_a[at..at + c.names.len()];
        if a * b < 0.0 {
            if retake_with_better_candidate(model, regime, solver, (ta, &x_a), candidates_a, digit)?
            {
                return Ok(PivotCrossing::Switched);
            }
            // The pivot's zero, by linear interpolation within the step.
            let t_zero = ta + (tb - ta) * a / (a - b);
            let halfway = ta + 0.5 * (t_zero - ta);
            let resolvable = halfway - ta > 64.0 * f64::EPSILON * ta.abs().max(1.0);
            if c.names.len() > 1 && resolvable {
                solver.retake(model, ta, &x_a)?;
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
        // A step that took the current candidate from good to poor (below
        // [`POOR_PIVOT`] of the best, where [`switch_candidates`] replaces
        // it at the step's end) divided by a pivot falling fast within it,
        // and DOP853's estimate does not see the error of such a step
        // ([`Solver::retakes_steps_into_poor_pivots`]):
        // Chaplygin's sleigh at rtol 1e-8, one step taking its heading's
        // sine from 0.49 to 0.08 of the unit, made 0.9 rtol in its spin
        // where the estimate said 0.005, and the run ended 10 rtol off.
        // With a better candidate at the step's start the step is taken
        // again from there in that mode.
        let (best_b, best_b_pivot) = largest_pivot(&p_b[at..at + c.names.len()]);
        if solver.retakes_steps_into_poor_pivots()
            && best_b != digit
            && b.abs() < POOR_PIVOT * best_b_pivot
            && retake_with_better_candidate(model, regime, solver, (ta, &x_a), candidates_a, digit)?
        {
            return Ok(PivotCrossing::Switched);
        }
        at += c.names.len();
    }
    Ok(PivotCrossing::None)
}

/// When a candidate of the constraint (pivots `candidates_a` at the
/// step's start `(ta, x_a)`) is better there than the current one
/// (`digit`), the run goes back to `ta` in the best mode and the step is
/// taken again (`Solver::retake`): true.
fn retake_with_better_candidate(
    model: &mut dyn DynModel,
    regime: &mut Regime,
    solver: &mut dyn Solver,
    (ta, x_a): (f64, &[f64]),
    candidates_a: &[f64],
    digit: usize,
) -> Result<bool, Failure> {
    let (best, best_pivot) = largest_pivot(candidates_a);
    if best == digit || best_pivot <= candidates_a[digit].abs() {
        return Ok(false);
    }
    let (mode, _, _) = best_mode(model, ta, x_a);
    regime.mode = mode;
    model.set_regime(regime);
    solver.retake(model, ta, x_a)?;
    Ok(true)
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
pub fn switch_candidates(
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

/// The mode a model of several modes goes on in after an impact whose
/// resets set the components `targets` (`x`: the state with the resets
/// applied, the fixed components not yet recomputed): the mode the run
/// is in (`current`) where it leaves every target free and its pivots
/// are not poor (as [`switch_candidates`] judges them), else the free
/// mode with the best pivots, chosen afresh for the new state as at the
/// start ([`best_mode`]). A target the current mode fixes is a component
/// the user meant to set (a bead on a hoop in `x, y` near its side, in
/// the mode solving for `x'`, with `x'` reset): in the mode that solves
/// for the other candidate the reset holds and the constraint moves the
/// rest. Where every mode with good pivots fixes a target, the reset
/// contradicts the constraint: the run stops, naming the `when`
/// (`condition`), the component and the constraint, instead of undoing
/// the reset or dividing by a vanishing pivot.
pub fn mode_after_resets(
    model: &dyn DynModel,
    current: usize,
    targets: &[usize],
    condition: &str,
    t: f64,
    x: &[f64],
) -> Result<usize, Failure> {
    let fixed = model.fixed_components();
    let constraints = model.constraints();
    if fixed.len() <= 1 || constraints.is_empty() {
        return Ok(current);
    }
    let total: usize = constraints.iter().map(|c| c.names.len()).sum();
    let mut pivots = vec![0.0; total];
    model.pivots(t, x, &mut pivots);
    // A mode's worst ratio of a chosen pivot to its constraint's best.
    let score = |mode: usize| -> f64 {
        let mut at = 0;
        let mut worst = f64::INFINITY;
        for (c, digit) in constraints.iter().zip(mode_digits(model, mode)) {
            let slice = &pivots[at..at + c.names.len()];
            let (_, best) = largest_pivot(slice);
            let ratio = slice[digit].abs() / best;
            worst = worst.min(if ratio.is_finite() { ratio } else { 0.0 });
            at += c.names.len();
        }
        worst
    };
    let free = |mode: usize| targets.iter().all(|j| !fixed[mode].contains(j));
    if free(current) && score(current) >= POOR_PIVOT {
        return Ok(current);
    }
    let chosen = (0..fixed.len())
        .filter(|&m| free(m))
        .map(|m| (m, score(m)))
        .filter(|&(_, s)| s >= POOR_PIVOT)
        .fold(None, |best: Option<(usize, f64)>, c| match best {
            Some(b) if b.1 >= c.1 => Some(b),
            _ => Some(c),
        });
    if let Some((mode, _)) = chosen {
        return Ok(mode);
    }
    // The target the modes with good pivots fix, and its constraint (the
    // one naming its coordinate among the candidates).
    let names = model.state_names();
    let good: Vec<usize> = (0..fixed.len())
        .filter(|&m| score(m) >= POOR_PIVOT)
        .collect();
    let target = targets
        .iter()
        .copied()
        .find(|j| good.iter().any(|&m| fixed[m].contains(j)))
        .or_else(|| targets.first().copied())
        .unwrap_or(0);
    let component = names.get(target).copied().unwrap_or("?");
    let coordinate = component.trim_end_matches('\'');
    let constraint = constraints
        .iter()
        .find(|c| {
            c.names
                .iter()
                .any(|n| n.trim_end_matches('\'') == coordinate)
        })
        .unwrap_or(&constraints[0]);
    Err(Failure::new(
        t,
        FailureKind::ResetOfFixedComponent {
            condition: condition.to_string(),
            component: component.to_string(),
            constraint: constraint.text.to_string(),
        },
    ))
}
