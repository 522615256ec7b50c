//! Initial values: which derivatives the state needs at t0, and which the
//! constraints fix.
//!
//! With constraints of order k (none: k = 0) the state holds every
//! coordinate's derivatives of order < u = max(2, k). Required: every
//! coordinate's position, every independent coordinate's first derivative,
//! and every dependent coordinate's derivatives of order < k. Dependent
//! derivatives of order ≥ k follow from the constraints; independent ones of
//! order 2..k−1 follow from the equations of motion (SPEC §1.4).

use super::expressions::Allowed;
use super::model::{Constraint, Initial};
use super::Checker;
use crate::diagnostic::{codes, Diagnostic};
use crate::syntax::ast::ItemKind;

impl Checker<'_> {
    pub(super) fn initial(
        &mut self,
        order: Option<u32>,
        constraints: &[Constraint],
    ) -> Vec<Initial> {
        let k = order.unwrap_or(0);
        let state_order = k.max(2);
        let mut initial: Vec<Initial> = Vec::new();
        let mut first_statement = None;
        for (item, statement_span) in self.items() {
            let ItemKind::Initial(values) = item else {
                continue;
            };
            first_statement.get_or_insert(statement_span);
            for value in values {
                if self.check_value(&value.value) {
                    self.evaluate_finite(&value.value, "an initial value");
                }
                let Some((coord, order)) =
                    self.derivative_target(&value.target, "an initial value")
                else {
                    continue;
                };
                if order >= state_order {
                    let diagnostic = Diagnostic::error(
                        codes::DERIVATIVE_ORDER_NOT_ALLOWED,
                        format!("an initial value of order {order} is not part of the state"),
                    )
                    .with_primary(
                        value.target.span,
                        format!("the state holds derivatives of order below {state_order}"),
                    )
                    .with_help("remove it: the equations of motion determine it");
                    self.report(diagnostic);
                    continue;
                }
                if let Some(first) = initial
                    .iter()
                    .find(|i| (i.coord, i.order) == (coord, order))
                {
                    let diagnostic = Diagnostic::error(
                        codes::DUPLICATE_STATEMENT,
                        "an initial value is given twice",
                    )
                    .with_primary(value.target.span, "given again here")
                    .with_secondary(first.span, "first given here");
                    self.report(diagnostic);
                    continue;
                }
                initial.push(Initial {
                    coord,
                    order,
                    value: value.value.clone(),
                    span: value.span,
                });
            }
        }
        if !self.constraints_incomplete {
            self.missing_initial(k, constraints, &initial, first_statement);
        }
        initial
    }

    /// Reports each coordinate whose required initial values are missing.
    fn missing_initial(
        &mut self,
        k: u32,
        constraints: &[Constraint],
        initial: &[Initial],
        first_statement: Option<crate::span::Span>,
    ) {
        for coord in 0..self.coords.len() {
            // A holonomic constraint's dependent needs nothing: its given
            // position is only Newton's starting value (0 when it is not
            // given, note N0003), and its derivatives below k follow from
            // the constraint's.
            let required_below = match constraints.iter().find(|c| c.coord == coord) {
                Some(c) if c.is_holonomic() => 0,
                Some(_) => k,
                None => 2,
            };
            let missing: Vec<String> = (0..required_below)
                .filter(|&order| !initial.iter().any(|i| (i.coord, i.order) == (coord, order)))
                .map(|order| {
                    format!(
                        "`{}{}`",
                        self.coords[coord].name,
                        "'".repeat(order as usize)
                    )
                })
                .collect();
            if missing.is_empty() {
                continue;
            }
            let coordinate = &self.coords[coord];
            let list = missing.join(", ");
            let mut diagnostic = Diagnostic::error(
                codes::MISSING_INITIAL,
                format!("missing initial value for {list}"),
            )
            .with_primary(
                coordinate.span,
                format!("`{}` needs an initial value for {list}", coordinate.name),
            )
            .with_help(format!(
                "add `{} = …` to the `initial` statement",
                missing[0].trim_matches('`')
            ));
            if let Some(statement) = first_statement {
                diagnostic = diagnostic.with_secondary(statement, "initial values are given here");
            }
            // A missing position in a model with holonomic constraints: say
            // which positions the constraints complete, so that the user
            // gives the others.
            let completed: Vec<String> = constraints
                .iter()
                .filter(|c| c.is_holonomic() && c.coord != coord)
                .map(|c| format!("`{}`", self.coords[c.coord].name))
                .collect();
            if !completed.is_empty() && missing[0] == format!("`{}`", coordinate.name) {
                diagnostic = diagnostic.with_note(format!(
                    "the holonomic constraints complete the position of {} from the \
                     others; `{}` is not one of them",
                    completed.join(", "),
                    coordinate.name
                ));
            }
            // A later candidate of an implicit constraint: the initial
            // values take the first candidate as the derivative the
            // constraint fixes. A motion that starts where the other one
            // must be fixed (a knife edge heading along y, where
            // `for y' or x'` cannot give y' from x') names it first.
            // A raised constraint's candidates are all given (their values
            // choose its root, below), so none of them is "later".
            let later_candidate = constraints.iter().find_map(|c| {
                let implicit = c.implicit.as_ref().filter(|i| !i.raised)?;
                let first = *implicit.candidates.first()?;
                let missing_order = !initial
                    .iter()
                    .any(|i| (i.coord, i.order) == (coord, c.order));
                (implicit.candidates.iter().skip(1).any(|&q| q == coord) && missing_order)
                    .then_some((first, c.order, c.is_holonomic()))
            });
            // A non-linear constraint's candidate: which root of the
            // constraint the motion starts on is the user's to say.
            if let Some(c) = constraints
                .iter()
                .find(|c| c.coord == coord && c.is_raised())
            {
                let candidate = format!("{}{}", coordinate.name, "'".repeat(c.order as usize - 1));
                if missing.contains(&format!("`{candidate}`")) {
                    diagnostic = diagnostic.with_note(format!(
                        "the constraint fixing `{candidate}` is kept as written and solved \
                         through its derivative (it, or one solved with it, is not linear in \
                         its candidates): it may hold at several values of `{candidate}`, and \
                         the initial value chooses the one the motion starts on (lagc checks \
                         it against the constraint)"
                    ));
                }
            }
            // A constraint's dependent given in its place: the user took
            // the constraint the other way round (`s' = r*phi'` with `s'`
            // given and `phi'` not).
            let given_in_its_place = constraints.iter().find(|c| {
                c.coord != coord
                    && c.order >= 1
                    && missing.contains(&format!(
                        "`{}{}`",
                        coordinate.name,
                        "'".repeat(c.order as usize)
                    ))
                    && initial
                        .iter()
                        .any(|i| (i.coord, i.order) == (c.coord, c.order))
            });
            if let (Some(c), None) = (given_in_its_place, later_candidate) {
                let primes = "'".repeat(c.order as usize);
                let (this, dependent) = (
                    format!("{}{primes}", coordinate.name),
                    format!("{}{primes}", self.coords[c.coord].name),
                );
                let named = named_after_for(&coordinate.name, &primes, c.is_holonomic());
                diagnostic = diagnostic
                    .with_secondary(
                        c.span,
                        format!("this constraint fixes `{dependent}` from the others"),
                    )
                    .with_note(format!(
                        "`{dependent}` is given, but the constraint fixes it: a given \
                         value of it is only checked against the constraint"
                    ))
                    .with_help(format!(
                        "give `{this} = …` instead, or make the constraint fix `{this}` \
                         by naming {naming}: `constraint … for {named};`",
                        naming = if named == this {
                            "it".to_string()
                        } else {
                            format!("`{named}`")
                        },
                    ));
            }
            if let Some((first, order, holonomic)) = later_candidate {
                let primes = "'".repeat(order as usize);
                let (this, other) = (
                    format!("{}{primes}", coordinate.name),
                    format!("{}{primes}", self.coords[first].name),
                );
                let (this_named, other_named) = (
                    named_after_for(&coordinate.name, &primes, holonomic),
                    named_after_for(&self.coords[first].name, &primes, holonomic),
                );
                diagnostic = diagnostic.with_help(format!(
                    "the initial values take the first candidate, `{other}`, as the \
                     derivative the constraint fixes; to give `{other}` and have `{this}` \
                     fixed instead, name `{this_named}` first: `for {this_named} or {other_named}`"
                ));
            }
            self.report(diagnostic);
        }
    }

    /// Checks an initial value's expression; true if it is clean.
    fn check_value(&mut self, value: &crate::syntax::ast::Expr) -> bool {
        let errors_before = self.diagnostics.len();
        self.check_expr(value, Allowed::constants("an initial value"));
        self.diagnostics.len() == errors_before
    }
}

/// How a candidate is named after `for`: a derivative for a velocity (or
/// higher) constraint, the coordinate itself for a holonomic one, which is
/// solved for coordinates (`for y1` where the constraint fixes `y1'`;
/// `for y1'` there is E0038).
fn named_after_for(coordinate: &str, primes: &str, holonomic: bool) -> String {
    if holonomic {
        coordinate.to_string()
    } else {
        format!("{coordinate}{primes}")
    }
}
