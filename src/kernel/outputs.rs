//! `output` columns and the `stop when` condition (SPEC §2.2) as
//! expressions of `t`, params and the state.

use super::motion::Motion;
use crate::check::model::Model;
use crate::diagnostic::{codes, Diagnostic};
use crate::ir::{try_lower_components, try_lower_condition, Arena, Cond, ExprId, Symbol};
use crate::mechanics::ReducedSystem;
use crate::span::Span;
use std::collections::HashMap;

type Lowered = (Vec<(String, ExprId)>, Option<Cond>);

/// The outputs, flattened (`E`, or `p.x`, `p.y`), and the stop condition.
/// A highest derivative `q^(u)` is replaced by the reduced system's value
/// where that is an expression (explicit systems), and a mass law of the
/// state by its expression (`state_laws`).
pub fn outputs(
    arena: &mut Arena,
    model: &Model,
    motion: &Motion,
    reduced: &ReducedSystem,
    state_laws: &HashMap<Symbol, ExprId>,
) -> Result<Lowered, Vec<Diagnostic>> {
    let mut highest = highest_values(motion, reduced);
    highest.extend(state_laws.iter().map(|(&s, &law)| (s, law)));
    let mut errors = Vec::new();
    let mut columns = Vec::new();
    for output in &model.outputs {
        let Ok(components) = try_lower_components(arena, &output.value, model) else {
            errors.push(internal(output.span));
            continue;
        };
        for (i, &c) in components.iter().enumerate() {
            let c = arena.subst(c, &highest);
            if let Some(d) = beyond_state(arena, c, reduced, output.span, "an output") {
                errors.push(d);
            }
            let name = if components.len() == 1 {
                output.name.clone()
            } else {
                format!("{}.{}", output.name, ["x", "y", "z"][i.min(2)])
            };
            columns.push((name, c));
        }
    }
    let stop = match &model.stop {
        None => None,
        Some(cond) => match try_lower_condition(arena, cond, model) {
            Ok(c) => {
                let mut switches = Vec::new();
                c.switches(&mut switches);
                for g in switches {
                    let g = arena.subst(g, &highest);
                    if let Some(d) = beyond_state(arena, g, reduced, cond.span, "a stop condition")
                    {
                        errors.push(d);
                    }
                }
                Some(substitute(arena, &c, &highest))
            }
            Err(_) => {
                errors.push(internal(cond.span));
                None
            }
        },
    };
    if errors.is_empty() {
        Ok((columns, stop))
    } else {
        Err(errors)
    }
}

/// The highest derivatives `q^(u)` by the reduced system's value, where
/// that is an expression (explicit systems).
pub(super) fn highest_values(motion: &Motion, reduced: &ReducedSystem) -> HashMap<Symbol, ExprId> {
    match motion {
        Motion::Explicit(m) => m
            .rhs
            .iter()
            .enumerate()
            .map(|(j, &e)| {
                (
                    Symbol::Jet {
                        coord: j as u32,
                        order: reduced.order,
                    },
                    e,
                )
            })
            .collect(),
        Motion::Implicit(_) => HashMap::new(),
    }
}

pub(super) fn substitute(arena: &mut Arena, cond: &Cond, map: &HashMap<Symbol, ExprId>) -> Cond {
    match cond {
        Cond::Negative(g) => Cond::Negative(arena.subst(*g, map)),
        Cond::Not(c) => Cond::Not(Box::new(substitute(arena, c, map))),
        Cond::And(a, b) => Cond::And(
            Box::new(substitute(arena, a, map)),
            Box::new(substitute(arena, b, map)),
        ),
        Cond::Or(a, b) => Cond::Or(
            Box::new(substitute(arena, a, map)),
            Box::new(substitute(arena, b, map)),
        ),
    }
}

/// A derivative the run does not have: above the state's order (or the
/// highest one of an implicit system).
pub(super) fn beyond_state(
    arena: &Arena,
    e: ExprId,
    reduced: &ReducedSystem,
    span: Span,
    what: &str,
) -> Option<Diagnostic> {
    let found = arena
        .free_symbols(e)
        .into_iter()
        .find(|s| matches!(s, Symbol::Jet { order, .. } if *order >= reduced.order))?;
    let name = arena.symbol_name(found);
    Some(
        Diagnostic::error(
            codes::DERIVATIVE_ORDER_NOT_ALLOWED,
            format!("{what} holds `{name}`, which the run does not compute"),
        )
        .with_primary(span, "this statement")
        .with_note(format!(
            "the state holds derivatives below order {}; the highest ones are available only when the reduced system gives them explicitly",
            reduced.order
        )),
    )
}

pub(super) fn internal(span: Span) -> Diagnostic {
    Diagnostic::error(
        codes::NAME_NOT_ALLOWED,
        "internal error: this statement could not be lowered",
    )
    .with_primary(span, "here")
}
