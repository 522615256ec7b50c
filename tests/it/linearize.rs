//! `lagc linearize` against closed forms: the eigenvalues of A at a
//! spherical pendulum's bottom, a double pendulum's normal modes (hanging
//! and inverted), a thin disk rolling upright on either side of its
//! critical speed, and Chaplygin's sleigh running straight; the ignorable
//! coordinates and the residual of steady motions; every error a request
//! can meet, rendered (snapshots). The closed forms are data here; the
//! same physics derived independently with SymPy's `linearize` is
//! `scripts/linearize_sympy.py` (its output: `docs/linearize_sympy.txt`).

use lagc::linearize::{linearize, Eigenvalue, ErrorKind, Linearization, LinearizeError, Request};

fn request(at: &str, params: &str) -> Request {
    Request {
        at: if at.is_empty() {
            vec![]
        } else {
            vec![at.to_string()]
        },
        params: if params.is_empty() {
            vec![]
        } else {
            vec![params.to_string()]
        },
        t: None,
        symbolic: false,
        inputs: vec![],
    }
}

fn run(file: &str, request: &Request) -> Result<Linearization, LinearizeError> {
    let path = crate::root().join(file);
    let source = std::fs::read_to_string(&path).expect("the model reads");
    let request = request.clone();
    lagc::on_big_stack(move || {
        let model = lagc::frontend(&source).expect("the model checks");
        let (derivation, _) = lagc::mechanics::derive_checked(&model).expect("it derives");
        linearize(&model, &derivation, &request)
    })
}

fn ok(file: &str, at: &str, params: &str) -> Linearization {
    run(file, &request(at, params)).unwrap_or_else(|e| panic!("{file} at {at}: {e}"))
}

/// Every expected eigenvalue matched by a distinct computed one within
/// 1e-8 (relative to the largest |λ|, at least 1).
fn assert_eigenvalues(l: &Linearization, expected: &[(f64, f64)], what: &str) {
    assert_eq!(l.eigenvalues.len(), expected.len(), "{what}: {l}");
    let scale = expected
        .iter()
        .map(|&(r, i)| r.hypot(i))
        .fold(1.0, f64::max);
    let mut free: Vec<Eigenvalue> = l.eigenvalues.clone();
    for &(re, im) in expected {
        let (k, d) = free
            .iter()
            .enumerate()
            .map(|(k, e)| (k, (e.re - re).hypot(e.im - im)))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .expect("an eigenvalue is left");
        assert!(
            d <= 1e-8 * scale,
            "{what}: no eigenvalue within 1e-8 of {re} + {im}i (nearest off by {d:e}):\n{l}"
        );
        free.remove(k);
    }
}

/// `±i ω` for each `ω² > 0`, `±sqrt(−ω²)` for `ω² < 0`.
fn pairs(omega_squared: &[f64]) -> Vec<(f64, f64)> {
    let mut out = Vec::new();
    for &w2 in omega_squared {
        if w2 >= 0.0 {
            out.push((0.0, w2.sqrt()));
            out.push((0.0, -w2.sqrt()));
        } else {
            out.push(((-w2).sqrt(), 0.0));
            out.push((-(-w2).sqrt(), 0.0));
        }
    }
    out
}

#[test]
fn spherical_pendulum_at_the_bottom_has_omega_squared_g_over_l_twice() {
    for (params, l, g) in [("", 1.5, 9.81), ("l=0.7,g=3", 0.7, 3.0)] {
        let lin = ok(
            "examples/spherical_pendulum.lag",
            "a=0,b=0,a'=0,b'=0",
            params,
        );
        assert_eigenvalues(&lin, &pairs(&[g / l, g / l]), "spherical pendulum");
        assert!(lin.equilibrium && lin.ignorable.is_empty(), "{lin}");
    }
}

#[test]
fn holonomic_models_eliminate_their_dependent_positions() {
    // The spherical pendulum on x² + y² + z² = l² (z dependent).
    for (params, l, g) in [("", 0.8, 9.81), ("l=2.5,g=1.6", 2.5, 1.6)] {
        let lin = ok(
            "tests/data/v2/spherical_pendulum_cartesian.lag",
            "x=0,y=0,x'=0,y'=0",
            params,
        );
        assert_eq!(lin.state, ["x", "y", "x'", "y'"], "{lin}");
        assert_eigenvalues(
            &lin,
            &pairs(&[g / l, g / l]),
            "Cartesian spherical pendulum",
        );
        assert!(lin.equilibrium, "{lin}");
    }
    // The plane pendulum x² + y² = l² (l = 1) off its bottom, against the
    // angle form θ'' = −g sin θ written in x = sin θ:
    // x'' = −g x sqrt(1 − x²) − x x'²/(1 − x²).
    let lin = ok("examples/cartesian_pendulum.lag", "x=0.6,x'=0.3", "");
    let (x, v, g) = (0.6_f64, 0.3_f64, 9.81);
    let c2 = 1.0 - x * x;
    let d_x = -g * c2.sqrt() + g * x * x / c2.sqrt() - v * v * (c2 + 2.0 * x * x) / (c2 * c2);
    let d_v = -2.0 * x * v / c2;
    let expected = [[0.0, 1.0], [d_x, d_v]];
    for (row, want) in lin.a.iter().zip(&expected) {
        for (got, want) in row.iter().zip(want) {
            assert!((got - want).abs() < 1e-12, "{lin}");
        }
    }
    let f = -g * x * c2.sqrt() - x * v * v / c2;
    assert!((lin.residual[1] - f).abs() < 1e-12, "{lin}");
}

/// `m1 l1 l2 ω⁴ − (m1+m2) g (l1+l2) ω² + (m1+m2) g² = 0` (hanging; the
/// inverted pendulum has `g → −g`).
fn double_pendulum_modes(l1: f64, l2: f64, m1: f64, m2: f64, g: f64) -> [f64; 2] {
    let (a, b, c) = (m1 * l1 * l2, -(m1 + m2) * g * (l1 + l2), (m1 + m2) * g * g);
    let root = (b * b - 4.0 * a * c).sqrt();
    [(-b - root) / (2.0 * a), (-b + root) / (2.0 * a)]
}

#[test]
fn double_pendulum_normal_modes_hanging_and_inverted() {
    let file = "examples/double_pendulum_energy.lag";
    for (params, (l1, l2, m1, m2, g)) in [
        ("", (1.0, 1.0, 1.0, 1.0, 9.81)),
        (
            "l1=1.3,l2=0.7,m1=2,m2=0.5,g=9.81",
            (1.3, 0.7, 2.0, 0.5, 9.81),
        ),
    ] {
        let hanging = ok(file, "a=0,b=0,a'=0,b'=0", params);
        let w2 = double_pendulum_modes(l1, l2, m1, m2, g);
        assert_eigenvalues(&hanging, &pairs(&w2), "double pendulum, hanging");
        let pi = std::f64::consts::PI;
        let inverted = ok(file, &format!("a={pi},b={pi},a'=0,b'=0"), params);
        assert_eigenvalues(
            &inverted,
            &pairs(&[-w2[0], -w2[1]]),
            "double pendulum, inverted",
        );
        assert!(hanging.equilibrium && inverted.equilibrium);
    }
}

/// A thin uniform disk (moments A = mR²/4 about a diameter, C = mR²/2
/// about its axle) rolling upright at spin Ω: the tilt obeys
/// `θ''' = ω²…`, `ω² = (C/A)(C + mR²)/(A + mR²) Ω² − mgR/(A + mR²)
/// = 2.4 Ω² − 0.8 g/R`; besides `±sqrt(−ω²)` two eigenvalues are 0 (the
/// spin and the heading rate are conserved to first order). Stable iff
/// `Ω² > g/(3R)`.
fn disk_omega_squared(spin: f64, r: f64, g: f64) -> f64 {
    2.4 * spin * spin - 0.8 * g / r
}

fn disk(spin: f64, params: &str) -> Linearization {
    ok(
        "examples/rolling_disk_3d.lag",
        &format!("th=0,th'=0,phi'=0,psi'={spin}"),
        params,
    )
}

#[test]
fn rolling_disk_upright_eigenvalues_and_critical_speed() {
    for (spin, params, r, g) in [
        (-4.0, "", 1.0, 9.81),
        (4.0, "", 1.0, 9.81),
        (1.5, "R=0.5,m=2", 0.5, 9.81),
        (-7.0, "R=0.2,g=3.7", 0.2, 3.7),
    ] {
        let lin = disk(spin, params);
        let mut expected = pairs(&[disk_omega_squared(spin, r, g)]);
        expected.extend([(0.0, 0.0), (0.0, 0.0)]);
        assert_eigenvalues(&lin, &expected, &format!("disk at spin {spin}, {params}"));
        let names: Vec<&str> = lin.ignorable.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["x", "y", "phi", "psi"], "{lin}");
        assert_eq!(lin.state, ["th", "phi'", "th'", "psi'"]);
        assert!(lin.equilibrium, "steady rolling has residual 0: {lin}");
    }
    // The stability changes at Ω_c² = g/(3R).
    let (r, g): (f64, f64) = (0.5, 9.81);
    let critical = (g / (3.0 * r)).sqrt();
    let largest_real = |spin: f64| {
        disk(spin, "R=0.5")
            .eigenvalues
            .iter()
            .map(|e| e.re)
            .fold(f64::NEG_INFINITY, f64::max)
    };
    assert!(largest_real(1.01 * critical) < 1e-9, "stable above Ω_c");
    assert!(largest_real(0.99 * critical) > 1e-2, "unstable below Ω_c");
}

#[test]
fn steady_rolling_linearizes_to_one_a_whatever_the_ignorable_coordinates() {
    let file = "examples/rolling_disk_3d.lag";
    let here = ok(file, "th=0,th'=0,phi'=0,psi'=-3", "");
    let there = ok(
        file,
        "x=5,y=-2,phi=2.2,psi=40,th=0,th'=0,phi'=0,psi'=-3",
        "",
    );
    for (r1, r2) in here.a.iter().zip(&there.a) {
        for (v1, v2) in r1.iter().zip(r2) {
            assert!(
                (v1 - v2).abs() <= 1e-12 * (1.0 + v1.abs()),
                "{here}\n{there}"
            );
        }
    }
    assert!(there.equilibrium, "{there}");
}

/// Chaplygin's sleigh running straight at speed v: its spin obeys
/// `ω' = −m a v/(J + m a²) ω`, the speed and heading are neutral.
#[test]
fn chaplygin_sleigh_running_straight_in_either_mode() {
    let (m, a, j) = (1.0, 0.01, 0.02);
    for (at, v) in [
        ("th=0,x'=1,th'=0", 1.0),
        ("th=0,x'=-2,th'=0", -2.0),
        ("th=1.5707963267948966,y'=1,th'=0", 1.0),
    ] {
        let lin = ok("examples/chaplygin_sleigh.lag", at, "");
        let rate = -m * a * v / (j + m * a * a);
        assert_eigenvalues(&lin, &[(rate, 0.0), (0.0, 0.0), (0.0, 0.0)], at);
        let names: Vec<&str> = lin.ignorable.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["x", "y"], "{lin}");
        assert!(lin.equilibrium, "{lin}");
    }
}

#[test]
fn a_point_off_equilibrium_says_so_with_its_residual() {
    let lin = ok("examples/spherical_pendulum.lag", "a=0.2,b=0,a'=0,b'=0", "");
    assert!(!lin.equilibrium);
    let expected = -9.81 / 1.5 * 0.2_f64.sin();
    assert!((lin.residual[2] - expected).abs() < 1e-12, "{lin}");
    assert!(lin.to_string().contains("not an equilibrium"), "{lin}");
}

#[test]
fn params_derivative_is_the_total_one() {
    // The paper's model: q1'' = (α − t/(1+t²)) q1', so ∂q1''/∂α = q1'.
    let mut req = request("q1'=2", "");
    req.t = Some("0.5".to_string());
    let lin = run("examples/paper.lag", &req).expect("linearizes");
    let alpha = lin.params.iter().position(|p| p == "alpha").expect("alpha");
    let row = lin.state.iter().position(|s| s == "q1'").expect("q1'");
    assert!((lin.b_params[row][alpha] - 2.0).abs() < 1e-12, "{lin}");
    // A at t = 0.5: ∂q1''/∂q1' = α − t/(1+t²) = 0.5 − 0.4.
    assert!((lin.a[row][row] - 0.1).abs() < 1e-12, "{lin}");
    // The rolling disk's derived params (Ia, Id, b) follow m.
    let lin = ok("examples/rolling_disk.lag", "phi'=4", "");
    let m = lin.params.iter().position(|p| p == "m").expect("m");
    let row = lin.state.iter().position(|s| s == "phi'").expect("phi'");
    // phi'' = −c phi'/(Ia + m R²) = −c phi'/(1.5 m R²): ∂/∂m = c phi'/(1.5 m² R²).
    let expected = 0.05 * 4.0 / (1.5 * 0.25);
    assert!((lin.b_params[row][m] - expected).abs() < 1e-12, "{lin}");
}

/// ∂f/∂u (issue 27): against the closed form, and against central
/// differences of the residual f in the input's value (f is evaluated
/// from the equations, ∂f/∂u from their symbolic partials).
#[test]
fn inputs_derivative_is_the_closed_form_and_the_residuals_slope() {
    let with = |file: &str, at: &str, params: &str, inputs: &str| {
        let mut req = request(at, params);
        req.inputs = vec![inputs.to_string()];
        run(file, &req).unwrap_or_else(|e| panic!("{file}: {e}"))
    };
    // m x'' + k x = F: ∂x''/∂F = 1/m.
    for (m, f) in [(2.0, 0.5), (4.0, -3.0)] {
        let file = "tests/data/driven_oscillator.lag";
        let (at, params) = ("x=0.3,x'=-1", format!("m={m}"));
        let lin = with(file, at, &params, &format!("F={f}"));
        assert_eq!(lin.inputs, ["F"]);
        let row = lin.state.iter().position(|s| s == "x'").expect("x'");
        assert!((lin.b_inputs[row][0] - 1.0 / m).abs() < 1e-14, "{lin}");
        let h = 1e-4;
        let up = with(file, at, &params, &format!("F={}", f + h));
        let down = with(file, at, &params, &format!("F={}", f - h));
        for (i, b) in lin.b_inputs.iter().enumerate() {
            let slope = (up.residual[i] - down.residual[i]) / (2.0 * h);
            assert!(
                (b[0] - slope).abs() < 1e-9,
                "row {i}: {} against {slope}",
                b[0]
            );
        }
    }
    // The path slope y'/x' = u steered from outside, a spring in y: the
    // rate of y is y' = u x' (∂/∂u = x'), and with u held
    // ∂x''/∂u = −k y (1 − u²) / (m (1 + u²)²).
    let file = "tests/data/steered_spring.lag";
    let (at, u) = ("y=0.5,x'=2", 0.3);
    let lin = with(file, at, "", &format!("u={u}"));
    let y = lin.state.iter().position(|s| s == "y").expect("y");
    let xd = lin.state.iter().position(|s| s == "x'").expect("x'");
    let (k, m, y0) = (4.0, 1.5, 0.5);
    let expected = -k * y0 * (1.0 - u * u) / (m * (1.0 + u * u) * (1.0 + u * u));
    assert!((lin.b_inputs[y][0] - 2.0).abs() < 1e-14, "{lin}");
    assert!((lin.b_inputs[xd][0] - expected).abs() < 1e-14, "{lin}");
    let h = 1e-4;
    let up = with(file, at, "", &format!("u={}", u + h));
    let down = with(file, at, "", &format!("u={}", u - h));
    for (i, b) in lin.b_inputs.iter().enumerate() {
        let slope = (up.residual[i] - down.residual[i]) / (2.0 * h);
        assert!(
            (b[0] - slope).abs() < 1e-8,
            "row {i}: {} against {slope}",
            b[0]
        );
    }
    assert!(
        lin.json().contains("\"inputs\": [\"u\"], \"B_inputs\": [["),
        "{}",
        lin.json()
    );
    // Symbolic A names the input, or substitutes its given value.
    let mut req = request(at, "");
    req.symbolic = true;
    let text = run(file, &req).expect("linearizes").to_string();
    assert!(text.contains("∂y'/∂x' = u\n"), "{text}");
    req.inputs = vec!["u=0.5".to_string()];
    let text = run(file, &req).expect("linearizes").to_string();
    assert!(text.contains("∂y'/∂x' = 0.5\n"), "{text}");
    // A model without inputs prints none; an unknown input is named.
    assert!(!ok("examples/paper.lag", "", "").json().contains("B_inputs"));
    let mut req = request("", "");
    req.inputs = vec!["G=1".to_string()];
    let err = run("tests/data/driven_oscillator.lag", &req).expect_err("unknown input");
    assert_eq!(err.kind, ErrorKind::Usage);
    insta::assert_snapshot!("linearize_error_unknown_input", err.to_string());
}

#[test]
fn json_has_the_stated_keys() {
    let lin = ok(
        "examples/rolling_disk_3d.lag",
        "th=0,th'=0,phi'=0,psi'=-4",
        "",
    );
    let json = lin.json();
    assert!(
        json.starts_with(
            "{\"state\": [\"th\", \"phi'\", \"th'\", \"psi'\"], \"ignorable\": [\"x\", \"y\", \"phi\", \"psi\"], \"A\": [["
        ),
        "{json}"
    );
    for key in [
        "\"eigenvalues\": [[",
        "\"residual\": [0.0, 0.0, 0.0, 0.0]",
        "\"B_params\"",
    ] {
        assert!(json.contains(key), "{key} in {json}");
    }
}

#[test]
fn symbolic_a_of_the_spherical_pendulum() {
    let mut req = request("b=0,b'=0", "");
    req.symbolic = true;
    let lin = run("examples/spherical_pendulum.lag", &req).expect("linearizes");
    insta::assert_snapshot!("linearize_symbolic_spherical", lin.to_string());
    insta::assert_snapshot!("linearize_symbolic_spherical_latex", lin.latex());
}

#[test]
fn text_of_the_rolling_disk() {
    let lin = ok(
        "examples/rolling_disk_3d.lag",
        "th=0,th'=0,phi'=0,psi'=-4",
        "",
    );
    insta::assert_snapshot!("linearize_rolling_disk_text", lin.to_string());
}

/// Every way a request can fail, rendered; never a panic.
#[test]
fn bad_requests_are_named() {
    // (snapshot, file, --at, --param, --t, kind)
    type Case<'a> = (
        &'a str,
        &'a str,
        &'a str,
        &'a str,
        Option<&'a str>,
        ErrorKind,
    );
    let cases: [Case; 12] = [
        (
            "singular_mass_matrix",
            "examples/rolling_disk_3d.lag",
            "",
            "m=0",
            None,
            ErrorKind::Undefined,
        ),
        (
            "unknown_state",
            "examples/double_pendulum_energy.lag",
            "c=0",
            "",
            None,
            ErrorKind::Usage,
        ),
        (
            "misspelt_state",
            "examples/double_pendulum_energy.lag",
            "aa=0",
            "",
            None,
            ErrorKind::Usage,
        ),
        (
            "param_in_at",
            "examples/double_pendulum_energy.lag",
            "g=1",
            "",
            None,
            ErrorKind::Usage,
        ),
        (
            "unknown_param",
            "examples/double_pendulum_energy.lag",
            "",
            "gg=1",
            None,
            ErrorKind::Usage,
        ),
        (
            "malformed_value",
            "examples/double_pendulum_energy.lag",
            "a=x",
            "",
            None,
            ErrorKind::Usage,
        ),
        (
            "not_name_value",
            "examples/double_pendulum_energy.lag",
            "a",
            "",
            None,
            ErrorKind::Usage,
        ),
        (
            "twice",
            "examples/double_pendulum_energy.lag",
            "a=1,a=2",
            "",
            None,
            ErrorKind::Usage,
        ),
        (
            "bad_time",
            "examples/paper.lag",
            "",
            "",
            Some("soon"),
            ErrorKind::Usage,
        ),
        (
            "off_constraint",
            "examples/rolling_disk_3d.lag",
            "psi'=1,x'=3",
            "",
            None,
            ErrorKind::Usage,
        ),
        (
            "division_by_zero",
            "examples/double_pendulum_energy.lag",
            "",
            "l1=0,l2=0",
            None,
            ErrorKind::Undefined,
        ),
        (
            "off_holonomic",
            "examples/cartesian_pendulum.lag",
            "x=0,y=-2",
            "",
            None,
            ErrorKind::Usage,
        ),
    ];
    for (name, file, at, params, t, kind) in cases {
        let mut req = request(at, params);
        req.t = t.map(str::to_string);
        let err = match run(file, &req) {
            Err(e) => e,
            Ok(l) => panic!("{name}: linearized\n{l}"),
        };
        assert_eq!(err.kind, kind, "{name}: {err}");
        insta::assert_snapshot!(format!("linearize_error_{name}"), err.to_string());
    }
}

#[test]
fn outside_a_domain_is_undefined() {
    // sqrt(l^2 - x^2) with x beyond l.
    let source = "param l = 1; param g = 9.81;\ncoord x;\nlet y = -sqrt(l^2 - x^2);\n\
                  lagrangian = (x'^2 + (y')^2) / 2 - g * y;\ninitial x = 0.5, x' = 0;\ntime 0 .. 1;\n";
    let err = lagc::on_big_stack(move || {
        let model = lagc::frontend(source).expect("checks");
        let (derivation, _) = lagc::mechanics::derive_checked(&model).expect("derives");
        linearize(&model, &derivation, &request("x=2", ""))
    })
    .expect_err("outside the domain");
    assert_eq!(err.kind, ErrorKind::Undefined, "{err}");
    insta::assert_snapshot!("linearize_error_outside_domain", err.to_string());
}

#[test]
fn the_binary_prints_json_and_exits_by_kind() {
    let lagc = |args: &[&str]| {
        std::process::Command::new(env!("CARGO_BIN_EXE_lagc"))
            .args(args)
            .current_dir(crate::root())
            .output()
            .expect("lagc runs")
    };
    let out = lagc(&[
        "linearize",
        "examples/spherical_pendulum.lag",
        "--at",
        "a=0,b=0",
        "--format",
        "json",
    ]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.starts_with("{\"state\": [\"a\", \"b\", \"a'\", \"b'\"]"),
        "{stdout}"
    );
    let out = lagc(&[
        "linearize",
        "examples/spherical_pendulum.lag",
        "--at",
        "z=0",
    ]);
    assert_eq!(out.status.code(), Some(2));
    let out = lagc(&[
        "linearize",
        "examples/double_pendulum_energy.lag",
        "--param",
        "l1=0,l2=0",
    ]);
    assert_eq!(out.status.code(), Some(3));
    let out = lagc(&["linearize", "tests/data/errors/unknown_name.lag"]);
    assert_eq!(out.status.code(), Some(1));
}

/// Every model that checks, at its initial state and at points with every
/// component 0, 1e300 or −1: an answer or a named error, never a panic.
#[test]
fn every_model_linearizes_or_says_why() {
    let mut files = Vec::new();
    for dir in [
        "examples",
        "tests/data",
        "tests/data/v2",
        "tests/data/runtime_failures",
    ] {
        files.extend(crate::expect::lag_files(dir));
    }
    let mut answered = 0;
    for path in files {
        let source = std::fs::read_to_string(&path).expect("reads");
        let outcomes = lagc::on_big_stack(move || {
            let Ok(model) = lagc::frontend(&source) else {
                return Vec::new();
            };
            let Ok((derivation, _)) = lagc::mechanics::derive_checked(&model) else {
                return Vec::new();
            };
            let names: Vec<String> = derivation
                .reduced
                .state
                .iter()
                .map(|&s| derivation.arena.symbol_name(s))
                .collect();
            let mut outcomes = vec![linearize(&model, &derivation, &Request::default()).is_ok()];
            for value in ["0", "1e300", "-1"] {
                let at: Vec<String> = names.iter().map(|n| format!("{n}={value}")).collect();
                let req = Request {
                    at: vec![at.join(",")],
                    ..Request::default()
                };
                // Fixed components given are checked against the
                // constraints: an error is an answer too.
                outcomes.push(linearize(&model, &derivation, &req).is_ok());
            }
            outcomes
        });
        if outcomes.first() == Some(&true) {
            answered += 1;
        }
    }
    assert!(
        answered > 40,
        "{answered} models linearized at their initial state"
    );
}

/// Points at rest where gravity still pulls are not equilibria: the
/// residual's rounding scale once was NaN wherever a squared velocity is
/// zero (`0 · ln 0` in the scale of `a'^2`), and every such point passed as
/// "an equilibrium": the double pendulum held horizontal, a Cartesian
/// pendulum at rest off the bottom, the paper's model at its start
/// (`q1'' = 0.5`, the scale of `t^2` at `t = 0`). Their true equilibria
/// still are.
#[test]
fn a_point_at_rest_off_equilibrium_is_not_called_one() {
    let cases = [
        (
            "examples/double_pendulum_energy.lag",
            "a=1.5707963267948966",
        ),
        ("examples/cartesian_pendulum.lag", "x=0.6,x'=0"),
        ("examples/paper.lag", "q1'=1"),
        ("examples/spherical_pendulum.lag", "a=0.2,b=0,a'=0,b'=0"),
    ];
    for (file, at) in cases {
        let lin = ok(file, at, "");
        let largest = lin.residual.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        assert!(largest > 0.1, "{file} at {at}: {lin}");
        assert!(!lin.equilibrium, "{file} at {at}: {lin}");
        assert!(lin.to_string().contains("not an equilibrium"), "{lin}");
    }
    let at_rest = [
        ("examples/double_pendulum_energy.lag", "a=0,b=0,a'=0,b'=0"),
        ("examples/cartesian_pendulum.lag", "x=0,x'=0"),
        ("examples/paper.lag", "q1'=0"),
    ];
    for (file, at) in at_rest {
        let lin = ok(file, at, "");
        assert!(lin.equilibrium, "{file} at {at}: {lin}");
    }
}
