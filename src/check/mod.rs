//! Stage 2: AST → checked model, collecting every problem.
//!
//! [`check`] never stops at the first mistake: each concern (declarations,
//! params, constraints, initial values, points, the remaining statements)
//! adds its diagnostics, and they come back sorted by position. The checked
//! [`model::Model`] is returned only when there are none.

pub mod atan2_cut;
mod components;
mod constraints;
mod declarations;
mod eval;
mod expressions;
mod impacts;
mod impacts_at_start;
mod initial;
mod linearity;
pub mod model;
mod points;
mod statements;
mod types;

pub use eval::{axis_index, sign};

use crate::diagnostic::{self, Diagnostic};
use crate::span::Span;
use crate::syntax::ast;
use declarations::Declared;
use std::collections::{HashMap, HashSet};

/// The highest derivative order accepted anywhere (`q` followed by 16
/// primes). Far above any mechanics lagc can derive; it keeps order
/// arithmetic downstream far from overflow.
pub const MAX_DERIVATIVE_ORDER: u32 = 16;

/// Checks a parsed model: names, statement rules, constraints, initial
/// values, time span. Returns every problem found, sorted by position.
pub fn check(ast: &ast::Model) -> Result<model::Model, Vec<Diagnostic>> {
    let mut checker = Checker::new(ast);
    checker.declare();
    let params = checker.params();
    let inputs = checker.inputs();
    let lets = checker.lets();
    let masses = checker.masses();
    let (constraint_order, constraints, groups) = checker.constraints();
    let lagrangian = checker.lagrangian();
    let forces = checker.forces();
    let points = checker.points();
    let initial = checker.initial(constraint_order, &constraints);
    let exact = checker.exact();
    let time = checker.time();
    let integrator = checker.integrator();
    let outputs = checker.outputs();
    let stop = checker.stop();
    let impacts = checker.impacts(constraint_order, &constraints);
    if let Some(time) = &time {
        checker.impacts_at_start(&impacts, &initial, time);
        checker.points_at_start(&points, &initial, time);
    }
    let mut params = params;
    let tunable = checker.tunable_params(params.len());
    for (param, tunable) in params.iter_mut().zip(tunable) {
        param.tunable = tunable;
    }

    let mut diagnostics = checker.diagnostics;
    let (Some(lagrangian), Some(time), true) = (lagrangian, time, diagnostics.is_empty()) else {
        if diagnostics.is_empty() {
            // Every None above comes with a diagnostic; keep the promise
            // "Err is never empty" even if that ever changes.
            diagnostics.push(Diagnostic::error(
                crate::diagnostic::codes::MISSING_LAGRANGIAN,
                "internal error: the model is incomplete",
            ));
        }
        diagnostic::sort(&mut diagnostics);
        return Err(diagnostics);
    };
    Ok(model::Model {
        params,
        inputs,
        coords: checker.coords,
        masses,
        lagrangian,
        constraint_order,
        constraints,
        groups,
        points,
        forces,
        initial,
        time,
        exact,
        integrator,
        lets,
        outputs,
        stop,
        impacts,
        names: checker
            .names
            .iter()
            .map(|(k, v)| (k.clone(), v.name))
            .collect(),
    })
}

/// The state shared by the checks: the declared names and the diagnostics
/// found so far. Each concern lives in its own file as an `impl Checker`.
struct Checker<'a> {
    ast: &'a ast::Model,
    diagnostics: Vec<Diagnostic>,
    names: HashMap<String, Declared>,
    coords: Vec<model::Coord>,
    /// Every param's default, once computed (`None` if it could not be).
    param_defaults: Vec<Option<f64>>,
    /// Params used where they may not change between steps
    /// (`Param::tunable`), with repeats.
    fixed_params: Vec<usize>,
    /// For each param, the params its value uses.
    param_uses: Vec<Vec<usize>>,
    /// Some constraint was rejected: its coordinate now looks independent,
    /// so "missing initial value" errors would be noise.
    constraints_incomplete: bool,
    /// The lets checked so far, by index.
    lets: Vec<types::LetInfo>,
    /// Unknown names already reported (each is reported once).
    unknown_reported: HashSet<String>,
    /// A zero-width span just after the last statement, where "missing …"
    /// diagnostics point.
    end_of_file: Span,
    /// The start, while a condition is evaluated there: coordinates and
    /// their derivatives evaluate to their stated initial values
    /// (`impacts_at_start`); `None` otherwise, where they are no constants.
    start: Option<impacts_at_start::Start>,
}

impl<'a> Checker<'a> {
    fn new(ast: &'a ast::Model) -> Self {
        let end = ast.items.last().map_or(0, |item| item.span.end);
        Checker {
            ast,
            diagnostics: Vec::new(),
            names: HashMap::new(),
            coords: Vec::new(),
            param_defaults: Vec::new(),
            fixed_params: Vec::new(),
            param_uses: Vec::new(),
            lets: Vec::new(),
            constraints_incomplete: false,
            unknown_reported: HashSet::new(),
            end_of_file: Span::new(end, end),
            start: None,
        }
    }

    fn report(&mut self, diagnostic: Diagnostic) {
        self.diagnostics.push(diagnostic);
    }

    fn items(&self) -> impl Iterator<Item = (&'a ast::ItemKind, Span)> {
        self.ast.items.iter().map(|item| (&item.kind, item.span))
    }
}
