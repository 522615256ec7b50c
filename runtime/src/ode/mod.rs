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

/// Systems the integrators' unit tests share.
#[cfg(test)]
pub(crate) mod test_systems {
    use super::system::System;
    use crate::failure::Failure;
    use crate::linalg::Matrix;

    /// `x' = v, v' = −ω² x` (ω = 0: a free flight).
    pub struct Spring(pub f64);

    impl System for Spring {
        fn dim(&self) -> usize {
            2
        }
        fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), Failure> {
            dy[0] = y[1];
            dy[1] = -self.0 * self.0 * y[0];
            Ok(())
        }
        fn jacobian(&self, _t: f64, _y: &[f64], jac: &mut Matrix) -> Result<(), Failure> {
            jac[(0, 1)] = 1.0;
            jac[(1, 0)] = -self.0 * self.0;
            Ok(())
        }
        fn time_partial(&self, _t: f64, _y: &[f64], _dydt: &mut [f64]) -> Result<(), Failure> {
            Ok(())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::stepper::{Family, StepperOf};
    use super::Integrator;
    use crate::ode::budget::Budget;
    use crate::ode::test_systems::Spring;
    use crate::ode::tolerance::Tolerance;

    /// The harmonic oscillator `y1' = y2, y2' = −y1`: `y = (cos t, −sin t)`
    /// from `(1, 0)`.
    const OSCILLATOR: Spring = Spring(1.0);

    struct OfOscillator;

    impl Family for OfOscillator {
        type System<'a> = Spring;
    }

    /// Every registered integrator keeps the registry's contract through
    /// the object a method holds: it starts, steps to the end landing on
    /// it, reaches the exact solution to about the tolerance, and has a
    /// continuous extension of its own (the quasilinear field's predictor
    /// relies on it), as a value and from the stepper, agreeing.
    #[test]
    fn every_registered_integrator_steps_and_extends_as_an_object() {
        let tol = Tolerance {
            rtol: 1e-10,
            atol: 1e-12,
        };
        for &integrator in Integrator::ALL {
            let name = integrator.name();
            let mut stepper: StepperOf<OfOscillator> = integrator
                .start::<OfOscillator>(&OSCILLATOR, 0.0, &[1.0, 0.0], tol, 10.0, None)
                .unwrap();
            let budget = Budget::new(100_000);
            let mut worst_dense: f64 = 0.0;
            while stepper.time() < 3.0 {
                stepper.step(&OSCILLATOR, 3.0, &budget).unwrap();
                let (a, b) = (stepper.previous_time(), stepper.time());
                let mid = 0.5 * (a + b);
                let mut from_stepper = [0.0; 2];
                stepper.dense(&OSCILLATOR, mid, &mut from_stepper).unwrap();
                let step = stepper.dense_step(&OSCILLATOR).unwrap();
                let step = step.unwrap_or_else(|| panic!("{name}: no continuous extension"));
                let mut from_value = [0.0; 2];
                step.eval(mid, &mut from_value);
                assert_eq!(from_stepper, from_value, "{name} at t = {mid}");
                worst_dense = worst_dense
                    .max((from_value[0] - mid.cos()).abs())
                    .max((from_value[1] + mid.sin()).abs());
            }
            assert_eq!(stepper.time(), 3.0, "{name} lands on the end");
            let y = stepper.state();
            let error = (y[0] - 3.0_f64.cos())
                .abs()
                .max((y[1] + 3.0_f64.sin()).abs());
            assert!(error < 1e-7, "{name}: error {error:e} at the end");
            assert!(worst_dense < 1e-6, "{name}: dense error {worst_dense:e}");
            assert!(stepper.stats().accepted_steps > 0, "{name}");
        }
        assert_eq!(Integrator::ALL.len(), 2);
        assert_eq!(Integrator::Explicit.name(), "DOP853");
        assert_eq!(Integrator::Stiff.name(), "RODAS4");
    }
}
