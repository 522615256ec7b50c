//! `lagc linearize`: A = ∂f/∂x of the reduced system at a point, its
//! eigenvalues and the residual, as text, JSON or LaTeX.

use super::{compile, status, EXIT_USAGE};
use crate::cli::args::{LinearizeArgs, LinearizeFormat};
use lagc::linearize::{ErrorKind, Request};
use std::process::ExitCode;

/// A point where A is not defined is a numerical failure, as at run time.
const EXIT_UNDEFINED: u8 = 3;

pub(crate) fn linearize(args: &LinearizeArgs) -> ExitCode {
    let stage = |source: &str| {
        let model = lagc::frontend(source)?;
        let (derivation, _) = lagc::mechanics::derive_checked(&model)?;
        Ok(((model, derivation), Vec::new()))
    };
    let request = Request {
        at: args.at.clone(),
        params: args.params.clone(),
        t: args.t.clone(),
        symbolic: args.symbolic,
        inputs: args.inputs.clone(),
    };
    status(compile(
        &args.file,
        stage,
        |(model, derivation)| match lagc::linearize::linearize(&model, &derivation, &request) {
            Ok(l) => {
                match args.format {
                    LinearizeFormat::Text => print!("{l}"),
                    LinearizeFormat::Json => print!("{}", l.json()),
                    LinearizeFormat::Latex => print!("{}", l.latex()),
                }
                ExitCode::SUCCESS
            }
            Err(e) => {
                eprint!("{e}");
                ExitCode::from(match e.kind {
                    ErrorKind::Usage => EXIT_USAGE,
                    ErrorKind::Undefined => EXIT_UNDEFINED,
                })
            }
        },
    ))
}
