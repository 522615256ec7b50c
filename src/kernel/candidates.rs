//! Implicit constraints `h = lhs − rhs = 0` with their candidates (SPEC
//! §2.2): the pivots `∂h/∂candidate` the run compares to choose (and
//! switch) the reduced system.

use crate::check::model::{Constraint, Model};
use crate::ir::{lower, Arena, ExprId, Symbol};
use std::collections::HashMap;

/// One implicit constraint.
#[derive(Debug, Clone)]
pub struct KernelCandidates {
    /// The constraint, `h = 0`, for messages.
    pub text: String,
    /// The candidates as written (`y'`).
    pub names: Vec<String>,
    /// `∂h/∂candidate`, one per candidate.
    pub pivots: Vec<ExprId>,
}

/// `state_laws`: the mass laws of the state, by their expressions.
pub fn candidates(
    arena: &mut Arena,
    model: &Model,
    state_laws: &HashMap<Symbol, ExprId>,
) -> Vec<KernelCandidates> {
    let mut found = Vec::new();
    for c in &model.constraints {
        let Some(implicit) = &c.implicit else {
            continue;
        };
        let lhs = lower(arena, &implicit.lhs, model);
        let rhs = lower(arena, &c.rhs, model);
        let h = arena.sub(lhs, rhs);
        let mut names = Vec::new();
        let mut pivots = Vec::new();
        for &coord in &implicit.candidates {
            let symbol = Symbol::Jet {
                coord: coord as u32,
                order: c.order,
            };
            names.push(arena.symbol_name(symbol));
            let pivot = arena.diff(h, symbol);
            pivots.push(if state_laws.is_empty() {
                pivot
            } else {
                arena.subst(pivot, state_laws)
            });
        }
        found.push(KernelCandidates {
            text: constraint_text(arena, c, h),
            names,
            pivots,
        });
    }
    found
}

/// The constraint as written (the front end's text), else `h = 0`.
pub fn constraint_text(arena: &Arena, c: &Constraint, h: ExprId) -> String {
    if c.text.is_empty() {
        format!("{} = 0", arena.display(h))
    } else {
        c.text.clone()
    }
}
