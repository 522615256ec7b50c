//! Constraints `q^(k) = φ`: the left side names a dependent coordinate, all
//! share one order k, and no right side holds a dependent derivative of
//! order ≥ k (which would make the constraints implicit).

use super::expressions::Allowed;
use super::model::{Constraint, Name};
use super::{Checker, MAX_DERIVATIVE_ORDER};
use crate::diagnostic::{codes, Diagnostic};
use crate::span::Span;
use crate::syntax::ast::{Expr, ExprKind, ItemKind};

impl Checker<'_> {
    /// Returns the common order k and the constraints, in source order.
    pub(super) fn constraints(&mut self) -> (Option<u32>, Vec<Constraint>) {
        let mut constraints: Vec<Constraint> = Vec::new();
        let mut right_sides = Vec::new();
        for (item, span) in self.items() {
            let ItemKind::Constraint { lhs, rhs } = item else {
                continue;
            };
            right_sides.push((rhs, span));
            let Some((coord, order)) = self.constraint_lhs(lhs) else {
                continue;
            };
            if let Some(first) = constraints.iter().find(|c| c.coord == coord) {
                let name = &self.coords[coord].name;
                let diagnostic = Diagnostic::error(
                    codes::DOUBLE_CONSTRAINT,
                    format!("coordinate `{name}` is constrained twice"),
                )
                .with_primary(lhs.span, "second constraint on it here")
                .with_secondary(first.span, "first constraint here")
                .with_help(
                    "each constraint makes one coordinate dependent; constrain another coordinate",
                );
                self.report(diagnostic);
                continue;
            }
            if let Some(first) = constraints.first() {
                if first.order != order {
                    let diagnostic = Diagnostic::error(
                        codes::MIXED_CONSTRAINT_ORDERS,
                        "constraints of different orders",
                    )
                    .with_primary(lhs.span, format!("this constraint has order {order}"))
                    .with_secondary(first.span, format!("the first constraint has order {}", first.order))
                    .with_help("all constraints of a model share one order k; differentiate the lower-order ones");
                    self.report(diagnostic);
                    continue;
                }
            }
            constraints.push(Constraint {
                coord,
                order,
                rhs: rhs.clone(),
                span,
            });
        }
        let order = constraints.first().map(|c| c.order);
        if let Some(k) = order {
            for (rhs, span) in right_sides {
                self.constraint_rhs(rhs, span, k, &constraints);
            }
        }
        if !self.coords.is_empty() && constraints.len() >= self.coords.len() {
            if let Some(last) = constraints.last() {
                let diagnostic = Diagnostic::error(
                    codes::NO_INDEPENDENT_COORDINATE,
                    "every coordinate is constrained",
                )
                .with_primary(
                    last.span,
                    "this constraint leaves no independent coordinate",
                )
                .with_help("at least one coordinate must stay independent");
                self.report(diagnostic);
            }
        }
        (order, constraints)
    }

    /// The coordinate and order of `q'`, `q''`, … on a constraint's left side.
    fn constraint_lhs(&mut self, lhs: &Expr) -> Option<(usize, u32)> {
        let ExprKind::Var { name, primes } = &lhs.kind else {
            self.report(bad_lhs(lhs.span, "not a derivative of a coordinate"));
            return None;
        };
        let Some(declared) = self.names.get(&name.name).copied() else {
            let diagnostic = self.unknown_name(&name.name, name.span);
            self.report(diagnostic);
            return None;
        };
        let Name::Coord(coord) = declared.name else {
            let what = super::declarations::kind_name(declared.name);
            let diagnostic = bad_lhs(lhs.span, &format!("`{}` is {what}", name.name))
                .with_secondary(declared.span, "declared here");
            self.report(diagnostic);
            return None;
        };
        if *primes == 0 {
            let diagnostic = bad_lhs(lhs.span, "a coordinate, not a derivative")
                .with_note("lagc handles non-holonomic constraints; a holonomic constraint `q2 = f(q1)` is best eliminated by choosing fewer coordinates")
                .with_help(format!("differentiate it: `constraint {}' = …;`", name.name));
            self.report(diagnostic);
            return None;
        }
        if *primes > MAX_DERIVATIVE_ORDER {
            let diagnostic = Diagnostic::error(
                codes::DERIVATIVE_ORDER_NOT_ALLOWED,
                format!("constraint of order {primes} is too high"),
            )
            .with_primary(
                lhs.span,
                format!("lagc accepts orders up to {MAX_DERIVATIVE_ORDER}"),
            );
            self.report(diagnostic);
            return None;
        }
        Some((coord, *primes))
    }

    fn constraint_rhs(&mut self, rhs: &Expr, span: Span, k: u32, constraints: &[Constraint]) {
        let allowed = Allowed {
            time: true,
            masses: true,
            coord_order: Some(k),
            ..Allowed::constants("a constraint")
        };
        for used in self.check_expr(rhs, allowed) {
            let Some(dependent) = constraints.iter().find(|c| c.coord == used.coord) else {
                continue;
            };
            if used.order >= k {
                let name = &self.coords[used.coord].name;
                let diagnostic = Diagnostic::error(
                    codes::DEPENDENT_DERIVATIVE_IN_RHS,
                    format!("a constraint's right side holds a dependent derivative of order {}", used.order),
                )
                .with_primary(used.span, format!("`{name}` is dependent"))
                .with_secondary(dependent.span, format!("`{name}` is made dependent here"))
                .with_note(format!(
                    "right sides may hold dependent coordinates' derivatives of order below k = {k} only"
                ));
                // The constraint's own statement span helps place the error.
                let diagnostic = if dependent.span == span {
                    diagnostic.with_help("a constraint cannot refer to the derivative it defines")
                } else {
                    diagnostic.with_help("substitute that coordinate's constraint into this one")
                };
                self.report(diagnostic);
            }
        }
    }
}

fn bad_lhs(span: Span, label: &str) -> Diagnostic {
    Diagnostic::error(
        codes::CONSTRAINT_LHS,
        "a constraint's left side must be a derivative of a coordinate",
    )
    .with_primary(span, label.to_string())
    .with_help("write it as `constraint q2' = …;`: the coordinate it makes dependent, with primes")
}
