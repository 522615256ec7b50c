//! Runs that cannot be trusted stop with their physical cause, never with
//! exit 0 and a wrong answer: a mass reaching zero, the work budget, an
//! anchor that makes the field cancel.

mod models;

use lagc_runtime::driver::{run, Options};
use lagc_runtime::failure::FailureKind;
use lagc_runtime::field::Anchor;
use lagc_runtime::method::Method;
use lagc_runtime::model::Model;
use models::{ChainOntoHeap, Oscillator, VanishingMass};

fn fails<M: Model + 'static>(
    model: &mut M,
    options: &Options,
    t1: f64,
) -> lagc_runtime::failure::Failure {
    let (t0, _) = model.time_span();
    let x0 = model.initial_state(&vec![None; M::STATE.len()]).unwrap();
    run(model, options, t0, t1, &x0, &[t1], |_, _, _| Ok(())).expect_err("the run should fail")
}

#[test]
fn a_mass_reaching_zero_is_named_by_every_method() {
    for method in [Method::Direct, Method::Field] {
        let failure = fails(
            &mut VanishingMass::new(&[]),
            &Options {
                method,
                ..Options::default()
            },
            12.0,
        );
        assert!(
            matches!(&failure.kind, FailureKind::MassVanishes { mass, .. } if mass == "M"),
            "{method:?}: {failure}"
        );
        assert!(
            (failure.time - 10.0).abs() < 1e-3,
            "{method:?}: at {}",
            failure.time
        );
        assert!(failure.to_string().contains("reaches zero"));
    }
}

/// A mass law of the state (`M = rho x`): the driver evaluates it at the
/// state, at the start and where the integrator gives up.
#[test]
fn a_mass_of_the_state_reaching_zero_is_named_by_every_method() {
    for method in [Method::Direct, Method::Field] {
        let failure = fails(
            &mut ChainOntoHeap::new(&[]),
            &Options {
                method,
                // The field's windows chase the singularity until the
                // budget stalls (a million steps take a minute unoptimised).
                max_steps: 50_000,
                ..Options::default()
            },
            1.0,
        );
        assert!(
            matches!(&failure.kind, FailureKind::MassVanishes { mass, .. } if mass == "M"),
            "{method:?}: {failure}"
        );
        assert!(
            (failure.time - ChainOntoHeap::T_STAR).abs() < 1e-6,
            "{method:?}: at {}",
            failure.time
        );
    }
    // At the start: `x = 0` is a chain of no mass.
    let mut model = ChainOntoHeap::new(&[]);
    let x0 = model.initial_state(&[Some(0.0), Some(0.0)]).unwrap();
    let failure = run(
        &mut model,
        &Options::default(),
        0.0,
        1.0,
        &x0,
        &[1.0],
        |_, _, _| Ok(()),
    )
    .expect_err("a chain of no mass cannot start");
    assert!(
        matches!(&failure.kind, FailureKind::MassVanishes { mass, value } if mass == "M" && *value == 0.0),
        "{failure}"
    );
    assert_eq!(failure.time, 0.0);
}

#[test]
fn every_method_stops_within_its_budget() {
    for method in [Method::Direct, Method::Field] {
        let mut model = Oscillator::new(&[2.0, 1e5]);
        let options = Options {
            method,
            max_steps: 10_000,
            ..Options::default()
        };
        let failure = fails(&mut model, &options, 1e5);
        assert!(
            // A long span that merely needs many steps is not a stall.
            matches!(failure.kind, FailureKind::StepBudgetExhausted { steps, stalled: None } if steps <= 10_000),
            "{method:?}: {failure}"
        );
    }
}

#[test]
fn an_anchor_that_makes_the_field_cancel_is_refused() {
    let mut model = Oscillator::new(&[2.0, 10.0]);
    let options = Options {
        method: Method::Field,
        anchor: Anchor::Given(vec![1e300]),
        ..Options::default()
    };
    let failure = fails(&mut model, &options, 10.0);
    assert!(
        matches!(failure.kind, FailureKind::AnchorCancels { .. }),
        "{failure}"
    );
    assert_eq!(failure.exit_status(), 2);
}

#[test]
fn a_field_window_cut_short_by_the_budget_keeps_its_steps() {
    // The knife edge's motion is smooth enough for one quasilinear window
    // to span it all: a budget that runs out inside that window used to
    // lose every step of it (no row after t0). The steps the window kept
    // are now written, agreeing with direct integration, and the failure
    // follows them.
    type M = models::KnifeEdge;
    let mut model = M::new(&M::parameters(&vec![None; M::PARAMS.len()]));
    let (t0, t1) = model.time_span();
    let x0 = model.initial_state(&vec![None; M::STATE.len()]).unwrap();
    let times: Vec<f64> = (0..=1000)
        .map(|i| t0 + (t1 - t0) * f64::from(i) / 1000.0)
        .collect();
    let mut sampled = |method, max_steps| {
        let mut rows: Vec<(f64, Vec<f64>)> = Vec::new();
        let options = Options {
            method,
            max_steps,
            ..Options::default()
        };
        let outcome = run(&mut model, &options, t0, t1, &x0, &times, |_, t, x| {
            rows.push((t, x.to_vec()));
            Ok(())
        });
        (rows, outcome)
    };
    let (direct, outcome) = sampled(Method::Direct, 1_000_000);
    assert!(outcome.is_ok());
    let (field, outcome) = sampled(Method::Field, 40);
    let failure = outcome.expect_err("the budget runs out");
    assert!(
        matches!(failure.kind, FailureKind::StepBudgetExhausted { .. }),
        "{failure}"
    );
    assert!(field.len() > 100, "the field wrote {} rows", field.len());
    for ((t, a), (_, b)) in field.iter().zip(&direct) {
        for (a, b) in a.iter().zip(b) {
            assert!(
                (a - b).abs() <= 1e-8 * b.abs().max(1.0),
                "t = {t}: {a} vs {b}"
            );
        }
    }
}
