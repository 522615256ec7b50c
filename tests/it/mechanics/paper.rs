//! The paper's example (SPEC §1.6): equation (4) and the reduced system
//! (16) against SPEC's formulas, and the two wrong readings of the star.

use super::{derive_source, Rng};
use lagc::ir::{Arena, ExprId, Symbol};
use lagc::mechanics::{Highest, InitialValue};
use std::collections::HashMap;

const PAPER: &str = include_str!("../../../examples/paper.lag");
const ALPHA: Symbol = Symbol::Param(1);
const M: Symbol = Symbol::Mass(0);
const Q1: u32 = 0;
const Q2: u32 = 1;

fn jet(coord: u32, order: u32) -> Symbol {
    Symbol::Jet { coord, order }
}

/// Random values of t, alpha, M and the jets of q1, q2 up to order 3.
fn points() -> Vec<HashMap<Symbol, f64>> {
    let mut rng = Rng::new(7);
    (0..100)
        .map(|_| {
            let mut p = HashMap::new();
            p.insert(Symbol::Time, rng.range(0.0, 3.0));
            p.insert(Symbol::Param(0), rng.range(0.5, 2.0));
            p.insert(ALPHA, rng.range(-1.0, 1.0));
            p.insert(M, rng.range(0.5, 2.0));
            for c in [Q1, Q2] {
                for r in 0..4 {
                    p.insert(jet(c, r), rng.range(-2.0, 2.0));
                }
            }
            p
        })
        .collect()
}

fn eval(arena: &Arena, e: ExprId, p: &HashMap<Symbol, f64>) -> f64 {
    arena.eval(e, &|s| p.get(&s).copied().unwrap_or(f64::NAN))
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12 * (1.0 + a.abs() + b.abs())
}

#[test]
fn equation_four_is_specs() {
    let d = derive_source(PAPER);
    assert_eq!(d.equations.len(), 1);
    let eq = d.equations[0];
    for p in points() {
        let (t, alpha, m) = (p[&Symbol::Time], p[&ALPHA], p[&M]);
        let (v, a) = (p[&jet(Q1, 1)], p[&jet(Q1, 2)]);
        let lhs = m * (1.0 + t * t) * a + m * t * v;
        let rhs = alpha * m * (1.0 + t * t) * v;
        assert!(close(eval(&d.arena, eq.lhs, &p), lhs), "lhs at {p:?}");
        assert!(close(eval(&d.arena, eq.rhs, &p), rhs), "rhs at {p:?}");
    }
    let text = d.text();
    assert!(
        text.contains("q1: M*(1 + t^2)*q1'' + M*t*q1' = alpha*M*(1 + t^2)*q1'\n"),
        "{text}"
    );
}

#[test]
fn reduced_system_is_sixteen() {
    let d = derive_source(PAPER);
    let Highest::Explicit(x) = &d.reduced.highest else {
        panic!("the paper's system is explicit: {:?}", d.reduced.highest);
    };
    for p in points() {
        let (t, alpha, v) = (p[&Symbol::Time], p[&ALPHA], p[&jet(Q1, 1)]);
        let q1 = (alpha - t / (1.0 + t * t)) * v;
        let q2 = (alpha * t + 1.0 / (1.0 + t * t)) * v;
        assert!(close(eval(&d.arena, x[0], &p), q1));
        assert!(close(eval(&d.arena, x[1], &p), q2));
    }
    // M = M0 e^{-αt} cancels: nothing of the mass law is left.
    assert!(d.reduced.mass_laws.is_empty());
    assert_eq!(d.divided_out, vec![Some(0)]);
    let text = d.text();
    assert!(
        text.contains("  q1'' = (alpha - t/(1 + t^2))*q1'\n"),
        "{text}"
    );
    assert!(
        text.contains("  q2'' = (alpha*t + 1/(1 + t^2))*q1'\n"),
        "{text}"
    );
    // q2'(0) is fixed by the constraint: t*q1'.
    let InitialValue::Constraint(q2_dot) = d.reduced.initial[3] else {
        panic!("{:?}", d.reduced.initial);
    };
    for p in points() {
        let expected = p[&Symbol::Time] * p[&jet(Q1, 1)];
        assert!(close(eval(&d.arena, q2_dot, &p), expected));
    }
}

/// `2 ∂L2/∂q1'' − 3 ∂L1/∂q1'` with the given substitutions made in L1 and
/// L2 before differentiating, then every q2 derivative eliminated.
fn left_side(
    a: &mut Arena,
    l: ExprId,
    in_l1: &HashMap<Symbol, ExprId>,
    in_l2: &HashMap<Symbol, ExprId>,
    eliminate: &HashMap<Symbol, ExprId>,
) -> ExprId {
    let l1 = a.total_derivative(l);
    let l2 = a.total_derivative(l1);
    let (l1, l2) = (a.subst(l1, in_l1), a.subst(l2, in_l2));
    let p2 = a.diff(l2, jet(Q1, 2));
    let p1 = a.diff(l1, jet(Q1, 1));
    let (two, three) = (a.constant(2.0), a.constant(-3.0));
    let (x, y) = (a.mul(&[two, p2]), a.mul(&[three, p1]));
    let lhs = a.add(&[x, y]);
    a.subst(lhs, eliminate)
}

/// SPEC §1.2: the literal reading and "substitute everything first" give
/// `M(1+t²)q1'' ∓ 2Mt q1'`, not the order-matched `+ Mt q1'`.
#[test]
fn the_wrong_readings_of_the_star_differ() {
    let mut d = derive_source(PAPER);
    let ours = d.equations[0].lhs;
    let a = &mut d.arena;
    let l = d.lagrangian;
    let phi = d.constraints[0].1;
    let dphi = a.total_derivative(phi);
    let d2phi = a.total_derivative(dphi);
    let both: HashMap<Symbol, ExprId> = HashMap::from([(jet(Q2, 1), phi), (jet(Q2, 2), dphi)]);
    let all: HashMap<Symbol, ExprId> =
        HashMap::from([(jet(Q2, 1), phi), (jet(Q2, 2), dphi), (jet(Q2, 3), d2phi)]);
    let literal = left_side(a, l, &both, &both, &all);
    let everything = left_side(a, l, &all, &all, &all);
    let mut differ = (0, 0);
    for p in points() {
        let (t, m) = (p[&Symbol::Time], p[&M]);
        let (v, acc) = (p[&jet(Q1, 1)], p[&jet(Q1, 2)]);
        let base = m * (1.0 + t * t) * acc;
        let ours_value = eval(a, ours, &p);
        let literal_value = eval(a, literal, &p);
        let everything_value = eval(a, everything, &p);
        assert!(close(ours_value, base + m * t * v));
        assert!(close(literal_value, base - 2.0 * m * t * v));
        assert!(close(everything_value, base + 2.0 * m * t * v));
        if !close(literal_value, ours_value) {
            differ.0 += 1;
        }
        if !close(everything_value, ours_value) {
            differ.1 += 1;
        }
    }
    assert!(differ.0 > 90 && differ.1 > 90, "{differ:?}");
}
