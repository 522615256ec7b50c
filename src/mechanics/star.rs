//! The order-matched star of equation (4) (SPEC §1.2) and the elimination of
//! the dependent derivatives through the constraints.
//!
//! With `q_d^(k) = φ_d`: `E_k = φ_d`, `E_{r+1} = (D E_r)` with `q_d^(k)`
//! replaced by `φ_d`. Each `E_r` is free of every dependent derivative of
//! order ≥ k, so replacing `q_d^(r) → E_r` for all r at once eliminates them.

use crate::ir::{Arena, ExprId, Symbol};
use std::collections::HashMap;

/// The constraints of order `k` and the eliminations derived from them.
#[derive(Debug, Clone)]
pub struct Elimination {
    k: u32,
    constraints: Vec<(u32, ExprId)>,
    /// `q_d^(r) → E_r` for every dependent `d` and `k ≤ r ≤ top`.
    map: HashMap<Symbol, ExprId>,
    /// The highest order in `map` (`k − 1` while empty).
    top: u32,
}

impl Elimination {
    pub fn new(k: u32, constraints: &[(u32, ExprId)]) -> Elimination {
        Elimination {
            k,
            constraints: constraints.to_vec(),
            map: HashMap::new(),
            top: k.saturating_sub(1),
        }
    }

    /// Extends the map up to order `order`.
    fn extend_to(&mut self, arena: &mut Arena, order: u32) {
        while self.top < order {
            let next = self.top + 1;
            for &(d, phi) in &self.constraints {
                let image = if next == self.k {
                    phi
                } else {
                    let previous = self.map[&jet(d, next - 1)];
                    let derivative = arena.total_derivative(previous);
                    let at_k: HashMap<Symbol, ExprId> = self
                        .constraints
                        .iter()
                        .map(|&(c, phi)| (jet(c, self.k), phi))
                        .collect();
                    arena.subst(derivative, &at_k)
                };
                self.map.insert(jet(d, next), image);
            }
            self.top = next;
        }
    }

    /// `e` with every dependent derivative of order ≥ k eliminated.
    pub fn eliminate(&mut self, arena: &mut Arena, e: ExprId) -> ExprId {
        let highest = self
            .constraints
            .iter()
            .filter_map(|&(d, _)| arena.max_jet_order(e, d))
            .max();
        match highest {
            Some(order) if order >= self.k => {
                self.extend_to(arena, order);
                arena.subst(e, &self.map)
            }
            _ => e,
        }
    }

    /// The eliminated image of `q_d^(order)` (`order ≥ k`).
    pub fn image(&mut self, arena: &mut Arena, d: u32, order: u32) -> ExprId {
        let q = arena.jet(d, order);
        self.eliminate(arena, q)
    }
}

/// `q_coord^(order)`.
pub fn jet(coord: u32, order: u32) -> Symbol {
    Symbol::Jet { coord, order }
}

/// The star of `L^(k)`: only `q_d^(k)` replaced by `φ_d`.
pub fn star_k(arena: &mut Arena, lk: ExprId, k: u32, constraints: &[(u32, ExprId)]) -> ExprId {
    let map: HashMap<Symbol, ExprId> = constraints
        .iter()
        .map(|&(d, phi)| (jet(d, k), phi))
        .collect();
    arena.subst(lk, &map)
}

/// The star of `L^(k+1)`: only `q_d^(k+1)` replaced by `Dφ_d`.
pub fn star_k1(arena: &mut Arena, lk1: ExprId, k: u32, constraints: &[(u32, ExprId)]) -> ExprId {
    let map: HashMap<Symbol, ExprId> = constraints
        .iter()
        .map(|&(d, phi)| (jet(d, k + 1), arena.total_derivative(phi)))
        .collect();
    arena.subst(lk1, &map)
}

/// `X_i + Σ_d X_d ∂φ_d/∂q_i^(k)`: a per-coordinate quantity (`x[j]` for
/// coordinate j) projected on independent coordinate `i` (not eliminated).
pub fn project(
    arena: &mut Arena,
    x: &[ExprId],
    i: u32,
    k: u32,
    constraints: &[(u32, ExprId)],
) -> ExprId {
    let mut terms = vec![x[i as usize]];
    for &(d, phi) in constraints {
        let slope = arena.diff(phi, jet(i, k));
        terms.push(arena.mul(&[x[d as usize], slope]));
    }
    arena.add(&terms)
}
