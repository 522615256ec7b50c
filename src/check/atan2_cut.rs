//! A warning for `atan2` in a position constraint (W0002).
//!
//! `atan2(y, x)` jumps by 2π where `y` changes sign with `x < 0` (its cut).
//! A holonomic constraint through it is a different curve on each side:
//! a bead on a helix written `z = c*atan2(y, x)` is kept on the constraint
//! as written until it reaches the cut, where the constraint's residual
//! jumps and the run stops (exit 3, "the motion left the constraint"),
//! with advice about roots that does not apply. The warning says so
//! before the run, with the form that has no cut (the angle as a
//! coordinate). Velocity constraints and equations of motion differentiate
//! `atan2`, whose derivative has no cut: they are not warned about.

use crate::diagnostic::{codes, Diagnostic};
use crate::span::Span;
use crate::syntax::ast::{Builtin, Expr, ExprKind, ItemKind, Model};
use std::collections::HashMap;

/// Lets are followed at most this deep (a cycle is an error elsewhere).
const LET_DEPTH: usize = 64;

/// Every holonomic constraint (no derivative in it, through lets) that
/// holds `atan2`: one warning each, at the first `atan2`.
pub fn atan2_cut_warnings(ast: &Model) -> Vec<Diagnostic> {
    let lets: HashMap<&str, &Expr> = ast
        .items
        .iter()
        .filter_map(|item| match &item.kind {
            ItemKind::Let { name, value } => Some((name.name.as_str(), value)),
            _ => None,
        })
        .collect();
    let mut warnings = Vec::new();
    for item in &ast.items {
        let ItemKind::Constraint { lhs, rhs, .. } = &item.kind else {
            continue;
        };
        let mut found = Found::default();
        walk(lhs, &lets, 0, &mut found);
        walk(rhs, &lets, 0, &mut found);
        let (Some(atan2), false) = (found.atan2, found.derivative) else {
            continue;
        };
        warnings.push(
            Diagnostic::warning(
                codes::ATAN2_IN_POSITION_CONSTRAINT,
                "`atan2` in a position constraint jumps by 2π on its cut",
            )
            .with_primary(atan2, "`atan2(y, x)` jumps from π to −π where `y` changes sign with `x < 0`")
            .with_secondary(item.span, "this constraint is another curve past the cut")
            .with_note(
                "a motion that reaches the cut leaves the constraint as written there, and the run \
                 stops (exit 3)",
            )
            .with_help(
                "write the angle as a coordinate (a helix: `coord s;` with `x = R*cos(s)`, \
                 `y = R*sin(s)`, `z = c*s`), or keep the motion away from the cut",
            ),
        );
    }
    warnings
}

#[derive(Default)]
struct Found {
    atan2: Option<Span>,
    derivative: bool,
}

fn walk(expr: &Expr, lets: &HashMap<&str, &Expr>, depth: usize, found: &mut Found) {
    match &expr.kind {
        ExprKind::Number(_) => {}
        ExprKind::Var { name, primes } => {
            if *primes > 0 {
                found.derivative = true;
            }
            if let (Some(value), true) = (lets.get(name.name.as_str()), depth < LET_DEPTH) {
                let before = found.atan2;
                walk(value, lets, depth + 1, found);
                // Inside a let, point at the use: the constraint's own text.
                if before.is_none() && found.atan2.is_some() && depth == 0 {
                    found.atan2 = Some(expr.span);
                }
            }
        }
        ExprKind::Call {
            func,
            func_span,
            args,
        } => {
            if *func == Builtin::Atan2 && found.atan2.is_none() {
                found.atan2 = Some(if depth == 0 { expr.span } else { *func_span });
            }
            for arg in args {
                walk(arg, lets, depth, found);
            }
        }
        ExprKind::Neg(inner) | ExprKind::Not(inner) => walk(inner, lets, depth, found),
        ExprKind::Component { base, .. } => walk(base, lets, depth, found),
        ExprKind::Binary { lhs, rhs, .. }
        | ExprKind::Compare { lhs, rhs, .. }
        | ExprKind::Logic { lhs, rhs, .. } => {
            walk(lhs, lets, depth, found);
            walk(rhs, lets, depth, found);
        }
        ExprKind::Vector(items) => items.iter().for_each(|e| walk(e, lets, depth, found)),
        ExprKind::If {
            cond,
            then,
            otherwise,
        } => {
            walk(cond, lets, depth, found);
            walk(then, lets, depth, found);
            walk(otherwise, lets, depth, found);
        }
    }
}
