//! A mass law's rate reaches every time partial (issue 10). Each model
//! under `tests/data/mass_law_forms/` comes twice: once with a `mass` law
//! (frozen under `D`, SPEC 1.1) and once with the same law written into
//! the Lagrangian or the forces as explicit `t`. Both are the same motion,
//! so every method must give the same answer (≤ 1e-9 at rtol 1e-10) in
//! the same number of steps (within 20%). While `∂X/∂t` ignored the mass
//! law, the field method and RODAS4 fell to first order on the mass-law
//! form: 60,537 windows against 1,838 and 140,309 steps against 413 on the
//! one-coordinate pendulum. DOP853, which has no time partial, always
//! agreed. Then each method's order is measured end to end on the
//! mass-law pendulum from a tolerance ladder.

use crate::generated::build_file;
use std::path::PathBuf;
use std::process::Command;

/// One coordinate; two coupled coordinates; a non-holonomic constraint;
/// a reactive force (thrust along the velocity) with drag.
const TWINS: &[&str] = &["pendulum", "double", "sleigh", "rocket"];

const METHODS: &[&[&str]] = &[
    &["--method", "field"],
    &["--method", "direct", "--integrator", "explicit"],
    &["--method", "direct", "--integrator", "stiff"],
];

fn model(name: &str) -> PathBuf {
    crate::root().join(format!("tests/data/mass_law_forms/{name}.lag"))
}

/// A run's samples (the CSV rows) and its accepted steps.
struct Run {
    rows: Vec<Vec<f64>>,
    steps: usize,
}

fn run(binary: &std::path::Path, args: &[&str]) -> Run {
    let output = Command::new(binary).args(args).output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{binary:?} {args:?}:\n{stderr}");
    let rows = String::from_utf8(output.stdout)
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    let steps = stderr
        .split("steps: ")
        .nth(1)
        .and_then(|rest| rest.split_whitespace().next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no step count in\n{stderr}"));
    Run { rows, steps }
}

/// The largest difference of two runs' samples, relative to
/// `max(|x|, 1)`.
fn largest_difference(a: &Run, b: &Run) -> f64 {
    assert_eq!(a.rows.len(), b.rows.len());
    a.rows
        .iter()
        .zip(&b.rows)
        .flat_map(|(r, s)| r.iter().zip(s))
        .map(|(x, y)| (x - y).abs() / x.abs().max(1.0))
        .fold(0.0, f64::max)
}

#[test]
fn a_mass_law_and_its_explicit_t_form_give_one_motion_under_every_method() {
    let mut problems = Vec::new();
    for twin in TWINS {
        let with_mass = build_file(&model(&format!("{twin}_mass")));
        let explicit = build_file(&model(&format!("{twin}_explicit")));
        for method in METHODS {
            let mut args = method.to_vec();
            args.extend(["--rtol", "1e-10", "--atol", "1e-12"]);
            let (a, b) = (run(&with_mass, &args), run(&explicit, &args));
            let difference = largest_difference(&a, &b);
            let ratio = a.steps as f64 / b.steps as f64;
            let label = format!("{twin} {}", method.join(" "));
            if difference > 1e-9 {
                problems.push(format!("{label}: the forms differ by {difference:e}"));
            }
            if !(0.8..=1.25).contains(&ratio) {
                problems.push(format!(
                    "{label}: {} steps with the mass law, {} with explicit t",
                    a.steps, b.steps
                ));
            }
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// The final state's error of each rung of a tolerance ladder against a
/// reference, and the slope of log(error) against log(steps): the order
/// the method shows. The reference is the explicit-t twin by DOP853 at
/// rtol 1e-14 (another generated model, another integrator for the field
/// method and RODAS4). Rungs whose error is near the reference's own
/// (< 1e-12) are left out.
fn measured_order(binary: &std::path::Path, method: &[&str], ladder: &[&str]) -> f64 {
    let reference = build_file(&model("pendulum_explicit"));
    let exact = run(
        &reference,
        &[
            "--method",
            "direct",
            "--integrator",
            "explicit",
            "--rtol",
            "1e-14",
            "--atol",
            "1e-16",
            "--samples",
            "2",
        ],
    );
    let end = exact.rows.last().unwrap().clone();
    let mut points = Vec::new();
    for rtol in ladder {
        let mut args = method.to_vec();
        args.extend(["--rtol", rtol, "--atol", rtol, "--samples", "2"]);
        let r = run(binary, &args);
        let last = r.rows.last().unwrap();
        let error = last
            .iter()
            .zip(&end)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
        if error > 1e-12 {
            points.push(((r.steps as f64).ln(), error.ln()));
        }
    }
    assert!(points.len() >= 3, "{method:?}: too few rungs above 1e-12");
    let n = points.len() as f64;
    let (mx, my) = points
        .iter()
        .fold((0.0, 0.0), |(a, b), (x, y)| (a + x / n, b + y / n));
    let (sxy, sxx) = points.iter().fold((0.0, 0.0), |(a, b), (x, y)| {
        (a + (x - mx) * (y - my), b + (x - mx) * (x - mx))
    });
    -sxy / sxx
}

/// Each method keeps its order on the mass-law pendulum: DOP853 8,
/// RODAS4 4, the field method the order of its DOP853 windows. The
/// bounds sit below the nominal orders by the scatter of adaptive step
/// counts; a method that sees only part of `∂X/∂t` shows order 1–3.
#[test]
fn every_method_keeps_its_order_on_a_variable_mass_model() {
    let binary = build_file(&model("pendulum_mass"));
    let cases: &[(&[&str], &[&str], f64)] = &[
        (
            &["--method", "direct", "--integrator", "explicit"],
            &["1e-5", "1e-6", "1e-7", "1e-8", "1e-9", "1e-10"],
            6.5,
        ),
        (
            &["--method", "direct", "--integrator", "stiff"],
            &["1e-4", "1e-5", "1e-6", "1e-7", "1e-8", "1e-9"],
            3.5,
        ),
        (
            &["--method", "field"],
            &["1e-5", "1e-6", "1e-7", "1e-8", "1e-9", "1e-10"],
            6.0,
        ),
    ];
    let mut problems = Vec::new();
    for (method, ladder, least) in cases {
        let order = measured_order(&binary, method, ladder);
        if order < *least {
            problems.push(format!("{method:?}: order {order:.2} < {least}"));
        }
        eprintln!("{method:?}: measured order {order:.2}");
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// The field's output between its steps is as accurate as direct DOP853's
/// between its own (within 5×), on the rocket with drag, whose conditions
/// (13) reach a condition number of ≈ 300. Measured at 101 samples, field
/// over direct error: 2.1 at rtol 1e-8, 2.8 at 1e-9; with the earlier
/// output (the coefficients' extension, recovered through the conditions)
/// 11.3 and 15.1 — so this test fails on that.
#[test]
fn the_fields_output_between_steps_is_as_accurate_as_direct_dop853s() {
    let binary = build_file(&model("rocket_mass"));
    let samples = ["--samples", "101"];
    let reference = run(
        &binary,
        &[
            &["--method", "direct", "--rtol", "1e-13", "--atol", "1e-15"],
            &samples[..],
        ]
        .concat(),
    );
    for (rtol, atol) in [("1e-8", "1e-10"), ("1e-9", "1e-11")] {
        let tol = ["--rtol", rtol, "--atol", atol];
        let field = run(
            &binary,
            &[&["--method", "field"], &tol[..], &samples[..]].concat(),
        );
        let direct = run(
            &binary,
            &[&["--method", "direct"], &tol[..], &samples[..]].concat(),
        );
        let (e_field, e_direct) = (
            largest_difference(&field, &reference),
            largest_difference(&direct, &reference),
        );
        eprintln!("rocket, rtol {rtol}, 101 samples: field {e_field:.2e}, direct {e_direct:.2e}");
        assert!(
            e_field <= 5.0 * e_direct,
            "rtol {rtol}: field {e_field:.2e} against direct {e_direct:.2e}"
        );
    }
}
