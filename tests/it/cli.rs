//! The built `lagc` binary: exit codes and where diagnostics go.

use std::process::{Command, Output};

fn lagc(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_lagc"))
        .args(args)
        .current_dir(crate::root())
        .output()
        .expect("lagc runs")
}

#[test]
fn clean_example_exits_0() {
    let out = lagc(&["check", "examples/paper.lag"]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.stdout.is_empty());
}

#[test]
fn model_error_exits_1_with_location() {
    let out = lagc(&["check", "tests/data/errors/unknown_name.lag"]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("tests/data/errors/unknown_name.lag:5:"),
        "{stderr}"
    );
    assert!(stderr.contains("error[E0002]"), "{stderr}");
    // stderr is not a terminal here: no colour codes.
    assert!(!stderr.contains('\u{1b}'), "{stderr}");
}

#[test]
fn invalid_utf8_exits_1() {
    let out = lagc(&["check", "tests/data/errors/invalid_utf8.lag"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("E0016"));
}

#[test]
fn missing_file_exits_2() {
    let out = lagc(&["check", "no/such/file.lag"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("cannot read `no/such/file.lag`"));
}

#[test]
fn bad_usage_exits_2() {
    for args in [
        &[][..],
        &["frobnicate"],
        &["check"],
        &["check", "a.lag", "b.lag"],
    ] {
        let out = lagc(args);
        assert_eq!(out.status.code(), Some(2), "lagc {args:?}");
    }
}

#[test]
fn help_exits_0() {
    let out = lagc(&["check", "--help"]);
    assert_eq!(out.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&out.stdout).contains("Usage: lagc check"));
}
