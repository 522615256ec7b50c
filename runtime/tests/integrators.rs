//! Every integrator against exact solutions or a tight reference, and its
//! order of convergence measured from a tolerance ladder: the error
//! against the number of steps must fall with the slope of the method's
//! order (a method right at one tolerance but of lower order has a bug —
//! a wrong `∂X/∂t` makes RODAS4 first order, for instance).

mod models;

use lagc_runtime::driver::{run, Options};
use lagc_runtime::method::{IntegratorChoice, Method};
use lagc_runtime::model::Model;
use lagc_runtime::output::sample_times;
use lagc_runtime::tolerance::Tolerance;
use models::{DoublePendulum, MassLossPendulum, Oscillator, SphericalPendulum};

struct Run {
    rows: Vec<(f64, Vec<f64>)>,
    steps: usize,
}

fn solve<M: Model + 'static>(
    method: Method,
    choice: IntegratorChoice,
    rtol: f64,
    samples: usize,
) -> Run {
    let params = M::parameters(&vec![None; M::PARAMS.len()]);
    let mut model = M::new(&params);
    let (t0, t1) = model.time_span();
    let x0 = model.initial_state(&vec![None; M::STATE.len()]).unwrap();
    let options = Options {
        method,
        integrator: Some(choice),
        tol: Tolerance { rtol, atol: rtol },
        ..Options::default()
    };
    let mut rows = Vec::new();
    let outcome = run(
        &mut model,
        &options,
        t0,
        t1,
        &x0,
        &sample_times(t0, t1, samples),
        |_, t, x| {
            rows.push((t, x.to_vec()));
            Ok(())
        },
    )
    .unwrap_or_else(|f| panic!("{} {method:?} {choice:?} rtol {rtol}: {f}", M::NAME));
    let r = outcome.report;
    let predictor = r
        .predictor
        .map_or(0, |p| p.accepted_steps + p.rejected_steps);
    Run {
        rows,
        steps: r.stats.accepted_steps + r.stats.rejected_steps + predictor,
    }
}

fn error(a: &[(f64, Vec<f64>)], b: &[(f64, Vec<f64>)]) -> f64 {
    a.iter()
        .zip(b)
        .flat_map(|((ta, x), (tb, y))| {
            assert_eq!(ta, tb);
            x.iter()
                .zip(y)
                .map(|(u, v)| (u - v).abs() / v.abs().max(1.0))
        })
        .fold(0.0, f64::max)
}

/// The least-squares slope of `log error` against `log steps`, negated:
/// the observed order.
fn order(points: &[(usize, f64)]) -> f64 {
    let xs: Vec<f64> = points.iter().map(|p| (p.0 as f64).ln()).collect();
    let ys: Vec<f64> = points.iter().map(|p| p.1.ln()).collect();
    let n = xs.len() as f64;
    let (mx, my) = (xs.iter().sum::<f64>() / n, ys.iter().sum::<f64>() / n);
    let num: f64 = xs.iter().zip(&ys).map(|(x, y)| (x - mx) * (y - my)).sum();
    let den: f64 = xs.iter().map(|x| (x - mx).powi(2)).sum();
    -num / den
}

fn ladder<M: Model + 'static>(
    method: Method,
    choice: IntegratorChoice,
    rtols: &[f64],
    reference: &[(f64, Vec<f64>)],
) -> (f64, Vec<(usize, f64)>) {
    let points: Vec<(usize, f64)> = rtols
        .iter()
        .map(|&rtol| {
            let r = solve::<M>(method, choice, rtol, reference.len());
            (r.steps, error(&r.rows, reference))
        })
        .collect();
    (order(&points), points)
}

fn exact_oscillator(samples: usize) -> Vec<(f64, Vec<f64>)> {
    sample_times(0.0, 10.0, samples)
        .into_iter()
        .map(|t| (t, vec![(2.0 * t).cos(), -2.0 * (2.0 * t).sin()]))
        .collect()
}

#[test]
fn dop853_is_of_order_8_and_rodas4_of_order_4() {
    let exact = exact_oscillator(11);
    let (p, pts) = ladder::<Oscillator>(
        Method::Direct,
        IntegratorChoice::Explicit,
        &[1e-5, 1e-7, 1e-9, 1e-11],
        &exact,
    );
    eprintln!("DOP853 oscillator: order {p:.2} {pts:?}");
    assert!(p > 7.0, "DOP853 order {p}: {pts:?}");
    let (p, pts) = ladder::<Oscillator>(
        Method::Direct,
        IntegratorChoice::Stiff,
        &[1e-4, 1e-5, 1e-6, 1e-7, 1e-8],
        &exact,
    );
    eprintln!("RODAS4 oscillator: order {p:.2} {pts:?}");
    assert!(p > 3.5, "RODAS4 order {p}: {pts:?}");
    // An explicitly time-dependent motion: RODAS4 needs the true ∂X/∂t.
    let reference =
        solve::<MassLossPendulum>(Method::Direct, IntegratorChoice::Explicit, 1e-14, 11).rows;
    let (p, pts) = ladder::<MassLossPendulum>(
        Method::Direct,
        IntegratorChoice::Stiff,
        &[1e-4, 1e-5, 1e-6, 1e-7, 1e-8],
        &reference,
    );
    eprintln!("RODAS4 mass-loss pendulum: order {p:.2} {pts:?}");
    assert!(p > 3.5, "RODAS4 order {p}: {pts:?}");
}

#[test]
fn field_is_of_high_order_on_affine_and_non_affine_motions() {
    let exact = exact_oscillator(11);
    let (p, pts) = ladder::<Oscillator>(
        Method::Field,
        IntegratorChoice::Auto,
        &[1e-5, 1e-7, 1e-9, 1e-11],
        &exact,
    );
    eprintln!("field oscillator: order {p:.2} {pts:?}");
    assert!(p > 6.0, "field order {p}: {pts:?}");
    let reference =
        solve::<MassLossPendulum>(Method::Direct, IntegratorChoice::Explicit, 1e-14, 11).rows;
    let (p, pts) = ladder::<MassLossPendulum>(
        Method::Field,
        IntegratorChoice::Auto,
        &[1e-5, 1e-7, 1e-9, 1e-11],
        &reference,
    );
    eprintln!("field mass-loss pendulum: order {p:.2} {pts:?}");
    assert!(p > 6.0, "field order {p}: {pts:?}");
    let reference =
        solve::<SphericalPendulum>(Method::Direct, IntegratorChoice::Explicit, 1e-14, 11).rows;
    let (p, pts) = ladder::<SphericalPendulum>(
        Method::Field,
        IntegratorChoice::Auto,
        &[1e-5, 1e-7, 1e-9, 1e-11],
        &reference,
    );
    eprintln!("field spherical pendulum: order {p:.2} {pts:?}");
    assert!(p > 6.0, "field order {p}: {pts:?}");
    // A double pendulum through its mass matrix.
    let reference =
        solve::<DoublePendulum>(Method::Direct, IntegratorChoice::Explicit, 1e-14, 11).rows;
    let (p, pts) = ladder::<DoublePendulum>(
        Method::Field,
        IntegratorChoice::Auto,
        &[1e-5, 1e-7, 1e-9, 1e-11],
        &reference,
    );
    eprintln!("field double pendulum: order {p:.2} {pts:?}");
    assert!(p > 6.0, "field order {p}: {pts:?}");
}

#[test]
fn tolerance_means_what_it_says_for_field_and_direct() {
    // A simple pendulum whose mass decreases: the error at rtol R stays
    // within 10·R for both methods.
    let reference =
        solve::<MassLossPendulum>(Method::Direct, IntegratorChoice::Explicit, 1e-14, 11).rows;
    for rtol in [1e-5, 1e-7, 1e-9, 1e-11] {
        for method in [Method::Field, Method::Direct] {
            let r = solve::<MassLossPendulum>(method, IntegratorChoice::Explicit, rtol, 11);
            let e = error(&r.rows, &reference);
            eprintln!(
                "pendulum {method:?} rtol {rtol:e}: error {e:.2e} ({} steps)",
                r.steps
            );
            assert!(e <= 10.0 * rtol, "{method:?} at rtol {rtol}: error {e}");
        }
    }
    // The spherical pendulum is sensitive enough that DOP853 itself is off
    // by 18·R at R = 1e-5: there the field must do as well as DOP853 does.
    let reference =
        solve::<SphericalPendulum>(Method::Direct, IntegratorChoice::Explicit, 1e-14, 11).rows;
    for rtol in [1e-5, 1e-7, 1e-9, 1e-11] {
        let field = error(
            &solve::<SphericalPendulum>(Method::Field, IntegratorChoice::Explicit, rtol, 11).rows,
            &reference,
        );
        let direct = error(
            &solve::<SphericalPendulum>(Method::Direct, IntegratorChoice::Explicit, rtol, 11).rows,
            &reference,
        );
        eprintln!("spherical rtol {rtol:e}: field {field:.2e}, direct {direct:.2e}");
        assert!(
            field <= (10.0 * rtol).max(direct),
            "field at rtol {rtol}: {field} (direct {direct})"
        );
    }
}

/// 11 and 1001 samples: the identical step sequence, and the same values
/// at the common times (output comes from dense output, never a step).
fn output_never_changes_the_steps<M: Model + 'static>(method: Method, choice: IntegratorChoice) {
    let few = solve::<M>(method, choice, 1e-9, 11);
    let many = solve::<M>(method, choice, 1e-9, 1001);
    assert_eq!(few.steps, many.steps, "{} {method:?} {choice:?}", M::NAME);
    let common: Vec<(f64, Vec<f64>)> = many.rows.iter().step_by(100).cloned().collect();
    let e = error(&few.rows, &common);
    assert!(
        e <= 1e-9,
        "{} {method:?} {choice:?}: 11 and 1001 samples differ by {e}",
        M::NAME
    );
}

#[test]
fn output_times_never_change_the_steps() {
    use IntegratorChoice::{Auto, Explicit, Magnus, Stiff};
    for method in [Method::Field, Method::Direct] {
        for choice in [Auto, Explicit, Stiff] {
            // Non-affine: the quasilinear field; affine: the coefficient
            // system's field (and the Magnus integrator).
            output_never_changes_the_steps::<SphericalPendulum>(method, choice);
            output_never_changes_the_steps::<Oscillator>(method, choice);
        }
    }
    output_never_changes_the_steps::<Oscillator>(Method::Field, Magnus);
}

/// Direct integration carries its global error estimate into the report
/// (the sum of the steps' local errors, Hairer's estimates scaled by a
/// Richardson measure once the sum passes rtol): over one period of the
/// oscillator the run stays within 10·rtol and so does the estimate; over
/// 320 periods the local errors add up past 10·rtol, and the estimate says
/// so, within a factor 2 of the largest error over 101 samples (the
/// estimate is the largest over the run: carried from rtol on, it follows
/// the error's swing between x and v, 9.7e-9 against 9.2e-9, where the
/// error at the end alone is 4.8e-9).
#[test]
fn direct_integration_estimates_its_global_error() {
    let rtol = 1e-10;
    for (span, within) in [(3.0, true), (1000.0, false)] {
        let params = Oscillator::parameters(&[None, Some(span)]);
        let mut model = Oscillator::new(&params);
        let x0 = model.initial_state(&[None, None]).unwrap();
        let options = Options {
            method: Method::Direct,
            integrator: Some(IntegratorChoice::Explicit),
            tol: Tolerance {
                rtol,
                atol: rtol / 100.0,
            },
            ..Options::default()
        };
        let mut error = 0.0_f64;
        let outcome = run(
            &mut model,
            &options,
            0.0,
            span,
            &x0,
            &sample_times(0.0, span, 101),
            |m, t, x| {
                let mut exact = [None, None];
                m.exact(t, &mut exact);
                for (v, e) in x.iter().zip(exact) {
                    let e = e.unwrap();
                    error = error.max((v - e).abs() / e.abs().max(1.0));
                }
                Ok(())
            },
        )
        .unwrap();
        let estimate = outcome.report.global_error.expect("direct estimates");
        eprintln!(
            "oscillator over {span}: error {error:.2e}, estimate {:.2e}",
            estimate.largest
        );
        assert!(estimate.complete);
        assert_eq!(error <= 10.0 * rtol, within, "error {error}");
        assert_eq!(estimate.largest <= 10.0 * rtol, within);
        if !within {
            let ratio = estimate.largest / error;
            assert!((0.5..2.0).contains(&ratio), "estimate / error = {ratio}");
        }
    }
}
