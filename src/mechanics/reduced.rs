//! The reduced first-order system (7), the mechanics stage's output and the
//! field method's and code emitter's input (CONTRACT: extend additively).

use crate::ir::{ExprId, Symbol};

/// `x' = X(t, x)` with the state (6) `x = (q, q', …, q^(u−1))`.
#[derive(Debug, Clone)]
pub struct ReducedSystem {
    /// `u = max(2, k)`: the order of the highest derivatives.
    pub order: u32,
    /// The state (6): `Symbol::Jet { coord, order }` for order `0..u`,
    /// coordinates in declaration order within each order.
    pub state: Vec<Symbol>,
    /// How the highest derivatives `q_j^(u)` are obtained.
    pub highest: Highest,
    /// The mass matrix `∂(4)/∂q_i^(u)` of the independent highest
    /// derivatives (rows of (4), columns of `Highest`'s unknowns), kept
    /// for naming a singular one as the cause of a run-time failure.
    /// (Added by the kernel work.)
    pub mass_matrix: Vec<Vec<ExprId>>,
    /// Mass laws still present in `highest` after the masses that factor out
    /// were divided out: `(i, law)` with `law` an expression of `t` and params
    /// standing for `Symbol::Mass(i)` (a law of the state is never here: (7)
    /// holds it as its expression, `Derivation::state_laws`).
    pub mass_laws: Vec<(u32, ExprId)>,
    /// Initial values of every state component, in state order.
    pub initial: Vec<InitialValue>,
    /// The state components the constraints fix — `(state index, value)`,
    /// the dependent derivatives of order ≥ k the state holds (the
    /// dependent velocities when k = 1) — and the values they require, in
    /// `t`, params, masses and the free components (the values of the
    /// `Constraint` initial values, for every mode).
    pub fixed: Vec<(usize, ExprId)>,
    /// For k ≥ 3: how the independent `q_i^(2..k−1)` at `t0` follow from
    /// (4) and its derivatives, one stage per order (2, 3, …, k−1), solved
    /// in order (stage r may use the values of stages before it). Empty
    /// for k ≤ 2. (Added by the mechanics.)
    pub consistency: Vec<Consistency>,
    /// The holonomic constraints at position level, `f_ν(t, q) = 0`, with
    /// this mode's dependents as the unknowns: the initial positions are
    /// completed by Newton from the given ones, and the run brings the
    /// positions back onto them. `None` without holonomic constraints.
    pub closure: Option<Closure>,
}

/// `f(t, q) = 0` for `z = unknowns` (`Symbol::Jet { coord: d, order: 0 }`,
/// the dependent coordinates of the holonomic constraints in this mode):
/// Newton with `jacobian = ∂f_ν/∂z_c` (row-major) moves only them.
#[derive(Debug, Clone)]
pub struct Closure {
    pub unknowns: Vec<Symbol>,
    /// `f_ν = lhs − rhs`, mass laws substituted (an expression of `t`,
    /// params and coordinates).
    pub residual: Vec<ExprId>,
    pub jacobian: Vec<Vec<ExprId>>,
    /// The constraints as written (`f = 0`, `; `-separated), for messages.
    pub text: String,
    /// `∂f_ν/∂q_j` over every coordinate `j` (row-major, `n` columns):
    /// the normals along which the run projects the state onto the
    /// constraints (the smallest correction, Gauss–Newton), in positions
    /// and, since `D^r f` is linear in `q^(r)` with the same matrix, in
    /// every derivative.
    pub normals: Vec<Vec<ExprId>>,
    /// `D^r f_ν` for r = 1..u−1: the constraints on the state's
    /// derivatives (expressions of `t`, params and the state).
    pub levels: Vec<Vec<ExprId>>,
}

/// `residual(t, x, z) = 0` for `z = unknowns = (q_i^(r))_i`, one order `r`.
/// The residual holds `t`, params, masses, the `Given` and `Constraint`
/// state components and the unknowns of earlier stages.
#[derive(Debug, Clone)]
pub struct Consistency {
    pub unknowns: Vec<Symbol>,
    pub residual: Vec<ExprId>,
    /// `∂residual_r/∂z_c`, row-major.
    pub jacobian: Vec<Vec<ExprId>>,
    /// `true`: affine in `z` (one linear solve, or `explicit`).
    pub linear: bool,
    /// The symbolic solution, one expression per unknown, when found.
    pub explicit: Option<Vec<ExprId>>,
}

/// The highest derivatives `q^(u)`.
#[derive(Debug, Clone)]
pub enum Highest {
    /// `q_j^(u) = expr_j` for every coordinate `j` (declaration order);
    /// expressions of `t`, params, masses and the state only.
    Explicit(Vec<ExprId>),
    /// Solve `residual(t, x, z) = 0` for the independent highest derivatives
    /// `z = unknowns` (`Symbol::Jet { coord: i, order: u }`), then the
    /// dependent ones follow from `dependent` (expressions that may hold `z`).
    Implicit {
        unknowns: Vec<Symbol>,
        residual: Vec<ExprId>,
        /// `∂residual_r/∂z_c`, row-major.
        jacobian: Vec<Vec<ExprId>>,
        /// `true`: the residual is affine in `z` (`A z = b`, one linear
        /// solve); `false`: Newton with `jacobian`.
        linear: bool,
        /// `(coord, expr)` for every dependent coordinate.
        dependent: Vec<(u32, ExprId)>,
    },
}

/// How one state component's initial value is found at `t0`.
#[derive(Debug, Clone)]
pub enum InitialValue {
    /// Given by the user: an expression of params.
    Given(ExprId),
    /// Fixed by a constraint (or its derivatives): an expression of `t`,
    /// params, masses and state components that are `Given` (positions
    /// after [`ReducedSystem::closure`] corrects the dependent ones; never of
    /// other `Constraint` or `Solved` ones — a dependent velocity may depend
    /// on an independent velocity declared after it, so "earlier in state
    /// order" would not hold).
    Constraint(ExprId),
    /// An independent derivative of order 2..k−1 (k ≥ 3): solved from (4)
    /// and its derivatives at `t0`; see `ReducedSystem::consistency`.
    Solved,
}
