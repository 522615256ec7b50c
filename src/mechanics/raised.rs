//! A group of raised constraints solved together (SPEC §2.3): the knife
//! edge and `x'^2 + y'^2 = v^2`, both naming `x'` and `y'`. Raised, each
//! member is solved through its derivative `D F_ν`, linear in the order-k
//! derivatives (Cramer, `coupled.rs`); the run keeps the written forms
//! `F(v) = 0` of every member — the linear ones too, all raised alike —
//! by Newton over the group's candidates `v` of order k − 1 (this mode's
//! dependents): the kept values are `v − J⁻¹F`, `J = ∂F/∂v`, by Cramer's
//! rule again. They equal `v` exactly on the constraints, and their
//! partials there are the implicit function's, as the lone constraint's
//! `v − f/f_v` (its group of one, kept by `mod.rs` unchanged).
//!
//! Why symbolic: the run keeps a constraint through the fixed values'
//! expressions and their gradients (`kernel::kept`, `run/keep.rs`); a
//! numeric Newton over the group would need a new kind of fixed value in
//! the runtime. `J` is the block whose determinant is already the group's
//! pivot for the choice of dependents (`kernel/candidates.rs`), so where
//! it becomes singular the run switches choice or stops, as for one
//! constraint.

use super::coupled;
use super::reduced::Closure;
use super::symbols::Symbolic;
use crate::check::model::{Group, Model};
use crate::diagnostic::Diagnostic;
use crate::ir::{Arena, ExprId, Symbol};
use std::collections::HashMap;

/// What a raised group adds to the derivation.
pub struct KeptGroup {
    /// `(state index, v − J⁻¹F)` for each candidate in the state.
    pub fixed: Vec<(usize, ExprId)>,
    /// The cross-check's identities, named.
    pub directions: Vec<(String, ExprId)>,
    /// `(F_ν, D F_ν)` of each member, for the derivation's text.
    pub shown: Vec<(ExprId, ExprId)>,
    /// `F = 0` over the candidates, for Newton on the initial values.
    pub newton: Closure,
}

/// The groups of more than one constraint that hold a raised one.
pub fn coupled_groups(model: &Model) -> Vec<&Group> {
    model
        .groups
        .iter()
        .filter(|g| g.constraints.len() > 1)
        .filter(|g| {
            g.constraints
                .iter()
                .any(|&i| model.constraints[i].is_raised())
        })
        .collect()
}

/// The fixed values, identities and Newton system of one raised group.
pub fn kept_group(
    arena: &mut Arena,
    model: &Model,
    symbolic: &Symbolic,
    group: &Group,
    laws: &HashMap<Symbol, ExprId>,
    state: &[Symbol],
) -> Result<KeptGroup, Diagnostic> {
    let members: Vec<&crate::check::model::Constraint> = group
        .constraints
        .iter()
        .map(|&i| &model.constraints[i])
        .collect();
    let mut residual = Vec::with_capacity(members.len());
    let mut texts = Vec::with_capacity(members.len());
    for c in &members {
        let f = coupled::written_residual(arena, model, c, laws)?;
        texts.push(if c.text.is_empty() {
            format!("{} = 0", arena.display(f))
        } else {
            c.text.clone()
        });
        residual.push(f);
    }
    let candidates: Vec<Symbol> = members
        .iter()
        .map(|c| Symbol::Jet {
            coord: c.coord as u32,
            order: c.order - 1,
        })
        .collect();
    let jacobian = coupled::block(arena, &residual, &candidates);
    let det = coupled::determinant(arena, &jacobian);
    // Newton's step `J⁻¹F`, component c by Cramer: `det(J, column c
    // replaced by F) / det J`.
    let mut fixed = Vec::new();
    for (c, &v) in candidates.iter().enumerate() {
        let replaced: Vec<Vec<ExprId>> = jacobian
            .iter()
            .zip(&residual)
            .map(|(row, &f)| {
                let mut row = row.clone();
                row[c] = f;
                row
            })
            .collect();
        let numerator = coupled::determinant(arena, &replaced);
        let step = arena.div(numerator, det);
        let v_expr = arena.symbol(v);
        let kept = arena.sub(v_expr, step);
        if let Some(i) = state.iter().position(|&s| s == v) {
            fixed.push((i, kept));
        }
    }
    // The cross-check's identities, row by row: `D F_ν` is linear in the
    // order-k derivatives with the coefficients `∂F_ν/∂q^(k−1)`, so the
    // solved `φ` satisfies `Σ_d J_νd ∂φ_d/∂q_i^(k) + ∂F_ν/∂q_i^(k−1) = 0`
    // for every independent `i` at every point of the jet space (the
    // lone constraint's Chetaev identity, `m = 1`): the reactions of the
    // derivatives are the written constraints'.
    let phis: Vec<Option<ExprId>> = members
        .iter()
        .map(|c| {
            symbolic
                .constraints
                .iter()
                .find(|&&(d, _)| d == c.coord as u32)
                .map(|&(_, phi)| phi)
        })
        .collect();
    let mut directions = Vec::new();
    if phis.iter().all(Option::is_some) {
        for &i in &symbolic.independent {
            let order = members[0].order;
            let q_k = Symbol::Jet { coord: i, order };
            let q_below = Symbol::Jet {
                coord: i,
                order: order - 1,
            };
            let d_phi: Vec<ExprId> = phis
                .iter()
                .flatten()
                .map(|&phi| arena.diff(phi, q_k))
                .collect();
            let name = arena.symbol_name(q_below);
            for (nu, (&f, row)) in residual.iter().zip(&jacobian).enumerate() {
                let mut terms: Vec<ExprId> = row
                    .iter()
                    .zip(&d_phi)
                    .map(|(&j, &d)| arena.mul(&[d, j]))
                    .collect();
                terms.push(arena.diff(f, q_below));
                let identity = arena.add(&terms);
                directions.push((
                    format!("{} (its reaction on `{name}`)", members[nu].text),
                    identity,
                ));
            }
        }
    }
    let shown = residual
        .iter()
        .map(|&f| (f, arena.total_derivative(f)))
        .collect();
    Ok(KeptGroup {
        fixed,
        directions,
        shown,
        newton: Closure {
            unknowns: candidates,
            residual,
            jacobian,
            text: texts.join("; "),
            normals: Vec::new(),
            levels: Vec::new(),
        },
    })
}
