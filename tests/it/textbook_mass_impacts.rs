//! Textbook problems of variable mass, staging and impacts, written as a
//! new user first writes them (`tests/data/textbook/`, issue 29), run by
//! both methods at two tolerances and checked at many samples against
//! closed forms computed here (never against lagc itself): a two-stage
//! rocket with a coast, a chain lifted from a heap, raindrops accreting by
//! three laws, carts leaking and collecting sand, a ball bouncing down
//! stairs, a block on a spring against a wall, and Newton's cradle with
//! touching balls (whose impacts the base lagc never fired).

use crate::generated::build_file;
use std::process::Command;

const G: f64 = 9.81;

/// Runs the model's binary with `method` at `rtol` (atol = rtol/100) at
/// `times`; returns the rows (t first) and stderr, asserting exit 0.
fn run(name: &str, method: &str, rtol: f64, times: &[f64]) -> (Vec<Vec<f64>>, String) {
    let path = crate::root().join(format!("tests/data/textbook/{name}.lag"));
    let binary = build_file(&path);
    let list: Vec<String> = times.iter().map(|t| format!("{t:?}")).collect();
    let output = Command::new(binary)
        .args(["--method", method])
        .args([
            "--rtol",
            &format!("{rtol:e}"),
            "--atol",
            &format!("{:e}", rtol * 1e-2),
        ])
        .args(["--times", &list.join(",")])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    assert!(output.status.success(), "{name} {method}: {stderr}");
    let stdout = String::from_utf8(output.stdout).unwrap();
    let rows = stdout
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    (rows, stderr)
}

/// Every sample of both methods at rtol 1e-6 and 1e-10 within `10·rtol`
/// of `exact` (the state columns after t), relative to each column's
/// largest magnitude (at least 1).
fn check(name: &str, times: &[f64], exact: impl Fn(f64) -> Vec<f64>) {
    let want: Vec<Vec<f64>> = times.iter().map(|&t| exact(t)).collect();
    let columns = want[0].len();
    let scale: Vec<f64> = (0..columns)
        .map(|j| want.iter().fold(1.0_f64, |m, w| m.max(w[j].abs())))
        .collect();
    for method in ["direct", "field"] {
        for rtol in [1e-6, 1e-10] {
            let (rows, stderr) = run(name, method, rtol, times);
            // A run that stops by name (the stairs' accumulation) adds
            // its last row at the stop, after the samples.
            assert!(
                rows.len() >= times.len(),
                "{name} {method} {rtol:e}: {stderr}"
            );
            for ((row, want), &t) in rows.iter().zip(&want).zip(times) {
                assert_eq!(row[0], t, "{name} {method} {rtol:e}: {stderr}");
                for j in 0..columns {
                    let error = (row[1 + j] - want[j]).abs() / scale[j];
                    assert!(
                        error <= 10.0 * rtol,
                        "{name} {method} rtol {rtol:e}: column {j} at t = {}: {} against {} \
                         ({:.1} rtol)\n{stderr}",
                        row[0],
                        row[1 + j],
                        want[j],
                        error / rtol
                    );
                }
            }
        }
    }
}

fn samples(from: f64, to: f64, n: usize) -> Vec<f64> {
    (1..=n)
        .map(|i| from + (to - from) * i as f64 / n as f64)
        .collect()
}

/// A Tsiolkovsky burn from `(z, v)` with mass `m` losing `mu` a second at
/// exhaust speed `w`, for `s` seconds.
fn burn(z: f64, v: f64, m: f64, mu: f64, w: f64, s: f64) -> (f64, f64) {
    let ms = m - mu * s;
    (
        z + v * s - G * s * s / 2.0 + w * (s + ms / mu * (ms / m).ln()),
        v + w * (m / ms).ln() - G * s,
    )
}

fn coast(z: f64, v: f64, s: f64) -> (f64, f64) {
    (z + v * s - G * s * s / 2.0, v - G * s)
}

#[test]
fn two_stage_rocket_with_a_coast_between_the_stages() {
    let (t1, t2, t3, w) = (60.0_f64, 70.0, 130.0_f64, 2500.0);
    let exact = |t: f64| {
        let (z1, v1) = burn(0.0, 0.0, 1000.0, 8.0, w, t1.min(t));
        let (z, v) = if t < t1 {
            (z1, v1)
        } else if t < t2 {
            coast(z1, v1, t - t1)
        } else {
            let (z2, v2) = coast(z1, v1, t2 - t1);
            let (z3, v3) = burn(z2, v2, 300.0, 2.0, w, t.min(t3) - t2);
            if t < t3 {
                (z3, v3)
            } else {
                coast(z3, v3, t - t3)
            }
        };
        vec![z, v]
    };
    check("rocket_two_stage_coast", &samples(0.0, 200.0, 80), exact);
}

#[test]
fn chain_lifted_from_a_heap_decelerates_at_a_third_of_g() {
    let v0 = (20.0_f64 / 2.0).sqrt();
    let exact = |t: f64| vec![v0 * t - G * t * t / 6.0, v0 - G * t / 3.0];
    check("chain_lifted_from_heap", &samples(0.1, 0.9, 40), exact);
}

#[test]
fn raindrops_accreting_at_a_constant_rate_and_exponentially() {
    let (m0, k, lam) = (1e-3, 2e-3, 0.5_f64);
    let exact = |t: f64| {
        let u: f64 = m0 + k * t;
        vec![
            G / (2.0 * k * k) * ((u * u - m0 * m0) / 2.0 - m0 * m0 * (u / m0).ln()),
            G * t / lam - G / (lam * lam) * (-(-lam * t).exp_m1()),
            G / (2.0 * k) * (u - m0 * m0 / u),
            G / lam * (-(-lam * t).exp_m1()),
        ]
    };
    check("raindrops_two_laws", &samples(0.0, 10.0, 40), exact);
}

/// M = M0 + c x: `x'^2 = 2 g (M^3 - M0^3) / (3 c M^2)` at every sample,
/// both methods, within 10·rtol of the speed's scale.
#[test]
fn raindrop_growing_with_distance_keeps_its_speed_law() {
    let (m0, c) = (1e-3, 2e-3);
    let times = samples(0.0, 10.0, 40);
    for method in ["direct", "field"] {
        for rtol in [1e-6, 1e-10] {
            let (rows, stderr) = run("raindrop_linear_in_distance", method, rtol, &times);
            assert_eq!(rows.len(), times.len(), "{method}: {stderr}");
            let top = rows.iter().fold(1.0_f64, |m, r| m.max(r[2].abs()));
            for row in &rows {
                let m = m0 + c * row[1];
                let speed = (2.0 * G * (m.powi(3) - m0.powi(3)) / (3.0 * c * m * m)).sqrt();
                let error = (row[2] - speed).abs() / top;
                assert!(
                    error <= 10.0 * rtol,
                    "{method} {rtol:e} at t = {}: {error:e}",
                    row[0]
                );
            }
        }
    }
}

#[test]
fn cart_leaking_sand_has_no_thrust() {
    let (m0, mu, f, v0) = (100.0, 4.0, 30.0, 1.0);
    let exact = |t: f64| {
        let m: f64 = m0 - mu * t;
        vec![
            v0 * t + f / mu * (t + m / mu * (m / m0).ln()),
            v0 + f / mu * (m0 / m).ln(),
        ]
    };
    check("cart_leaking_sand", &samples(0.0, 20.0, 40), exact);
}

#[test]
fn cart_collecting_sand_keeps_its_momentum_law() {
    let (m0, mu, f, v0) = (100.0, 4.0, 30.0, 1.0);
    let exact = |t: f64| {
        let m: f64 = m0 + mu * t;
        vec![
            f * t / mu + (m0 * v0 - f * m0 / mu) / mu * (m / m0).ln(),
            (m0 * v0 + f * t) / m,
        ]
    };
    check("cart_collecting_sand", &samples(0.0, 20.0, 40), exact);
}

/// The ball on the stairs from event to event: on tread k (the last one
/// endless) it lands by the quadratic formula or leaves over the edge.
fn stairs(t: f64) -> Vec<f64> {
    let (e, h, w, u, x0) = (0.6, 0.2, 0.5, 1.0, 0.1);
    let (mut now, mut y, mut v) = (0.0_f64, 0.3_f64, 0.0_f64);
    loop {
        let x = x0 + u * now;
        let k = ((x / w + 1e-12).floor() as i32).min(3);
        let floor = -f64::from(k) * h;
        let land = (v + (v * v + 2.0 * G * (y - floor)).max(0.0).sqrt()) / G;
        let edge = if k < 3 {
            (f64::from(k + 1) * w - x) / u
        } else {
            f64::INFINITY
        };
        let s = land.min(edge);
        if now + s >= t {
            let s = t - now;
            return vec![x0 + u * t, y + v * s - G * s * s / 2.0, u, v - G * s];
        }
        now += s;
        if edge < land {
            (y, v) = (y + v * s - G * s * s / 2.0, v - G * s);
        } else {
            (y, v) = (floor, e * (G * s - v));
        }
    }
}

#[test]
fn ball_bouncing_down_stairs() {
    // The bounces accumulate on the last tread at 2.3264597: samples
    // before it (the run stops there, by name).
    check("ball_down_stairs", &samples(0.0, 2.3, 46), stairs);
}

/// The block between the spring and the wall: harmonic arcs of frequency
/// 2, each impact where x = d moving outwards.
fn spring_wall(t: f64) -> Vec<f64> {
    let (om, d, e) = (2.0_f64, 0.3, 0.7);
    let (mut now, mut x, mut v) = (0.0_f64, 0.0_f64, 1.0_f64);
    loop {
        let r = (x * x + (v / om).powi(2)).sqrt();
        let mut s = f64::INFINITY;
        if r > d {
            let phi = (v / om).atan2(x);
            s = (phi - (d / r).acos()) / om;
            while s <= 1e-12 {
                s += 2.0 * std::f64::consts::PI / om;
            }
        }
        if now + s >= t {
            let s = t - now;
            let (c, sn) = ((om * s).cos(), (om * s).sin());
            return vec![x * c + v / om * sn, -x * om * sn + v * c];
        }
        now += s;
        (x, v) = (d, -e * r * om * (d / r).acos().sin());
    }
}

#[test]
fn block_on_a_spring_against_a_wall() {
    check("spring_block_wall", &samples(0.0, 6.0, 60), spring_wall);
}

/// Newton's cradle with balls 2 and 3 touching: at t = 0.1 ball 1 strikes
/// ball 2, ball 2 at once ball 3, ball 1 at once ball 2 again; then every
/// ball moves apart at constant velocity. Before the fix the touching
/// pair's `when` held from the start and never fired: ball 2 ran through
/// ball 3 at 0.95 (x2 = 0.58 > x3 = 0.3 at t = 0.5), exit 0.
#[test]
fn newtons_cradle_with_touching_balls_fires_every_impact() {
    let (e, r) = (0.9, 0.05);
    let half = (1.0 + e) / 2.0;
    let (v1, v2) = (1.0 - half, half);
    let (v2, v3) = (v2 - half * v2, half * v2);
    let (v1, v2) = (v1 - half * (v1 - v2), v2 + half * (v1 - v2));
    let exact = |t: f64| {
        if t < 0.1 {
            vec![t, 0.2, 0.3, 1.0, 0.0, 0.0]
        } else {
            let s = t - 0.1;
            vec![0.1 + v1 * s, 0.2 + v2 * s, 0.3 + v3 * s, v1, v2, v3]
        }
    };
    let times: Vec<f64> = samples(0.0, 1.0, 40).iter().map(|t| t - 0.0123).collect();
    check("newton_cradle_touching", &times, exact);
    // And the balls never pass through each other.
    for method in ["direct", "field"] {
        let (rows, _) = run("newton_cradle_touching", method, 1e-10, &times);
        for row in &rows {
            assert!(
                row[3] - row[2] >= 2.0 * r - 1e-9,
                "{method} at t = {}",
                row[0]
            );
            assert!(
                row[2] - row[1] >= 2.0 * r - 1e-9,
                "{method} at t = {}",
                row[0]
            );
        }
    }
}

/// A ball on its floor thrown down: it bounces from t = 0 (flight n lasts
/// `2 e^n v / g`) and the run ends where the bounces accumulate, never
/// below the floor.
#[test]
fn ball_thrown_down_from_its_floor_bounces_at_once() {
    let (e, v) = (0.8_f64, 1.0);
    let times = samples(0.0, 0.8, 40);
    let t_inf = 2.0 * e * v / (G * (1.0 - e));
    let exact = |t: f64| {
        let (mut start, mut speed) = (0.0, e * v);
        loop {
            let flight = 2.0 * speed / G;
            if t < start + flight {
                let s = t - start;
                return vec![speed * s - G * s * s / 2.0, speed - G * s];
            }
            start += flight;
            speed *= e;
        }
    };
    check("ball_thrown_down_from_floor", &times, exact);
    for method in ["direct", "field"] {
        let (rows, stderr) = run("ball_thrown_down_from_floor", method, 1e-10, &times);
        let stop = rows.last().unwrap()[0];
        assert!(
            (stop - t_inf).abs() < 1e-6,
            "{method}: stopped at {stop}\n{stderr}"
        );
        assert!(stderr.contains("accumulate"), "{method}: {stderr}");
    }
}
