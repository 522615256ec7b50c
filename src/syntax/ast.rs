//! The abstract syntax tree of a `.lag` file. Every node carries its span.
//!
//! The AST is what the user wrote, names unresolved: `check` resolves names
//! and validates the model. The grammar is deliberately more permissive than
//! the language (a constraint's left side is any expression, for instance) so
//! that mistakes reach `check` and get a precise diagnostic instead of a
//! syntax error.

use crate::span::Span;

#[derive(Debug, Clone, PartialEq)]
pub struct Ident {
    pub name: String,
    pub span: Span,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Expr {
    pub kind: ExprKind,
    pub span: Span,
}

#[derive(Debug, Clone, PartialEq)]
pub enum ExprKind {
    /// A numeric literal, already converted (`1e999` is rejected by the parser).
    Number(f64),
    /// A name with `primes` derivative marks: `M` (0), `q1'` (1), `q1''` (2).
    Var {
        name: Ident,
        primes: u32,
    },
    Neg(Box<Expr>),
    Binary {
        op: BinOp,
        lhs: Box<Expr>,
        rhs: Box<Expr>,
    },
    /// `f(a, …)`: the parser knows the function and checks its arity.
    Call {
        func: Builtin,
        func_span: Span,
        args: Vec<Expr>,
    },
    /// `(e1, e2)` or `(e1, e2, e3)` (SPEC §2.2).
    Vector(Vec<Expr>),
    /// `u.x`, `u.y`, `u.z`: `check` requires a vector and a known axis.
    Component {
        base: Box<Expr>,
        axis: Ident,
    },
    /// `a < b`, …: a truth value.
    Compare {
        op: CmpOp,
        lhs: Box<Expr>,
        rhs: Box<Expr>,
    },
    /// `a and b`, `a or b`.
    Logic {
        op: LogicOp,
        lhs: Box<Expr>,
        rhs: Box<Expr>,
    },
    Not(Box<Expr>),
    /// `if cond then a else b`.
    If {
        cond: Box<Expr>,
        then: Box<Expr>,
        otherwise: Box<Expr>,
    },
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum CmpOp {
    Less,
    LessEq,
    Greater,
    GreaterEq,
}

impl CmpOp {
    pub fn symbol(self) -> &'static str {
        match self {
            CmpOp::Less => "<",
            CmpOp::LessEq => "<=",
            CmpOp::Greater => ">",
            CmpOp::GreaterEq => ">=",
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum LogicOp {
    And,
    Or,
}

/// Every function a model may call: v1's elementary functions and SPEC
/// §2.2's piecewise and vector ones.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Builtin {
    Elementary(Func),
    Abs,
    Sign,
    Atan2,
    Min,
    Max,
    Dot,
    Cross,
    Norm,
}

impl Builtin {
    const OTHERS: [(Builtin, &'static str, usize); 8] = [
        (Builtin::Abs, "abs", 1),
        (Builtin::Sign, "sign", 1),
        (Builtin::Atan2, "atan2", 2),
        (Builtin::Min, "min", 2),
        (Builtin::Max, "max", 2),
        (Builtin::Dot, "dot", 2),
        (Builtin::Cross, "cross", 2),
        (Builtin::Norm, "norm", 1),
    ];

    pub fn from_name(name: &str) -> Option<Builtin> {
        Func::from_name(name).map(Builtin::Elementary).or_else(|| {
            Self::OTHERS
                .iter()
                .find(|(_, n, _)| *n == name)
                .map(|&(b, _, _)| b)
        })
    }

    pub fn name(self) -> &'static str {
        match self {
            Builtin::Elementary(f) => f.name(),
            other => Self::OTHERS
                .iter()
                .find(|(b, _, _)| *b == other)
                .map_or("?", |&(_, n, _)| n),
        }
    }

    /// The number of arguments.
    pub fn arity(self) -> usize {
        match self {
            Builtin::Elementary(_) => 1,
            other => Self::OTHERS
                .iter()
                .find(|(b, _, _)| *b == other)
                .map_or(1, |&(_, _, a)| a),
        }
    }

    /// Every function name, for suggestions.
    pub fn names() -> Vec<&'static str> {
        let mut names: Vec<&str> = Func::ALL.iter().map(|f| f.name()).collect();
        names.extend(Self::OTHERS.iter().map(|&(_, n, _)| n));
        names
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum BinOp {
    Add,
    Sub,
    Mul,
    Div,
    Pow,
}

/// The elementary functions of the language (SPEC §2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Func {
    Sin,
    Cos,
    Tan,
    Asin,
    Acos,
    Atan,
    Sinh,
    Cosh,
    Tanh,
    Exp,
    Ln,
    Sqrt,
}

impl Func {
    pub const ALL: [Func; 12] = [
        Func::Sin,
        Func::Cos,
        Func::Tan,
        Func::Asin,
        Func::Acos,
        Func::Atan,
        Func::Sinh,
        Func::Cosh,
        Func::Tanh,
        Func::Exp,
        Func::Ln,
        Func::Sqrt,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Func::Sin => "sin",
            Func::Cos => "cos",
            Func::Tan => "tan",
            Func::Asin => "asin",
            Func::Acos => "acos",
            Func::Atan => "atan",
            Func::Sinh => "sinh",
            Func::Cosh => "cosh",
            Func::Tanh => "tanh",
            Func::Exp => "exp",
            Func::Ln => "ln",
            Func::Sqrt => "sqrt",
        }
    }

    /// The function's value at a number. Its name is also the name of the
    /// `f64` method that computes it, which the emitter relies on.
    pub fn apply(self, x: f64) -> f64 {
        match self {
            Func::Sin => x.sin(),
            Func::Cos => x.cos(),
            Func::Tan => x.tan(),
            Func::Asin => x.asin(),
            Func::Acos => x.acos(),
            Func::Atan => x.atan(),
            Func::Sinh => x.sinh(),
            Func::Cosh => x.cosh(),
            Func::Tanh => x.tanh(),
            Func::Exp => x.exp(),
            Func::Ln => x.ln(),
            Func::Sqrt => x.sqrt(),
        }
    }

    pub fn from_name(name: &str) -> Option<Func> {
        Func::ALL.into_iter().find(|f| f.name() == name)
    }
}

/// A whole `.lag` file: its statements in source order.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Model {
    pub items: Vec<Item>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Item {
    pub kind: ItemKind,
    /// The whole statement, keyword to `;` (or `}`).
    pub span: Span,
}

#[derive(Debug, Clone, PartialEq)]
pub enum ItemKind {
    /// `param NAME = expr;`
    Param { name: Ident, value: Expr },
    /// `input NAME = DEFAULT;` — a signal set from outside between steps
    /// (SPEC §2.3); `check` requires the default to be a number.
    Input { name: Ident, default: Expr },
    /// `coord q1, q2;`
    Coords(Vec<Ident>),
    /// `mass NAME = expr;`
    Mass { name: Ident, law: Expr },
    /// `lagrangian = expr;`
    Lagrangian(Expr),
    /// `constraint lhs = rhs [for y' or x' …];` — without candidates
    /// `check` requires `lhs` to be `q'`, `q''`, …
    Constraint {
        lhs: Expr,
        rhs: Expr,
        candidates: Vec<Expr>,
    },
    /// `point NAME { field; … }`
    Point {
        name: Ident,
        fields: Vec<PointField>,
    },
    /// `force q = expr;` — a generalized force on coordinate `q`.
    Force { coord: Ident, value: Expr },
    /// `initial q1 = 0, q1' = 1;` — each target is a `Var` with primes.
    Initial(Vec<InitialValue>),
    /// `time start .. end;`
    Time { start: Expr, end: Expr },
    /// `exact q = expr;` — `target` is a `Var` (with primes for a derivative).
    Exact { target: Expr, value: Expr },
    /// `integrator stiff;` — the integrator runs use unless told otherwise;
    /// `check` requires `auto`, `explicit` or `stiff`.
    Integrator(Ident),
    /// `let NAME = expr;` — a named scalar or vector (SPEC §2.2).
    Let { name: Ident, value: Expr },
    /// `output NAME = expr;` — an extra CSV column (or columns).
    Output { name: Ident, value: Expr },
    /// `stop when cond;`
    Stop(Expr),
    /// `when cond then y' = expr, x = expr;` — an impact (SPEC §2.3):
    /// where `cond` becomes true the targets are reset.
    When {
        cond: Expr,
        /// The condition as written (whitespace collapsed), for messages.
        text: String,
        resets: Vec<Reset>,
    },
}

/// `y' = -e * y'` in a `when`: the target is a `Var` (validated by `check`).
#[derive(Debug, Clone, PartialEq)]
pub struct Reset {
    pub target: Expr,
    pub value: Expr,
    pub span: Span,
}

#[derive(Debug, Clone, PartialEq)]
pub struct InitialValue {
    /// `q1` or `q1'`: a `Var` expression (validated by `check`).
    pub target: Expr,
    pub value: Expr,
    pub span: Span,
}

#[derive(Debug, Clone, PartialEq)]
pub struct PointField {
    pub kind: PointFieldKind,
    pub span: Span,
}

#[derive(Debug, Clone, PartialEq)]
pub enum PointFieldKind {
    /// `mass = expr;`
    Mass(Expr),
    /// `position = (x, y[, z]);` — any vector expression.
    Position(Expr),
    /// `absolute velocity = (…);` — the velocity V of the separated/added particles.
    AbsoluteVelocity(Expr),
    /// `relative velocity = (…);` — u = V − dr/dt.
    RelativeVelocity(Expr),
}
