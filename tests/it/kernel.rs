//! The kernel IR as text (stage 6): what the generated crate evaluates,
//! with the true time partials (mass laws move with `t`). One model with
//! a mass law and a reactive force, one with a constraint.

fn kernel_text(path: &str) -> String {
    let name = path;
    let source = std::fs::read_to_string(crate::root().join(path)).unwrap();
    let model = lagc::frontend(&source).unwrap_or_else(|d| panic!("{name}: {d:?}"));
    let mut derivation = lagc::mechanics::derive(&model).unwrap();
    let reduced = derivation.reduced.clone();
    let field = lagc::field::field_system(&mut derivation.arena, &reduced);
    let kernel = lagc::kernel::build(&model, &derivation, &field).unwrap();
    kernel.to_string()
}

/// `X = −sin(x)/M` keeps the mass law's value `M`, so `∂X/∂t` must hold
/// `∂X/∂M · M ρ` with `ρ = Ṁ/M` (issue 10's bug: it held nothing).
#[test]
fn kernel_time_partial_carries_the_mass_rate() {
    insta::assert_snapshot!(kernel_text("tests/data/mass_law_forms/pendulum_mass.lag"));
}

#[test]
fn kernel_of_the_vertical_rocket() {
    insta::assert_snapshot!(kernel_text("examples/vertical_rocket.lag"));
}

#[test]
fn kernel_of_the_knife_edge() {
    insta::assert_snapshot!(kernel_text("examples/knife_edge.lag"));
}
