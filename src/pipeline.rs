//! The stages chained: checked model → derivation → field system → kernel
//! → crate.

use crate::check::model::Model;
use crate::diagnostic::Diagnostic;
use crate::emit::{emit_crate, EmitOptions, GeneratedCrate};
use crate::field::{field_system, local_field_note};
use crate::kernel::Kernel;
use crate::mechanics::Derivation;

/// The compiler as one call: `.lag` text → the generated crate and the
/// notes to show, or every diagnostic. `lagc build`, `run` and `report`
/// and the tests call this, so they compile exactly alike.
pub fn compile(
    source: &str,
    options: &EmitOptions,
) -> Result<(GeneratedCrate, Vec<Diagnostic>), Vec<Diagnostic>> {
    let model = crate::frontend::frontend(source)?;
    generate_crate(&model, options)
}

/// [`compile`] for an FMI 2.0 co-simulation FMU: its crate (depending on
/// the lagc-fmu library at `fmu_path`) and its modelDescription.xml.
pub fn compile_fmu(
    source: &str,
    options: &EmitOptions,
    fmu_path: &str,
) -> Result<(crate::emit::FmuCrate, Vec<Diagnostic>), Vec<Diagnostic>> {
    let model = crate::frontend::frontend(source)?;
    let (derivation, _) = crate::mechanics::derive_checked(&model)?;
    let (kernel, notes) = kernel_of(&model, derivation)?;
    Ok((crate::emit::emit_fmu(&kernel, options, fmu_path)?, notes))
}

/// The generated crate of `model`, with the notes the build should show
/// (e.g. that the local field method is used).
pub fn generate_crate(
    model: &Model,
    options: &EmitOptions,
) -> Result<(GeneratedCrate, Vec<Diagnostic>), Vec<Diagnostic>> {
    let (derivation, _) = crate::mechanics::derive_checked(model)?;
    let (kernel, notes) = kernel_of(model, derivation)?;
    let generated = emit_crate(&kernel, options)?;
    Ok((generated, notes))
}

/// The Python module's `impl lagc_python::Linear` for `source`'s model:
/// the linearization's symbolic half (`linearize::parts`), printed, or the
/// impl saying why the module has none. Only `lagc build --python` asks.
pub fn python_linear(source: &str) -> Result<String, Vec<Diagnostic>> {
    let model = crate::frontend::frontend(source)?;
    let (derivation, _) = crate::mechanics::derive_checked(&model)?;
    let parts = crate::linearize::parts(&model, &derivation);
    // A module without `linearize` is better than no module: a failure to
    // print it (lagc's own) becomes the reason `linearize` gives.
    crate::emit::linear::linear_code(&parts)
        .or_else(|d| crate::emit::linear::linear_code(&Err(format!("lagc: {}", d.message))))
        .map_err(|d| vec![d])
}

/// Every stage after the derivation that can reject a model, short of
/// printing: the field system, the kernel (initial values, outputs, stop)
/// and the other modes' kernels. `lagc check` runs it too, so that check
/// and build agree on every model.
pub fn kernel_of(
    model: &Model,
    mut derivation: Derivation,
) -> Result<(Kernel, Vec<Diagnostic>), Vec<Diagnostic>> {
    let reduced = derivation.reduced.clone();
    let field = field_system(&mut derivation.arena, &reduced);
    let mut notes: Vec<Diagnostic> = derivation.notes.clone();
    notes.extend(local_field_note(&field, model.lagrangian.span));
    let mut kernel = crate::kernel::build_owned(model, derivation, &field, true)?;
    for mode in 1..model.mode_count() {
        let other = mode_kernel(&model.in_mode(mode))?;
        // Every mode reads the first mode's branches; a switch only another
        // mode has would read none (never silently: refuse).
        if let Some(text) = crate::kernel::switches::unshared_switches(&kernel, &other).first() {
            return Err(vec![Diagnostic::error(
                crate::diagnostic::codes::UNSHARED_SWITCHES,
                format!("a reduced system of another candidate switches on `{text}`, which the first does not"),
            )
            .with_primary(model.lagrangian.span, "this model")
            .with_note("models whose implicit constraints have several candidates share the first candidate's switches (`if`, `abs`, …)")
            .with_help("name the candidates in another order, or write the switching expression where every candidate's system holds it")]);
        }
        kernel.modes.push(other);
    }
    Ok((kernel, notes))
}

/// The kernel of one more mode (other candidates of the implicit
/// constraints): derived and cross-checked like the first.
fn mode_kernel(model: &Model) -> Result<crate::kernel::Kernel, Vec<Diagnostic>> {
    let mut derivation = crate::mechanics::derive_mode_checked(model)?;
    let reduced = derivation.reduced.clone();
    let field = field_system(&mut derivation.arena, &reduced);
    crate::kernel::build_owned(model, derivation, &field, false)
}
