//! Unusual source text (issue 15, item 12): old Mac line endings (`\r`
//! alone) and control characters, read and shown faithfully.

/// The paper's example with every `\n` replaced by `\r`.
fn paper_cr_only() -> String {
    let text = std::fs::read_to_string(crate::root().join("examples/paper.lag"))
        .expect("examples/paper.lag is readable");
    assert!(!text.contains('\r'));
    text.replace('\n', "\r")
}

/// A CR-only file is a model of many lines, not one comment: it checks
/// clean as a file (`check_bytes`, as `lagc check`) and as text given to
/// the front end directly (the grammar ends a comment at `\r` as well).
#[test]
fn a_cr_only_model_checks_clean() {
    let text = paper_cr_only();
    let model = crate::check_bytes(text.as_bytes(), "paper_cr.lag")
        .unwrap_or_else(|rendered| panic!("the CR-only paper does not check:\n{rendered}"));
    assert_eq!(model.coords.len(), 2);
    let direct = lagc::on_big_stack(|| lagc::frontend(&text).map(|m| m.coords.len()));
    assert_eq!(direct, Ok(2));
}

/// An error in a CR-only file is reported at its line and column, with
/// that line alone as the snippet.
#[test]
fn an_error_in_a_cr_only_model_names_its_line() {
    let text = "// old Mac line endings\rparam m = 1;\rcoord x;\r\
                lagrangian = m / 2 * x'^2 - k * x;\rinitial x = 1, x' = 0;\rtime 0 .. 1;\r";
    let rendered =
        crate::check_bytes(text.as_bytes(), "cr_only.lag").expect_err("`k` is not declared");
    assert!(rendered.contains("cr_only.lag:4:29"), "{rendered}");
    assert!(!rendered.contains('\r'), "{rendered:?}");
    insta::assert_snapshot!(rendered);
}

/// Mixed endings: `\r\n`, `\n` and a lone `\r` in one file, an error on
/// the line after the lone `\r`.
#[test]
fn mixed_line_endings_count_every_line() {
    let text = "coord x;\r\nparam m = 1;\nparam c = 2;\rlagrangian = m / 2 * x'^2 - k;\r\n";
    let rendered = crate::check_bytes(text.as_bytes(), "mixed.lag").expect_err("`k` is unknown");
    assert!(rendered.contains("mixed.lag:4:29"), "{rendered}");
}
