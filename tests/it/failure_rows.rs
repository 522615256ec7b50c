//! A run that stops on a failure (exit 3) writes the rows it reached
//! before it, by either method, with or without `--sensitivity`, and no
//! row at or past the failure: the constant-speed particle written on
//! its rising branch (`tests/data/textbook_constraints/
//! constant_speed_rising_branch.lag`) stops at the apex
//! t = (v/g) atanh(0.8) = 0.22398; its rows before it are checked
//! against the closed form. `--sensitivity` wrote no row at all here
//! (its augmented run failed first and the run returned before the CSV).

use crate::generated::build_file;
use std::process::Command;

const G: f64 = 9.81;
const V: f64 = 2.0;
const TIMES: [f64; 7] = [0.05, 0.1, 0.15, 0.2, 0.25, 0.3, 1.0];

/// The closed form: the reaction lies along the velocity (Chetaev), so
/// the speed stays `V` and gravity's normal part turns the heading θ,
/// `V θ' = −g cos θ`: `sin θ = tanh(u)`, `u = atanh(0.8) − g t / V`.
fn closed_form(t: f64) -> [f64; 4] {
    let a = 0.8_f64.atanh();
    let u = a - G * t / V;
    let k = V * V / G;
    let gd = |u: f64| u.sinh().atan();
    [
        k * (gd(a) - gd(u)),
        k * (a.cosh().ln() - u.cosh().ln()),
        V / u.cosh(),
        V * u.tanh(),
    ]
}

/// The CSV rows (t first) and stderr of a run, asserting exit 3.
fn rows(method: &str, rtol: f64, extra: &[&str]) -> (Vec<Vec<f64>>, String) {
    let binary = build_file(
        &crate::root().join("tests/data/textbook_constraints/constant_speed_rising_branch.lag"),
    );
    let list: Vec<String> = TIMES.iter().map(|t| format!("{t:?}")).collect();
    let out = Command::new(binary)
        .args(["--method", method, "--rtol", &format!("{rtol:e}")])
        .args(["--atol", &format!("{:e}", rtol * 1e-2)])
        .args(["--times", &list.join(",")])
        .args(extra)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(
        out.status.code(),
        Some(3),
        "{method} {rtol:e} {extra:?}: {stderr}"
    );
    let stdout = String::from_utf8(out.stdout).unwrap();
    let rows = stdout
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    (rows, stderr)
}

/// Where stderr says the run stopped.
fn stopped_at(stderr: &str) -> f64 {
    stderr
        .split("at t = ")
        .nth(1)
        .and_then(|s| s.split(':').next())
        .and_then(|s| s.trim().parse().ok())
        .unwrap_or_else(|| panic!("no time in {stderr}"))
}

#[test]
fn a_failure_keeps_the_rows_before_it_with_or_without_sensitivities() {
    let apex = V / G * 0.8_f64.atanh();
    for rtol in [1e-6, 1e-10] {
        let mut sensitivities: Vec<Vec<Vec<f64>>> = Vec::new();
        for method in ["direct", "field"] {
            for extra in [&[][..], &["--sensitivity"][..]] {
                let (rows, stderr) = rows(method, rtol, extra);
                let at = stopped_at(&stderr);
                let what = format!("{method} {rtol:e} {extra:?}");
                assert!((at - apex).abs() <= 1e-5, "{what}: stopped at {at}");
                // Every sample time before the stop, none at or after it.
                let times: Vec<f64> = rows.iter().map(|r| r[0]).collect();
                let before: Vec<f64> = TIMES.iter().copied().filter(|&t| t < at).collect();
                assert_eq!(times, before, "{what}: {stderr}");
                for row in &rows {
                    let exact = closed_form(row[0]);
                    for (i, (value, truth)) in row[1..5].iter().zip(exact).enumerate() {
                        assert!(
                            (value - truth).abs() <= 100.0 * rtol * truth.abs().max(1.0),
                            "{what}: column {i} at t = {}: {value} vs {truth}",
                            row[0]
                        );
                    }
                }
                if !extra.is_empty() {
                    assert!(rows
                        .iter()
                        .all(|r| r.len() > 5 && r.iter().all(|v| v.is_finite())));
                    sensitivities.push(rows.iter().map(|r| r[5..].to_vec()).collect());
                }
            }
        }
        // The sensitivities are the augmented system's by direct
        // integration whatever the method: the same rows.
        assert_eq!(sensitivities[0], sensitivities[1], "rtol {rtol:e}");
    }
}
