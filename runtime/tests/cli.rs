//! The generated binary's command line, parsed and prepared: every bad
//! argument is a usage error with lagc's own words, and overrides get the
//! same checks as the model file's own values.

mod models;

use lagc_runtime::cli::{parse, prepare, Command, Invocation, MAX_SAMPLES};
use lagc_runtime::failure::{Failure, FailureKind};
use lagc_runtime::model::Model;
use models::{KnifeEdge, Oscillator};

fn args(text: &str) -> Vec<String> {
    text.split_whitespace().map(str::to_string).collect()
}

fn invocation<M: Model>(text: &str) -> Invocation {
    match parse(&args(text), M::PARAMS, M::STATE, M::OUTPUTS) {
        Ok(Command::Run(inv)) => *inv,
        other => panic!("{text}: {other:?}"),
    }
}

fn usage_error<M: Model>(text: &str) -> String {
    parse(&args(text), M::PARAMS, M::STATE, M::OUTPUTS).expect_err(text)
}

#[test]
fn bad_arguments_are_refused_in_words() {
    let cases = [
        ("--rtol -1", "between 0 and 1"),
        ("--rtol 10", "between 0 and 1"),
        ("--rtol abc", "not a finite number"),
        ("--atol 0", "must be positive"),
        ("--samples 0", "count ≥ 1"),
        ("--samples 18446744073709551615", "at most"),
        ("--samples 1e11", "at most"),
        ("--method sideways", "`field` or `direct`"),
        (
            "--integrator fast",
            "`auto`, `explicit`, `stiff` or `magnus`",
        ),
        ("--param nope=1", "no param `nope`"),
        ("--param w", "expected NAME=VALUE"),
        ("--init z=1", "not a component of the state"),
        ("--times 3,2", "increasing"),
        ("--phase x,x'", "needs `--plot"),
        ("--plot a.svg --phase x,q", "no column `q`"),
        ("--frobnicate", "unknown argument"),
        ("--rtol", "needs a value"),
    ];
    for (text, expected) in cases {
        let message = usage_error::<Oscillator>(text);
        assert!(message.contains(expected), "{text}: {message}");
    }
    let many = usage_error::<Oscillator>(&format!("--samples {}", MAX_SAMPLES + 1));
    assert!(many.contains("at most"), "{many}");
}

#[test]
fn good_arguments_parse() {
    let inv =
        invocation::<Oscillator>("--method direct --stiff --rtol 1e-8 --samples 1e3 --param w=3");
    assert_eq!(inv.samples, 1000);
    assert_eq!(inv.params, vec![(0, 3.0)]);
    assert_eq!(inv.options.tol.rtol, 1e-8);
    let tiny = invocation::<Oscillator>("--rtol 1e-300");
    assert!(tiny.warnings[0].contains("below the rounding"));
    assert_eq!(parse(&args("--help"), &[], &[], &[]), Ok(Command::Help));
}

/// [`prepare`] for a model type with its file's param values: the
/// initial state it prepares.
fn prepared<M: Model + 'static>(inv: &Invocation) -> Result<Vec<f64>, Failure> {
    let prototype = M::new(&M::parameters(&vec![None; M::PARAMS.len()]));
    prepare(&prototype, inv).map(|prepared| prepared.x0)
}

#[test]
fn overrides_get_the_checks_the_file_gets() {
    // A reversed span after `--param T=-1`.
    let inv = invocation::<Oscillator>("--param T=-1");
    let failure = prepared::<Oscillator>(&inv).unwrap_err();
    assert!(
        matches!(failure.kind, FailureKind::BadTimeSpan { .. }),
        "{failure}"
    );
    assert_eq!(failure.exit_status(), 2);
    let inv = invocation::<Oscillator>("--param T=0");
    assert!(prepared::<Oscillator>(&inv).is_err());
    // An initial value the constraint fixes: stated consistently, it is
    // accepted; otherwise refused, naming the component.
    let inv = invocation::<KnifeEdge>("--init y'=0");
    assert!(prepared::<KnifeEdge>(&inv).is_ok());
    let inv = invocation::<KnifeEdge>("--init y'=5");
    let failure = prepared::<KnifeEdge>(&inv).unwrap_err();
    assert!(failure.to_string().contains("y'"), "{failure}");
    assert_eq!(failure.exit_status(), 2);
    // A given value is overridden.
    let inv = invocation::<Oscillator>("--init x=2");
    let x0 = prepared::<Oscillator>(&inv).unwrap();
    assert_eq!(x0[0], 2.0);
}
