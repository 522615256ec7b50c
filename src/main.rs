//! The `lagc` command line: the only place that does IO.
//!
//! Exit status (SPEC §3): 0 success, 1 the model has errors, 2 bad usage —
//! including a FILE that cannot be read, since that is a wrong argument
//! rather than a wrong model.

use clap::{Args, Parser, Subcommand};
use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;

/// lagc compiles a `.lag` model of a mechanical system with variable mass
/// and non-holonomic constraints into the generalized Lagrange equations of
/// the second kind, and integrates them with the field method.
#[derive(Debug, Parser)]
#[command(name = "lagc", version, about, long_about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Check a model and report every problem; prints nothing else.
    ///
    /// Exit status: 0 when the model is clean, 1 when it has errors, 2 when
    /// FILE cannot be read.
    Check(CheckArgs),
    /// Derive equations (4) and the reduced first-order system (7).
    ///
    /// Prints the equations, the reduced system, the state and its initial
    /// values, and the result of the cross-check of (4) against the
    /// multiplier route. Exit status: 0 on success, 1 when the model has
    /// errors, 2 when FILE cannot be read.
    Derive(DeriveArgs),
}

#[derive(Debug, Args)]
struct DeriveArgs {
    /// The `.lag` model.
    file: PathBuf,
    /// The output format.
    #[arg(long, value_enum, default_value_t = Format::Text)]
    format: Format,
}

#[derive(Debug, Clone, Copy, clap::ValueEnum)]
enum Format {
    /// Plain text.
    Text,
    /// A LaTeX `align*` block.
    Latex,
}

#[derive(Debug, Args)]
struct CheckArgs {
    /// The `.lag` model to check.
    file: PathBuf,
}

const EXIT_MODEL_ERRORS: u8 = 1;
const EXIT_USAGE: u8 = 2;

fn main() -> ExitCode {
    // clap exits with status 2 on a usage error, 0 for --help/--version.
    let cli = Cli::parse();
    match cli.command {
        Command::Check(args) => check(&args),
        Command::Derive(args) => derive(&args),
    }
}

fn check(args: &CheckArgs) -> ExitCode {
    let file_name = args.file.display().to_string();
    let bytes = match std::fs::read(&args.file) {
        Ok(bytes) => bytes,
        Err(error) => {
            eprintln!("error: cannot read `{file_name}`: {error}");
            return ExitCode::from(EXIT_USAGE);
        }
    };
    let color = std::io::stderr().is_terminal();
    lagc::on_big_stack(|| {
        let (source, result) = lagc::frontend_bytes(&bytes);
        match result {
            Ok(model) => {
                let constraints = match model.constraint_order {
                    Some(k) => format!(
                        "{} of order {k}",
                        count(model.constraints.len(), "constraint")
                    ),
                    None => "no constraints".to_string(),
                };
                let coords = count(model.coords.len(), "coordinate");
                eprintln!("{file_name}: ok ({coords}, {constraints})");
                ExitCode::SUCCESS
            }
            Err(diagnostics) => {
                eprint!(
                    "{}",
                    lagc::diagnostic::render(&diagnostics, &file_name, &source, color)
                );
                let errors = diagnostics.iter().filter(|d| d.is_error()).count();
                eprintln!("error: `{file_name}` has {}", count(errors, "error"));
                ExitCode::from(EXIT_MODEL_ERRORS)
            }
        }
    })
}

fn derive(args: &DeriveArgs) -> ExitCode {
    let file_name = args.file.display().to_string();
    let bytes = match std::fs::read(&args.file) {
        Ok(bytes) => bytes,
        Err(error) => {
            eprintln!("error: cannot read `{file_name}`: {error}");
            return ExitCode::from(EXIT_USAGE);
        }
    };
    let color = std::io::stderr().is_terminal();
    lagc::on_big_stack(|| {
        let (source, result) = lagc::frontend_bytes(&bytes);
        let derived = result.and_then(|model| lagc::mechanics::derive(&model));
        match derived {
            Ok(mut derivation) => {
                match args.format {
                    Format::Text => {
                        print!("{}", derivation.text());
                        let reduced = derivation.reduced.clone();
                        let mut arena = derivation.arena.clone();
                        let field = lagc::field::field_system(&mut arena, &reduced);
                        print!("{}", field.text(&arena, &reduced.state));
                    }
                    Format::Latex => print!("{}", derivation.latex()),
                }
                match lagc::mechanics::cross_check(&mut derivation) {
                    Ok(check) => eprintln!(
                        "cross-check of (4) against the multiplier route: passed at {} points",
                        check.points
                    ),
                    Err(failure) => {
                        eprintln!("error: cross-check failed: {failure}");
                        return ExitCode::from(EXIT_MODEL_ERRORS);
                    }
                }
                ExitCode::SUCCESS
            }
            Err(diagnostics) => {
                eprint!(
                    "{}",
                    lagc::diagnostic::render(&diagnostics, &file_name, &source, color)
                );
                let errors = diagnostics.iter().filter(|d| d.is_error()).count();
                eprintln!("error: `{file_name}` has {}", count(errors, "error"));
                ExitCode::from(EXIT_MODEL_ERRORS)
            }
        }
    })
}

/// "1 constraint", "2 constraints".
fn count(n: usize, noun: &str) -> String {
    let plural = if n == 1 { "" } else { "s" };
    format!("{n} {noun}{plural}")
}
