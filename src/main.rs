//! The `lagc` command line: the only place that does IO (`cli/`).
//!
//! Exit status (SPEC §3): 0 success, 1 the model has errors, 2 bad usage —
//! including a FILE that cannot be read, since that is a wrong argument
//! rather than a wrong model.

mod cli;

fn main() -> std::process::ExitCode {
    cli::commands::main()
}
