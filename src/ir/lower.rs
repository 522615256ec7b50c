//! AST expressions of a checked model → IR expressions.
//!
//! Vectors, lets and conditions exist only here: a vector lowers to its
//! components, a let to its (memoised) lowered body, a condition to nested
//! [`Node::Select`](super::expr::Node) on switching functions `g < 0`.

use super::expr::{Arena, ExprId, Names, Symbol};
use crate::check::model::{Model, Name};
use crate::span::Span;
use crate::syntax::ast::{BinOp, Builtin, CmpOp, Expr, ExprKind, Func, LogicOp};

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
        inputs: model.inputs.iter().map(|u| u.name.clone()).collect(),
    }
}

/// Lowers `expr`. A name that does not resolve to a symbol (see
/// [`try_lower`]) lowers to a NaN constant, which can never pass a numeric
/// check unnoticed; callers that want the error use [`try_lower`].
pub fn lower(arena: &mut Arena, expr: &Expr, model: &Model) -> ExprId {
    try_lower(arena, expr, model).unwrap_or_else(|_| arena.constant(f64::NAN))
}

/// Lowers a number-valued `expr`, or names the first name that is not a
/// symbol: an unknown name, a point, or a derivative mark on `t`, a param or
/// a mass law.
pub fn try_lower(arena: &mut Arena, expr: &Expr, model: &Model) -> Result<ExprId, LowerError> {
    match lower_value(arena, expr, model)? {
        Value::Components(c) if c.len() == 1 => Ok(c[0]),
        _ => Err(not_a_number(expr)),
    }
}

/// Lowers a vector-valued (or number-valued) `expr` to its components.
pub fn try_lower_components(
    arena: &mut Arena,
    expr: &Expr,
    model: &Model,
) -> Result<Vec<ExprId>, LowerError> {
    match lower_value(arena, expr, model)? {
        Value::Components(c) => Ok(c),
        Value::Cond(_) => Err(not_a_number(expr)),
    }
}

/// Lowers a condition to `if cond then 1 else 0`'s selection tree, whose
/// switching functions are the comparisons' differences.
pub fn try_lower_condition(
    arena: &mut Arena,
    expr: &Expr,
    model: &Model,
) -> Result<Cond, LowerError> {
    match lower_value(arena, expr, model)? {
        Value::Cond(c) => Ok(c),
        Value::Components(_) => Err(not_a_number(expr)),
    }
}

fn not_a_number(expr: &Expr) -> LowerError {
    LowerError {
        name: "(an expression of the wrong type)".to_string(),
        primes: 0,
        span: expr.span,
    }
}

/// A lowered condition: `Negative(g)` is `g < 0`.
#[derive(Debug, Clone, PartialEq)]
pub enum Cond {
    Negative(ExprId),
    Not(Box<Cond>),
    And(Box<Cond>, Box<Cond>),
    Or(Box<Cond>, Box<Cond>),
}

impl Cond {
    /// Every switching function `g` of the condition, in order.
    pub fn switches(&self, out: &mut Vec<ExprId>) {
        match self {
            Cond::Negative(g) => out.push(*g),
            Cond::Not(c) => c.switches(out),
            Cond::And(a, b) | Cond::Or(a, b) => {
                a.switches(out);
                b.switches(out);
            }
        }
    }
}

/// `if cond then a else b`, as selections on the condition's switches.
pub fn select(arena: &mut Arena, cond: &Cond, a: ExprId, b: ExprId) -> ExprId {
    match cond {
        Cond::Negative(g) => arena.select(*g, a, b),
        Cond::Not(c) => select(arena, c, b, a),
        Cond::And(c1, c2) => {
            let inner = select(arena, c2, a, b);
            select(arena, c1, inner, b)
        }
        Cond::Or(c1, c2) => {
            let inner = select(arena, c2, a, b);
            select(arena, c1, a, inner)
        }
    }
}

enum Value {
    /// A number (one component) or a vector.
    Components(Vec<ExprId>),
    Cond(Cond),
}

fn components(value: Value, expr: &Expr) -> Result<Vec<ExprId>, LowerError> {
    match value {
        Value::Components(c) => Ok(c),
        Value::Cond(_) => Err(not_a_number(expr)),
    }
}

fn scalar(arena: &mut Arena, expr: &Expr, model: &Model) -> Result<ExprId, LowerError> {
    try_lower(arena, expr, model)
}

fn condition(arena: &mut Arena, expr: &Expr, model: &Model) -> Result<Cond, LowerError> {
    try_lower_condition(arena, expr, model)
}

fn lower_value(arena: &mut Arena, expr: &Expr, model: &Model) -> Result<Value, LowerError> {
    let one = |e| Ok(Value::Components(vec![e]));
    match &expr.kind {
        ExprKind::Number(v) => one(arena.constant(*v)),
        ExprKind::Var { name, primes } => {
            let symbol = match (name.name.as_str(), model.resolve(&name.name), *primes) {
                (_, Some(Name::Let(i)), r) => {
                    return Ok(Value::Components(lower_let(arena, model, i, r, expr)?));
                }
                ("pi", None, 0) => return one(arena.constant(std::f64::consts::PI)),
                ("t", _, 0) => Some(Symbol::Time),
                (_, Some(Name::Param(i)), 0) => Some(Symbol::Param(i as u32)),
                (_, Some(Name::Mass(i)), 0) => Some(Symbol::Mass(i as u32)),
                (_, Some(Name::Input(i)), 0) => Some(Symbol::Input(i as u32)),
                (_, Some(Name::Coord(j)), r) => Some(Symbol::Jet {
                    coord: j as u32,
                    order: r,
                }),
                _ => None,
            };
            match symbol {
                Some(s) => one(arena.symbol(s)),
                None => Err(LowerError {
                    name: name.name.clone(),
                    primes: *primes,
                    span: expr.span,
                }),
            }
        }
        ExprKind::Neg(a) => {
            let a = components(lower_value(arena, a, model)?, expr)?;
            Ok(Value::Components(
                a.into_iter().map(|x| arena.neg(x)).collect(),
            ))
        }
        ExprKind::Binary { op, lhs, rhs } => {
            let a = components(lower_value(arena, lhs, model)?, expr)?;
            let b = components(lower_value(arena, rhs, model)?, expr)?;
            binary(arena, *op, &a, &b)
                .ok_or_else(|| not_a_number(expr))
                .map(Value::Components)
        }
        ExprKind::Call { func, args, .. } => call(arena, *func, args, model, expr),
        ExprKind::Vector(elements) => {
            let mut c = Vec::with_capacity(elements.len());
            for e in elements {
                c.push(scalar(arena, e, model)?);
            }
            Ok(Value::Components(c))
        }
        ExprKind::Component { base, axis } => {
            let v = components(lower_value(arena, base, model)?, expr)?;
            let i = crate::check::axis_index(&axis.name).ok_or_else(|| not_a_number(expr))?;
            v.get(i)
                .map(|&c| Value::Components(vec![c]))
                .ok_or_else(|| not_a_number(expr))
        }
        ExprKind::Compare { op, lhs, rhs } => {
            let a = scalar(arena, lhs, model)?;
            let b = scalar(arena, rhs, model)?;
            Ok(Value::Cond(match op {
                CmpOp::Less => Cond::Negative(arena.sub(a, b)),
                CmpOp::Greater => Cond::Negative(arena.sub(b, a)),
                CmpOp::LessEq => Cond::Not(Box::new(Cond::Negative(arena.sub(b, a)))),
                CmpOp::GreaterEq => Cond::Not(Box::new(Cond::Negative(arena.sub(a, b)))),
            }))
        }
        ExprKind::Logic { op, lhs, rhs } => {
            let a = Box::new(condition(arena, lhs, model)?);
            let b = Box::new(condition(arena, rhs, model)?);
            Ok(Value::Cond(match op {
                LogicOp::And => Cond::And(a, b),
                LogicOp::Or => Cond::Or(a, b),
            }))
        }
        ExprKind::Not(a) => Ok(Value::Cond(Cond::Not(Box::new(condition(
            arena, a, model,
        )?)))),
        ExprKind::If {
            cond,
            then,
            otherwise,
        } => {
            let c = condition(arena, cond, model)?;
            let a = components(lower_value(arena, then, model)?, expr)?;
            let b = components(lower_value(arena, otherwise, model)?, expr)?;
            if a.len() != b.len() {
                return Err(not_a_number(expr));
            }
            let selected = a
                .iter()
                .zip(&b)
                .map(|(&x, &y)| select(arena, &c, x, y))
                .collect();
            Ok(Value::Components(selected))
        }
    }
}

/// Let `index` differentiated `primes` times by `D` (mass laws frozen),
/// lowered once per arena.
fn lower_let(
    arena: &mut Arena,
    model: &Model,
    index: usize,
    primes: u32,
    at: &Expr,
) -> Result<Vec<ExprId>, LowerError> {
    let key = (index as u32, primes);
    if let Some(found) = arena.lets.get(&key) {
        return Ok(found.to_vec());
    }
    let value = if primes == 0 {
        let body = &model.lets.get(index).ok_or_else(|| not_a_number(at))?.value;
        try_lower_components(arena, body, model)?
    } else {
        lower_let(arena, model, index, primes - 1, at)?
            .into_iter()
            .map(|c| arena.total_derivative(c))
            .collect()
    };
    arena.lets.insert(key, value.clone().into_boxed_slice());
    Ok(value)
}

fn binary(arena: &mut Arena, op: BinOp, a: &[ExprId], b: &[ExprId]) -> Option<Vec<ExprId>> {
    let each = |arena: &mut Arena, f: &dyn Fn(&mut Arena, ExprId, ExprId) -> ExprId| {
        if a.len() == b.len() {
            Some(a.iter().zip(b).map(|(&x, &y)| f(arena, x, y)).collect())
        } else if a.len() == 1 {
            Some(b.iter().map(|&y| f(arena, a[0], y)).collect())
        } else if b.len() == 1 {
            Some(a.iter().map(|&x| f(arena, x, b[0])).collect())
        } else {
            None
        }
    };
    match op {
        BinOp::Add => each(arena, &|ar, x, y| ar.add(&[x, y])),
        BinOp::Sub => each(arena, &|ar, x, y| ar.sub(x, y)),
        BinOp::Mul => each(arena, &|ar, x, y| ar.mul(&[x, y])),
        BinOp::Div => each(arena, &|ar, x, y| ar.div(x, y)),
        BinOp::Pow => each(arena, &|ar, x, y| ar.pow(x, y)),
    }
}

fn call(
    arena: &mut Arena,
    func: Builtin,
    args: &[Expr],
    model: &Model,
    at: &Expr,
) -> Result<Value, LowerError> {
    let mut lowered = Vec::with_capacity(args.len());
    for a in args {
        lowered.push(components(lower_value(arena, a, model)?, at)?);
    }
    let number = |i: usize| -> Result<ExprId, LowerError> {
        match lowered.get(i) {
            Some(c) if c.len() == 1 => Ok(c[0]),
            _ => Err(not_a_number(at)),
        }
    };
    let value = match func {
        Builtin::Elementary(f) => arena.func(f, number(0)?),
        Builtin::Abs => {
            let x = number(0)?;
            let minus = arena.neg(x);
            arena.select(x, minus, x)
        }
        Builtin::Sign => {
            let x = number(0)?;
            match arena.as_const(x) {
                Some(v) => arena.constant(crate::check::sign(v)),
                None => {
                    let (minus_one, one) = (arena.constant(-1.0), arena.one());
                    arena.select(x, minus_one, one)
                }
            }
        }
        Builtin::Min | Builtin::Max => {
            let (a, b) = (number(0)?, number(1)?);
            let g = arena.sub(a, b);
            if func == Builtin::Min {
                arena.select(g, a, b)
            } else {
                arena.select(g, b, a)
            }
        }
        Builtin::Atan2 => {
            // Half-angle formulas about the y axis, one per half-plane:
            // π/2 − 2·atan(x/(r + y)) where y ≥ 0 and −π/2 + 2·atan(x/(r − y))
            // where y < 0, r = √(x² + y²). Each is atan2 on its closed
            // half-plane, well conditioned (r ± y ≥ r) with its derivative
            // (x dy − y dx)/r² defined everywhere but the origin. The one
            // switch is y = 0: across it the value is smooth where x > 0
            // and jumps by 2π on the cut (x < 0). (atan(y/x) ± π, switched
            // on x, had the derivative 0/0 at x = 0: exit 3 there.)
            let (y, x) = (number(0)?, number(1)?);
            let (x2, y2) = (arena.powi(x, 2), arena.powi(y, 2));
            let sum = arena.add(&[x2, y2]);
            let r = arena.func(Func::Sqrt, sum);
            let half_angle = |arena: &mut Arena, y: ExprId| {
                let denominator = arena.add(&[r, y]);
                let ratio = arena.div(x, denominator);
                let angle = arena.func(Func::Atan, ratio);
                let two = arena.constant(2.0);
                arena.mul(&[two, angle])
            };
            let upper = half_angle(arena, y);
            let minus_y = arena.neg(y);
            let lower = half_angle(arena, minus_y);
            let upper = arena.neg(upper);
            let half_pi = arena.constant(std::f64::consts::FRAC_PI_2);
            let minus_half_pi = arena.constant(-std::f64::consts::FRAC_PI_2);
            let above = arena.add(&[half_pi, upper]);
            let below = arena.add(&[minus_half_pi, lower]);
            arena.select(y, below, above)
        }
        Builtin::Dot | Builtin::Norm => {
            let u = lowered.first().cloned().unwrap_or_default();
            let v = if func == Builtin::Dot {
                lowered.get(1).cloned().unwrap_or_default()
            } else {
                u.clone()
            };
            if u.len() != v.len() {
                return Err(not_a_number(at));
            }
            let terms: Vec<ExprId> = u
                .iter()
                .zip(&v)
                .map(|(&a, &b)| arena.mul(&[a, b]))
                .collect();
            let sum = arena.add(&terms);
            if func == Builtin::Dot {
                sum
            } else {
                arena.func(Func::Sqrt, sum)
            }
        }
        Builtin::Cross => {
            let (a, b) = match (lowered.first(), lowered.get(1)) {
                (Some(a), Some(b)) if a.len() == 3 && b.len() == 3 => (a.clone(), b.clone()),
                _ => return Err(not_a_number(at)),
            };
            let mut c = Vec::with_capacity(3);
            for (i, j) in [(1, 2), (2, 0), (0, 1)] {
                let p = arena.mul(&[a[i], b[j]]);
                let q = arena.mul(&[a[j], b[i]]);
                c.push(arena.sub(p, q));
            }
            return Ok(Value::Components(c));
        }
    };
    Ok(Value::Components(vec![value]))
}

impl Arena {
    /// The lets lowered so far, by `(index, primes)`.
    pub fn lowered_lets(&self) -> std::collections::HashMap<(u32, u32), Vec<ExprId>> {
        self.lets.iter().map(|(&k, v)| (k, v.to_vec())).collect()
    }
}
