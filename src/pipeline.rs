//! The stages chained: checked model → derivation → field system → kernel
//! → crate.

use crate::check::model::Model;
use crate::diagnostic::Diagnostic;
use crate::emit::{emit_crate, EmitOptions, GeneratedCrate};
use crate::field::{field_system, local_field_note};

/// The generated crate of `model`, with the notes the build should show
/// (e.g. that the local field method is used).
pub fn generate_crate(
    model: &Model,
    options: &EmitOptions,
) -> Result<(GeneratedCrate, Vec<Diagnostic>), Vec<Diagnostic>> {
    let (mut derivation, _) = crate::mechanics::derive_checked(model)?;
    let reduced = derivation.reduced.clone();
    let field = field_system(&mut derivation.arena, &reduced);
    let notes: Vec<Diagnostic> = local_field_note(&field, model.lagrangian.span)
        .into_iter()
        .collect();
    let mut kernel = crate::kernel::build(model, &derivation, &field)?;
    for mode in 1..model.mode_count() {
        kernel.modes.push(mode_kernel(&model.in_mode(mode))?);
    }
    let generated = emit_crate(&kernel, options)?;
    Ok((generated, notes))
}

/// The kernel of one more mode (other candidates of the implicit
/// constraints): derived and cross-checked like the first.
fn mode_kernel(model: &Model) -> Result<crate::kernel::Kernel, Vec<Diagnostic>> {
    let mut derivation = crate::mechanics::derive_mode_checked(model)?;
    let reduced = derivation.reduced.clone();
    let field = field_system(&mut derivation.arena, &reduced);
    crate::kernel::build_mode(model, &derivation, &field)
}
