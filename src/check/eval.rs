//! Evaluating constant expressions (numbers, params, functions) to `f64`:
//! param defaults, initial values, time bounds.

use super::model::Name;
use super::Checker;
use crate::diagnostic::{codes, Diagnostic};
use crate::syntax::ast::{BinOp, Builtin, CmpOp, Expr, ExprKind, ItemKind, LogicOp};

/// A constant expression's value.
#[derive(Debug, Clone, PartialEq)]
enum Value {
    Number(f64),
    Vector(Vec<f64>),
    Truth(bool),
}

pub fn axis_index(axis: &str) -> Option<usize> {
    match axis {
        "x" => Some(0),
        "y" => Some(1),
        "z" => Some(2),
        _ => None,
    }
}

/// `sign` as the language defines it: 0 at 0 (unlike `f64::signum`).
pub fn sign(x: f64) -> f64 {
    if x > 0.0 {
        1.0
    } else if x < 0.0 {
        -1.0
    } else {
        0.0
    }
}

fn call(func: Builtin, args: &[Value]) -> Option<Value> {
    use Value::{Number, Vector};
    let number = |i: usize| match args.get(i) {
        Some(Number(v)) => Some(*v),
        _ => None,
    };
    let vector = |i: usize| match args.get(i) {
        Some(Vector(v)) => Some(v.clone()),
        _ => None,
    };
    Some(match func {
        Builtin::Elementary(f) => Number(f.apply(number(0)?)),
        Builtin::Abs => Number(number(0)?.abs()),
        Builtin::Sign => Number(sign(number(0)?)),
        Builtin::Atan2 => Number(number(0)?.atan2(number(1)?)),
        Builtin::Min => Number(number(0)?.min(number(1)?)),
        Builtin::Max => Number(number(0)?.max(number(1)?)),
        Builtin::Dot => Number(vector(0)?.iter().zip(&vector(1)?).map(|(a, b)| a * b).sum()),
        Builtin::Norm => Number(vector(0)?.iter().map(|a| a * a).sum::<f64>().sqrt()),
        Builtin::Cross => {
            let (a, b) = (vector(0)?, vector(1)?);
            if a.len() != 3 || b.len() != 3 {
                return None;
            }
            Vector(vec![
                a[1] * b[2] - a[2] * b[1],
                a[2] * b[0] - a[0] * b[2],
                a[0] * b[1] - a[1] * b[0],
            ])
        }
    })
}

impl Checker<'_> {
    /// The value of a constant expression with every param at its default;
    /// `None` if it names anything else or a param without a default (both
    /// already reported). Recursion depth is bounded by the parser's
    /// expression depth limit.
    pub(super) fn evaluate(&self, expr: &Expr) -> Option<f64> {
        match self.value(expr)? {
            Value::Number(v) => Some(v),
            _ => None,
        }
    }

    fn value(&self, expr: &Expr) -> Option<Value> {
        use Value::{Number, Truth, Vector};
        Some(match &expr.kind {
            ExprKind::Number(value) => Number(*value),
            ExprKind::Var { name, primes: 0 } => match self.names.get(&name.name).map(|d| d.name) {
                Some(Name::Param(index)) => Number((*self.param_defaults.get(index)?)?),
                Some(Name::Let(index)) => {
                    let value = self.ast.items.iter().filter_map(|item| match &item.kind {
                        ItemKind::Let { value, .. } => Some(value),
                        _ => None,
                    });
                    return self.value(value.into_iter().nth(index)?);
                }
                None if name.name == "pi" => Number(std::f64::consts::PI),
                None if name.name == "t" => Number(self.start.as_ref()?.t0),
                Some(Name::Coord(index)) => Number(self.start.as_ref()?.value(index, 0)?),
                _ => return None,
            },
            ExprKind::Var { name, primes } => match self.names.get(&name.name).map(|d| d.name) {
                Some(Name::Coord(index)) => Number(self.start.as_ref()?.value(index, *primes)?),
                _ => return None,
            },
            ExprKind::Neg(inner) => match self.value(inner)? {
                Number(v) => Number(-v),
                Vector(v) => Vector(v.iter().map(|x| -x).collect()),
                Truth(_) => return None,
            },
            ExprKind::Binary { op, lhs, rhs } => match (self.value(lhs)?, self.value(rhs)?) {
                (Number(a), Number(b)) => Number(match op {
                    BinOp::Add => a + b,
                    BinOp::Sub => a - b,
                    BinOp::Mul => a * b,
                    BinOp::Div => a / b,
                    BinOp::Pow => a.powf(b),
                }),
                (Vector(a), Vector(b)) if a.len() == b.len() => match op {
                    BinOp::Add => Vector(a.iter().zip(&b).map(|(x, y)| x + y).collect()),
                    BinOp::Sub => Vector(a.iter().zip(&b).map(|(x, y)| x - y).collect()),
                    _ => return None,
                },
                (Number(a), Vector(b)) if *op == BinOp::Mul => {
                    Vector(b.iter().map(|y| a * y).collect())
                }
                (Vector(a), Number(b)) => match op {
                    BinOp::Mul => Vector(a.iter().map(|x| x * b).collect()),
                    BinOp::Div => Vector(a.iter().map(|x| x / b).collect()),
                    _ => return None,
                },
                _ => return None,
            },
            ExprKind::Call { func, args, .. } => {
                let values: Option<Vec<Value>> = args.iter().map(|a| self.value(a)).collect();
                call(*func, &values?)?
            }
            ExprKind::Vector(elements) => {
                let values: Option<Vec<f64>> = elements.iter().map(|e| self.evaluate(e)).collect();
                Vector(values?)
            }
            ExprKind::Component { base, axis } => match self.value(base)? {
                Vector(v) => Number(*v.get(axis_index(&axis.name)?)?),
                _ => return None,
            },
            ExprKind::Compare { op, lhs, rhs } => {
                let (a, b) = (self.evaluate(lhs)?, self.evaluate(rhs)?);
                Truth(match op {
                    CmpOp::Less => a < b,
                    CmpOp::LessEq => a <= b,
                    CmpOp::Greater => a > b,
                    CmpOp::GreaterEq => a >= b,
                })
            }
            ExprKind::Logic { op, lhs, rhs } => match (self.value(lhs)?, self.value(rhs)?) {
                (Truth(a), Truth(b)) => Truth(match op {
                    LogicOp::And => a && b,
                    LogicOp::Or => a || b,
                }),
                _ => return None,
            },
            ExprKind::Not(inner) => match self.value(inner)? {
                Truth(a) => Truth(!a),
                _ => return None,
            },
            ExprKind::If {
                cond,
                then,
                otherwise,
            } => match self.value(cond)? {
                Truth(true) => self.value(then)?,
                Truth(false) => self.value(otherwise)?,
                _ => return None,
            },
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
