//! `lagc build -o DIR`: the generated crate and the runtime it depends on,
//! written where they build on their own.

use super::{generate, EXIT_USAGE};
use crate::cli::args::BuildArgs;
use std::process::ExitCode;

pub(crate) fn build(args: &BuildArgs) -> ExitCode {
    if args.fmu {
        return super::fmu::build_fmu(args);
    }
    let runtime_dir = args
        .runtime
        .clone()
        .unwrap_or_else(|| args.output.join(crate::cli::RUNTIME_IN_CRATE));
    // The crate's path to the runtime, relative where both can be placed.
    let runtime_path = match &args.runtime {
        None => crate::cli::RUNTIME_IN_CRATE.to_string(),
        Some(dir) => {
            // The runtime's sources are written over whatever is there: a
            // folder lagc did not write (the runtime's own source tree, a
            // project) must not lose its files to them.
            if !args.force && !crate::cli::may_write_into(dir) {
                eprintln!(
                    "error: `{}` is not empty and was not written by `lagc build`: refusing \
                     to write the runtime over it\n  = help: give --runtime an empty or new \
                     directory, or one an earlier `lagc build --runtime` wrote, or pass --force",
                    dir.display()
                );
                return ExitCode::from(EXIT_USAGE);
            }
            let made =
                std::fs::create_dir_all(dir).and_then(|()| std::fs::create_dir_all(&args.output));
            if let Err(error) = made {
                eprintln!("error: cannot create `{}`: {error}", dir.display());
                return ExitCode::from(EXIT_USAGE);
            }
            crate::cli::relative_path(&args.output, dir)
        }
    };
    let generated = match generate(&args.file, &runtime_path, None) {
        Ok(generated) => generated,
        Err(status) => return status,
    };
    if !args.force && !crate::cli::may_write_into(&args.output) {
        eprintln!(
            "error: `{}` is not empty and was not written by `lagc build`: refusing to \
             overwrite it\n  = help: choose an empty or new directory, or pass --force",
            args.output.display()
        );
        return ExitCode::from(EXIT_USAGE);
    }
    let marker = "written by `lagc build`; a later `lagc build` may overwrite this directory\n";
    let written = crate::cli::write_crate(&generated, &args.output)
        .and_then(|()| crate::cli::write_runtime(&runtime_dir))
        .and_then(|()| std::fs::write(args.output.join(crate::cli::MARKER), marker))
        .and_then(|()| std::fs::write(runtime_dir.join(crate::cli::MARKER), marker));
    match written {
        Ok(()) => {
            eprintln!(
                "wrote crate `{}` to {}",
                generated.package,
                args.output.display()
            );
            ExitCode::SUCCESS
        }
        Err(error) => {
            eprintln!(
                "error: cannot write to `{}`: {error}",
                args.output.display()
            );
            ExitCode::from(EXIT_USAGE)
        }
    }
}
