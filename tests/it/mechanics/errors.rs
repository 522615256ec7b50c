//! The mechanics' diagnostics, rendered through the full pipeline (front end
//! and derive) as snapshots: one mistake per file under `tests/data/errors/`.

use lagc::diagnostic::{codes, render, Diagnostic};

fn diagnostics(name: &str) -> (String, Vec<Diagnostic>) {
    let path = format!("{}/tests/data/errors/{name}", env!("CARGO_MANIFEST_DIR"));
    let source = std::fs::read_to_string(&path).unwrap();
    let result = lagc::frontend(&source).and_then(|model| lagc::mechanics::derive(&model));
    match result {
        Ok(_) => panic!("{name}: derived without an error"),
        Err(d) => (source, d),
    }
}

#[test]
fn inconsistent_initial_value() {
    let (source, d) = diagnostics("inconsistent_initial.lag");
    assert_eq!(d.len(), 1, "{d:#?}");
    assert_eq!(d[0].code, codes::INCONSISTENT_INITIAL);
    insta::assert_snapshot!(render(&d, "inconsistent_initial.lag", &source, false));
}

#[test]
fn singular_mass_matrix() {
    let (source, d) = diagnostics("singular_mass_matrix.lag");
    assert_eq!(d.len(), 1, "{d:#?}");
    assert_eq!(d[0].code, codes::SINGULAR_MASS_MATRIX);
    insta::assert_snapshot!(render(&d, "singular_mass_matrix.lag", &source, false));
}

/// k ≥ 3: a given `x''` that contradicts (4) at t0.
#[test]
fn inconsistent_solved_initial_value() {
    let source = include_str!("../../../examples/third_order_constraint.lag")
        .replace("y'' = ypp0;", "y'' = ypp0, x'' = 5;");
    let model = lagc::frontend(&source).unwrap();
    let d = lagc::mechanics::derive(&model).unwrap_err();
    assert_eq!(d.len(), 1, "{d:#?}");
    assert_eq!(d[0].code, codes::INCONSISTENT_INITIAL);
    assert!(d[0].notes[0].contains("`x''` = -4.5"), "{:?}", d[0].notes);
    // The consistent value passes.
    let consistent = include_str!("../../../examples/third_order_constraint.lag")
        .replace("y'' = ypp0;", "y'' = ypp0, x'' = xpp0;");
    let model = lagc::frontend(&consistent).unwrap();
    assert!(lagc::mechanics::derive(&model).is_ok());
}

/// The checker rejects `q''` in a Lagrangian; the mechanics also refuses it
/// on its own (a model built by hand).
#[test]
fn a_second_order_lagrangian_is_refused() {
    let source = include_str!("../../../examples/second_order_constraint.lag");
    let mut model = lagc::frontend(source).unwrap();
    model.lagrangian = model.constraints[0].rhs.clone(); // t * x''
    let d = lagc::mechanics::derive(&model).unwrap_err();
    assert_eq!(d[0].code, codes::DERIVATIVE_ORDER_NOT_ALLOWED);
    assert!(d[0].message.contains("x''"), "{}", d[0].message);
}
