//! The stiff and extreme examples: each states in its `// expect:
//! outcome …` lines the one result each method must have — field method,
//! direct DOP853, direct RODAS4, at rtol 1e-10, atol 1e-12 — either
//! `finishes within TOL` of the exact solution (relative where |x| > 1,
//! the generated crate's measure) or `stops with exit 3` at a stated time
//! naming the quantity. Never a wrong answer with exit 0, and never a
//! change of outcome unnoticed. An example is a stiff case when it has
//! `outcome` lines.

use crate::expect::{expectations_of, lag_files, run_as_stated, Expectation};
use crate::generated::build_file;

/// Every stiff case states an outcome for each of these runs.
const METHODS: &[(&str, Option<&str>)] = &[
    ("field", None),
    ("direct", Some("explicit")),
    ("direct", Some("stiff")),
];

#[test]
fn stiff_and_extreme_examples_have_their_stated_outcomes() {
    let mut problems = Vec::new();
    let mut cases = 0;
    let mut runs = 0;
    for path in lag_files("examples") {
        let name = path.file_stem().unwrap().to_string_lossy().into_owned();
        let outcomes: Vec<_> = expectations_of(&path)
            .into_iter()
            .filter_map(|e| match e {
                Expectation::Outcome { run, result } => Some((run, result)),
                _ => None,
            })
            .collect();
        if outcomes.is_empty() {
            continue;
        }
        cases += 1;
        for (method, integrator) in METHODS {
            assert!(
                outcomes.iter().any(|(run, _)| run.method == *method
                    && run.integrator.as_deref() == *integrator
                    && run.rtol.as_deref() == Some("1e-10")
                    && run.atol.as_deref() == Some("1e-12")
                    && run.flags.is_empty()),
                "{name}: no outcome for {method} {integrator:?} at rtol 1e-10 atol 1e-12"
            );
        }
        let binary = build_file(&path);
        for (run, result) in &outcomes {
            runs += 1;
            if let Err(problem) = run_as_stated(&binary, &name, run, result) {
                problems.push(problem);
            }
        }
    }
    assert!(cases >= 10, "{cases} stiff cases");
    assert!(runs >= 31, "{runs} runs");
    assert!(problems.is_empty(), "{problems:#?}");
}
