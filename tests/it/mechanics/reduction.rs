//! The reduced system's forms: explicit, implicit linear, Newton, k = 3, and
//! the mass laws divided out.

use super::{derive_source, Rng};
use lagc::ir::Symbol;
use lagc::mechanics::{Highest, InitialValue};

fn jet(coord: u32, order: u32) -> Symbol {
    Symbol::Jet { coord, order }
}

/// `M0·e^{1000t}` factors out, so the right side is finite at t = 20 where
/// the law itself is far beyond f64.
#[test]
fn an_overflowing_mass_law_is_divided_out() {
    let d = derive_source(include_str!("../../../examples/mass_gain_1000.lag"));
    assert!(d.reduced.mass_laws.is_empty(), "{:?}", d.reduced.mass_laws);
    let Highest::Explicit(x) = &d.reduced.highest else {
        panic!("{:?}", d.reduced.highest)
    };
    let names = &d.arena.names().params;
    let value = |s: Symbol| match s {
        Symbol::Time => 20.0,
        Symbol::Param(i) => match names[i as usize].as_str() {
            "gam" => 1000.0,
            "w" => 1.0,
            _ => 1.0,
        },
        Symbol::Jet { order, .. } => 0.5 + f64::from(order),
        _ => f64::NAN,
    };
    let acceleration = d.arena.eval(x[0], &value);
    // x'' = -gam x' - w² x at x = 0.5, x' = 1.5.
    assert_eq!(acceleration, -1000.0 * 1.5 - 0.5);
}

/// A mass that does not factor (the spring has none) stays, with its law.
#[test]
fn a_mass_that_does_not_factor_keeps_its_law() {
    let d = derive_source(include_str!("../../../examples/mass_loss_stiff_spring.lag"));
    assert_eq!(d.divided_out, vec![None]);
    assert_eq!(d.reduced.mass_laws.len(), 1);
    assert_eq!(d.reduced.mass_laws[0].0, 0);
}

/// Two masses with a constant ratio in one row: divided by the first, the
/// second becomes the quotient of the laws (3). With
/// `E_x = M1 x'' + M2 (x'' + y'') + M1`, `E_y = M2 (x'' + y'') + M2`:
/// `x'' = M2/M1 − 1 = 2`, `y'' = −3`.
#[test]
fn two_masses_divide_out_by_their_ratio() {
    let d = derive_source(
        "param M0 = 1; param a = 0.5; coord x, y;
         mass M1 = M0 * exp(-a * t); mass M2 = 3 * M0 * exp(-a * t);
         lagrangian = M1 / 2 * x'^2 + M2 / 2 * (x' + y')^2 - M1 * x - M2 * y;
         initial x = 0, y = 0, x' = 1, y' = 1; time 0 .. 1;",
    );
    assert_eq!(d.divided_out, vec![Some(0), Some(1)]);
    assert!(d.reduced.mass_laws.is_empty());
    let Highest::Explicit(x) = &d.reduced.highest else {
        panic!()
    };
    let got: Vec<f64> = x.iter().map(|&e| d.arena.eval(e, &|_| 0.3)).collect();
    assert!(
        (got[0] - 2.0).abs() < 1e-14 && (got[1] + 3.0).abs() < 1e-14,
        "{got:?}"
    );
}

/// A non-linear second-order constraint: Newton with the symbolic Jacobian.
#[test]
fn a_nonlinear_second_order_constraint_needs_newton() {
    let d = derive_source(include_str!("../../../examples/nonlinear_second_order.lag"));
    let Highest::Implicit {
        unknowns,
        residual,
        jacobian,
        linear,
        dependent,
    } = &d.reduced.highest
    else {
        panic!("{:?}", d.reduced.highest)
    };
    assert!(!linear);
    assert_eq!(unknowns, &[jet(0, 2)]);
    assert_eq!(
        (residual.len(), jacobian.len(), jacobian[0].len()),
        (1, 1, 1)
    );
    assert_eq!(dependent.len(), 1);
    assert!(d.arena.depends_on(jacobian[0][0], jet(0, 2)));
}

/// The planar N-link pendulum with N = 3: s > 2, a full mass matrix, one
/// linear solve.
#[test]
fn three_link_pendulum_is_implicit_and_linear() {
    let d = derive_source(include_str!("../../../benches/data/pendulum_3.lag"));
    let Highest::Implicit {
        unknowns,
        jacobian,
        linear,
        ..
    } = &d.reduced.highest
    else {
        panic!("{:?}", d.reduced.highest)
    };
    assert!(linear);
    assert_eq!(unknowns.len(), 3);
    assert!(!d.arena.is_zero(jacobian[0][2]));
}

/// k = 3: `x''' = −ks x' / (m (1 + a²))`, `y''' = a x'''`, and x''(t0)
/// solved from (4).
#[test]
fn third_order_constraint() {
    let d = derive_source(include_str!("../../../examples/third_order_constraint.lag"));
    assert_eq!(d.reduced.order, 3);
    let Highest::Explicit(x) = &d.reduced.highest else {
        panic!()
    };
    assert!(matches!(d.reduced.initial[4], InitialValue::Solved));
    assert_eq!(d.reduced.consistency.len(), 1);
    let names = d.arena.names().params.clone();
    let mut rng = Rng::new(5);
    for _ in 0..50 {
        let params: Vec<f64> = (0..names.len()).map(|_| rng.range(0.5, 2.0)).collect();
        let jets: Vec<f64> = (0..6).map(|_| rng.range(-1.0, 1.0)).collect();
        let p = |name: &str| params[names.iter().position(|n| n == name).unwrap()];
        let env = |s: Symbol| match s {
            Symbol::Param(i) => params[i as usize],
            Symbol::Jet { coord, order } => jets[(2 * order + coord) as usize],
            Symbol::Time => 0.7,
            _ => f64::NAN,
        };
        let (m, ks, a) = (p("m"), p("ks"), p("a"));
        let xddd = -ks * jets[2] / (m * (1.0 + a * a));
        let got = d.arena.eval_many(x, &env);
        assert!((got[0] - xddd).abs() < 1e-12 * (1.0 + xddd.abs()));
        assert!((got[1] - a * xddd).abs() < 1e-12 * (1.0 + xddd.abs()));
        // x''(t0) = −(ks x + a m (y'' + g)) / m
        let stage = &d.reduced.consistency[0];
        let xdd = d.arena.eval(stage.explicit.as_ref().unwrap()[0], &env);
        let expected = -(ks * jets[0] + a * m * (jets[5] + p("g"))) / m;
        assert!((xdd - expected).abs() < 1e-12 * (1.0 + expected.abs()));
    }
}
