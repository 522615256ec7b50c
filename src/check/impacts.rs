//! Impacts (SPEC §2.3): `when COND then y' = EXPR, x = EXPR;`. The
//! condition is a condition like `stop when`'s; each target is a component
//! of the state (a coordinate or one of its derivatives below the state's
//! order `u = max(2, k)`) that the run integrates freely: a dependent
//! derivative the constraints fix follows from them after the reset (lagc
//! recomputes it) and cannot be reset itself. With implicit constraints of
//! several candidates, a derivative some candidates fix is accepted: the
//! run resets it in a mode that leaves it free (or stops naming it).

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
                if let Some(diagnostic) =
                    fixed_component(&name, coord, order, k, constraints, &self.coords)
                {
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
/// reset, without its primary label: the constraints fix it in every mode
/// (a constraint of one candidate, or constraints of several whose
/// choices all take it), or the state's higher derivatives follow from
/// the equations of motion (k ≥ 3). A component only some candidates fix
/// is accepted: at the impact the run keeps or chooses a mode that leaves
/// it free, or stops naming it (`run::regime::mode_after_resets`).
fn fixed_component(
    name: &str,
    coord: usize,
    order: u32,
    k: u32,
    constraints: &[Constraint],
    coords: &[super::model::Coord],
) -> Option<Diagnostic> {
    let several = |c: &Constraint| c.implicit.as_ref().is_some_and(|i| i.candidates.len() > 1);
    if let Some(c) = constraints.iter().find(|c| !several(c) && c.coord == coord) {
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
    // The constraints of several candidates that would fix it where they
    // choose its coordinate (a raised one fixes its candidates from order
    // k − 1, the others from k): it is free in some mode unless they
    // cannot all choose another (coupled constraints take distinct
    // dependents).
    let taking: Vec<&Constraint> = constraints
        .iter()
        .filter(|c| {
            c.implicit.as_ref().is_some_and(|i| {
                let from = if i.raised { k.saturating_sub(1) } else { k };
                i.candidates.len() > 1 && i.candidates.contains(&coord) && order >= from
            })
        })
        .collect();
    if !taking.is_empty() {
        let mut others: Vec<usize> = taking
            .iter()
            .flat_map(|c| {
                c.implicit
                    .as_ref()
                    .map(|i| i.candidates.clone())
                    .unwrap_or_default()
            })
            .filter(|&j| j != coord)
            .collect();
        others.sort_unstable();
        others.dedup();
        if others.len() < taking.len() {
            let primes = "'".repeat(order as usize);
            let candidates = taking[0]
                .implicit
                .as_ref()
                .map(|i| {
                    i.candidates
                        .iter()
                        .map(|&j| format!("`{}{primes}`", coords[j].name))
                        .collect::<Vec<_>>()
                        .join(", ")
                })
                .unwrap_or_default();
            let mut diagnostic = Diagnostic::error(
                codes::RESET_OF_FIXED_COMPONENT,
                format!("`{name}` is fixed by the constraints whichever candidates they take: it cannot be reset"),
            )
            .with_note(format!(
                "these {} constraints solve for {} dependents among {candidates}; every choice \
                 takes `{name}`",
                taking.len(),
                taking.len()
            ))
            .with_help("reset a derivative that some choice of candidates leaves free");
            for c in &taking {
                diagnostic = diagnostic.with_secondary(c.span, "this constraint may fix it");
            }
            return Some(diagnostic);
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
