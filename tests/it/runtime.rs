//! The numeric runtime of generated crates, checked on hand-written systems
//! against exact motions.

#[path = "../../src/emit/runtime/mod.rs"]
mod rt;

mod stability;
mod systems;

use rt::direct::solve_direct;
use rt::error::{Failure, FailureKind};
use rt::field::{solve_field, Anchor, FieldOptions, FieldReport};
use rt::method::Integrator;
use rt::output::sample_times;
use rt::stepper::{Stats, Tolerance};
use rt::system::{CoefficientSystem, Motion};
use systems::*;

const TOL: Tolerance = Tolerance {
    rtol: 1e-10,
    atol: 1e-12,
};

type Trajectory = Vec<(f64, Vec<f64>)>;

fn direct(
    motion: &dyn Motion,
    integrator: Integrator,
    times: &[f64],
    x0: &[f64],
) -> Result<(Trajectory, Stats), Failure> {
    let mut samples = Vec::new();
    let stats = solve_direct(motion, integrator, TOL, times, x0, |t, x| {
        samples.push((t, x.to_vec()))
    })?;
    Ok((samples, stats))
}

fn field(
    coefficients: &dyn CoefficientSystem,
    options: &FieldOptions,
    times: &[f64],
    x0: &[f64],
) -> Result<(Trajectory, FieldReport), Failure> {
    let mut samples = Vec::new();
    let report = solve_field(coefficients, options, times, x0, |t, x| {
        samples.push((t, x.to_vec()))
    })?;
    Ok((samples, report))
}

fn field_options() -> FieldOptions {
    FieldOptions {
        tol: TOL,
        ..FieldOptions::default()
    }
}

/// The largest error relative to `max(|exact|, 1)` over all samples.
fn largest_error(samples: &Trajectory, exact: impl Fn(f64) -> Vec<f64>) -> f64 {
    let mut largest = 0.0_f64;
    for (t, x) in samples {
        for (value, truth) in x.iter().zip(exact(*t)) {
            largest = largest.max((value - truth).abs() / truth.abs().max(1.0));
        }
    }
    largest
}

#[test]
fn paper_example_by_field_and_direct_matches_exact_motion() {
    let system = PaperExample { alpha: 0.5 };
    let x0 = [0.0, 0.0, 1.0, 0.0];
    let times = sample_times(0.0, 5.0, 51);
    let exact = |t| system.exact(t, &x0);
    let (by_field, report) = field(&system, &field_options(), &times, &x0).unwrap();
    assert_eq!(by_field.len(), 51);
    assert_eq!(by_field[50].0, 5.0);
    let field_error = largest_error(&by_field, exact);
    assert!(field_error <= 1e-8, "field error {field_error:e}");
    assert!(report.largest_condition >= 1.0);
    for integrator in [Integrator::Explicit, Integrator::Stiff] {
        let (by_direct, _) = direct(&system, integrator, &times, &x0).unwrap();
        let error = largest_error(&by_direct, exact);
        assert!(error <= 1e-8, "{integrator:?} error {error:e}");
    }
}

#[test]
fn paper_example_field_does_not_depend_on_the_anchor() {
    let system = PaperExample { alpha: 0.5 };
    let x0 = [0.3, -0.2, 1.0, 0.0];
    let times = sample_times(0.0, 5.0, 26);
    let (zero, _) = field(&system, &field_options(), &times, &x0).unwrap();
    let other = FieldOptions {
        anchor: Anchor::Given(vec![0.3, -0.7, 1.1]),
        ..field_options()
    };
    let (given, _) = field(&system, &other, &times, &x0).unwrap();
    let difference = largest_error(&given, |t| {
        zero.iter().find(|(s, _)| *s == t).unwrap().1.clone()
    });
    assert!(difference <= 1e-9, "anchors differ by {difference:e}");
    let error = largest_error(&given, |t| system.exact(t, &x0));
    assert!(error <= 1e-8, "error {error:e}");
}

#[test]
fn oscillator_field_reanchors_before_the_riccati_blow_up() {
    let system = Oscillator { omega: 1.0 };
    let x0 = [1.0, 0.5];
    let times = sample_times(0.0, 100.0, 401);
    let exact = |t| system.exact(t, &x0);
    let (by_field, report) = field(&system, &field_options(), &times, &x0).unwrap();
    // f_2 = tan(t)/ω from c_2 = 0: at least one pole every π.
    assert!(report.reanchorings >= 31, "{report:?}");
    let error = largest_error(&by_field, exact);
    assert!(error <= 1e-8, "field error {error:e}");
    for integrator in [Integrator::Explicit, Integrator::Stiff] {
        let (by_direct, _) = direct(&system, integrator, &times, &x0).unwrap();
        let error = largest_error(&by_direct, exact);
        assert!(error <= 1e-8, "{integrator:?} error {error:e}");
    }
}

#[test]
fn damped_oscillator_by_field_and_direct_matches_exact_motion() {
    let system = DampedOscillator {
        omega: 2.0,
        zeta: 0.1,
    };
    let x0 = [1.0, -0.5];
    let times = sample_times(0.0, 20.0, 201);
    let exact = |t| system.exact(t, &x0);
    let (by_field, _) = field(&system, &field_options(), &times, &x0).unwrap();
    let error = largest_error(&by_field, exact);
    assert!(error <= 1e-8, "field error {error:e}");
    for integrator in [Integrator::Explicit, Integrator::Stiff] {
        let (by_direct, _) = direct(&system, integrator, &times, &x0).unwrap();
        let error = largest_error(&by_direct, exact);
        assert!(error <= 1e-8, "{integrator:?} error {error:e}");
    }
}

#[test]
fn stiff_system_field_reanchors_and_both_integrators_handle_it() {
    let system = StiffPair { rate: 1000.0 };
    let x0 = [1.0, 2.0];
    // Past t = 0.8, where S would overflow without re-anchoring.
    let times = sample_times(0.0, 1.0, 11);
    let exact = |t| system.exact(t, &x0);
    for integrator in [Integrator::Explicit, Integrator::Stiff] {
        let options = FieldOptions {
            integrator,
            magnus: false,
            ..field_options()
        };
        let (by_field, report) = field(&system, &options, &times, &x0).unwrap();
        // f_2 grows like e^{999 t}: without re-anchoring S overflows by t = 0.8.
        assert!(report.reanchorings > 0, "{report:?}");
        let error = largest_error(&by_field, exact);
        assert!(error <= 1e-8, "field {integrator:?} error {error:e}");
        let (by_direct, _) = direct(&system, integrator, &times, &x0).unwrap();
        let error = largest_error(&by_direct, exact);
        assert!(error <= 1e-8, "direct {integrator:?} error {error:e}");
    }
}

#[test]
fn very_stiff_system_takes_rosenbrock_far_fewer_steps() {
    // Stiffness 1e6: DOP853 is held to h ≲ 6e-6 by stability alone.
    let system = StiffPair { rate: 1e6 };
    let x0 = [1.0, 2.0];
    let times = sample_times(0.0, 1.0, 11);
    let exact = |t| system.exact(t, &x0);
    let (explicit, explicit_stats) = direct(&system, Integrator::Explicit, &times, &x0).unwrap();
    let (stiff, stiff_stats) = direct(&system, Integrator::Stiff, &times, &x0).unwrap();
    for samples in [&explicit, &stiff] {
        let error = largest_error(samples, exact);
        assert!(error <= 1e-8, "direct error {error:e}");
    }
    assert!(
        10 * stiff_stats.accepted_steps < explicit_stats.accepted_steps,
        "RODAS4 {stiff_stats:?} vs DOP853 {explicit_stats:?}"
    );
}

#[test]
fn overflowing_blow_up_is_a_non_finite_state_at_t_1() {
    // x' = (1e-150 x)², x(0) = 1e300: x = 1e300/(1 − t) and
    // x' = 1e300/(1 − t)² pass 1e306 at 1 − t ≈ 1e-3, where the stage sums
    // of a step overflow whatever its length.
    let system = Quadratic { scale: 1e-150 };
    for integrator in [Integrator::Explicit, Integrator::Stiff] {
        let failure = direct(&system, integrator, &[0.0, 2.0], &[1e300]).unwrap_err();
        assert!(
            matches!(&failure.kind, FailureKind::NonFiniteState { component } if component.starts_with("x1")),
            "{integrator:?}: {failure}"
        );
        assert!(
            (failure.time - 1.0).abs() < 2e-3,
            "{integrator:?}: {failure}"
        );
        assert!(failure.to_string().contains("x1"), "{failure}");
    }
}

#[test]
fn representable_blow_up_is_a_step_size_underflow_at_t_1() {
    // x' = x², x(0) = 1: x = 1/(1 − t) stays finite at every representable
    // t < 1, so the step size underflows first.
    let system = Quadratic { scale: 1.0 };
    for integrator in [Integrator::Explicit, Integrator::Stiff] {
        let failure = direct(&system, integrator, &[0.0, 2.0], &[1.0]).unwrap_err();
        assert!(
            matches!(failure.kind, FailureKind::StepSizeUnderflow { step } if step < 1e-12),
            "{integrator:?}: {failure}"
        );
        assert!(
            (failure.time - 1.0).abs() < 1e-6,
            "{integrator:?}: {failure}"
        );
        assert!(failure.to_string().contains("step size"), "{failure}");
    }
}

#[test]
fn vanishing_condition_without_reanchoring_is_a_singular_condition_matrix() {
    // x' = diag(0, 50, 0) x: the condition matrix is diag(e^{-50t}, 1), whose
    // condition number e^{50t} passes 1e4 at t = ln(1e4)/50.
    let system = Diverging { rate: 50.0 };
    let x0 = [1.0, 1.0, 2.0];
    let times = sample_times(0.0, 0.5, 501);
    let options = FieldOptions {
        reanchor: false,
        ..field_options()
    };
    let failure = field(&system, &options, &times, &x0).unwrap_err();
    let onset = 1e4_f64.ln() / 50.0;
    match failure.kind {
        FailureKind::SingularConditionMatrix { condition } => assert!(condition > 1e4),
        _ => panic!("{failure}"),
    }
    assert!(
        failure.time >= onset && failure.time <= onset + 1e-3,
        "{failure}"
    );
    assert!(failure.to_string().contains("condition"), "{failure}");
    // Re-anchoring restores the conditioning; the motion is x2 = e^{50t}.
    let (samples, report) = field(&system, &field_options(), &times, &x0).unwrap();
    assert!(report.reanchorings > 0);
    let error = largest_error(&samples, |t| system.exact(t, &x0));
    assert!(error <= 1e-8, "error {error:e}");
}

/// `AffineCoefficients` (SPEC's formulas, used by the local field method)
/// agrees with the hand-derived coefficient systems.
#[test]
fn affine_coefficients_match_the_hand_derived_ones() {
    use nalgebra::{DMatrix, DVector};
    use rt::local_field::AffineCoefficients;
    fn compare(hand: &dyn CoefficientSystem, motion: &dyn Motion, t: f64, f: &[f64]) {
        let n = f.len();
        let mut a = DMatrix::zeros(n, n);
        motion.jacobian(t, &vec![0.0; n], &mut a).unwrap();
        let mut b0 = vec![0.0; n];
        motion.rhs(t, &vec![0.0; n], &mut b0).unwrap();
        let mut b_slope = vec![0.0; n];
        motion.time_partial(t, &vec![0.0; n], &mut b_slope).unwrap();
        let general = AffineCoefficients {
            a,
            b0: DVector::from_vec(b0),
            b_slope: DVector::from_vec(b_slope),
            t_r: t,
        };
        assert_eq!(general.is_linear(), hand.is_linear());
        let (mut df_hand, mut df_general) = (vec![0.0; n], vec![0.0; n]);
        hand.rhs(t, f, &mut df_hand).unwrap();
        general.rhs(t, f, &mut df_general).unwrap();
        let (mut j_hand, mut j_general) = (DMatrix::zeros(n, n), DMatrix::zeros(n, n));
        hand.jacobian(t, f, &mut j_hand).unwrap();
        general.jacobian(t, f, &mut j_general).unwrap();
        for i in 0..n {
            assert!(
                (df_hand[i] - df_general[i]).abs() < 1e-14,
                "{df_hand:?} {df_general:?}"
            );
        }
        assert!((j_hand - j_general).abs().max() < 1e-14);
    }
    let f4 = [0.3, -1.2, 0.7, 2.5];
    compare(
        &PaperExample { alpha: 0.5 },
        &PaperExample { alpha: 0.5 },
        1.7,
        &f4,
    );
    compare(
        &Oscillator { omega: 1.3 },
        &Oscillator { omega: 1.3 },
        0.4,
        &f4[..2],
    );
    let damped = DampedOscillator {
        omega: 2.0,
        zeta: 0.1,
    };
    compare(&damped, &damped, 0.0, &f4[1..3]);
    compare(
        &StiffPair { rate: 1e3 },
        &StiffPair { rate: 1e3 },
        0.0,
        &f4[2..],
    );
}

#[test]
fn local_field_follows_a_non_affine_motion() {
    use rt::local_field::solve_local_field;
    let system = Cubic;
    let x0 = [0.5, 0.25];
    let times = sample_times(0.0, 1.0, 11);
    let options = FieldOptions {
        tol: Tolerance {
            rtol: 1e-9,
            atol: 1e-11,
        },
        ..field_options()
    };
    let mut samples = Vec::new();
    let report = solve_local_field(&system, &options, &times, &x0, |t, x| {
        samples.push((t, x.to_vec()))
    })
    .unwrap();
    let error = largest_error(&samples, |t| system.exact(t, &x0));
    assert!(error <= 1e-8, "error {error:e}, {report:?}");
    // The affine paper example goes through the same windows.
    let paper = PaperExample { alpha: 0.5 };
    let x0 = [0.0, 0.0, 1.0, 0.0];
    let times = sample_times(0.0, 5.0, 11);
    let mut samples = Vec::new();
    solve_local_field(&paper, &options, &times, &x0, |t, x| {
        samples.push((t, x.to_vec()))
    })
    .unwrap();
    let error = largest_error(&samples, |t| paper.exact(t, &x0));
    assert!(error <= 1e-8, "paper error {error:e}");
}

#[test]
fn samples_and_csv_follow_the_spec() {
    use rt::output::{write_header, write_row, Summary};
    let times = sample_times(0.0, 5.0, 4);
    assert_eq!(times.len(), 4);
    assert_eq!((times[0], times[3]), (0.0, 5.0));
    for (i, t) in times.iter().enumerate() {
        assert!((t - 5.0 * i as f64 / 3.0).abs() <= 1e-15 * 5.0);
    }
    let mut csv = Vec::new();
    write_header(&mut csv, &["q1", "q2", "q1'", "q2'"]).unwrap();
    write_row(&mut csv, 0.1, &[1.0, -2.5e-300, 0.1 + 0.2, 3e20]).unwrap();
    let text = String::from_utf8(csv).unwrap();
    assert_eq!(
        text,
        "t,q1,q2,q1',q2'\n0.1,1,-2.5e-300,0.30000000000000004,3e20\n"
    );
    let summary = Summary {
        method: "field (DOP853)".into(),
        steps: 10,
        rejected_steps: 1,
        rhs_evaluations: 130,
        largest_condition: Some(12.5),
        reanchorings: Some(2),
        wall_time: std::time::Duration::from_micros(1500),
    };
    assert_eq!(
        summary.to_string(),
        "method: field (DOP853); steps: 10 (+1 rejected); right-side evaluations: 130; \
         largest condition number: 1.250e1; re-anchorings: 2; wall time: 1.500 ms"
    );
}

/// Work of field vs direct at rtol 1e-10 (run by hand, in release:
/// `cargo test --release --test it measure_ -- --ignored --nocapture`).
#[test]
#[ignore = "a measurement: run by hand in release"]
fn measure_field_against_direct() {
    use rt::output::Summary;
    use std::time::Instant;
    fn field_summary(
        c: &dyn CoefficientSystem,
        times: &[f64],
        x0: &[f64],
        reps: u32,
    ) -> (Summary, Trajectory) {
        let start = Instant::now();
        let mut run = None;
        for _ in 0..reps {
            run = Some(field(c, &field_options(), times, x0).unwrap());
        }
        let (samples, report) = run.unwrap();
        let summary = Summary {
            method: format!("field ({})", report.integrator),
            steps: report.stats.accepted_steps,
            rejected_steps: report.stats.rejected_steps,
            rhs_evaluations: report.stats.rhs_evaluations,
            largest_condition: Some(report.largest_condition),
            reanchorings: Some(report.reanchorings),
            wall_time: start.elapsed() / reps,
        };
        (summary, samples)
    }
    fn direct_summary(
        m: &dyn Motion,
        integrator: Integrator,
        times: &[f64],
        x0: &[f64],
        reps: u32,
    ) -> (Summary, Trajectory) {
        let start = Instant::now();
        let mut run = None;
        for _ in 0..reps {
            run = Some(direct(m, integrator, times, x0).unwrap());
        }
        let (samples, stats) = run.unwrap();
        let summary = Summary {
            method: format!("direct ({})", integrator.name()),
            steps: stats.accepted_steps,
            rejected_steps: stats.rejected_steps,
            rhs_evaluations: stats.rhs_evaluations,
            largest_condition: None,
            reanchorings: None,
            wall_time: start.elapsed() / reps,
        };
        (summary, samples)
    }
    let paper = PaperExample { alpha: 0.5 };
    let x0 = [0.0, 0.0, 1.0, 0.0];
    let times = sample_times(0.0, 5.0, 101);
    let runs = [
        field_summary(&paper, &times, &x0, 20),
        direct_summary(&paper, Integrator::Explicit, &times, &x0, 20),
        direct_summary(&paper, Integrator::Stiff, &times, &x0, 20),
    ];
    for (summary, samples) in &runs {
        let error = largest_error(samples, |t| paper.exact(t, &x0));
        println!("paper example t∈[0,5], 101 samples: {summary}; error {error:.2e}");
        assert!(error <= 1e-8);
    }
    let oscillator = Oscillator { omega: 1.0 };
    let x0 = [1.0, 0.5];
    let times = sample_times(0.0, 100.0, 101);
    let runs = [
        field_summary(&oscillator, &times, &x0, 20),
        direct_summary(&oscillator, Integrator::Explicit, &times, &x0, 20),
        direct_summary(&oscillator, Integrator::Stiff, &times, &x0, 20),
    ];
    for (summary, samples) in &runs {
        let error = largest_error(samples, |t| oscillator.exact(t, &x0));
        println!("oscillator t∈[0,100], 101 samples: {summary}; error {error:.2e}");
        assert!(error <= 1e-8);
    }
}
