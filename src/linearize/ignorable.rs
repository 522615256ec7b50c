//! The ignorable coordinates: positions that no remaining right side
//! contains, found symbolically (the variable in a rate's exact partial),
//! a partial's vanishing confirmed at random points where the simplifier
//! leaves an identity such as `sin²φ + cos²φ − 1` standing.

use super::system::{Implicit, Partials, Rate};
use crate::ir::{Arena, ExprId, Symbol};
use crate::mechanics::{eval_scaled, Rng};
use std::collections::HashMap;

/// The greatest set of free positions that no remaining rate depends on.
/// "Depends" is symbolic — the variable in the rate's partial — with the
/// partial's vanishing checked at random points near this one, so that an
/// identity the simplifier leaves standing (`sin²φ + cos²φ − 1`) does not
/// hide an ignorable heading.
#[allow(clippy::too_many_arguments)]
pub(super) fn ignorable(
    arena: &Arena,
    free: &[usize],
    rates: &[Rate],
    partials: &Partials,
    n: usize,
    env: &dyn Fn(Symbol) -> f64,
    implicit: Option<&Implicit>,
    through_closure: &[bool],
) -> Vec<usize> {
    let positions: Vec<usize> = (0..free.len()).filter(|&i| free[i] < n).collect();
    let mut zero_cache: HashMap<ExprId, bool> = HashMap::new();
    let mut is_zero = |e: ExprId| -> bool {
        *zero_cache
            .entry(e)
            .or_insert_with(|| vanishes(arena, e, env, implicit))
    };
    let mut direct = |row: usize, col: usize| -> bool {
        match rates[row] {
            Rate::Expr(_) => !is_zero(partials.state[row][col]),
            Rate::Unknown(_) => partials.g_state.iter().any(|g| !is_zero(g[col])),
            Rate::Dependent(_) => {
                !is_zero(partials.state[row][col])
                    || partials.g_state.iter().any(|g| !is_zero(g[col]))
            }
        }
    };
    let bound = partials.columns - free.len();
    let mut depends = |row: usize, col: usize| -> bool {
        direct(row, col)
            || (through_closure[col] && (0..bound).any(|d| direct(row, free.len() + d)))
    };
    let mut set: Vec<usize> = positions;
    loop {
        let before = set.len();
        let current = set.clone();
        set.retain(|&c| {
            !(0..free.len())
                .filter(|r| !current.contains(r))
                .any(|r| depends(r, c))
        });
        if set.len() == before {
            return set;
        }
    }
}

/// Whether `e` is identically zero: structurally, or (to rounding) at
/// random points near the linearization point. A point where it cannot be
/// evaluated is skipped; with too few points left it counts as non-zero.
pub(super) fn vanishes(
    arena: &Arena,
    e: ExprId,
    env: &dyn Fn(Symbol) -> f64,
    implicit: Option<&Implicit>,
) -> bool {
    if arena.is_zero(e) {
        return true;
    }
    if arena.as_const(e).is_some() {
        return false;
    }
    let mut rng = Rng::new(0x6c69_6e65_6172_697a ^ e.index() as u64);
    let symbols = arena.free_symbols(e);
    let mut finite = 0;
    for _ in 0..24 {
        let shifts: HashMap<Symbol, f64> = symbols
            .iter()
            .map(|&s| {
                let base = env(s);
                let base = if base.is_finite() { base } else { 0.0 };
                let unknown = implicit.is_some_and(|imp| imp.unknowns.contains(&s));
                let spread = if unknown { 1.0 } else { 0.5 };
                (s, base + spread * (1.0 + base.abs()) * rng.range(-1.0, 1.0))
            })
            .collect();
        let value = eval_scaled(arena, &[e], &|s| {
            shifts.get(&s).copied().unwrap_or(f64::NAN)
        })[0];
        if !value.is_finite() {
            continue;
        }
        finite += 1;
        if value.value.abs() > 1e-9 * value.scale {
            return false;
        }
    }
    finite >= 8
}
