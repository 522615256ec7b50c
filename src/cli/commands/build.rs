//! `lagc build -o DIR`: the generated crate and the runtime it depends on,
//! written where they build on their own; with `--python`, the model's
//! Python project and the `lagc-python` library beside the runtime.

use super::{generate, EXIT_USAGE};
use crate::cli::args::BuildArgs;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

const MARKER_TEXT: &str =
    "written by `lagc build`; a later `lagc build` may overwrite this directory\n";

/// Refuses a library directory given by an option (`--runtime`,
/// `--python-lib`) that holds files lagc did not write: the library's
/// sources are written over whatever is there, and a folder lagc did not
/// write (the runtime's own source tree, a project) must not lose its files
/// to them.
fn refuse_foreign(
    dir: &Option<PathBuf>,
    option: &str,
    what: &str,
    force: bool,
) -> Result<(), ExitCode> {
    match dir {
        Some(dir) if !force && !crate::cli::may_write_into(dir) => {
            eprintln!(
                "error: `{}` is not empty and was not written by `lagc build`: refusing \
                 to write the {what} over it\n  = help: give {option} an empty or new \
                 directory, or one an earlier `lagc build {option}` wrote, or pass --force",
                dir.display()
            );
            Err(ExitCode::from(EXIT_USAGE))
        }
        _ => Ok(()),
    }
}

/// The library's directory and its path as the project at `output` sees
/// it: `default_name` inside `output`, or the option's directory.
fn library_dir(
    output: &Path,
    given: &Option<PathBuf>,
    default_name: &str,
) -> Result<(PathBuf, String), ExitCode> {
    match given {
        None => Ok((output.join(default_name), default_name.to_string())),
        Some(dir) => {
            let made = std::fs::create_dir_all(dir).and_then(|()| std::fs::create_dir_all(output));
            if let Err(error) = made {
                eprintln!("error: cannot create `{}`: {error}", dir.display());
                return Err(ExitCode::from(EXIT_USAGE));
            }
            Ok((dir.clone(), crate::cli::relative_path(output, dir)))
        }
    }
}

pub(crate) fn build(args: &BuildArgs) -> ExitCode {
    if args.fmu {
        return super::fmu::build_fmu(args);
    }
    match build_checked(args) {
        Ok(status) | Err(status) => status,
    }
}

fn build_checked(args: &BuildArgs) -> Result<ExitCode, ExitCode> {
    refuse_foreign(&args.runtime, "--runtime", "runtime", args.force)?;
    refuse_foreign(
        &args.python_lib,
        "--python-lib",
        "Python library",
        args.force,
    )?;
    let (runtime_dir, runtime_path) =
        library_dir(&args.output, &args.runtime, crate::cli::RUNTIME_IN_CRATE)?;
    let python = if args.python {
        Some(library_dir(
            &args.output,
            &args.python_lib,
            crate::cli::PYTHON_IN_PROJECT,
        )?)
    } else {
        None
    };
    let generated = generate(&args.file, &runtime_path, None)?;
    if !args.force && !crate::cli::may_write_into(&args.output) {
        eprintln!(
            "error: `{}` is not empty and was not written by `lagc build`: refusing to \
             overwrite it\n  = help: choose an empty or new directory, or pass --force",
            args.output.display()
        );
        return Err(ExitCode::from(EXIT_USAGE));
    }
    let written = if let Some((python_dir, python_path)) = python {
        let paths = lagc::emit::python::PythonPaths {
            runtime: runtime_path,
            python: python_path,
        };
        let linear = python_linear(&args.file)?;
        write_python(args, &generated, &linear, &runtime_dir, &python_dir, &paths)
    } else {
        crate::cli::write_crate(&generated, &args.output).map(|()| {
            format!(
                "wrote crate `{}` to {}",
                generated.package,
                args.output.display()
            )
        })
    };
    let written = written.and_then(|message| {
        crate::cli::write_runtime(&runtime_dir)?;
        std::fs::write(args.output.join(crate::cli::MARKER), MARKER_TEXT)?;
        std::fs::write(runtime_dir.join(crate::cli::MARKER), MARKER_TEXT)?;
        Ok(message)
    });
    match written {
        Ok(message) => {
            eprintln!("{message}");
            Ok(ExitCode::SUCCESS)
        }
        Err(error) => {
            eprintln!(
                "error: cannot write to `{}`: {error}",
                args.output.display()
            );
            Err(ExitCode::from(EXIT_USAGE))
        }
    }
}

/// The Python project into `args.output` and the `lagc-python` library
/// (default: inside it); the message to print.
/// The model's `impl lagc_python::Linear` (its linearization for
/// `m.linearize`); the model compiled already, so a failure here is lagc's.
fn python_linear(file: &Path) -> Result<String, ExitCode> {
    let source = std::fs::read_to_string(file).unwrap_or_default();
    match lagc::on_big_stack(move || lagc::pipeline::python_linear(&source)) {
        Ok(code) => Ok(code),
        Err(diagnostics) => {
            for d in diagnostics {
                eprintln!("error: {}", d.message);
            }
            Err(ExitCode::from(EXIT_USAGE))
        }
    }
}

fn write_python(
    args: &BuildArgs,
    generated: &lagc::emit::GeneratedCrate,
    linear: &str,
    runtime_dir: &Path,
    python_dir: &Path,
    paths: &lagc::emit::python::PythonPaths,
) -> std::io::Result<String> {
    use lagc::emit::python::{python_library_files, python_module_name, python_project};
    std::fs::create_dir_all(python_dir)?;
    std::fs::create_dir_all(runtime_dir)?;
    let model_name = args
        .file
        .file_stem()
        .map_or_else(|| "model".to_string(), |s| s.to_string_lossy().into_owned());
    let module = python_module_name(&model_name);
    for (path, contents) in python_project(generated, linear, &module, paths) {
        crate::cli::cache::write_if_changed(&args.output.join(path), contents.as_bytes())?;
    }
    let runtime_from_python = crate::cli::relative_path(python_dir, runtime_dir);
    for (path, contents) in python_library_files(&runtime_from_python) {
        crate::cli::cache::write_if_changed(&python_dir.join(path), contents.as_bytes())?;
    }
    std::fs::write(python_dir.join(crate::cli::MARKER), MARKER_TEXT)?;
    Ok(format!(
        "wrote the Python project of module `{module}` to {} (`pip install {}` builds and \
         installs it)",
        args.output.display(),
        args.output.display()
    ))
}
