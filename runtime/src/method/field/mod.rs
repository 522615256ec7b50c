//! Vujanović's field method (SPEC §1.5).
//!
//! | file | what |
//! |---|---|
//! | `coefficients.rs` | coefficient systems with sensitivities: the model's symbolic one, and the motion linearised along an iterate |
//! | `conditions.rs` | the conditions (13): the state from `f`, `S`; errors of `f`, `S` as errors of the state |
//! | `window.rs` | one anchored field, stepped with the state's error controlled |
//! | `affine.rs` | the field method proper, for affine reduced systems |
//! | `middle.rs` | the quasilinear field's output between steps, judged at each piece's middle |
//! | `quasilinear.rs` | non-affine systems: Newton–Kantorovich on windows, each pass an affine field |
//! | `global_error.rs` | the global error estimate carried along the run, for the summary |

pub mod affine;
pub mod coefficients;
pub mod conditions;
pub mod global_error;
pub mod middle;
pub mod quasilinear;
pub mod window;

pub use window::Anchor;

use crate::ode::tolerance::Tolerance;

/// How the field method runs.
#[derive(Clone, Debug, PartialEq)]
pub struct FieldOptions {
    pub tol: Tolerance,
    pub anchor: Anchor,
    /// Re-anchor when the condition number of the conditions (13) would
    /// pass this: rounding in the recovered state grows with it.
    pub max_condition: f64,
    /// Re-anchor when `max |S_ij|` would pass this (the field nears a pole
    /// of a Riccati coefficient system, or the adjoint of a fast decaying
    /// mode grows like `e^{+|λ|t}`).
    pub max_growth: f64,
    /// Without re-anchoring, degraded conditions are a failure
    /// (`--no-reanchor`, to see where the field degrades).
    pub reanchor: bool,
    /// Integrate the coefficients with RODAS4 from the start.
    pub stiff: bool,
    /// Switch to RODAS4 at the next re-anchoring once DOP853 detects
    /// stiffness in the coefficients.
    pub auto_stiff: bool,
    /// Affine models: integrate the coefficients (in projective form) by
    /// the Magnus integrator.
    pub magnus: bool,
    /// Estimate the global error along the run (`Options::global_error`).
    pub global_error: bool,
}

impl Default for FieldOptions {
    fn default() -> Self {
        FieldOptions {
            tol: Tolerance::default(),
            anchor: Anchor::Zero,
            max_condition: 1e4,
            max_growth: 1e12,
            reanchor: true,
            stiff: false,
            auto_stiff: true,
            magnus: false,
            global_error: true,
        }
    }
}

/// How many times the first step after an anchor is shortened (by 4 each
/// time) before the conditions are declared singular there.
pub(crate) const MAX_SHORTENINGS: usize = 40;

use crate::failure::{Failure, FailureKind};
use crate::model::DynModel;

/// A failure met while the field looked ahead of the motion, said in
/// terms of the motion. The field evaluates the equations at trial times
/// beyond where the motion has got to (a predictor's or a window's
/// stages), so the time of the first bad value is not where the motion
/// stops: when the equations at the state reached fail as time alone
/// advances (a force infinite at some `t`, accelerations that cease to
/// exist), the failure is placed where they start to fail, found by
/// bisection. A non-finite value in the field's own quantities (its
/// coefficients, their sensitivities) is named as the rate it comes
/// from, or else as the motion blowing up. Internal names never reach
/// the user.
pub(crate) fn explain(
    model: &dyn DynModel,
    failure: Failure,
    t_reached: f64,
    x: &[f64],
) -> Failure {
    let internal = match &failure.kind {
        FailureKind::NonFiniteState { component } | FailureKind::NonFiniteRate { component } => {
            component.starts_with("the field")
        }
        FailureKind::NewtonNonConvergence { .. } | FailureKind::SingularMassMatrix { .. } => false,
        _ => return failure,
    };
    let mut rate = vec![0.0; x.len()];
    // How the equations fail at the state reached, at time `t`.
    let mut broken_at = |t: f64| -> Option<Failure> {
        match model.rhs(t, x, &mut rate) {
            Err(failure) => Some(failure),
            Ok(()) => crate::ode::tolerance::first_non_finite(&rate).map(|i| {
                let name = model.state_names().get(i).map_or("x", |s| s);
                Failure::non_finite_rate(t, format!("{name}'"))
            }),
        }
    };
    let t = failure.time;
    let lo = t_reached.min(t);
    if let Some(broken) = broken_at(lo) {
        return if internal { broken } else { failure };
    }
    // Where the equations first fail: at the failure's time, or (for the
    // field's own quantities, which fail a little before the rates they
    // come from) just ahead of it.
    let hi = if t > lo && broken_at(t).is_some() {
        Some(t)
    } else if internal {
        (0..=12)
            .map(|k| t + t.abs().max(1.0) * 1e-13 * 10f64.powi(k))
            .find(|&ahead| broken_at(ahead).is_some())
    } else {
        None
    };
    if let Some(mut hi) = hi {
        let mut lo = lo;
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            if broken_at(mid).is_some() {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        if let Some(broken) = broken_at(hi) {
            return broken;
        }
    }
    if !internal {
        return failure;
    }
    Failure::non_finite(t, "the state (the field's coefficients overflow)")
}
