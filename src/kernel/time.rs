//! The one place that knows every explicit time dependence of the reduced
//! system: `t` itself, the mass laws still in it and the inputs (each a
//! line in `t` on a segment).
//!
//! Inside `D` of the Lagrangian a mass law is frozen (SPEC §1.1); after the
//! reduction, `X(t, x)` is an ordinary function of `t` and its time partial
//! must see the masses move: `∂e/∂t + Σ_i ∂e/∂M_i · Ṁ_i`, with
//! `Ṁ_i = M_i ρ_i` and `ρ_i = law_i'/law_i` simplified (so an overflowing
//! law such as `M0·e^{1000t}` is never evaluated: `ρ = 1000`). Every
//! consumer — `∂X/∂t` for RODAS4, the coefficient system's `∂F/∂t`,
//! Newton's `∂G/∂t` — goes through [`TimeDependence::partial`].

use crate::ir::{Arena, ExprId, Symbol};
use crate::mechanics::tidy::simplify;

/// The mass laws the reduced system still holds, with their relative rates.
#[derive(Debug, Clone, Default)]
pub struct TimeDependence {
    /// `(i, ρ_i)` for every `Symbol::Mass(i)` left in the system.
    pub rates: Vec<(u32, ExprId)>,
}

impl TimeDependence {
    /// From the reduced system's `(i, law_i)`.
    pub fn new(arena: &mut Arena, laws: &[(u32, ExprId)]) -> TimeDependence {
        let rates = laws
            .iter()
            .map(|&(i, law)| {
                let rate = arena.diff(law, Symbol::Time);
                let rho = arena.div(rate, law);
                (i, simplify(arena, rho))
            })
            .collect();
        TimeDependence { rates }
    }

    /// The true partial derivative of `e` in `t` (state held fixed).
    pub fn partial(&self, arena: &mut Arena, e: ExprId) -> ExprId {
        let mut terms = vec![arena.diff(e, Symbol::Time)];
        for &(i, rho) in &self.rates {
            let mass = Symbol::Mass(i);
            if !arena.depends_on(e, mass) {
                continue;
            }
            let slope = arena.diff(e, mass);
            let m = arena.symbol(mass);
            terms.push(arena.mul(&[slope, m, rho]));
        }
        // Inputs move along their segment's line: `∂e/∂u_i · u_i'`.
        for i in 0..arena.names().inputs.len() as u32 {
            let input = Symbol::Input(i);
            if !arena.depends_on(e, input) {
                continue;
            }
            let slope = arena.diff(e, input);
            let rate = arena.symbol(Symbol::InputRate(i));
            terms.push(arena.mul(&[slope, rate]));
        }
        arena.add(&terms)
    }
}
