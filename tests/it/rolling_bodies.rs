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
    let rows = String::from_utf8(output.stdout)
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    (rows, stderr)
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
