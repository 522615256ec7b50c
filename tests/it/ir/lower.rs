//! AST → IR, and the paper's equation (4) worked through the IR API.

use super::{env_at, q};
use lagc::check::model::{Coord, MassLaw, Model, Name, Param, TimeSpan};
use lagc::ir::{lower, names_of, try_lower, Arena, Func, Symbol};
use lagc::span::Span;
use lagc::syntax::ast::{BinOp, Builtin, Expr, ExprKind, Ident};
use std::collections::HashMap;

fn e(kind: ExprKind) -> Expr {
    Expr {
        kind,
        span: Span::default(),
    }
}

fn var(name: &str, primes: u32) -> Expr {
    e(ExprKind::Var {
        name: Ident {
            name: name.into(),
            span: Span::default(),
        },
        primes,
    })
}

fn n(v: f64) -> Expr {
    e(ExprKind::Number(v))
}

fn bin(op: BinOp, lhs: Expr, rhs: Expr) -> Expr {
    e(ExprKind::Binary {
        op,
        lhs: Box::new(lhs),
        rhs: Box::new(rhs),
    })
}

fn call(func: Func, arg: Expr) -> Expr {
    e(ExprKind::Call {
        func: Builtin::Elementary(func),
        func_span: Span::default(),
        args: vec![arg],
    })
}

/// The paper's model: `M = M0*exp(-alpha*t)`, `L = M/2*(q1'^2 + q2'^2)`.
fn paper_model() -> Model {
    let law = bin(
        BinOp::Mul,
        var("M0", 0),
        call(
            Func::Exp,
            e(ExprKind::Neg(Box::new(bin(
                BinOp::Mul,
                var("alpha", 0),
                var("t", 0),
            )))),
        ),
    );
    let lagrangian = bin(
        BinOp::Mul,
        bin(BinOp::Div, var("M", 0), n(2.0)),
        bin(
            BinOp::Add,
            bin(BinOp::Pow, var("q1", 1), n(2.0)),
            bin(BinOp::Pow, var("q2", 1), n(2.0)),
        ),
    );
    let param = |name: &str, default: f64| Param {
        name: name.into(),
        span: Span::default(),
        value: n(default),
        default,
        tunable: false,
    };
    let coord = |name: &str| Coord {
        name: name.into(),
        span: Span::default(),
    };
    Model {
        params: vec![param("M0", 1.0), param("alpha", 0.5)],
        inputs: Vec::new(),
        coords: vec![coord("q1"), coord("q2")],
        masses: vec![MassLaw {
            name: "M".into(),
            span: Span::default(),
            law,
        }],
        lagrangian,
        constraint_order: Some(1),
        constraints: Vec::new(),
        groups: Vec::new(),
        points: Vec::new(),
        forces: Vec::new(),
        initial: Vec::new(),
        time: TimeSpan {
            start: n(0.0),
            end: n(5.0),
            span: Span::default(),
        },
        exact: Vec::new(),
        integrator: None,
        lets: Vec::new(),
        outputs: Vec::new(),
        stop: None,
        impacts: Vec::new(),
        names: HashMap::from([
            ("M0".to_string(), Name::Param(0)),
            ("alpha".to_string(), Name::Param(1)),
            ("q1".to_string(), Name::Coord(0)),
            ("q2".to_string(), Name::Coord(1)),
            ("M".to_string(), Name::Mass(0)),
        ]),
    }
}

#[test]
fn lowering_resolves_names() {
    let model = paper_model();
    let mut a = Arena::new(names_of(&model));
    let l = lower(&mut a, &model.lagrangian, &model);
    assert_eq!(a.display(l).to_string(), "0.5*M*(q1'^2 + q2'^2)");
    let law = lower(&mut a, &model.masses[0].law, &model);
    assert_eq!(a.display(law).to_string(), "M0*exp(-alpha*t)");
    let root = lower(&mut a, &call(Func::Sqrt, var("t", 0)), &model);
    assert_eq!(a.display(root).to_string(), "sqrt(t)");
    let sub = lower(&mut a, &bin(BinOp::Sub, var("q2", 3), var("q1", 0)), &model);
    assert_eq!(a.display(sub).to_string(), "-q1 + q2'''");
}

#[test]
fn unresolvable_names_are_errors_not_panics() {
    let model = paper_model();
    let mut a = Arena::new(names_of(&model));
    for bad in [var("nope", 0), var("t", 1), var("M", 1), var("alpha", 2)] {
        let wrapped = bin(BinOp::Add, n(1.0), bad);
        assert!(try_lower(&mut a, &wrapped, &model).is_err());
        let nan = lower(&mut a, &wrapped, &model);
        assert!(a.as_const(nan).is_some_and(f64::is_nan));
    }
}

/// SPEC §1.6 through the IR: the order-matched star of equation (4) for the
/// paper's example gives `M(1+t²)q1'' + M t q1'` (k = 1, i = 1).
#[test]
fn paper_equation_four() {
    let model = paper_model();
    let mut a = Arena::new(names_of(&model));
    let l = lower(&mut a, &model.lagrangian, &model);
    let t = a.symbol(Symbol::Time);
    let q1d = a.jet(0, 1);
    let phi = a.mul(&[t, q1d]); // q2' = t q1'
    let d_phi = a.total_derivative(phi);
    let l1 = a.total_derivative(l);
    let l2 = a.total_derivative(l1);
    let l1_star = a.subst(l1, &HashMap::from([(q(1, 1), phi)]));
    let l2_star = a.subst(l2, &HashMap::from([(q(1, 2), d_phi)]));
    let p2 = a.diff(l2_star, q(0, 2));
    let p1 = a.diff(l1_star, q(0, 1));
    let two = a.constant(2.0);
    let minus_three = a.constant(-3.0);
    let left = a.mul(&[two, p2]);
    let right = a.mul(&[minus_three, p1]);
    let lhs = a.add(&[left, right]);
    let eliminate = HashMap::from([(q(1, 1), phi), (q(1, 2), d_phi)]);
    let lhs = a.subst(lhs, &eliminate);
    assert!(a.max_jet_order(lhs, 1).is_none());

    let m = a.symbol(Symbol::Mass(0));
    let q1dd = a.jet(0, 2);
    let one = a.one();
    let t2 = a.powi(t, 2);
    let s = a.add(&[one, t2]);
    let first = a.mul(&[m, s, q1dd]);
    let second = a.mul(&[m, t, q1d]);
    let expected = a.add(&[first, second]);
    for p in 0..10 {
        let env = env_at(p);
        let (x, y) = (a.eval(lhs, &env), a.eval(expected, &env));
        assert!(
            (x - y).abs() <= 1e-12 * y.abs(),
            "{} vs {}",
            a.display(lhs),
            a.display(expected)
        );
    }
}

/// Issue 28: `atan2` lowered is `f64::atan2`, and its derivatives are
/// `∂/∂x = −y/r²`, `∂/∂y = x/r²` on either side of x = 0 and at it (the
/// branch the selection keeps), where `atan(y/x) ± π` had the derivative
/// 0/0 (the runs stopped with exit 3); the one jump is the cut (x < 0,
/// y = 0), between the branches of y's sign.
#[test]
fn atan2_and_its_derivatives_are_defined_through_x_0() {
    let source = "coord x, y; lagrangian = x'^2 + y'^2; output a = atan2(y, x);\n\
                  initial x = 1, y = 0, x' = 0, y' = 0; time 0 .. 1;";
    let ast = lagc::syntax::parse(source).unwrap();
    let model = lagc::check::check(&ast).unwrap();
    let mut arena = Arena::new(names_of(&model));
    let angle = lower(&mut arena, &model.outputs[0].value, &model);
    let (x, y) = (q(0, 0), q(1, 0));
    let by_x = arena.diff(angle, x);
    let by_y = arena.diff(angle, y);
    let small = [1e-300, 1e-12, 1e-6, 0.1, 1.0, 7.0];
    let mut values: Vec<f64> = small.iter().flat_map(|&v| [v, -v]).collect();
    values.push(0.0);
    for &xv in &values {
        for &yv in &values {
            if xv == 0.0 && yv == 0.0 || xv.hypot(yv) < 1e-200 {
                continue;
            }
            let env = |s: Symbol| if s == x { xv } else { yv };
            let got = arena.eval(angle, &env);
            let expected = yv.atan2(xv);
            assert!(
                (got - expected).abs() <= 4.0 * f64::EPSILON * expected.abs().max(1.0),
                "atan2({yv:e}, {xv:e}) = {got}, expected {expected}"
            );
            // Relative to the gradient's size 1/r.
            let r = xv.hypot(yv);
            for (what, d, exact) in [("x", by_x, -yv / r / r), ("y", by_y, xv / r / r)] {
                let got = arena.eval(d, &env);
                assert!(
                    (got - exact).abs() <= 1e-13 / r,
                    "∂atan2/∂{what} at ({xv:e}, {yv:e}) = {got:e}, expected {exact:e}"
                );
            }
        }
    }
}
