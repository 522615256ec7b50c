//! Every file under `tests/data/errors/` holds one mistake and states, in
//! its `// expect:` header, every diagnostic `lagc check` gives (code and
//! position of each error and warning); its rendered diagnostics are a
//! snapshot.

use crate::expect::{as_stated, expectations_of, header_lines, stated, Expectation, REFUSED};
use std::collections::BTreeSet;
use std::sync::Mutex;

const LAST_CODE: u32 = 43;

#[test]
fn each_error_file_renders_its_diagnostics() {
    assert_eq!(REFUSED, ["tests/data/errors"]);
    let seen = Mutex::new(BTreeSet::new());
    let count = Mutex::new(0);
    insta::glob!("../data/errors", "*.lag", |path| {
        let bytes = std::fs::read(path).expect("error file is readable");
        let file_name = format!(
            "tests/data/errors/{}",
            path.file_name()
                .map(|n| n.to_string_lossy())
                .unwrap_or_default()
        );
        let expectations = expectations_of(path);
        assert!(
            !expectations.contains(&Expectation::CheckOk),
            "{file_name}: an error file cannot expect `check ok`"
        );
        let (source, diagnostics) = crate::expect::check_diagnostics(&bytes);
        let diagnostics = diagnostics
            .err()
            .unwrap_or_else(|| panic!("{file_name} checks clean, but it should hold a mistake"));
        let found = as_stated(&diagnostics, &source);
        assert!(
            found
                .iter()
                .any(|d| d.0 == lagc::diagnostic::Severity::Error),
            "{file_name}: no error"
        );
        assert_eq!(
            stated(&expectations),
            found,
            "{file_name}: the header states other diagnostics than check gives; it gives\n{}",
            header_lines(&found)
        );
        let rendered = crate::check_bytes(&bytes, &file_name).unwrap_err();
        assert!(
            rendered.contains("error["),
            "{file_name}: no error in\n{rendered}"
        );
        let comment = String::from_utf8_lossy(&bytes)
            .lines()
            .take_while(|l| l.starts_with("//"))
            .any(|l| !l.starts_with("// expect:"));
        assert!(
            comment,
            "{file_name} must open with a `//` comment saying what is wrong"
        );
        let mut seen = seen.lock().unwrap();
        for part in rendered.split("error[").skip(1) {
            seen.insert(part[..5].to_string());
        }
        *count.lock().unwrap() += 1;
        insta::assert_snapshot!(rendered);
    });
    assert_eq!(
        count.into_inner().unwrap(),
        crate::expect::lag_files("tests/data/errors").len()
    );
    let seen = seen.into_inner().unwrap();
    let missing: Vec<String> = (1..=LAST_CODE)
        .map(|n| format!("E{n:04}"))
        .filter(|code| !seen.contains(code))
        .collect();
    assert!(missing.is_empty(), "no error file shows {missing:?}");
}
