//! Holonomic constraints `f(t, q) = 0` at the point: the dependent
//! positions put on them by Newton, and their slopes `∂z/∂v = −f_z⁻¹ f_v`
//! that carry a perturbation of the other positions (or the params) onto
//! the dependent ones.

use super::point;
use super::system::matrix;
use super::LinearizeError;
use crate::check::model::Model;
use crate::ir::{Arena, ExprId, Symbol};
use crate::mechanics::eval_scaled;
use nalgebra::{DMatrix, DVector};
use std::collections::HashMap;

/// The holonomic constraints `f(t, q) = 0` over their dependent positions.
pub(super) struct Closure {
    pub(super) unknowns: Vec<Symbol>,
    pub(super) residual: Vec<ExprId>,
    pub(super) jacobian: Vec<Vec<ExprId>>,
    pub(super) text: String,
}

/// The dependent positions at the point: Newton on `f = 0` over them
/// alone from the values given (or the model's), as at `t0`; a value
/// given that is not on the constraints is an error.
#[allow(clippy::too_many_arguments)]
pub(super) fn close(
    arena: &mut Arena,
    model: &Model,
    c: &Closure,
    bound: &[usize],
    state: &[Symbol],
    names: &[String],
    at: &[(usize, f64)],
    params: &[f64],
    t: f64,
    values: &mut HashMap<Symbol, f64>,
) -> Result<(), LinearizeError> {
    let mut guess = Vec::with_capacity(bound.len());
    for &k in bound {
        let given = at.iter().find(|&&(i, _)| i == k).map(|&(_, v)| v);
        let v = given
            .or_else(|| point::stated(arena, model, state[k], params))
            .ok_or_else(|| {
                LinearizeError::usage(
                    format!("the model states no value of `{}`", names[k]),
                    format!("give it with `--at \"{}=…\"`", names[k]),
                )
            })?;
        values.insert(state[k], v);
        guess.push(v);
    }
    let m = c.unknowns.len();
    for _ in 0..50 {
        let env = |s: Symbol| match s {
            Symbol::Time => t,
            Symbol::Param(j) => params.get(j as usize).copied().unwrap_or(f64::NAN),
            other => values.get(&other).copied().unwrap_or(f64::NAN),
        };
        let f = DVector::from_iterator(m, c.residual.iter().map(|&e| arena.eval(e, &env)));
        let scale = eval_scaled(arena, &c.residual, &env)
            .iter()
            .fold(0.0_f64, |a, s| a.max(s.scale));
        if f.iter().all(|v| v.abs() <= 1e-14 * scale.max(1e-300)) {
            break;
        }
        let jz = matrix(arena, &c.jacobian, &env);
        let Some(step) = jz
            .lu()
            .solve(&(-f))
            .filter(|s| s.iter().all(|v| v.is_finite()))
        else {
            return Err(LinearizeError::undefined(
                format!(
                    "the holonomic constraints {} cannot be solved for their dependent positions here (their Jacobian is singular)",
                    c.text
                ),
                "choose another point, or give the dependent positions on the constraints",
            ));
        };
        for (u, d) in c.unknowns.iter().zip(step.iter()) {
            if let Some(v) = values.get_mut(u) {
                *v += d;
            }
        }
    }
    for (&k, g) in bound.iter().zip(&guess) {
        let v = values[&state[k]];
        let given = at.iter().any(|&(i, _)| i == k);
        let residual = c.residual.iter().map(|&e| {
            arena.eval(e, &|s| match s {
                Symbol::Time => t,
                Symbol::Param(j) => params.get(j as usize).copied().unwrap_or(f64::NAN),
                other => values.get(&other).copied().unwrap_or(f64::NAN),
            })
        });
        if residual
            .clone()
            .any(|r| !r.is_finite() || r.abs() > 1e-8 * (1.0 + v.abs()))
        {
            return Err(LinearizeError::undefined(
                format!(
                    "no configuration on the holonomic constraints {} near this point",
                    c.text
                ),
                "choose positions on (or near) the constraints",
            ));
        }
        if given && (v - g).abs() > 1e-9 * (1.0 + v.abs()) {
            return Err(LinearizeError::usage(
                format!(
                    "`{}={g}` in `--at` is off the holonomic constraints {}, which put it at {v} here",
                    names[k], c.text
                ),
                format!("leave `{}` out: it is computed from the other positions", names[k]),
            ));
        }
    }
    Ok(())
}

/// `∂z/∂v = −f_z⁻¹ ∂f/∂v` for the dependent positions `z`, one row per
/// `z`, one column per variable.
pub(super) fn closure_slopes(
    arena: &mut Arena,
    c: &Closure,
    vars: &[Symbol],
    env: &dyn Fn(Symbol) -> f64,
) -> Result<Vec<Vec<f64>>, LinearizeError> {
    let m = c.unknowns.len();
    let fv: Vec<Vec<ExprId>> = c
        .residual
        .iter()
        .map(|&f| vars.iter().map(|&v| arena.diff(f, v)).collect())
        .collect();
    let fz = matrix(arena, &c.jacobian, env);
    let fv = DMatrix::from_fn(m, vars.len(), |r, k| arena.eval(fv[r][k], env));
    let slopes = fz.lu().solve(&(-fv)).ok_or_else(|| {
        LinearizeError::undefined(
            format!("the holonomic constraints {} are singular here", c.text),
            "choose another point",
        )
    })?;
    Ok((0..m)
        .map(|r| slopes.row(r).iter().copied().collect())
        .collect())
}

/// `A[r][c] += Σ_d A[r][free + d] ∂z_d/∂x_c` for the free columns.
pub(super) fn chain_through(a: &mut [Vec<f64>], dz: &[Vec<f64>], free: usize) {
    for row in a.iter_mut() {
        let through: Vec<f64> = row[free..].to_vec();
        for (c, cell) in row.iter_mut().take(free).enumerate() {
            *cell += through
                .iter()
                .zip(dz)
                .map(|(a, dzd)| a * dzd[c])
                .sum::<f64>();
        }
    }
}
