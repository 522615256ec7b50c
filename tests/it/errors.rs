//! Every file under `tests/data/errors/` holds one mistake; its rendered
//! diagnostics are a snapshot.

use std::collections::BTreeSet;
use std::sync::Mutex;

const LAST_CODE: u32 = 39;

#[test]
fn each_error_file_renders_its_diagnostics() {
    let seen = Mutex::new(BTreeSet::new());
    insta::glob!("../data/errors", "*.lag", |path| {
        let bytes = std::fs::read(path).expect("error file is readable");
        let file_name = format!(
            "tests/data/errors/{}",
            path.file_name()
                .map(|n| n.to_string_lossy())
                .unwrap_or_default()
        );
        let rendered = match crate::check_bytes(&bytes, &file_name) {
            Ok(_) => panic!("{file_name} checks clean, but it should hold a mistake"),
            Err(rendered) => rendered,
        };
        assert!(
            rendered.contains("error["),
            "{file_name}: no error in\n{rendered}"
        );
        assert!(
            bytes.starts_with(b"//"),
            "{file_name} must start with a `//` comment saying what is wrong"
        );
        let mut seen = seen.lock().unwrap();
        for part in rendered.split("error[").skip(1) {
            seen.insert(part[..5].to_string());
        }
        insta::assert_snapshot!(rendered);
    });
    let seen = seen.into_inner().unwrap();
    let missing: Vec<String> = (1..=LAST_CODE)
        .map(|n| format!("E{n:04}"))
        .filter(|code| !seen.contains(code))
        .collect();
    assert!(missing.is_empty(), "no error file shows {missing:?}");
}
