//! The linearization's symbolic half, for a model's Python module
//! (`m.linearize(at=…)`, issue 27): everything `lagc linearize` derives
//! before it evaluates — the free state, the ignorable coordinates, the
//! rates with the constraints' fixed components substituted, their exact
//! partials in the free state, the params and the inputs, the params'
//! slopes in the params before them and the model's stated initial
//! values — as expressions, so that emission only prints them and the
//! module evaluates them at a point as `system.rs` does.
//!
//! Taken as `system.rs` takes them (the same substitutions, the same
//! `Partials`, the same `ignorable`), so the module's `A`, `∂f/∂p` and
//! `∂f/∂u` are the command line's to rounding. The ignorable coordinates
//! are found once, at the model's stated initial point (they are a
//! symbolic property: a rate's partial that vanishes identically).
//!
//! An implicit system of the highest derivatives (a mass matrix solved at
//! run time, `G(t, x, z) = 0`) is carried as `G` and its exact partials;
//! the module solves it and differentiates through it as `system.rs`
//! does (`∂z/∂x = −G_z⁻¹ G_x`).
//!
//! A model whose implicit constraints have several candidates has the
//! parts of every mode; the module picks the mode as `lagc linearize` does
//! (the first whose fixed components the request does not give and that
//! linearizes there).
//!
//! Holonomic constraints `f(t, q) = 0` are carried as `f` and its exact
//! partials: the module puts the dependent positions on them by Newton and
//! carries `A` and `B` through `∂z/∂v = −f_z⁻¹ f_v` (`closure.rs`).
//!
//! Not carried (the module says so and names `lagc linearize`): the
//! derivatives of order 2..k−1 the consistency of (4) fixes (k ≥ 3).

use super::ignorable::{ignorable, vanishes};
use super::point;
use super::system::{solve_highest, Implicit, Partials, Rate};
use crate::check::model::Model;
use crate::ir::{lower, Arena, ExprId, Symbol};
use crate::mechanics::{Derivation, Highest};
use std::collections::HashMap;

/// The symbolic linearization of a model, in its own arena. Indices into
/// the state are the generated crate's; "free position" `i` is
/// `free[i]`.
#[derive(Debug, Clone)]
pub struct LinearParts {
    pub arena: Arena,
    /// The state (6), as the generated crate holds it.
    pub state: Vec<Symbol>,
    /// The state components that are not fixed by the constraints.
    pub free: Vec<usize>,
    /// Free positions of `A`'s state (the free state without the
    /// ignorable coordinates).
    pub kept: Vec<usize>,
    /// Free positions of the ignorable coordinates.
    pub ignorable: Vec<usize>,
    /// `(state index, value)` of every component the constraints fix.
    pub fixed: Vec<(usize, ExprId)>,
    /// `(free position, value)`: the model's stated initial values, as
    /// expressions of the params.
    pub stated: Vec<(usize, ExprId)>,
    /// `(free position, rate)`.
    pub rates: Vec<(usize, ExprId)>,
    /// `(free row, free column, ∂rate/∂x)`, non-zero entries.
    pub a: Vec<(usize, usize, ExprId)>,
    /// `(free row, column, ∂rate/∂v)`: columns `0..np` the params,
    /// `np + i` input `i` (held at its value: its rate is zero).
    pub b: Vec<(usize, usize, ExprId)>,
    /// `(k, l, ∂p_k/∂p_l)`: param `k`'s expression in the params before it.
    pub chain: Vec<(usize, usize, ExprId)>,
    /// `(free position, j)`: the rates that are the implicit system's
    /// unknown `z_j` (their rows of `A` and `B` are `−G_z⁻¹ G_x`, `−G_z⁻¹
    /// G_p`); `rates`, `a` and `b` hold the other rows only.
    pub unknown_rows: Vec<(usize, usize)>,
    /// The implicit system `G(t, x, z) = 0` of the highest derivatives.
    pub implicit: Option<LinearImplicit>,
    /// The holonomic constraints `f(t, q) = 0` (their dependent positions
    /// are columns `free.len() + d` of `a` and of `g_x`, and positions
    /// `free.len() + d` of `stated`).
    pub closure: Option<LinearClosure>,
}

/// Holonomic constraints `f(t, q) = 0` over their dependent positions.
#[derive(Debug, Clone)]
pub struct LinearClosure {
    pub unknowns: Vec<Symbol>,
    /// The dependent positions' state indices.
    pub bound: Vec<usize>,
    /// `(r, f_r)`.
    pub residual: Vec<(usize, ExprId)>,
    /// `(r, d, ∂f_r/∂z_d)`.
    pub f_z: Vec<(usize, usize, ExprId)>,
    /// `(r, free column, ∂f_r/∂x)`.
    pub f_x: Vec<(usize, usize, ExprId)>,
    /// `(r, column, ∂f_r/∂v)`, columns as `LinearParts::b`'s.
    pub f_p: Vec<(usize, usize, ExprId)>,
}

/// `G(t, x, z) = 0` for the independent highest derivatives `z`, and the
/// partials the linearization takes through it. Expressions of `t`, the
/// params, the inputs, the free state and `z`.
#[derive(Debug, Clone)]
pub struct LinearImplicit {
    pub unknowns: Vec<Symbol>,
    /// Affine in `z`: one linear solve; else Newton from `z = 0`.
    pub linear: bool,
    /// `(r, G_r)`.
    pub residual: Vec<(usize, ExprId)>,
    /// `(r, k, ∂G_r/∂z_k)`.
    pub g_z: Vec<(usize, usize, ExprId)>,
    /// `(r, free column, ∂G_r/∂x)`.
    pub g_x: Vec<(usize, usize, ExprId)>,
    /// `(r, column, ∂G_r/∂v)`, columns as `LinearParts::b`'s.
    pub g_p: Vec<(usize, usize, ExprId)>,
    /// `(free row, k, ∂D/∂z_k)` of the dependent highest derivatives' rates.
    pub d_z: Vec<(usize, usize, ExprId)>,
}

/// The parts of every mode (the candidates' choices of dependents, in
/// order: `lagc linearize` tries them so), or why the module cannot carry
/// them.
pub fn parts(model: &Model, derivation: &Derivation) -> Result<Vec<LinearParts>, String> {
    let mut all = vec![parts_in(model, derivation)?];
    for mode in 1..model.mode_count() {
        let other = model.in_mode(mode);
        let d = crate::mechanics::derive_mode_checked(&other)
            .map_err(|_| format!("its reduced system of mode {} does not derive", mode + 1))?;
        all.push(parts_in(&other, &d)?);
    }
    Ok(all)
}

/// The parts in one mode.
fn parts_in(model: &Model, derivation: &Derivation) -> Result<LinearParts, String> {
    let reduced = &derivation.reduced;
    let mut arena = derivation.arena.clone();
    let state = reduced.state.clone();
    let n = derivation.coordinates;
    let u = reduced.order as usize;
    let np = model.params.len();

    let mut subst: HashMap<Symbol, ExprId> = HashMap::new();
    for i in 0..model.inputs.len() {
        let zero = arena.zero();
        subst.insert(Symbol::InputRate(i as u32), zero);
    }
    for (i, m) in model.masses.iter().enumerate() {
        let law = lower(&mut arena, &m.law, model);
        subst.insert(Symbol::Mass(i as u32), law);
    }
    let mut fixed: Vec<(usize, ExprId)> = Vec::new();
    for &(i, phi) in &reduced.fixed {
        let phi = arena.subst(phi, &subst);
        fixed.push((i, phi));
    }
    for &(i, phi) in &fixed {
        subst.insert(state[i], phi);
    }
    // Holonomic constraints f(t, q) = 0: their dependent positions
    // (`bound`) follow the free ones through `∂z/∂q = −f_z⁻¹ f_q`.
    let closure = reduced.closure.as_ref().map(|c| {
        let residual: Vec<ExprId> = c.residual.iter().map(|&f| arena.subst(f, &subst)).collect();
        let jacobian: Vec<Vec<ExprId>> = c
            .jacobian
            .iter()
            .map(|row| row.iter().map(|&e| arena.subst(e, &subst)).collect())
            .collect();
        (c.unknowns.clone(), residual, jacobian)
    });
    let bound: Vec<usize> = closure.as_ref().map_or_else(Vec::new, |(unknowns, _, _)| {
        unknowns
            .iter()
            .filter_map(|u| state.iter().position(|s| s == u))
            .collect()
    });
    let free: Vec<usize> = (0..state.len())
        .filter(|&k| !fixed.iter().any(|&(i, _)| i == k) && !bound.contains(&k))
        .collect();
    let implicit = match &reduced.highest {
        Highest::Implicit {
            unknowns,
            residual,
            jacobian,
            linear,
            ..
        } => Some(Implicit {
            unknowns: unknowns.clone(),
            residual: residual.iter().map(|&g| arena.subst(g, &subst)).collect(),
            jacobian: jacobian
                .iter()
                .map(|row| row.iter().map(|&e| arena.subst(e, &subst)).collect())
                .collect(),
            linear: *linear,
        }),
        Highest::Explicit(_) => None,
    };
    let mut rates = Vec::with_capacity(free.len());
    for &k in &free {
        let (order, coord) = (k / n, k % n);
        let rate = if order + 1 < u {
            let next = arena.symbol(state[k + n]);
            Rate::Expr(arena.subst(next, &subst))
        } else {
            match &reduced.highest {
                Highest::Explicit(rhs) => Rate::Expr(arena.subst(rhs[coord], &subst)),
                Highest::Implicit {
                    unknowns,
                    dependent,
                    ..
                } => {
                    let z = Symbol::Jet {
                        coord: coord as u32,
                        order: u as u32,
                    };
                    match unknowns.iter().position(|&s| s == z) {
                        Some(j) => Rate::Unknown(j),
                        None => {
                            let d = dependent
                                .iter()
                                .find(|&&(c, _)| c as usize == coord)
                                .map_or_else(|| arena.constant(f64::NAN), |&(_, e)| e);
                            Rate::Dependent(arena.subst(d, &subst))
                        }
                    }
                }
            }
        };
        rates.push(rate);
    }

    // The stated point, at the model's params, for the ignorable test.
    let exprs: Vec<ExprId> = model
        .params
        .iter()
        .map(|p| lower(&mut arena, &p.value, model))
        .collect();
    let params = point::params(&mut arena, model, &[]).map_err(|e| e.message)?;
    let t0 = point::time(&mut arena, model, None, &params.values).map_err(|e| e.message)?;
    let mut stated = Vec::new();
    let mut values: HashMap<Symbol, f64> = HashMap::new();
    for (i, &k) in free.iter().chain(&bound).enumerate() {
        let Symbol::Jet { coord, order } = state[k] else {
            continue;
        };
        let Some(init) = model
            .initial
            .iter()
            .find(|v| v.coord as u32 == coord && v.order == order)
        else {
            // Unstated: another mode's dependent (the request must give
            // it), or (k ≥ 3) a derivative the consistency of (4) fixes.
            if order >= 2 {
                return Err(format!(
                    "the model states no initial `{}` (k ≥ 3: (4) fixes it)",
                    arena.symbol_name(state[k])
                ));
            }
            continue;
        };
        let e = lower(&mut arena, &init.value, model);
        let v = point::stated(&mut arena, model, state[k], &params.values).unwrap_or(f64::NAN);
        values.insert(state[k], v);
        stated.push((i, e));
    }
    let inputs: Vec<f64> = model.inputs.iter().map(|i| i.default).collect();
    let env_of = |values: &HashMap<Symbol, f64>| {
        let values = values.clone();
        let (pv, inputs) = (params.values.clone(), inputs.clone());
        move |s: Symbol| match s {
            Symbol::Time => t0,
            Symbol::Param(j) => pv.get(j as usize).copied().unwrap_or(f64::NAN),
            Symbol::Input(j) => inputs.get(j as usize).copied().unwrap_or(f64::NAN),
            other => values.get(&other).copied().unwrap_or(f64::NAN),
        }
    };
    // The highest derivatives at the stated point (the ignorable test
    // samples near them).
    // (Where they are not defined there, the test samples near zero.)
    if let Some(imp) = &implicit {
        if let Ok(z) = solve_highest(&arena, imp, &env_of(&values)) {
            for (&s, &v) in imp.unknowns.iter().zip(&z) {
                values.insert(s, v);
            }
        }
    }
    let env = env_of(&values);

    let columns: Vec<Symbol> = free.iter().chain(&bound).map(|&k| state[k]).collect();
    let partials = Partials::new(&mut arena, &rates, implicit.as_ref(), &columns);
    let through_closure: Vec<bool> = match &closure {
        Some((_, residual, _)) => free
            .iter()
            .map(|&k| {
                residual.iter().any(|&f| {
                    let d = arena.diff(f, state[k]);
                    !vanishes(&arena, d, &env, None)
                })
            })
            .collect(),
        None => vec![false; free.len()],
    };
    let ignorable = ignorable(
        &arena,
        &free,
        &rates,
        &partials,
        n,
        &env,
        implicit.as_ref(),
        &through_closure,
    );
    let kept: Vec<usize> = (0..free.len()).filter(|c| !ignorable.contains(c)).collect();

    let mut vars: Vec<Symbol> = (0..np as u32).map(Symbol::Param).collect();
    vars.extend((0..model.inputs.len() as u32).map(Symbol::Input));
    let param_partials = Partials::new(&mut arena, &rates, implicit.as_ref(), &vars);
    let cells = |m: &[Vec<ExprId>], arena: &Arena| -> Vec<(usize, usize, ExprId)> {
        m.iter()
            .enumerate()
            .flat_map(|(r, row)| {
                row.iter()
                    .enumerate()
                    .filter(|&(_, &e)| !arena.is_zero(e))
                    .map(move |(c, &e)| (r, c, e))
            })
            .collect()
    };
    let a = cells(&partials.state, &arena);
    let b = cells(&param_partials.state, &arena);
    let mut chain = Vec::new();
    for (k, &e) in exprs.iter().enumerate() {
        for l in 0..k {
            let d = arena.diff(e, Symbol::Param(l as u32));
            if !arena.is_zero(d) {
                chain.push((k, l, d));
            }
        }
    }
    let holonomic = closure.map(|(unknowns, residual, jacobian)| {
        let mut slopes = |vars: &[Symbol]| -> Vec<Vec<ExprId>> {
            residual
                .iter()
                .map(|&f| vars.iter().map(|&v| arena.diff(f, v)).collect())
                .collect()
        };
        let f_x = slopes(&columns[..free.len()]);
        let f_p = slopes(&vars);
        LinearClosure {
            bound: bound.clone(),
            residual: residual.iter().copied().enumerate().collect(),
            f_z: cells(&jacobian, &arena),
            f_x: cells(&f_x, &arena),
            f_p: cells(&f_p, &arena),
            unknowns,
        }
    });
    let unknown_rows: Vec<(usize, usize)> = rates
        .iter()
        .enumerate()
        .filter_map(|(i, r)| match *r {
            Rate::Unknown(j) => Some((i, j)),
            _ => None,
        })
        .collect();
    let highest = implicit.as_ref().map(|imp| {
        let square: Vec<Vec<ExprId>> = imp.jacobian.clone();
        LinearImplicit {
            unknowns: imp.unknowns.clone(),
            linear: imp.linear,
            residual: imp.residual.iter().copied().enumerate().collect(),
            g_z: cells(&square, &arena),
            g_x: cells(&partials.g_state, &arena),
            g_p: cells(&param_partials.g_state, &arena),
            d_z: cells(&partials.d_z, &arena),
        }
    });
    let rates = rates
        .iter()
        .enumerate()
        .filter_map(|(i, r)| match *r {
            Rate::Expr(e) | Rate::Dependent(e) => Some((i, e)),
            Rate::Unknown(_) => None,
        })
        .collect::<Vec<_>>();
    Ok(LinearParts {
        arena,
        state,
        free,
        kept,
        ignorable,
        fixed,
        stated,
        rates,
        a,
        b,
        chain,
        unknown_rows,
        implicit: highest,
        closure: holonomic,
    })
}
