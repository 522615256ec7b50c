//! lagc-runtime: the numeric runtime of every crate lagc generates.
//!
//! A generated crate implements [`model::Model`] — the right side of the
//! reduced system (7), its exact Jacobians, the field method's coefficient
//! system, initial values, outputs, switching functions — and its `main`
//! is one line, [`cli::main`]. Everything that does not depend on the
//! model lives here, compiled and tested once.
//!
//! | module | what it holds |
//! |---|---|
//! | `model` | the trait generated code implements |
//! | `failure` | run-time failures with their physical cause (exit 3) |
//! | `linalg` | dense matrices, LU, Cholesky-free fixed solves, `expm` |
//! | `tolerance`, `controller`, `budget` | tolerances, the PI step controller, the work budget |
//! | `system`, `stepper` | what integrators integrate, and their interface |
//! | `dop853`, `rodas4` | the integrators, with dense output |
//! | `method` | integrator choice |

pub mod budget;
pub mod controller;
pub mod dop853;
pub mod failure;
pub mod highest;
pub mod linalg;
pub mod magnus;
pub mod method;
pub mod model;
pub mod rodas4;
pub mod stepper;
pub mod system;
pub mod tolerance;
pub mod cli;
pub mod direct;
pub mod driver;
pub mod events;
pub mod field;
pub mod output;
pub mod plot;
pub mod progress;
pub mod solution;
pub mod solver;
pub mod summary;
