//! The model's data in the kernel: params, mass laws, the time span, the
//! initial state, the exact solution and the coefficient system.

use super::time::TimeDependence;
use crate::check::model::Model;
use crate::diagnostic::{codes, Diagnostic};
use crate::field::FieldSystem;
use crate::ir::{lower, Arena, ExprId, Symbol};
use crate::mechanics::{InitialValue, ReducedSystem};

/// A param: its name and its value as an expression of the params before
/// it.
#[derive(Debug, Clone)]
pub struct KernelParam {
    pub name: String,
    pub value: ExprId,
    /// It may change between steps (`check::model::Param::tunable`).
    pub tunable: bool,
}

pub fn params(arena: &mut Arena, model: &Model) -> Vec<KernelParam> {
    model
        .params
        .iter()
        .map(|p| KernelParam {
            name: p.name.clone(),
            value: lower(arena, &p.value, model),
            tunable: p.tunable,
        })
        .collect()
}

/// Every mass law, by name.
pub fn masses(arena: &mut Arena, model: &Model) -> Vec<(String, ExprId)> {
    model
        .masses
        .iter()
        .map(|m| (m.name.clone(), lower(arena, &m.law, model)))
        .collect()
}

pub fn time_span(arena: &mut Arena, model: &Model) -> (ExprId, ExprId) {
    (
        lower(arena, &model.time.start, model),
        lower(arena, &model.time.end, model),
    )
}

/// How a state component's initial value is found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InitialKind {
    Given,
    Constraint,
    Solved,
}

/// Where an initial value comes from, in the order the generated code
/// computes them.
#[derive(Debug, Clone)]
pub enum InitialSource {
    /// A value the model states (overridable): an expression of params.
    Given { index: usize, value: ExprId },
    /// The dependent positions of the holonomic constraints, moved onto
    /// them by Newton from the given values ([`Kernel::closure`]).
    Closure,
    /// Fixed by a constraint from the given values (and `t0`, masses).
    Constraint { index: usize, value: ExprId },
    /// An independent derivative of order 2..k−1, solved from (4).
    Solved { symbol: Symbol, value: ExprId },
}

#[derive(Debug, Clone)]
pub struct KernelInitial {
    pub kinds: Vec<InitialKind>,
    pub sources: Vec<InitialSource>,
    /// Values the model states for components it does not give (fixed by
    /// the constraints or the equations): checked at run time, after
    /// overrides, against the values computed.
    pub stated: Vec<(usize, ExprId)>,
}

pub fn initial(
    arena: &mut Arena,
    model: &Model,
    reduced: &ReducedSystem,
) -> Result<KernelInitial, Diagnostic> {
    let mut kinds = Vec::with_capacity(reduced.state.len());
    let mut sources = Vec::new();
    let mut constrained = Vec::new();
    for (k, value) in reduced.initial.iter().enumerate() {
        match value {
            InitialValue::Given(e) => {
                kinds.push(InitialKind::Given);
                sources.push(InitialSource::Given {
                    index: k,
                    value: *e,
                });
            }
            InitialValue::Constraint(e) => {
                kinds.push(InitialKind::Constraint);
                constrained.push(InitialSource::Constraint {
                    index: k,
                    value: *e,
                });
            }
            InitialValue::Solved => kinds.push(InitialKind::Solved),
        }
    }
    if reduced.closure.is_some() {
        sources.push(InitialSource::Closure);
    }
    sources.extend(constrained);
    for stage in &reduced.consistency {
        let Some(explicit) = &stage.explicit else {
            return Err(Diagnostic::error(
                codes::INCONSISTENT_INITIAL,
                "the consistent initial values of the higher derivatives have no symbolic \
                 solution; the code generator cannot solve them numerically yet",
            ));
        };
        for (&symbol, &value) in stage.unknowns.iter().zip(explicit) {
            sources.push(InitialSource::Solved { symbol, value });
        }
    }
    let mut stated = Vec::new();
    for value in &model.initial {
        let symbol = Symbol::Jet {
            coord: value.coord as u32,
            order: value.order,
        };
        if let Some(k) = reduced.state.iter().position(|&s| s == symbol) {
            if kinds[k] != InitialKind::Given {
                stated.push((k, lower(arena, &value.value, model)));
            }
        }
    }
    Ok(KernelInitial {
        kinds,
        sources,
        stated,
    })
}

/// The model's exact solution lines, for the state components they give.
pub fn exact(arena: &mut Arena, model: &Model, reduced: &ReducedSystem) -> Vec<(usize, ExprId)> {
    model
        .exact
        .iter()
        .filter_map(|exact| {
            let symbol = Symbol::Jet {
                coord: exact.coord as u32,
                order: exact.order,
            };
            let k = reduced.state.iter().position(|&s| s == symbol)?;
            Some((k, lower(arena, &exact.value, model)))
        })
        .collect()
}

/// The coefficient system `f' = F(t, f)` of an affine reduced system.
#[derive(Debug, Clone)]
pub struct Coefficients {
    /// The coefficients `f_1..f_N` (`Symbol::Aux`).
    pub symbols: Vec<Symbol>,
    pub rhs: Vec<ExprId>,
    /// Non-zero `(row, column, ∂F_row/∂f_column)`.
    pub jacobian: Vec<(usize, usize, ExprId)>,
    /// Non-zero `(row, ∂F_row/∂t)` (true time partial).
    pub time_partial: Vec<(usize, ExprId)>,
    /// `F` is affine in `f` (no `X_A` depends on `x_1`).
    pub linear: bool,
}

pub fn coefficients(
    arena: &mut Arena,
    field: &FieldSystem,
    time: &TimeDependence,
) -> Option<Coefficients> {
    let system = field.coefficient_system.as_ref()?;
    let mut jacobian = Vec::new();
    for (a, row) in system.jacobian.iter().enumerate() {
        for (b, &e) in row.iter().enumerate() {
            if !arena.is_zero(e) {
                jacobian.push((a, b, e));
            }
        }
    }
    let mut time_partial = Vec::new();
    for (a, &f) in system.rhs.iter().enumerate() {
        let d = time.partial(arena, f);
        if !arena.is_zero(d) {
            time_partial.push((a, d));
        }
    }
    Some(Coefficients {
        symbols: field.coefficients.clone(),
        rhs: system.rhs.clone(),
        jacobian,
        time_partial,
        linear: system.linear,
    })
}

/// The holonomic constraints at position level in the kernel: `f_ν` and
/// its non-zero partials in the dependent coordinates, by state index.
#[derive(Debug, Clone)]
pub struct KernelClosure {
    /// The state indices of the dependent coordinates (the unknowns).
    pub unknowns: Vec<usize>,
    pub residual: Vec<ExprId>,
    /// `(row, column, ∂f_row/∂z_column)`, non-zero entries.
    pub jacobian: Vec<(usize, usize, ExprId)>,
    /// The constraints as written, for messages.
    pub text: String,
    /// `(row, coordinate, ∂f_row/∂q_coordinate)`, non-zero entries: the
    /// normals of the projection (`Closure::normals`).
    pub normals: Vec<(usize, usize, ExprId)>,
    /// `D^r f` for r = 1..u−1 (`Closure::levels`).
    pub levels: Vec<Vec<ExprId>>,
}

pub fn closure(arena: &mut Arena, reduced: &ReducedSystem) -> Option<KernelClosure> {
    let closure = reduced.closure.as_ref()?;
    let unknowns = closure
        .unknowns
        .iter()
        .filter_map(|z| reduced.state.iter().position(|s| s == z))
        .collect();
    let residual = closure
        .residual
        .iter()
        .map(|&e| crate::mechanics::tidy::simplify(arena, e))
        .collect();
    let mut jacobian = Vec::new();
    for (r, row) in closure.jacobian.iter().enumerate() {
        for (c, &e) in row.iter().enumerate() {
            if !arena.is_zero(e) {
                jacobian.push((r, c, crate::mechanics::tidy::simplify(arena, e)));
            }
        }
    }
    let mut normals = Vec::new();
    for (r, row) in closure.normals.iter().enumerate() {
        for (c, &e) in row.iter().enumerate() {
            if !arena.is_zero(e) {
                normals.push((r, c, crate::mechanics::tidy::simplify(arena, e)));
            }
        }
    }
    let levels = closure
        .levels
        .iter()
        .map(|level| {
            level
                .iter()
                .map(|&e| crate::mechanics::tidy::simplify(arena, e))
                .collect()
        })
        .collect();
    Some(KernelClosure {
        unknowns,
        residual,
        jacobian,
        text: closure.text.clone(),
        normals,
        levels,
    })
}
