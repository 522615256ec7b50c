//! Inputs (SPEC §2.3, issue 26) through the generated crates, with both
//! methods, against closed forms: an oscillator driven by a force that a
//! CSV holds piecewise constant or interpolates linearly (exact by pieces),
//! and a velocity constraint steered by an input moving along a line (the
//! input's rate enters (4) through `D`); the run restarts at every change.

use crate::generated::build_file;
use std::path::{Path, PathBuf};
use std::process::Command;

const METHODS: [&str; 2] = ["direct", "field"];

fn model(name: &str) -> PathBuf {
    crate::root().join(format!("tests/data/{name}.lag"))
}

/// A signal file under `target/`.
fn signal(name: &str, text: &str) -> PathBuf {
    let dir = crate::root().join("target/input-signals");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

struct Run {
    rows: Vec<Vec<f64>>,
    stderr: String,
    code: i32,
}

fn run(binary: &Path, args: &[&str]) -> Run {
    let output = Command::new(binary).args(args).output().unwrap();
    let stdout = String::from_utf8(output.stdout).unwrap();
    Run {
        rows: stdout
            .lines()
            .skip(1)
            .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
            .collect(),
        stderr: String::from_utf8_lossy(&output.stderr).into_owned(),
        code: output.status.code().unwrap_or(-1),
    }
}

fn times(from: f64, to: f64, n: usize) -> String {
    (0..n)
        .map(|i| format!("{}", from + (to - from) * i as f64 / (n - 1) as f64))
        .collect::<Vec<_>>()
        .join(",")
}

/// The driven oscillator `m x'' + k x = F` with `F = c + r (t − τ)` on
/// each piece `[τ, next)`: `(x, x')` at `t` from `(0, 0)` at 0.
fn oscillator(m: f64, k: f64, pieces: &[(f64, f64, f64)], t: f64) -> (f64, f64) {
    let w = (k / m).sqrt();
    let (mut x, mut v) = (0.0, 0.0);
    for (i, &(tau, c, r)) in pieces.iter().enumerate() {
        if tau > t {
            break;
        }
        let end = pieces.get(i + 1).map_or(f64::INFINITY, |p| p.0).min(t);
        // x = (c + r s)/k + A cos ws + B sin ws, s = t − τ.
        let a = x - c / k;
        let b = (v - r / k) / w;
        let s = end - tau;
        x = (c + r * s) / k + a * (w * s).cos() + b * (w * s).sin();
        v = r / k - a * w * (w * s).sin() + b * w * (w * s).cos();
    }
    (x, v)
}

fn largest_error(rows: &[Vec<f64>], exact: impl Fn(f64) -> Vec<f64>) -> f64 {
    let mut largest = 0.0_f64;
    for row in rows {
        let truth = exact(row[0]);
        for (value, truth) in row[1..].iter().zip(&truth) {
            largest = largest.max((value - truth).abs() / truth.abs().max(1.0));
        }
    }
    largest
}

#[test]
fn a_force_held_between_rows_moves_the_oscillator_exactly_by_pieces() {
    let binary = build_file(&model("driven_oscillator"));
    // Rows where F keeps its value are no change (no restart there).
    let file = signal("held.csv", "t,F\n0,1\n1,-2\n2,-2\n3.25,0.5\n");
    let file = file.to_str().unwrap();
    let pieces = [(0.0, 1.0, 0.0), (1.0, -2.0, 0.0), (3.25, 0.5, 0.0)];
    let ts = times(0.0, 5.0, 41);
    for method in METHODS {
        let args = [
            "--method",
            method,
            "--rtol",
            "1e-10",
            "--atol",
            "1e-12",
            "--times",
            &ts,
            "--input",
            &format!("F={file}"),
        ];
        let out = run(&binary, &args);
        assert_eq!(out.code, 0, "{method}: {}", out.stderr);
        assert!(
            out.stderr.contains("inputs: restarted at 2 changes"),
            "{method}: {}",
            out.stderr
        );
        let error = largest_error(&out.rows, |t| {
            let (x, v) = oscillator(2.0, 8.0, &pieces, t);
            // The output column is the input itself, the new value from
            // its change time on.
            let f = pieces.iter().rev().find(|p| p.0 <= t).unwrap().1;
            vec![x, v, f]
        });
        assert!(error < 1e-8, "{method}: error {error:e}");
    }
}

#[test]
fn a_force_interpolated_linearly_moves_the_oscillator_exactly_by_pieces() {
    let binary = build_file(&model("driven_oscillator"));
    let file = signal("ramps.csv", "t,F\n0,0\n1.5,3\n2,-1\n4,-1\n");
    let file = file.to_str().unwrap();
    // Before the first row and after the last the values hold.
    let pieces = [
        (0.0, 0.0, 2.0),
        (1.5, 3.0, -8.0),
        (2.0, -1.0, 0.0),
        (4.0, -1.0, 0.0),
    ];
    let ts = times(0.0, 5.0, 51);
    for method in METHODS {
        let args = [
            "--method",
            method,
            "--rtol",
            "1e-10",
            "--atol",
            "1e-12",
            "--times",
            &ts,
            "--input",
            &format!("F={file}"),
            "--input-interp",
            "linear",
        ];
        let out = run(&binary, &args);
        assert_eq!(out.code, 0, "{method}: {}", out.stderr);
        let error = largest_error(&out.rows, |t| {
            let (x, v) = oscillator(2.0, 8.0, &pieces, t);
            vec![x, v]
        });
        assert!(error < 1e-8, "{method}: error {error:e}");
    }
}

#[test]
fn without_a_signal_an_input_keeps_its_default() {
    let binary = build_file(&model("driven_oscillator"));
    let ts = times(0.0, 5.0, 21);
    for method in METHODS {
        let args = [
            "--method", method, "--rtol", "1e-10", "--atol", "1e-12", "--times", &ts,
        ];
        let out = run(&binary, &args);
        assert_eq!(out.code, 0, "{method}: {}", out.stderr);
        assert!(!out.stderr.contains("restarted"), "{}", out.stderr);
        let error = largest_error(&out.rows, |t| {
            let (x, v) = oscillator(2.0, 8.0, &[(0.0, 0.5, 0.0)], t);
            vec![x, v, 0.5]
        });
        assert!(error < 1e-8, "{method}: error {error:e}");
    }
}

#[test]
fn an_input_moving_along_a_line_steers_a_velocity_constraint_through_its_rate() {
    // u = a + r t on [0, 4] (one row past the span): (4) holds the term
    // m u u' x' that only the input's rate gives.
    let binary = build_file(&model("driven_constraint"));
    let (a, r) = (-1.0, 0.75);
    let file = signal("slope.csv", &format!("t,u\n0,{a}\n5,{}\n", a + 5.0 * r));
    let file = file.to_str().unwrap();
    let ts = times(0.0, 4.0, 41);
    let c = (1.0_f64 + a * a).sqrt();
    for method in METHODS {
        let args = [
            "--method",
            method,
            "--rtol",
            "1e-10",
            "--atol",
            "1e-12",
            "--times",
            &ts,
            "--input",
            &format!("u={file}"),
            "--input-interp",
            "linear",
        ];
        let out = run(&binary, &args);
        assert_eq!(out.code, 0, "{method}: {}", out.stderr);
        let error = largest_error(&out.rows, |t| {
            let u: f64 = a + r * t;
            let s = (1.0 + u * u).sqrt();
            let x = c * (u.asinh() - a.asinh()) / r;
            let y = c * (s - c) / r;
            vec![x, y, c / s, u * c / s]
        });
        assert!(error < 1e-8, "{method}: error {error:e}");
    }
}

#[test]
fn a_held_input_in_a_velocity_constraint_moves_the_dependent_velocity_at_its_change() {
    // Held, u' = 0: x' stays 1, and y' = u x' follows u's jump (the
    // components the constraints fix are recomputed at the restart).
    let binary = build_file(&model("driven_constraint"));
    let file = signal("turn.csv", "t,u\n0,0.5\n2,-2\n");
    let file = file.to_str().unwrap();
    let ts = times(0.0, 4.0, 41);
    for method in METHODS {
        let args = [
            "--method",
            method,
            "--rtol",
            "1e-10",
            "--atol",
            "1e-12",
            "--times",
            &ts,
            "--input",
            &format!("u={file}"),
        ];
        let out = run(&binary, &args);
        assert_eq!(out.code, 0, "{method}: {}", out.stderr);
        let error = largest_error(&out.rows, |t| {
            let y = if t < 2.0 {
                0.5 * t
            } else {
                1.0 - 2.0 * (t - 2.0)
            };
            let u = if t < 2.0 { 0.5 } else { -2.0 };
            vec![t, y, 1.0, u]
        });
        assert!(error < 1e-9, "{method}: error {error:e}");
    }
}

#[test]
fn bad_input_signals_are_usage_errors() {
    let binary = build_file(&model("driven_oscillator"));
    let good = signal("good.csv", "t,F\n0,1\n");
    let cases = [
        (format!("G={}", good.display()), "no input `G` (inputs: F)"),
        (
            format!("F={}", signal("no_column.csv", "t,G\n0,1\n").display()),
            "no column `F`",
        ),
        (
            format!("F={}", signal("back.csv", "t,F\n1,1\n0,2\n").display()),
            "the times must increase",
        ),
        (
            format!("F={}", signal("word.csv", "t,F\n0,one\n").display()),
            "`one` is not a number",
        ),
        (
            "F=target/no/such/file.csv".to_string(),
            "cannot read the file",
        ),
    ];
    for (arg, message) in cases {
        let out = run(&binary, &["--input", &arg]);
        assert_eq!(out.code, 2, "{arg}: {}", out.stderr);
        assert!(out.stderr.contains(message), "{arg}: {}", out.stderr);
    }
    let out = run(&binary, &["--input-interp", "cubic"]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    // A model without inputs refuses `--input`.
    let plain = crate::generated::build("damped_oscillator");
    let out = run(&plain, &["--input", &format!("F={}", good.display())]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(
        out.stderr.contains("the model has no inputs"),
        "{}",
        out.stderr
    );
}

#[test]
fn generated_crates_with_inputs_pass_clippy() {
    for name in ["driven_oscillator", "driven_constraint"] {
        crate::generated::clippy_file(&model(name));
    }
}

#[test]
fn the_generated_model_holds_its_inputs_and_reads_them_like_params() {
    // The right side reads `self.inputs` (a load and a multiply-add per
    // input), the time partial holds `∂X/∂u · u'`, and `set_inputs` is
    // the one way the run changes them.
    let generated = crate::generated::generate_file(&model("driven_constraint"));
    insta::assert_snapshot!(generated.file("src/lib.rs").unwrap());
}
