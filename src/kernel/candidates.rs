//! Implicit constraints `h = lhs − rhs = 0` with their candidates (SPEC
//! §2.2, §2.3): for each group of constraints solved together, the pivot
//! of each choice of dependents — `∂h/∂candidate` for a lone constraint,
//! the determinant of the block `∂h_ν/∂z_c` of the chosen derivatives for
//! a coupled group — which the run compares to choose (and switch) the
//! reduced system. A holonomic constraint `f = 0` shows as `f = 0`, its
//! candidates as coordinates (its pivots `∂f/∂q` equal those of `D^k f`
//! in `q^(k)`).

use crate::check::model::{Constraint, Model};
use crate::ir::{lower, Arena, ExprId, Symbol};
use crate::mechanics::coupled;
use std::collections::HashMap;

/// One group of implicit constraints (most often one constraint).
#[derive(Debug, Clone)]
pub struct KernelCandidates {
    /// The constraints, `h = 0` (`; `-separated), for messages.
    pub text: String,
    /// The choices as written (`y'`; `t3, t2` for a coupled group).
    pub names: Vec<String>,
    /// The pivot of each choice.
    pub pivots: Vec<ExprId>,
}

/// `state_laws`: the mass laws of the state, by their expressions.
pub fn candidates(
    arena: &mut Arena,
    model: &Model,
    state_laws: &HashMap<Symbol, ExprId>,
) -> Vec<KernelCandidates> {
    let laws: HashMap<Symbol, ExprId> = model
        .masses
        .iter()
        .enumerate()
        .map(|(i, m)| (Symbol::Mass(i as u32), lower(arena, &m.law, model)))
        .collect();
    let mut found = Vec::new();
    for group in &model.groups {
        let mut texts = Vec::new();
        // The rows: `h` of an implicit constraint in its derivatives of
        // order k, `f` of a holonomic one in the coordinates.
        let mut rows = Vec::new();
        for &i in &group.constraints {
            let c = &model.constraints[i];
            let Some(implicit) = &c.implicit else {
                continue;
            };
            let lhs = lower(arena, &implicit.lhs, model);
            let rhs = lower(arena, &c.rhs, model);
            let h = arena.sub(lhs, rhs);
            texts.push(constraint_text(arena, c, h));
            let h = if implicit.holonomic {
                arena.subst(h, &laws)
            } else {
                h
            };
            // A raised constraint's pivots are those of the constraint as
            // written, in its candidates of order k − 1 (the derivative's
            // in the order-k ones are the same expressions).
            let order = if implicit.holonomic {
                0
            } else if implicit.raised {
                c.order - 1
            } else {
                c.order
            };
            let h = if implicit.raised {
                arena.subst(h, &laws)
            } else {
                h
            };
            rows.push((h, order));
        }
        let mut names = Vec::new();
        let mut pivots = Vec::new();
        for choice in &group.choices {
            let symbols: Vec<Vec<Symbol>> = rows
                .iter()
                .map(|&(_, order)| {
                    choice
                        .iter()
                        .map(|&coord| Symbol::Jet {
                            coord: coord as u32,
                            order,
                        })
                        .collect()
                })
                .collect();
            let block: Vec<Vec<ExprId>> = rows
                .iter()
                .zip(&symbols)
                .map(|(&(h, _), row)| row.iter().map(|&z| arena.diff(h, z)).collect())
                .collect();
            let pivot = if block.len() == 1 {
                block[0][0]
            } else {
                coupled::determinant(arena, &block)
            };
            pivots.push(if state_laws.is_empty() {
                pivot
            } else {
                arena.subst(pivot, state_laws)
            });
            // Named by the first row's order: coordinates for a holonomic
            // group, derivatives for the others.
            let chosen: Vec<String> = symbols[0].iter().map(|&z| arena.symbol_name(z)).collect();
            names.push(chosen.join(", "));
        }
        found.push(KernelCandidates {
            text: texts.join("; "),
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
