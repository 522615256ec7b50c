//! Initial values of the state (6) (SPEC §1.4): given by the user, fixed by
//! the constraints (dependent derivatives of order ≥ k), or solved from (4)
//! and its derivatives (independent `q_i^(2..k−1)`, k ≥ 3). A given value
//! that the constraints or the equations fix is checked at `t0` with the
//! params at their defaults (E0013).

use super::reduced::{Closure, Consistency, InitialValue};
use super::star::Elimination;
use super::symbols::{lower_checked, Symbolic};
use crate::check::model::Model;
use crate::diagnostic::{codes, Diagnostic};
use crate::ir::{Arena, ExprId, Symbol};
use nalgebra::{DMatrix, DVector};
use std::collections::HashMap;

/// Relative agreement required between a given value and the value the
/// constraints or the equations fix.
const TOLERANCE: f64 = 1e-9;
const NEWTON_STEPS: usize = 50;

/// The state's initial values, in state order.
/// With holonomic constraints, the given positions of their dependents
/// are starting values: Newton (at the params' defaults here, at run time
/// in the generated code) moves them onto the constraints, and a move
/// beyond the agreement required of given values is a note. `levels`:
/// for k ≥ 2, the dependents' derivatives of order 1..k−1 that the
/// holonomic constraints fix.
#[allow(clippy::too_many_arguments)]
pub fn initial_values(
    arena: &mut Arena,
    model: &Model,
    symbolic: &Symbolic,
    elimination: &mut Elimination,
    state: &[Symbol],
    consistency: &[Consistency],
    closure: Option<&Closure>,
    levels: &HashMap<Symbol, ExprId>,
    raised: &[Raised],
    raised_groups: &[Closure],
) -> Result<(Vec<InitialValue>, Vec<Diagnostic>), Vec<Diagnostic>> {
    let mut errors = Vec::new();
    let t0 = lower_checked(arena, &model.time.start, model)
        .map(|e| arena.eval(e, &|s| param_env(symbolic, s)))
        .map_err(|d| vec![d])?;
    let laws_at_t0: Vec<f64> = symbolic
        .laws
        .iter()
        .map(|&law| arena.eval(law, &|s| at(symbolic, t0, &[], &HashMap::new(), s)))
        .collect();
    let mut values: HashMap<Symbol, f64> = HashMap::new();
    let mut initial = Vec::with_capacity(state.len());
    // Pass 1: what the user gives and what the constraints fix.
    let mut given: HashMap<Symbol, (ExprId, &crate::check::model::Initial)> = HashMap::new();
    for value in &model.initial {
        let symbol = Symbol::Jet {
            coord: value.coord as u32,
            order: value.order,
        };
        match lower_checked(arena, &value.value, model) {
            Ok(e) => {
                values.insert(symbol, arena.eval(e, &|s| param_env(symbolic, s)));
                given.insert(symbol, (e, value));
            }
            Err(d) => errors.push(d),
        }
    }
    for &symbol in state {
        let Symbol::Jet { coord, order } = symbol else {
            continue;
        };
        let dependent = symbolic.constraints.iter().any(|&(d, _)| d == coord);
        if dependent && order >= symbolic.k {
            let fixed = elimination.image(arena, coord, order);
            initial.push(InitialValue::Constraint(fixed));
            continue;
        }
        if let Some(&fixed) = levels.get(&symbol) {
            initial.push(InitialValue::Constraint(fixed));
            continue;
        }
        if !dependent && order >= 2 {
            initial.push(InitialValue::Solved);
            continue;
        }
        let completed_by_newton =
            order == 0 && closure.is_some_and(|closure| closure.unknowns.contains(&symbol));
        match given.get(&symbol) {
            Some(&(e, _)) => initial.push(InitialValue::Given(e)),
            // A dependent position not given: Newton on the constraints
            // starts from 0 (here and at run time), note N0003.
            None if completed_by_newton => {
                let zero = arena.zero();
                initial.push(InitialValue::Given(zero));
                values.insert(symbol, 0.0);
            }
            None => errors.push(
                Diagnostic::error(
                    codes::MISSING_INITIAL,
                    format!("missing initial value for `{}`", arena.symbol_name(symbol)),
                )
                .with_primary(model.time.span, "the motion starts here"),
            ),
        }
    }
    if !errors.is_empty() {
        return Err(errors);
    }
    // Pass 2: the positions the holonomic constraints fix, by Newton from
    // the given ones.
    let mut notes = Vec::new();
    if let Some(closure) = closure {
        let env_values = values.clone();
        let start: Vec<f64> = closure
            .unknowns
            .iter()
            .map(|z| env_values.get(z).copied().unwrap_or(f64::NAN))
            .collect();
        let env = |s: Symbol| at(symbolic, t0, &laws_at_t0, &env_values, s);
        match closure_newton(arena, closure, &start, &env) {
            Ok(solution) => {
                for ((&z, &from), &to) in closure.unknowns.iter().zip(&start).zip(&solution) {
                    if !given.contains_key(&z) {
                        let name = arena.symbol_name(z);
                        notes.push(
                            Diagnostic::note_diagnostic(
                                codes::INITIAL_POSITION_COMPLETED,
                                format!("the initial value of `{name}` is completed from the constraints"),
                            )
                            .with_primary(model.time.span, "the motion starts here")
                            .with_note(format!(
                                "`{name}` is not given: at t = {t0}, Newton on `{}` from \
                                 `{name}` = 0 gives `{name}` = {to} (params at their defaults); \
                                 the run starts there",
                                closure.text
                            ))
                            .with_help(format!(
                                "give `{name} = …` to start near another configuration \
                                 the constraints allow"
                            )),
                        );
                    } else if !close(from, to) {
                        if let Some(&(_, user)) = given.get(&z) {
                            let name = arena.symbol_name(z);
                            notes.push(
                                Diagnostic::note_diagnostic(
                                    codes::INITIAL_POSITION_CORRECTED,
                                    format!("the initial value of `{name}` is moved onto the constraints"),
                                )
                                .with_primary(user.span, format!("`{name}` = {from} here"))
                                .with_note(format!(
                                    "at t = {t0}, Newton on `{}` from the given positions \
                                     gives `{name}` = {to} (params at their defaults); the \
                                     run starts there",
                                    closure.text
                                ))
                                .with_help(format!("give `{name}` = {to} to start there as written")),
                            );
                        }
                    }
                    values.insert(z, to);
                }
            }
            Err(why) => {
                let z = closure.unknowns[0];
                let name = arena.symbol_name(z);
                let mut diagnostic = Diagnostic::error(
                    codes::INCONSISTENT_INITIAL,
                    format!(
                        "the initial positions cannot be brought onto `{}`",
                        closure.text
                    ),
                )
                .with_note(format!(
                    "at t = {t0}, Newton on the dependent coordinates from the given values \
                     (params at their defaults): {why}"
                ))
                .with_help(format!(
                    "give `{name}` (and the other dependent coordinates) closer to a \
                     configuration that satisfies the constraints"
                ));
                let omitted: Vec<String> = closure
                    .unknowns
                    .iter()
                    .filter(|z| !given.contains_key(z))
                    .map(|&z| format!("`{}`", arena.symbol_name(z)))
                    .collect();
                if !omitted.is_empty() {
                    diagnostic = diagnostic.with_note(format!(
                        "{} not given: Newton started from 0 there",
                        omitted.join(", ")
                    ));
                }
                diagnostic = match given.get(&z) {
                    Some(&(_, user)) => {
                        diagnostic.with_primary(user.span, "starting from this value")
                    }
                    None => diagnostic.with_primary(model.time.span, "the motion starts here"),
                };
                errors.push(diagnostic);
                return Err(errors);
            }
        }
    }
    // Pass 3: the values the constraints fix (they depend on given values only).
    let env_values = values.clone();
    // Given values the first candidates cannot fix at the start (their
    // pivots vanish there): taken as given when every constraint holds.
    let mut taken_as_given = Vec::new();
    for (&symbol, value) in state.iter().zip(&initial) {
        if let InitialValue::Constraint(fixed) = value {
            let required = arena.eval(*fixed, &|s| at(symbolic, t0, &laws_at_t0, &env_values, s));
            if !required.is_finite() && given.contains_key(&symbol) {
                taken_as_given.push((symbol, required));
                continue;
            }
            // The first such value only: the ones after it are usually
            // not finite through it (a helix's `z'` through `y'`).
            if !required.is_finite() {
                errors.push(undetermined(
                    arena,
                    model,
                    symbol,
                    required,
                    t0,
                    given.get(&symbol),
                ));
                break;
            }
            if let Some(&(_, user)) = given.get(&symbol) {
                let got = values[&symbol];
                if !close(got, required) {
                    let name = arena.symbol_name(symbol);
                    errors.push(
                        Diagnostic::error(
                            codes::INCONSISTENT_INITIAL,
                            format!("the initial value of `{name}` violates a constraint"),
                        )
                        .with_primary(user.span, format!("`{name}` = {got} here"))
                        .with_note(format!(
                            "at t = {t0} the constraint requires `{name}` = {required} \
                             (params at their defaults)"
                        ))
                        .with_help("omit it: lagc computes it from the constraint"),
                    );
                }
            }
            values.insert(symbol, required);
        }
    }
    // A pendulum in `x, y` released level with its pivot, `x' = y' = 0`
    // given: `y' = -x x'/y` is 0/0 there, but the values the user gives
    // hold every constraint, and the run starts on the candidates whose
    // pivots do not vanish (`x'` fixed from `y'`).
    if let Some(&(symbol, required)) = taken_as_given.first() {
        if errors.is_empty() && !constraints_hold(arena, model, symbolic, t0, &laws_at_t0, &values)
        {
            let name = arena.symbol_name(symbol);
            let mut diagnostic =
                undetermined(arena, model, symbol, required, t0, given.get(&symbol));
            diagnostic.message = format!(
                "the initial values violate a constraint where it does not determine `{name}`"
            );
            diagnostic.notes = vec![format!(
                "at t = {t0} solving the constraint for `{name}` gives {required} (its pivot \
                 vanishes), so the given `{name}` stands; with it the given values break the \
                 constraint (params at their defaults)"
            )];
            diagnostic.help = Some(
                "give values that hold the constraint, or leave out the one it can fix".to_string(),
            );
            errors.push(diagnostic);
        }
    }
    // Pass 4: the consistency stages (k ≥ 3), in order.
    for stage in consistency {
        let env_values = values.clone();
        let Some(solution) = solve_stage(arena, stage, &|s| {
            at(symbolic, t0, &laws_at_t0, &env_values, s)
        }) else {
            continue;
        };
        for (&z, &required) in stage.unknowns.iter().zip(&solution) {
            if let Some(&(_, user)) = given.get(&z) {
                let got = values[&z];
                if !close(got, required) {
                    let name = arena.symbol_name(z);
                    errors.push(
                        Diagnostic::error(
                            codes::INCONSISTENT_INITIAL,
                            format!(
                                "the initial value of `{name}` contradicts the equations of motion"
                            ),
                        )
                        .with_primary(user.span, format!("`{name}` = {got} here"))
                        .with_note(format!(
                            "at t = {t0} equations (4) and the other initial values require \
                             `{name}` = {required} (params at their defaults)"
                        ))
                        .with_help("omit it: lagc computes it from the equations of motion"),
                    );
                }
            }
            values.insert(z, required);
        }
    }
    // Pass 5: a raised constraint's candidate is given (a non-linear
    // constraint has several roots: the user's value says which the
    // motion starts on) and must satisfy it; Newton from the given value
    // names the root near it, or says there is none.
    for r in raised {
        let Some(&(_, user)) = given.get(&r.candidate) else {
            continue;
        };
        let env_values = values.clone();
        let got = values[&r.candidate];
        let root = raised_newton(arena, r, got, &|s| {
            at(symbolic, t0, &laws_at_t0, &env_values, s)
        });
        if root.as_ref().is_ok_and(|&root| close(got, root)) {
            continue;
        }
        let name = arena.symbol_name(r.candidate);
        let diagnostic = Diagnostic::error(
            codes::INCONSISTENT_INITIAL,
            format!("the initial value of `{name}` violates a constraint"),
        )
        .with_primary(user.span, format!("`{name}` = {got} here"));
        errors.push(match root {
            Ok(root) => diagnostic
                .with_note(format!(
                    "at t = {t0}, `{}` holds at `{name}` = {root} near it \
                     (Newton from the given value, params at their defaults)",
                    r.text
                ))
                .with_help(format!("give `{name}` = {root}")),
            Err(why) => diagnostic
                .with_note(format!(
                    "at t = {t0}, Newton on `{}` from the given value finds no root \
                     (params at their defaults): {why}",
                    r.text
                ))
                .with_help("give initial values on which the constraint can hold"),
        });
    }
    // Pass 5 for a group of raised constraints (`raised.rs`): Newton over
    // its candidates from the given values, each of which must be the
    // root's.
    for g in raised_groups {
        let user_given: Vec<(usize, &crate::check::model::Initial)> = g
            .unknowns
            .iter()
            .enumerate()
            .filter_map(|(i, z)| given.get(z).map(|&(_, user)| (i, user)))
            .collect();
        if user_given.is_empty() {
            continue;
        }
        let env_values = values.clone();
        let start: Vec<f64> = g
            .unknowns
            .iter()
            .map(|z| values.get(z).copied().unwrap_or(f64::NAN))
            .collect();
        let root = closure_newton(arena, g, &start, &|s| {
            at(symbolic, t0, &laws_at_t0, &env_values, s)
        });
        // On the constraints, but where they do not determine this
        // choice's candidates (`J` singular): the kept values are 0/0 there.
        if let Ok(root) = &root {
            let lookup = |s: Symbol| match g.unknowns.iter().position(|&u| u == s) {
                Some(i) => root[i],
                None => at(symbolic, t0, &laws_at_t0, &env_values, s),
            };
            let m = g.unknowns.len();
            let entries: Vec<ExprId> = g.jacobian.iter().flatten().copied().collect();
            let j = DMatrix::from_row_slice(m, m, &arena.eval_many(&entries, &lookup));
            let scale: f64 = j
                .row_iter()
                .map(|r| r.iter().fold(0.0_f64, |a, v| a.max(v.abs())))
                .product();
            let det = j.determinant();
            // NaN is not determined either.
            let determined = det.abs() > 1e-12 * scale;
            if !determined {
                let names: Vec<String> = g
                    .unknowns
                    .iter()
                    .map(|&z| format!("`{}`", arena.symbol_name(z)))
                    .collect();
                let (_, user) = user_given[0];
                errors.push(
                    Diagnostic::error(
                        codes::INCONSISTENT_INITIAL,
                        format!(
                            "at the initial values the constraints solved together do not \
                             determine {}",
                            names.join(", ")
                        ),
                    )
                    .with_primary(user.span, "the initial values given here")
                    .with_note(format!(
                        "at t = {t0}, the Jacobian of `{}` in {} is singular (determinant \
                         {det:.3e}, params at their defaults): the motion would start at the \
                         end of a branch",
                        g.text,
                        names.join(", ")
                    ))
                    .with_help(
                        "name first after `for` the candidates the constraints determine at \
                         the start, or start elsewhere",
                    ),
                );
                continue;
            }
        }
        let off = match &root {
            Ok(root) => user_given
                .iter()
                .find(|&&(i, _)| !close(start[i], root[i]))
                .copied(),
            Err(_) => user_given.first().copied(),
        };
        let Some((i, user)) = off else {
            continue;
        };
        let name = arena.symbol_name(g.unknowns[i]);
        let got = start[i];
        let diagnostic = Diagnostic::error(
            codes::INCONSISTENT_INITIAL,
            format!("the initial value of `{name}` violates a constraint"),
        )
        .with_primary(user.span, format!("`{name}` = {got} here"));
        errors.push(match root {
            Ok(root) => {
                // Every candidate the root moves, in one help: each alone
                // would be refused again for the next.
                let moved: Vec<String> = g
                    .unknowns
                    .iter()
                    .zip(&root)
                    .zip(&start)
                    .filter(|((_, r), s)| !close(**s, **r))
                    .map(|((&z, r), _)| format!("`{}` = {r}", arena.symbol_name(z)))
                    .collect();
                diagnostic
                    .with_note(format!(
                        "at t = {t0}, `{}` hold at {} near the given values \
                         (Newton over the constraints' candidates, params at their defaults)",
                        g.text,
                        moved.join(", ")
                    ))
                    .with_help(format!("give {}", moved.join(", ")))
            }
            Err(why) => diagnostic
                .with_note(format!(
                    "at t = {t0}, Newton on `{}` from the given values finds no root \
                     (params at their defaults): {why}",
                    g.text
                ))
                .with_help("give initial values on which the constraints can hold"),
        });
    }
    if errors.is_empty() {
        Ok((initial, notes))
    } else {
        Err(errors)
    }
}

/// A constraint solved through its derivative (`check::model::Implicit::
/// raised`): `residual = f = 0` as written, in its candidate of order
/// k − 1 (this mode's), with `pivot = ∂f/∂candidate`.
#[derive(Debug, Clone)]
pub struct Raised {
    pub candidate: Symbol,
    pub residual: ExprId,
    pub pivot: ExprId,
    pub text: String,
}

/// Newton on `f(v) = 0` from `v`, the other values from `env`: the root,
/// or why there is none near `v`.
fn raised_newton(
    arena: &Arena,
    r: &Raised,
    start: f64,
    env: &dyn Fn(Symbol) -> f64,
) -> Result<f64, String> {
    let mut v = start;
    let eval = |v: f64, e: ExprId| arena.eval(e, &|s| if s == r.candidate { v } else { env(s) });
    for _ in 0..NEWTON_STEPS {
        let f = eval(v, r.residual);
        let pivot = eval(v, r.pivot);
        if !f.is_finite() {
            return Err(format!("the constraint is not defined there ({f})"));
        }
        if f == 0.0 {
            return Ok(v);
        }
        let step = f / pivot;
        if !step.is_finite() || pivot == 0.0 {
            return Err(format!(
                "its derivative in the candidate vanishes (residual {:.3e})",
                f.abs()
            ));
        }
        // Halved while the residual does not decrease.
        // (A NaN residual does not decrease.)
        let decreases = |next: f64| eval(next, r.residual).abs() < f.abs();
        let mut scale = 1.0;
        let mut next = v - step;
        while !decreases(next) && scale > 1e-3 {
            scale *= 0.5;
            next = v - scale * step;
        }
        if !decreases(next) {
            if step.abs() <= 1e-9 * v.abs().max(1.0) {
                return Ok(v);
            }
            return Err(format!("it stalls with the residual {:.3e}", f.abs()));
        }
        v = next;
        if step.abs() <= 4.0 * f64::EPSILON * v.abs().max(1.0) {
            return Ok(v);
        }
    }
    Err(format!("no convergence in {NEWTON_STEPS} steps"))
}

/// Newton on `f(t0, q) = 0` over the closure's unknowns from `start`,
/// halving a step that does not decrease the residual; the solution, or
/// why there is none.
fn closure_newton(
    arena: &Arena,
    closure: &Closure,
    start: &[f64],
    env: &dyn Fn(Symbol) -> f64,
) -> Result<Vec<f64>, String> {
    let n = start.len();
    let mut z = start.to_vec();
    let entries: Vec<ExprId> = closure.jacobian.iter().flatten().copied().collect();
    let residual = |z: &[f64]| {
        let lookup = |s: Symbol| match closure.unknowns.iter().position(|&u| u == s) {
            Some(i) => z[i],
            None => env(s),
        };
        arena.eval_many(&closure.residual, &lookup)
    };
    let norm = |r: &[f64]| r.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    if z.iter().any(|v| !v.is_finite()) {
        return Err("a given value is not finite".to_string());
    }
    let mut r = residual(&z);
    for _ in 0..NEWTON_STEPS {
        if norm(&r) == 0.0 {
            return Ok(z);
        }
        let lookup = |s: Symbol| match closure.unknowns.iter().position(|&u| u == s) {
            Some(i) => z[i],
            None => env(s),
        };
        let j = arena.eval_many(&entries, &lookup);
        let Some(step) = DMatrix::from_row_slice(n, n, &j)
            .lu()
            .solve(&DVector::from_vec(r.clone()))
        else {
            // On the constraints but for rounding, where no step can be
            // taken (the generated code's Newton takes the same rule).
            if lagc_runtime::closure::on_constraints_by_rounding(norm(&r), &z) {
                return Ok(z);
            }
            return Err(format!(
                "the constraints' Jacobian in the dependent coordinates is singular there \
                 (residual {:.3e})",
                norm(&r)
            ));
        };
        let mut scale = 1.0;
        let (mut next, mut r_next);
        loop {
            next = z
                .iter()
                .zip(step.iter())
                .map(|(z, d)| z - scale * d)
                .collect::<Vec<_>>();
            r_next = residual(&next);
            if norm(&r_next) < norm(&r) || scale < 1e-3 {
                break;
            }
            scale *= 0.5;
        }
        let full = step.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let magnitude = z.iter().fold(1.0_f64, |m, v| m.max(v.abs()));
        if norm(&r_next) >= norm(&r) || norm(&r_next).is_nan() {
            // Rounding: the residual no longer decreases, and the step
            // that would reduce it is at the level of rounding.
            if full <= 1e-9 * magnitude {
                return Ok(z);
            }
            return Err(format!(
                "it stalls with the residual {:.3e} (no configuration near the given one)",
                norm(&r)
            ));
        }
        z = next;
        r = r_next;
        if full <= 4.0 * f64::EPSILON * magnitude {
            return Ok(z);
        }
    }
    Err(format!(
        "no convergence in {NEWTON_STEPS} steps (residual {:.3e})",
        norm(&r)
    ))
}

/// Whether every constraint holds at `t0` with `values` (each of its
/// order; a holonomic one as `f = 0` and its derivatives up to the
/// constraints' order `k`), each residual within [`TOLERANCE`] of its
/// terms' size `Σ |∂r/∂s| |s|` over the jets and time it holds.
fn constraints_hold(
    arena: &mut Arena,
    model: &Model,
    symbolic: &Symbolic,
    t0: f64,
    laws: &[f64],
    values: &HashMap<Symbol, f64>,
) -> bool {
    let mut residuals = Vec::new();
    for c in &model.constraints {
        let Ok(rhs) = lower_checked(arena, &c.rhs, model) else {
            return false;
        };
        match &c.implicit {
            Some(implicit) => {
                let Ok(lhs) = lower_checked(arena, &implicit.lhs, model) else {
                    return false;
                };
                let f = arena.sub(lhs, rhs);
                if implicit.holonomic {
                    let mut level = f;
                    residuals.push(level);
                    for _ in 0..symbolic.k {
                        level = arena.total_derivative(level);
                        residuals.push(level);
                    }
                } else {
                    residuals.push(f);
                }
            }
            None => {
                let dependent = arena.symbol(Symbol::Jet {
                    coord: c.coord as u32,
                    order: c.order,
                });
                residuals.push(arena.sub(dependent, rhs));
            }
        }
    }
    let env = |s: Symbol| at(symbolic, t0, laws, values, s);
    residuals.into_iter().all(|r| {
        let value = arena.eval(r, &env);
        let mut size = 0.0;
        for s in arena.free_symbols(r) {
            if matches!(s, Symbol::Jet { .. } | Symbol::Time) {
                let partial = arena.diff(r, s);
                size += (arena.eval(partial, &env) * env(s)).abs();
            }
        }
        value == 0.0 || value.abs() <= TOLERANCE * size
    })
}

/// A value a constraint fixes that is not finite at the start: the
/// constraint cannot be solved for its dependent there (a pendulum in
/// Cartesian coordinates released level with its pivot, `y' = -x x'/y` at
/// y = 0), and the run would stop at once on `NaN`.
fn undetermined(
    arena: &Arena,
    model: &Model,
    symbol: Symbol,
    required: f64,
    t0: f64,
    user: Option<&(ExprId, &crate::check::model::Initial)>,
) -> Diagnostic {
    let name = arena.symbol_name(symbol);
    // A constraint fixes a coordinate's derivative; any other symbol gets
    // the message without the constraint's label.
    let coord = match symbol {
        Symbol::Jet { coord, .. } => coord as usize,
        _ => usize::MAX,
    };
    let constraint = model.constraints.iter().find(|c| c.coord == coord);
    let mut diagnostic = Diagnostic::error(
        codes::INCONSISTENT_INITIAL,
        format!("the constraint does not determine `{name}` at the start"),
    );
    diagnostic = match user {
        Some((_, user)) => diagnostic.with_primary(user.span, format!("`{name}` is given here")),
        None => diagnostic.with_primary(model.time.span, "the motion starts here"),
    };
    if let Some(c) = constraint {
        diagnostic = diagnostic.with_secondary(c.span, format!("this constraint fixes `{name}`"));
    }
    diagnostic = diagnostic.with_note(format!(
        "at t = {t0} solving the constraint for `{name}` gives {required} (params at their \
         defaults): its coefficient of `{name}` vanishes at this state, or it has no real \
         solution there"
    ));
    let others: Vec<&str> = constraint
        .and_then(|c| c.implicit.as_ref())
        .map(|implicit| {
            implicit
                .candidates
                .iter()
                .filter(|&&q| q != coord)
                .map(|&q| model.coords[q].name.as_str())
                .collect()
        })
        .unwrap_or_default();
    let Some(c) = constraint else {
        return diagnostic;
    };
    let holonomic = c.implicit.as_ref().is_some_and(|i| i.holonomic);
    let primes = |order: u32| "'".repeat(order as usize);
    let (this, level) = (&model.coords[c.coord].name, c.order);
    // A holonomic constraint's candidates are coordinates; the user gives
    // derivatives of the order the constraint fixes.
    let candidate = |q: &str| {
        if holonomic {
            q.to_string()
        } else {
            format!("{q}{}", primes(level))
        }
    };
    match others.first() {
        Some(other) => {
            let primes = primes(level);
            diagnostic.with_help(format!(
                "give `{this}{primes}` too (the constraint fixes `{other}{primes}` here, and \
                 lagc checks the value given for it); or write it `… for {} or {}` and give \
                 `{this}{primes}` instead of `{other}{primes}`",
                candidate(other),
                candidate(this),
            ))
        }
        None => diagnostic.with_help(format!(
            "start where the constraint can be solved for `{name}`"
        )),
    }
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= TOLERANCE * a.abs().max(b.abs()) || a == b
}

fn param_env(symbolic: &Symbolic, s: Symbol) -> f64 {
    match s {
        Symbol::Param(i) => symbolic
            .param_defaults
            .get(i as usize)
            .copied()
            .unwrap_or(f64::NAN),
        _ => f64::NAN,
    }
}

/// Symbol values at `t0`: params at their defaults, masses at their laws'
/// values, jets from `values` (NaN when unknown, so nothing passes unseen).
fn at(symbolic: &Symbolic, t0: f64, laws: &[f64], values: &HashMap<Symbol, f64>, s: Symbol) -> f64 {
    match s {
        Symbol::Time => t0,
        Symbol::Param(_) => param_env(symbolic, s),
        Symbol::Mass(i) => laws.get(i as usize).copied().unwrap_or(f64::NAN),
        Symbol::Jet { .. } => values.get(&s).copied().unwrap_or(f64::NAN),
        // The model's own initial values are checked with its inputs at
        // their defaults, held.
        Symbol::Input(i) => symbolic
            .input_defaults
            .get(i as usize)
            .copied()
            .unwrap_or(f64::NAN),
        Symbol::InputRate(_) => 0.0,
        Symbol::Aux(_) => f64::NAN,
    }
}

/// The numeric solution of one consistency stage (explicit, or Newton from
/// zero; one Newton step is exact for a linear stage).
fn solve_stage(
    arena: &Arena,
    stage: &Consistency,
    env: &dyn Fn(Symbol) -> f64,
) -> Option<Vec<f64>> {
    if let Some(explicit) = &stage.explicit {
        return Some(arena.eval_many(explicit, env));
    }
    let n = stage.unknowns.len();
    let mut z = vec![0.0; n];
    for _ in 0..NEWTON_STEPS {
        let lookup = |s: Symbol| match stage.unknowns.iter().position(|&u| u == s) {
            Some(i) => z[i],
            None => env(s),
        };
        let r = arena.eval_many(&stage.residual, &lookup);
        let entries: Vec<ExprId> = stage.jacobian.iter().flatten().copied().collect();
        let j = arena.eval_many(&entries, &lookup);
        let step = DMatrix::from_row_slice(n, n, &j)
            .lu()
            .solve(&DVector::from_vec(r))?;
        for (zi, di) in z.iter_mut().zip(step.iter()) {
            *zi -= di;
        }
        if step.norm() <= 1e-14 * (1.0 + z.iter().map(|v| v.abs()).sum::<f64>()) {
            return Some(z);
        }
    }
    Some(z)
}
