//! `lagc check` and `lagc build` agree on every input: a model check
//! accepts builds, and one it refuses, build refuses with the same codes.

use lagc::emit::EmitOptions;

fn codes(diagnostics: &[lagc::diagnostic::Diagnostic]) -> Vec<String> {
    let mut codes: Vec<String> = diagnostics.iter().map(|d| d.code.to_string()).collect();
    codes.sort();
    codes.dedup();
    codes
}

#[test]
fn check_and_build_agree_on_every_example_and_error_file() {
    let root = crate::root();
    let mut files = Vec::new();
    for dir in [
        "examples",
        "tests/data/errors",
        "tests/data/v2",
        "tests/data/runtime_failures",
        "tests/data/mass_law_forms",
    ] {
        let Ok(entries) = std::fs::read_dir(root.join(dir)) else {
            continue;
        };
        files.extend(
            entries
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|e| e == "lag")),
        );
    }
    files.sort();
    assert!(files.len() > 50, "{} files", files.len());
    lagc::on_big_stack(|| {
        for path in &files {
            let bytes = std::fs::read(path).unwrap();
            let (_, checked) = lagc::check_and_derive_bytes(&bytes);
            let (source, front) = lagc::frontend_bytes(&bytes);
            let built = front.and_then(|model| {
                let options = EmitOptions {
                    model_name: "agreement".to_string(),
                    source_hash: "test".to_string(),
                    runtime_path: "../runtime".to_string(),
                    package_key: None,
                };
                lagc::pipeline::generate_crate(&model, &options).map(|_| ())
            });
            let name = path.display();
            match (&checked, &built) {
                (Ok(_), Ok(())) => {}
                (Err(c), Err(b)) => assert_eq!(codes(c), codes(b), "{name}: different errors"),
                (Ok(_), Err(b)) => panic!(
                    "{name}: check accepts what build refuses:\n{}",
                    lagc::diagnostic::render(b, "x.lag", &source, false)
                ),
                (Err(c), Ok(())) => panic!(
                    "{name}: build accepts what check refuses:\n{}",
                    lagc::diagnostic::render(c, "x.lag", &source, false)
                ),
            }
        }
    });
}
