//! The first derivative of a let (`p'`) that an expression holds, read
//! through the bodies of the lets it names. The linearity reading
//! ([`super::linearity`]) takes such a derivative as not linear in the
//! candidates, so a constraint written with one is solved through its
//! derivative even where it is linear; the missing-initial-value
//! diagnostic names it so that the user can see why.

use super::model::Name;
use super::Checker;
use crate::syntax::ast::{Expr, ExprKind};

impl Checker<'_> {
    /// The written form (`p'`) of the first let derivative in `expr`.
    pub(super) fn let_derivative(&self, expr: &Expr) -> Option<String> {
        self.let_derivative_at(expr, 0)
    }

    fn let_derivative_at(&self, expr: &Expr, depth: usize) -> Option<String> {
        // Lets refer only to earlier lets; the bound is a guard.
        if depth > 64 {
            return None;
        }
        let of = |e: &Expr| self.let_derivative_at(e, depth + 1);
        match &expr.kind {
            ExprKind::Number(_) => None,
            ExprKind::Var { name, primes } => match self.names.get(&name.name).map(|d| d.name) {
                Some(Name::Let(_)) if *primes > 0 => {
                    Some(format!("{}{}", name.name, "'".repeat(*primes as usize)))
                }
                Some(Name::Let(_)) => self.let_body(&name.name).and_then(of),
                _ => None,
            },
            ExprKind::Neg(e) | ExprKind::Not(e) | ExprKind::Component { base: e, .. } => of(e),
            ExprKind::Vector(items) => items.iter().find_map(of),
            ExprKind::Call { args, .. } => args.iter().find_map(of),
            ExprKind::Binary { lhs, rhs, .. }
            | ExprKind::Compare { lhs, rhs, .. }
            | ExprKind::Logic { lhs, rhs, .. } => of(lhs).or_else(|| of(rhs)),
            ExprKind::If {
                cond,
                then,
                otherwise,
            } => of(cond).or_else(|| of(then)).or_else(|| of(otherwise)),
        }
    }
}
