//! The checked model in symbols: the Lagrangian, the mass laws and the
//! constraints lowered into one arena, with the coordinates split into
//! independent and dependent ones.

use crate::check::model::Model;
use crate::diagnostic::{codes, Diagnostic};
use crate::ir::{try_lower, Arena, ExprId, Symbol};
use crate::syntax::ast::Expr;
use std::collections::HashMap;

/// The model's symbolic pieces.
#[derive(Debug, Clone)]
pub struct Symbolic {
    pub lagrangian: ExprId,
    /// Mass law `i` as an expression of `t`, params and coordinates.
    pub laws: Vec<ExprId>,
    /// The constraint order used by equation (4): the model's `k`, or 1 for
    /// a holonomic model (then every coordinate is independent, s = n).
    pub k: u32,
    pub independent: Vec<u32>,
    /// `(d, φ_d)`: `q_d^(k) = φ_d`, with every mass symbol replaced by its
    /// law, because constraints are differentiated with the true time
    /// derivative (only the Lagrangian freezes masses).
    pub constraints: Vec<(u32, ExprId)>,
    /// The implicit constraints as the mechanics solves them, `h = 0` of
    /// order k (a holonomic one's `D^k f`; mass symbols replaced by their
    /// laws, explicit constraints' dependents by their right sides), with
    /// their text: the cross-check verifies that `φ` satisfies them.
    pub written: Vec<(String, ExprId)>,
    pub param_defaults: Vec<f64>,
}

/// Lowers a checked expression; a name that does not lower is an internal
/// error (the checker rules it out), reported rather than panicked on.
pub fn lower_checked(arena: &mut Arena, expr: &Expr, model: &Model) -> Result<ExprId, Diagnostic> {
    try_lower(arena, expr, model).map_err(|error| {
        Diagnostic::error(
            codes::NAME_NOT_ALLOWED,
            format!(
                "internal error: `{}{}` cannot be used in the mechanics",
                error.name,
                "'".repeat(error.primes as usize)
            ),
        )
        .with_primary(error.span, "this name")
    })
}

impl Symbolic {
    pub fn lower(arena: &mut Arena, model: &Model) -> Result<Symbolic, Vec<Diagnostic>> {
        let mut errors = Vec::new();
        let mut lower = |arena: &mut Arena, expr: &Expr| match lower_checked(arena, expr, model) {
            Ok(e) => e,
            Err(d) => {
                errors.push(d);
                arena.zero()
            }
        };
        // sin² + cos² = 1 before any derivative: vector kinetic energies
        // are full of it.
        let lagrangian = lower(arena, &model.lagrangian);
        let lagrangian = arena.pythagoras(lagrangian);
        let laws: Vec<ExprId> = model.masses.iter().map(|m| lower(arena, &m.law)).collect();
        let masses_to_laws: HashMap<Symbol, ExprId> = laws
            .iter()
            .enumerate()
            .map(|(i, &law)| (Symbol::Mass(i as u32), law))
            .collect();
        let mut phis: Vec<Option<ExprId>> = vec![None; model.constraints.len()];
        let mut unsolved = Vec::new();
        // Explicit constraints first: an implicit one may hold their
        // dependents (a holonomic constraint's derivative does), which are
        // replaced by their right sides.
        let mut explicit: HashMap<Symbol, ExprId> = HashMap::new();
        for (i, c) in model.constraints.iter().enumerate() {
            if c.implicit.is_none() {
                let rhs = lower(arena, &c.rhs);
                phis[i] = Some(rhs);
                let rhs = arena.subst(rhs, &masses_to_laws);
                explicit.insert(
                    Symbol::Jet {
                        coord: c.coord as u32,
                        order: c.order,
                    },
                    rhs,
                );
            }
        }
        let mut written = Vec::new();
        for group in &model.groups {
            let mut residuals = Vec::new();
            for &i in &group.constraints {
                let c = &model.constraints[i];
                match super::coupled::residual(arena, model, c, &masses_to_laws) {
                    Ok(Some(h)) => {
                        let h = arena.subst(h, &explicit);
                        let shown = format!("{} = 0", arena.display(h));
                        let with_laws = arena.subst(h, &masses_to_laws);
                        written.push((shown, with_laws));
                        residuals.push(h);
                    }
                    Ok(None) => {}
                    Err(d) => errors.push(d),
                }
            }
            if residuals.len() != group.constraints.len() {
                continue;
            }
            if let [i] = group.constraints[..] {
                let c = &model.constraints[i];
                match solve_implicit(arena, model, c, residuals[0]) {
                    Ok(phi) => phis[i] = Some(phi),
                    Err(d) => unsolved.push(d),
                }
                continue;
            }
            let unknowns: Vec<Symbol> = group
                .constraints
                .iter()
                .map(|&i| Symbol::Jet {
                    coord: model.constraints[i].coord as u32,
                    order: model.constraints[i].order,
                })
                .collect();
            let span = model.constraints[group.constraints[0]].span;
            match super::coupled::solve(arena, &residuals, &unknowns, span) {
                Ok(solution) => {
                    for (&i, phi) in group.constraints.iter().zip(solution) {
                        phis[i] = Some(phi);
                    }
                }
                Err(d) => unsolved.push(d),
            }
        }
        let constraints: Vec<(u32, ExprId)> = model
            .constraints
            .iter()
            .zip(&phis)
            .filter_map(|(c, phi)| Some((c.coord as u32, (*phi)?)))
            .map(|(d, phi)| (d, arena.subst(phi, &masses_to_laws)))
            .collect();
        errors.extend(unsolved);
        if !errors.is_empty() {
            return Err(errors);
        }
        if let Some(d) = lagrangian_order(arena, model, lagrangian) {
            return Err(vec![d]);
        }
        Ok(Symbolic {
            lagrangian,
            laws,
            k: model.constraint_order.unwrap_or(1),
            independent: model.independent().iter().map(|&i| i as u32).collect(),
            constraints,
            written,
            param_defaults: model.params.iter().map(|p| p.default).collect(),
        })
    }

    pub fn dependent(&self) -> Vec<u32> {
        self.constraints.iter().map(|&(d, _)| d).collect()
    }

    /// `M_i → law_i` for every mass law of the state (SPEC §2.3: `rho * x`).
    pub fn state_laws(&self, arena: &Arena) -> HashMap<Symbol, ExprId> {
        state_laws(arena, &self.laws)
    }

    /// `u = max(2, k)`: the order of the reduced system.
    pub fn u(&self) -> u32 {
        self.k.max(2)
    }

    /// `q_j^(order)` for every independent `j`.
    pub fn independent_jets(&self, order: u32) -> Vec<Symbol> {
        self.independent
            .iter()
            .map(|&coord| Symbol::Jet { coord, order })
            .collect()
    }
}

/// Whether a mass law depends on the state (a coordinate), not only on `t`.
pub fn is_state_law(arena: &Arena, law: ExprId) -> bool {
    arena
        .free_symbols(law)
        .iter()
        .any(|s| matches!(s, Symbol::Jet { .. }))
}

/// `M_i → law_i` for every law of `laws` that depends on the state.
///
/// Inside the Lagrangian a mass is frozen (SPEC §1.1), so equations (4)
/// hold it as the symbol `M_i`; the reduced system (7) is a function of
/// `(t, x)` and its `∂X/∂x` must see the mass move with the state, so from
/// (7) on a law of the state is its expression (a law of `t` alone stays a
/// symbol, its time dependence known to `kernel/time.rs`).
pub fn state_laws(arena: &Arena, laws: &[ExprId]) -> HashMap<Symbol, ExprId> {
    laws.iter()
        .enumerate()
        .filter(|&(_, &law)| is_state_law(arena, law))
        .map(|(i, &law)| (Symbol::Mass(i as u32), law))
        .collect()
}

/// `lhs = rhs` solved for its candidate `q_d^(k)`: the constraint must be
/// linear in it, `h = c·q_d^(k) + r`, and then `q_d^(k) = −r / c` (the
/// pivot `c` may vanish somewhere; the run watches it).
fn solve_implicit(
    arena: &mut Arena,
    model: &Model,
    c: &crate::check::model::Constraint,
    h: ExprId,
) -> Result<ExprId, Diagnostic> {
    let dep = Symbol::Jet {
        coord: c.coord as u32,
        order: c.order,
    };
    let pivot = arena.diff(h, dep);
    // A selection switching on the candidate (`sign(y')`) has the
    // derivative 0 there, yet the candidate does not enter linearly.
    if arena.depends_on(pivot, dep) || arena.switches_on(h, dep) {
        let name = arena.symbol_name(dep);
        // Its derivative is linear in the next derivatives and keeps every
        // branch: `x'^2 + y'^2 = c^2` becomes `2*x'*x'' + 2*y'*y'' = 0`. An
        // explicit root holds one branch and stops where it ends.
        let next = Symbol::Jet {
            coord: c.coord as u32,
            order: c.order + 1,
        };
        let differentiated = arena.total_derivative(h);
        let help = if arena.switches_on(h, dep) {
            format!("solve the constraint for `{name}` and write it explicitly: `constraint {name} = …;`")
        } else {
            // The checker raises every constraint whose text is not
            // affine in its candidates (`check/linearity.rs`), so this is
            // one it read as affine: say what lagc would do with it.
            format!(
                "its derivative `{} = 0` is linear in `{}`: written so that the candidate's \
                 non-linear use shows in the constraint itself (not through a let's derivative), \
                 lagc solves it through that derivative and keeps it as written",
                arena.display(differentiated),
                arena.symbol_name(next),
            )
        };
        return Err(Diagnostic::error(
            codes::BAD_CANDIDATE,
            format!("the constraint is not linear in `{name}`"),
        )
        .with_primary(c.span, format!("`{name}` enters non-linearly"))
        .with_note("lagc solves an implicit constraint for its candidate symbolically, which needs it to enter linearly")
        .with_help(help));
    }
    if arena.is_zero(pivot) {
        // A raised constraint is written in the derivative below.
        let written = Symbol::Jet {
            coord: c.coord as u32,
            order: c.order - u32::from(c.is_raised()),
        };
        let name = arena.symbol_name(written);
        return Err(Diagnostic::error(
            codes::BAD_CANDIDATE,
            format!("the constraint does not depend on `{name}`"),
        )
        .with_primary(c.span, "its derivative with respect to the candidate is 0"));
    }
    let _ = model;
    let zero = arena.zero();
    let at_zero: HashMap<Symbol, ExprId> = [(dep, zero)].into_iter().collect();
    let free = arena.subst(h, &at_zero);
    let minus_free = arena.neg(free);
    Ok(arena.div(minus_free, pivot))
}

/// Equation (4) is derived for Lagrangians of the first order only: a
/// derivative of order ≥ 2 would need the higher-order Euler operator. The
/// checker already rejects it; this keeps the mechanics honest on its own.
fn lagrangian_order(arena: &Arena, model: &Model, lagrangian: ExprId) -> Option<Diagnostic> {
    let (coord, order) = (0..model.coords.len() as u32)
        .filter_map(|j| arena.max_jet_order(lagrangian, j).map(|r| (j, r)))
        .find(|&(_, r)| r >= 2)?;
    let name = arena.symbol_name(Symbol::Jet { coord, order });
    Some(
        Diagnostic::error(
            codes::DERIVATIVE_ORDER_NOT_ALLOWED,
            format!("the Lagrangian holds `{name}`, a derivative of order {order}"),
        )
        .with_primary(model.lagrangian.span, "this Lagrangian")
        .with_note("equations (4) are derived for Lagrangians of coordinates and velocities")
        .with_help("write the Lagrangian with first derivatives only"),
    )
}
