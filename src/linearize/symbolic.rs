//! `--symbolic`: A's entries as expressions.

use super::system::{rate_name, Implicit, Partials, Rate};
use super::text::{Entry, Symbolic};
use crate::check::model::Model;
use crate::ir::{Arena, ExprId, Symbol};
use std::collections::HashMap;

pub(super) struct SymbolicInput<'a> {
    pub(super) free: &'a [usize],
    pub(super) kept: &'a [usize],
    pub(super) state: &'a [Symbol],
    pub(super) rates: &'a [Rate],
    pub(super) partials: &'a Partials,
    pub(super) implicit: Option<&'a Implicit>,
    pub(super) at: &'a [(usize, f64)],
    pub(super) overrides: &'a [(String, f64)],
    /// `--input` values: each input stands in as the param after the
    /// model's params and the inputs before it.
    pub(super) inputs: &'a [(String, f64)],
    pub(super) model: &'a Model,
    pub(super) t: Option<f64>,
}

/// `A`'s non-zero entries as expressions, with the values given on the
/// command line (`--at`, `--param`, `--t`) substituted and the rest left
/// as symbols; an implicit system's highest rows as the parts of
/// `G_z ∂z/∂x = −G_x`.
pub(super) fn symbolic(arena: &mut Arena, input: &SymbolicInput) -> Symbolic {
    let mut map: HashMap<Symbol, ExprId> = HashMap::new();
    for &(k, v) in input.at {
        let c = arena.constant(v);
        map.insert(input.state[k], c);
    }
    for (name, v) in input.overrides {
        if let Some(i) = input.model.params.iter().position(|p| &p.name == name) {
            let c = arena.constant(*v);
            map.insert(Symbol::Param(i as u32), c);
        }
    }
    for (name, v) in input.inputs {
        if let Some(i) = input.model.inputs.iter().position(|u| &u.name == name) {
            let c = arena.constant(*v);
            map.insert(Symbol::Param((input.model.params.len() + i) as u32), c);
        }
    }
    if let Some(t) = input.t {
        let c = arena.constant(t);
        map.insert(Symbol::Time, c);
    }
    let show = |arena: &mut Arena, e: ExprId| -> Option<(String, String)> {
        let e = arena.subst(e, &map);
        if arena.is_zero(e) {
            return None;
        }
        let e = crate::mechanics::tidy::tidy(arena, e);
        if arena.is_zero(e) {
            return None;
        }
        Some((arena.display(e).to_string(), arena.latex(e)))
    };
    let name = |arena: &Arena, k: usize| arena.symbol_name(input.state[input.free[k]]);
    let mut entries = Vec::new();
    let mut implicit_rows = Vec::new();
    for &i in input.kept {
        let row = rate_name(arena, input.state[input.free[i]]);
        match input.rates[i] {
            Rate::Expr(_) => {
                for &c in input.kept {
                    if let Some((text, latex)) = show(arena, input.partials.state[i][c]) {
                        entries.push(Entry {
                            row: row.clone(),
                            column: name(arena, c),
                            text,
                            latex,
                        });
                    }
                }
            }
            Rate::Unknown(_) | Rate::Dependent(_) => implicit_rows.push(row),
        }
    }
    let mut parts = Vec::new();
    if let (Some(imp), false) = (input.implicit, implicit_rows.is_empty()) {
        for (r, row) in imp.jacobian.iter().enumerate() {
            for (c, &e) in row.iter().enumerate() {
                if let Some((text, latex)) = show(arena, e) {
                    parts.push(Entry {
                        row: format!("G{}", r + 1),
                        column: arena.symbol_name(imp.unknowns[c]),
                        text,
                        latex,
                    });
                }
            }
        }
        for (r, g) in input.partials.g_state.iter().enumerate() {
            for &c in input.kept {
                if let Some((text, latex)) = show(arena, g[c]) {
                    parts.push(Entry {
                        row: format!("G{}", r + 1),
                        column: name(arena, c),
                        text,
                        latex,
                    });
                }
            }
        }
    }
    Symbolic {
        entries,
        implicit_rows,
        implicit_parts: parts,
    }
}
