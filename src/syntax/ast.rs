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
    Call {
        func: Func,
        func_span: Span,
        arg: Box<Expr>,
    },
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
    /// `coord q1, q2;`
    Coords(Vec<Ident>),
    /// `mass NAME = expr;`
    Mass { name: Ident, law: Expr },
    /// `lagrangian = expr;`
    Lagrangian(Expr),
    /// `constraint lhs = rhs;` — `check` requires `lhs` to be `q'`, `q''`, …
    Constraint { lhs: Expr, rhs: Expr },
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
    /// `position = (x, y[, z]);`
    Position(Vec<Expr>),
    /// `absolute velocity = (…);` — the velocity V of the separated/added particles.
    AbsoluteVelocity(Vec<Expr>),
    /// `relative velocity = (…);` — u = V − dr/dt.
    RelativeVelocity(Vec<Expr>),
}
