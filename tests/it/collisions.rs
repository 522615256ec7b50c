//! Two balls colliding between two walls (`tests/data/two_balls_between_walls.lag`),
//! written as a user first writes a collision: one `when` per ball on one
//! condition. Every reset reads the state before the impact (SPEC §2.3):
//! applied in turn, the second ball's reset read the first ball's new
//! velocity and the momentum went from 2 to −2.06 with exit 0. No force
//! acts between impacts, so the reference here is exact: the motion is
//! followed from event to event in closed form.

use crate::generated::build_file;
use std::path::Path;
use std::process::Command;

const M1: f64 = 1.0;
const M2: f64 = 3.0;
const E: f64 = 0.9;
const EW: f64 = 0.8;
const L: f64 = 1.0;

/// The state `[x1, x2, x1', x2']` at `t`, from `x0` at 0: the next event
/// is the earliest of the balls meeting, ball 1 reaching 0 and ball 2
/// reaching L; each moves at constant velocity until then.
fn exact(t: f64) -> [f64; 4] {
    let [mut x1, mut x2, mut v1, mut v2] = [0.2, 0.6, 1.0, -0.5];
    let mut now = 0.0;
    loop {
        let meet = if v1 > v2 {
            (x2 - x1) / (v1 - v2)
        } else {
            f64::INFINITY
        };
        let wall1 = if v1 < 0.0 { -x1 / v1 } else { f64::INFINITY };
        let wall2 = if v2 > 0.0 {
            (L - x2) / v2
        } else {
            f64::INFINITY
        };
        let dt = meet.min(wall1).min(wall2);
        if now + dt >= t {
            let s = t - now;
            return [x1 + v1 * s, x2 + v2 * s, v1, v2];
        }
        x1 += v1 * dt;
        x2 += v2 * dt;
        now += dt;
        if dt == meet {
            let relative = v1 - v2;
            v1 -= (1.0 + E) * M2 / (M1 + M2) * relative;
            v2 += (1.0 + E) * M1 / (M1 + M2) * relative;
        } else if dt == wall1 {
            v1 *= -EW;
        } else {
            v2 *= -EW;
        }
    }
}

#[test]
fn two_whens_on_one_collision_read_the_velocities_before_it() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/two_balls_between_walls.lag");
    let binary = build_file(&path);
    for method in ["direct", "field"] {
        let output = Command::new(&binary)
            .args(["--method", method, "--samples", "81"])
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(output.status.success(), "{method}: {stderr}");
        let stdout = String::from_utf8(output.stdout).unwrap();
        let rows: Vec<Vec<f64>> = stdout
            .lines()
            .skip(1)
            .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
            .collect();
        assert_eq!(rows.len(), 81, "{method}: {stderr}");
        let mut worst: f64 = 0.0;
        for row in &rows {
            let want = exact(row[0]);
            for (got, want) in row[1..5].iter().zip(want) {
                worst = worst.max((got - want).abs());
            }
            // The momentum column against the exact velocities.
            let momentum = M1 * want[2] + M2 * want[3];
            worst = worst.max((row[5] - momentum).abs());
        }
        assert!(worst < 1e-8, "{method}: worst error {worst:e}\n{stderr}");
    }
}
