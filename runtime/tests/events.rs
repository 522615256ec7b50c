//! Events and `stop when` through the driver: kinks located on the dense
//! output, the integrator (the field) restarted there, the stop time found
//! to rounding, with both methods.

mod models;

use lagc_runtime::driver::{run, Ending, Options};
use lagc_runtime::method::{IntegratorChoice, Method};
use lagc_runtime::model::Model;
use lagc_runtime::output::sample_times;
use lagc_runtime::tolerance::Tolerance;
use models::{StiffDamped, ThrownBall};

#[test]
fn a_ball_with_drag_rises_turns_and_lands_on_time_with_both_methods() {
    for method in [Method::Direct, Method::Field] {
        let mut model = ThrownBall::new(&[]);
        let x0 = model.initial_state(&[None, None]).unwrap();
        let options = Options {
            method,
            tol: Tolerance {
                rtol: 1e-10,
                atol: 1e-12,
            },
            ..Options::default()
        };
        let times = sample_times(0.0, 10.0, 101);
        let mut rows = Vec::new();
        let outcome = run(&mut model, &options, 0.0, 10.0, &x0, &times, |_, t, x| {
            rows.push((t, x.to_vec()));
            Ok(())
        })
        .unwrap();
        let landing = ThrownBall::landing_time();
        let Ending::Stopped(t_stop) = outcome.ending else {
            panic!("{method:?}: the ball did not land");
        };
        assert!(
            (t_stop - landing).abs() < 1e-9,
            "{method:?}: landed at {t_stop}, not {landing}"
        );
        assert_eq!(
            rows.last().unwrap().0,
            t_stop,
            "the last row is at the stop time"
        );
        assert!(rows.iter().all(|(t, _)| *t <= t_stop));
        assert_eq!(outcome.events, 2, "the top and the landing");
        let error = rows
            .iter()
            .flat_map(|(t, x)| {
                let e = ThrownBall::exact_at(*t);
                [
                    (x[0] - e[0]).abs(),
                    (x[1] - e[1]).abs() / e[1].abs().max(1.0),
                ]
            })
            .fold(0.0, f64::max);
        eprintln!(
            "{method:?}: landing {t_stop} (exact {landing}), error {error:.2e}, {:?}",
            outcome.report.stats
        );
        assert!(error < 1e-8, "{method:?}: error {error}");
    }
}

#[test]
fn stiff_affine_field_switches_to_rodas4_and_stays_accurate() {
    for choice in [IntegratorChoice::Auto, IntegratorChoice::Stiff] {
        let mut model = StiffDamped::new(&[]);
        let x0 = model.initial_state(&[None, None]).unwrap();
        let options = Options {
            method: Method::Field,
            integrator: Some(choice),
            tol: Tolerance {
                rtol: 1e-8,
                atol: 1e-10,
            },
            ..Options::default()
        };
        let times = sample_times(0.0, 2.0, 21);
        let mut error = 0.0_f64;
        let outcome = run(&mut model, &options, 0.0, 2.0, &x0, &times, |_, t, x| {
            let e = StiffDamped::exact_at(t);
            error = error.max((x[0] - e[0]).abs()).max((x[1] - e[1]).abs());
            Ok(())
        })
        .unwrap();
        eprintln!("{choice:?}: error {error:.2e}, {:?}", outcome.report);
        assert!(error < 1e-6, "{choice:?}: error {error}");
    }
}

#[test]
fn an_implicit_constraint_switches_candidates_through_every_heading() {
    use models::KnifeEdge;
    for method in [Method::Direct, Method::Field] {
        let mut model = KnifeEdge::new(&[]);
        let x0 = model.initial_state(&[None; 6]).unwrap();
        let options = Options {
            method,
            tol: Tolerance {
                rtol: 1e-10,
                atol: 1e-12,
            },
            ..Options::default()
        };
        let mut error = 0.0_f64;
        let outcome = run(
            &mut model,
            &options,
            0.0,
            10.0,
            &x0,
            &sample_times(0.0, 10.0, 101),
            |_, t, x| {
                for (a, b) in x.iter().zip(KnifeEdge::exact_at(t)) {
                    error = error.max((a - b).abs() / b.abs().max(1.0));
                }
                Ok(())
            },
        )
        .unwrap_or_else(|f| panic!("{method:?}: {f}"));
        eprintln!("{method:?}: error {error:.2e}, {:?}", outcome.report.stats);
        assert!(error < 1e-8, "{method:?}: error {error}");
    }
}

#[test]
fn a_solution_value_interpolates_every_method_across_events() {
    use lagc_runtime::driver::solve;
    for method in [Method::Direct, Method::Field] {
        for choice in [IntegratorChoice::Explicit, IntegratorChoice::Stiff] {
            let mut model = ThrownBall::new(&[]);
            let x0 = model.initial_state(&[None, None]).unwrap();
            let options = Options {
                method,
                integrator: Some(choice),
                tol: Tolerance {
                    rtol: 1e-10,
                    atol: 1e-12,
                },
                ..Options::default()
            };
            let solution = solve(&mut model, &options, 0.0, 10.0, &x0).unwrap();
            assert!((solution.end() - ThrownBall::landing_time()).abs() < 1e-9);
            let mut error = 0.0_f64;
            for k in 0..=300 {
                let t = solution.end() * k as f64 / 300.0;
                let x = solution.at(t);
                let e = ThrownBall::exact_at(t);
                error = error.max((x[0] - e[0]).abs()).max((x[1] - e[1]).abs());
            }
            eprintln!("{method:?} {choice:?}: Solution::at error {error:.2e}");
            let allowed = if choice == IntegratorChoice::Stiff {
                1e-6
            } else {
                1e-8
            };
            assert!(error < allowed, "{method:?} {choice:?}: {error}");
        }
    }
}
