//! Initial values of the state (6) (SPEC §1.4): given by the user, fixed by
//! the constraints (dependent derivatives of order ≥ k), or solved from (4)
//! and its derivatives (independent `q_i^(2..k−1)`, k ≥ 3). A given value
//! that the constraints or the equations fix is checked at `t0` with the
//! params at their defaults (E0013).

use super::reduced::{Consistency, InitialValue};
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
pub fn initial_values(
    arena: &mut Arena,
    model: &Model,
    symbolic: &Symbolic,
    elimination: &mut Elimination,
    state: &[Symbol],
    consistency: &[Consistency],
) -> Result<Vec<InitialValue>, Vec<Diagnostic>> {
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
        if !dependent && order >= 2 {
            initial.push(InitialValue::Solved);
            continue;
        }
        match given.get(&symbol) {
            Some(&(e, _)) => initial.push(InitialValue::Given(e)),
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
    // Pass 2: the values the constraints fix (they depend on given values only).
    let env_values = values.clone();
    for (&symbol, value) in state.iter().zip(&initial) {
        if let InitialValue::Constraint(fixed) = value {
            let required = arena.eval(*fixed, &|s| at(symbolic, t0, &laws_at_t0, &env_values, s));
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
    // Pass 3: the consistency stages (k ≥ 3), in order.
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
    if errors.is_empty() {
        Ok(initial)
    } else {
        Err(errors)
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
