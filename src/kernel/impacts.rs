//! Impacts (SPEC §2.3): each `when` as a condition on the regime's
//! branches (its comparisons become switching functions, located as events
//! like `stop when`'s) and the new values of the components it resets, as
//! expressions of `t`, params, masses and the state before the impact.
//! After the resets the derivatives the constraints fix are recomputed
//! from the new state (the same expressions that fix them at `t0`), in a
//! model of one mode; a model of several modes recomputes them at run
//! time in the mode the run goes on in (`run::impacts` of the runtime),
//! since which derivatives are fixed changes with the mode.

use super::motion::Motion;
use super::switches::{BranchCond, Switches};
use crate::check::model::Model;
use crate::diagnostic::Diagnostic;
use crate::ir::{try_lower, try_lower_condition, Arena, Cond, ExprId, Symbol};
use crate::mechanics::{InitialValue, ReducedSystem};
use std::collections::HashMap;

/// One `when` statement.
#[derive(Debug, Clone)]
pub struct KernelImpact {
    /// The condition as written (`y < 0`), for messages.
    pub text: String,
    /// The condition on the switches' branches: the impact happens at the
    /// event where it becomes true.
    pub condition: BranchCond,
    /// `(state index, new value)`: read at the state before the impact
    /// (not latched: selections test their conditions there directly).
    pub resets: Vec<(usize, ExprId)>,
}

/// A `when` lowered but not yet on branches: its condition as a [`Cond`].
pub struct Lowered {
    pub text: String,
    pub cond: Cond,
    pub resets: Vec<(usize, ExprId)>,
}

/// `(state index, value)` of the components the constraints fix.
type Fixed = Vec<(usize, ExprId)>;

/// The impacts of `model` with their conditions lowered (the kernel puts
/// them on the switches' branches once the motion is latched), and the
/// state components the constraints fix with their expressions (empty
/// without impacts: nothing is recomputed then).
pub fn impacts(
    arena: &mut Arena,
    model: &Model,
    motion: &Motion,
    reduced: &ReducedSystem,
) -> Result<(Vec<Lowered>, Fixed), Vec<Diagnostic>> {
    if model.impacts.is_empty() {
        return Ok((Vec::new(), Vec::new()));
    }
    let highest = super::outputs::highest_values(motion, reduced);
    let position: HashMap<Symbol, usize> = reduced
        .state
        .iter()
        .enumerate()
        .map(|(i, &s)| (s, i))
        .collect();
    let mut errors = Vec::new();
    let mut lowered = Vec::new();
    for impact in &model.impacts {
        let cond = match try_lower_condition(arena, &impact.cond, model) {
            Ok(c) => {
                let mut switches = Vec::new();
                c.switches(&mut switches);
                for g in switches {
                    let g = arena.subst(g, &highest);
                    if let Some(d) = super::outputs::beyond_state(
                        arena,
                        g,
                        reduced,
                        impact.cond.span,
                        "an impact's condition",
                    ) {
                        errors.push(d);
                    }
                }
                super::outputs::substitute(arena, &c, &highest)
            }
            Err(_) => {
                errors.push(super::outputs::internal(impact.cond.span));
                continue;
            }
        };
        let mut resets = Vec::new();
        for reset in &impact.resets {
            let symbol = Symbol::Jet {
                coord: reset.coord as u32,
                order: reset.order,
            };
            let Some(&k) = position.get(&symbol) else {
                errors.push(super::outputs::internal(reset.span));
                continue;
            };
            let Ok(value) = try_lower(arena, &reset.value, model) else {
                errors.push(super::outputs::internal(reset.span));
                continue;
            };
            let value = arena.subst(value, &highest);
            if let Some(d) =
                super::outputs::beyond_state(arena, value, reduced, reset.span, "a reset")
            {
                errors.push(d);
            }
            resets.push((k, value));
        }
        lowered.push(Lowered {
            text: impact.text.clone(),
            cond,
            resets,
        });
    }
    let fixed = reduced
        .initial
        .iter()
        .enumerate()
        .filter_map(|(k, v)| match v {
            InitialValue::Constraint(e) => Some((k, *e)),
            _ => None,
        })
        .collect();
    if errors.is_empty() {
        Ok((lowered, fixed))
    } else {
        Err(errors)
    }
}

/// The impacts on the switches' branches.
pub fn on_branches(
    arena: &mut Arena,
    switches: &mut Switches,
    lowered: Vec<Lowered>,
) -> Vec<KernelImpact> {
    lowered
        .into_iter()
        .map(|l| KernelImpact {
            condition: switches.condition(arena, &l.cond),
            text: l.text,
            resets: l.resets,
        })
        .collect()
}
