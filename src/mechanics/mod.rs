//! Stage 4: the checked model → equations (4) and the reduced first-order
//! system (7) (SPEC §1.2–§1.4).
//!
//! | file | what |
//! |---|---|
//! | `symbols.rs` | the model lowered: L, mass laws, constraints φ |
//! | `coupled.rs` | implicit and holonomic constraints solved together (Cramer) |
//! | `raised.rs` | a group of raised constraints kept by Newton over its candidates |
//! | `star.rs` | the order-matched star; eliminating dependent derivatives |
//! | `reactive_forces.rs` | `R_j` of the variable-mass points |
//! | `generalized_forces.rs` | the declared `Q_j` |
//! | `equations.rs` | equations (4) |
//! | `multiplier_route.rs` | the independent cross-check through `E_j` |
//! | `mass_factor.rs` | dividing mass laws out of the equations |
//! | `solve.rs` | solving for the highest derivatives |
//! | `singular.rs` | the identically singular mass matrix (E0015) |
//! | `reduce.rs` | the reduced system (7) |
//! | `initial.rs` | the initial values of the state (6) |
//! | `reduced.rs` | the output contract for the field method and emitter |
//! | `tidy.rs`, `text.rs` | readable text and LaTeX |
//! | `sample.rs` | random points and rounding scales for numeric checks |

pub mod coupled;
mod equations;
mod generalized_forces;
mod initial;
mod jet_coefficients;
mod mass_factor;
mod multiplier_route;
mod raised;
mod reactive_forces;
mod reduce;
pub mod reduced;
mod sample;
pub use sample::{eval_scaled, Rng, Scaled};
mod singular;
mod solve;
mod star;
mod symbols;
mod text;
pub mod tidy;

pub use equations::Equation4;
pub use multiplier_route::{cross_check, CrossCheck, CrossCheckFailure};
pub use reduced::{Closure, Consistency, Highest, InitialValue, ReducedSystem};

use crate::check::model::Model;
use crate::diagnostic::Diagnostic;
use crate::ir::{names_of, Arena, ExprId, Symbol};
use star::Elimination;
use std::collections::HashMap;
use symbols::Symbolic;

/// Everything the mechanics derived from one model.
#[derive(Debug, Clone)]
pub struct Derivation {
    /// The arena every `ExprId` below points into.
    pub arena: Arena,
    /// n: the number of coordinates.
    pub coordinates: usize,
    /// The independent coordinates (s of them), declaration order.
    pub independent: Vec<u32>,
    /// The model's constraint order; `None` for a holonomic model.
    pub constraint_order: Option<u32>,
    /// The order `k` used in (4): the constraint order, or 1 when holonomic.
    pub k: u32,
    /// The Lagrangian `L(t, q, q')`, masses as `Symbol::Mass`.
    pub lagrangian: ExprId,
    /// `(d, φ_d)`: `q_d^(k) = φ_d` (mass symbols replaced by their laws).
    pub constraints: Vec<(u32, ExprId)>,
    /// `R_j + Q_j` for every coordinate, before projection and star.
    pub forces: Vec<ExprId>,
    /// Equations (4), one per independent coordinate.
    pub equations: Vec<Equation4>,
    /// For each equation: the mass divided out of it in the reduced system.
    pub divided_out: Vec<Option<u32>>,
    /// `(i, law_i)` for every mass law of the state (SPEC §2.3), in index
    /// order: a symbol in `L` and (4), its expression in (7) and after.
    pub state_laws: Vec<(u32, ExprId)>,
    /// With laws of the state: `R_j + Q_j` again, each point's `Ṁ` the
    /// total derivative of its mass through those laws (the cross-check's
    /// route along the motion); empty without them.
    pub forces_along_motion: Vec<ExprId>,
    /// The reduced system (7).
    pub reduced: ReducedSystem,
    /// The model's lets that the derivation used, by name, as lowered
    /// (a number or a vector's components), in declaration order.
    pub lets: Vec<(String, Vec<ExprId>)>,
    /// Param defaults, for numeric checks.
    pub param_defaults: Vec<f64>,
    /// The implicit constraints of order k as solved (`Symbolic::written`).
    pub written: Vec<(String, ExprId)>,
    /// The holonomic constraints `f = 0` as written (mass symbols kept)
    /// and the form of order k the mechanics solves, `D^k f = 0`.
    pub holonomic: Vec<(ExprId, ExprId)>,
    /// The non-linear implicit constraints `f = 0` as written and the
    /// derivative the mechanics solves, `D f = 0` (`Implicit::raised`).
    pub raised: Vec<(ExprId, ExprId)>,
    /// Notes for the build (an initial position that Newton moved onto
    /// the constraints).
    pub notes: Vec<Diagnostic>,
}

impl Derivation {
    /// The dependent coordinates, in constraint order.
    pub fn dependent(&self) -> Vec<u32> {
        self.constraints.iter().map(|&(d, _)| d).collect()
    }
}

/// [`derive`], then the [`cross_check`] of its equations (4) against the
/// multiplier route, a failure of which is an error (E0033). Every path —
/// `lagc check`, `derive`, `build`, `run`, `report` — derives through this
/// one function, so none integrates equations the others would refuse.
pub fn derive_checked(model: &Model) -> Result<(Derivation, CrossCheck), Vec<Diagnostic>> {
    let mut derivation = derive(model)?;
    match cross_check(&mut derivation) {
        Ok(check) => Ok((derivation, check)),
        Err(failure) => Err(vec![failure.diagnostic(model.lagrangian.span)]),
    }
}

/// Derives equations (4) and the reduced system (7) of a checked model.
pub fn derive(model: &Model) -> Result<Derivation, Vec<Diagnostic>> {
    derive_with(model, true)
}

/// [`derive_checked`] for one more mode of a model with implicit
/// constraints: the motion only (the initial state is mode 0's, whose
/// dependent derivatives differ).
pub fn derive_mode_checked(model: &Model) -> Result<Derivation, Vec<Diagnostic>> {
    let mut derivation = derive_with(model, false)?;
    match cross_check(&mut derivation) {
        Ok(_) => Ok(derivation),
        Err(failure) => Err(vec![failure.diagnostic(model.lagrangian.span)]),
    }
}

fn derive_with(model: &Model, with_initial: bool) -> Result<Derivation, Vec<Diagnostic>> {
    let mut arena = Arena::new(names_of(model));
    let symbolic = Symbolic::lower(&mut arena, model)?;
    let mut elimination = Elimination::new(symbolic.k, &symbolic.constraints);
    let none = HashMap::new();
    let reactive = reactive_forces::reactive_forces(&mut arena, model, &symbolic.laws, &none)?;
    let generalized = generalized_forces::generalized_forces(&mut arena, model)?;
    let forces: Vec<ExprId> = reactive
        .iter()
        .zip(&generalized)
        .map(|(&r, &q)| arena.add(&[r, q]))
        .collect();
    // With laws of the state, the forces again with each point's Ṁ the
    // total derivative of its mass written through those laws: the
    // cross-check's route along the motion.
    let state_laws = symbolic.state_laws(&arena);
    let forces_along_motion: Vec<ExprId> = if state_laws.is_empty() {
        Vec::new()
    } else {
        let reactive =
            reactive_forces::reactive_forces(&mut arena, model, &symbolic.laws, &state_laws)?;
        reactive
            .iter()
            .zip(&generalized)
            .map(|(&r, &q)| arena.add(&[r, q]))
            .collect()
    };
    let mut equations = equations::equations(&mut arena, &symbolic, &mut elimination, &forces);
    // sin² + cos² = 1 again: differentiation brings squares of sums apart.
    // One memo for all sides: the equations share most of their nodes.
    let sides: Vec<ExprId> = equations.iter().flat_map(|e| [e.lhs, e.rhs]).collect();
    let paired = arena.pythagoras_all(&sides);
    for (e, sides) in equations.iter_mut().zip(paired.chunks(2)) {
        e.lhs = sides[0];
        e.rhs = sides[1];
    }
    let rows: Vec<ExprId> = equations.iter().map(|e| arena.sub(e.lhs, e.rhs)).collect();
    let divided =
        mass_factor::divide_out_masses(&mut arena, &rows, &symbolic.laws, &symbolic.param_defaults);
    // From (7) on a mass law of the state is its expression of `q`: the
    // reduced system must see the mass move with the state (its ∂X/∂x).
    let rows: Vec<ExprId> = divided
        .iter()
        .map(|d| {
            if state_laws.is_empty() {
                d.row
            } else {
                arena.subst(d.row, &state_laws)
            }
        })
        .collect();
    let reduction = reduce::reduce(
        &mut arena,
        &symbolic,
        &mut elimination,
        &rows,
        model.lagrangian.span,
        model.constraints.first().map(|c| c.span),
    )
    .map_err(|d| vec![d])?;
    let u = symbolic.u();
    let state: Vec<Symbol> = (0..u)
        .flat_map(|order| {
            (0..model.coords.len() as u32).map(move |coord| Symbol::Jet { coord, order })
        })
        .collect();
    // The state components the constraints fix (dependent derivatives of
    // order ≥ k within the state), with the values they require: every
    // mode keeps its own.
    let mut fixed = Vec::new();
    for (i, &symbol) in state.iter().enumerate() {
        if let Symbol::Jet { coord, order } = symbol {
            let dependent = symbolic.constraints.iter().any(|&(d, _)| d == coord);
            if dependent && order >= symbolic.k {
                fixed.push((i, elimination.image(&mut arena, coord, order)));
            }
        }
    }
    let laws: std::collections::HashMap<Symbol, ExprId> = symbolic
        .laws
        .iter()
        .enumerate()
        .map(|(i, &law)| (Symbol::Mass(i as u32), law))
        .collect();
    // A raised constraint (not linear in its candidate `v` of order
    // k − 1) fixes that candidate through `f = 0` as written: the value
    // kept is Newton's `v − f/f_v`, equal to `v` exactly on the
    // constraint, whose partials there are the implicit function's.
    let mut raised = Vec::new();
    let mut directions: Vec<(String, ExprId)> = Vec::new();
    let mut shown_raised = Vec::new();
    let raised_groups = raised::coupled_groups(model);
    let grouped = |i: usize| raised_groups.iter().any(|g| g.constraints.contains(&i));
    for (_, c) in model
        .constraints
        .iter()
        .enumerate()
        .filter(|&(i, c)| c.is_raised() && !grouped(i))
    {
        let f = coupled::written_residual(&mut arena, model, c, &laws).map_err(|d| vec![d])?;
        let v = Symbol::Jet {
            coord: c.coord as u32,
            order: c.order - 1,
        };
        let pivot = arena.diff(f, v);
        let step = arena.div(f, pivot);
        let v_expr = arena.symbol(v);
        let kept = arena.sub(v_expr, step);
        if let Some(i) = state.iter().position(|&s| s == v) {
            fixed.push((i, kept));
        }
        let text = if c.text.is_empty() {
            format!("{} = 0", arena.display(f))
        } else {
            c.text.clone()
        };
        // The cross-check's extra identity: the derivative's reactions are
        // the written constraint's (Chetaev), `∂φ_d/∂q_i^(k) · f_v +
        // ∂f/∂q_i^(k−1) = 0` for every independent `i`. `D f` is linear in
        // the order-k derivatives with the coefficients `∂f/∂q^(k−1)`, so
        // this holds at every point of the jet space, on `f = 0` or off it:
        // the random points need not lie on the constraint.
        if let Some(&(_, phi)) = symbolic
            .constraints
            .iter()
            .find(|&&(d, _)| d == c.coord as u32)
        {
            for &i in &symbolic.independent {
                let d_phi = arena.diff(
                    phi,
                    Symbol::Jet {
                        coord: i,
                        order: c.order,
                    },
                );
                let d_f = arena.diff(
                    f,
                    Symbol::Jet {
                        coord: i,
                        order: c.order - 1,
                    },
                );
                let scaled = arena.mul(&[d_phi, pivot]);
                let identity = arena.add(&[scaled, d_f]);
                let name = arena.symbol_name(Symbol::Jet {
                    coord: i,
                    order: c.order - 1,
                });
                directions.push((format!("{} (its reaction on `{name}`)", c.text), identity));
            }
        }
        let derivative = arena.total_derivative(f);
        shown_raised.push((f, derivative));
        raised.push(initial::Raised {
            candidate: v,
            residual: f,
            pivot,
            text,
        });
    }
    // Raised constraints solved together: Newton over the group.
    let mut newton_groups = Vec::new();
    for group in raised_groups {
        let kept = raised::kept_group(&mut arena, model, &symbolic, group, &laws, &state)
            .map_err(|d| vec![d])?;
        fixed.extend(kept.fixed);
        directions.extend(kept.directions);
        shown_raised.extend(kept.shown);
        newton_groups.push(kept.newton);
    }
    let closure = coupled::closure(&mut arena, model, &laws).map_err(|d| vec![d])?;
    let levels = match &closure {
        Some(closure) if symbolic.k >= 2 => {
            let span = model.constraints[0].span;
            coupled::holonomic_levels(&mut arena, model, closure, symbolic.k, span)
                .map_err(|d| vec![d])?
        }
        _ => Default::default(),
    };
    let (initial, notes) = if with_initial {
        initial::initial_values(
            &mut arena,
            model,
            &symbolic,
            &mut elimination,
            &state,
            &reduction.consistency,
            closure.as_ref(),
            &levels,
            &raised,
            &newton_groups,
        )?
    } else {
        (Vec::new(), Vec::new())
    };
    let mut reduced = ReducedSystem {
        order: u,
        state,
        highest: reduction.highest,
        mass_matrix: reduction.mass_matrix,
        mass_laws: Vec::new(),
        initial,
        fixed,
        consistency: reduction.consistency,
        closure,
    };
    reduced.mass_laws = remaining_masses(&arena, &reduced)
        .into_iter()
        .filter_map(|i| symbolic.laws.get(i as usize).map(|&law| (i, law)))
        .collect();
    let mut holonomic = Vec::new();
    for c in model.constraints.iter().filter(|c| c.is_holonomic()) {
        let f = coupled::position_residual(&mut arena, model, c, &Default::default())
            .map_err(|d| vec![d])?;
        let h = coupled::residual(&mut arena, model, c, &laws)
            .map_err(|d| vec![d])?
            .unwrap_or(f);
        holonomic.push((f, h));
    }
    let mut state_laws: Vec<(u32, ExprId)> = state_laws
        .into_iter()
        .filter_map(|(s, law)| match s {
            Symbol::Mass(i) => Some((i, law)),
            _ => None,
        })
        .collect();
    state_laws.sort_unstable();
    let arena_lets = arena.lowered_lets();
    Ok(Derivation {
        arena,
        coordinates: model.coords.len(),
        independent: symbolic.independent.clone(),
        constraint_order: model.constraint_order,
        k: symbolic.k,
        lagrangian: symbolic.lagrangian,
        constraints: symbolic.constraints.clone(),
        forces,
        equations,
        divided_out: divided.iter().map(|d| d.mass).collect(),
        state_laws,
        forces_along_motion,
        reduced,
        param_defaults: symbolic.param_defaults,
        holonomic,
        raised: shown_raised,
        written: symbolic.written.iter().cloned().chain(directions).collect(),
        notes,
        lets: model
            .lets
            .iter()
            .enumerate()
            .filter_map(|(i, l)| {
                let lowered = arena_lets.get(&(i as u32, 0))?;
                Some((l.name.clone(), lowered.to_vec()))
            })
            .collect(),
    })
}

/// The mass symbols the reduced system still holds.
fn remaining_masses(arena: &Arena, reduced: &ReducedSystem) -> Vec<u32> {
    let mut roots: Vec<ExprId> = Vec::new();
    match &reduced.highest {
        Highest::Explicit(exprs) => roots.extend(exprs),
        Highest::Implicit {
            residual,
            jacobian,
            dependent,
            ..
        } => {
            roots.extend(residual);
            roots.extend(jacobian.iter().flatten());
            roots.extend(dependent.iter().map(|&(_, e)| e));
        }
    }
    for stage in &reduced.consistency {
        roots.extend(&stage.residual);
        roots.extend(stage.jacobian.iter().flatten());
        roots.extend(stage.explicit.iter().flatten());
    }
    for value in &reduced.initial {
        if let InitialValue::Given(e) | InitialValue::Constraint(e) = value {
            roots.push(*e);
        }
    }
    let mut masses: Vec<u32> = roots
        .iter()
        .flat_map(|&r| arena.free_symbols(r))
        .filter_map(|s| match s {
            Symbol::Mass(i) => Some(i),
            _ => None,
        })
        .collect();
    masses.sort_unstable();
    masses.dedup();
    masses
}
