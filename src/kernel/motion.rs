//! The motion `x' = X(t, x)` of the reduced system (7) with its exact
//! Jacobian `∂X/∂x` and time partial `∂X/∂t`.
//!
//! Explicit systems: the highest derivatives are expressions, and so are
//! their partials. Implicit systems: the independent highest derivatives
//! `z` solve `G(t, x, z) = 0`; the kernel holds `G`, `∂G/∂z`, `∂G/∂x`,
//! `∂G/∂t` and the dependent highest derivatives `D(t, x, z)` with their
//! partials, and the generated code gets `∂z/∂x = −G_z⁻¹ G_x` by implicit
//! differentiation at run time — no finite differences.

use super::time::TimeDependence;
use crate::ir::{Arena, ExprId, Symbol};
use crate::mechanics::{Highest, ReducedSystem};
use std::collections::HashMap;

#[derive(Debug, Clone)]
pub enum Motion {
    Explicit(Explicit),
    Implicit(Implicit),
}

#[derive(Debug, Clone)]
pub struct Explicit {
    /// `q_j^(u)` for every coordinate `j`.
    pub rhs: Vec<ExprId>,
    /// The non-zero `(row, column, ∂X_row/∂x_column)` of the highest rows.
    pub jacobian: Vec<(usize, usize, ExprId)>,
    /// The non-zero `(row, ∂X_row/∂t)`.
    pub time_partial: Vec<(usize, ExprId)>,
}

#[derive(Debug, Clone)]
pub struct Implicit {
    /// `z`: the independent highest derivatives.
    pub unknowns: Vec<Symbol>,
    /// `G` is affine in `z`: `G = G_z z + G(z = 0)`, one linear solve.
    pub linear: bool,
    /// `G(t, x, z)`, one row per unknown.
    pub residual: Vec<ExprId>,
    /// `G(t, x, 0)` (linear systems).
    pub free: Vec<ExprId>,
    /// Non-zero cells `(row, unknown, ∂G/∂z)`.
    pub g_z: Vec<(usize, usize, ExprId)>,
    /// A linear system whose `G_z` is symmetric cell by cell (the same
    /// expression at `(r, c)` and `(c, r)`): a Lagrangian's mass matrix,
    /// solved by `L D Lᵀ` (LU when that fails).
    pub symmetric: bool,
    /// Non-zero cells `(row, state column, ∂G/∂x)`.
    pub g_x: Vec<(usize, usize, ExprId)>,
    /// Non-zero `(row, ∂G/∂t)` (true time partial).
    pub g_t: Vec<(usize, ExprId)>,
    pub dependent: Vec<Dependent>,
}

/// A dependent coordinate's highest derivative `D(t, x, z)`.
#[derive(Debug, Clone)]
pub struct Dependent {
    pub coord: u32,
    pub value: ExprId,
    pub d_x: Vec<(usize, ExprId)>,
    pub d_z: Vec<(usize, ExprId)>,
    pub d_t: ExprId,
}

fn nonzero(
    arena: &Arena,
    cells: impl IntoIterator<Item = (usize, usize, ExprId)>,
) -> Vec<(usize, usize, ExprId)> {
    cells
        .into_iter()
        .filter(|&(_, _, e)| !arena.is_zero(e))
        .collect()
}

pub fn motion(arena: &mut Arena, reduced: &ReducedSystem, time: &TimeDependence) -> Motion {
    let coords = reduced.state.len() / reduced.order.max(1) as usize;
    let highest_row = |coord: u32| (reduced.order as usize - 1) * coords + coord as usize;
    match &reduced.highest {
        Highest::Explicit(rhs) => {
            let mut jacobian = Vec::new();
            let mut time_partial = Vec::new();
            // All partials in one pass over the DAG (`Arena::jacobian`).
            let partials = arena.jacobian(rhs, &reduced.state);
            for (j, (&h, cells)) in rhs.iter().zip(partials).enumerate() {
                let row = highest_row(j as u32);
                for (k, d) in cells.into_iter().enumerate() {
                    jacobian.push((row, k, d));
                }
                let d = time.partial(arena, h);
                if !arena.is_zero(d) {
                    time_partial.push((row, d));
                }
            }
            Motion::Explicit(Explicit {
                rhs: rhs.clone(),
                jacobian: nonzero(arena, jacobian),
                time_partial,
            })
        }
        Highest::Implicit {
            unknowns,
            residual,
            jacobian,
            linear,
            dependent,
        } => {
            let zero = arena.zero();
            let at_zero: HashMap<Symbol, ExprId> = unknowns.iter().map(|&z| (z, zero)).collect();
            let free = if *linear {
                arena.subst_all(residual, &at_zero)
            } else {
                Vec::new()
            };
            let g_z = nonzero(
                arena,
                jacobian
                    .iter()
                    .enumerate()
                    .flat_map(|(r, row)| row.iter().enumerate().map(move |(c, &e)| (r, c, e)))
                    .collect::<Vec<_>>(),
            );
            let mut g_x = Vec::new();
            let mut g_t = Vec::new();
            let partials = arena.jacobian(residual, &reduced.state);
            for (r, (&g, cells)) in residual.iter().zip(partials).enumerate() {
                for (k, d) in cells.into_iter().enumerate() {
                    g_x.push((r, k, d));
                }
                let d = time.partial(arena, g);
                if !arena.is_zero(d) {
                    g_t.push((r, d));
                }
            }
            let g_x = nonzero(arena, g_x);
            let dependent = dependent
                .iter()
                .map(|&(coord, value)| {
                    let d_x: Vec<(usize, ExprId)> = reduced
                        .state
                        .iter()
                        .enumerate()
                        .map(|(k, &s)| (k, arena.diff(value, s)))
                        .collect();
                    let d_x = d_x
                        .into_iter()
                        .filter(|&(_, e)| !arena.is_zero(e))
                        .collect();
                    let d_z: Vec<(usize, ExprId)> = unknowns
                        .iter()
                        .enumerate()
                        .map(|(k, &s)| (k, arena.diff(value, s)))
                        .collect();
                    let d_z = d_z
                        .into_iter()
                        .filter(|&(_, e)| !arena.is_zero(e))
                        .collect();
                    let d_t = time.partial(arena, value);
                    Dependent {
                        coord,
                        value,
                        d_x,
                        d_z,
                        d_t,
                    }
                })
                .collect();
            let cells: HashMap<(usize, usize), ExprId> =
                g_z.iter().map(|&(r, c, e)| ((r, c), e)).collect();
            let symmetric = *linear
                && residual.len() == unknowns.len()
                && g_z.iter().all(|&(r, c, e)| cells.get(&(c, r)) == Some(&e));
            Motion::Implicit(Implicit {
                unknowns: unknowns.clone(),
                linear: *linear,
                symmetric,
                residual: residual.clone(),
                free,
                g_z,
                g_x,
                g_t,
                dependent,
            })
        }
    }
}
