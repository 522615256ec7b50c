//! The field method's symbolic stage on the examples: the coefficient
//! system built from (9) against SPEC §1.5's formulas for affine systems,
//! and the classification.

use lagc::field::{field_system, FieldSystem};
use lagc::ir::{Arena, Symbol};
use lagc::mechanics::{derive, Derivation};

pub fn derived(name: &str) -> (lagc::check::model::Model, Derivation) {
    let path = format!("{}/examples/{name}.lag", env!("CARGO_MANIFEST_DIR"));
    let source = std::fs::read_to_string(&path).unwrap();
    let model = lagc::frontend(&source).unwrap_or_else(|d| panic!("{name}: {d:?}"));
    let derivation = derive(&model).unwrap_or_else(|d| panic!("{name}: {d:?}"));
    (model, derivation)
}

fn field_of(name: &str) -> (Derivation, FieldSystem) {
    let (_, mut derivation) = derived(name);
    let reduced = derivation.reduced.clone();
    let field = field_system(&mut derivation.arena, &reduced);
    (derivation, field)
}

/// F from (9) equals `f_1' = b_1 − Σ f_A b_A + λ f_1`,
/// `f_B' = a_1B − Σ f_A a_AB + λ f_B`, `λ = a_11 − Σ f_A a_A1` with `a`, `b`
/// taken from `X` by `affine_parts`, at random points.
fn check_against_spec_formulas(name: &str) {
    let (mut derivation, field) = field_of(name);
    let system = field
        .coefficient_system
        .clone()
        .unwrap_or_else(|| panic!("{name} should be affine"));
    let arena: &mut Arena = &mut derivation.arena;
    let state = derivation.reduced.state.clone();
    let n = state.len();
    let motion = field.motion.clone().unwrap();
    let mut a = Vec::new();
    let mut b = Vec::new();
    for &x_rate in &motion {
        let (row, free) = arena.affine_parts(x_rate, &state);
        a.push(row);
        b.push(free);
    }
    let mut random = lagc::mechanics::Rng::new(17);
    for _ in 0..50 {
        let t = 0.5 + random.range(-1.0, 1.0);
        let params: Vec<f64> = derivation
            .param_defaults
            .iter()
            .map(|v| v * (1.0 + 0.1 * random.range(-1.0, 1.0)))
            .collect();
        let f: Vec<f64> = (0..n).map(|_| random.range(-1.0, 1.0)).collect();
        let masses: Vec<f64> = (0..8)
            .map(|_| 1.0 + 0.5 * random.range(-1.0, 1.0))
            .collect();
        let coefficients = field.coefficients.clone();
        let env = |s: Symbol| match s {
            Symbol::Time => t,
            Symbol::Param(i) => params[i as usize],
            Symbol::Mass(i) => masses[i as usize],
            Symbol::Aux(i) => coefficients
                .iter()
                .position(|&c| c == Symbol::Aux(i))
                .map_or(f64::NAN, |k| f[k]),
            Symbol::Jet { .. } | Symbol::Input(_) | Symbol::InputRate(_) => f64::NAN,
        };
        let a_num: Vec<Vec<f64>> = a.iter().map(|row| arena.eval_many(row, &env)).collect();
        let b_num = arena.eval_many(&b, &env);
        let lambda = a_num[0][0] - (1..n).map(|k| f[k] * a_num[k][0]).sum::<f64>();
        let mut expected =
            vec![b_num[0] - (1..n).map(|k| f[k] * b_num[k]).sum::<f64>() + lambda * f[0]];
        for col in 1..n {
            expected.push(
                a_num[0][col] - (1..n).map(|k| f[k] * a_num[k][col]).sum::<f64>() + lambda * f[col],
            );
        }
        let got = arena.eval_many(&system.rhs, &env);
        for (i, (g, e)) in got.iter().zip(&expected).enumerate() {
            assert!(
                (g - e).abs() <= 1e-12 * e.abs().max(1.0),
                "{name}: F_{} = {g} but the formula gives {e}",
                i + 1
            );
        }
    }
}

#[test]
fn coefficient_system_matches_spec_formulas_on_affine_examples() {
    for name in [
        "paper",
        "paper_constant_mass_long",
        "damped_oscillator",
        "weak_damping",
        "oscillator_long",
        "mass_gain_stiff",
        "mass_loss_stiff_spring",
        "vertical_rocket",
        "saturn_rocket",
        "second_order_constraint",
        "third_order_constraint",
    ] {
        check_against_spec_formulas(name);
    }
}

#[test]
fn classification_of_the_examples() {
    // The paper: no X_A depends on q1, so the coefficient system is linear,
    // and f1, f2 have F ≡ 0 (SPEC §1.6).
    let (_, paper) = field_of("paper");
    let system = paper.coefficient_system.unwrap();
    assert!(system.linear);
    assert_eq!(system.constant, vec![true, true, false, false]);
    // The oscillator: X_2 = −ω² x_1 depends on x_1: Riccati.
    let (_, oscillator) = field_of("damped_oscillator");
    let system = oscillator.coefficient_system.unwrap();
    assert!(!system.linear);
    assert_eq!(system.constant, vec![false, false]);
    // Non-affine and implicit systems: the local field method.
    for name in ["knife_edge", "rolling_disk", "nonlinear_constraint"] {
        let (_, field) = field_of(name);
        assert!(field.motion.is_some() && !field.is_affine(), "{name}");
    }
    let (_, implicit) = field_of("nonlinear_second_order");
    assert!(implicit.motion.is_none() && !implicit.is_affine());
}

#[test]
fn derive_text_shows_the_basic_equation_and_coefficient_system() {
    let (derivation, field) = field_of("paper");
    let text = field.text(&derivation.arena, &derivation.reduced.state);
    assert!(
        text.contains("ansatz (10): q1 = f1 + f2*q2 + f3*q1' + f4*q2'"),
        "{text}"
    );
    assert!(text.contains("coefficient system (linear):"), "{text}");
    assert!(text.contains("f1' = 0  (constant: f = c)"), "{text}");
    assert!(text.contains("f4' = -f2"), "{text}");
}
