//! Constrained models started where a constraint's first candidate
//! cannot be solved, written as a new user first writes them: a pendulum
//! in `x, y` released level with its pivot (`y' = -x x'/y` is 0/0 there)
//! and a double pendulum on a cart released with its second rod level
//! (the first candidates' Jacobian is singular, and the positions are on
//! the constraints only to rounding). Both were refused (E0013); with
//! every velocity given and the constraints holding, they run on the
//! candidates whose pivots do not vanish. Against a closed form and a
//! reference in the rods' angles that lagc has no part in.

use crate::generated::build_file;
use crate::rolling_bodies::run;
use std::f64::consts::PI;

const METHODS: [&str; 2] = ["field", "direct"];

/// `K(k)` by the arithmetic-geometric mean: `K = π / (2 AGM(1, sqrt(1 - k²)))`.
fn elliptic_k(k: f64) -> f64 {
    let (mut a, mut b) = (1.0_f64, (1.0 - k * k).sqrt());
    for _ in 0..40 {
        (a, b) = ((a + b) / 2.0, (a * b).sqrt());
    }
    PI / (2.0 * a)
}

#[test]
fn a_pendulum_in_x_y_released_level_with_its_pivot_reaches_the_other_side_at_its_half_period() {
    // Amplitude π/2: the period is 4 sqrt(l/g) K(sin(π/4)). Written as a
    // new user writes it (every velocity given), and with its constraint
    // solved for `x` first as E0013's help says.
    let (g, l) = (9.81_f64, 1.0_f64);
    let half_period = 2.0 * (l / g).sqrt() * elliptic_k((PI / 4.0).sin());
    let times = format!("{},{half_period}", half_period / 2.0);
    for file in [
        "tests/data/v2/pendulum_released_level_as_written.lag",
        "tests/data/v2/pendulum_released_level.lag",
    ] {
        let binary = build_file(&crate::root().join(file));
        for method in METHODS {
            let args = [
                "--method", method, "--rtol", "1e-10", "--atol", "1e-12", "--times", &times,
            ];
            let (rows, _) = run(&binary, &args);
            // At the quarter period the bob hangs straight down, at its fastest.
            let (x, y, speed) = (rows[0][1], rows[0][2], rows[0][4].hypot(rows[0][3]));
            assert!(
                x.abs() <= 1e-9 && (y + l).abs() <= 1e-9,
                "{file} {method}: ({x}, {y})"
            );
            assert!(
                (speed - (2.0 * g * l).sqrt()).abs() <= 1e-9,
                "{file} {method}: {speed}"
            );
            let (x, y) = (rows[1][1], rows[1][2]);
            assert!(
                (x + l).abs() <= 1e-9 && y.abs() <= 1e-9,
                "{file} {method}: ({x}, {y})"
            );
        }
    }
}

/// The double pendulum on a cart in the rods' angles from the downward
/// vertical (a = 0.8, b = π/2 at rest), SciPy DOP853 at rtol 2.3e-14 (its
/// difference to rtol 1e-13: 5e-13): (t, xc, x1, y1, x2, y2).
const CART_DOUBLE_PENDULUM: [(f64, [f64; 5]); 4] = [
    (
        0.5,
        [
            0.31701285985830496,
            0.40542328613784273,
            -0.9960841312484957,
            0.6442577431986567,
            -1.6540796495618548,
        ],
    ),
    (
        1.0,
        [
            0.4589690174403521,
            -0.023708446450203258,
            -0.8757981878561873,
            -0.7224027842380156,
            -0.8330638650787018,
        ],
    ),
    (
        1.5,
        [
            -0.3105649354039523,
            -0.28302609704370785,
            -0.999620734269637,
            -0.6647735259081764,
            -1.586365057254843,
        ],
    ),
    (
        2.0,
        [
            -0.7982453191226144,
            -0.6967822124294437,
            -0.9948393025912126,
            -0.02308109301774275,
            -0.8047687848789146,
        ],
    ),
];

#[test]
fn a_double_pendulum_on_a_cart_released_with_its_second_rod_level_follows_its_angle_form() {
    let binary = build_file(&crate::root().join("tests/data/v2/cart_double_pendulum_level.lag"));
    let times: Vec<String> = CART_DOUBLE_PENDULUM
        .iter()
        .map(|(t, _)| t.to_string())
        .collect();
    let times = times.join(",");
    for method in METHODS {
        let args = [
            "--method", method, "--rtol", "1e-10", "--atol", "1e-12", "--times", &times,
        ];
        let (rows, _) = run(&binary, &args);
        for (row, (t, reference)) in rows.iter().zip(&CART_DOUBLE_PENDULUM) {
            for (j, want) in reference.iter().enumerate() {
                let got = row[1 + j];
                assert!(
                    (got - want).abs() <= 1e-8,
                    "{method} at t = {t}, column {}: {got} against {want}",
                    1 + j
                );
            }
        }
    }
}
