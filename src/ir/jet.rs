//! The total time derivative on the jet space (SPEC §1.1):
//! `D = ∂/∂t + Σ_j Σ_r q_j^(r+1) ∂/∂q_j^(r)`, with params, aux symbols and
//! mass laws constant (mass laws frozen inside the Lagrangian).

use super::expr::{Arena, Derivation, ExprId};

impl Arena {
    /// `D e`, memoised per node for the life of the arena. Computed as a
    /// derivation in one walk (leaves: `D t = 1`, `D q^(r) = q^(r+1)`), which
    /// equals the sum over free jet symbols without building it.
    pub fn total_derivative(&mut self, e: ExprId) -> ExprId {
        self.derive(e, Derivation::Total)
    }

    /// `D^n e`.
    pub fn total_derivative_n(&mut self, e: ExprId, n: u32) -> ExprId {
        (0..n).fold(e, |acc, _| self.total_derivative(acc))
    }
}
