//! `lagc derive`: equations (4), the reduced system (7) and the field's
//! system, as text or LaTeX.

use super::{compile, status};
use crate::cli::args::{DeriveArgs, Format};
use std::process::ExitCode;

pub(crate) fn derive(args: &DeriveArgs) -> ExitCode {
    // The same derivation, cross-check included, as every other path: a
    // model whose equations (4) fail it is a model with errors (E0033).
    // An implicit constraint with several candidates has a reduced system
    // (7) for each choice (SPEC 2.2): the text shows every mode's, the
    // first in full.
    let stage = |source: &str| {
        let model = lagc::frontend(source)?;
        let first = lagc::mechanics::derive_checked(&model)?;
        let mut others = Vec::new();
        for mode in 1..model.mode_count() {
            others.push(lagc::mechanics::derive_mode_checked(&model.in_mode(mode))?);
        }
        Ok(((first, others, model), Vec::new()))
    };
    status(compile(
        &args.file,
        stage,
        |((derivation, check), others, model)| {
            match args.format {
                Format::Text => {
                    print!("{}", derivation.text());
                    print!("{}", derivation.impacts_text(&model));
                    let reduced = derivation.reduced.clone();
                    let mut arena = derivation.arena.clone();
                    let field = lagc::field::field_system(&mut arena, &reduced);
                    print!("{}", field.text(&arena, &reduced.state));
                    let modes = others.len() + 1;
                    for (i, other) in others.iter().enumerate() {
                        println!(
                            "\n--- mode {} of {modes}: the implicit constraints solved for \
                         another candidate (the run switches to it where its pivot is \
                         the larger) ---\n",
                            i + 2
                        );
                        print!("{}", other.text());
                    }
                }
                Format::Latex => {
                    let reduced = derivation.reduced.clone();
                    let mut arena = derivation.arena.clone();
                    let field = lagc::field::field_system(&mut arena, &reduced);
                    print!(
                        "\\begin{{align*}}\n{}{}{}\\end{{align*}}\n",
                        derivation.latex_lines(),
                        derivation.impacts_latex_lines(&model),
                        field.latex_lines(&arena, &reduced.state)
                    );
                }
            }
            eprintln!(
                "cross-check of (4) against the multiplier route: passed at {} points",
                check.points
            );
            ExitCode::SUCCESS
        },
    ))
}
