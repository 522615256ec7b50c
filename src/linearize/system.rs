//! The reduced system with the constraints eliminated, its exact symbolic
//! Jacobians in the state and the params, the ignorable coordinates, and
//! all of it evaluated at the point.
//!
//! Each component of the free state (the state minus the components the
//! constraints fix) has a rate: an expression (a lower derivative, with a
//! fixed component replaced by its constraint's value), an independent
//! highest derivative `z_k` of an implicit system (`G(t, x, z) = 0`: then
//! `∂z/∂x = −G_z⁻¹ G_x`, implicit differentiation of exact partials), or a
//! dependent highest derivative `D(t, x, z)`.

use super::closure::{chain_through, close, closure_slopes, Closure};
use super::eigen;
use super::ignorable::{ignorable, vanishes};
use super::point::{self, Params};
use super::symbolic::{symbolic, SymbolicInput};
use super::{Linearization, LinearizeError, Request};
use crate::check::model::Model;
use crate::ir::{lower, Arena, ExprId, Symbol};
use crate::mechanics::{eval_scaled, Derivation, Highest};
use nalgebra::{DMatrix, DVector};
use std::collections::HashMap;

/// How a free component's rate is found.
#[derive(Clone, Copy)]
pub(super) enum Rate {
    Expr(ExprId),
    Unknown(usize),
    Dependent(ExprId),
}

/// `G(t, x, z) = 0` for the independent highest derivatives `z`.
pub(super) struct Implicit {
    pub(super) unknowns: Vec<Symbol>,
    pub(super) residual: Vec<ExprId>,
    pub(super) jacobian: Vec<Vec<ExprId>>,
    pub(super) linear: bool,
}

/// A residual smaller than this fraction of its rounding scale is zero.
const ZERO: f64 = 1e-9;

pub(super) fn linearize_in(
    model: &Model,
    derivation: &Derivation,
    request: &Request,
) -> Result<Linearization, LinearizeError> {
    let reduced = &derivation.reduced;
    let mut arena = derivation.arena.clone();
    let state = reduced.state.clone();
    let names: Vec<String> = state.iter().map(|&s| arena.symbol_name(s)).collect();
    let n = derivation.coordinates;
    let u = reduced.order as usize;

    let overrides = point::items(&request.params, "--param")?;
    let at = point::items(&request.at, "--at")?;
    let at = point::resolve_at(&at, &names, model)?;
    let mut params = point::params(&mut arena, model, &overrides)?;
    let t = point::time(&mut arena, model, request.t.as_deref(), &params.values)?;
    let np = params.values.len();

    // Mass laws are functions of t (or of q): substituted, so that every
    // expression below is one of t, params and the state.
    let mut subst: HashMap<Symbol, ExprId> = HashMap::new();
    // Inputs are held at their values (`--input`, else their defaults):
    // each stands in as one more param after the model's, so that ∂f/∂u is
    // taken as ∂f/∂p is (through the constraints' closure too), and its
    // rate is zero (the point is an operating point of constant inputs).
    let given_inputs = point::items(&request.inputs, "--input")?;
    let input_values = point::inputs(model, &given_inputs)?;
    for (i, (input, &value)) in model.inputs.iter().zip(&input_values).enumerate() {
        let stand_in = arena.symbol(Symbol::Param((np + i) as u32));
        subst.insert(Symbol::Input(i as u32), stand_in);
        let zero = arena.zero();
        subst.insert(Symbol::InputRate(i as u32), zero);
        arena.names.params.push(input.name.clone());
        params.values.push(value);
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
    // Holonomic constraints f(t, q) = 0: their dependent positions are
    // functions of the other positions (∂z/∂q = −f_z⁻¹ f_q), eliminated
    // like the fixed velocities.
    let closure = reduced.closure.as_ref().map(|c| Closure {
        unknowns: c.unknowns.clone(),
        residual: c.residual.iter().map(|&f| arena.subst(f, &subst)).collect(),
        jacobian: c
            .jacobian
            .iter()
            .map(|row| row.iter().map(|&e| arena.subst(e, &subst)).collect())
            .collect(),
        text: c.text.clone(),
    });
    let bound: Vec<usize> = closure.as_ref().map_or_else(Vec::new, |c| {
        c.unknowns
            .iter()
            .filter_map(|u| state.iter().position(|s| s == u))
            .collect()
    });
    let is_fixed = |k: usize| fixed.iter().any(|&(i, _)| i == k) || bound.contains(&k);
    let free: Vec<usize> = (0..state.len()).filter(|&k| !is_fixed(k)).collect();

    // The rates of the free components.
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
        let (order, coord) = (k / n, (k % n) as u32);
        let rate = if order + 1 < u {
            let next = arena.symbol(state[k + n]);
            Rate::Expr(arena.subst(next, &subst))
        } else {
            match &reduced.highest {
                Highest::Explicit(rhs) => Rate::Expr(arena.subst(rhs[coord as usize], &subst)),
                Highest::Implicit {
                    unknowns,
                    dependent,
                    ..
                } => {
                    let z = Symbol::Jet {
                        coord,
                        order: u as u32,
                    };
                    match unknowns.iter().position(|&s| s == z) {
                        Some(j) => Rate::Unknown(j),
                        None => {
                            let d = dependent
                                .iter()
                                .find(|&&(c, _)| c == coord)
                                .map_or_else(|| arena.constant(f64::NAN), |&(_, e)| e);
                            Rate::Dependent(arena.subst(d, &subst))
                        }
                    }
                }
            }
        };
        rates.push(rate);
    }

    // The point: free components from `--at`, else as the model states
    // them, else (k ≥ 3: the independent derivatives of order 2..k−1) as
    // the consistency of (4) gives them from the rest, as at `t0`; fixed
    // ones from their constraints.
    let solved: Vec<(Symbol, ExprId)> = reduced
        .consistency
        .iter()
        .filter_map(|stage| stage.explicit.as_ref().map(|e| (&stage.unknowns, e)))
        .flat_map(|(unknowns, explicit)| unknowns.iter().copied().zip(explicit.iter().copied()))
        .collect();
    let mut values: HashMap<Symbol, f64> = HashMap::new();
    let mut deferred = Vec::new();
    for &k in &free {
        let given = at.iter().find(|&&(i, _)| i == k).map(|&(_, v)| v);
        let v = match given {
            Some(v) => v,
            None => match point::stated(&mut arena, model, state[k], &params.values) {
                Some(v) => v,
                None if solved.iter().any(|&(s, _)| s == state[k]) => {
                    deferred.push(k);
                    continue;
                }
                None => {
                    return Err(LinearizeError::usage(
                        format!("the model states no value of `{}`", names[k]),
                        format!("give it with `--at \"{}=…\"`", names[k]),
                    ))
                }
            },
        };
        if !v.is_finite() {
            return Err(LinearizeError::undefined(
                format!(
                    "the model's initial `{}` is {v} with these params",
                    names[k]
                ),
                format!("give it with `--at \"{}=…\"`", names[k]),
            ));
        }
        values.insert(state[k], v);
    }
    // In stage order: a stage may use the values of the stages before it.
    for &(symbol, e) in &solved {
        let Some(&k) = deferred.iter().find(|&&k| state[k] == symbol) else {
            continue;
        };
        let e = arena.subst(e, &subst);
        let v = arena.eval(e, &|s| match s {
            Symbol::Time => t,
            Symbol::Param(j) => params.values.get(j as usize).copied().unwrap_or(f64::NAN),
            other => values.get(&other).copied().unwrap_or(f64::NAN),
        });
        if !v.is_finite() {
            return Err(LinearizeError::undefined(
                format!("`{}` as (4) gives it here is {v}", names[k]),
                format!("give it with `--at \"{}=…\"`", names[k]),
            ));
        }
        values.insert(symbol, v);
    }
    if let Some(c) = &closure {
        close(
            &mut arena,
            model,
            c,
            &bound,
            &state,
            &names,
            &at,
            &params.values,
            t,
            &mut values,
        )?;
    }
    let pv = params.values.clone();
    let env_of = |values: &HashMap<Symbol, f64>, pv: &[f64], t: f64| {
        let values = values.clone();
        let pv = pv.to_vec();
        move |s: Symbol| match s {
            Symbol::Time => t,
            Symbol::Param(j) => pv.get(j as usize).copied().unwrap_or(f64::NAN),
            other => values.get(&other).copied().unwrap_or(f64::NAN),
        }
    };
    let mut fixed_values = Vec::new();
    for &(k, phi) in &fixed {
        let env = env_of(&values, &pv, t);
        let v = arena.eval(phi, &env);
        if !v.is_finite() {
            return Err(LinearizeError::undefined(
                format!(
                    "the constraint's value of `{}` is {v} at this point",
                    names[k]
                ),
                "the constraint has no value here (a pole or the end of its domain): choose another point",
            ));
        }
        if let Some(&(_, g)) = at.iter().find(|&&(i, _)| i == k) {
            if (g - v).abs() > 1e-9 * (1.0 + v.abs()) {
                return Err(LinearizeError::usage(
                    format!(
                        "`{}={g}` in `--at` violates the constraints, which fix it at {v} here",
                        names[k]
                    ),
                    format!(
                        "leave `{}` out: the constraints compute it from the rest of the state",
                        names[k]
                    ),
                ));
            }
        }
        fixed_values.push((names[k].clone(), v));
    }

    // The highest derivatives of an implicit system at the point.
    let z = match &implicit {
        Some(imp) => solve_highest(&arena, imp, &env_of(&values, &pv, t))?,
        None => Vec::new(),
    };
    if let Some(imp) = &implicit {
        for (&s, &v) in imp.unknowns.iter().zip(&z) {
            values.insert(s, v);
        }
    }
    let env = env_of(&values, &pv, t);

    // Symbolic partials of each rate in each free component.
    let columns: Vec<Symbol> = free.iter().chain(&bound).map(|&k| state[k]).collect();
    let partials = Partials::new(&mut arena, &rates, implicit.as_ref(), &columns);
    // Which free columns the holonomic constraints hold (through them a
    // row that holds a dependent position holds those positions too).
    let through_closure: Vec<bool> = match &closure {
        Some(c) => free
            .iter()
            .map(|&k| {
                c.residual.iter().any(|&f| {
                    let d = arena.diff(f, state[k]);
                    !vanishes(&arena, d, &env_of(&values, &pv, t), None)
                })
            })
            .collect(),
        None => vec![false; free.len()],
    };

    // Ignorable coordinates: the greatest set of free positions that no
    // other row's rate depends on.
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

    // A on the free state, then restricted to the kept components.
    let g_z = implicit
        .as_ref()
        .map(|imp| matrix(&arena, &imp.jacobian, &env));
    let mut a_free = evaluate_rows(
        &arena,
        &rates,
        &partials.state,
        &partials.g_state,
        &partials.d_z,
        g_z.as_ref(),
        &env,
        columns.len(),
    )?;
    let free_symbols: Vec<Symbol> = free.iter().map(|&k| state[k]).collect();
    if let Some(c) = &closure {
        let dz = closure_slopes(&mut arena, c, &free_symbols, &env)?;
        chain_through(&mut a_free, &dz, free.len());
    }
    let a: Vec<Vec<f64>> = kept
        .iter()
        .map(|&i| kept.iter().map(|&c| a_free[i][c]).collect())
        .collect();
    for (r, row) in a.iter().enumerate() {
        for (c, v) in row.iter().enumerate() {
            if !v.is_finite() {
                let (rk, ck) = (free[kept[r]], free[kept[c]]);
                return Err(LinearizeError::undefined(
                    format!(
                        "A is not defined at this point: ∂({})/∂{} is {v}",
                        rate_name(&arena, state[rk]),
                        names[ck]
                    ),
                    "the right side divides by zero or leaves a function's domain here: choose another point",
                ));
            }
        }
    }

    // ∂f/∂p and ∂f/∂u (the inputs' stand-ins after the params), the params'
    // total through the params declared after each.
    let np_all = params.values.len();
    let param_partials = Partials::new(
        &mut arena,
        &rates,
        implicit.as_ref(),
        &(0..np_all as u32).map(Symbol::Param).collect::<Vec<_>>(),
    );
    let mut b_partial = evaluate_rows(
        &arena,
        &rates,
        &param_partials.state,
        &param_partials.g_state,
        &param_partials.d_z,
        g_z.as_ref(),
        &env,
        np_all,
    )?;
    if let Some(c) = &closure {
        // The dependent positions move with the params too.
        let through: Vec<Vec<f64>> = a_free
            .iter()
            .map(|row| row[free.len()..].to_vec())
            .collect();
        let param_symbols: Vec<Symbol> = (0..np_all as u32).map(Symbol::Param).collect();
        let dz = closure_slopes(&mut arena, c, &param_symbols, &env)?;
        for (row, bound_row) in b_partial.iter_mut().zip(&through) {
            for (p, cell) in row.iter_mut().enumerate() {
                *cell += bound_row
                    .iter()
                    .zip(&dz)
                    .map(|(a, dzd)| a * dzd[p])
                    .sum::<f64>();
            }
        }
    }
    let chain = param_chain(&mut arena, &params, &env);
    let b_params: Vec<Vec<f64>> = kept
        .iter()
        .map(|&i| {
            (0..np)
                .map(|j| {
                    (0..np)
                        .map(|k| b_partial[i][k] * chain[k][j])
                        .filter(|v| *v != 0.0)
                        .sum()
                })
                .collect()
        })
        .collect();
    let b_inputs: Vec<Vec<f64>> = kept.iter().map(|&i| b_partial[i][np..].to_vec()).collect();

    // The residual f at the point, zero to rounding or not.
    let mut residual = Vec::with_capacity(kept.len());
    let mut equilibrium = true;
    for &i in &kept {
        let (value, scale) = match rates[i] {
            Rate::Expr(e) | Rate::Dependent(e) => {
                let s = eval_scaled(&arena, &[e], &env)[0];
                (s.value, s.scale)
            }
            Rate::Unknown(j) => {
                let imp = implicit
                    .as_ref()
                    .map(|imp| imp.residual.clone())
                    .unwrap_or_default();
                let scales = eval_scaled(&arena, &imp, &env);
                let g_scale = scales.iter().map(|s| s.scale).fold(0.0, f64::max);
                let pivot = g_z.as_ref().map_or(1.0, |m| {
                    m.row(j).iter().map(|v| v.abs()).fold(0.0, f64::max)
                });
                (z[j], z[j].abs() + g_scale / pivot.max(f64::MIN_POSITIVE))
            }
        };
        if !value.is_finite() {
            return Err(LinearizeError::undefined(
                format!(
                    "the right side is not defined at this point: {} is {value}",
                    rate_name(&arena, state[free[i]])
                ),
                "the right side divides by zero or leaves a function's domain here: choose another point",
            ));
        }
        // Written so that a scale that is not a number (a part the
        // evaluation could not scale) cannot call a non-zero rate zero.
        let zero = value == 0.0 || value.abs() <= ZERO * scale;
        if !zero {
            equilibrium = false;
        }
        residual.push(value);
    }

    let eigenvalues = eigen::eigenvalues(&a);
    let symbolic = if request.symbolic {
        Some(symbolic(
            &mut arena,
            &SymbolicInput {
                free: &free,
                kept: &kept,
                state: &state,
                rates: &rates,
                partials: &partials,
                implicit: implicit.as_ref(),
                at: &at,
                overrides: &overrides,
                inputs: &given_inputs,
                model,
                t: request.t.as_ref().map(|_| t),
            },
        ))
    } else {
        None
    };
    Ok(Linearization {
        t,
        state: kept.iter().map(|&i| names[free[i]].clone()).collect(),
        point: kept.iter().map(|&i| values[&state[free[i]]]).collect(),
        ignorable: ignorable
            .iter()
            .map(|&i| (names[free[i]].clone(), values[&state[free[i]]]))
            .collect(),
        fixed: fixed_values,
        mode: None,
        a,
        params: model.params.iter().map(|p| p.name.clone()).collect(),
        b_params,
        inputs: model.inputs.iter().map(|u| u.name.clone()).collect(),
        b_inputs,
        eigenvalues,
        residual,
        equilibrium,
        symbolic,
    })
}

/// The name of the rate of a state component: `th'` for `th`, `th''` for `th'`.
pub(super) fn rate_name(arena: &Arena, s: Symbol) -> String {
    match s {
        Symbol::Jet { coord, order } => arena.symbol_name(Symbol::Jet {
            coord,
            order: order + 1,
        }),
        other => arena.symbol_name(other),
    }
}

/// The symbolic partials of every rate in a list of variables.
pub(super) struct Partials {
    /// Per rate: for `Expr`/`Dependent` rates `∂rate/∂v` per variable
    /// (empty for `Unknown`).
    pub(super) state: Vec<Vec<ExprId>>,
    /// `∂G_r/∂v` per residual row and variable.
    pub(super) g_state: Vec<Vec<ExprId>>,
    /// Per rate: `∂D/∂z_k` for `Dependent` rates.
    pub(super) d_z: Vec<Vec<ExprId>>,
    /// The number of variables.
    pub(super) columns: usize,
}

impl Partials {
    pub(super) fn new(
        arena: &mut Arena,
        rates: &[Rate],
        implicit: Option<&Implicit>,
        vars: &[Symbol],
    ) -> Partials {
        let mut state = Vec::with_capacity(rates.len());
        let mut d_z = Vec::with_capacity(rates.len());
        for rate in rates {
            match *rate {
                Rate::Expr(e) | Rate::Dependent(e) => {
                    state.push(vars.iter().map(|&v| arena.diff(e, v)).collect());
                    let dz = match (rate, implicit) {
                        (Rate::Dependent(_), Some(imp)) => {
                            imp.unknowns.iter().map(|&z| arena.diff(e, z)).collect()
                        }
                        _ => Vec::new(),
                    };
                    d_z.push(dz);
                }
                Rate::Unknown(_) => {
                    state.push(Vec::new());
                    d_z.push(Vec::new());
                }
            }
        }
        let g_state = implicit.map_or_else(Vec::new, |imp| {
            imp.residual
                .iter()
                .map(|&g| vars.iter().map(|&v| arena.diff(g, v)).collect())
                .collect()
        });
        Partials {
            state,
            g_state,
            d_z,
            columns: vars.len(),
        }
    }
}

pub(super) fn matrix(
    arena: &Arena,
    cells: &[Vec<ExprId>],
    env: &dyn Fn(Symbol) -> f64,
) -> DMatrix<f64> {
    let rows = cells.len();
    let cols = cells.first().map_or(0, Vec::len);
    DMatrix::from_fn(rows, cols, |r, c| arena.eval(cells[r][c], env))
}

/// `G(t, x, z) = 0` solved for `z` at the point: one linear solve, or
/// Newton from `z = 0` with the exact `G_z`.
pub(super) fn solve_highest(
    arena: &Arena,
    imp: &Implicit,
    env: &dyn Fn(Symbol) -> f64,
) -> Result<Vec<f64>, LinearizeError> {
    let m = imp.unknowns.len();
    let mut z = vec![0.0; m];
    let iterations = if imp.linear { 1 } else { 50 };
    for _ in 0..iterations {
        let at = |s: Symbol| match imp.unknowns.iter().position(|&u| u == s) {
            Some(k) => z[k],
            None => env(s),
        };
        let g = DVector::from_iterator(m, imp.residual.iter().map(|&e| arena.eval(e, &at)));
        let jz = matrix(arena, &imp.jacobian, &at);
        let step = jz
            .clone()
            .lu()
            .solve(&(-&g))
            .filter(|s| s.iter().all(|v| v.is_finite()));
        let Some(step) = step else {
            return Err(singular_mass_matrix(arena, imp));
        };
        let size = step.amax();
        for (zk, dk) in z.iter_mut().zip(step.iter()) {
            *zk += dk;
        }
        if size <= 1e-14 * (1.0 + z.iter().fold(0.0_f64, |a, v| a.max(v.abs()))) {
            break;
        }
    }
    Ok(z)
}

fn singular_mass_matrix(arena: &Arena, imp: &Implicit) -> LinearizeError {
    let names: Vec<String> = imp.unknowns.iter().map(|&s| arena.symbol_name(s)).collect();
    LinearizeError::undefined(
        format!(
            "the highest derivatives ({}) are not defined at this point: the matrix of their \
             coefficients is singular",
            names.join(", ")
        ),
        "a singular mass matrix or a vanishing pivot of the constraints: choose another point",
    )
}

/// `∂rate_i/∂v_c` evaluated, one row per rate: `Expr` rows directly,
/// `Unknown` rows `−G_z⁻¹ G_v`, `Dependent` rows `D_v + D_z z_v`.
#[allow(clippy::too_many_arguments)]
fn evaluate_rows(
    arena: &Arena,
    rates: &[Rate],
    partial: &[Vec<ExprId>],
    g_partial: &[Vec<ExprId>],
    d_z: &[Vec<ExprId>],
    g_z: Option<&DMatrix<f64>>,
    env: &dyn Fn(Symbol) -> f64,
    columns: usize,
) -> Result<Vec<Vec<f64>>, LinearizeError> {
    let z_v = match g_z {
        Some(jz) => {
            let gv = matrix(arena, g_partial, env);
            if gv.nrows() == 0 {
                Some(DMatrix::zeros(0, 0))
            } else {
                let lu = jz.clone().lu();
                match lu.solve(&(-gv)) {
                    Some(s) => Some(s),
                    None => {
                        return Err(LinearizeError::undefined(
                            "the highest derivatives' coefficients are singular at this point",
                            "choose another point",
                        ))
                    }
                }
            }
        }
        None => None,
    };
    let mut rows = Vec::with_capacity(rates.len());
    for (i, rate) in rates.iter().enumerate() {
        let row: Vec<f64> = match *rate {
            Rate::Expr(_) => partial[i].iter().map(|&e| arena.eval(e, env)).collect(),
            Rate::Unknown(j) => match &z_v {
                Some(zv) if zv.nrows() > j => zv.row(j).iter().copied().collect(),
                _ => vec![f64::NAN; columns],
            },
            Rate::Dependent(_) => {
                let direct: Vec<f64> = partial[i].iter().map(|&e| arena.eval(e, env)).collect();
                let dz: Vec<f64> = d_z[i].iter().map(|&e| arena.eval(e, env)).collect();
                direct
                    .iter()
                    .enumerate()
                    .map(|(c, &v)| {
                        let through: f64 = match &z_v {
                            Some(zv) => dz
                                .iter()
                                .enumerate()
                                .filter(|&(_, &d)| d != 0.0)
                                .map(|(k, &d)| d * zv[(k, c)])
                                .sum(),
                            None => 0.0,
                        };
                        v + through
                    })
                    .collect()
            }
        };
        rows.push(row);
    }
    Ok(rows)
}

/// `T[k][j] = dp_k/dp_j` with the params after `p_j` recomputed from it
/// (an overridden one is not recomputed).
fn param_chain(arena: &mut Arena, params: &Params, env: &dyn Fn(Symbol) -> f64) -> Vec<Vec<f64>> {
    // The model's params only (the inputs' stand-ins follow their values).
    let np = params.exprs.len();
    let mut t = vec![vec![0.0; np]; np];
    for k in 0..np {
        t[k][k] = 1.0;
        if params.overridden[k] {
            continue;
        }
        for l in 0..k {
            let d = arena.diff(params.exprs[k], Symbol::Param(l as u32));
            if arena.is_zero(d) {
                continue;
            }
            let slope = arena.eval(d, env);
            let (done, rest) = t.split_at_mut(k);
            for (sum, &through) in rest[0].iter_mut().zip(&done[l]).take(l + 1) {
                *sum += slope * through;
            }
        }
    }
    t
}
