//! Declared names: params, coordinates, mass laws and points share one
//! namespace; `t` is time and cannot be declared.

use super::model::{Coord, Name};
use super::Checker;
use crate::diagnostic::{codes, Diagnostic};
use crate::span::Span;
use crate::syntax::ast::{Ident, ItemKind};

#[derive(Debug, Clone, Copy)]
pub struct Declared {
    pub name: Name,
    pub span: Span,
}

pub fn kind_name(name: Name) -> &'static str {
    match name {
        Name::Param(_) => "a param",
        Name::Input(_) => "an input",
        Name::Coord(_) => "a coordinate",
        Name::Mass(_) => "a mass law",
        Name::Point(_) => "a point",
        Name::Let(_) => "a let",
        Name::Output(_) => "an output",
    }
}

impl Checker<'_> {
    /// Declares every name in source order. Indices count every declaration
    /// of a kind, so they match the order of the checked model's vectors.
    pub(super) fn declare(&mut self) {
        let (mut params, mut masses, mut points, mut inputs) = (0, 0, 0, 0);
        let (mut lets, mut outputs) = (0, 0);
        for (item, _) in self.items() {
            match item {
                ItemKind::Param { name, .. } => {
                    self.declare_one(name, Name::Param(params));
                    params += 1;
                }
                ItemKind::Input { name, .. } => {
                    self.declare_one(name, Name::Input(inputs));
                    inputs += 1;
                }
                ItemKind::Coords(names) => {
                    for name in names {
                        let index = self.coords.len();
                        if self.declare_one(name, Name::Coord(index)) {
                            self.coords.push(Coord {
                                name: name.name.clone(),
                                span: name.span,
                            });
                        }
                    }
                }
                ItemKind::Mass { name, .. } => {
                    self.declare_one(name, Name::Mass(masses));
                    masses += 1;
                }
                ItemKind::Point { name, .. } => {
                    self.declare_one(name, Name::Point(points));
                    points += 1;
                }
                ItemKind::Let { name, .. } => {
                    self.declare_one(name, Name::Let(lets));
                    lets += 1;
                }
                ItemKind::Output { name, .. } => {
                    self.declare_one(name, Name::Output(outputs));
                    outputs += 1;
                }
                _ => {}
            }
        }
        if !self
            .items()
            .any(|(item, _)| matches!(item, ItemKind::Coords(_)))
        {
            let diagnostic =
                Diagnostic::error(codes::MISSING_COORDINATES, "no coordinates declared")
                    .with_primary(
                        self.end_of_file,
                        "the model ends here without a `coord` statement",
                    )
                    .with_help("declare the generalized coordinates, e.g. `coord q1, q2;`");
            self.report(diagnostic);
        }
    }

    /// Declares `ident`; false (with a diagnostic) if it is `t` or taken.
    fn declare_one(&mut self, ident: &Ident, name: Name) -> bool {
        if ident.name == "t" {
            let diagnostic = Diagnostic::error(
                codes::RESERVED_TIME,
                "`t` is time and cannot be declared as a name",
            )
            .with_primary(ident.span, format!("declared here as {}", kind_name(name)))
            .with_help("choose another name; `t` always means time");
            self.report(diagnostic);
            return false;
        }
        if let Some(first) = self.names.get(&ident.name) {
            let diagnostic = Diagnostic::error(
                codes::DUPLICATE_NAME,
                format!("`{}` is declared twice", ident.name),
            )
            .with_primary(
                ident.span,
                format!("declared again here as {}", kind_name(name)),
            )
            .with_secondary(
                first.span,
                format!("first declared here as {}", kind_name(first.name)),
            )
            .with_help(
                "params, inputs, coordinates, mass laws, points, lets and outputs share one namespace",
            );
            self.report(diagnostic);
            return false;
        }
        self.names.insert(
            ident.name.clone(),
            Declared {
                name,
                span: ident.span,
            },
        );
        true
    }

    /// Every declared name and `t`, sorted, for "did you mean" help.
    pub(super) fn known_names(&self) -> Vec<&str> {
        let mut names: Vec<&str> = self.names.keys().map(String::as_str).collect();
        names.push("t");
        names.sort_unstable();
        names
    }
}
