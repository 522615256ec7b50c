//! The reactive forces of the variable-mass points (SPEC §1.3):
//! `R_j = Σ_P Ṁ_P (V_P − D r_P) · ∂r_P/∂q_j`, or `Σ_P Ṁ_P u_P · ∂r_P/∂q_j`
//! with the relative velocity `u_P`.
//!
//! `Ṁ_P` is the true time derivative of the point's mass `m_P(t, params,
//! masses)`, written through the mass symbols: `∂m/∂t + Σ_i ∂m/∂M_i · M_i ρ_i`
//! with `ρ_i = (d law_i/dt) / law_i` simplified. For `M0·e^{γt}`, `ρ = γ`, so
//! `Ṁ = γ M` and no overflowing law appears in the equations.

use super::symbols::lower_checked;
use crate::check::model::{EjectaVelocity, Model};
use crate::diagnostic::Diagnostic;
use crate::ir::{Arena, ExprId, Symbol};

/// `R_j` for every coordinate `j` (declaration order).
pub fn reactive_forces(
    arena: &mut Arena,
    model: &Model,
    laws: &[ExprId],
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

/// `ρ = (d law/dt) / law`, the relative rate of change of a mass law.
fn relative_rate(arena: &mut Arena, law: ExprId) -> ExprId {
    let rate = arena.diff(law, Symbol::Time);
    arena.div(rate, law)
}

/// `Ṁ = ∂m/∂t + Σ_i ∂m/∂M_i · M_i ρ_i` for a point mass `m(t, params, masses)`.
fn mass_rate(arena: &mut Arena, mass: ExprId, rates: &[ExprId]) -> ExprId {
    let mut terms = vec![arena.diff(mass, Symbol::Time)];
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
