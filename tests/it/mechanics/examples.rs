//! Every `examples/*.lag` through the mechanics: it derives, equations (4)
//! agree with the multiplier route at 100 random points, the reduced system
//! satisfies (4), and the text and LaTeX forms are snapshots.

use super::Rng;
use lagc::ir::Symbol;
use lagc::mechanics::{cross_check, derive, Highest};
use std::collections::HashMap;

#[test]
fn every_example_derives_and_passes_the_cross_check() {
    insta::glob!("../../../examples", "*.lag", |path| {
        let source = std::fs::read_to_string(path).unwrap();
        let model = lagc::frontend(&source).unwrap_or_else(|d| panic!("{path:?}: {d:#?}"));
        let mut derivation = derive(&model).unwrap_or_else(|d| panic!("{path:?}: {d:#?}"));
        let check = cross_check(&mut derivation)
            .unwrap_or_else(|failure| panic!("{path:?}: cross-check failed: {failure}"));
        assert!(check.points >= 100, "{path:?}: {check:?}");
        insta::assert_snapshot!("text", derivation.text());
        insta::assert_snapshot!("latex", derivation.latex());
    });
}

/// For k ≤ 2: the explicit highest derivatives, put into (4) (`lhs − rhs`,
/// with the dependent `q_d''` eliminated), give zero at random points.
#[test]
fn explicit_reduced_systems_satisfy_equation_four() {
    insta::glob!("../../../examples", "*.lag", |path| {
        let source = std::fs::read_to_string(path).unwrap();
        let model = lagc::frontend(&source).unwrap();
        let derivation = derive(&model).unwrap();
        let Highest::Explicit(highest) = &derivation.reduced.highest else {
            return;
        };
        if derivation.k > 2 {
            return;
        }
        let arena = &derivation.arena;
        let mut rng = Rng::new(11);
        let mut checked = 0;
        for _ in 0..200 {
            let mut values: HashMap<Symbol, f64> = HashMap::new();
            values.insert(Symbol::Time, rng.range(0.0, 2.0));
            for (i, &d) in derivation.param_defaults.iter().enumerate() {
                let v = if d == 0.0 {
                    rng.range(-0.2, 0.2)
                } else {
                    d * rng.range(0.8, 1.2)
                };
                values.insert(Symbol::Param(i as u32), v);
            }
            for i in 0..arena.names().masses.len() {
                values.insert(Symbol::Mass(i as u32), rng.range(0.5, 2.0));
            }
            for &s in &derivation.reduced.state {
                values.insert(s, rng.range(-0.9, 0.9));
            }
            let env = |s: Symbol| values.get(&s).copied().unwrap_or(f64::NAN);
            let accelerations = arena.eval_many(highest, &env);
            for (j, &a) in accelerations.iter().enumerate() {
                values.insert(
                    Symbol::Jet {
                        coord: j as u32,
                        order: 2,
                    },
                    a,
                );
            }
            let env = |s: Symbol| values.get(&s).copied().unwrap_or(f64::NAN);
            for eq in &derivation.equations {
                let (l, r) = (arena.eval(eq.lhs, &env), arena.eval(eq.rhs, &env));
                if !(l.is_finite() && r.is_finite()) {
                    continue;
                }
                // Relative to the values and to their rounding scales: near
                // a small determinant of coupled constraints (a four-bar's
                // links nearly aligned at a random point) the terms of (4)
                // are large and cancel.
                let rounding: f64 = lagc::mechanics::eval_scaled(arena, &[eq.lhs, eq.rhs], &env)
                    .iter()
                    .map(|v| v.scale)
                    .sum();
                let scale = 1.0 + l.abs() + r.abs() + rounding;
                assert!(
                    (l - r).abs() <= 1e-9 * scale,
                    "{path:?}: {l} vs {r} (rounding scale {rounding:e})"
                );
                checked += 1;
            }
        }
        assert!(checked >= 100, "{path:?}: only {checked} finite points");
    });
}
