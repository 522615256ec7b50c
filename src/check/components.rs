//! Whether an expression really holds a coordinate's derivative once the
//! components of vectors are taken: `let vel = (x', y');` used as `vel.x`
//! holds `x'` only. The uses of a let (`types::Uses`) are its whole body's,
//! which is right for every check but one: a constraint's right side that
//! reads `vel.x` beside `constraint y' = …` was refused (E0009, "a
//! constraint cannot refer to the derivative it defines") although the
//! derivation never sees `y'` there (a new user's constant speed written
//! with a velocity vector, issue 29).
//!
//! The reading is conservative: it follows vector literals, lets (their
//! bodies, not their derivatives), sums, differences, negations and the
//! vector side of a product or quotient by a scalar; anywhere else a
//! component holds whatever its vector holds. An answer of "holds" is
//! never wrong, so the check it refines refuses no less than before where
//! the reading stops.

use super::model::Name;
use super::Checker;
use crate::syntax::ast::{BinOp, Expr, ExprKind, ItemKind};

/// Lets refer only to earlier lets; this bound is a guard (past it, the
/// answer is "holds").
const DEPTH: usize = 64;

impl Checker<'_> {
    /// Whether `expr` holds a derivative of `coord` of order at least
    /// `order`, components of vectors taken (see the module's note).
    pub(super) fn holds_jet_of(&self, expr: &Expr, coord: usize, order: u32) -> bool {
        self.jet_holds(expr, coord, order, 0)
    }

    fn jet_holds(&self, expr: &Expr, coord: usize, order: u32, depth: usize) -> bool {
        if depth > DEPTH {
            return true;
        }
        let of = |e: &Expr| self.jet_holds(e, coord, order, depth + 1);
        match &expr.kind {
            ExprKind::Number(_) => false,
            ExprKind::Var { name, primes } => match self.names.get(&name.name).map(|d| d.name) {
                Some(Name::Coord(c)) => c == coord && *primes >= order,
                Some(Name::Let(_)) => match self.let_body(&name.name) {
                    Some(body) if *primes == 0 => of(body),
                    // A let's derivative raises the orders of its body's
                    // derivatives (and brings in the next ones): whatever
                    // of the coordinate it uses counts.
                    Some(body) => self.jet_holds(body, coord, 0, depth + 1),
                    None => true,
                },
                _ => false,
            },
            ExprKind::Component { base, axis } => match crate::check::axis_index(&axis.name) {
                Some(index) => self.component_holds(base, index, coord, order, depth + 1),
                None => of(base),
            },
            ExprKind::Neg(e) | ExprKind::Not(e) => of(e),
            ExprKind::Vector(items) => items.iter().any(of),
            ExprKind::Binary { lhs, rhs, .. }
            | ExprKind::Compare { lhs, rhs, .. }
            | ExprKind::Logic { lhs, rhs, .. } => of(lhs) || of(rhs),
            ExprKind::Call { args, .. } => args.iter().any(of),
            ExprKind::If {
                cond,
                then,
                otherwise,
            } => of(cond) || of(then) || of(otherwise),
        }
    }

    /// Whether component `index` of the vector `base` holds the
    /// derivative; where the reading stops, whether `base` does.
    fn component_holds(
        &self,
        base: &Expr,
        index: usize,
        coord: usize,
        order: u32,
        depth: usize,
    ) -> bool {
        if depth > DEPTH {
            return true;
        }
        let whole = |e: &Expr| self.jet_holds(e, coord, order, depth + 1);
        let part = |e: &Expr| self.component_holds(e, index, coord, order, depth + 1);
        match &base.kind {
            ExprKind::Vector(items) => items.get(index).is_none_or(whole),
            ExprKind::Var { name, primes: 0 } => match self.names.get(&name.name).map(|d| d.name) {
                Some(Name::Let(_)) => self.let_body(&name.name).is_none_or(part),
                _ => whole(base),
            },
            ExprKind::Neg(e) => part(e),
            ExprKind::Binary { op, lhs, rhs } => match op {
                BinOp::Add | BinOp::Sub => part(lhs) || part(rhs),
                // A vector divided by a scalar.
                BinOp::Div => part(lhs) || whole(rhs),
                // A scalar times a vector: which side is the vector is not
                // known here, so each side is read both ways.
                BinOp::Mul => (part(lhs) || whole(rhs)) && (whole(lhs) || part(rhs)),
                BinOp::Pow => whole(base),
            },
            _ => whole(base),
        }
    }

    /// The body of the let named `name`.
    pub(super) fn let_body(&self, name: &str) -> Option<&Expr> {
        self.ast.items.iter().find_map(|item| match &item.kind {
            ItemKind::Let { name: n, value } if n.name == name => Some(value),
            _ => None,
        })
    }
}
