//! Runs of a model's binary against a reference CSV, shared by the test
//! files of models written as a user first writes them
//! (`textbook_constraints.rs`, `coupled_nonlinear.rs`, `textbook_rolling.rs`):
//! the binary run at
//! given times with `atol = rtol/100`, the CSV's header and rows, and every
//! state column at every sample within `10·rtol` of the reference,
//! relative to the column's largest magnitude (at least 1).

use crate::generated::build_file;
use std::path::Path;
use std::process::{Command, Output};

/// The model's binary run with `method` at `rtol` (atol = rtol/100) at
/// `times`.
pub(crate) fn output(model: &Path, method: &str, rtol: f64, times: &[f64]) -> Output {
    let binary = build_file(model);
    let list: Vec<String> = times.iter().map(|t| format!("{t:?}")).collect();
    Command::new(binary)
        .args(["--method", method])
        .args([
            "--rtol",
            &format!("{rtol:e}"),
            "--atol",
            &format!("{:e}", rtol * 1e-2),
        ])
        .args(["--times", &list.join(",")])
        .output()
        .unwrap()
}

/// A CSV's header and rows.
pub(crate) fn parse(text: &str) -> (Vec<String>, Vec<Vec<f64>>) {
    let mut lines = text.lines();
    let head = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_string)
        .collect();
    let rows = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    (head, rows)
}

/// The CSV at `path` (relative to the repository): header and rows.
pub(crate) fn read(path: &str) -> (Vec<String>, Vec<Vec<f64>>) {
    let path = crate::root().join(path);
    parse(&std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display())))
}

/// [`output`]'s header and rows (t first) and stderr, asserting exit 0.
pub(crate) fn run(
    model: &Path,
    method: &str,
    rtol: f64,
    times: &[f64],
) -> (Vec<String>, Vec<Vec<f64>>, String) {
    let out = output(model, method, rtol, times);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(
        out.status.success(),
        "{} {method}: {stderr}",
        model.display()
    );
    let (head, rows) = parse(&String::from_utf8(out.stdout).unwrap());
    (head, rows, stderr)
}

/// Each column's largest magnitude in `want`, at least 1.
pub(crate) fn scales(head: &[String], want: &[Vec<f64>]) -> Vec<f64> {
    (0..head.len())
        .map(|j| want.iter().fold(1.0_f64, |m, w| m.max(w[j].abs())))
        .collect()
}

/// A run's `rows` at `want`'s times, every column of `head` (t first)
/// within `10·rtol` of `want` relative to `scale`; `label` and `stderr`
/// name the run in a failure.
pub(crate) fn assert_within(
    label: &str,
    rtol: f64,
    (head, scale): (&[String], &[f64]),
    rows: &[Vec<f64>],
    want: &[Vec<f64>],
    stderr: &str,
) {
    assert_eq!(rows.len(), want.len(), "{label}: {stderr}");
    for (row, want) in rows.iter().zip(want) {
        assert_eq!(row[0], want[0], "{label}");
        for j in 1..head.len() {
            let error = (row[j] - want[j]).abs() / scale[j];
            assert!(
                error <= 10.0 * rtol,
                "{label}: {} at t = {}: {} against {} ({:.1} rtol)\n{stderr}",
                head[j],
                row[0],
                row[j],
                want[j],
                error / rtol
            );
        }
    }
}

/// Every sample of both methods at each of `rtols` within `10·rtol` of
/// `want` (rows of t and the columns named in `head`), relative to each
/// column's largest magnitude (at least 1).
pub(crate) fn check_both_methods(model: &Path, rtols: &[f64], head: &[String], want: &[Vec<f64>]) {
    let times: Vec<f64> = want.iter().map(|w| w[0]).collect();
    let scale = scales(head, want);
    let name = model.file_stem().unwrap().to_string_lossy();
    for method in ["direct", "field"] {
        for &rtol in rtols {
            let (got_head, rows, stderr) = run(model, method, rtol, &times);
            assert_eq!(&got_head[..head.len()], head, "{name}: columns");
            let label = format!("{name} {method} rtol {rtol:e}");
            assert_within(&label, rtol, (head, &scale), &rows, want, &stderr);
        }
    }
}
