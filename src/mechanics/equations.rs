//! Equations (4), one per independent coordinate `i`:
//!
//! ```text
//! (k+1) ∂L*^(k+1)/∂q_i^(k+1) − (k+2) ∂L*^(k)/∂q_i^(k)
//!     = (R_i + R_d ∂φ_d/∂q_i^(k))* + (Q_i + Q_d ∂φ_d/∂q_i^(k))*
//! ```
//!
//! with the order-matched star of `star.rs`: substitute, differentiate, and
//! only then eliminate the remaining dependent derivatives.

use super::star::{jet, project, star_k, star_k1, Elimination};
use super::symbols::Symbolic;
use crate::ir::{Arena, ExprId, Symbol};

/// Equation (4) for independent coordinate `coord`: `lhs = rhs`, both free
/// of dependent derivatives of order ≥ k.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Equation4 {
    pub coord: u32,
    pub lhs: ExprId,
    pub rhs: ExprId,
}

/// `L^(k) = D^k L` and `L^(k+1)`, masses frozen (the arena's `D` keeps mass
/// symbols constant).
pub fn lagrangian_derivatives(arena: &mut Arena, lagrangian: ExprId, k: u32) -> (ExprId, ExprId) {
    let lk = arena.total_derivative_n(lagrangian, k);
    let lk1 = arena.total_derivative(lk);
    (lk, lk1)
}

/// Equations (4) for every independent coordinate; `forces[j]` is
/// `R_j + Q_j` for every coordinate `j`.
pub fn equations(
    arena: &mut Arena,
    model: &Symbolic,
    elimination: &mut Elimination,
    forces: &[ExprId],
) -> Vec<Equation4> {
    let k = model.k;
    let (lk, lk1) = lagrangian_derivatives(arena, model.lagrangian, k);
    let lk_star = star_k(arena, lk, k, &model.constraints);
    let lk1_star = star_k1(arena, lk1, k, &model.constraints);
    let upper = arena.constant(f64::from(k + 1));
    let lower = arena.constant(-f64::from(k + 2));
    // Each gradient in one pass over its DAG (`Arena::jacobian`).
    let of_order =
        |order: u32| -> Vec<Symbol> { model.independent.iter().map(|&i| jet(i, order)).collect() };
    let highs = arena.jacobian(&[lk1_star], &of_order(k + 1)).remove(0);
    let lows = arena.jacobian(&[lk_star], &of_order(k)).remove(0);
    model
        .independent
        .iter()
        .zip(highs.into_iter().zip(lows))
        .map(|(&i, (high, low))| {
            let high = arena.mul(&[upper, high]);
            let low = arena.mul(&[lower, low]);
            let lhs = arena.add(&[high, low]);
            let lhs = elimination.eliminate(arena, lhs);
            let rhs = project(arena, forces, i, k, &model.constraints);
            let rhs = elimination.eliminate(arena, rhs);
            Equation4 { coord: i, lhs, rhs }
        })
        .collect()
}
