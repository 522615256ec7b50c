//! Direct integration's global error estimate on a motion whose errors
//! are made next to poor pivots and amplified afterwards: Chaplygin's
//! sleigh (docs/BENCHMARKS.md §10o, §10s). Each run's error is every
//! column's at 201 samples against direct integration at rtol 1e-13, as
//! `scripts/all_columns_error.py` measures it.

use crate::generated::build;
use crate::rolling_bodies::{global_error_estimate, relative_error, run};

/// A direct run's error against `reference` (relative to `max(|x|, 1)`)
/// and its estimate.
fn direct_run(binary: &std::path::Path, rtol: f64, reference: &[Vec<f64>]) -> (f64, f64) {
    let (r, a) = (format!("{rtol:e}"), format!("{:e}", rtol / 100.0));
    let args = ["--method", "direct", "--rtol", &r, "--atol", &a];
    let rest = ["--samples", "201", "--summary", "json"];
    let (rows, stderr) = run(binary, &[&args[..], &rest[..]].concat());
    (
        relative_error(&rows, reference),
        global_error_estimate(&stderr),
    )
}

#[test]
fn the_sleigh_s_errors_next_to_its_poor_pivots_are_carried_by_direct_integration() {
    // At rtol 1e-11 the run ends 11 rtol off. It said "within" (0.32
    // rtol): one calibration measure late in the run, on a straight
    // stretch, scaled the spinning phase's errors 30-fold down, and the
    // errors were not carried, though the motion amplifies them. Carried
    // from its first step into a poor pivot: warned, near its error.
    let binary = build("chaplygin_sleigh");
    let tight = ["--method", "direct", "--rtol", "1e-13", "--atol", "1e-15"];
    let reference = run(&binary, &[&tight[..], &["--samples", "201"][..]].concat()).0;
    let rtol = 1e-11;
    let (error, estimate) = direct_run(&binary, rtol, &reference);
    // The case itself: a run past the bound.
    assert!(error > 10.0 * rtol, "error {:.2} rtol", error / rtol);
    assert!(
        estimate > 10.0 * rtol && estimate <= 2.0 * error,
        "error {:.2} rtol, estimate {:.2} rtol",
        error / rtol,
        estimate / rtol
    );
    // At the other tolerances the estimate is within 2× of the error
    // either way (at 1e-12 it was 0.48×: 3.3 rtol for 6.9).
    for rtol in [1e-8, 1e-10, 1e-12] {
        let (error, estimate) = direct_run(&binary, rtol, &reference);
        assert!(
            estimate >= 0.5 * error && estimate <= 2.0 * error,
            "rtol {rtol:e}: error {:.2} rtol, estimate {:.2} rtol",
            error / rtol,
            estimate / rtol
        );
    }
}
