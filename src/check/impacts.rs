//! Impacts (SPEC §2.3): `when COND then y' = EXPR, x = EXPR;`. The
//! condition is a condition like `stop when`'s; each target is a component
//! of the state (a coordinate or one of its derivatives below the state's
//! order `u = max(2, k)`) that the run integrates freely: a dependent
//! derivative the constraints fix follows from them after the reset (lagc
//! recomputes it) and cannot be reset itself.

use super::expressions::Allowed;
use super::model::{Constraint, Impact, ImpactReset};
use super::types::Ty;
use super::Checker;
use crate::diagnostic::{codes, Diagnostic};
use crate::syntax::ast::ItemKind;

impl Checker<'_> {
    /// Every `when` statement, in source order.
    pub(super) fn impacts(
        &mut self,
        order: Option<u32>,
        constraints: &[Constraint],
    ) -> Vec<Impact> {
        let k = order.unwrap_or(0);
        let state_order = k.max(2);
        // The first constraint with several candidates, and how its
        // candidates are named: a holonomic constraint's are coordinates
        // (`for y`), a raised one's of order k − 1.
        let several_candidates = constraints.iter().find_map(|c| {
            let implicit = c.implicit.as_ref().filter(|i| i.candidates.len() > 1)?;
            let primes = if implicit.holonomic {
                0
            } else if implicit.raised {
                c.order - 1
            } else {
                c.order
            };
            let candidates: Vec<String> = implicit
                .candidates
                .iter()
                .map(|&j| format!("{}{}", self.coords[j].name, "'".repeat(primes as usize)))
                .collect();
            Some(candidates)
        });
        let condition = Allowed {
            time: true,
            masses: true,
            coord_order: Some(super::MAX_DERIVATIVE_ORDER),
            ..Allowed::constants("the condition of a `when`")
        };
        let value = Allowed {
            what: "a reset",
            ..condition
        };
        let mut impacts = Vec::new();
        for (item, span) in self.items() {
            let ItemKind::When { cond, text, resets } = item else {
                continue;
            };
            let errors = self.diagnostics.len();
            self.check_typed(cond, condition, Ty::Bool);
            let mut checked: Vec<ImpactReset> = Vec::new();
            for reset in resets {
                self.check_expr(&reset.value, value);
                let Some((coord, order)) = self.derivative_target(&reset.target, "a reset") else {
                    continue;
                };
                let name = format!("{}{}", self.coords[coord].name, "'".repeat(order as usize));
                if order >= state_order {
                    let diagnostic = Diagnostic::error(
                        codes::DERIVATIVE_ORDER_NOT_ALLOWED,
                        format!("`{name}` is not part of the state: it cannot be reset"),
                    )
                    .with_primary(
                        reset.target.span,
                        format!("the state holds derivatives of order below {state_order}"),
                    )
                    .with_help(
                        "reset a coordinate or a derivative the state holds (an impact \
                         resets velocities: `y' = -e * y'`)",
                    );
                    self.report(diagnostic);
                    continue;
                }
                if let Some(diagnostic) = fixed_component(
                    &name,
                    coord,
                    order,
                    k,
                    constraints,
                    several_candidates.as_deref(),
                ) {
                    self.report(diagnostic.with_primary(reset.target.span, "reset here"));
                    continue;
                }
                if let Some(first) = checked
                    .iter()
                    .find(|r| (r.coord, r.order) == (coord, order))
                {
                    let diagnostic = Diagnostic::error(
                        codes::DUPLICATE_STATEMENT,
                        format!("`{name}` is reset twice by one `when`"),
                    )
                    .with_primary(reset.target.span, "reset again here")
                    .with_secondary(first.span, "first reset here")
                    .with_help("one impact gives each component one new value");
                    self.report(diagnostic);
                    continue;
                }
                checked.push(ImpactReset {
                    coord,
                    order,
                    value: reset.value.clone(),
                    span: reset.span,
                });
            }
            if self.diagnostics.len() == errors {
                impacts.push(Impact {
                    text: text.clone(),
                    cond: cond.clone(),
                    resets: checked,
                    span,
                });
            }
        }
        impacts
    }
}

/// Why `name` (coordinate `coord`'s derivative of order `order`) cannot be
/// reset, without its primary label: the constraints fix it, or the
/// state's higher derivatives follow from the equations of motion (k ≥ 3),
/// or which derivatives the constraints fix changes along the run (several
/// candidates: the first such constraint's, as `for` names them).
fn fixed_component(
    name: &str,
    coord: usize,
    order: u32,
    k: u32,
    constraints: &[Constraint],
    several_candidates: Option<&[String]>,
) -> Option<Diagnostic> {
    if let Some(candidates) = several_candidates {
        return Some(
            Diagnostic::error(
                codes::RESET_OF_FIXED_COMPONENT,
                format!("`{name}` cannot be reset in a model whose implicit constraints have several candidates"),
            )
            .with_note(
                "which derivatives the constraints fix changes along the run; after a reset \
                 lagc recomputes the fixed ones, which it does for one candidate only",
            )
            .with_help(format!(
                "name one candidate, `constraint … for {};` (its candidates are {}), or write \
                 the constraint explicitly",
                candidates[0],
                candidates
                    .iter()
                    .map(|c| format!("`{c}`"))
                    .collect::<Vec<_>>()
                    .join(", ")
            )),
        );
    }
    if let Some(c) = constraints.iter().find(|c| c.coord == coord) {
        if order >= k {
            return Some(
                Diagnostic::error(
                    codes::RESET_OF_FIXED_COMPONENT,
                    format!("`{name}` is fixed by a constraint: it cannot be reset"),
                )
                .with_secondary(c.span, "this constraint fixes it")
                .with_note(
                    "after a reset lagc recomputes every derivative the constraints fix from \
                     the new state",
                )
                .with_help("reset the independent coordinates' derivatives"),
            );
        }
    }
    if k >= 3 {
        return Some(
            Diagnostic::error(
                codes::RESET_OF_FIXED_COMPONENT,
                format!("`{name}` cannot be reset in a model with constraints of order {k}"),
            )
            .with_note(
                "the state's derivatives of order 2 and above follow from equations (4) and \
                 would have to be solved again after the reset; lagc does not do that yet",
            ),
        );
    }
    None
}
