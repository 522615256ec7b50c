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

/// Whether `text` holds a control character other than a line end.
fn has_raw_control(text: &str) -> bool {
    text.chars().any(|c| c.is_control() && c != '\n')
}

/// Control characters in the source never reach the terminal raw: the
/// snippet shows NUL, SOH, ESC, DEL and a C1 control as pictures (`␀`, `␁`,
/// `␛`, `␡`, U+FFFD), the label still under the right column; the message
/// quotes them escaped.
#[test]
fn control_characters_are_shown_not_echoed() {
    let comment = "param m = 1;\ncoord x;\n\
                   lagrangian = m / 2 * x'^2 - k; // \0 \u{1} \u{7f} \u{85} \u{1b}[2J\n\
                   initial x = 1, x' = 0;\ntime 0 .. 1;\n";
    let in_comment =
        crate::check_bytes(comment.as_bytes(), "controls.lag").expect_err("`k` is not declared");
    assert!(in_comment.contains("controls.lag:3:29"), "{in_comment}");
    let found = "param m = 1;\ncoord x;\nlagrangian = m / 2 * x'^2\u{1b}[31m;\n";
    let as_token =
        crate::check_bytes(found.as_bytes(), "escape.lag").expect_err("ESC is not a token");
    let nul = "coord x;\nlagrangian = x\0'^2;\n";
    let as_nul = crate::check_bytes(nul.as_bytes(), "nul.lag").expect_err("NUL is not a token");
    for rendered in [&in_comment, &as_token, &as_nul] {
        assert!(!has_raw_control(rendered), "{rendered:?}");
    }
    insta::assert_snapshot!(format!("{in_comment}\n{as_token}\n{as_nul}"));
}

/// A file name with control characters is escaped too.
#[test]
fn a_control_character_in_the_file_name_is_escaped() {
    let rendered = crate::check_bytes(b"coord x;\n", "a\u{1b}[2Jb.lag").expect_err("incomplete");
    assert!(!has_raw_control(&rendered), "{rendered:?}");
    assert!(rendered.contains("a\\u{1b}[2Jb.lag:"), "{rendered}");
}
