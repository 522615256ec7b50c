//! The declared non-potential generalized forces `Q_j` (zero when absent).

use super::symbols::lower_checked;
use crate::check::model::Model;
use crate::diagnostic::Diagnostic;
use crate::ir::{Arena, ExprId};

/// `Q_j` for every coordinate `j` (declaration order).
pub fn generalized_forces(
    arena: &mut Arena,
    model: &Model,
) -> Result<Vec<ExprId>, Vec<Diagnostic>> {
    let mut forces = vec![arena.zero(); model.coords.len()];
    let mut errors = Vec::new();
    for force in &model.forces {
        match lower_checked(arena, &force.value, model) {
            Ok(q) => {
                if let Some(slot) = forces.get_mut(force.coord) {
                    *slot = arena.add(&[*slot, q]);
                }
            }
            Err(d) => errors.push(d),
        }
    }
    if errors.is_empty() {
        Ok(forces)
    } else {
        Err(errors)
    }
}
