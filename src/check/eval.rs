//! Evaluating constant expressions (numbers, params, functions) to `f64`:
//! param defaults, initial values, time bounds.

use super::model::Name;
use super::Checker;
use crate::diagnostic::{codes, Diagnostic};
use crate::syntax::ast::{BinOp, Expr, ExprKind};

impl Checker<'_> {
    /// The value of a constant expression with every param at its default;
    /// `None` if it names anything else or a param without a default (both
    /// already reported). Recursion depth is bounded by the parser's
    /// expression depth limit.
    pub(super) fn evaluate(&self, expr: &Expr) -> Option<f64> {
        Some(match &expr.kind {
            ExprKind::Number(value) => *value,
            ExprKind::Var { name, primes: 0 } => match self.names.get(&name.name)?.name {
                Name::Param(index) => (*self.param_defaults.get(index)?)?,
                _ => return None,
            },
            ExprKind::Var { .. } => return None,
            ExprKind::Neg(inner) => -self.evaluate(inner)?,
            ExprKind::Binary { op, lhs, rhs } => {
                let (lhs, rhs) = (self.evaluate(lhs)?, self.evaluate(rhs)?);
                match op {
                    BinOp::Add => lhs + rhs,
                    BinOp::Sub => lhs - rhs,
                    BinOp::Mul => lhs * rhs,
                    BinOp::Div => lhs / rhs,
                    BinOp::Pow => lhs.powf(rhs),
                }
            }
            ExprKind::Call { func, arg, .. } => func.apply(self.evaluate(arg)?),
        })
    }

    /// [`Checker::evaluate`], reporting a non-finite value as `what`.
    pub(super) fn evaluate_finite(&mut self, expr: &Expr, what: &str) -> Option<f64> {
        let value = self.evaluate(expr)?;
        if value.is_finite() {
            return Some(value);
        }
        let diagnostic = Diagnostic::error(
            codes::NON_FINITE_VALUE,
            format!("{what} is not a finite number"),
        )
        .with_primary(expr.span, format!("this evaluates to {value}"))
        .with_note("params are evaluated at their defaults");
        self.report(diagnostic);
        None
    }
}
