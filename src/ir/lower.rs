//! AST expressions of a checked model → IR expressions.

use super::expr::{Arena, ExprId, Names, Symbol};
use crate::check::model::{Model, Name};
use crate::span::Span;
use crate::syntax::ast::{BinOp, Expr, ExprKind};

/// A name that `lower` could not turn into a symbol. The checker rules all of
/// these out; they are reported, not panicked on, in case a caller lowers an
/// unchecked expression.
#[derive(Debug, Clone, PartialEq)]
pub struct LowerError {
    pub name: String,
    pub primes: u32,
    pub span: Span,
}

/// The display names of a model's symbols.
pub fn names_of(model: &Model) -> Names {
    Names {
        params: model.params.iter().map(|p| p.name.clone()).collect(),
        coords: model.coords.iter().map(|c| c.name.clone()).collect(),
        masses: model.masses.iter().map(|m| m.name.clone()).collect(),
    }
}

/// Lowers `expr`. A name that does not resolve to a symbol (see
/// [`try_lower`]) lowers to a NaN constant, which can never pass a numeric
/// check unnoticed; callers that want the error use [`try_lower`].
pub fn lower(arena: &mut Arena, expr: &Expr, model: &Model) -> ExprId {
    try_lower(arena, expr, model).unwrap_or_else(|_| arena.constant(f64::NAN))
}

/// Lowers `expr`, or names the first name that is not a symbol: an unknown
/// name, a point, or a derivative mark on `t`, a param or a mass law.
pub fn try_lower(arena: &mut Arena, expr: &Expr, model: &Model) -> Result<ExprId, LowerError> {
    Ok(match &expr.kind {
        ExprKind::Number(v) => arena.constant(*v),
        ExprKind::Var { name, primes } => {
            let symbol = match (name.name.as_str(), model.resolve(&name.name), *primes) {
                ("t", _, 0) => Some(Symbol::Time),
                (_, Some(Name::Param(i)), 0) => Some(Symbol::Param(i as u32)),
                (_, Some(Name::Mass(i)), 0) => Some(Symbol::Mass(i as u32)),
                (_, Some(Name::Coord(j)), r) => Some(Symbol::Jet {
                    coord: j as u32,
                    order: r,
                }),
                _ => None,
            };
            match symbol {
                Some(s) => arena.symbol(s),
                None => {
                    return Err(LowerError {
                        name: name.name.clone(),
                        primes: *primes,
                        span: expr.span,
                    })
                }
            }
        }
        ExprKind::Neg(a) => {
            let a = try_lower(arena, a, model)?;
            arena.neg(a)
        }
        ExprKind::Binary { op, lhs, rhs } => {
            let a = try_lower(arena, lhs, model)?;
            let b = try_lower(arena, rhs, model)?;
            match op {
                BinOp::Add => arena.add(&[a, b]),
                BinOp::Sub => arena.sub(a, b),
                BinOp::Mul => arena.mul(&[a, b]),
                BinOp::Div => arena.div(a, b),
                BinOp::Pow => arena.pow(a, b),
            }
        }
        ExprKind::Call { func, arg, .. } => {
            let a = try_lower(arena, arg, model)?;
            arena.func(*func, a)
        }
    })
}
