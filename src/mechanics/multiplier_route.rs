//! The independent cross-check of equations (4) (SPEC §1.2): the multiplier
//! route `E_i + E_d ∂φ_d/∂q_i^(k)` with `E_j = D(∂L/∂q_j') − ∂L/∂q_j` (masses
//! frozen) and the same elimination must equal the left side of (4).

use super::sample::{eval_scaled, Rng, SamplePoint};
use super::star::{jet, project, Elimination};
use super::Derivation;
use crate::diagnostic::{codes, Diagnostic};
use crate::ir::ExprId;
use crate::span::Span;
use std::fmt;

/// Points at which both routes must agree.
pub const CROSS_CHECK_POINTS: usize = 100;
/// Tries before giving up on finding enough points where both are finite.
const MAX_TRIES: usize = 20 * CROSS_CHECK_POINTS;
/// Agreement relative to the rounding scale of the two values.
pub const CROSS_CHECK_TOLERANCE: f64 = 1e-12;

/// A passed cross-check.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CrossCheck {
    /// Points at which both routes were finite and compared.
    pub points: usize,
    /// The largest `|a − b| / (scale_a + scale_b)` seen.
    pub worst: f64,
}

/// Why the cross-check failed.
#[derive(Debug, Clone, PartialEq)]
pub enum CrossCheckFailure {
    /// The two routes differ at a point.
    Differ {
        coord: String,
        t: f64,
        via_equation_four: f64,
        via_multipliers: f64,
    },
    /// Too few random points gave finite values on both routes.
    TooFewPoints { found: usize },
    /// The solved dependents `φ` do not satisfy an implicit (or
    /// holonomic, differentiated) constraint as written.
    ConstraintViolated {
        constraint: String,
        t: f64,
        residual: f64,
    },
}

impl fmt::Display for CrossCheckFailure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CrossCheckFailure::Differ {
                coord,
                t,
                via_equation_four,
                via_multipliers,
            } => write!(
                f,
                "equation (4) for `{coord}` disagrees with the multiplier route at t = {t}: \
                 {via_equation_four} vs {via_multipliers}"
            ),
            CrossCheckFailure::ConstraintViolated {
                constraint,
                t,
                residual,
            } => write!(
                f,
                "the solved dependent derivatives leave the constraint `{constraint}` with \
                 the residual {residual} at t = {t}"
            ),
            CrossCheckFailure::TooFewPoints { found } => write!(
                f,
                "only {found} of {MAX_TRIES} random points were finite on both routes \
                 (need {CROSS_CHECK_POINTS})"
            ),
        }
    }
}

impl CrossCheckFailure {
    /// The failure as an error located at the Lagrangian (`lagrangian`, its
    /// span): the equations derived from it cannot be trusted.
    pub fn diagnostic(&self, lagrangian: Span) -> Diagnostic {
        Diagnostic::error(
            codes::CROSS_CHECK_FAILED,
            format!("the derivation fails its cross-check: {self}"),
        )
        .with_primary(lagrangian, "equations (4) derived from this Lagrangian")
        .with_note(
            "equations (4) are checked against an independent route (the multiplier form \
             `E_i + E_d ∂φ_d/∂q_i^(k)`), and the solved constraints against the constraints \
             as written, at random points; when they cannot be compared or disagree, the \
             equations cannot be trusted and nothing is integrated",
        )
        .with_help(
            "look for a term that overflows or is not finite at ordinary values (such as \
             an exponent like `x'^1e300`); if the model is sound, this is a bug in lagc",
        )
    }
}

/// The multiplier route's left sides, one per equation (4), eliminated.
pub fn multiplier_route(derivation: &mut Derivation) -> Vec<ExprId> {
    let arena = &mut derivation.arena;
    let l = derivation.lagrangian;
    let euler_lagrange: Vec<ExprId> = (0..derivation.coordinates as u32)
        .map(|j| {
            let momentum = arena.diff(l, jet(j, 1));
            let rate = arena.total_derivative(momentum);
            let force = arena.diff(l, jet(j, 0));
            arena.sub(rate, force)
        })
        .collect();
    let mut elimination = Elimination::new(derivation.k, &derivation.constraints);
    derivation
        .equations
        .iter()
        .map(|eq| {
            let e = project(
                arena,
                &euler_lagrange,
                eq.coord,
                derivation.k,
                &derivation.constraints,
            );
            elimination.eliminate(arena, e)
        })
        .collect()
}

/// Compares the left sides of (4) with the multiplier route at
/// [`CROSS_CHECK_POINTS`] random points.
pub fn cross_check(derivation: &mut Derivation) -> Result<CrossCheck, CrossCheckFailure> {
    let multipliers = multiplier_route(derivation);
    // The constraints as written with the solved dependents: zero (an
    // implicit or coupled solve, and a holonomic constraint's derivative,
    // checked independently of the route both sides of (4) share).
    let solved: std::collections::HashMap<crate::ir::Symbol, ExprId> = derivation
        .constraints
        .iter()
        .map(|&(d, phi)| (jet(d, derivation.k), phi))
        .collect();
    let written: Vec<ExprId> = derivation
        .written
        .iter()
        .map(|&(_, h)| derivation.arena.subst(h, &solved))
        .collect();
    let arena = &derivation.arena;
    let mut roots: Vec<ExprId> = derivation.equations.iter().map(|e| e.lhs).collect();
    roots.extend(&multipliers);
    roots.extend(&written);
    let rows = derivation.equations.len();
    let masses = arena.names().masses.len();
    let mut rng = Rng::new(0x6d75_6c74);
    let mut points = 0;
    let mut worst: f64 = 0.0;
    for _ in 0..MAX_TRIES {
        let point = SamplePoint::random(&mut rng, &derivation.param_defaults, masses);
        let values = eval_scaled(arena, &roots, &|s| point.value(s));
        if !values.iter().all(|v| v.is_finite()) {
            continue;
        }
        for r in 0..rows {
            let (a, b) = (values[r], values[rows + r]);
            if !a.agrees(b, CROSS_CHECK_TOLERANCE) {
                return Err(CrossCheckFailure::Differ {
                    coord: arena.symbol_name(jet(derivation.equations[r].coord, 0)),
                    t: point.t,
                    via_equation_four: a.value,
                    via_multipliers: b.value,
                });
            }
            let scale = a.scale + b.scale;
            if scale > 0.0 {
                worst = worst.max((a.value - b.value).abs() / scale);
            }
        }
        for (w, (text, _)) in derivation.written.iter().enumerate() {
            let h = values[2 * rows + w];
            let zero = super::sample::Scaled {
                value: 0.0,
                scale: 0.0,
            };
            if !h.agrees(zero, CROSS_CHECK_TOLERANCE) {
                return Err(CrossCheckFailure::ConstraintViolated {
                    constraint: text.clone(),
                    t: point.t,
                    residual: h.value,
                });
            }
        }
        points += 1;
        if points == CROSS_CHECK_POINTS {
            return Ok(CrossCheck { points, worst });
        }
    }
    Err(CrossCheckFailure::TooFewPoints { found: points })
}
