//! The steppable integration: where the caller stops does not change the
//! steps (advancing in pieces equals advancing at once, to the bit), and a
//! restart from a changed state equals a fresh run from that state.

mod models;

use lagc_runtime::driver::{Ending, Options};
use lagc_runtime::failure::FailureKind;
use lagc_runtime::integration::{Advance, Integration};
use lagc_runtime::method::Method;
use lagc_runtime::model::{DynModel, Model};
use lagc_runtime::tolerance::Tolerance;
use models::{DoublePendulum, KnifeEdge, Oscillator, ThrownBall};

fn options(method: Method) -> Options {
    Options {
        method,
        tol: Tolerance {
            rtol: 1e-10,
            atol: 1e-12,
        },
        ..Options::default()
    }
}

/// Makes a fresh model.
type Make = Box<dyn Fn() -> Box<dyn DynModel>>;

/// The models: an affine oscillator, a ball with drag that lands (events,
/// `stop when`), a knife edge changing candidates (modes), a double
/// pendulum (non-affine).
fn cases() -> Vec<(&'static str, Make)> {
    vec![
        (
            "oscillator",
            Box::new(|| {
                Box::new(Oscillator::new(&<Oscillator as Model>::parameters(&[
                    None, None,
                ])))
            }),
        ),
        ("thrown ball", Box::new(|| Box::new(ThrownBall::new(&[])))),
        ("knife edge", Box::new(|| Box::new(KnifeEdge::new(&[])))),
        (
            "double pendulum",
            Box::new(|| {
                Box::new(DoublePendulum::new(&<DoublePendulum as Model>::parameters(
                    &[],
                )))
            }),
        ),
    ]
}

/// Where a run stands after asking for each of `times`: every answer,
/// the states (bits), and the work done when it is finished.
fn advance_through(
    make: &dyn Fn() -> Box<dyn DynModel>,
    method: Method,
    times: &[f64],
) -> (Vec<(Advance, Vec<u64>)>, String) {
    let mut model = make();
    let (t0, t1) = DynModel::time_span(&*model);
    let x0 = DynModel::initial_state(&*model, &vec![None; model.dim()]).unwrap();
    let mut integration = Integration::new(&mut *model, &options(method), t0, t1, &x0);
    let mut answers = Vec::new();
    for &t in times {
        let advance = integration.advance_to(t).unwrap();
        let bits = integration.state().iter().map(|v| v.to_bits()).collect();
        answers.push((advance, bits));
    }
    let o = integration.finish().unwrap();
    // The steps, not the evaluations: a step's continuous extension costs
    // right sides when it is first read, so more stops cost more of them.
    let r = &o.report;
    let steps = format!(
        "{} (+{} rejected), windows {:?}, passes {:?}, re-anchorings {:?}, predictor {:?}, \
         events {}, budget {}, {:?}",
        r.stats.accepted_steps,
        r.stats.rejected_steps,
        r.windows,
        r.passes,
        r.reanchorings,
        r.predictor.map(|p| (p.accepted_steps, p.rejected_steps)),
        o.events,
        o.budget_used,
        o.ending
    );
    (answers, steps)
}

#[test]
fn advancing_in_ten_pieces_takes_the_steps_of_one_advance_to_the_bit() {
    for method in [Method::Direct, Method::Field] {
        for (name, make) in cases() {
            let (t0, t1) = DynModel::time_span(&*make());
            let pieces: Vec<f64> = (1..=10).map(|k| t0 + (t1 - t0) * k as f64 / 10.0).collect();
            let (in_pieces, work_in_pieces) = advance_through(&*make, method, &pieces);
            let (at_once, work_at_once) = advance_through(&*make, method, &[t1]);
            assert_eq!(
                in_pieces.last().unwrap(),
                at_once.last().unwrap(),
                "{name} {method:?}: the state at the end"
            );
            assert_eq!(work_in_pieces, work_at_once, "{name} {method:?}: the steps");
            // Many more stops than steps: still the same steps.
            let many: Vec<f64> = (1..=1000)
                .map(|k| t0 + (t1 - t0) * k as f64 / 1000.0)
                .collect();
            let (dense, work_dense) = advance_through(&*make, method, &many);
            assert_eq!(work_dense, work_at_once, "{name} {method:?}: 1000 stops");
            assert_eq!(dense.last().unwrap(), at_once.last().unwrap());
            eprintln!("{name} {method:?}: {work_at_once}");
        }
    }
}

#[test]
fn a_stop_when_ends_the_advance_with_its_time_and_state() {
    for method in [Method::Direct, Method::Field] {
        let mut model = ThrownBall::new(&[]);
        let x0 = Model::initial_state(&model, &[None, None]).unwrap();
        let mut integration = Integration::new(&mut model, &options(method), 0.0, 10.0, &x0);
        let Advance::Ended(Ending::Stopped(t)) = integration.advance_to(10.0).unwrap() else {
            panic!("{method:?}: the ball did not land");
        };
        assert!((t - ThrownBall::landing_time()).abs() < 1e-9);
        assert_eq!(integration.t(), t);
        assert!(integration.state()[0].abs() < 1e-9, "on the ground");
        // Asked again, the same answer.
        assert_eq!(
            integration.advance_to(10.0).unwrap(),
            Advance::Ended(Ending::Stopped(t))
        );
        // Before where it stands: refused, naming the span.
        let failure = integration.advance_to(t / 2.0).unwrap_err();
        assert!(matches!(failure.kind, FailureKind::OutsideSpan { .. }));
    }
}

#[test]
fn a_restart_from_a_changed_state_equals_a_fresh_run_from_it() {
    for method in [Method::Direct, Method::Field] {
        for (name, make) in cases() {
            let mut model = make();
            let (t0, t1) = DynModel::time_span(&*model);
            let x0 = DynModel::initial_state(&*model, &vec![None; model.dim()]).unwrap();
            let t_mid = t0 + 0.3 * (t1 - t0);
            let mut integration = Integration::new(&mut *model, &options(method), t0, t1, &x0);
            let Advance::Reached(_) = integration.advance_to(t_mid).unwrap() else {
                panic!("{name}: ended early");
            };
            let steps_before = integration.outcome().report.stats.accepted_steps;
            // A kick: the last velocity grows by a tenth.
            let mut x = integration.state().to_vec();
            let last = x.len() - 1;
            x[last] *= 1.1;
            integration.restart_from(t_mid, &x).unwrap();
            let restarted = integration.advance_to(t1).unwrap();
            let restarted_state = integration.state().to_vec();
            let outcome = integration.finish().unwrap();
            assert!(
                outcome.report.stats.accepted_steps > steps_before,
                "{name}: work adds up"
            );

            let mut fresh_model = make();
            let mut fresh = Integration::new(&mut *fresh_model, &options(method), t_mid, t1, &x);
            let from_fresh = fresh.advance_to(t1).unwrap();
            assert_eq!(restarted, from_fresh, "{name} {method:?}");
            let bits = |x: &[f64]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
            assert_eq!(
                bits(&restarted_state),
                bits(fresh.state()),
                "{name} {method:?}"
            );
        }
    }
}

#[test]
fn a_restart_checks_the_state_as_init_values_are() {
    let mut model = Oscillator::new(&<Oscillator as Model>::parameters(&[None, None]));
    let mut integration =
        Integration::new(&mut model, &options(Method::Field), 0.0, 10.0, &[1.0, 0.0]);
    integration.advance_to(1.0).unwrap();
    let failure = integration.restart_from(1.0, &[f64::NAN, 0.0]).unwrap_err();
    assert!(matches!(
        failure.kind,
        FailureKind::NonFiniteInitialValue { .. }
    ));
    let failure = integration.restart_from(11.0, &[1.0, 0.0]).unwrap_err();
    assert!(matches!(failure.kind, FailureKind::OutsideSpan { .. }));
    // Back before a later restart (an FMU's state saved before an input
    // changed): allowed, down to where the integration was made.
    integration.restart_from(1.0, &[1.0, 0.0]).unwrap();
    integration.advance_to(2.0).unwrap();
    integration.restart_from(0.5, &[1.0, 0.0]).unwrap();
    assert_eq!(integration.t(), 0.5);
    integration.advance_to(1.5).unwrap();
    let failure = integration.restart_from(-0.5, &[1.0, 0.0]).unwrap_err();
    assert!(matches!(failure.kind, FailureKind::OutsideSpan { .. }));
}

/// The largest error against the oscillator's exact motion over `samples`
/// evenly spaced times, and the accepted steps, of a direct run.
fn oscillator_samples(rtol: f64, samples: usize, step_to_times: bool) -> (f64, usize) {
    let params = <Oscillator as Model>::parameters(&[None, None]);
    let mut model = Oscillator::new(&params);
    let (t0, t1) = Model::time_span(&model);
    let x0 = Model::initial_state(&model, &[None, None]).unwrap();
    let options = Options {
        method: Method::Direct,
        tol: Tolerance {
            rtol,
            atol: rtol * 1e-2,
        },
        step_to_times,
        ..Options::default()
    };
    let mut integration = Integration::new(&mut model, &options, t0, t1, &x0);
    let mut error = 0.0_f64;
    for i in 1..samples {
        let t = t0 + (t1 - t0) * i as f64 / (samples - 1) as f64;
        assert!(matches!(integration.advance_to(t), Ok(Advance::Reached(_))));
        let mut exact = [None; 2];
        integration.model().exact(t, &mut exact);
        for (x, e) in integration.state().iter().zip(exact) {
            let e = e.unwrap();
            error = error.max((x - e).abs() / e.abs().max(1.0));
        }
    }
    let outcome = integration.finish().unwrap();
    (error, outcome.report.stats.accepted_steps)
}

/// `step_to_times`: every output time is a step's end, so there are at
/// least as many steps as sample intervals, and the samples carry the
/// step's error, not the continuous extension's (order 7 against the
/// step's 8): on the oscillator at 41 samples they are several times more
/// accurate at every tolerance of the ladder.
#[test]
fn stepping_onto_the_times_gives_the_steps_accuracy() {
    for rtol in [1e-7, 1e-9, 1e-11] {
        let (interpolated, free_steps) = oscillator_samples(rtol, 41, false);
        let (stepped, steps) = oscillator_samples(rtol, 41, true);
        assert!(steps >= 40, "rtol {rtol}: {steps} steps for 40 intervals");
        println!(
            "rtol {rtol}: {stepped:.3e} ({steps} steps) against {interpolated:.3e} ({free_steps})"
        );
        assert!(
            stepped * 2.0 < interpolated,
            "rtol {rtol}: {stepped:.3e} stepped against {interpolated:.3e} interpolated"
        );
    }
}
