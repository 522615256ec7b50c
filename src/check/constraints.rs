//! Constraints `q^(k) = φ`: the left side names a dependent coordinate, all
//! share one order k, and no right side holds a dependent derivative of
//! order ≥ k (which would make the constraints implicit).

use super::expressions::Allowed;
use super::model::{Constraint, Implicit, Name};
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
            let ItemKind::Constraint {
                lhs,
                rhs,
                candidates,
            } = item
            else {
                continue;
            };
            let (coord, order, implicit) = if candidates.is_empty() {
                let Some((coord, order)) = self.constraint_lhs(lhs) else {
                    self.constraints_incomplete = true;
                    right_sides.push((rhs, span, None));
                    continue;
                };
                right_sides.push((rhs, span, Some(order)));
                (coord, order, None)
            } else {
                let Some((order, owned)) = self.candidates(candidates) else {
                    self.constraints_incomplete = true;
                    continue;
                };
                let implicit = Implicit {
                    lhs: lhs.clone(),
                    candidates: owned,
                };
                (implicit.candidates[0], order, Some(implicit))
            };
            let mine = owned_by(coord, implicit.as_ref());
            if let Some(first) = constraints.iter().find(|c| {
                owned_by(c.coord, c.implicit.as_ref())
                    .iter()
                    .any(|j| mine.contains(j))
            }) {
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
                self.constraints_incomplete = true;
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
                    self.constraints_incomplete = true;
                    continue;
                }
            }
            constraints.push(Constraint {
                coord,
                order,
                rhs: rhs.clone(),
                span,
                text: String::new(),
                implicit,
            });
        }
        let order = constraints.first().map(|c| c.order);
        for index in 0..constraints.len() {
            if let Some(implicit) = constraints[index].implicit.clone() {
                self.implicit_residual(&constraints[index], &implicit, &constraints);
            }
        }
        if let Some(k) = order {
            // A right side is checked against its own constraint's order, so
            // that a constraint of the wrong order gets one error, not two.
            for (rhs, span, own_order) in right_sides {
                self.constraint_rhs(rhs, span, own_order.unwrap_or(k), &constraints);
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
            let Some(dependent) = constraints
                .iter()
                .find(|c| owned_by(c.coord, c.implicit.as_ref()).contains(&used.coord))
            else {
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

impl Checker<'_> {
    /// The order and coordinates of `for y' or x'`: derivatives of one
    /// order, of distinct coordinates.
    fn candidates(&mut self, candidates: &[Expr]) -> Option<(u32, Vec<usize>)> {
        let mut order = None;
        let mut owned = Vec::new();
        for candidate in candidates {
            if let ExprKind::Var { name, primes: 0 } = &candidate.kind {
                let diagnostic = Diagnostic::error(
                    codes::BAD_CANDIDATE,
                    format!("`for` names `{}`, not a derivative", name.name),
                )
                .with_primary(candidate.span, "not a derivative")
                .with_help("name the derivative the constraint is solved for, e.g. `for y'`");
                self.report(diagnostic);
                return None;
            }
            let (coord, primes) = self.constraint_lhs(candidate)?;
            match order {
                None => order = Some(primes),
                Some(k) if k != primes => {
                    let diagnostic = Diagnostic::error(
                        codes::BAD_CANDIDATE,
                        "a constraint's candidates differ in order",
                    )
                    .with_primary(candidate.span, format!("of order {primes}"))
                    .with_secondary(candidates[0].span, format!("of order {k}"))
                    .with_help("a constraint of order k is solved for a derivative of order k");
                    self.report(diagnostic);
                    return None;
                }
                Some(_) => {}
            }
            if owned.contains(&coord) {
                let diagnostic =
                    Diagnostic::error(codes::BAD_CANDIDATE, "a candidate is named twice")
                        .with_primary(candidate.span, "named again here");
                self.report(diagnostic);
                return None;
            }
            owned.push(coord);
        }
        Some((order?, owned))
    }

    /// Checks `lhs = rhs` of an implicit constraint: its order is the
    /// candidates', every candidate occurs in it, and no other constraint's
    /// dependent derivative of order ≥ k does.
    fn implicit_residual(&mut self, own: &Constraint, implicit: &Implicit, all: &[Constraint]) {
        let k = own.order;
        let allowed = Allowed {
            time: true,
            masses: true,
            coord_order: Some(k),
            ..Allowed::constants("a constraint")
        };
        let errors = self.diagnostics.len();
        let mut uses = self.check_expr(&implicit.lhs, allowed);
        uses.extend(self.check_expr(&own.rhs, allowed));
        if self.diagnostics.len() > errors {
            return;
        }
        for &candidate in &implicit.candidates {
            if !uses.iter().any(|u| u.coord == candidate && u.order == k) {
                let name = &self.coords[candidate].name;
                let diagnostic = Diagnostic::error(
                    codes::BAD_CANDIDATE,
                    format!(
                        "the constraint does not hold `{name}{}`",
                        "'".repeat(k as usize)
                    ),
                )
                .with_primary(own.span, "solved for a derivative it does not contain")
                .with_help("name after `for` derivatives that occur in the constraint");
                self.report(diagnostic);
            }
        }
        for used in uses {
            if used.order < k || implicit.candidates.contains(&used.coord) {
                continue;
            }
            if let Some(other) = all
                .iter()
                .find(|c| owned_by(c.coord, c.implicit.as_ref()).contains(&used.coord))
            {
                let name = &self.coords[used.coord].name;
                let diagnostic = Diagnostic::error(
                    codes::DEPENDENT_DERIVATIVE_IN_RHS,
                    format!(
                        "a constraint holds another constraint's dependent derivative of order {}",
                        used.order
                    ),
                )
                .with_primary(used.span, format!("`{name}` is dependent"))
                .with_secondary(other.span, format!("`{name}` is made dependent here"))
                .with_help("substitute that coordinate's constraint into this one");
                self.report(diagnostic);
            }
        }
    }
}

/// The coordinates a constraint may make dependent.
fn owned_by(coord: usize, implicit: Option<&Implicit>) -> Vec<usize> {
    match implicit {
        Some(i) => i.candidates.clone(),
        None => vec![coord],
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
