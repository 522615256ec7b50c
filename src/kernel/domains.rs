//! Where a constraint as written stops being defined (issue 28): the
//! argument of a square root (of any fractional power), of a logarithm,
//! `1 − u²` for an arcsine or arccosine of `u`, and the poles of its
//! divisions and tangents. A branch that ends must stop the run naming the
//! constraint, never pass silently: `y' = sqrt(c^2 - x'^2)` in gravity
//! reaches `c^2 - x'^2 = 0` at its apex, where `∂φ/∂x'` is infinite, and
//! direct integration ran on past it with exit 0 (y' = −2 where the
//! constraint demands 0). The runtime watches every closed or open end
//! after each step and names a pole when a failure happens at one.

use super::candidates::constraint_text;
use crate::check::model::Model;
use crate::ir::{lower, Arena, ExprId, Func, Node, Symbol};
use std::collections::HashSet;

/// What kind of end an argument marks: the runtime's own type, as the
/// generated crate names it (one definition for both sides).
pub use lagc_runtime::model::DomainKind;

#[derive(Debug, Clone)]
pub struct KernelDomain {
    /// The constraint as written.
    pub constraint: String,
    pub kind: DomainKind,
    /// The argument: defined where it is positive.
    pub argument: ExprId,
    /// Its size for a rounding test: the sum of its terms' magnitudes (1
    /// for an argument that is not a sum).
    pub scale: ExprId,
    /// The argument as text.
    pub text: String,
}

/// Every end of every constraint's expressions, in source order (each
/// argument once per constraint).
pub fn domains(arena: &mut Arena, model: &Model) -> Vec<KernelDomain> {
    let mut found = Vec::new();
    for c in &model.constraints {
        let rhs = lower(arena, &c.rhs, model);
        let (roots, h) = match &c.implicit {
            Some(implicit) => {
                let lhs = lower(arena, &implicit.lhs, model);
                (vec![lhs, rhs], arena.sub(lhs, rhs))
            }
            None => (vec![rhs], rhs),
        };
        let text = if c.text.is_empty() && c.implicit.is_none() {
            let dependent = Symbol::Jet {
                coord: c.coord as u32,
                order: c.order,
            };
            format!("{} = {}", arena.symbol_name(dependent), arena.display(rhs))
        } else {
            constraint_text(arena, c, h)
        };
        let mut seen = HashSet::new();
        for e in arena.reachable(&roots) {
            let Some((kind, argument)) = end_of(arena, e) else {
                continue;
            };
            if arena.as_const(argument).is_some() || !seen.insert((kind, argument)) {
                continue;
            }
            let scale = scale_of(arena, argument);
            found.push(KernelDomain {
                constraint: text.clone(),
                kind,
                argument,
                scale,
                text: arena.display(argument).to_string(),
            });
        }
    }
    found
}

/// The end node `e` marks, with its argument.
fn end_of(arena: &mut Arena, e: ExprId) -> Option<(DomainKind, ExprId)> {
    match arena.node(e).clone() {
        Node::Pow(base, exponent) => {
            let p = arena.as_const(exponent)?;
            if p.fract() == 0.0 {
                return (p < 0.0).then_some((DomainKind::Pole, base));
            }
            Some((
                if p < 1.0 {
                    DomainKind::Root
                } else {
                    DomainKind::Power
                },
                base,
            ))
        }
        Node::Func(Func::Ln, u) => Some((DomainKind::Logarithm, u)),
        Node::Func(f @ (Func::Asin | Func::Acos), u) => {
            let one = arena.one();
            let square = arena.powi(u, 2);
            let margin = arena.sub(one, square);
            let kind = if f == Func::Asin {
                DomainKind::Arcsine
            } else {
                DomainKind::Arccosine
            };
            Some((kind, margin))
        }
        Node::Func(Func::Tan, u) => Some((DomainKind::Pole, arena.func(Func::Cos, u))),
        _ => None,
    }
}

/// `Σ |term|` of a sum, else 1.
fn scale_of(arena: &mut Arena, argument: ExprId) -> ExprId {
    let Node::Add(terms) = arena.node(argument).clone() else {
        return arena.one();
    };
    let magnitudes: Vec<ExprId> = terms
        .iter()
        .map(|&term| {
            let minus = arena.neg(term);
            arena.select(term, minus, term)
        })
        .collect();
    arena.add(&magnitudes)
}
