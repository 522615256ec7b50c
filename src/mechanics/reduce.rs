//! The reduced system (7) (SPEC §1.4): `q^(u) = X(t, q, …, q^(u−1))`,
//! `u = max(2, k)`.
//!
//! - k ≤ 2: (4) holds the independent `q_i''`; the dependent `q_d''` follow
//!   from the constraints (`Dφ_d` for k = 1, `φ_d` for k = 2).
//! - k ≥ 3: (4) is differentiated k−2 times (true time derivative: masses
//!   replaced by their laws first) to reach `q_i^(k)`; the dependent
//!   `q_d^(k) = φ_d`. The lower derivatives of (4) fix the independent
//!   `q_i^(2..k−1)` at `t0` (the consistency stages).

use super::reduced::{Consistency, Highest};
use super::singular::check_mass_matrix;
use super::solve::System;
use super::star::Elimination;
use super::symbols::Symbolic;
use super::tidy::tidy;
use crate::diagnostic::{codes, Diagnostic};
use crate::ir::{Arena, ExprId, Symbol};
use crate::span::Span;
use std::collections::HashMap;

/// For k ≥ 3 the rows of (4) must be of second order in the independent
/// coordinates: they are differentiated k − 2 times to reach order k. A
/// constraint whose derivative with respect to its highest derivatives
/// holds higher ones (`y^(4) = a·x^(4)²`: `∂φ/∂x^(4) = 2a·x^(4)`) puts
/// them into (4), and the same differentiation would pass the state
/// (`x^(6)` in a state that ends at `x^(3)`): refused, not derived wrongly.
fn refuse_rows_above_second_order(
    arena: &Arena,
    model: &Symbolic,
    rows: &[ExprId],
    constraint: Span,
) -> Result<(), Diagnostic> {
    let highest = rows
        .iter()
        .flat_map(|&row| arena.free_symbols(row))
        .filter_map(|s| match s {
            Symbol::Jet { coord, order } if model.independent.contains(&coord) => {
                Some((order, coord))
            }
            _ => None,
        })
        .max();
    match highest {
        Some((order, coord)) if order > 2 => {
            let name = arena.symbol_name(Symbol::Jet { coord, order: 0 });
            let k = model.k;
            Err(Diagnostic::error(
                codes::UNSUPPORTED_REDUCTION,
                format!(
                    "with this constraint the equations of motion (4) hold a derivative of \
                     order {order} of `{name}`"
                ),
            )
            .with_primary(
                constraint,
                "its derivative with respect to its highest derivatives holds derivatives \
                 above the second",
            )
            .with_note(format!(
                "for a constraint of order k = {k} ≥ 3, lagc differentiates (4) k − 2 times \
                 to reach order k (SPEC §1.4); from order {order} that reaches order {} and \
                 passes the state, and the reduction of such systems is not implemented",
                order + k - 2,
            ))
            .with_help(
                "write the constraint linear in its highest derivatives, with coefficients \
                 free of derivatives above the second",
            ))
        }
        _ => Ok(()),
    }
}

#[derive(Debug, Clone)]
pub struct Reduction {
    pub highest: Highest,
    /// `∂(4)/∂q_i^(u)`: the mass matrix of the highest derivatives.
    pub mass_matrix: Vec<Vec<ExprId>>,
    pub consistency: Vec<Consistency>,
}

/// Reduces the rows of (4) (`lhs − rhs`, masses divided out where they
/// factor) to the highest derivatives.
pub fn reduce(
    arena: &mut Arena,
    model: &Symbolic,
    elimination: &mut Elimination,
    rows: &[ExprId],
    lagrangian: Span,
    constraint: Option<Span>,
) -> Result<Reduction, Diagnostic> {
    let (k, u) = (model.k, model.u());
    if k >= 3 {
        refuse_rows_above_second_order(arena, model, rows, constraint.unwrap_or(lagrangian))?;
    }
    let masses = model.laws.len();
    let defaults = &model.param_defaults;
    // For k ≥ 3 the rows are differentiated in time: D must see the masses
    // vary, so they become their laws.
    let rows: Vec<ExprId> = if k >= 3 {
        let laws: HashMap<Symbol, ExprId> = model
            .laws
            .iter()
            .enumerate()
            .map(|(i, &law)| (Symbol::Mass(i as u32), law))
            .collect();
        rows.iter().map(|&r| arena.subst(r, &laws)).collect()
    } else {
        rows.to_vec()
    };
    let top_rows: Vec<ExprId> = rows
        .iter()
        .map(|&r| {
            let d = arena.total_derivative_n(r, u - 2);
            elimination.eliminate(arena, d)
        })
        .collect();
    let mut system = System::new(arena, top_rows, model.independent_jets(u), defaults, masses);
    check_mass_matrix(
        arena,
        &system.jacobian,
        &system.unknowns,
        defaults,
        masses,
        lagrangian,
    )?;
    let mass_matrix = system.jacobian.clone();
    system.solve_symbolically(arena);
    let dependent: Vec<(u32, ExprId)> = model
        .dependent()
        .into_iter()
        .map(|d| (d, elimination.image(arena, d, u)))
        .collect();
    let highest = match &system.explicit {
        Some(solution) => {
            let by_unknown: HashMap<Symbol, ExprId> = system
                .unknowns
                .iter()
                .copied()
                .zip(solution.iter().copied())
                .collect();
            let n = model.independent.len() + dependent.len();
            let mut exprs = Vec::with_capacity(n);
            for coord in 0..n as u32 {
                let z = Symbol::Jet { coord, order: u };
                let e = match by_unknown.get(&z) {
                    Some(&e) => e,
                    None => match dependent.iter().find(|&&(d, _)| d == coord) {
                        Some(&(_, image)) => arena.subst(image, &by_unknown),
                        None => arena.constant(f64::NAN),
                    },
                };
                exprs.push(e);
            }
            // The readable form (jets collected, each coefficient in its
            // smallest form) unless it costs more operations than the
            // solution as found: the generated right side evaluates these,
            // sharing sub-expressions across them (Cramer's rule on a
            // pendulum's 2×2 mass matrix shares its rows; tidying each
            // apart loses that).
            let tidied: Vec<ExprId> = exprs.iter().map(|&e| tidy(arena, e)).collect();
            if arena.op_count(&tidied) <= arena.op_count(&exprs) {
                exprs = tidied;
            }
            Highest::Explicit(exprs)
        }
        None => Highest::Implicit {
            unknowns: system.unknowns.clone(),
            residual: system.rows.clone(),
            jacobian: system.jacobian.clone(),
            linear: system.linear,
            dependent,
        },
    };
    let consistency = (2..k)
        .map(|order| {
            let stage_rows: Vec<ExprId> = rows
                .iter()
                .map(|&r| {
                    let d = arena.total_derivative_n(r, order - 2);
                    elimination.eliminate(arena, d)
                })
                .collect();
            let mut stage = System::new(
                arena,
                stage_rows,
                model.independent_jets(order),
                defaults,
                masses,
            );
            stage.solve_symbolically(arena);
            let explicit = stage
                .explicit
                .map(|sol| sol.into_iter().map(|e| tidy(arena, e)).collect());
            Consistency {
                unknowns: stage.unknowns,
                residual: stage.rows,
                jacobian: stage.jacobian,
                linear: stage.linear,
                explicit,
            }
        })
        .collect();
    Ok(Reduction {
        highest,
        mass_matrix,
        consistency,
    })
}
