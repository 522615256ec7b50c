//! The edge: the generated binary's command line, the Rust entry points
//! (`api`), a run's rows as numbers (`table`), CSV, summaries and plots.

pub mod api;
pub mod cli;
pub mod driver;
pub mod output;
pub mod plot;
pub mod summary;
pub mod table;
