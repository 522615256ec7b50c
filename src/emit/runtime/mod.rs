//! The numeric runtime of a generated crate.
//!
//! lagc copies the modules a system needs into the generated crate verbatim
//! (`include_str!`) and emits only the system-specific parts: the right side
//! of (7) as a [`system::Motion`] and the coefficient system as a
//! [`system::CoefficientSystem`]. Every module depends on `std` and
//! `nalgebra` only.
//!
//! | module | what it holds |
//! |---|---|
//! | `system` | the traits the generated code implements |
//! | `error` | [`error::Failure`], the run-time failures (exit status 3) |
//! | `stepper` | tolerances, work counters, the error norm, the stepping loop |
//! | `dop853` | the explicit DOP853 integrator (order 8, embedded 5 and 3) |
//! | `rosenbrock` | the stiff RODAS4 integrator (order 4, embedded 3) |
//! | `magnus` | the Magnus integrator (order 4) for linear coefficient systems |
//! | `sensitivity` | the coefficient system augmented by `S = ∂f/∂c` |
//! | `conditioned` | the conditions (13): `x_B(t)` from `f`, `S` |
//! | `field` | the field method with re-anchoring |
//! | `local_field` | the local field method for non-affine systems |
//! | `method` | the choice of integrator at run time |
//! | `direct` | direct integration of (7) at the sample times |
//! | `output` | sample times, CSV, the run summary |

// A library of parts: each generated crate uses only some of them, and the
// test binary compiles them all, so unused items are expected.
#![allow(dead_code)]

pub mod conditioned;
pub mod direct;
pub mod dop853;
pub mod error;
pub mod field;
pub mod local_field;
pub mod magnus;
pub mod method;
pub mod output;
pub mod rosenbrock;
pub mod sensitivity;
pub mod stepper;
pub mod system;
