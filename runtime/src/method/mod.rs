//! The methods that compute a model's motion, behind one interface
//! (`solver::Solver`): direct integration of the reduced system (7)
//! (`direct`) and Vujanović's field method (`field/`); `segment`, a step's
//! motion kept as a value for a solution.

pub mod deviation;
pub mod direct;
pub mod field;
pub mod segment;
pub mod solver;

// Where generated crates and the Python layer name them.
pub use crate::choice::{IntegratorChoice, Method};
