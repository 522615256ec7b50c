//! Where a quasilinear field window ends (issue 29, docs/BENCHMARKS.md §0
//! "h-gt6"): once the conditions decline a step and its quarter fits, the
//! window ends after that quarter, as the next step's whole length would
//! be declined again (a field step's work each) before its quarter is
//! taken.

use crate::generated::build_file;
use crate::rolling_bodies::{global_error_estimate, relative_error, run};

/// The figure `key` of a run's `--summary json` line.
fn figure(stderr: &str, key: &str) -> f64 {
    let line = stderr.lines().find(|l| l.starts_with('{')).unwrap();
    let (_, rest) = line.split_once(&format!("\"{key}\":")).unwrap();
    rest.split([',', '}']).next().unwrap().parse().unwrap()
}

#[test]
fn a_window_ends_after_the_quarter_of_a_declined_step() {
    // The gravity-turn rocket's windows end on its conditions. Its first
    // window at rtol 1e-6 declined a step, took its quarter, and did so
    // six times more before its end: 14 rejected attempts in the run (28
    // at 1e-9), 12 of them declines. Ended after the first quarter: 4
    // (9), the errors the same.
    let binary = build_file(&crate::root().join("benches/data/rocket_planar_gravity_turn.lag"));
    let tight = ["--method", "direct", "--rtol", "1e-13", "--atol", "1e-15"];
    let samples = ["--samples", "101"];
    let reference = run(&binary, &[&tight[..], &samples[..]].concat()).0;
    for (rtol, most_rejected) in [(1e-6, 6.0), (1e-9, 12.0)] {
        let (r, a) = (format!("{rtol:e}"), format!("{:e}", rtol / 100.0));
        let args = ["--method", "field", "--rtol", &r, "--atol", &a];
        let (rows, stderr) = run(
            &binary,
            &[&args[..], &samples[..], &["--summary", "json"][..]].concat(),
        );
        let rejected = figure(&stderr, "rejected_steps");
        assert!(rejected <= most_rejected, "rtol {r}: {rejected} rejected");
        let error = relative_error(&rows, &reference);
        assert!(error <= rtol, "rtol {r}: error {:.2} rtol", error / rtol);
        let estimate = global_error_estimate(&stderr);
        assert!(
            estimate >= error,
            "rtol {r}: error {:.2} rtol, estimate {:.2} rtol",
            error / rtol,
            estimate / rtol
        );
    }
}
