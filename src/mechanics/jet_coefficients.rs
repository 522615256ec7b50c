//! The coefficients `∂e/∂v` the tidy forms need to find the jets an
//! expression is affine in, taken one derivative order at a time and only
//! where the answer is not already known.
//!
//! The rule of [`super::tidy`] (drop, one at a time, the last jet that
//! takes part in a dependence among the jets kept) decides jet `i` as soon
//! as every jet after it is decided, and then only from the jets up to it:
//! jet `i` is dropped exactly when some `∂e/∂v_m`, `m ≤ i`, holds `v_i` or
//! `∂e/∂v_i` holds some `v_m`, `m ≤ i` (the drops go strictly backwards: a
//! kept jet after `i` has no dependence left, so none with `i`). So a jet
//! that a coefficient already taken holds is dropped whatever its own
//! coefficient is, and that coefficient is not needed — unless a later
//! jet's decision needs it, which happens only when that later jet is not
//! itself held by the coefficients taken.
//!
//! The N-link pendulum's equations hold every angle in the coefficients of
//! the accelerations (its mass matrix), so the coefficients in the 100
//! angles (each `∂row/∂θ_k` some O(N) terms built through `add`) are never
//! built (the tidy forms' Jacobian of pendulum_100 went from 1.48e9
//! instructions to 0.85e9).

use super::tidy::priority;
use crate::ir::{Arena, ExprId, Symbol};
use std::collections::BTreeSet;

/// From this many expressions on, a group's coefficients come from one
/// Jacobian (their shared nodes' partials built once) rather than by
/// `diff`, whose memo already holds the derivation's partials (a few
/// expressions share little: the joint pass alone cost nested_sin_120
/// +10 % instructions).
pub(crate) const JOINT_JACOBIAN_ROOTS: usize = 8;

/// An expression's candidate jets, in priority order, that the affinity
/// rule must decide from coefficients, with `∂e/∂v` of each. The
/// candidates left out come after all of these and are held by one of
/// these coefficients: the rule drops them.
pub(crate) struct JetCoefficients {
    pub vars: Vec<Symbol>,
    pub coefficients: Vec<ExprId>,
}

/// The jets of `e` the tidy forms may collect: free in `e`, not switched
/// on by a selection (`sign(x')` has the derivative 0 in `x'` yet is not
/// `c + 0·x'`), in priority order (highest derivatives first).
pub(crate) fn candidate_jets(arena: &Arena, e: ExprId) -> Vec<Symbol> {
    let mut vars: Vec<Symbol> = arena
        .free_symbols(e)
        .into_iter()
        .filter(|s| matches!(s, Symbol::Jet { .. }))
        .filter(|&s| !arena.switches_on(e, s))
        .collect();
    vars.sort_by_key(|&s| priority(s));
    vars
}

/// The state of one expression while its groups are taken.
struct Pending {
    candidates: Vec<Symbol>,
    /// How many of `candidates` have their coefficient in `coefficients`
    /// (always a prefix).
    taken: usize,
    coefficients: Vec<ExprId>,
}

/// [`JetCoefficients`] of each of `es`. The candidates are taken a
/// derivative order at a time, highest first; an expression skips an
/// order whose every candidate a coefficient already taken holds, and
/// takes the skipped ones after all when a later order has a candidate
/// none holds (the rule then needs them).
pub(crate) fn jet_coefficients(arena: &mut Arena, es: &[ExprId]) -> Vec<JetCoefficients> {
    let mut pending: Vec<Pending> = es
        .iter()
        .map(|&e| Pending {
            candidates: candidate_jets(arena, e),
            taken: 0,
            coefficients: Vec::new(),
        })
        .collect();
    let orders: BTreeSet<std::cmp::Reverse<u32>> = pending
        .iter()
        .flat_map(|p| p.candidates.iter().map(|&s| std::cmp::Reverse(order(s))))
        .collect();
    for std::cmp::Reverse(o) in orders {
        // The expressions that need their candidates up to order `o`.
        let mut needs: Vec<usize> = Vec::new();
        for (i, p) in pending.iter().enumerate() {
            let group = p.candidates.iter().filter(|&&s| order(s) == o);
            let mut unheld = group.filter(|&&s| match arena.symbol_slot(s) {
                Some(slot) => !p.coefficients.iter().any(|&c| arena.holds_slot(c, slot)),
                None => true,
            });
            if unheld.next().is_some() {
                needs.push(i);
            }
        }
        take_up_to(arena, es, &mut pending, &needs, o);
    }
    pending
        .into_iter()
        .map(|mut p| {
            p.candidates.truncate(p.taken);
            JetCoefficients {
                vars: p.candidates,
                coefficients: p.coefficients,
            }
        })
        .collect()
}

fn order(s: Symbol) -> u32 {
    match s {
        Symbol::Jet { order, .. } => order,
        _ => 0,
    }
}

/// Takes the coefficients of the candidates of order `o` and higher not
/// yet taken, for the expressions `needs`: in one Jacobian for the
/// columns they share from [`JOINT_JACOBIAN_ROOTS`] expressions on, else
/// by `diff`. Each entry is the node `diff` gives either way.
fn take_up_to(arena: &mut Arena, es: &[ExprId], pending: &mut [Pending], needs: &[usize], o: u32) {
    let missing = |p: &Pending| -> Vec<Symbol> {
        p.candidates[p.taken..]
            .iter()
            .copied()
            .take_while(|&s| order(s) >= o)
            .collect()
    };
    // Coefficients the derivation already took (the mass matrix of the
    // reduced system is the accelerations' coefficients of its residuals,
    // often equations (4) themselves) are found in `diff`'s memo: an
    // expression whose coefficients are all there takes no part in the
    // Jacobian.
    let mut unknown: Vec<usize> = Vec::new();
    for &i in needs {
        let known: Option<Vec<ExprId>> = missing(&pending[i])
            .into_iter()
            .map(|s| arena.known_partial(es[i], s))
            .collect();
        match known {
            Some(known) => {
                let p = &mut pending[i];
                p.taken += known.len();
                p.coefficients.extend(known);
            }
            None => unknown.push(i),
        }
    }
    let needs = &unknown[..];
    if needs.len() >= JOINT_JACOBIAN_ROOTS {
        let columns: Vec<Symbol> = needs
            .iter()
            .flat_map(|&i| missing(&pending[i]))
            .collect::<BTreeSet<Symbol>>()
            .into_iter()
            .collect();
        let roots: Vec<ExprId> = needs.iter().map(|&i| es[i]).collect();
        let rows = arena.jacobian(&roots, &columns);
        for (&i, row) in needs.iter().zip(rows) {
            let p = &mut pending[i];
            for s in missing(p) {
                let c = columns
                    .binary_search(&s)
                    .map_or_else(|_| arena.zero(), |c| row[c]);
                p.coefficients.push(c);
                p.taken += 1;
            }
        }
    } else {
        for &i in needs {
            let p = &mut pending[i];
            for s in missing(p) {
                let c = arena.diff(es[i], s);
                p.coefficients.push(c);
                p.taken += 1;
            }
        }
    }
}
