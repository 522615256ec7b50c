//! The checked model: the front end's output and the mechanics' input.
//!
//! Invariants (established by `check::check`, relied on downstream):
//! - every name in every expression resolves through [`Model::resolve`], and
//!   each expression uses only the names its statement allows (a mass law
//!   only `t`, params and numbers; an initial value or time bound only params
//!   and numbers; …);
//! - coordinates have distinct names, at most one constraint each, and all
//!   constraints share one order `k = constraint_order`;
//! - no constraint right side holds a dependent coordinate's derivative of
//!   order ≥ k;
//! - every param has a finite default value.
//!
//! Expressions stay as AST expressions (with their spans, for diagnostics of
//! later stages); `ir::lower` turns them into symbolic expressions.

use crate::span::Span;
use crate::syntax::ast::Expr;
use std::collections::HashMap;

#[derive(Debug, Clone, PartialEq)]
pub struct Model {
    pub params: Vec<Param>,
    /// `input` statements in source order (SPEC §2.3).
    pub inputs: Vec<Input>,
    pub coords: Vec<Coord>,
    pub masses: Vec<MassLaw>,
    pub lagrangian: Expr,
    /// The common order `k` of the constraints; `None` for a holonomic model.
    pub constraint_order: Option<u32>,
    pub constraints: Vec<Constraint>,
    /// The implicit (and holonomic) constraints in groups solved together,
    /// in the order of their first constraints.
    pub groups: Vec<Group>,
    pub points: Vec<Point>,
    pub forces: Vec<Force>,
    pub initial: Vec<Initial>,
    pub time: TimeSpan,
    pub exact: Vec<Exact>,
    /// The model's `integrator` statement, when it has one: the default of
    /// every run (a command-line `--integrator` overrides it).
    pub integrator: Option<DeclaredIntegrator>,
    /// `let` statements in source order (each uses only earlier ones).
    pub lets: Vec<Let>,
    /// `output` statements in source order.
    pub outputs: Vec<Output>,
    /// `stop when cond;`: a condition of `t`, the state and params.
    pub stop: Option<Expr>,
    /// `when cond then y' = …;` statements in source order (SPEC §2.3).
    pub impacts: Vec<Impact>,
    /// Every declared name (params, coordinates, masses, points, lets,
    /// outputs).
    pub names: HashMap<String, Name>,
}

/// What a declared name refers to; indices into the [`Model`] vectors.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Name {
    Param(usize),
    Input(usize),
    Coord(usize),
    Mass(usize),
    Point(usize),
    Let(usize),
    Output(usize),
}

impl Model {
    pub fn resolve(&self, name: &str) -> Option<Name> {
        self.names.get(name).copied()
    }

    /// The constraint that makes coordinate `coord` dependent, if any.
    pub fn constraint_on(&self, coord: usize) -> Option<&Constraint> {
        self.constraints.iter().find(|c| c.coord == coord)
    }

    /// Indices of the independent coordinates, in declaration order.
    pub fn independent(&self) -> Vec<usize> {
        (0..self.coords.len())
            .filter(|&j| self.constraint_on(j).is_none())
            .collect()
    }

    /// Indices of the dependent coordinates, in constraint order.
    pub fn dependent(&self) -> Vec<usize> {
        self.constraints.iter().map(|c| c.coord).collect()
    }

    /// The number of modes: combinations of the groups' choices of
    /// dependents (1 when none has several).
    pub fn mode_count(&self) -> usize {
        self.groups.iter().map(|g| g.choices.len()).product()
    }

    /// The model of mode `mode`: each group of implicit constraints solved
    /// for the choice of its digit (mixed radix, the first group lowest, as
    /// the runtime counts modes).
    pub fn in_mode(&self, mode: usize) -> Model {
        let mut model = self.clone();
        let mut rest = mode;
        for g in &self.groups {
            let n = g.choices.len();
            for (&i, &j) in g.constraints.iter().zip(&g.choices[rest % n]) {
                model.constraints[i].coord = j;
            }
            rest /= n;
        }
        model
    }

    /// The group a constraint belongs to, if it is implicit.
    pub fn group_of(&self, constraint: usize) -> Option<&Group> {
        self.groups
            .iter()
            .find(|g| g.constraints.contains(&constraint))
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct Param {
    pub name: String,
    pub span: Span,
    pub value: Expr,
    /// The value with every earlier param at its default.
    pub default: f64,
    /// The param may change between steps (an FMU's `tunable` parameter):
    /// it is used, directly, through lets or through the params computed
    /// from it, only where an input may be used (forces, velocity
    /// constraints, points' velocities, outputs, `stop when`) and in
    /// initial values, which are read once. A param of the Lagrangian, a
    /// mass law, a position, a holonomic constraint, a `when` or the time
    /// span stays fixed: a jump there would be an impulse, an ejection of
    /// matter or a moved body, which a restart carrying the state over
    /// does not model (the reasons inputs are refused there, E0042).
    pub tunable: bool,
}

/// A signal set from outside between steps (`input u = 0;`): held by the
/// generated model and changed only where the integration restarts, so it
/// is a constant (or, interpolated linearly, a line in `t`) on every
/// segment the integrators see.
#[derive(Debug, Clone, PartialEq)]
pub struct Input {
    pub name: String,
    pub span: Span,
    /// Its value until it is set (a number).
    pub default: f64,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Coord {
    pub name: String,
    pub span: Span,
}

#[derive(Debug, Clone, PartialEq)]
pub struct MassLaw {
    pub name: String,
    pub span: Span,
    /// An expression of `t`, params, numbers and coordinates (no
    /// derivatives): frozen inside the Lagrangian, its `Ṁ` along the
    /// motion in the reactive forces (SPEC §1.1, §1.3, §2.3).
    pub law: Expr,
}

/// `q_dep^(order) = rhs`, or an implicit constraint `lhs = rhs for …`
/// solved for the candidate `coord`.
#[derive(Debug, Clone, PartialEq)]
pub struct Constraint {
    pub coord: usize,
    pub order: u32,
    pub rhs: Expr,
    pub span: Span,
    /// The statement as written, for run-time messages (`y' = sqrt(c^2 -
    /// x'^2)`, `sin(th) * x' = cos(th) * y' for y' or x'`): filled by the
    /// front end, which has the text ([`crate::frontend::frontend`]);
    /// empty for a model checked from an AST alone.
    pub text: String,
    /// `Some` for `constraint lhs = rhs for q' [or …];`.
    pub implicit: Option<Implicit>,
}

/// An implicit constraint `lhs = rhs` with its candidate dependent
/// coordinates (all of the constraint's order), as written.
#[derive(Debug, Clone, PartialEq)]
pub struct Implicit {
    pub lhs: Expr,
    pub candidates: Vec<usize>,
    /// `lhs = rhs` holds no derivative (SPEC §2.3): the constraint of
    /// order k is its k-th total derivative, and the candidates are
    /// coordinates (named `for y or x`, else the left side's coordinate,
    /// else all it holds, the last declared first).
    pub holonomic: bool,
    /// The constraint as written is not affine in its candidates
    /// (`x'^2 + y'^2 = c^2 for y' or x'`), or shares the model with one
    /// that is not: the constraint of order k is its total derivative
    /// `D (lhs − rhs) = 0` (linear in the order-k derivatives), and the
    /// run keeps `lhs = rhs` itself on the candidates of order k − 1
    /// (SPEC §2.3).
    pub raised: bool,
}

impl Constraint {
    pub fn is_holonomic(&self) -> bool {
        self.implicit.as_ref().is_some_and(|i| i.holonomic)
    }

    /// Solved through its derivative ([`Implicit::raised`]).
    pub fn is_raised(&self) -> bool {
        self.implicit.as_ref().is_some_and(|i| i.raised)
    }
}

/// Implicit constraints solved together (they share candidates, or hold
/// each other's): `m = constraints.len()` equations linear in the order-k
/// derivatives of `m` dependents, chosen among their candidates.
#[derive(Debug, Clone, PartialEq)]
pub struct Group {
    /// Indices into [`Model::constraints`], in source order.
    pub constraints: Vec<usize>,
    /// The choices of dependents, the runtime's digit order: for each, the
    /// dependent coordinate of each constraint of the group (distinct; a
    /// coordinate it holds). The first is the initial values'.
    pub choices: Vec<Vec<usize>>,
}

/// `let NAME = value;`: `size` 1 for a number, 2 or 3 for a vector.
#[derive(Debug, Clone, PartialEq)]
pub struct Let {
    pub name: String,
    pub span: Span,
    pub value: Expr,
    pub size: usize,
}

/// `output NAME = value;`: `size` 1 for a number, 2 or 3 for a vector
/// (columns `NAME.x`, `NAME.y`[, `NAME.z`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Output {
    pub name: String,
    pub span: Span,
    pub value: Expr,
    pub size: usize,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Point {
    pub name: String,
    pub span: Span,
    /// The point's mass: an expression of `t`, params, masses and
    /// coordinates (no derivatives).
    pub mass: Expr,
    pub position: Vec<Expr>,
    pub velocity: EjectaVelocity,
}

/// The velocity of the separated (or added) particles of a point.
#[derive(Debug, Clone, PartialEq)]
pub enum EjectaVelocity {
    /// The absolute velocity `V`.
    Absolute(Vec<Expr>),
    /// The relative velocity `u = V − dr/dt`.
    Relative(Vec<Expr>),
}

#[derive(Debug, Clone, PartialEq)]
pub struct Force {
    pub coord: usize,
    pub value: Expr,
    pub span: Span,
}

/// `when cond then y' = …, x = …;`: where `cond` becomes true, the
/// targets (free components of the state) are reset to their values, all
/// evaluated at the state before the impact.
#[derive(Debug, Clone, PartialEq)]
pub struct Impact {
    /// The condition as written, for messages (`y < 0`).
    pub text: String,
    /// A condition of `t`, the state and params.
    pub cond: Expr,
    pub resets: Vec<ImpactReset>,
    pub span: Span,
}

/// `coord^(order) = value` in a `when`; `value` an expression of `t`,
/// params, masses and the state.
#[derive(Debug, Clone, PartialEq)]
pub struct ImpactReset {
    pub coord: usize,
    pub order: u32,
    pub value: Expr,
    pub span: Span,
}

/// `coord^(order)(t0) = value`; `value` holds only params and numbers.
#[derive(Debug, Clone, PartialEq)]
pub struct Initial {
    pub coord: usize,
    pub order: u32,
    pub value: Expr,
    pub span: Span,
}

/// How a run chooses its one-step integrator (`integrator NAME;`): the
/// runtime's type, so that the declaration and `--integrator` are one.
pub use lagc_runtime::method::IntegratorChoice;

/// `integrator NAME;`, with the statement's span.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DeclaredIntegrator {
    pub choice: IntegratorChoice,
    pub span: Span,
}

#[derive(Debug, Clone, PartialEq)]
pub struct TimeSpan {
    pub start: Expr,
    pub end: Expr,
    pub span: Span,
}

/// `exact coord^(order) = value`: a known solution, an expression of `t` and params.
#[derive(Debug, Clone, PartialEq)]
pub struct Exact {
    pub coord: usize,
    pub order: u32,
    pub value: Expr,
    pub span: Span,
}
