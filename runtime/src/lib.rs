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
//! | `closure` | Newton on holonomic constraints (initial positions, keeping) |
//! | `failure` | run-time failures with their physical cause (exit 3) |
//! | `linalg` | dense matrices, LU, fixed-size LU and `L D Lᵀ` solves, `expm` |
//! | `math` | `sin_cos`: a sine and a cosine in one call |
//! | `tolerance`, `controller`, `budget` | tolerances, the PI step controller, the work budget |
//! | `system`, `stepper` | what integrators integrate, and their interface |
//! | `dop853`, `rodas4` | the integrators, with dense output |
//! | `dense` | a step's continuous extension as a value (`DenseStep`) |
//! | `method` | integrator choice |
//! | `run/` | the run: `integration` (a run as an object: `advance_to(t)`, the state, a restart from a given state), `options`, `regime` (branches, candidates), `diagnosis`, `solution`; the loops over an integration (`run::run`, `run::solve`) |
//! | `segment` | one step's motion as a value, for a `Solution` |
//! | `driver` | the run's public names where they have always been (re-exports of `run`) |
//! | `events`, `impacts` | locating events; the resets of `when` at them |
//! | `inputs` | inputs set from outside: their values in the model, signals, runs restarted at their changes |
//! | `table` | a run's rows as numbers (bit for bit the CLI's), many runs on threads |
//! | `sensitivity` | forward sensitivities: the variational equations as an augmented system |
//! | `quantity` | the quantity a failure is about, as a value |
//! | `watch` | the constraints as written along a run: where a branch ends, a failure's cause |

// Numerical kernels index several arrays with one loop variable; and
// `!(x > 0.0)` is meant: it is true for NaN.
#![allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]

pub mod choice;
pub mod closure;
pub mod domain;
pub mod ensemble;
pub mod failure;
pub mod highest;
pub mod io;
pub mod linalg;
pub mod math;
pub mod method;
pub mod model;
pub mod ode;
pub mod quantity;
pub mod run;

// The flat names every module had before the folders.
pub use io::{api, cli, driver, output, plot, summary, table};
pub use method::{direct, field, segment, solver};
pub use ode::{budget, controller, dense, dop853, magnus, rodas4, stepper, system, tolerance};
pub use run::{events, impacts, inputs, integration, keep, progress, sensitivity, solution, watch};
