//! SPEC §2.3, non-linear implicit constraints, through the generated
//! crates: kept as written at a loose tolerance, their candidate's initial
//! value checked at run time, and a motion without a closed form against a
//! reference lagc has no part in (`scripts/check_constant_speed.py`: SciPy
//! DOP853 at rtol 1e-13 on the hand-derived x'' = -A x/r, y'' = -A y/r).

use crate::generated::{build, build_file};
use crate::rolling_bodies::run;

const METHODS: [&str; 2] = ["field", "direct"];

/// The eccentric orbit (`--init "y'=1.2"`): (t, x, y, x', y').
const ECCENTRIC: [(f64, [f64; 4]); 4] = [
    (
        2.5,
        [
            -0.7572381118135726,
            0.9746454636368767,
            -0.6683941001925316,
            -0.7244124586018171,
        ],
    ),
    (
        5.0,
        [
            0.10650036455114198,
            -1.180574484620857,
            1.027185958363055,
            -0.11896234775966735,
        ],
    ),
    (
        7.5,
        [
            0.8047190911912214,
            0.6176634161464478,
            -0.8064966736029955,
            0.8721757904768667,
        ],
    ),
    (
        10.0,
        [
            -1.2541294570484731,
            0.18427838111920677,
            -0.04578395086578752,
            -0.9501116499228919,
        ],
    ),
];

/// The summary's largest residual carried, relative to the tolerance.
fn residual_relative(stderr: &str) -> f64 {
    let line = stderr
        .lines()
        .find(|l| l.starts_with("constraints kept:"))
        .unwrap_or_else(|| panic!("no residual in the summary: {stderr}"));
    let open = line.find('(').unwrap();
    line[open + 1..]
        .split_whitespace()
        .next()
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("unreadable: {line}"))
}

#[test]
fn the_speed_circle_is_kept_as_written_at_a_loose_tolerance() {
    // Differentiated alone (examples/constant_speed_through_apex.lag) the
    // speed drifts by 2e-7 here; kept, every output is on the circle.
    let binary = build("constant_speed_implicit");
    for method in METHODS {
        let (rows, stderr) = run(
            &binary,
            &[
                "--method",
                method,
                "--rtol",
                "1e-6",
                "--atol",
                "1e-9",
                "--param",
                "g=30",
                "--samples",
                "2001",
            ],
        );
        let worst = rows.iter().map(|r| (r[5] - 1.0).abs()).fold(0.0, f64::max);
        assert!(worst <= 1e-12, "{method}: |speed² − 1| up to {worst:e}");
        let relative = residual_relative(&stderr);
        assert!(
            relative <= 10.0,
            "{method}: residual {relative} of the tolerance"
        );
        // Through the apex onto the falling branch.
        let last = rows.last().unwrap();
        assert!(last[4] < -0.99, "{method}: y' = {} at the end", last[4]);
    }
}

#[test]
fn the_candidates_initial_value_chooses_the_root_and_is_checked() {
    let binary = build("constant_speed_implicit");
    // The other root: the motion starts falling, and stays on the circle.
    let (rows, _) = run(&binary, &["--init", "y'=-0.8", "--samples", "101"]);
    assert!(rows
        .iter()
        .all(|r| r[4] < 0.0 && (r[5] - 1.0).abs() <= 1e-12));
    // Off the circle: stopped before the run, naming the root near it.
    let output = std::process::Command::new(&binary)
        .args(["--init", "y'=0.7", "--samples", "2"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains(
            "the initial value `y' = 0.7` violates the constraints, which require y' = 0.8"
        ),
        "{stderr}"
    );
}

#[test]
fn an_eccentric_constant_acceleration_orbit_matches_its_scipy_reference() {
    let binary = build("constant_acceleration_orbit");
    for method in METHODS {
        let (rows, stderr) = run(
            &binary,
            &[
                "--method",
                method,
                "--rtol",
                "1e-10",
                "--atol",
                "1e-12",
                "--init",
                "y'=1.2",
                "--samples",
                "5",
            ],
        );
        for ((t, reference), row) in ECCENTRIC.iter().zip(&rows[1..]) {
            assert!((row[0] - t).abs() <= 1e-12);
            for (c, (&want, &got)) in reference.iter().zip(&row[1..5]).enumerate() {
                assert!(
                    (got - want).abs() <= 1e-8,
                    "{method}: component {c} at t = {t}: {got} against {want}"
                );
            }
            assert!((row[7] - 1.0).abs() <= 1e-12, "{method}: |a|² = {}", row[7]);
        }
        let relative = residual_relative(&stderr);
        assert!(
            relative <= 10.0,
            "{method}: residual {relative} of the tolerance"
        );
    }
}

/// A constraint written as a new user first writes it, without `for`
/// and with an expression on the left (`x'^2 + y'^2 = v^2`), is solved
/// for the highest derivatives it holds, the last declared first, as a
/// holonomic constraint is: the generated crate is byte for byte the one
/// of the same constraint with those candidates named, but for the
/// constraint's quoted text. (Until 2026-11-26 it was E0006, "a
/// constraint's left side must be a derivative of a coordinate".)
#[test]
fn a_constraint_without_for_is_solved_for_its_highest_derivatives() {
    let model = |constraint: &str| {
        format!(
            "param v = 1; param k = 1; coord x, y;\n\
             lagrangian = (x'^2 + y'^2) / 2 - k / 2 * (x^2 + y^2);\n\
             {constraint}\n\
             initial x = 1, y = 0, x' = 0, y' = 1;\ntime 0 .. 1;\n"
        )
    };
    let options = lagc::emit::EmitOptions {
        model_name: "written".to_string(),
        source_hash: "test".to_string(),
        runtime_path: "../runtime".to_string(),
        package_key: None,
    };
    let lib = |source: String| {
        let (generated, _) = lagc::on_big_stack(|| lagc::pipeline::compile(&source, &options))
            .unwrap_or_else(|d| {
                panic!("{}", lagc::diagnostic::render(&d, "x.lag", &source, false))
            });
        generated.file("src/lib.rs").unwrap().to_string()
    };
    // Non-linear, and linear with a sum on the left.
    for (written, named) in [
        (
            "constraint x'^2 + y'^2 = v^2;",
            "constraint x'^2 + y'^2 = v^2 for y' or x';",
        ),
        (
            "constraint y' + x' = v;",
            "constraint y' + x' = v for y' or x';",
        ),
    ] {
        // The generated crate quotes each constraint as written (in its
        // run-time messages); nothing else may differ.
        let named_lib = lib(model(named)).replace(" for y' or x'", "");
        assert_eq!(lib(model(written)), named_lib, "{written}");
    }
}

/// The constant-speed particle on a spring as first written (no `for`):
/// its exact motion is the unit circle, x = cos t, y = sin t.
#[test]
fn the_constant_speed_particle_written_without_for_runs_its_circle() {
    let dir = std::env::temp_dir().join(format!("lagc-speed-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("constant_speed_first_try.lag");
    std::fs::write(
        &file,
        "param v = 1; param k = 1;\ncoord x, y;\n\
         lagrangian = (x'^2 + y'^2) / 2 - k / 2 * (x^2 + y^2);\n\
         constraint x'^2 + y'^2 = v^2;\n\
         initial x = 1, y = 0, x' = 0, y' = 1;\ntime 0 .. 20;\n\
         exact x = cos(t);\nexact y = sin(t);\n",
    )
    .unwrap();
    within_1e_9_of_its_exact_lines(&file);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A second-order constraint written with the candidate a new user names
/// first, `y''`, whose pivot `y'` is 0 at the start (thrown level): it fixes
/// no initial value (`y''` is not state), so the run starts on `x''`. The
/// run stopped at t = 0 asking for a `y''` no initial value can give. With
/// gravity the constraint's force keeps the speed v: the velocity's angle
/// obeys φ' = −(g/v) cos φ, φ = −gd(g t / v).
#[test]
fn a_second_order_constraint_starts_on_its_best_candidate() {
    let dir = std::env::temp_dir().join(format!("lagc-perpendicular-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("perpendicular_acceleration.lag");
    std::fs::write(
        &file,
        "param g = 9.81; param v = 1;\ncoord x, y;\n\
         lagrangian = (x'^2 + y'^2) / 2 - g * y;\n\
         constraint x' * x'' + y' * y'' = 0 for y'' or x'';\n\
         initial x = 0, y = 0, x' = v, y' = 0;\ntime 0 .. 3;\n\
         exact x = v^2 / g * atan(sinh(g * t / v));\n\
         exact y = -v^2 / g * ln(cosh(g * t / v));\n",
    )
    .unwrap();
    within_1e_9_of_its_exact_lines(&file);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Both methods at rtol 1e-10 within 1e-9 of the model's `exact` lines.
fn within_1e_9_of_its_exact_lines(file: &std::path::Path) {
    let binary = build_file(file);
    for method in METHODS {
        let (_, stderr) = run(
            &binary,
            &[
                "--method", method, "--rtol", "1e-10", "--atol", "1e-12", "--quiet",
            ],
        );
        let error: f64 = stderr
            .lines()
            .find_map(|l| l.strip_prefix("largest error against the exact solution: "))
            .unwrap_or_else(|| panic!("{method}: no error line in {stderr}"))
            .trim()
            .parse()
            .unwrap();
        assert!(error < 1e-9, "{method}: {error:e}");
    }
}

/// A particle at constant speed thrown level (`--init x'=1 --init y'=0`,
/// `x'^2 + y'^2 = c^2 for y' or x'`): the first candidate, `y'`, has no
/// pivot there (`2 y' = 0`), and its Newton value was 0/0 — the start was
/// refused ("which require y' = NaN") though the constraint allows it; it
/// is checked in the mode the run starts in (`x'` fixed) and follows the
/// closed form `x' = c / cosh(g t / c)`, `y' = −c tanh(g t / c)`.
#[test]
fn a_constant_speed_particle_thrown_level_starts_on_its_other_candidate() {
    let binary = build("constant_speed_implicit");
    let g = 9.81;
    for method in METHODS {
        let (rows, stderr) = run(
            &binary,
            &[
                "--method",
                method,
                "--rtol",
                "1e-9",
                "--init",
                "x'=1",
                "--init",
                "y'=0",
                "--samples",
                "11",
            ],
        );
        for r in &rows {
            let gt = g * r[0];
            let want = [
                gt.sinh().atan() / g,
                -gt.cosh().ln() / g,
                1.0 / gt.cosh(),
                -gt.tanh(),
            ];
            for (got, want) in r[1..5].iter().zip(want) {
                assert!(
                    (got - want).abs() <= 1e-8,
                    "{method} at t = {}: {got} against {want}\n{stderr}",
                    r[0]
                );
            }
        }
    }
}
