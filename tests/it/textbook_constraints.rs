//! Non-linear velocity constraints (k = 1), second-order constraints
//! (k = 2) and the v2 language, written as a new user first writes them
//! (`tests/data/textbook_constraints/`, issue 29): constant speed under
//! gravity, a spring, drag and a push; Appell and Hamel's weight on a
//! thread; constant kinetic energy in 3-D; an acceleration held
//! perpendicular to the velocity and one of fixed magnitude; a speed set
//! by height; a gearing that depends on a dependent coordinate; a sleigh
//! driven at constant speed. Both methods at rtol 1e-6 and 1e-10, every
//! state column at every sample within 10·rtol of a closed form or of a
//! reference computed independently of lagc (the multiplier form with
//! Chetaev's normals by SymPy and SciPy,
//! `scripts/textbook_constraints_reference.py`, the CSVs beside the
//! models).

use std::process::Output;

const G: f64 = 9.81;
const RTOLS: [f64; 2] = [1e-6, 1e-10];

fn model(name: &str) -> std::path::PathBuf {
    crate::root().join(format!("tests/data/textbook_constraints/{name}.lag"))
}

/// The model's binary run with `method` at `rtol` (atol = rtol/100) at
/// `times`.
fn output(name: &str, method: &str, rtol: f64, times: &[f64]) -> Output {
    crate::reference_runs::output(&model(name), method, rtol, times)
}

/// Every sample of both methods at [`RTOLS`] within `10·rtol` of `want`
/// (rows of t and the columns named in `head`).
fn check(name: &str, head: &[String], want: &[Vec<f64>]) {
    crate::reference_runs::check_both_methods(&model(name), &RTOLS, head, want);
}

/// The reference `tests/data/textbook_constraints/{csv}.csv`: header and rows.
fn reference(csv: &str) -> (Vec<String>, Vec<Vec<f64>>) {
    crate::reference_runs::read(&format!("tests/data/textbook_constraints/{csv}.csv"))
}

fn check_reference(name: &str, csv: &str) {
    let (head, rows) = reference(csv);
    check(name, &head, &rows);
}

#[test]
fn constant_speed_in_gravity_written_as_stated_follows_the_closed_form() {
    let (v, u0) = (2.0_f64, -(0.8_f64).atanh());
    let exact = |t: f64| {
        let u = G * t / v + u0;
        vec![
            t,
            v * v / G * (u.sinh().atan() - u0.sinh().atan()),
            -v * v / G * (u.cosh().ln() - u0.cosh().ln()),
            v / u.cosh(),
            -v * u.tanh(),
        ]
    };
    let want: Vec<Vec<f64>> = (0..=60).map(|i| exact(3.0 * i as f64 / 60.0)).collect();
    let head: Vec<String> = ["t", "x", "y", "x'", "y'"].map(String::from).to_vec();
    check("constant_speed_gravity", &head, &want);
}

#[test]
fn constant_speed_on_a_spring_at_velocity_and_at_acceleration_level() {
    check_reference("constant_speed_spring", "constant_speed_spring");
    check_reference("acceleration_perpendicular_spring", "constant_speed_spring");
}

#[test]
fn appell_hamel_weight_on_a_thread() {
    check_reference("appell_hamel", "appell_hamel");
}

#[test]
fn constant_kinetic_energy_in_three_dimensions() {
    check_reference("constant_kinetic_energy_3d", "constant_kinetic_energy_3d");
}

#[test]
fn acceleration_of_fixed_magnitude_with_drag() {
    check_reference("acceleration_magnitude_drag", "acceleration_magnitude_drag");
}

#[test]
fn speed_set_by_the_dependent_coordinate() {
    check_reference("speed_set_by_height", "speed_set_by_height");
}

#[test]
fn constant_speed_with_drag_and_a_periodic_push() {
    check_reference(
        "constant_speed_drag_and_push",
        "constant_speed_drag_and_push",
    );
}

#[test]
fn sleigh_at_constant_speed_solved_and_differentiated() {
    check_reference("sleigh_constant_speed", "sleigh_constant_speed");
    check_reference(
        "sleigh_constant_speed_differentiated",
        "sleigh_constant_speed",
    );
}

#[test]
fn second_order_gearing_on_the_dependent_coordinate() {
    check_reference("gearing_on_height", "gearing_on_height");
}

/// The v1 model and the same written with a velocity vector (whose `.x`
/// the base refused in the constraint's right side): the reference, and
/// the same bits from both.
#[test]
fn constant_speed_in_v1_and_with_lets_agree_bit_for_bit() {
    check_reference("constant_speed_v1", "constant_speed_v1");
    let (_, rows) = reference("constant_speed_v1");
    let times: Vec<f64> = rows.iter().map(|r| r[0]).collect();
    for method in ["direct", "field"] {
        for rtol in RTOLS {
            let v1 = output("constant_speed_v1", method, rtol, &times);
            let lets = output("constant_speed_lets", method, rtol, &times);
            assert!(v1.status.success() && lets.status.success());
            assert_eq!(v1.stdout, lets.stdout, "{method} {rtol:e}");
        }
    }
}

/// The rising branch `y' = sqrt(v^2 - x'^2)` ends at the apex: both
/// methods stop there (exit 3) naming the constraint, never going on.
#[test]
fn constant_speed_on_its_rising_branch_stops_at_the_apex() {
    let apex = 2.0 / G * 0.8_f64.atanh();
    for method in ["direct", "field"] {
        for rtol in RTOLS {
            let out = output(
                "constant_speed_rising_branch",
                method,
                rtol,
                &[0.1, 0.2, 0.3, 1.0],
            );
            let stderr = String::from_utf8_lossy(&out.stderr);
            assert_eq!(out.status.code(), Some(3), "{method} {rtol:e}: {stderr}");
            assert!(
                stderr.contains("y' = sqrt(v^2 - x'^2)") && stderr.contains("end of its branch"),
                "{method} {rtol:e}: {stderr}"
            );
            let at: f64 = stderr
                .split("at t = ")
                .nth(1)
                .and_then(|s| s.split(':').next())
                .and_then(|s| s.trim().parse().ok())
                .unwrap_or_else(|| panic!("{method} {rtol:e}: no time in {stderr}"));
            assert!(
                (at - apex).abs() <= 1e-5,
                "{method} {rtol:e}: stopped at {at}, apex {apex}"
            );
        }
    }
}
