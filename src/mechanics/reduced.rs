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
    /// Mass laws still present in `highest` after the masses that factor out
    /// were divided out: `(i, law)` with `law` an expression of `t` and params
    /// standing for `Symbol::Mass(i)`.
    pub mass_laws: Vec<(u32, ExprId)>,
    /// Initial values of every state component, in state order.
    pub initial: Vec<InitialValue>,
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
    /// params, masses and EARLIER state components (so it can be evaluated
    /// in state order).
    Constraint(ExprId),
    /// An independent derivative of order 2..k−1 (k ≥ 3): solved from (4)
    /// and its derivatives at `t0`; see `ReducedSystem::consistency`.
    Solved,
}
