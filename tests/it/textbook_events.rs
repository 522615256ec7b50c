//! Events as a new user first writes them (`tests/data/textbook/`, issue
//! 29), run by both methods at two tolerances and checked against closed
//! forms computed here: bounces that accumulate (restitution 1/2, the
//! accumulation at 3 T0), walls joined by `or`, two `when`s firing at one
//! instant on different coordinates, an event at the final time and at a
//! sample time, a `stop when` at the top of a throw, a ball at rest on its
//! floor, a contact that only grazes its boundary (whose impact the base
//! lagc fired on the field's rounding: 60 rtol, "within 10·rtol"), and
//! starts inside a `when`'s condition or a `stop when`'s.

use crate::generated::build_file;
use std::process::Command;

const G: f64 = 9.81;

/// A run's exit status, rows (t first) and stderr.
struct Run {
    code: i32,
    rows: Vec<Vec<f64>>,
    stderr: String,
}

fn run(name: &str, args: &[&str]) -> Run {
    let path = crate::root().join(format!("tests/data/textbook/{name}.lag"));
    let output = Command::new(build_file(&path)).args(args).output().unwrap();
    let stdout = String::from_utf8(output.stdout).unwrap();
    Run {
        code: output.status.code().unwrap_or(-1),
        rows: stdout
            .lines()
            .skip(1)
            .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
            .collect(),
        stderr: String::from_utf8_lossy(&output.stderr).into_owned(),
    }
}

/// `run` with `method` at `rtol` (atol = rtol/100) at `times`, exit 0.
fn solve(name: &str, method: &str, rtol: f64, times: &[f64]) -> Run {
    let list: Vec<String> = times.iter().map(|t| format!("{t:?}")).collect();
    let (rtol, atol) = (format!("{rtol:e}"), format!("{:e}", rtol * 1e-2));
    let args = ["--method", method, "--rtol", &rtol, "--atol", &atol];
    let joined = list.join(",");
    let out = run(name, &[&args[..], &["--times", &joined]].concat());
    assert_eq!(out.code, 0, "{name} {method}: {}", out.stderr);
    out
}

const RTOLS: [f64; 2] = [1e-6, 1e-10];

/// Every sample of both methods at [`RTOLS`] within `10·rtol` of `exact`
/// (the state columns after t), relative to each column's largest
/// magnitude (at least 1). Returns the runs' stderr.
fn check(name: &str, times: &[f64], exact: impl Fn(f64) -> Vec<f64>) -> Vec<String> {
    let want: Vec<Vec<f64>> = times.iter().map(|&t| exact(t)).collect();
    let columns = want[0].len();
    let scale: Vec<f64> = (0..columns)
        .map(|j| want.iter().fold(1.0_f64, |m, w| m.max(w[j].abs())))
        .collect();
    let mut stderrs = Vec::new();
    for method in ["direct", "field"] {
        for rtol in RTOLS {
            let out = solve(name, method, rtol, times);
            let stderr = &out.stderr;
            assert!(
                out.rows.len() >= times.len(),
                "{name} {method} {rtol:e}: {stderr}"
            );
            for ((row, want), &t) in out.rows.iter().zip(&want).zip(times) {
                assert_eq!(row[0], t, "{name} {method} {rtol:e}: {stderr}");
                for j in 0..columns {
                    let error = (row[1 + j] - want[j]).abs() / scale[j];
                    assert!(
                        error <= 10.0 * rtol,
                        "{name} {method} rtol {rtol:e}: column {j} at t = {t}: {} against {} \
                         ({:.1} rtol)\n{stderr}",
                        row[1 + j],
                        want[j],
                        error / rtol
                    );
                }
            }
            stderrs.push(out.stderr);
        }
    }
    stderrs
}

fn samples(from: f64, to: f64, n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| from + (to - from) * i as f64 / (n - 1) as f64)
        .collect()
}

/// A ball dropped from `h` at rest onto a floor at 0 with restitution `e`:
/// `(y, y')` at `t`.
fn bouncing(h: f64, e: f64, t: f64) -> [f64; 2] {
    let t0 = (2.0 * h / G).sqrt();
    if t < t0 {
        return [h - G * t * t / 2.0, -G * t];
    }
    let (mut start, mut speed) = (t0, e * G * t0);
    while t >= start + 2.0 * speed / G {
        start += 2.0 * speed / G;
        speed *= e;
    }
    let s = t - start;
    [speed * s - G * s * s / 2.0, speed - G * s]
}

#[test]
fn bounces_with_restitution_one_half_accumulate_at_three_drop_times() {
    let t0 = (2.0 / G).sqrt();
    let times = samples(0.0, 1.25, 26);
    let stderrs = check("ball_half_restitution", &times, |t| {
        bouncing(1.0, 0.5, t).to_vec()
    });
    for stderr in stderrs {
        let limit: f64 = stderr
            .split("accumulate at t ≈ ")
            .nth(1)
            .and_then(|s| s.split(':').next())
            .and_then(|s| s.parse().ok())
            .unwrap_or_else(|| panic!("no accumulation named:\n{stderr}"));
        assert!(
            (limit - 3.0 * t0).abs() < 1e-6,
            "{limit} against {}",
            3.0 * t0
        );
    }
}

#[test]
fn a_ball_between_two_walls_joined_by_or_bounces_as_a_triangle_wave() {
    let (l, v, x0) = (1.0, 2.5, 0.3);
    check("ball_between_walls", &samples(0.0, 3.0, 31), |t| {
        let m = (x0 + v * t).rem_euclid(2.0 * l);
        if m <= l {
            vec![m, v]
        } else {
            vec![2.0 * l - m, -v]
        }
    });
}

#[test]
fn two_whens_firing_at_one_instant_on_two_coordinates_both_fire() {
    check("two_balls_one_instant", &samples(0.0, 1.0, 21), |t| {
        let ([y1, v1], [y2, v2]) = (bouncing(1.0, 0.9, t), bouncing(1.0, 0.6, t));
        vec![y1, y2, v1, v2]
    });
}

#[test]
fn a_stop_when_the_velocity_turns_ends_at_the_top_of_a_throw() {
    let v = 10.0;
    for method in ["direct", "field"] {
        for rtol in RTOLS {
            let out = solve("throw_stops_at_top", method, rtol, &[0.5]);
            let last = out.rows.last().unwrap();
            let (t, y) = (v / G, v * v / (2.0 * G));
            assert!(
                (last[0] - t).abs() <= 10.0 * rtol * t,
                "{method} {rtol:e}: {last:?}"
            );
            assert!(
                (last[1] - y).abs() <= 10.0 * rtol * y,
                "{method} {rtol:e}: {last:?}"
            );
            assert!(out.stderr.contains("became true"), "{}", out.stderr);
        }
    }
}

/// Thrown up to touch a ceiling at its top: no impact fires (the base
/// fired one on the field's rounding, y' off by 60 rtol at rtol 1e-10).
#[test]
fn a_contact_that_only_grazes_its_boundary_fires_no_impact() {
    let v = (2.0 * G).sqrt();
    let mut times = samples(0.0, 0.6, 13);
    times.push(v / G);
    times.sort_by(f64::total_cmp);
    check("ball_grazing_ceiling", &times, |t| {
        vec![v * t - G * t * t / 2.0, v - G * t]
    });
}

/// An impact at the final time, and at a sample time: the row there is
/// the state before or after it, never something between.
#[test]
fn an_event_at_the_final_time_or_at_a_sample_is_either_side_of_it() {
    let either = |row: &[f64], before: f64, after: f64, rtol: f64, what: &str| {
        assert!(row[1].abs() <= 10.0 * rtol * 5.0, "{what}: {row:?}");
        let near = |v: f64| (row[2] - v).abs() <= 10.0 * rtol * before.abs().max(1.0);
        assert!(near(before) || near(after), "{what}: {row:?}");
    };
    let t0 = (2.0 / G).sqrt();
    for method in ["direct", "field"] {
        for rtol in RTOLS {
            let end = solve("ball_impact_at_end", method, rtol, &[0.5, 1.0]);
            let what = format!("at the end, {method} {rtol:e}: {}", end.stderr);
            either(end.rows.last().unwrap(), -G, 0.8 * G, rtol, &what);
            let at = solve("ball_half_restitution", method, rtol, &[0.2, t0, 0.6]);
            let what = format!("at a sample, {method} {rtol:e}: {}", at.stderr);
            either(&at.rows[1], -G * t0, 0.5 * G * t0, rtol, &what);
            let [y, v] = bouncing(1.0, 0.5, 0.6);
            assert!((at.rows[2][1] - y).abs() < 10.0 * rtol * 5.0, "{what}");
            assert!((at.rows[2][2] - v).abs() < 10.0 * rtol * 5.0, "{what}");
        }
    }
}

#[test]
fn a_ball_at_rest_on_its_floor_stops_at_once_by_name() {
    for method in ["direct", "field"] {
        let out = run("ball_resting_on_floor", &["--method", method]);
        assert_eq!(out.code, 0, "{}", out.stderr);
        assert!(out
            .rows
            .iter()
            .all(|r| r[1].abs() < 1e-12 && r[2].abs() < 1e-12));
        assert!(out.rows.last().unwrap()[0] < 1e-9, "{:?}", out.rows);
        assert!(
            out.stderr.contains("stays on its boundary") && out.stderr.contains("when y < 0"),
            "{}",
            out.stderr
        );
    }
}

/// A start inside a `when`'s condition set at run time (the file's own
/// start is checked by `lagc check`, E0043) is refused, naming the
/// condition and the values; the base let the ball fall through its
/// floor for ever, exit 0.
#[test]
fn a_start_inside_a_whens_condition_is_refused_naming_it() {
    for method in ["direct", "field"] {
        let below = run(
            "ball_half_restitution",
            &["--method", method, "--init", "y=-0.1"],
        );
        assert_eq!(below.code, 2, "{}", below.stderr);
        assert!(below.rows.is_empty());
        assert!(
            below
                .stderr
                .contains("`when y < 0` already holds at the start (y = -0.1)")
                && below
                    .stderr
                    .contains("give initial values on its other side"),
            "{}",
            below.stderr
        );
        let outside = run(
            "ball_between_walls",
            &["--method", method, "--init", "x=1.5"],
        );
        assert_eq!(outside.code, 2, "{}", outside.stderr);
        assert!(
            outside
                .stderr
                .contains("`when x < 0 or x > L` already holds at the start (x = 1.5)"),
            "{}",
            outside.stderr
        );
        // On the boundary is no start inside: the motion into it fires.
        let on = run("ball_between_walls", &["--method", method, "--init", "x=1"]);
        assert_eq!(on.code, 0, "{}", on.stderr);
    }
}

/// A `stop when` that holds at the start ends the run there, one row,
/// saying so.
#[test]
fn a_stop_when_holding_at_the_start_ends_there_saying_so() {
    for method in ["direct", "field"] {
        let out = run(
            "throw_stops_at_top",
            &["--method", method, "--init", "y'=-1"],
        );
        assert_eq!(out.code, 0, "{}", out.stderr);
        assert_eq!(out.rows, vec![vec![0.0, 0.0, -1.0]]);
        assert!(
            out.stderr
                .contains("stopped at t = 0 (`stop when` already holds at the start"),
            "{}",
            out.stderr
        );
    }
}

/// `--sensitivity` and `--ensemble` on a start on a singular point of the
/// first candidate (a pendulum in x, y released level with its pivot):
/// the base said only that Newton found no positions, or that the
/// constraint fixing `y'` had no value, not why nor what to do.
#[test]
fn sensitivity_and_ensemble_on_a_singular_start_say_why_and_what_to_do() {
    let path = crate::root().join("tests/data/v2/pendulum_released_level_as_written.lag");
    let binary = build_file(&path);
    let error_of = |args: &[&str]| {
        let output = Command::new(&binary).args(args).output().unwrap();
        assert!(!output.status.success());
        let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
        let line = stderr.lines().find(|l| l.starts_with("error"));
        (output.status.code(), line.unwrap_or_default().to_string())
    };
    let (code, sensitivity) = error_of(&["--sensitivity", "--samples", "3"]);
    assert_eq!(code, Some(3));
    insta::assert_snapshot!("sensitivity_on_singular_start", sensitivity);
    let csv = std::env::temp_dir().join(format!("lagc-ensemble-{}.csv", std::process::id()));
    let csv = csv.to_string_lossy().into_owned();
    let (code, ensemble) = error_of(&["--ensemble", "4", "-o", &csv, "--samples", "3"]);
    assert_eq!(code, Some(2));
    insta::assert_snapshot!("ensemble_on_singular_start", ensemble);
}
