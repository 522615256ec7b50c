//! The run's public names where they have always been: the run itself
//! lives in [`crate::run`] (the steppable [`crate::run::integration::Integration`]
//! and the loops over it).

pub use crate::run::diagnosis::{diagnose, MassScale};
pub use crate::run::integration::make_solver;
pub use crate::run::integration::Spare;
pub use crate::run::options::{Ending, Options, Outcome};
pub use crate::run::regime::{
    best_mode, check_initial_candidates, initial_branches, mode_index, pivot_volumes,
};
pub use crate::run::{run, run_ensemble, run_reusing, solve, EnsembleOutcome};
