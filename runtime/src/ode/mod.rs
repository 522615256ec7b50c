//! One-step integrators and what they share: the systems they integrate,
//! the stepper interface, tolerances, the step-size controller, the work
//! budget, dense output.

pub mod budget;
pub mod controller;
pub mod dense;
pub mod dop853;
pub mod magnus;
pub mod rodas4;
pub mod stepper;
pub mod system;
pub mod tolerance;

use crate::failure::Failure;
use stepper::{Family, Start, StepperOf};
use tolerance::Tolerance;

/// The registry: every integrator that steps any [`system::System`], one
/// line each (`Variant => type`, the type implementing [`Start`] and
/// [`stepper::Stepper`]). A new integrator is its file here and its line.
/// (Magnus-4 is not here: it steps linear systems only, and the field's
/// windows, the one place that can use it, start it themselves.)
macro_rules! registry {
    ($($(#[$doc:meta])* $variant:ident => $ty:ty,)*) => {
        /// Which one-step method integrates a system.
        #[derive(Clone, Copy, Debug, PartialEq, Eq)]
        pub enum Integrator {
            $($(#[$doc])* $variant,)*
        }

        impl Integrator {
            /// Every registered integrator.
            pub const ALL: &'static [Integrator] = &[$(Integrator::$variant,)*];

            /// Its name in messages and summaries (`DOP853`).
            pub fn name(self) -> &'static str {
                match self {
                    $(Integrator::$variant => <$ty as Start>::NAME,)*
                }
            }

            /// Starts it at `(t0, y0)` on `system` (see [`Start::start`]),
            /// as a stepper for every system of the family `F`.
            pub fn start<F: Family>(
                self,
                system: &F::System<'_>,
                t0: f64,
                y0: &[f64],
                tol: Tolerance,
                h_max: f64,
                h0: Option<f64>,
            ) -> Result<StepperOf<F>, Failure> {
                Ok(match self {
                    $(Integrator::$variant => {
                        Box::new(<$ty as Start>::start(system, t0, y0, tol, h_max, h0)?)
                    })*
                })
            }
        }
    };
}

registry! {
    /// DOP853, explicit, order 8.
    Explicit => dop853::Dop853,
    /// RODAS4, linearly implicit, order 4, for stiff systems.
    Stiff => rodas4::Rodas4,
}
