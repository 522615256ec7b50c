//! `lagc check` and `lagc build` agree on every input: a model check
//! accepts builds, and one it refuses, build refuses with the same
//! diagnostics (codes and positions). Every folder of models with an
//! `// expect:` header takes part (`expect::ACCEPTED`, `expect::REFUSED`),
//! and both agree with the header: `check ok` exactly when both accept.
//! Build runs as `lagc build` does up to the crate's source (the front end
//! and `pipeline::generate_crate`: derivation, kernel, emission), so a
//! rejection anywhere after `check` would show here.

use crate::expect::{as_stated, expectations_of, Expectation, ACCEPTED, REFUSED};
use lagc::emit::EmitOptions;

#[test]
fn check_and_build_agree_on_every_example_and_error_file() {
    let mut files = Vec::new();
    for dir in ACCEPTED.iter().chain(REFUSED) {
        files.extend(crate::expect::lag_files(dir));
    }
    assert!(files.len() > 120, "{} files", files.len());
    lagc::on_big_stack(|| {
        for path in &files {
            let name = path.display();
            let accepted_by_header = expectations_of(path).contains(&Expectation::CheckOk);
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
            match (&checked, &built) {
                (Ok(_), Ok(())) => {}
                (Err(c), Err(b)) => assert_eq!(
                    as_stated(c, &source),
                    as_stated(b, &source),
                    "{name}: different errors"
                ),
                (Ok(_), Err(b)) => panic!(
                    "{name}: check accepts what build refuses:\n{}",
                    lagc::diagnostic::render(b, "x.lag", &source, false)
                ),
                (Err(c), Ok(())) => panic!(
                    "{name}: build accepts what check refuses:\n{}",
                    lagc::diagnostic::render(c, "x.lag", &source, false)
                ),
            }
            assert_eq!(
                checked.is_ok(),
                accepted_by_header,
                "{name}: the header says check {}",
                if accepted_by_header {
                    "accepts it"
                } else {
                    "refuses it"
                }
            );
        }
    });
}
