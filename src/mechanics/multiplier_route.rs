//! The independent cross-check of equations (4) (SPEC §1.2): the multiplier
//! route `E_i + E_d ∂φ_d/∂q_i^(k)` with `E_j = D(∂L/∂q_j') − ∂L/∂q_j` (masses
//! frozen) and the same elimination must equal the left side of (4).
//!
//! With mass laws of the state (SPEC §2.3) the check goes on along the
//! motion: the multiplier route's whole equation, `E − R − Q` projected and
//! eliminated, each law of the state put in after the differentiation of
//! `L` (frozen) and each point's `Ṁ` the total derivative of its mass
//! through those laws (not the derivation's `M·ρ`), must vanish where the
//! reduced system (7) puts its highest derivatives (explicit, or one
//! linear solve). That covers the rates along the motion, the masses
//! divided out and the laws put in for (7).

use super::reduced::Highest;
use super::sample::{Rng, SamplePoint, Tape};
use super::star::{jet, project, Elimination};
use super::Derivation;
use crate::diagnostic::{codes, Diagnostic};
use crate::ir::{Arena, ExprId, Symbol};
use crate::span::Span;
use nalgebra::{DMatrix, DVector};
use std::collections::HashMap;
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
    /// With mass laws of the state: the multiplier route's equation along
    /// the motion does not vanish at the reduced system's highest
    /// derivatives.
    AlongMotion {
        coord: String,
        t: f64,
        residual: f64,
        scale: f64,
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
            CrossCheckFailure::AlongMotion {
                coord,
                t,
                residual,
                scale,
            } => write!(
                f,
                "the reduced system (7) misses the equation of `{coord}` along the motion \
                 (mass laws of the state) at t = {t}: residual {residual} on a scale of {scale}"
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

/// `E_j = D(∂L/∂q_j') − ∂L/∂q_j` for every coordinate, masses frozen.
fn euler_lagrange(derivation: &mut Derivation) -> Vec<ExprId> {
    let arena = &mut derivation.arena;
    let l = derivation.lagrangian;
    let n = derivation.coordinates as u32;
    // `∂L/∂q_j'` and `∂L/∂q_j` for every j in one pass (`Arena::jacobian`).
    let wrt: Vec<Symbol> = (0..n)
        .map(|j| jet(j, 1))
        .chain((0..n).map(|j| jet(j, 0)))
        .collect();
    let gradient = arena.jacobian(&[l], &wrt).remove(0);
    let (momenta, forces) = gradient.split_at(n as usize);
    momenta
        .iter()
        .zip(forces)
        .map(|(&momentum, &force)| {
            let rate = arena.total_derivative(momentum);
            arena.sub(rate, force)
        })
        .collect()
}

/// The multiplier route's left sides, one per equation (4), eliminated.
pub fn multiplier_route(derivation: &mut Derivation) -> Vec<ExprId> {
    let euler_lagrange = euler_lagrange(derivation);
    let arena = &mut derivation.arena;
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

/// The multiplier route's equations along the motion (with mass laws of
/// the state), one `(coord, row)` per equation (4), and how the reduced
/// system (7) gives their highest derivatives at a point.
struct AlongMotion {
    rows: Vec<(u32, ExprId)>,
    highest: HighestAt,
}

/// `q_i''` from (7): explicit expressions, or one linear solve of
/// `G(z) = G_z z + G(0) = 0`.
enum HighestAt {
    Explicit(Vec<(Symbol, ExprId)>),
    Linear {
        unknowns: Vec<Symbol>,
        /// `G(0)`, then `G_z` row-major.
        roots: Vec<ExprId>,
    },
}

impl HighestAt {
    /// The values of `q_i''` at `point`; `None` where (7) gives none
    /// (a singular mass matrix, a value that is not finite).
    fn at(&self, arena: &Arena, point: &SamplePoint) -> Option<Vec<(Symbol, f64)>> {
        let env = |s: Symbol| point.value(s);
        let values = match self {
            HighestAt::Explicit(highest) => {
                let roots: Vec<ExprId> = highest.iter().map(|&(_, e)| e).collect();
                let values = arena.eval_many(&roots, &env);
                highest.iter().map(|&(s, _)| s).zip(values).collect()
            }
            HighestAt::Linear { unknowns, roots } => {
                let n = unknowns.len();
                let values = arena.eval_many(roots, &env);
                let (free, jacobian) = values.split_at(n);
                let z = DMatrix::from_row_slice(n, n, jacobian)
                    .lu()
                    .solve(&DVector::from_iterator(n, free.iter().map(|g| -g)))?;
                unknowns.iter().copied().zip(z.iter().copied()).collect()
            }
        };
        let values: Vec<(Symbol, f64)> = values;
        values.iter().all(|(_, v)| v.is_finite()).then_some(values)
    }
}

/// With mass laws of the state and a reduced system of order 2, explicit
/// or linear in its highest derivatives: the multiplier route's whole
/// equation `E − R − Q` along the motion, projected and eliminated, each
/// law of the state put in (zero at the reduced system's `q_i''` when (7)
/// is right). `None` without laws of the state, and for a reduced system
/// of higher order or solved by Newton (which the check does not follow).
fn along_motion(derivation: &mut Derivation) -> Option<AlongMotion> {
    if derivation.forces_along_motion.is_empty() || derivation.reduced.order != 2 {
        return None;
    }
    let highest = match derivation.reduced.highest.clone() {
        Highest::Explicit(highest) => HighestAt::Explicit(
            derivation
                .independent
                .iter()
                .map(|&i| (jet(i, 2), highest[i as usize]))
                .collect(),
        ),
        Highest::Implicit {
            unknowns,
            residual,
            jacobian,
            linear: true,
            ..
        } => {
            let arena = &mut derivation.arena;
            let zero = arena.zero();
            let at_zero: HashMap<Symbol, ExprId> = unknowns.iter().map(|&z| (z, zero)).collect();
            let mut roots: Vec<ExprId> =
                residual.iter().map(|&g| arena.subst(g, &at_zero)).collect();
            roots.extend(jacobian.iter().flatten());
            HighestAt::Linear { unknowns, roots }
        }
        Highest::Implicit { .. } => return None,
    };
    let euler_lagrange = euler_lagrange(derivation);
    let arena = &mut derivation.arena;
    let residuals: Vec<ExprId> = euler_lagrange
        .iter()
        .zip(&derivation.forces_along_motion)
        .map(|(&e, &f)| arena.sub(e, f))
        .collect();
    let laws: HashMap<Symbol, ExprId> = derivation
        .state_laws
        .iter()
        .map(|&(i, law)| (Symbol::Mass(i), law))
        .collect();
    let mut elimination = Elimination::new(derivation.k, &derivation.constraints);
    let rows = derivation
        .equations
        .iter()
        .map(|eq| {
            let e = project(
                arena,
                &residuals,
                eq.coord,
                derivation.k,
                &derivation.constraints,
            );
            let e = elimination.eliminate(arena, e);
            (eq.coord, arena.subst(e, &laws))
        })
        .collect();
    Some(AlongMotion { rows, highest })
}

/// Compares the left sides of (4) with the multiplier route at
/// [`CROSS_CHECK_POINTS`] random points (and, with mass laws of the state,
/// the multiplier route's equations along the motion with the reduced
/// system (7)).
pub fn cross_check(derivation: &mut Derivation) -> Result<CrossCheck, CrossCheckFailure> {
    let multipliers = multiplier_route(derivation);
    let along = along_motion(derivation);
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
    let along_rows: &[(u32, ExprId)] = along.as_ref().map_or(&[], |a| &a.rows);
    roots.extend(along_rows.iter().map(|&(_, e)| e));
    roots.extend(&written);
    let rows = derivation.equations.len();
    let masses = arena.names().masses.len();
    let tape = Tape::new(arena, &roots);
    let mut rng = Rng::new(0x6d75_6c74);
    let mut points = 0;
    let mut worst: f64 = 0.0;
    for _ in 0..MAX_TRIES {
        let mut point = SamplePoint::random(&mut rng, &derivation.param_defaults, masses);
        if let Some(along) = &along {
            // The highest derivatives where (7) puts them (every identity
            // of the first comparison holds for any value of them).
            let Some(highest) = along.highest.at(arena, &point) else {
                continue;
            };
            for (s, v) in highest {
                if let Symbol::Jet { coord, order } = s {
                    point.set_jet(coord, order, v);
                }
            }
        }
        let values = tape.eval_scaled(&|s| point.value(s));
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
        for (&(coord, _), r) in along_rows.iter().zip(&values[2 * rows..]) {
            if r.value.abs() > CROSS_CHECK_TOLERANCE * r.scale {
                return Err(CrossCheckFailure::AlongMotion {
                    coord: arena.symbol_name(jet(coord, 0)),
                    t: point.t,
                    residual: r.value,
                    scale: r.scale,
                });
            }
            if r.scale > 0.0 {
                worst = worst.max(r.value.abs() / r.scale);
            }
        }
        for (w, (text, _)) in derivation.written.iter().enumerate() {
            let h = values[2 * rows + along_rows.len() + w];
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
