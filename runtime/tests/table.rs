//! A run as numbers (`table`): the rows equal those of the run the CLI
//! streams, bit for bit; a failure keeps the rows before it; many
//! requests on threads equal one at a time.

mod models;

use lagc_runtime::driver::{run, Options};
use lagc_runtime::inputs::{Interpolation, Signal};
use lagc_runtime::method::Method;
use lagc_runtime::model::{DynModel, Model};
use lagc_runtime::output::sample_times;
use lagc_runtime::table::{jacobian_at, rhs_at, tabulate, tabulate_many, Request, TableError};
use models::{Oscillator, VanishingMass};

fn prototype<M: Model + 'static>() -> Box<dyn DynModel> {
    Box::new(M::new(&M::parameters(&vec![None; M::PARAMS.len()])))
}

#[test]
fn rows_are_the_runs_samples_bit_for_bit() {
    for method in [Method::Field, Method::Direct] {
        let request = Request {
            params: vec![(0, 3.0)],
            inits: vec![(1, 0.5)],
            options: Options {
                method,
                ..Options::default()
            },
            times: Some(vec![0.0, 0.25, 1.0, 7.5]),
            inputs: Vec::new(),
        };
        let table = tabulate(&*prototype::<Oscillator>(), &request)
            .unwrap()
            .table;
        // The same run through the driver, as the CLI makes it.
        let mut model = Oscillator::new(&[3.0, 10.0]);
        let mut rows = Vec::new();
        run(
            &mut model,
            &request.options,
            0.0,
            10.0,
            &[1.0, 0.5],
            request.times.as_ref().unwrap(),
            |_, t, x| {
                rows.push((t, x.to_vec()));
                Ok(())
            },
        )
        .unwrap();
        assert_eq!(table.t, rows.iter().map(|r| r.0).collect::<Vec<_>>());
        let states: Vec<f64> = rows.iter().flat_map(|r| r.1.clone()).collect();
        assert_eq!(table.states, states, "{method:?}");
        // And it is the motion: x = cos 3t + (0.5/3) sin 3t.
        let t = 7.5_f64;
        let x = (3.0 * t).cos() + 0.5 / 3.0 * (3.0 * t).sin();
        assert!((table.states[6] - x).abs() < 1e-8, "{}", table.states[6]);
    }
}

#[test]
fn default_times_are_the_clis_101_samples_and_the_summary_has_the_exact_error() {
    let done = tabulate(&*prototype::<Oscillator>(), &Request::new()).unwrap();
    assert_eq!(done.table.t, sample_times(0.0, 10.0, 101));
    let error = done.summary.exact_error.unwrap();
    assert!(error > 0.0 && error < 1e-8, "{error}");
    assert!(done.summary.json().contains("\"steps\":"));
}

#[test]
fn a_failure_keeps_the_rows_before_it_and_names_its_quantity() {
    let request = Request {
        times: Some((0..=24).map(|i| i as f64 * 0.5).collect()),
        ..Request::new()
    };
    match tabulate(&*prototype::<VanishingMass>(), &request) {
        Err(TableError::Failed(failed)) => {
            let (failure, table) = (failed.failure, failed.table);
            assert!((failure.time - 10.0).abs() < 1e-3, "{failure}");
            assert_eq!(failure.quantity(), "M");
            // The rows up to the failure: t = 0, 0.5, …, below 10.
            assert!(
                table.t.len() >= 19 && *table.t.last().unwrap() < 10.0,
                "{:?}",
                table.t
            );
            assert_eq!(table.states.len(), 2 * table.t.len());
        }
        other => panic!("expected a failure, got {other:?}"),
    }
}

#[test]
fn bad_requests_are_usage_errors() {
    let p = prototype::<Oscillator>();
    for times in [vec![1.0, 0.5], vec![-1.0, 1.0], vec![f64::NAN]] {
        let request = Request {
            times: Some(times.clone()),
            ..Request::new()
        };
        assert!(
            matches!(tabulate(&*p, &request), Err(TableError::Usage(_))),
            "{times:?}"
        );
    }
    let mut request = Request::new();
    request.options.tol.rtol = 2.0;
    assert!(matches!(tabulate(&*p, &request), Err(TableError::Usage(_))));
}

#[test]
fn times_past_the_span_are_refused_as_the_cli_refuses_them() {
    // The span's end is the model's `time` statement: a later time is a
    // usage error (it used to extend the run silently), the end itself is
    // a sample.
    let p = prototype::<Oscillator>();
    let past = Request {
        times: Some(vec![0.0, 12.0]),
        ..Request::new()
    };
    match tabulate(&*p, &past) {
        Err(TableError::Usage(message)) => {
            assert!(message.contains("12 is past the end"), "{message}")
        }
        other => panic!("expected a usage error, got {other:?}"),
    }
    let end = Request {
        times: Some(vec![0.0, 10.0]),
        ..Request::new()
    };
    let table = tabulate(&*p, &end).unwrap().table;
    assert_eq!(table.t, vec![0.0, 10.0]);
    assert!((table.states[2] - (2.0 * 10.0_f64).cos()).abs() < 1e-8);
}

#[test]
fn signals_for_a_model_without_inputs_are_a_usage_error() {
    let signal = Signal::new(vec![0.0], vec![1.0], Interpolation::Hold).unwrap();
    let request = Request {
        inputs: vec![(0, signal)],
        ..Request::new()
    };
    match tabulate(&*prototype::<Oscillator>(), &request) {
        Err(TableError::Usage(message)) => assert!(message.contains("no inputs"), "{message}"),
        other => panic!("expected a usage error, got {other:?}"),
    }
}

#[test]
fn many_requests_on_threads_equal_one_at_a_time() {
    let requests: Vec<Request> = (0..40)
        .map(|k| Request {
            params: vec![(0, 1.0 + 0.05 * k as f64)],
            ..Request::new()
        })
        .collect();
    let make = || prototype::<Oscillator>();
    let parallel = tabulate_many(&make, &requests, 3);
    let serial = tabulate_many(&make, &requests, 1);
    assert_eq!(parallel.len(), 40);
    for (a, b) in parallel.iter().zip(&serial) {
        assert_eq!(a.as_ref().unwrap().table, b.as_ref().unwrap().table);
    }
}

#[test]
fn rhs_and_jacobian_at_a_state() {
    let mut model = Oscillator::new(&[2.0, 10.0]);
    assert_eq!(
        rhs_at(&mut model, 0.0, &[1.0, 3.0]).unwrap(),
        vec![3.0, -4.0]
    );
    let jac = jacobian_at(&mut model, 0.0, &[1.0, 3.0]).unwrap();
    assert_eq!((jac[(0, 1)], jac[(1, 0)], jac[(0, 0)]), (1.0, -4.0, 0.0));
}
