//! Whether an implicit constraint is affine in its candidates, read from
//! its text (SPEC §2.3): one that is not (`x'^2 + y'^2 = c^2 for y' or
//! x'`) is solved through its total derivative, which is linear in the
//! next derivatives, and kept on `f = 0` by the run
//! ([`super::constraints`] raises its order).
//!
//! The reading is conservative: "affine" only where every operation is
//! affine in the candidates (sums, products and quotients by expressions
//! free of them, vectors and their components, `dot` and `cross` with one
//! side free of them). Anything else is taken as non-linear, which is
//! never wrong: the derivative of a constraint that is affine after all
//! gives the same motion, and the run keeps the constraint as written.
//! The mechanics still refuses a candidate that a selection switches on
//! (E0038), which no derivative makes smooth.

use super::model::Name;
use super::Checker;
use crate::syntax::ast::{BinOp, Builtin, Expr, ExprKind, ItemKind};

/// How an expression depends on the candidates.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum Degree {
    Free,
    Affine,
    Other,
    /// The candidates enter through a selection (`abs`, `sign`, `min`,
    /// `max`, `atan2`, a condition): no derivative is smooth there, and
    /// the constraint is left to the mechanics, which refuses it (E0038).
    Switch,
}

impl Checker<'_> {
    /// Whether `expr` is affine in the derivatives `(coord, order)` of
    /// `jets` (lets read through their bodies).
    pub(super) fn is_nonlinear_in(&self, expr: &Expr, jets: &[(usize, u32)]) -> bool {
        self.degree(expr, jets, 0) == Degree::Other
    }

    /// Whether `expr` switches on the derivatives of `jets`.
    pub(super) fn switches_on(&self, expr: &Expr, jets: &[(usize, u32)]) -> bool {
        self.degree(expr, jets, 0) == Degree::Switch
    }

    /// The highest order of `coord`'s derivatives in `expr`, through lets
    /// and their derivatives (`None` where it does not appear; the
    /// conservative `u32::MAX` past the depth guard).
    fn highest_order(&self, expr: &Expr, coord: usize, depth: usize) -> Option<u32> {
        if depth > 64 {
            return Some(u32::MAX / 2);
        }
        let of = |e: &Expr| self.highest_order(e, coord, depth + 1);
        match &expr.kind {
            ExprKind::Number(_) => None,
            ExprKind::Var { name, primes } => match self.names.get(&name.name).map(|d| d.name) {
                Some(Name::Coord(c)) if c == coord => Some(*primes),
                Some(Name::Let(_)) => {
                    let body = self.ast.items.iter().find_map(|item| match &item.kind {
                        ItemKind::Let { name: n, value } if n.name == name.name => Some(value),
                        _ => None,
                    })?;
                    of(body).map(|m| m + primes)
                }
                _ => None,
            },
            ExprKind::Neg(e) | ExprKind::Not(e) | ExprKind::Component { base: e, .. } => of(e),
            ExprKind::Vector(items) | ExprKind::Call { args: items, .. } => {
                items.iter().filter_map(of).max()
            }
            ExprKind::Binary { lhs, rhs, .. }
            | ExprKind::Compare { lhs, rhs, .. }
            | ExprKind::Logic { lhs, rhs, .. } => of(lhs).max(of(rhs)),
            ExprKind::If {
                cond,
                then,
                otherwise,
            } => of(cond).max(of(then)).max(of(otherwise)),
        }
    }

    fn degree(&self, expr: &Expr, jets: &[(usize, u32)], depth: usize) -> Degree {
        // Lets refer only to earlier lets; the bound is a guard, and past
        // it the answer is the conservative one.
        if depth > 64 {
            return Degree::Other;
        }
        let of = |e: &Expr| self.degree(e, jets, depth + 1);
        match &expr.kind {
            ExprKind::Number(_) => Degree::Free,
            ExprKind::Var { name, primes } => match self.names.get(&name.name).map(|d| d.name) {
                Some(Name::Coord(coord)) => {
                    if jets.contains(&(coord, *primes)) {
                        Degree::Affine
                    } else {
                        Degree::Free
                    }
                }
                Some(Name::Let(i)) => {
                    let body = self.ast.items.iter().find_map(|item| match &item.kind {
                        ItemKind::Let { name: n, value } if n.name == name.name => Some(value),
                        _ => None,
                    });
                    let holds_coordinates =
                        self.lets.get(i).is_none_or(|l| !l.uses.coords.is_empty());
                    match body {
                        _ if !holds_coordinates => Degree::Free,
                        Some(body) if *primes == 0 => of(body),
                        // The derivative of a let, `D^p b`: affine in a
                        // candidate's derivative of order k where b holds
                        // that coordinate to order k − p at most (a total
                        // derivative is affine in its top order, `∂b/∂q^(k−p)
                        // q^(k)`), free of it below. A rolling coin's
                        // `G' + cross(w, P - G) = 0` was read as not linear
                        // and solved through its derivative, asking for
                        // initial values of its dependents.
                        Some(body) => jets
                            .iter()
                            .map(
                                |&(coord, k)| match self.highest_order(body, coord, depth + 1) {
                                    None => Degree::Free,
                                    Some(m) if m + primes < k => Degree::Free,
                                    Some(m) if m + primes == k => Degree::Affine,
                                    Some(_) => Degree::Other,
                                },
                            )
                            .max()
                            .unwrap_or(Degree::Free),
                        None => Degree::Other,
                    }
                }
                _ => Degree::Free,
            },
            ExprKind::Neg(e) | ExprKind::Component { base: e, .. } => of(e),
            ExprKind::Vector(items) => items.iter().map(of).max().unwrap_or(Degree::Free),
            ExprKind::Binary { op, lhs, rhs } => {
                let (a, b) = (of(lhs), of(rhs));
                match op {
                    BinOp::Add | BinOp::Sub => a.max(b),
                    BinOp::Mul => product(a, b),
                    BinOp::Div | BinOp::Pow if b != Degree::Free => a.max(b).max(Degree::Other),
                    BinOp::Div => a,
                    BinOp::Pow if a == Degree::Free => Degree::Free,
                    BinOp::Pow => a.max(Degree::Other),
                }
            }
            ExprKind::Call { func, args, .. } => {
                let degrees: Vec<Degree> = args.iter().map(of).collect();
                let switch = matches!(
                    func,
                    Builtin::Abs | Builtin::Sign | Builtin::Min | Builtin::Max | Builtin::Atan2
                );
                match (func, &degrees[..]) {
                    (Builtin::Dot | Builtin::Cross, &[a, b]) => product(a, b),
                    _ if degrees.iter().all(|&d| d == Degree::Free) => Degree::Free,
                    _ if switch => Degree::Switch,
                    _ => degrees
                        .iter()
                        .copied()
                        .max()
                        .unwrap_or(Degree::Free)
                        .max(Degree::Other),
                }
            }
            ExprKind::Compare { lhs, rhs, .. } | ExprKind::Logic { lhs, rhs, .. } => {
                if of(lhs) == Degree::Free && of(rhs) == Degree::Free {
                    Degree::Free
                } else {
                    Degree::Switch
                }
            }
            ExprKind::Not(e) => {
                if of(e) == Degree::Free {
                    Degree::Free
                } else {
                    Degree::Switch
                }
            }
            ExprKind::If {
                cond,
                then,
                otherwise,
            } => match of(cond) {
                Degree::Free => of(then).max(of(otherwise)),
                _ => Degree::Switch,
            },
        }
    }
}

fn product(a: Degree, b: Degree) -> Degree {
    match (a, b) {
        (Degree::Free, d) | (d, Degree::Free) => d,
        _ => a.max(b).max(Degree::Other),
    }
}

impl Checker<'_> {
    /// The model's order once its non-linear implicit constraints are
    /// known (`k`, or `k + 1` when one is not affine in its candidates:
    /// then every implicit and holonomic constraint is differentiated once
    /// more, [`super::model::Implicit::raised`]). A non-linear constraint
    /// beside an explicit one, or solved together with a holonomic one, is
    /// refused (E0038): the run keeps `f = 0` by Newton on its candidate,
    /// or over its group's candidates.
    pub(super) fn raise_nonlinear(
        &mut self,
        constraints: &mut [super::model::Constraint],
        groups: &[super::model::Group],
        k: u32,
    ) -> u32 {
        let nonlinear: Vec<usize> = (0..constraints.len())
            .filter(|&i| {
                let c = &constraints[i];
                let Some(implicit) = c.implicit.as_ref().filter(|im| !im.holonomic) else {
                    return false;
                };
                let jets: Vec<(usize, u32)> =
                    implicit.candidates.iter().map(|&j| (j, c.order)).collect();
                // A switch on a candidate anywhere: left to the mechanics.
                let switches =
                    self.switches_on(&implicit.lhs, &jets) || self.switches_on(&c.rhs, &jets);
                !switches
                    && (self.is_nonlinear_in(&implicit.lhs, &jets)
                        || self.is_nonlinear_in(&c.rhs, &jets))
            })
            .collect();
        let Some(&first) = nonlinear.first() else {
            return k;
        };
        let mut refused = false;
        if let Some(explicit) = constraints.iter().find(|c| c.implicit.is_none()) {
            let name = format!(
                "{}{}",
                self.coords[explicit.coord].name,
                "'".repeat(explicit.order as usize)
            );
            let diagnostic = crate::diagnostic::Diagnostic::error(
                crate::diagnostic::codes::BAD_CANDIDATE,
                "an explicit constraint beside a constraint that is not linear in its candidate",
            )
            .with_primary(explicit.span, "this constraint is explicit")
            .with_secondary(constraints[first].span, "not linear in its candidate")
            .with_note(
                "a non-linear constraint is solved through its derivative, one order higher, \
                 and every constraint of a model shares one order",
            )
            .with_help(format!(
                "write the explicit constraint implicitly: `constraint {name} = … for {name};`"
            ));
            self.report(diagnostic);
            refused = true;
        }
        // A group is kept by Newton over its candidates (all its members'
        // written forms, `src/mechanics/raised.rs`); a holonomic member is
        // kept at position level by the closure, which that Newton does not
        // reach: refused.
        for &i in &nonlinear {
            let holonomic = groups
                .iter()
                .find(|g| g.constraints.contains(&i))
                .and_then(|g| {
                    g.constraints.iter().copied().find(|&j| {
                        constraints[j]
                            .implicit
                            .as_ref()
                            .is_some_and(|im| im.holonomic)
                    })
                });
            if let Some(j) = holonomic {
                let diagnostic = crate::diagnostic::Diagnostic::error(
                    crate::diagnostic::codes::BAD_CANDIDATE,
                    "a constraint that is not linear in its candidate is solved together with a \
                     holonomic one",
                )
                .with_primary(constraints[i].span, "not linear in its candidate")
                .with_secondary(constraints[j].span, "holonomic, sharing candidates with it")
                .with_note(
                    "the run keeps a group of velocity constraints by Newton over its \
                     candidates, and a holonomic constraint at position level: not both in one \
                     group",
                )
                .with_help(
                    "name candidates that uncouple the holonomic constraint (`for x` of its own \
                     coordinate), or differentiate the non-linear constraint by hand",
                );
                self.report(diagnostic);
                refused = true;
                break;
            }
        }
        if refused {
            self.constraints_incomplete = true;
            return k;
        }
        for c in constraints.iter_mut() {
            c.order = k + 1;
            if let Some(implicit) = c.implicit.as_mut().filter(|im| !im.holonomic) {
                implicit.raised = true;
            }
        }
        k + 1
    }
}
