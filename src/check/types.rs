//! The types of expressions (SPEC §2.2): numbers, 2- and 3-vectors and
//! truth values share one grammar, and every operator, function, `let` and
//! statement says which it takes. A mismatch is a located diagnostic.

use super::expressions::{Allowed, CoordUse};
use super::model::Name;
use super::{Checker, MAX_DERIVATIVE_ORDER};
use crate::diagnostic::{codes, Diagnostic};
use crate::span::Span;
use crate::syntax::ast::{BinOp, Builtin, Expr, ExprKind};

/// The type of an expression.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Ty {
    Scalar,
    /// A vector of 2 or 3 components.
    Vector(usize),
    /// A condition: a comparison or `and`/`or`/`not` of comparisons.
    Bool,
}

impl Ty {
    fn describe(self) -> String {
        match self {
            Ty::Scalar => "a number".to_string(),
            Ty::Vector(n) => format!("a {n}-vector"),
            Ty::Bool => "a condition".to_string(),
        }
    }
}

/// What an expression (or a let's body) uses, for the statements that use
/// a let to check it against what they allow.
#[derive(Debug, Clone, Default)]
pub struct Uses {
    pub coords: Vec<CoordUse>,
    /// The first use of `t`.
    pub time: Option<Span>,
    /// The first use of a mass law.
    pub mass: Option<Span>,
    /// The first use of an input.
    pub input: Option<Span>,
    /// The params used, directly or through lets (for `Param::tunable`).
    pub params: Vec<usize>,
}

/// A checked `let`: its type (`None` if its body has errors) and uses.
#[derive(Debug, Clone)]
pub struct LetInfo {
    pub name: String,
    pub span: Span,
    pub ty: Option<Ty>,
    pub uses: Uses,
}

pub fn type_mismatch(span: Span, found: Ty, wanted: Ty, what: &str) -> Diagnostic {
    let diagnostic = Diagnostic::error(
        codes::TYPE_MISMATCH,
        format!(
            "{what} must be {}, not {}",
            wanted.describe(),
            found.describe()
        ),
    )
    .with_primary(span, format!("this is {}", found.describe()));
    match (found, wanted) {
        (Ty::Bool, Ty::Scalar) => {
            diagnostic.with_help("a condition gives a number through `if … then … else …`")
        }
        (Ty::Scalar, Ty::Bool) => diagnostic.with_help("compare it: `x > 0`"),
        (Ty::Vector(_), Ty::Scalar) => {
            diagnostic.with_help("take a component (`.x`), `norm(…)` or `dot(…, …)`")
        }
        _ => diagnostic,
    }
}

fn operand_error(span: Span, message: String, label: String) -> Diagnostic {
    Diagnostic::error(codes::TYPE_MISMATCH, message).with_primary(span, label)
}

impl Checker<'_> {
    /// The type of `expr`, or `None` after reporting why it has none.
    /// Recursion depth is bounded by the parser's expression depth limit.
    pub(super) fn type_of(&mut self, expr: &Expr, allowed: Allowed, uses: &mut Uses) -> Option<Ty> {
        match &expr.kind {
            ExprKind::Number(_) => Some(Ty::Scalar),
            ExprKind::Var { name, primes } => {
                self.var_type(name, *primes, expr.span, allowed, uses)
            }
            ExprKind::Neg(inner) => match self.type_of(inner, allowed, uses)? {
                Ty::Bool => {
                    self.report(type_mismatch(
                        inner.span,
                        Ty::Bool,
                        Ty::Scalar,
                        "`-`'s operand",
                    ));
                    None
                }
                ty => Some(ty),
            },
            ExprKind::Binary { op, lhs, rhs } => {
                let a = self.type_of(lhs, allowed, uses);
                let b = self.type_of(rhs, allowed, uses);
                self.binary_type(*op, expr, lhs, rhs, a?, b?)
            }
            ExprKind::Call {
                func,
                func_span,
                args,
            } => {
                let types: Vec<Option<Ty>> = args
                    .iter()
                    .map(|a| self.type_of(a, allowed, uses))
                    .collect();
                let types: Option<Vec<Ty>> = types.into_iter().collect();
                self.call_type(*func, *func_span, args, &types?)
            }
            ExprKind::Vector(elements) => {
                let mut ok = true;
                for element in elements {
                    match self.type_of(element, allowed, uses) {
                        Some(Ty::Scalar) => {}
                        Some(found) => {
                            self.report(type_mismatch(
                                element.span,
                                found,
                                Ty::Scalar,
                                "a vector's component",
                            ));
                            ok = false;
                        }
                        None => ok = false,
                    }
                }
                ok.then_some(Ty::Vector(elements.len()))
            }
            ExprKind::Component { base, axis } => {
                let ty = self.type_of(base, allowed, uses)?;
                let Ty::Vector(n) = ty else {
                    self.report(operand_error(
                        base.span,
                        format!(
                            "`.{}` takes a component of a vector, not of {}",
                            axis.name,
                            ty.describe()
                        ),
                        format!("this is {}", ty.describe()),
                    ));
                    return None;
                };
                let index = match axis.name.as_str() {
                    "x" => 0,
                    "y" => 1,
                    "z" => 2,
                    _ => usize::MAX,
                };
                if index >= n {
                    let diagnostic = Diagnostic::error(
                        codes::UNKNOWN_COMPONENT,
                        format!("a {n}-vector has no component `{}`", axis.name),
                    )
                    .with_primary(axis.span, "unknown component")
                    .with_help(if n == 2 {
                        "the components of a 2-vector are `.x` and `.y`"
                    } else {
                        "the components of a 3-vector are `.x`, `.y` and `.z`"
                    });
                    self.report(diagnostic);
                    return None;
                }
                Some(Ty::Scalar)
            }
            ExprKind::Compare { op, lhs, rhs } => {
                let a = self.type_of(lhs, allowed, uses);
                let b = self.type_of(rhs, allowed, uses);
                let what = format!("`{}`'s operand", op.symbol());
                let mut ok = true;
                for (side, ty) in [(lhs, a), (rhs, b)] {
                    match ty {
                        Some(Ty::Scalar) => {}
                        Some(found) => {
                            self.report(type_mismatch(side.span, found, Ty::Scalar, &what));
                            ok = false;
                        }
                        None => ok = false,
                    }
                }
                ok.then_some(Ty::Bool)
            }
            ExprKind::Logic { op, lhs, rhs } => {
                let what = match op {
                    crate::syntax::ast::LogicOp::And => "`and`'s operand",
                    crate::syntax::ast::LogicOp::Or => "`or`'s operand",
                };
                let a = self.condition(lhs, allowed, uses, what);
                let b = self.condition(rhs, allowed, uses, what);
                (a && b).then_some(Ty::Bool)
            }
            ExprKind::Not(inner) => self
                .condition(inner, allowed, uses, "`not`'s operand")
                .then_some(Ty::Bool),
            ExprKind::If {
                cond,
                then,
                otherwise,
            } => {
                let c = self.condition(cond, allowed, uses, "an `if`'s condition");
                let a = self.type_of(then, allowed, uses);
                let b = self.type_of(otherwise, allowed, uses);
                let (a, b) = (a?, b?);
                if a == Ty::Bool {
                    self.report(type_mismatch(then.span, a, Ty::Scalar, "an `if`'s value"));
                    return None;
                }
                if a != b {
                    let diagnostic = Diagnostic::error(
                        codes::TYPE_MISMATCH,
                        format!(
                            "the branches of `if` differ: {} and {}",
                            a.describe(),
                            b.describe()
                        ),
                    )
                    .with_primary(otherwise.span, format!("this is {}", b.describe()))
                    .with_secondary(then.span, format!("this is {}", a.describe()));
                    self.report(diagnostic);
                    return None;
                }
                c.then_some(a)
            }
        }
    }

    /// Checks that `expr` is a condition; false after reporting.
    fn condition(&mut self, expr: &Expr, allowed: Allowed, uses: &mut Uses, what: &str) -> bool {
        match self.type_of(expr, allowed, uses) {
            Some(Ty::Bool) => true,
            Some(found) => {
                self.report(type_mismatch(expr.span, found, Ty::Bool, what));
                false
            }
            None => false,
        }
    }

    fn binary_type(
        &mut self,
        op: BinOp,
        _expr: &Expr,
        lhs: &Expr,
        rhs: &Expr,
        a: Ty,
        b: Ty,
    ) -> Option<Ty> {
        let symbol = match op {
            BinOp::Add => "+",
            BinOp::Sub => "-",
            BinOp::Mul => "*",
            BinOp::Div => "/",
            BinOp::Pow => "^",
        };
        for (side, ty) in [(lhs, a), (rhs, b)] {
            if ty == Ty::Bool {
                let what = format!("`{symbol}`'s operand");
                self.report(type_mismatch(side.span, ty, Ty::Scalar, &what));
                return None;
            }
        }
        let result = match (op, a, b) {
            (_, Ty::Scalar, Ty::Scalar) => Some(Ty::Scalar),
            (BinOp::Add | BinOp::Sub, Ty::Vector(n), Ty::Vector(m)) if n == m => Some(a),
            (BinOp::Mul, Ty::Scalar, Ty::Vector(_)) => Some(b),
            (BinOp::Mul | BinOp::Div, Ty::Vector(_), Ty::Scalar) => Some(a),
            _ => None,
        };
        if result.is_none() {
            let help = match (op, a, b) {
                (BinOp::Mul, Ty::Vector(_), Ty::Vector(_)) => {
                    "vectors multiply by `dot(u, v)` or `cross(u, v)`"
                }
                (BinOp::Add | BinOp::Sub, _, _) => {
                    "add numbers to numbers and vectors to vectors of one size"
                }
                (BinOp::Pow, _, _) => "`^` takes numbers; `dot(u, u)` squares a vector's length",
                _ => "a vector divides by a number only",
            };
            let diagnostic = Diagnostic::error(
                codes::TYPE_MISMATCH,
                format!("`{symbol}` of {} and {}", a.describe(), b.describe()),
            )
            .with_primary(rhs.span, format!("this is {}", b.describe()))
            .with_secondary(lhs.span, format!("this is {}", a.describe()))
            .with_help(help);
            self.report(diagnostic);
        }
        result
    }

    fn call_type(
        &mut self,
        func: Builtin,
        func_span: Span,
        args: &[Expr],
        types: &[Ty],
    ) -> Option<Ty> {
        let name = func.name();
        let want = |checker: &mut Self, i: usize, ok: bool, wanted: &str| -> bool {
            if !ok {
                let found = types[i].describe();
                checker.report(operand_error(
                    args[i].span,
                    format!("`{name}` takes {wanted}, not {found}"),
                    format!("this is {found}"),
                ));
            }
            ok
        };
        match func {
            Builtin::Elementary(_)
            | Builtin::Abs
            | Builtin::Sign
            | Builtin::Atan2
            | Builtin::Min
            | Builtin::Max => {
                let mut ok = true;
                for (i, ty) in types.iter().enumerate() {
                    ok &= want(self, i, *ty == Ty::Scalar, "numbers");
                }
                ok.then_some(Ty::Scalar)
            }
            Builtin::Norm => {
                want(self, 0, matches!(types[0], Ty::Vector(_)), "a vector").then_some(Ty::Scalar)
            }
            Builtin::Dot | Builtin::Cross => {
                let mut ok = true;
                for (i, ty) in types.iter().enumerate() {
                    ok &= want(self, i, matches!(ty, Ty::Vector(_)), "vectors");
                }
                if !ok {
                    return None;
                }
                if types[0] != types[1] {
                    let diagnostic = Diagnostic::error(
                        codes::TYPE_MISMATCH,
                        format!(
                            "`{name}` of {} and {}",
                            types[0].describe(),
                            types[1].describe()
                        ),
                    )
                    .with_primary(func_span, "the vectors differ in size")
                    .with_secondary(args[0].span, types[0].describe())
                    .with_secondary(args[1].span, types[1].describe());
                    self.report(diagnostic);
                    return None;
                }
                if func == Builtin::Dot {
                    return Some(Ty::Scalar);
                }
                if types[0] != Ty::Vector(3) {
                    let diagnostic = Diagnostic::error(
                        codes::TYPE_MISMATCH,
                        "`cross` takes 3-vectors, not 2-vectors",
                    )
                    .with_primary(func_span, "a cross product of 2-vectors")
                    .with_help(
                        "write the planar cross product as a number: `u.x * v.y - u.y * v.x`",
                    );
                    self.report(diagnostic);
                    return None;
                }
                Some(Ty::Vector(3))
            }
        }
    }

    fn var_type(
        &mut self,
        name: &crate::syntax::ast::Ident,
        primes: u32,
        span: Span,
        allowed: Allowed,
        uses: &mut Uses,
    ) -> Option<Ty> {
        let declared = self.names.get(&name.name).copied();
        match declared.map(|d| d.name) {
            None if name.name == "pi" && primes == 0 => Some(Ty::Scalar),
            Some(Name::Let(index)) => self.let_use(index, primes, span, allowed, uses),
            Some(Name::Output(_)) => {
                let diagnostic = Diagnostic::error(
                    codes::NAME_NOT_ALLOWED,
                    format!("{} cannot use the output `{}`", allowed.what, name.name),
                )
                .with_primary(span, "an output names a CSV column; it has no value here")
                .with_help("name the value with `let` and output the let");
                self.report(diagnostic);
                None
            }
            found => {
                if name.name == "t" && primes == 0 && allowed.time {
                    uses.time.get_or_insert(span);
                }
                if matches!(found, Some(Name::Mass(_))) && allowed.masses {
                    uses.mass.get_or_insert(span);
                }
                if matches!(found, Some(Name::Input(_))) && allowed.inputs {
                    uses.input.get_or_insert(span);
                }
                if let Some(Name::Param(index)) = found {
                    uses.params.push(index);
                }
                if let Some(used) = self.check_var(&name.name, primes, span, allowed) {
                    uses.coords.push(used);
                }
                match found {
                    Some(Name::Point(_)) => None,
                    _ => Some(Ty::Scalar),
                }
            }
        }
    }

    /// A use of let `index` (`primes` times differentiated): its body's
    /// uses, raised by `primes`, checked against `allowed` at the use.
    fn let_use(
        &mut self,
        index: usize,
        primes: u32,
        span: Span,
        allowed: Allowed,
        uses: &mut Uses,
    ) -> Option<Ty> {
        let Some(info) = self
            .lets
            .get(index)
            .cloned()
            .filter(|_| index < allowed.lets_before)
        else {
            let (name, defined) = self.ast_let(index)?;
            let diagnostic = Diagnostic::error(
                codes::LET_BEFORE_DEFINITION,
                format!("let `{name}` is used before its definition"),
            )
            .with_primary(span, "used here")
            .with_secondary(defined, "defined here")
            .with_help("a let may use only lets defined before it (so that no let is defined through itself)");
            self.report(diagnostic);
            return None;
        };
        let ty = info.ty?;
        if primes > 0 && ty == Ty::Bool {
            return None;
        }
        let defined = info.span;
        let name = &info.name;
        let through = |what: String| {
            Diagnostic::error(
                codes::NAME_NOT_ALLOWED,
                format!(
                    "{} cannot use let `{name}`: it depends on {what}",
                    allowed.what
                ),
            )
            .with_primary(span, "used here")
            .with_secondary(defined, format!("`{name}` defined here"))
        };
        if allowed.params_before != usize::MAX {
            let diagnostic = Diagnostic::error(
                codes::NAME_NOT_ALLOWED,
                format!("{} cannot use let `{name}`", allowed.what),
            )
            .with_primary(span, "used here")
            .with_help(
                "a param is a number of its own; compute it from numbers and earlier params",
            );
            self.report(diagnostic);
            return None;
        }
        uses.params.extend_from_slice(&info.uses.params);
        let mut ok = true;
        if let Some(at) = info.uses.time {
            if allowed.time {
                uses.time.get_or_insert(at);
            } else {
                self.report(through("time `t`".to_string()).with_secondary(at, "`t` used here"));
                ok = false;
            }
        }
        if let Some(at) = info.uses.mass {
            if allowed.masses {
                uses.mass.get_or_insert(at);
            } else {
                self.report(
                    through("a mass law".to_string()).with_secondary(at, "mass law used here"),
                );
                ok = false;
            }
        }
        if let Some(at) = info.uses.input {
            if allowed.inputs {
                uses.input.get_or_insert(at);
            } else {
                let diagnostic = Diagnostic::error(
                    codes::INPUT_NOT_ALLOWED,
                    format!(
                        "{} cannot use let `{name}`: it depends on an input",
                        allowed.what
                    ),
                )
                .with_primary(span, "used here")
                .with_secondary(at, "input used here")
                .with_secondary(defined, format!("`{name}` defined here"))
                .with_note(super::expressions::input_note(allowed));
                self.report(diagnostic);
                ok = false;
            }
        }
        for used in &info.uses.coords {
            let order = used.order.saturating_add(primes);
            let coord_name = self
                .coords
                .get(used.coord)
                .map_or("?", |c| c.name.as_str())
                .to_string();
            match allowed.coord_order {
                None => {
                    let diagnostic = Diagnostic::error(
                        allowed.coord_code,
                        format!(
                            "{} cannot use let `{name}`: it depends on the coordinate `{coord_name}`",
                            allowed.what
                        ),
                    )
                    .with_primary(span, "used here")
                    .with_secondary(used.span, "coordinate used here");
                    self.report(diagnostic);
                    ok = false;
                    break;
                }
                Some(max)
                    if order > max.min(MAX_DERIVATIVE_ORDER)
                        && allowed.order_code == codes::MASS_DEPENDS_ON_STATE =>
                {
                    let diagnostic = super::expressions::mass_of_velocity(
                        allowed.what,
                        &coord_name,
                        order,
                        span,
                        &format!("let `{name}` used here"),
                    )
                    .with_secondary(
                        used.span,
                        format!(
                            "`{coord_name}{}` used here",
                            "'".repeat(used.order as usize)
                        ),
                    );
                    self.report(diagnostic);
                    ok = false;
                    break;
                }
                Some(max) if order > max.min(MAX_DERIVATIVE_ORDER) => {
                    let diagnostic = Diagnostic::error(
                        codes::DERIVATIVE_ORDER_NOT_ALLOWED,
                        format!(
                            "{} cannot hold a derivative of `{coord_name}` of order {order}, which let `{name}{}` holds",
                            allowed.what,
                            "'".repeat(primes as usize)
                        ),
                    )
                    .with_primary(span, "used here")
                    .with_secondary(used.span, format!("`{coord_name}` used here"));
                    self.report(diagnostic);
                    ok = false;
                    break;
                }
                Some(_) => {
                    // One entry per coordinate and order at this use: a let
                    // used twice by the next, and so on, would otherwise
                    // double its list at every level (a chain of 30 lets
                    // took 13 GB to check).
                    let entry = CoordUse {
                        coord: used.coord,
                        order,
                        span,
                    };
                    if !uses.coords.contains(&entry) {
                        uses.coords.push(entry);
                    }
                }
            }
        }
        ok.then_some(ty)
    }

    /// The name and span of the `index`-th let statement.
    fn ast_let(&self, index: usize) -> Option<(String, Span)> {
        self.items()
            .filter_map(|(item, _)| match item {
                crate::syntax::ast::ItemKind::Let { name, .. } => {
                    Some((name.name.clone(), name.span))
                }
                _ => None,
            })
            .nth(index)
    }

    /// Checks every `let` in order: its type and what it uses.
    pub(super) fn lets(&mut self) -> Vec<super::model::Let> {
        let mut lets = Vec::new();
        let mut index = 0;
        for (item, span) in self.items() {
            let crate::syntax::ast::ItemKind::Let { name, value } = item else {
                continue;
            };
            let mut uses = Uses::default();
            let allowed = Allowed::anything("a let", index);
            let ty = self.type_of(value, allowed, &mut uses);
            if ty == Some(Ty::Bool) {
                self.report(
                    type_mismatch(value.span, Ty::Bool, Ty::Scalar, "a let").with_note(
                        "a let names a number or a vector; conditions go into `if` or `stop when`",
                    ),
                );
            }
            let ty = ty.filter(|&t| t != Ty::Bool);
            // Only the first let of a name is declared; a duplicate keeps
            // its place (indices count every let) but nothing refers to it.
            self.lets.push(LetInfo {
                name: name.name.clone(),
                span: name.span,
                ty,
                uses,
            });
            lets.push(super::model::Let {
                name: name.name.clone(),
                span,
                value: value.clone(),
                size: match ty {
                    Some(Ty::Vector(n)) => n,
                    _ => 1,
                },
            });
            index += 1;
        }
        lets
    }
}
