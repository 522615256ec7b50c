//! The generated binary's command line: one function, [`main`], that a
//! generated crate's `main` hands over to.
//!
//! Exit status: 0 success, 2 bad usage (including overrides that make the
//! model inconsistent), 3 a numerical failure.
//!
//! | file | what it holds |
//! |---|---|
//! | `args` | the arguments, parsed ([`parse`], [`USAGE`]) |
//! | `run` | a run: prepared, streamed as CSV, summarised |
//! | `bench` | `--ensemble`: one field for many initial states, timed |
//! | `exit` | a failure's message and exit status |
//!
//! (This file, not `cli/mod.rs`: a runtime written over an older one,
//! whose `cli.rs` stays, would otherwise hold the module twice.)

pub mod args;
pub mod bench;
mod exit;
pub mod run;

pub use args::{parse, Command, Invocation, MAX_SAMPLES, USAGE};
pub use bench::ensemble_member;
pub use run::{plan, prepare, prepare_driven, Prepared};

use crate::failure::USAGE_EXIT_STATUS;
use crate::model::{DynModel, Model};
use std::process::ExitCode;

/// The generated binary's `main`: the model with its file's param values
/// hands over to [`command_line`], compiled once here.
pub fn main<M: Model + 'static>() -> ExitCode {
    command_line(&M::new(&M::parameters(&vec![None; M::PARAMS.len()])))
}

/// The command line of `prototype`'s model (its param values are the
/// file's; `--param` makes another with [`DynModel::with_params`]).
pub fn command_line(prototype: &dyn DynModel) -> ExitCode {
    let model = prototype;
    let args: Vec<String> = std::env::args().skip(1).collect();
    match parse(
        &args,
        model.param_names(),
        model.state_names(),
        model.output_names(),
    ) {
        Err(message) => {
            eprintln!("error: {message}\n\n{USAGE}");
            ExitCode::from(USAGE_EXIT_STATUS)
        }
        Ok(Command::Help) => {
            println!("{USAGE}");
            ExitCode::SUCCESS
        }
        Ok(Command::SourceHash) => {
            println!("{}", model.source_hash());
            ExitCode::SUCCESS
        }
        Ok(Command::Run(invocation)) => run::execute(prototype, &invocation),
    }
}
