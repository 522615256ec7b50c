//! The stiff and extreme examples never give a wrong answer with exit 0:
//! each run — field method, direct DOP853, direct RODAS4, all at rtol
//! 1e-10, atol 1e-12 — either meets the exact solution to 1e-6 (relative
//! where |x| > 1, the generated crate's measure) or stops with exit
//! status 3 and a failure message naming the time.

use crate::generated::build;
use std::process::Command;

const STIFF_AND_EXTREME: &[&str] = &[
    "mass_gain_1000",
    "mass_gain_stiff",
    "mass_loss_stiff_spring",
    "oscillator_long",
    "paper_constant_mass_long",
    "weak_damping",
    "saturn_rocket",
    "rocket_near_burnout",
    "knife_edge_near_singular",
    "nonlinear_constraint_near_branch",
];

const METHODS: &[&[&str]] = &[
    &["--method", "field"],
    &["--method", "direct", "--integrator", "explicit"],
    &["--method", "direct", "--integrator", "stiff"],
];

/// `Ok(())` when the run is right or stops clearly; `Err` says why not.
fn right_or_clear_stop(name: &str, args: &[&str]) -> Result<(), String> {
    let binary = build(name);
    let mut all = args.to_vec();
    all.extend(["--rtol", "1e-10", "--atol", "1e-12"]);
    let output = Command::new(&binary).args(&all).output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    let label = format!("{name} {}", args.join(" "));
    match output.status.code() {
        Some(0) => {
            let error: f64 = stderr
                .lines()
                .find_map(|l| l.strip_prefix("largest error against the exact solution: "))
                .and_then(|v| v.trim().parse().ok())
                .ok_or_else(|| format!("{label}: no exact error in\n{stderr}"))?;
            if error <= 1e-6 {
                Ok(())
            } else {
                Err(format!("{label}: exit 0 with error {error:e}"))
            }
        }
        Some(3) if stderr.contains("error: at t = ") => Ok(()),
        other => Err(format!("{label}: exit {other:?}\n{stderr}")),
    }
}

#[test]
fn stiff_and_extreme_examples_are_right_or_stop_clearly() {
    let mut problems = Vec::new();
    for name in STIFF_AND_EXTREME {
        for args in METHODS {
            if let Err(problem) = right_or_clear_stop(name, args) {
                problems.push(problem);
            }
        }
    }
    assert!(problems.is_empty(), "{problems:#?}");
}

/// RODAS4 on the mass-loss spring (frequency sweeping 100-fold over ~315
/// oscillations). While the time partial ignored the mass law, RODAS4
/// fell to first order here: 10.5 million steps and an error of 2.0e-4
/// at rtol 1e-10. With the mass law's rate in `∂f/∂t` it meets the exact
/// motion to 1.2e-8 in about 209,000 steps (measured); the test asks for
/// 1e-7 well inside a quarter of the step budget, which a first-order
/// RODAS4 cannot do.
#[test]
fn rodas4_on_the_mass_loss_spring_is_accurate_within_the_budget() {
    let binary = build("mass_loss_stiff_spring");
    let output = Command::new(&binary)
        .args([
            "--method",
            "direct",
            "--integrator",
            "stiff",
            "--rtol",
            "1e-10",
            "--atol",
            "1e-12",
            "--samples",
            "2",
        ])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(0), "{stderr}");
    let error: f64 = stderr
        .lines()
        .find_map(|l| l.strip_prefix("largest error against the exact solution: "))
        .and_then(|v| v.trim().parse().ok())
        .expect("the exact error is reported");
    assert!(error <= 1e-7, "{stderr}");
    let steps: usize = stderr
        .split("steps: ")
        .nth(1)
        .and_then(|rest| rest.split_whitespace().next())
        .and_then(|n| n.parse().ok())
        .expect("the step count is reported");
    assert!(steps <= 250_000, "{stderr}");
}
