//! Forward sensitivities (`--sensitivity`, issue 27): every column against
//! central differences of tight runs (one Richardson step, so that the
//! differences' own truncation, `O(h⁴)`, is far below the 1e-6 asked),
//! on a variable mass, non-holonomic constraints with a variable mass, a
//! velocity constraint kept by projection, a constraint of order k = 2,
//! impacts (a bouncing ball), switches (Coulomb friction), and a closed
//! form; run-time candidates across their changes; and the refusals
//! (holonomic constraints, `--ensemble`) as usage errors.

use crate::generated::build;
use std::path::Path;
use std::process::Command;

struct Run {
    header: Vec<String>,
    rows: Vec<Vec<f64>>,
    stderr: String,
    code: i32,
}

fn run(binary: &Path, args: &[&str]) -> Run {
    let output = Command::new(binary).args(args).output().unwrap();
    let stdout = String::from_utf8(output.stdout).unwrap();
    let mut lines = stdout.lines();
    let header = lines
        .next()
        .unwrap_or("")
        .split(',')
        .map(str::to_string)
        .collect();
    Run {
        header,
        rows: lines
            .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
            .collect(),
        stderr: String::from_utf8_lossy(&output.stderr).into_owned(),
        code: output.status.code().unwrap_or(-1),
    }
}

const TIGHT: [&str; 6] = ["--method", "direct", "--rtol", "1e-12", "--atol", "1e-14"];

/// The state columns of a tight run with one more `flag NAME=VALUE`.
fn states(binary: &Path, times: &str, n: usize, extra: &[String]) -> Vec<Vec<f64>> {
    let mut args: Vec<&str> = TIGHT.to_vec();
    args.extend(["--times", times]);
    args.extend(extra.iter().map(String::as_str));
    let out = run(binary, &args);
    assert_eq!(out.code, 0, "{args:?}: {}", out.stderr);
    // A run that ends early (impacts at rest) adds the row where it ends.
    let count = times.split(',').count();
    assert!(out.rows.len() >= count, "{args:?}");
    out.rows[..count]
        .iter()
        .map(|r| r[1..=n].to_vec())
        .collect()
}

/// `(flag, name, the model's value, the column's name in the header)`.
type Moved = (&'static str, &'static str, f64, &'static str);

/// The largest difference, relative to the column's largest value, between
/// each sensitivity column and the differences of runs moved along it.
fn largest_disagreement(model: &str, times: &str, moved: &[Moved]) -> f64 {
    largest_disagreement_with(model, times, 0, &[], moved)
}

/// [`largest_disagreement`] for a model with `outputs` output columns,
/// and columns `unchecked` that differences cannot check (only finite).
fn largest_disagreement_with(
    model: &str,
    times: &str,
    outputs: usize,
    unchecked: &[&str],
    moved: &[Moved],
) -> f64 {
    disagreement_of(&build(model), model, times, outputs, unchecked, moved)
}

/// [`largest_disagreement_with`] for a model's binary built already.
fn disagreement_of(
    binary: &Path,
    model: &str,
    times: &str,
    outputs: usize,
    unchecked: &[&str],
    moved: &[Moved],
) -> f64 {
    let mut args: Vec<&str> = TIGHT.to_vec();
    args.extend(["--times", times, "--sensitivity"]);
    let mut out = run(binary, &args);
    assert_eq!(out.code, 0, "{model}: {}", out.stderr);
    out.rows.truncate(times.split(',').count());
    let n = out.header[1..]
        .iter()
        .take_while(|h| !h.starts_with("d("))
        .count()
        - outputs;
    let state: Vec<String> = out.header[1..=n].to_vec();
    // Every column of S is checked: the list names them all.
    assert_eq!(
        out.header.len(),
        1 + n + outputs + n * (moved.len() + unchecked.len()),
        "{model}: {:?}",
        out.header
    );
    for column in unchecked {
        let suffix = format!("/d({column})");
        for (c, h) in out.header.iter().enumerate() {
            if h.ends_with(&suffix) {
                assert!(out.rows.iter().all(|r| r[c].is_finite()), "{model}: {h}");
            }
        }
    }
    let mut worst = 0.0_f64;
    for &(flag, name, base, column) in moved {
        let at = |v: f64| {
            states(
                binary,
                times,
                n,
                &[flag.to_string(), format!("{name}={v:?}")],
            )
        };
        // Small enough that no event crosses a sample time between the
        // runs moved, large enough that the runs' errors (1e-12) stay far
        // below the differences.
        let h = if base == 0.0 { 1e-3 } else { 1e-3 * base.abs() };
        let central = |h: f64| -> Vec<Vec<f64>> {
            let (a, b) = (at(base + h), at(base - h));
            a.iter()
                .zip(&b)
                .map(|(a, b)| a.iter().zip(b).map(|(a, b)| (a - b) / (2.0 * h)).collect())
                .collect()
        };
        let (coarse, fine) = (central(h), central(h / 2.0));
        let mut scale = 0.0_f64;
        let mut difference = 0.0_f64;
        for (r, row) in out.rows.iter().enumerate() {
            for (i, x) in state.iter().enumerate() {
                let title = format!("d({x})/d({column})");
                let c = out
                    .header
                    .iter()
                    .position(|h| *h == title)
                    .unwrap_or_else(|| panic!("{model}: no column {title}"));
                let reference = (4.0 * fine[r][i] - coarse[r][i]) / 3.0;
                scale = scale.max(reference.abs());
                difference = difference.max((row[c] - reference).abs());
            }
        }
        let relative = difference / scale.max(1e-300);
        let relative = if scale < 1e-9 { difference } else { relative };
        eprintln!("{model}: d(x)/d({column}): {relative:.2e} (scale {scale:.2e})");
        worst = worst.max(relative);
    }
    worst
}

/// With `--method field` the state columns come from the field method and
/// the sensitivities from the same augmented direct run: the largest
/// difference between the field's and the direct run's sensitivity
/// columns (relative to the largest value), the state columns checked to
/// agree to 1e-8 (both runs at rtol 1e-12).
fn field_disagreement(binary: &Path, model: &str, times: &str) -> f64 {
    let at = |method: &str| {
        let mut args: Vec<&str> = TIGHT.to_vec();
        args[1] = method;
        args.extend(["--times", times, "--sensitivity"]);
        let out = run(binary, &args);
        assert_eq!(out.code, 0, "{model} {method}: {}", out.stderr);
        out
    };
    let (direct, field) = (at("direct"), at("field"));
    assert_eq!(direct.header, field.header, "{model}");
    let first = direct
        .header
        .iter()
        .position(|h| h.starts_with("d("))
        .unwrap();
    let (mut scale, mut difference) = (0.0_f64, 0.0_f64);
    for (d, f) in direct.rows.iter().zip(&field.rows) {
        for (a, b) in d[1..first].iter().zip(&f[1..first]) {
            assert!(
                (a - b).abs() < 1e-8 * a.abs().max(1.0),
                "{model}: {d:?} {f:?}"
            );
        }
        for (a, b) in d[first..].iter().zip(&f[first..]) {
            scale = scale.max(a.abs());
            difference = difference.max((a - b).abs());
        }
    }
    assert_eq!(direct.rows.len(), field.rows.len(), "{model}");
    difference / scale.max(1e-300)
}

#[test]
fn a_variable_mass_agrees_with_differences_of_runs() {
    // The raindrop: the param t0 moves the start, so x(t) moves by
    // −X(t0, x0)·dt0 as well; c enters through the mass law alone.
    let worst = largest_disagreement(
        "raindrop",
        "2,5,10,20",
        &[
            ("--init", "z", 0.0, "z0"),
            ("--init", "z'", -9.81 / 7.0, "z'0"),
            ("--param", "c", 1e-6, "c"),
            ("--param", "g", 9.81, "g"),
            ("--param", "t0", 1.0, "t0"),
        ],
    );
    assert!(worst < 1e-6, "{worst:e}");
}

#[test]
fn a_non_holonomic_constraint_with_a_variable_mass_agrees_with_differences() {
    // paper.lag: q2' is fixed by the constraint (not a column), and moves
    // with q1'0 through it.
    let worst = largest_disagreement(
        "paper",
        "1,2.5,5",
        &[
            ("--init", "q1", 0.0, "q10"),
            ("--init", "q2", 0.0, "q20"),
            ("--init", "q1'", 1.0, "q1'0"),
            ("--param", "M0", 1.0, "M0"),
            ("--param", "alpha", 0.5, "alpha"),
        ],
    );
    assert!(worst < 1e-6, "{worst:e}");
}

#[test]
fn a_knife_edge_kept_on_its_constraint_agrees_with_differences() {
    let worst = largest_disagreement(
        "knife_edge",
        "0.5,1,2",
        &[
            ("--init", "x", 0.0, "x0"),
            ("--init", "y", 0.0, "y0"),
            ("--init", "theta", 0.0, "theta(t0)"),
            ("--init", "x'", 1.0, "x'0"),
            ("--init", "theta'", 0.5, "theta'0"),
            ("--param", "m", 1.0, "m"),
            ("--param", "J", 0.1, "J"),
            ("--param", "theta0", 0.0, "theta0"),
            ("--param", "omega", 0.5, "omega"),
            ("--param", "v0", 1.0, "v0"),
        ],
    );
    assert!(worst < 1e-6, "{worst:e}");
}

#[test]
fn a_second_order_constraint_agrees_with_differences() {
    let worst = largest_disagreement(
        "second_order_constraint",
        "1,3,5",
        &[
            ("--init", "x", 0.0, "x0"),
            ("--init", "y", 0.0, "y0"),
            ("--init", "x'", 1.0, "x'0"),
            ("--init", "y'", 2.0, "y'0"),
            ("--param", "m", 1.0, "m"),
            ("--param", "g", 1.0, "g"),
            ("--param", "v0", 1.0, "v0"),
            ("--param", "w0", 2.0, "w0"),
        ],
    );
    assert!(worst < 1e-6, "{worst:e}");
}

#[test]
fn a_bouncing_ball_agrees_with_differences_through_its_impacts() {
    // Every impact moves S by the reset's Jacobian and by the change of the
    // motion times the impact time's own sensitivity; at t = 3 the ball
    // has bounced six times. Samples between bounces.
    let worst = largest_disagreement_with(
        "bouncing_ball",
        "0.2,1,2,3",
        1,
        &[],
        &[
            ("--init", "y", 1.0, "y0"),
            ("--init", "y'", 0.0, "y'0"),
            ("--param", "g", 9.81, "g"),
            ("--param", "e", 0.8, "e"),
            ("--param", "h0", 1.0, "h0"),
        ],
    );
    assert!(worst < 1e-6, "{worst:e}");
}

#[test]
fn coulomb_friction_agrees_with_differences_through_its_switches() {
    // `sign(x')` switches where the block turns (t = π/√(k/m), …): no
    // reset, S jumps by (f⁻ − f⁺) dτ. The block starts at rest, on the
    // switching surface x' = 0: the motion is not differentiable in x'0
    // there (a run moved to x'0 = +h starts on the other branch), so that
    // column is checked for its finite values only.
    let worst = largest_disagreement_with(
        "coulomb_friction",
        "1,4,7,11",
        0,
        &["x'0"],
        &[
            ("--init", "x", 1.0, "x0"),
            ("--param", "m", 1.0, "m"),
            ("--param", "k", 1.0, "k"),
            ("--param", "mu", 0.05, "mu"),
            ("--param", "g", 2.0, "g"),
        ],
    );
    assert!(worst < 1e-6, "{worst:e}");
}

#[test]
fn a_start_on_a_switch_branch_and_a_param_start_time_agree_with_differences() {
    // The run starts on the negative branch of `sign(x)`; t0 a param moves
    // x(t) by −X(t0, x0)·dt0 with X in that branch (the model's default
    // branch gave the opposite sign).
    let binary = crate::generated::build_file(&crate::root().join("tests/data/start_switch.lag"));
    let worst = disagreement_of(
        &binary,
        "start_switch",
        "1,2.5,3,3.8",
        0,
        &[],
        &[
            ("--init", "x", -1.0, "x0"),
            ("--init", "x'", 0.0, "x'0"),
            ("--param", "t0", 0.5, "t0"),
            ("--param", "k", 1.0, "k"),
        ],
    );
    assert!(worst < 1e-6, "{worst:e}");
}

#[test]
fn the_damped_oscillator_agrees_with_its_closed_form() {
    // m x'' + c x' + k x = 0 is linear: x(t) = Φ(t) x(0), and
    // ∂x/∂x(0) = e^{−γt}(cos ω t + γ/ω sin ω t), ∂x/∂x'(0) = e^{−γt} sin(ω t)/ω.
    let binary = build("damped_oscillator");
    let times = "0,1,2.5,7,13,20";
    let mut args: Vec<&str> = TIGHT.to_vec();
    args.extend(["--times", times, "--sensitivity"]);
    let out = run(&binary, &args);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let column = |name: &str| {
        out.header
            .iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("no column {name}: {:?}", out.header))
    };
    // The model's param `x0` takes the name `x0`: the initial value's
    // column is `x(t0)`.
    let (dx_dx0, dv_dx0, dx_dv0) = (
        column("d(x)/d(x(t0))"),
        column("d(x')/d(x(t0))"),
        column("d(x)/d(x'0)"),
    );
    let (m, k, c) = (1.0_f64, 4.0_f64, 0.4_f64);
    let gam = c / (2.0 * m);
    let w = (k / m - gam * gam).sqrt();
    let mut worst = 0.0_f64;
    for row in &out.rows {
        let t = row[0];
        let decay = (-gam * t).exp();
        let (s, co) = (w * t).sin_cos();
        let exact = [
            decay * (co + gam / w * s),
            -decay * (k / m) / w * s,
            decay * s / w,
        ];
        for (&col, e) in [dx_dx0, dv_dx0, dx_dv0].iter().zip(exact) {
            worst = worst.max((row[col] - e).abs());
        }
    }
    assert!(worst < 1e-9, "{worst:e}");
    // The param `x0` moves x through the initial value only: the same
    // column as `x(t0)`'s.
    let param = column("d(x)/d(x0)");
    for row in &out.rows {
        assert!((row[param] - row[dx_dx0]).abs() < 1e-9, "{row:?}");
    }
}

/// Run-time candidates (`for y' or x'`): the heading turns through many
/// multiples of π/2 by t = 10, so the run changes which velocity the
/// constraint fixes several times. The modes integrate one state, and
/// their right sides agree on the constraint (and so their Jacobians along
/// it), so `S` goes on unchanged at a change; differences of tight runs
/// check it. Refused until 2026-11-26.
#[test]
fn a_knife_edge_changing_candidates_agrees_with_differences() {
    let worst = largest_disagreement(
        "knife_edge_turning",
        "2,5,10",
        &[
            ("--init", "x", 0.0, "x0"),
            ("--init", "y", 0.0, "y0"),
            ("--init", "th", 0.0, "th0"),
            ("--init", "x'", 1.0, "x'0"),
            ("--init", "th'", 1.0, "th'0"),
            ("--param", "w", 1.0, "w"),
        ],
    );
    assert!(worst < 1e-6, "{worst:e}");
}

/// The Chaplygin sleigh (run-time candidates, a mass off the contact
/// point): spinning at 5 rad/s, it changes candidates within a second.
#[test]
fn a_chaplygin_sleigh_changing_candidates_agrees_with_differences() {
    let worst = largest_disagreement_with(
        "chaplygin_sleigh",
        "0.5,1.5,3",
        1,
        &[],
        &[
            ("--init", "x", 0.0, "x0"),
            ("--init", "y", 0.0, "y0"),
            ("--init", "th", 0.0, "th0"),
            ("--init", "x'", 0.2, "x'0"),
            ("--init", "th'", 5.0, "th'0"),
            ("--param", "m", 1.0, "m"),
            ("--param", "a", 0.01, "a"),
            ("--param", "J", 0.02, "J"),
        ],
    );
    assert!(worst < 1e-6, "{worst:e}");
}

#[test]
fn sensitivities_are_refused_where_they_are_not_computed() {
    let cases = [(
        "damped_oscillator",
        vec!["--sensitivity", "--ensemble", "10"],
        "does not combine with `--ensemble`",
    )];
    for (model, args, message) in cases {
        let out = run(&build(model), &args);
        assert_eq!(out.code, 2, "{model}: {}", out.stderr);
        assert!(out.stderr.contains(message), "{model}: {}", out.stderr);
        assert!(out.rows.is_empty(), "{model}: no CSV");
    }
}

#[test]
fn an_undriven_input_holds_its_default_and_a_driven_run_is_refused() {
    // The driven oscillator, m x'' + k x = F with F at its default 0.5:
    // the sensitivities of the undriven run agree with differences; with
    // `--input` (a signal whose changes they do not follow yet) they are
    // refused with exit 2, never columns that ignore the signal.
    let path = crate::root().join("tests/data/driven_oscillator.lag");
    let binary = crate::generated::build_file(&path);
    let worst = disagreement_of(
        &binary,
        "driven_oscillator",
        "1,2.5,4",
        1,
        &[],
        &[
            ("--init", "x", 0.0, "x0"),
            ("--init", "x'", 0.0, "x'0"),
            ("--param", "m", 2.0, "m"),
            ("--param", "k", 8.0, "k"),
        ],
    );
    assert!(worst < 1e-6, "{worst:e}");
    let signal = std::env::temp_dir().join(format!("lagc-sens-input-{}.csv", std::process::id()));
    std::fs::write(&signal, "t,F\n0,1\n1,-2\n").unwrap();
    let input = format!("F={}", signal.display());
    let out = run(&binary, &["--sensitivity", "--input", &input]);
    let _ = std::fs::remove_file(&signal);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(
        out.stderr.contains("does not combine with `--input`"),
        "{}",
        out.stderr
    );
    assert!(out.rows.is_empty(), "no CSV");
}

/// Holonomic constraints (positions completed by Newton on the closure,
/// velocities by the constraint's derivative, candidates chosen at run
/// time): the Cartesian pendulum. `y0` only picks the root of the closure
/// (its column is zero); `l` moves the start through Newton. (Its bob
/// stays below 45°, so `y` is the dependent throughout; the particle on a
/// circle below changes it.) Refused until 2026-11-26.
#[test]
fn a_cartesian_pendulum_kept_on_its_circle_agrees_with_differences() {
    let binary = build("cartesian_pendulum");
    assert!(field_disagreement(&binary, "cartesian_pendulum", "0.5,3") < 1e-9);
    let worst = disagreement_of(
        &binary,
        "cartesian_pendulum",
        "0.5,1.5,3",
        2,
        &[],
        &[
            ("--init", "x", 0.6, "x0"),
            ("--init", "y", -0.8, "y0"),
            ("--init", "x'", 0.0, "x'0"),
            ("--param", "g", 9.81, "g"),
            ("--param", "l", 1.0, "l"),
        ],
    );
    assert!(worst < 1e-6, "{worst:e}");
}

/// Two coupled holonomic constraints (a closed loop): the crank turns, so
/// the pair of dependents changes; `b0` and `c0` only pick the loop's
/// branch (their columns are zero).
#[test]
fn a_four_bar_closure_agrees_with_differences() {
    let binary = build("four_bar_closure");
    assert!(field_disagreement(&binary, "four_bar_closure", "0.5,3") < 1e-9);
    let worst = disagreement_of(
        &binary,
        "four_bar_closure",
        "0.5,1.5,3",
        1,
        &[],
        &[
            ("--init", "a", 1.0, "a0"),
            ("--init", "b", 0.4, "b0"),
            ("--init", "c", 1.4, "c0"),
            ("--init", "a'", 3.0, "a'0"),
            ("--param", "l1", 1.0, "l1"),
            ("--param", "l2", 3.0, "l2"),
            ("--param", "l3", 2.5, "l3"),
            ("--param", "d", 3.0, "d"),
            ("--param", "m1", 1.0, "m1"),
            ("--param", "m3", 1.5, "m3"),
            ("--param", "g", 9.81, "g"),
        ],
    );
    assert!(worst < 1e-6, "{worst:e}");
}

/// A rheonomic holonomic constraint (the tube turns at `w`): the bead's
/// `x0` cannot move alone in a run (the model states `y' = r0 w`, the
/// tube's speed where the bead starts at `x0 = r0`), so its column, the
/// tangent with `x'0` held and `y0, y'0` following the constraint, is
/// checked against the closed form of the motion from `(x0, x'0)` at
/// rest across the tube: `r = x0 cosh(w t) + x'0 sinh(w t)/w` along it,
/// `x = r cos(w t)`, `y = r sin(w t)`. The params against differences of
/// runs (`r0` moves `x0` and `y'0` together).
#[test]
fn a_bead_in_a_spinning_tube_agrees_with_its_closed_form_and_differences() {
    let binary = build("bead_in_spinning_tube");
    let times = "0,0.5,1.5,3";
    assert!(field_disagreement(&binary, "bead_in_spinning_tube", times) < 1e-9);
    let worst = disagreement_of(
        &binary,
        "bead_in_spinning_tube",
        times,
        0,
        &["x0", "x'0"],
        &[
            ("--init", "y", 0.0, "y0"),
            ("--param", "w", 2.0, "w"),
            ("--param", "r0", 0.5, "r0"),
        ],
    );
    assert!(worst < 1e-6, "{worst:e}");
    let mut args: Vec<&str> = TIGHT.to_vec();
    args.extend(["--times", times, "--sensitivity"]);
    let out = run(&binary, &args);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let w = 2.0_f64;
    let mut worst = 0.0_f64;
    for row in &out.rows {
        let t = row[0];
        let (s, c) = (w * t).sin_cos();
        let (ch, sh) = ((w * t).cosh(), (w * t).sinh());
        // ∂r/∂x0 = cosh, ∂r/∂x'0 = sinh/w; r' likewise; x = r cos, y = r sin,
        // x' = r' cos − w r sin, y' = r' sin + w r cos.
        for (column, r, rd) in [("x0", ch, w * sh), ("x'0", sh / w, ch)] {
            let exact = [r * c, r * s, rd * c - w * r * s, rd * s + w * r * c];
            for (x, e) in ["x", "y", "x'", "y'"].iter().zip(exact) {
                let title = format!("d({x})/d({column})");
                let i = out.header.iter().position(|h| *h == title).unwrap();
                worst = worst.max((row[i] - e).abs() / ch.max(1.0));
            }
        }
    }
    eprintln!("bead_in_spinning_tube: x0, x'0 against the closed form: {worst:.2e}");
    assert!(worst < 1e-6, "{worst:e}");
}

/// A bead on a cycloid: two holonomic constraints with one candidate
/// each (`x`, `y` follow the rolling angle `th`), started from rest at
/// `th0` (a param: it moves the start through the closure). `x0` and `y0`
/// only seed Newton (zero columns).
#[test]
fn a_bead_on_a_cycloid_agrees_with_differences() {
    let binary = build("bead_on_cycloid");
    assert!(field_disagreement(&binary, "bead_on_cycloid", "0.5,3") < 1e-9);
    let worst = disagreement_of(
        &binary,
        "bead_on_cycloid",
        "0.5,1.5,3",
        0,
        &[],
        &[
            ("--init", "th", 2.0, "th(t0)"),
            ("--init", "x", 0.0, "x0"),
            ("--init", "y", 0.0, "y0"),
            ("--init", "th'", 0.0, "th'0"),
            ("--param", "r", 0.5, "r"),
            ("--param", "g", 9.81, "g"),
            ("--param", "th0", 2.0, "th0"),
        ],
    );
    assert!(worst < 1e-6, "{worst:e}");
}

/// Uniform motion on a circle: the dependent changes between `y` and `x`
/// every eighth of a turn (the larger pivot), four times a turn; by t = 6
/// the particle has turned almost twice.
#[test]
fn a_particle_on_a_circle_changing_its_dependent_agrees_with_differences() {
    let binary = build("particle_on_circle");
    assert!(field_disagreement(&binary, "particle_on_circle", "1,6") < 1e-9);
    let worst = disagreement_of(
        &binary,
        "particle_on_circle",
        "1,3.5,6",
        0,
        &[],
        &[
            ("--init", "x", 0.0, "x0"),
            ("--init", "y", -1.0, "y0"),
            ("--init", "x'", 2.0, "x'0"),
            ("--param", "l", 1.0, "l"),
            ("--param", "w", 2.0, "w"),
        ],
    );
    assert!(worst < 1e-6, "{worst:e}");
}

/// A holonomic constraint beside a second-order one (`z'' = x''`), no
/// params: the holonomic one kept by the projection and its derivative,
/// the other invariant under the reduced system's flow.
#[test]
fn a_holonomic_constraint_beside_a_second_order_one_agrees_with_differences() {
    let path = crate::root().join("tests/data/v2/holonomic_second_order.lag");
    let binary = crate::generated::build_file(&path);
    let worst = disagreement_of(
        &binary,
        "holonomic_second_order",
        "1,3,5",
        0,
        &[],
        &[
            ("--init", "x", 0.6, "x0"),
            ("--init", "y", -0.8, "y0"),
            ("--init", "z", 0.0, "z0"),
            ("--init", "x'", 0.0, "x'0"),
            ("--init", "z'", 0.0, "z'0"),
        ],
    );
    assert!(worst < 1e-6, "{worst:e}");
}
