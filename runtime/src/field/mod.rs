//! Vujanović's field method (SPEC §1.5).
//!
//! | file | what |
//! |---|---|
//! | `coefficients.rs` | coefficient systems with sensitivities: the model's symbolic one, and the motion linearised along an iterate |
//! | `conditions.rs` | the conditions (13): the state from `f`, `S`; errors of `f`, `S` as errors of the state |
//! | `window.rs` | one anchored field, stepped with the state's error controlled |
//! | `affine.rs` | the field method proper, for affine reduced systems |
//! | `quasilinear.rs` | non-affine systems: Newton–Kantorovich on windows, each pass an affine field |

pub mod affine;
pub mod coefficients;
pub mod conditions;
pub mod quasilinear;
pub mod window;

pub use window::Anchor;

use crate::tolerance::Tolerance;

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
        }
    }
}

/// How many times the first step after an anchor is shortened (by 4 each
/// time) before the conditions are declared singular there.
pub(crate) const MAX_SHORTENINGS: usize = 40;
