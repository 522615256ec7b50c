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
