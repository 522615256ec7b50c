//! Run-time failures end to end (SPEC §4): every model under
//! `tests/data/runtime_failures/` fails at a known time, and states in its
//! `// expect: runtime failure RUN: exit 3 at t T ± W naming "…"` lines how
//! each run fails: its generated crate must exit with status 3, and stderr
//! must name the time (within W of T) and the quantity (one of the named
//! texts). The stderr of each file's runs (the integrator choice and the
//! failure; no wall time is printed on failure) is a snapshot.

use crate::expect::{expectations_of, run_as_stated, Expectation, RunResult};
use crate::generated::build_file;

#[test]
fn failing_models_stop_with_status_3_naming_time_and_quantity() {
    let count = std::sync::Mutex::new(0);
    insta::glob!("../data/runtime_failures", "*.lag", |path| {
        let name = path.file_stem().unwrap().to_string_lossy().into_owned();
        let text = std::fs::read_to_string(path).unwrap();
        let comment: Vec<&str> = text
            .lines()
            .take_while(|l| l.starts_with("//"))
            .filter(|l| !l.starts_with("// expect:"))
            .collect();
        assert!(
            comment.first().is_some_and(|l| l.starts_with("// Fails")),
            "{name}: the header comment must open with `// Fails` saying how it fails"
        );
        let failures: Vec<_> = expectations_of(path)
            .into_iter()
            .filter_map(|e| match e {
                Expectation::RuntimeFailure { run, result } => Some((run, result)),
                _ => None,
            })
            .collect();
        assert!(!failures.is_empty(), "{name}: no `runtime failure` line");
        let binary = build_file(path);
        let mut problems = Vec::new();
        let mut snapshot = String::new();
        for (run, result) in &failures {
            assert!(
                matches!(result, RunResult::Stops { exit: 3, .. }),
                "{name}: a run-time failure exits with status 3"
            );
            match run_as_stated(&binary, &name, run, result) {
                Ok((label, stderr)) => snapshot.push_str(&format!("$ {label}\n{stderr}\n")),
                Err(problem) => problems.push(problem),
            }
        }
        assert!(problems.is_empty(), "{}", problems.join("\n"));
        *count.lock().unwrap() += 1;
        insta::assert_snapshot!(snapshot);
    });
    assert_eq!(
        count.into_inner().unwrap(),
        crate::expect::lag_files("tests/data/runtime_failures").len()
    );
}

#[test]
fn the_field_stepping_over_a_constraint_s_pole_ends_on_the_exact_solution() {
    // tests/data/runtime_failures/constraint_pole.lag at the default rtol
    // (1e-10) and at 1e-12: the field steps over the pole of
    // `y' = tan(th) x'` at th = pi/2, where x' = 0 keeps the product
    // finite, as direct integration does. Not silently: every sample is
    // the exact state (th = t, x = sin t, y = 1 - cos t), the run ends at
    // t = 3, and the summary reports the residual at the pole.
    let path = crate::root().join("tests/data/runtime_failures/constraint_pole.lag");
    let binary = build_file(&path);
    for (rtol, bound) in [(None, 1e-8), (Some("1e-12"), 1e-10)] {
        let mut args = vec!["--method", "field", "--samples", "31"];
        if let Some(rtol) = rtol {
            args.extend(["--rtol", rtol]);
        }
        let (rows, stderr) = crate::rolling_bodies::run(&binary, &args);
        assert_eq!(rows.len(), 31, "{rtol:?}: {stderr}");
        assert!((rows[30][0] - 3.0).abs() < 1e-12, "{rtol:?}: {stderr}");
        for row in &rows {
            let t = row[0];
            let exact = [t.sin(), 1.0 - t.cos(), t, t.cos(), t.sin(), 1.0];
            for (got, want) in row[1..].iter().zip(exact) {
                assert!(
                    (got - want).abs() < bound,
                    "{rtol:?} at t = {t}: {got} against {want}: {stderr}"
                );
            }
        }
        assert!(stderr.contains("largest residual"), "{rtol:?}: {stderr}");
    }
}
