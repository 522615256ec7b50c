//! lagc-runtime: the numeric runtime of every crate lagc generates.
//!
//! A generated crate implements [`model::Model`] — the right side of the
//! reduced system (7), its exact Jacobians, the field method's coefficient
//! system, initial values, outputs, switching functions — and its `main`
//! is one line, [`cli::main`]. Everything that does not depend on the
//! model lives here, compiled and tested once.
//!
//! Its layers, one folder each, bottom up; a module imports only its own
//! layer and those below (`tests/layers.rs`):
//!
//! | layer | modules |
//! |---|---|
//! | the root | `model` (the trait generated code implements, and `DynModel`, its object-safe face), `choice` (the user's method and integrator), `failure`, `quantity` (what a failure is about), `domain`, `linalg` (matrices, LU, `L D Lᵀ`, `expm`), `math` (`sin_cos`), `lanes` (four members' values computed together, each lane bit for bit the `f64` arithmetic), `highest` (the highest derivatives' solves), `closure` (Newton on holonomic constraints), `ensemble` (members' states) |
//! | `ode/` | the one-step integrators: `stepper` (the object-safe `Stepper<S>`, `Clock`, error measures), `dense` (a step's extension as a value), `dop853`, `rodas4`, `magnus`, `controller`, `tolerance`, `budget`, `system`; `ode/mod.rs` registers the integrators, one line each |
//! | `method/` | the methods behind `solver::Solver`: `direct`, `field/`; `segment`, a step's motion for a `Solution` |
//! | `run/` | the run: `integration` (a run as an object: `advance_to(t)`, the state, a restart), `options`, `regime` (branches, candidates), `diagnosis`, `solution`, `events`, `impacts` (`when`), `keep` (constraints kept), `watch` (the constraints as written), `progress`, `inputs`, `sensitivity`; the loops (`run::run`, `run::solve`) |
//! | `io/` | the edge: `api` (Rust entry points), `cli/` (the generated binary), `table` (rows as numbers, many runs on threads), `output`, `summary`, `plot`, `driver` (the run's old public names) |
//!
//! Every module is also re-exported under its old flat name
//! (`lagc_runtime::dop853`, `lagc_runtime::solution`, …): generated
//! crates, the Python module and the FMU name them so.

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
pub mod lanes;
pub mod linalg;
pub mod math;
pub mod method;
pub mod model;
pub mod ode;
pub mod quantity;
pub mod run;

// The flat names every module had before the folders (generated crates,
// the Python module and the FMU use them; the runtime itself does not).
pub use io::{api, cli, driver, output, plot, summary, table};
pub use method::{direct, field, segment, solver};
pub use ode::{budget, controller, dense, dop853, magnus, rodas4, stepper, system, tolerance};
pub use run::{events, impacts, inputs, integration, keep, progress, sensitivity, solution, watch};
