//! One handler per subcommand; this module reads the model file and
//! renders its diagnostics for all of them. The handlers are the only code
//! that prints (the library does no IO).

mod build;
mod cache;
mod check;
mod derive;
mod fmu;
mod linearize;
mod report;
mod run;

use super::args::{Cli, Command};
use clap::Parser;
use lagc::diagnostic::{render, Diagnostic};
use std::io::IsTerminal;
use std::path::Path;
use std::process::ExitCode;

pub(crate) const EXIT_MODEL_ERRORS: u8 = 1;
pub(crate) const EXIT_USAGE: u8 = 2;

/// `lagc`'s `main`: the subcommand's handler.
pub fn main() -> ExitCode {
    // clap exits with status 2 on a usage error, 0 for --help/--version.
    let cli = Cli::parse();
    match cli.command {
        Command::Check(args) => check::check(&args),
        Command::Derive(args) => derive::derive(&args),
        Command::Build(args) => build::build(&args),
        Command::Run(args) => run::run(&args),
        Command::Cache(args) => cache::cache(&args),
        Command::Report(args) => report::report(&args),
        Command::Linearize(args) => linearize::linearize(&args),
    }
}

/// Reads `file`, runs `stage` on its text (on the big stack, invalid UTF-8
/// a diagnostic) and renders what it reports on stderr: on success its
/// notes, after which `then` runs (still on the big stack); on failure the
/// diagnostics and a count. `Err` holds the exit status of a failure.
pub(crate) fn compile<T, R: Send>(
    file: &Path,
    stage: impl FnOnce(&str) -> Result<(T, Vec<Diagnostic>), Vec<Diagnostic>> + Send,
    then: impl FnOnce(T) -> R + Send,
) -> Result<R, ExitCode> {
    compile_with(file, stage, then, true).map(|(value, _)| value)
}

/// [`compile`], the notes rendered and returned instead of printed when
/// `print_notes` is false (warnings and errors are printed either way).
fn compile_with<T, R: Send>(
    file: &Path,
    stage: impl FnOnce(&str) -> Result<(T, Vec<Diagnostic>), Vec<Diagnostic>> + Send,
    then: impl FnOnce(T) -> R + Send,
    print_notes: bool,
) -> Result<(R, String), ExitCode> {
    let file_name = file.display().to_string();
    let bytes = match super::read_model_file(file) {
        Ok(bytes) => bytes,
        Err(message) => {
            eprintln!("error: cannot read `{file_name}`: {message}");
            return Err(ExitCode::from(EXIT_USAGE));
        }
    };
    let color = std::io::stderr().is_terminal();
    lagc::on_big_stack(|| {
        let (source, result) = lagc::decode_then(&bytes, stage);
        let warnings = lagc::source_warnings(&source);
        match result {
            Ok((value, notes)) => {
                eprint!("{}", render(&warnings, &file_name, &source, color));
                let mut notes = render(&notes, &file_name, &source, color);
                if print_notes {
                    eprint!("{notes}");
                    notes.clear();
                }
                Ok((then(value), notes))
            }
            Err(mut diagnostics) => {
                diagnostics.extend(warnings);
                lagc::diagnostic::sort(&mut diagnostics);
                eprint!("{}", render(&diagnostics, &file_name, &source, color));
                let errors = diagnostics.iter().filter(|d| d.is_error()).count();
                eprintln!("error: `{file_name}` has {}", count(errors, "error"));
                Err(ExitCode::from(EXIT_MODEL_ERRORS))
            }
        }
    })
}

/// `Ok` or `Err`, both an exit status.
pub(crate) fn status(result: Result<ExitCode, ExitCode>) -> ExitCode {
    result.unwrap_or_else(|status| status)
}

/// "1 constraint", "2 constraints".
pub(crate) fn count(n: usize, noun: &str) -> String {
    let plural = if n == 1 { "" } else { "s" };
    format!("{n} {noun}{plural}")
}

/// The crate of `file` for `lagc run` and `lagc report`: built against the
/// runtime in the cache, keyed by the file's canonical path. Diagnostics
/// are printed; the notes (the local field method, N0001) are returned
/// rendered, for the caller to show when it builds the crate (or asked).
pub(crate) fn generate_cached(
    file: &Path,
) -> Result<(lagc::emit::GeneratedCrate, String), ExitCode> {
    generate_with(
        file,
        &crate::cli::runtime_path_from_cache(),
        Some(crate::cli::path_key(file)),
        false,
    )
}

/// Reads, checks and generates the crate of `file`, printing diagnostics
/// and notes; `Err(status)` when that fails.
pub(crate) fn generate(
    file: &Path,
    runtime_path: &str,
    package_key: Option<String>,
) -> Result<lagc::emit::GeneratedCrate, ExitCode> {
    generate_with(file, runtime_path, package_key, true).map(|(generated, _)| generated)
}

fn generate_with(
    file: &Path,
    runtime_path: &str,
    package_key: Option<String>,
    print_notes: bool,
) -> Result<(lagc::emit::GeneratedCrate, String), ExitCode> {
    let model_name = file
        .file_stem()
        .map_or_else(|| "model".to_string(), |s| s.to_string_lossy().into_owned());
    let stage = |source: &str| {
        let options = lagc::emit::EmitOptions {
            model_name: model_name.clone(),
            source_hash: super::source_hash(source),
            runtime_path: runtime_path.to_string(),
            package_key: package_key.clone(),
        };
        lagc::compile(source, &options)
    };
    compile_with(file, stage, |generated| generated, print_notes)
}
