//! `lagc derive`: equations (4), the reduced system (7) and the field's
//! system, as text or LaTeX.

use super::{compile, status};
use crate::cli::args::{DeriveArgs, Format};
use std::process::ExitCode;

pub(crate) fn derive(args: &DeriveArgs) -> ExitCode {
    // The same derivation, cross-check included, as every other path: a
    // model whose equations (4) fail it is a model with errors (E0033).
    let stage = |source: &str| {
        let model = lagc::frontend(source)?;
        lagc::mechanics::derive_checked(&model).map(|checked| (checked, Vec::new()))
    };
    status(compile(&args.file, stage, |(derivation, check)| {
        match args.format {
            Format::Text => {
                print!("{}", derivation.text());
                let reduced = derivation.reduced.clone();
                let mut arena = derivation.arena.clone();
                let field = lagc::field::field_system(&mut arena, &reduced);
                print!("{}", field.text(&arena, &reduced.state));
            }
            Format::Latex => {
                let reduced = derivation.reduced.clone();
                let mut arena = derivation.arena.clone();
                let field = lagc::field::field_system(&mut arena, &reduced);
                print!(
                    "\\begin{{align*}}\n{}{}\\end{{align*}}\n",
                    derivation.latex_lines(),
                    field.latex_lines(&arena, &reduced.state)
                );
            }
        }
        eprintln!(
            "cross-check of (4) against the multiplier route: passed at {} points",
            check.points
        );
        ExitCode::SUCCESS
    }))
}
