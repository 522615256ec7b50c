//! The reactive forces of the variable-mass points (SPEC §1.3):
//! `R_j = Σ_P Ṁ_P (V_P − D r_P) · ∂r_P/∂q_j`, or `Σ_P Ṁ_P u_P · ∂r_P/∂q_j`
//! with the relative velocity `u_P`.
//!
//! `Ṁ_P` is the true time derivative of the point's mass `m_P(t, params,
//! masses, q)` along the motion, written through the mass symbols:
//! `∂m/∂t + Σ_j ∂m/∂q_j q_j' + Σ_i ∂m/∂M_i · M_i ρ_i` with
//! `ρ_i = (D law_i) / law_i` simplified. For `M0·e^{γt}`, `ρ = γ`, so
//! `Ṁ = γ M` and no overflowing law appears in the equations; for a law of
//! the state (`rho * x`, SPEC §2.3) `D` is the total derivative along the
//! motion, `ρ = x'/x`, and the rows stay homogeneous in the masses, so the
//! mass still divides out (`x'' = g − x'^2/x` for Cayley's chain).

use super::symbols::lower_checked;
use crate::check::model::{EjectaVelocity, Model};
use crate::diagnostic::Diagnostic;
use crate::ir::{Arena, ExprId, Func, Node, Symbol};
use std::collections::HashMap;

/// `R_j` for every coordinate `j` (declaration order).
///
/// With `state_laws` (`M_i → law_i` for the laws of the state) each point's
/// mass is first written through those laws, so its `Ṁ` is the total
/// derivative of its expression of `q` — the cross-check's independent
/// route (`multiplier_route.rs`); the derivation passes none and writes
/// `Ṁ` through the mass symbols.
pub fn reactive_forces(
    arena: &mut Arena,
    model: &Model,
    laws: &[ExprId],
    state_laws: &HashMap<Symbol, ExprId>,
) -> Result<Vec<ExprId>, Vec<Diagnostic>> {
    let n = model.coords.len();
    let mut forces = vec![Vec::new(); n];
    let mut errors = Vec::new();
    let rates: Vec<ExprId> = laws.iter().map(|&law| relative_rate(arena, law)).collect();
    for point in &model.points {
        let lowered = (|| -> Result<_, Diagnostic> {
            let mass = lower_checked(arena, &point.mass, model)?;
            let position = point
                .position
                .iter()
                .map(|x| lower_checked(arena, x, model))
                .collect::<Result<Vec<_>, _>>()?;
            let (velocity, absolute) = match &point.velocity {
                EjectaVelocity::Absolute(v) => (v, true),
                EjectaVelocity::Relative(v) => (v, false),
            };
            let velocity = velocity
                .iter()
                .map(|x| lower_checked(arena, x, model))
                .collect::<Result<Vec<_>, _>>()?;
            Ok((mass, position, velocity, absolute))
        })();
        let (mass, position, velocity, absolute) = match lowered {
            Ok(parts) => parts,
            Err(d) => {
                errors.push(d);
                continue;
            }
        };
        let mass = if state_laws.is_empty() {
            mass
        } else {
            arena.subst(mass, state_laws)
        };
        let mass_rate = mass_rate(arena, mass, &rates);
        if arena.is_zero(mass_rate) {
            continue;
        }
        // u = V − D r (absolute) or the given relative velocity.
        let relative: Vec<ExprId> = position
            .iter()
            .zip(&velocity)
            .map(|(&r, &v)| {
                if absolute {
                    let dr = arena.total_derivative(r);
                    arena.sub(v, dr)
                } else {
                    v
                }
            })
            .collect();
        for (j, force) in forces.iter_mut().enumerate() {
            let q = Symbol::Jet {
                coord: j as u32,
                order: 0,
            };
            let mut dot = Vec::new();
            for (&r, &u) in position.iter().zip(&relative) {
                let slope = arena.diff(r, q);
                dot.push(arena.mul(&[u, slope]));
            }
            let dot = arena.add(&dot);
            force.push(arena.mul(&[mass_rate, dot]));
        }
    }
    if !errors.is_empty() {
        return Err(errors);
    }
    Ok(forces.iter().map(|terms| arena.add(terms)).collect())
}

/// `ρ = (D law) / law`, the relative rate of change of a mass law along
/// the motion (for a law of the state, factor by factor: [`log_rate`]).
fn relative_rate(arena: &mut Arena, law: ExprId) -> ExprId {
    if super::symbols::is_state_law(arena, law) {
        return log_rate(arena, law);
    }
    let rate = rate_along_motion(arena, law);
    arena.div(rate, law)
}

/// `D e / e` as the logarithmic derivative of a product, `Σ_k n_k D f_k /
/// f_k` for `e = Π f_k^{n_k}` (`n_k` constant) and `D u` for `e^u`: the
/// rate of `c·x^3` is `3 x'/x` exactly, with no constant folded into `D e`
/// and divided out again (`4/3·pi·r^3` gave `3.0000000000000004 r'/r`).
fn log_rate(arena: &mut Arena, e: ExprId) -> ExprId {
    if !arena.varies_in_time(e) {
        return arena.zero();
    }
    match arena.node(e).clone() {
        Node::Mul(factors) => {
            let terms: Vec<ExprId> = factors.iter().map(|&f| log_rate(arena, f)).collect();
            arena.add(&terms)
        }
        Node::Pow(base, n) if !arena.varies_in_time(n) => {
            let rate = log_rate(arena, base);
            arena.mul(&[n, rate])
        }
        Node::Func(Func::Exp, u) => rate_along_motion(arena, u),
        _ => {
            let rate = rate_along_motion(arena, e);
            arena.div(rate, e)
        }
    }
}

/// `D e` with the masses frozen: `∂e/∂t + Σ_j ∂e/∂q_j q_j'` (for an
/// expression of `t` alone, `∂e/∂t`, as before laws of the state).
pub fn rate_along_motion(arena: &mut Arena, e: ExprId) -> ExprId {
    let of_state = arena
        .free_symbols(e)
        .iter()
        .any(|s| matches!(s, Symbol::Jet { .. }));
    if of_state {
        arena.total_derivative(e)
    } else {
        arena.diff(e, Symbol::Time)
    }
}

/// `Ṁ = ∂m/∂t + Σ_j ∂m/∂q_j q_j' + Σ_i ∂m/∂M_i · M_i ρ_i` for a point mass
/// `m(t, params, masses, q)`.
fn mass_rate(arena: &mut Arena, mass: ExprId, rates: &[ExprId]) -> ExprId {
    let mut terms = vec![rate_along_motion(arena, mass)];
    for (i, &rho) in rates.iter().enumerate() {
        let symbol = Symbol::Mass(i as u32);
        if !arena.depends_on(mass, symbol) {
            continue;
        }
        let slope = arena.diff(mass, symbol);
        let m = arena.symbol(symbol);
        terms.push(arena.mul(&[slope, m, rho]));
    }
    arena.add(&terms)
}
