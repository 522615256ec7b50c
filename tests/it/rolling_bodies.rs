//! Rolling bodies in Euler angles, written with SPEC §2.2's vectors, run by
//! both methods: a tilting disk against its conserved energy and against
//! the other method. (The ball on a turntable, against Routh's closed form
//! — its centre's velocity turns at 2/7 of the table's rate — states its
//! accuracy in its header: `examples/ball_on_turntable.lag`.)

use crate::generated::build;
use std::process::Command;

/// The CSV rows and the summary of a run that must succeed.
pub(crate) fn run(binary: &std::path::Path, args: &[&str]) -> (Vec<Vec<f64>>, String) {
    let output = Command::new(binary).args(args).output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    assert!(output.status.success(), "{args:?}: {stderr}");
    let rows = csv_rows(&String::from_utf8(output.stdout).unwrap());
    (rows, stderr)
}

/// A CSV's rows of numbers, its header skipped.
pub(crate) fn csv_rows(text: &str) -> Vec<Vec<f64>> {
    text.lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect()
}

/// The rows of the reference CSV `tests/data/{name}`.
pub(crate) fn reference_rows(name: &str) -> Vec<Vec<f64>> {
    let path = crate::root().join("tests/data").join(name);
    csv_rows(&std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display())))
}

/// The largest difference of a run's samples from `reference`'s over
/// every column, relative to `max(|reference|, 1)` (the estimate's
/// measure, as `scripts/all_columns_error.py` takes it).
pub(crate) fn relative_error(rows: &[Vec<f64>], reference: &[Vec<f64>]) -> f64 {
    assert_eq!(rows.len(), reference.len());
    rows.iter()
        .zip(reference)
        .flat_map(|(a, b)| a[1..].iter().zip(&b[1..]))
        .map(|(a, b)| (a - b).abs() / b.abs().max(1.0))
        .fold(0.0, f64::max)
}

/// The global error estimate of a run's `--summary json` line.
pub(crate) fn global_error_estimate(stderr: &str) -> f64 {
    let line = stderr.lines().find(|l| l.starts_with('{')).unwrap();
    let (_, rest) = line.split_once("\"global_error_estimate\":").unwrap();
    rest.split([',', '}']).next().unwrap().parse().unwrap()
}

#[test]
fn a_tilting_rolling_disk_keeps_its_energy_and_both_methods_agree() {
    let binary = build("rolling_disk_3d");
    let mut ends = Vec::new();
    for method in ["field", "direct"] {
        let (rows, _) = run(&binary, &["--method", method, "--samples", "501"]);
        let e = rows[0].len() - 1;
        let first = rows[0][e];
        let drift = rows
            .iter()
            .map(|r| (r[e] - first).abs() / first.abs())
            .fold(0.0, f64::max);
        assert!(drift < 1e-9, "{method}: energy drifts by {drift:e}");
        ends.push(rows.last().unwrap().clone());
    }
    let difference = crate::largest_difference(&ends[0], &ends[1]);
    assert!(
        difference < 1e-7,
        "field and direct differ by {difference:e}"
    );
}

#[test]
fn a_rolling_disk_s_amplified_early_errors_are_carried_by_the_field() {
    // This motion amplifies an error about 5,000-fold over its 10 s: at
    // rtol 1e-11 the field's first window's 0.006 rtol ended as most of
    // its 43 rtol, and the field, which carried its errors only once
    // their sum passed rtol, said "within" (0.8 rtol). Carried from the
    // first step: a run over 10·rtol says so, with an estimate of its
    // size (every column against direct integration at rtol 1e-13).
    let binary = build("rolling_disk_3d");
    let samples = ["--samples", "201"];
    let tight = ["--method", "direct", "--rtol", "1e-13", "--atol", "1e-15"];
    let (reference, _) = run(&binary, &[&tight[..], &samples[..]].concat());
    for rtol in [1e-11, 2e-12] {
        let (r, a) = (format!("{rtol:e}"), format!("{:e}", rtol / 100.0));
        let args = ["--method", "field", "--rtol", &r, "--atol", &a];
        let json = ["--summary", "json"];
        let (rows, stderr) = run(&binary, &[&args[..], &samples[..], &json[..]].concat());
        let error = relative_error(&rows, &reference);
        let estimate = global_error_estimate(&stderr);
        let warned = stderr.contains("passes 10·rtol");
        assert!(
            error <= 10.0 * rtol || (warned && estimate >= 0.5 * error),
            "rtol {rtol:e}: error {:.1} rtol, estimate {:.1} rtol, warned {warned}",
            error / rtol,
            estimate / rtol
        );
    }
}
