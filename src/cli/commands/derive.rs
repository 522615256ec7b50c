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
                    // The derivation's arena is written in and goes on into
                    // the field's system without a copy (a large model's
                    // holds millions of nodes), and is left to the
                    // operating system at exit instead of being freed node
                    // by node.
                    let mut derivation = derivation;
                    let names = derivation.arena.names().clone();
                    let mut arena =
                        std::mem::replace(&mut derivation.arena, lagc::ir::Arena::new(names));
                    print!("{}", derivation.text_in(&mut arena));
                    std::mem::swap(&mut derivation.arena, &mut arena);
                    print!("{}", derivation.impacts_text(&model));
                    let lagc::mechanics::Derivation {
                        mut arena, reduced, ..
                    } = derivation;
                    let field = lagc::field::field_system(&mut arena, &reduced);
                    print!("{}", field.text(&arena, &reduced.state));
                    std::mem::forget(arena);
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
                    let lines = derivation.latex_lines();
                    let impacts = derivation.impacts_latex_lines(&model);
                    // As for the text: the arena without a copy, unfreed.
                    let lagc::mechanics::Derivation {
                        mut arena, reduced, ..
                    } = derivation;
                    let field = lagc::field::field_system(&mut arena, &reduced);
                    print!(
                        "\\begin{{align*}}\n{lines}{impacts}{}\\end{{align*}}\n",
                        field.latex_lines(&arena, &reduced.state)
                    );
                    std::mem::forget(arena);
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
