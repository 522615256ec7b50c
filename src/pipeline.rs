//! The stages chained: checked model → derivation → field system → crate.

use crate::check::model::Model;
use crate::diagnostic::Diagnostic;
use crate::emit::{emit_crate, EmitOptions, GeneratedCrate};
use crate::field::{field_system, local_field_note};

/// The generated crate of `model`, with the notes the build should show
/// (e.g. that the local field method is used).
pub fn generate_crate(
    model: &Model,
    model_name: &str,
) -> Result<(GeneratedCrate, Vec<Diagnostic>), Vec<Diagnostic>> {
    let mut derivation = crate::mechanics::derive(model)?;
    let reduced = derivation.reduced.clone();
    let field = field_system(&mut derivation.arena, &reduced);
    let notes: Vec<Diagnostic> = local_field_note(&field, model.lagrangian.span)
        .into_iter()
        .collect();
    let options = EmitOptions {
        model_name: model_name.to_string(),
    };
    let generated = emit_crate(model, &derivation, &field, &options)?;
    Ok((generated, notes))
}
