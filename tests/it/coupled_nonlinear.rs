//! Implicit constraints solved together, at least one not linear in its
//! candidates (`tests/data/coupled_nonlinear/`): raised, derived through
//! their derivatives (Cramer) and kept on the written forms by Newton over
//! the group's candidates (`src/mechanics/raised.rs`). The sleigh driven at
//! constant speed as a user first writes it (the knife edge and
//! `x'^2 + y'^2 = v^2`) against the reference of its solved form, and a
//! particle under a contact `z' = x y'` at constant speed against the
//! multiplier form (`scripts/coupled_nonlinear_reference.py`): both
//! methods at several rtols, every state column at every sample within
//! 10·rtol, and the written constraints (outputs) held to the tolerance
//! at every sample. With one candidate each, the group's Jacobian vanishes
//! along the contact's motion: the run stops there, exit 3.

use crate::reference_runs::{assert_within, read, scales};
use std::process::Output;

const RTOLS: [f64; 3] = [1e-6, 1e-8, 1e-10];

fn model(name: &str) -> std::path::PathBuf {
    crate::root().join(format!("tests/data/coupled_nonlinear/{name}.lag"))
}

/// The model's binary run with `method` at `rtol` (atol = rtol/100) at
/// `times`.
fn output(name: &str, method: &str, rtol: f64, times: &[f64]) -> Output {
    crate::reference_runs::output(&model(name), method, rtol, times)
}

/// Every sample of both methods at [`RTOLS`] within `10·rtol` of the
/// reference `csv` (relative to each column's largest magnitude, at least
/// 1), and the outputs, `speed2` at 1 and the others (the written
/// constraints' residuals) at 0, within `10·rtol`.
fn check(name: &str, csv: &str) {
    let (head, want) = read(csv);
    let times: Vec<f64> = want.iter().map(|w| w[0]).collect();
    let scale = scales(&head, &want);
    for method in ["direct", "field"] {
        for rtol in RTOLS {
            let (got_head, rows, stderr) =
                crate::reference_runs::run(&model(name), method, rtol, &times);
            assert_eq!(&got_head[..head.len()], head, "{name}: columns");
            assert!(got_head.len() >= head.len() + 2, "{name}: the outputs");
            let label = format!("{name} {method} rtol {rtol:e}");
            assert_within(&label, rtol, (&head, &scale), &rows, &want, &stderr);
            for row in &rows {
                let speed2 = row[head.len()];
                assert!(
                    (speed2 - 1.0).abs() <= 10.0 * rtol,
                    "{label}: off the speed at t = {}: speed² {speed2}",
                    row[0]
                );
                for (j, residual) in row.iter().enumerate().skip(head.len() + 1) {
                    assert!(
                        residual.abs() <= 10.0 * rtol,
                        "{label}: off the constraints at t = {}: {} {residual}",
                        row[0],
                        got_head[j]
                    );
                }
            }
        }
    }
}

#[test]
fn sleigh_at_constant_speed_as_first_written_follows_its_solved_form_reference() {
    check(
        "sleigh_constant_speed_written",
        "tests/data/textbook_constraints/sleigh_constant_speed.csv",
    );
}

/// A linear pair solved together beside a constant speed: raised with it,
/// kept by Newton over the pair (the base refused it, E0033).
#[test]
fn linear_pair_beside_a_constant_speed_follows_the_multiplier_form() {
    check(
        "linear_group_beside_constant_speed",
        "tests/data/coupled_nonlinear/linear_group_beside_constant_speed.csv",
    );
}

#[test]
fn particle_at_constant_speed_under_a_contact_follows_the_multiplier_form() {
    check(
        "particle_constant_speed_contact",
        "tests/data/coupled_nonlinear/particle_constant_speed_contact.csv",
    );
}

/// The reference's event `y' = 0` (SciPy, rtol 2.3e-14): where the pair's
/// Jacobian in `(z', y')`, `2 y' (1 + x²)`, vanishes.
const Y_TURNS: f64 = 0.32212126;

#[test]
fn one_choice_stops_where_the_groups_jacobian_vanishes() {
    for method in ["direct", "field"] {
        let out = output("particle_contact_one_choice", method, 1e-9, &[5.0]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(3), "{method}: {stderr}");
        let line = stderr
            .lines()
            .find(|l| l.starts_with("error: at t = "))
            .unwrap_or_else(|| panic!("{method}: {stderr}"));
        let t: f64 = line["error: at t = ".len()..]
            .split(':')
            .next()
            .unwrap()
            .parse()
            .unwrap();
        assert!((t - Y_TURNS).abs() < 1e-7, "{method}: {line}");
        assert!(
            line.contains("`z' = x * y' for z'; x'^2 + y'^2 + z'^2 = v^2 for y'`"),
            "{method}: {line}"
        );
    }
}
