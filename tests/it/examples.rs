//! Every model that `lagc check` accepts (`expect::ACCEPTED`: the
//! examples, the language-v2, mass-law and run-time-failure models, the
//! warning files and the loose models under `tests/data/`) states `check
//! ok` in its `// expect:` header, and every warning `lagc check` and note
//! `lagc build` give it, with positions. An example with `exact` lines
//! states how close both methods come to them.

use crate::expect::{as_stated, expectations_of, header_lines, stated, Expectation, ACCEPTED};
use lagc::diagnostic::Severity;
use lagc::emit::EmitOptions;

#[test]
fn every_accepted_model_checks_clean_with_the_stated_warnings_and_notes() {
    let mut checked = 0;
    for dir in ACCEPTED {
        let files = crate::expect::lag_files(dir);
        assert!(!files.is_empty(), "no models in {dir}");
        for path in files {
            let name = path.display().to_string();
            let expectations = expectations_of(&path);
            assert!(
                expectations.contains(&Expectation::CheckOk),
                "{name}: the header must state `// expect: check ok`"
            );
            let bytes = std::fs::read(&path).expect("model is readable");
            let (source, checked_model) = crate::expect::check_diagnostics(&bytes);
            let model = match checked_model {
                Ok(model) => model,
                Err(_) => panic!(
                    "{name} has errors:\n{}",
                    crate::check_bytes(&bytes, &name).unwrap_err()
                ),
            };
            let mut diagnostics = lagc::source_warnings(&source);
            let options = EmitOptions {
                model_name: "notes".to_string(),
                source_hash: "test".to_string(),
                runtime_path: "../runtime".to_string(),
                package_key: None,
            };
            let (_, notes) =
                lagc::on_big_stack(|| lagc::pipeline::generate_crate(&model, &options))
                    .unwrap_or_else(|d| panic!("{name}: build refuses: {d:?}"));
            diagnostics.extend(notes);
            let found = as_stated(&diagnostics, &source);
            assert_eq!(
                stated(&expectations),
                found,
                "{name}: the header states other warnings or notes than check and build give; they give\n{}",
                header_lines(&found)
            );
            if *dir == "tests/data/warnings" {
                assert!(
                    found.iter().any(|d| d.0 == Severity::Warning),
                    "{name}: a warning file without a warning"
                );
            }
            // A model with an exact solution states how close both methods
            // come to it (tests/it/generated.rs runs them).
            if *dir == "examples" && !model.exact.is_empty() {
                for method in ["field", "direct"] {
                    assert!(
                        expectations.iter().any(|e| matches!(
                            e,
                            Expectation::Within { run, .. } if run.method == method
                        )),
                        "{name} has `exact` lines but no `// expect: {method} within …`"
                    );
                }
            }
            checked += 1;
        }
    }
    assert!(checked >= 40, "{checked} models");
}

#[test]
fn paper_example_has_the_papers_structure() {
    let bytes = std::fs::read(crate::root().join("examples/paper.lag")).unwrap();
    let model = crate::check_bytes(&bytes, "paper.lag").unwrap();
    let names: Vec<&str> = model.coords.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names, ["q1", "q2"]);
    assert_eq!(model.constraint_order, Some(1));
    assert_eq!(model.independent(), [0]);
    assert_eq!(model.dependent(), [1]);
    let defaults: Vec<f64> = model.params.iter().map(|p| p.default).collect();
    assert_eq!(defaults, [1.0, 0.5]);
    assert_eq!(model.points.len(), 1);
    assert_eq!(model.initial.len(), 3);
    assert_eq!(model.forces.len(), 1);
}
