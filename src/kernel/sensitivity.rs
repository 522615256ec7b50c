//! `∂X/∂p`: the partials of the reduced system (7) in the params, for the
//! forward sensitivities (`lagc run --sensitivity`, issue 27). Taken here,
//! by the one differentiator (`Arena::diff`, as `∂X/∂x` and the
//! linearization's `∂f/∂p`), on the motion as the run evaluates it (its
//! selections latched), so that emission only prints.
//!
//! A param reaches the motion directly and through the mass laws the
//! reduced system still holds as symbols: `∂e/∂p + Σ_i ∂e/∂M_i · ∂law_i/∂p`.
//! The params computed from other params are chained at run time (an
//! override stops the recomputation, so the chain depends on the
//! invocation, not on the model).

use super::motion::Motion;
use crate::ir::{Arena, ExprId, Symbol};
use crate::mechanics::tidy::simplify;

/// The non-zero partials of the motion in the params.
#[derive(Debug, Clone, Default)]
pub struct ParamPartials {
    /// Explicit motion: `(state row, param, ∂X_row/∂p)`. Implicit motion:
    /// `(residual row, param, ∂G_row/∂p)`.
    pub cells: Vec<(usize, usize, ExprId)>,
    /// Implicit motion only: for each dependent highest derivative (in
    /// `Implicit::dependent` order), `(param, ∂D/∂p)` with `z` held.
    pub dependent: Vec<Vec<(usize, ExprId)>>,
}

/// The partials of the (latched) motion in `params` params; `None` where a
/// mass law switches (its partial would hold a selection the run does not
/// latch).
pub fn param_partials(
    arena: &mut Arena,
    motion: &Motion,
    state_len: usize,
    params: usize,
    masses: &[(String, ExprId)],
    remaining: &[u32],
) -> Option<ParamPartials> {
    if remaining.iter().any(|&i| {
        masses
            .get(i as usize)
            .is_none_or(|(_, law)| arena.has_select(*law))
    }) {
        return None;
    }
    // `∂law_i/∂p` for every mass law the motion still holds.
    let law_slopes: Vec<(Symbol, Vec<ExprId>)> = remaining
        .iter()
        .map(|&i| {
            let law = masses[i as usize].1;
            let slopes = (0..params)
                .map(|p| arena.diff(law, Symbol::Param(p as u32)))
                .collect();
            (Symbol::Mass(i), slopes)
        })
        .collect();
    let total = |arena: &mut Arena, e: ExprId, p: usize| -> ExprId {
        let mut terms = vec![arena.diff(e, Symbol::Param(p as u32))];
        for (mass, slopes) in &law_slopes {
            if arena.is_zero(slopes[p]) || !arena.depends_on(e, *mass) {
                continue;
            }
            let d = arena.diff(e, *mass);
            terms.push(arena.mul(&[d, slopes[p]]));
        }
        let sum = arena.add(&terms);
        simplify(arena, sum)
    };
    let mut partials = ParamPartials::default();
    match motion {
        Motion::Explicit(m) => {
            // The highest rows are the last block of the state.
            let first = state_len.saturating_sub(m.rhs.len());
            for (j, &h) in m.rhs.iter().enumerate() {
                for p in 0..params {
                    let d = total(arena, h, p);
                    if !arena.is_zero(d) {
                        partials.cells.push((first + j, p, d));
                    }
                }
            }
        }
        Motion::Implicit(m) => {
            for (r, &g) in m.residual.iter().enumerate() {
                for p in 0..params {
                    let d = total(arena, g, p);
                    if !arena.is_zero(d) {
                        partials.cells.push((r, p, d));
                    }
                }
            }
            for d in &m.dependent {
                let mut row = Vec::new();
                for p in 0..params {
                    let e = total(arena, d.value, p);
                    if !arena.is_zero(e) {
                        row.push((p, e));
                    }
                }
                partials.dependent.push(row);
            }
        }
    }
    Some(partials)
}
