//! Dividing the mass laws out of the equations (SPEC §1.3, the issue's
//! `M0·e^{1000t}` case): a row homogeneous of degree 1 in the mass symbols
//! jointly is divided by one mass `M_a` — `M_a → 1`, `M_b → law_b/law_a` —
//! so that a law that overflows f64 never has to be evaluated.

use super::sample::{eval_scaled, Rng, SamplePoint};
use crate::ir::{Arena, ExprId, Symbol};
use std::collections::HashMap;

/// How many random points must show homogeneity.
const POINTS: usize = 20;
/// The factor the masses are scaled by at each point.
const SCALE: f64 = 1.75;
/// Agreement relative to the rounding scale.
const TOLERANCE: f64 = 1e-12;

/// A row after dividing out masses: the new row and the mass divided out.
#[derive(Debug, Clone, Copy)]
pub struct Divided {
    pub row: ExprId,
    pub mass: Option<u32>,
}

/// Divides each row by a mass when it is homogeneous of degree 1 in the
/// masses; rows without masses, or not homogeneous, are kept.
pub fn divide_out_masses(
    arena: &mut Arena,
    rows: &[ExprId],
    laws: &[ExprId],
    param_defaults: &[f64],
) -> Vec<Divided> {
    rows.iter()
        .map(|&row| {
            let masses: Vec<u32> = arena
                .free_symbols(row)
                .into_iter()
                .filter_map(|s| match s {
                    Symbol::Mass(i) => Some(i),
                    _ => None,
                })
                .collect();
            let Some(&first) = masses.first() else {
                return Divided { row, mass: None };
            };
            if !homogeneous_degree_one(arena, row, laws.len(), param_defaults) {
                return Divided { row, mass: None };
            }
            let one = arena.one();
            let mut map = HashMap::from([(Symbol::Mass(first), one)]);
            for &b in &masses[1..] {
                if let (Some(&law_b), Some(&law_a)) =
                    (laws.get(b as usize), laws.get(first as usize))
                {
                    map.insert(Symbol::Mass(b), arena.div(law_b, law_a));
                }
            }
            Divided {
                row: arena.subst(row, &map),
                mass: Some(first),
            }
        })
        .collect()
}

/// `G(λM) = λ G(M)` at random points (all finite points; at least half of
/// them must be finite for a verdict).
fn homogeneous_degree_one(arena: &Arena, row: ExprId, masses: usize, defaults: &[f64]) -> bool {
    let mut rng = Rng::new(0x6d61_7373);
    let mut finite = 0;
    for _ in 0..2 * POINTS {
        let point = SamplePoint::random(&mut rng, defaults, masses);
        let scaled = point.masses_scaled(SCALE);
        let g = eval_scaled(arena, &[row], &|s| point.value(s))[0];
        let h = eval_scaled(arena, &[row], &|s| scaled.value(s))[0];
        if !(g.is_finite() && h.is_finite()) {
            continue;
        }
        let expected = super::sample::Scaled {
            value: SCALE * g.value,
            scale: SCALE * g.scale,
        };
        if !h.agrees(expected, TOLERANCE) {
            return false;
        }
        finite += 1;
        if finite == POINTS {
            return true;
        }
    }
    false
}
