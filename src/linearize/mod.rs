//! Stage: the linearization of the reduced system (7) at a point
//! (`lagc linearize`). Pure: the request's text in, a [`Linearization`]
//! (printable as text, JSON and LaTeX) or a [`LinearizeError`] out.
//!
//! `A = ∂f/∂x` is the exact symbolic Jacobian of the reduced system,
//! evaluated — never differenced. The state of `A` is the state the
//! generated crate integrates with two kinds of components left out:
//!
//! - the components the constraints fix (`ReducedSystem::fixed`, the
//!   dependent velocities of first-order constraints): they are functions
//!   `φ(t, x)` of the others, substituted before differentiating, so a
//!   perturbation of the state moves them along the constraint
//!   (`δx_d = ∂φ/∂x δx`) and `A` has no directions off the constraints;
//!   likewise the dependent positions of holonomic constraints `f = 0`
//!   (`∂z/∂q = −f_z⁻¹ f_q`, evaluated);
//! - the ignorable coordinates: positions that no remaining right side
//!   contains (found symbolically, the derivative's vanishing confirmed at
//!   random points where the simplifier leaves `sin²φ + cos²φ` standing),
//!   so steady motions linearize to a constant `A` with residual 0.
//!
//! | file | what |
//! |---|---|
//! | `point.rs` | the request: `--at`, `--param`, `--t` parsed, the point completed |
//! | `system.rs` | the eliminated system, its symbolic Jacobians, their evaluation |
//! | `closure.rs` | holonomic constraints: dependent positions by Newton, their slopes |
//! | `ignorable.rs` | the ignorable coordinates |
//! | `symbolic.rs` | `--symbolic`: A's entries as expressions |
//! | `eigen.rs` | eigenvalues of a real matrix, frequency and damping |
//! | `parts.rs` | the symbolic half as expressions, for a Python module's `linearize` |
//! | `text.rs` | text, JSON and LaTeX |

mod closure;
mod eigen;
mod ignorable;
mod parts;
mod point;
mod symbolic;
mod system;
mod text;

pub use eigen::{eigenvalues, Eigenvalue};
pub use parts::{parts, LinearParts};

use crate::check::model::Model;
use crate::mechanics::Derivation;

/// What the command line asks for, as written.
#[derive(Debug, Clone, Default)]
pub struct Request {
    /// `NAME=VALUE` items (each may hold several, comma-separated).
    pub at: Vec<String>,
    /// `NAME=VALUE` param overrides (comma-separated too).
    pub params: Vec<String>,
    /// `NAME=VALUE` input values at the point (default: the inputs'
    /// defaults), comma-separated too.
    pub inputs: Vec<String>,
    /// The time, for rheonomic models (default: the start of the model's span).
    pub t: Option<String>,
    /// `A` as expressions of the params and the state components not given.
    pub symbolic: bool,
}

/// The linearization at one point.
#[derive(Debug, Clone)]
pub struct Linearization {
    pub t: f64,
    /// The state of `A`: the integrated state without the components the
    /// constraints fix and without the ignorable coordinates.
    pub state: Vec<String>,
    /// Its values at the point.
    pub point: Vec<f64>,
    /// The ignorable coordinates, with their values at the point.
    pub ignorable: Vec<(String, f64)>,
    /// The components the constraints fix, with their values at the point.
    pub fixed: Vec<(String, f64)>,
    /// The candidates' choice (the dependent components) when the model has
    /// several: the reduced system the point was linearized in.
    pub mode: Option<String>,
    /// `A = ∂f/∂x`, row-major.
    pub a: Vec<Vec<f64>>,
    /// Param names and `∂f/∂p` (rows of the state, a column per param; the
    /// total derivative: params declared after `p` follow it, as
    /// `--param` recomputes them).
    pub params: Vec<String>,
    pub b_params: Vec<Vec<f64>>,
    /// The inputs (SPEC §2.3) and ∂f/∂u, rows as `state`, the inputs held
    /// at their values at the point.
    pub inputs: Vec<String>,
    pub b_inputs: Vec<Vec<f64>>,
    pub eigenvalues: Vec<Eigenvalue>,
    /// `f` at the point, per component of `state`, and whether it is zero
    /// to rounding (`|f_i| ≤ 1e-9` of its rounding scale).
    pub residual: Vec<f64>,
    pub equilibrium: bool,
    /// With `--symbolic`: the text and LaTeX of the non-zero entries
    /// `(row, column, text, latex)`, or of the implicit system's parts.
    pub symbolic: Option<text::Symbolic>,
}

/// A request that cannot be answered: an unknown name, a malformed value,
/// a point where `A` is not defined.
#[derive(Debug, Clone, PartialEq)]
pub struct LinearizeError {
    pub kind: ErrorKind,
    pub message: String,
    pub help: Option<String>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ErrorKind {
    /// The request is malformed (exit 2).
    Usage,
    /// The model cannot be linearized there (exit 3, as a numerical failure).
    Undefined,
}

impl LinearizeError {
    fn usage(message: impl Into<String>, help: impl Into<String>) -> LinearizeError {
        LinearizeError {
            kind: ErrorKind::Usage,
            message: message.into(),
            help: Some(help.into()),
        }
    }

    fn undefined(message: impl Into<String>, help: impl Into<String>) -> LinearizeError {
        LinearizeError {
            kind: ErrorKind::Undefined,
            message: message.into(),
            help: Some(help.into()),
        }
    }
}

impl std::fmt::Display for LinearizeError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "error: {}", self.message)?;
        if let Some(help) = &self.help {
            writeln!(f, "  = help: {help}")?;
        }
        Ok(())
    }
}

/// Linearizes the derived model at the requested point. A model whose
/// implicit constraints have several candidates has a reduced system for
/// each choice; the point is linearized in the first whose free state
/// holds every component `--at` gives and whose pivots do not vanish there
/// (mode 1 if none does).
pub fn linearize(
    model: &Model,
    derivation: &Derivation,
    request: &Request,
) -> Result<Linearization, LinearizeError> {
    let first = || {
        system::linearize_in(model, derivation, request).map(|l| with_mode(l, model, derivation, 0))
    };
    if model.mode_count() < 2 {
        return first();
    }
    let given: Vec<String> = point::items(&request.at, "--at")?
        .into_iter()
        .map(|(name, _)| name)
        .collect();
    for mode in 0..model.mode_count() {
        let result = if mode == 0 {
            try_mode(model, derivation, &given, request).map(|r| (r, None))
        } else {
            let other = model.in_mode(mode);
            let Ok(d) = crate::mechanics::derive_mode_checked(&other) else {
                continue;
            };
            try_mode(&other, &d, &given, request).map(|r| (r, Some(d)))
        };
        if let Some((Ok(l), d)) = result {
            return Ok(with_mode(l, model, d.as_ref().unwrap_or(derivation), mode));
        }
    }
    first()
}

/// The linearization in one mode, `None` when the mode fixes a component
/// the request gives.
fn try_mode(
    model: &Model,
    derivation: &Derivation,
    given: &[String],
    request: &Request,
) -> Option<Result<Linearization, LinearizeError>> {
    let fixes_given = derivation.reduced.fixed.iter().any(|&(k, _)| {
        let name = derivation.arena.symbol_name(derivation.reduced.state[k]);
        given.contains(&name)
    });
    if fixes_given {
        return None;
    }
    Some(system::linearize_in(model, derivation, request))
}

/// Names the dependents of the mode used, when there is a choice.
fn with_mode(mut l: Linearization, model: &Model, d: &Derivation, mode: usize) -> Linearization {
    if model.mode_count() > 1 {
        let names: Vec<String> = d
            .dependent()
            .iter()
            .map(|&c| {
                d.arena.symbol_name(crate::ir::Symbol::Jet {
                    coord: c,
                    order: d.k,
                })
            })
            .collect();
        l.mode = Some(format!(
            "mode {} (dependent {})",
            mode + 1,
            names.join(", ")
        ));
    }
    l
}
