//! The mechanics' diagnostics beyond the error files (whose rendered
//! snapshots `tests/it/errors.rs` takes through the same pipeline as `lagc check`).

use lagc::diagnostic::codes;

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
