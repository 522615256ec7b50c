//! A chain of five links written as a user first writes it, in Cartesian
//! coordinates with one length constraint per link (five coupled holonomic
//! constraints, solved together), against the chain in its link angles
//! integrated by SciPy (`scripts/chain_reference.py 5`: DOP853 at rtol
//! 1e-13 on the hand-derived equations; its own error 1.9e-13). lagc
//! refused this model while it solved at most four constraints together.

use crate::generated::build_file;
use crate::rolling_bodies::run;

/// The points (x_k, y_k) of the chain at four times: (t, points).
const CHAIN: [(f64, [[f64; 2]; 5]); 4] = [
    (
        0.5,
        [
            [0.1462245277415644, -0.4781405520208012],
            [0.3108407516123821, -0.9502650047221126],
            [0.539577443783708, -1.3948766618505781],
            [0.908766450181365, -1.7320701931573201],
            [1.3337549644903086, -1.9954800690266141],
        ],
    ),
    (
        1.0,
        [
            [-0.18146684145061492, -0.4659074859389334],
            [-0.4079450433240076, -0.9116738194323846],
            [-0.6569388814306607, -1.3452658726170779],
            [-1.0210625546546614, -1.687923063695656],
            [-1.5004730753181186, -1.8299285307636282],
        ],
    ),
    (
        1.5,
        [
            [-0.37504552790444384, -0.3306672829278352],
            [-0.8284973927453508, -0.5413362324014199],
            [-1.29119680514829, -0.7308336037868164],
            [-1.7401557052797243, -0.950915193186686],
            [-2.1599616963781743, -1.2225085101844506],
        ],
    ),
    (
        2.0,
        [
            [-0.12878545931185967, -0.4831296983935404],
            [-0.30189221062147265, -0.9522075732192796],
            [-0.5150771845006721, -1.4044820108256129],
            [-0.7820786862606434, -1.827223300573752],
            [-1.17819563045451, -2.132332078753786],
        ],
    ),
];

const MODEL: &str = "param g = 9.81; param l = 0.5; param m = 1;
coord x1, y1, x2, y2, x3, y3, x4, y4, x5, y5;
lagrangian = m/2*(x1'^2 + y1'^2) + m/2*(x2'^2 + y2'^2) + m/2*(x3'^2 + y3'^2)
    + m/2*(x4'^2 + y4'^2) + m/2*(x5'^2 + y5'^2) - m*g*(y1 + y2 + y3 + y4 + y5);
constraint x1^2 + y1^2 = l^2 for y1;
constraint (x2 - x1)^2 + (y2 - y1)^2 = l^2 for y2;
constraint (x3 - x2)^2 + (y3 - y2)^2 = l^2 for y3;
constraint (x4 - x3)^2 + (y4 - y3)^2 = l^2 for y4;
constraint (x5 - x4)^2 + (y5 - y4)^2 = l^2 for y5;
let s = sin(pi / 3) * l;
let c = cos(pi / 3) * l;
initial x1 = s, y1 = -c, x2 = 2*s, y2 = -2*c, x3 = 3*s, y3 = -3*c, x4 = 4*s, y4 = -4*c,
    x5 = 5*s, y5 = -5*c, x1' = 0, x2' = 0, x3' = 0, x4' = 0, x5' = 0;
time 0 .. 2;
";

#[test]
fn a_five_link_chain_in_cartesian_coordinates_follows_its_angles() {
    let dir = std::env::temp_dir().join(format!("lagc-chain-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("chain_5_cartesian.lag");
    std::fs::write(&file, MODEL).unwrap();
    let binary = build_file(&file);
    for method in ["field", "direct"] {
        let (rows, stderr) = run(
            &binary,
            &[
                "--method",
                method,
                "--rtol",
                "1e-10",
                "--atol",
                "1e-12",
                "--times",
                "0.5,1,1.5,2",
            ],
        );
        assert_eq!(rows.len(), CHAIN.len(), "{method}: {stderr}");
        let mut worst: f64 = 0.0;
        for (row, (t, points)) in rows.iter().zip(&CHAIN) {
            assert_eq!(row[0], *t);
            for (k, [x, y]) in points.iter().enumerate() {
                worst = worst
                    .max((row[1 + 2 * k] - x).abs())
                    .max((row[2 + 2 * k] - y).abs());
            }
        }
        assert!(worst < 1e-9, "{method}: worst error {worst:e}\n{stderr}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A double pendulum in Cartesian coordinates (two coupled rod
/// constraints, `tests/data/cartesian_double_pendulum.lag`) by both
/// methods, at the tolerances a user first gives (`--rtol` alone, and
/// `--atol` equal to it), every column within 10·rtol of the pendulum in
/// its angles by SciPy (`scripts/cartesian_double_pendulum_reference.py`).
/// The field's window carried a rod's velocity drift unprojected until the
/// window ended (the run projects after each advance, a window is one):
/// 52, 145, 495 and 23 rtol off here, warned, before its windows ended at
/// the first step past the projection's threshold.
#[test]
fn a_cartesian_double_pendulum_follows_its_angles() {
    let binary = build_file(&crate::root().join("tests/data/cartesian_double_pendulum.lag"));
    let reference = crate::rolling_bodies::reference_rows("cartesian_double_pendulum_scipy.csv");
    let times: Vec<String> = reference.iter().map(|r| format!("{:?}", r[0])).collect();
    let times = times.join(",");
    let tolerances: [&[&str]; 4] = [
        &["--rtol", "1e-6"],
        &["--rtol", "1e-8"],
        &["--rtol", "1e-7", "--atol", "1e-7"],
        &["--rtol", "1e-9", "--atol", "1e-9"],
    ];
    for method in ["field", "direct"] {
        for tolerance in tolerances {
            let mut args = vec!["--method", method, "--times", &times];
            args.extend_from_slice(tolerance);
            let (rows, stderr) = run(&binary, &args);
            let rtol: f64 = tolerance[1].parse().unwrap();
            let error = crate::rolling_bodies::relative_error(&rows, &reference);
            assert!(
                error <= 10.0 * rtol,
                "{method} {tolerance:?}: {:.1} rtol off\n{stderr}",
                error / rtol
            );
        }
    }
}
