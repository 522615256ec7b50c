//! A `when` whose condition already holds at the start (SPEC §2.3): an
//! impact fires where the motion enters its condition, so a state that
//! starts inside it never fires one — a ball started below its floor
//! (`initial y = -0.1` with `when y < 0 then y' = -e * y'`) fell through
//! the floor for ever, exit 0. Where every value the condition reads is a
//! constant the file states, `check` says so; a start set at run time
//! (`--init`, `--param`, Python, an FMU) meets the run's own check
//! (lagc-runtime's `run::start`), which this one never contradicts: a
//! comparison within a millionth of its sides' size of its boundary is
//! left to the run, which tells the boundary from rounding (Newton's
//! cradle with touching balls, `x3 - x2 < 2 * r` with 0.3 − 0.2).

use super::model::{Impact, Initial, TimeSpan};
use super::Checker;
use crate::diagnostic::{codes, Diagnostic};
use crate::syntax::ast::{CmpOp, Expr, ExprKind, LogicOp};

/// The start as the condition reads it: `t0` and the stated initial
/// values, each `((coord, order), value)`.
pub(super) struct Start {
    pub t0: f64,
    values: Vec<((usize, u32), f64)>,
}

impl Start {
    pub fn value(&self, coord: usize, order: u32) -> Option<f64> {
        self.values
            .iter()
            .find(|(key, _)| *key == (coord, order))
            .map(|&(_, v)| v)
    }
}

/// How far (relative to the larger side) a comparison must stand from its
/// boundary to count as decided here.
const MARGIN: f64 = 1e-6;

impl Checker<'_> {
    /// Sets the start the file states (its time and the initial values that
    /// read constants only) as what expressions are evaluated at, and
    /// returns its time; `None` where that time is not a constant.
    pub(super) fn state_the_start(&mut self, initial: &[Initial], time: &TimeSpan) -> Option<f64> {
        let t0 = self.evaluate(&time.start)?;
        let values = initial
            .iter()
            .filter_map(|i| Some(((i.coord, i.order), self.evaluate(&i.value)?)))
            .filter(|(_, v)| v.is_finite())
            .collect();
        self.start = Some(Start { t0, values });
        Some(t0)
    }

    /// Reports every `when` whose condition holds, clear of its boundary,
    /// at the start the file states.
    pub(super) fn impacts_at_start(
        &mut self,
        impacts: &[Impact],
        initial: &[Initial],
        time: &TimeSpan,
    ) {
        if impacts.is_empty() || self.state_the_start(initial, time).is_none() {
            return;
        }
        let holding: Vec<(&Impact, Vec<&Initial>)> = impacts
            .iter()
            .filter(|impact| self.holds(&impact.cond) == Some(true))
            .map(|impact| {
                let mut read = Vec::new();
                self.initial_read(&impact.cond, initial, &mut read);
                (impact, read)
            })
            .collect();
        self.start = None;
        for (impact, read) in holding {
            let start = read
                .iter()
                .map(|i| {
                    let name = format!(
                        "{}{}",
                        self.coords[i.coord].name,
                        "'".repeat(i.order as usize)
                    );
                    let value = self.evaluate(&i.value).unwrap_or(f64::NAN);
                    format!("{name} = {value}")
                })
                .collect::<Vec<_>>()
                .join(", ");
            let mut diagnostic = Diagnostic::error(
                codes::IMPACT_HOLDS_AT_START,
                format!(
                    "the condition of `when {}` already holds at the start",
                    impact.text
                ),
            )
            .with_primary(
                impact.cond.span,
                if start.is_empty() {
                    "true at the start".to_string()
                } else {
                    format!("true at the start, where {start}")
                },
            );
            for i in &read {
                diagnostic = diagnostic.with_secondary(i.span, "the initial value");
            }
            diagnostic = diagnostic
                .with_note(
                    "an impact fires where the motion enters its condition: started inside \
                     it, the motion would pass through the region the impact forbids with \
                     no impact at all",
                )
                .with_help(
                    "start on the condition's other side (on its boundary is fine: the \
                     motion into it fires the impact)",
                );
            self.report(diagnostic);
        }
    }

    /// The condition's truth at the start: `None` where it reads a value
    /// not stated as a constant or a comparison stands within [`MARGIN`]
    /// of its boundary.
    fn holds(&self, cond: &Expr) -> Option<bool> {
        match &cond.kind {
            ExprKind::Compare { op, lhs, rhs } => {
                let (a, b) = (self.evaluate(lhs)?, self.evaluate(rhs)?);
                if !(a.is_finite() && b.is_finite())
                    || (a - b).abs() <= MARGIN * a.abs().max(b.abs())
                {
                    return None;
                }
                Some(match op {
                    CmpOp::Less | CmpOp::LessEq => a < b,
                    CmpOp::Greater | CmpOp::GreaterEq => a > b,
                })
            }
            ExprKind::Logic { op, lhs, rhs } => {
                let (a, b) = (self.holds(lhs), self.holds(rhs));
                match op {
                    LogicOp::And if a == Some(false) || b == Some(false) => Some(false),
                    LogicOp::And => Some(a? && b?),
                    LogicOp::Or if a == Some(true) || b == Some(true) => Some(true),
                    LogicOp::Or => Some(a? || b?),
                }
            }
            ExprKind::Not(inner) => self.holds(inner).map(|v| !v),
            _ => None,
        }
    }

    /// The initial values `expr` reads (through lets), in statement order.
    fn initial_read<'i>(&self, expr: &Expr, initial: &'i [Initial], read: &mut Vec<&'i Initial>) {
        let mut names = Vec::new();
        collect_names(expr, &mut names);
        for i in initial {
            let name = &self.coords[i.coord].name;
            let used = names
                .iter()
                .any(|&(n, primes)| n == name.as_str() && primes == i.order);
            if used && !read.iter().any(|r| std::ptr::eq(*r, i)) {
                read.push(i);
            }
        }
    }
}

/// Every name `expr` uses, with its primes.
fn collect_names<'e>(expr: &'e Expr, out: &mut Vec<(&'e str, u32)>) {
    match &expr.kind {
        ExprKind::Number(_) => {}
        ExprKind::Var { name, primes } => out.push((name.name.as_str(), *primes)),
        ExprKind::Neg(e) | ExprKind::Not(e) => collect_names(e, out),
        ExprKind::Component { base, .. } => collect_names(base, out),
        ExprKind::Binary { lhs, rhs, .. }
        | ExprKind::Compare { lhs, rhs, .. }
        | ExprKind::Logic { lhs, rhs, .. } => {
            collect_names(lhs, out);
            collect_names(rhs, out);
        }
        ExprKind::Call { args, .. } | ExprKind::Vector(args) => {
            args.iter().for_each(|a| collect_names(a, out))
        }
        ExprKind::If {
            cond,
            then,
            otherwise,
        } => {
            collect_names(cond, out);
            collect_names(then, out);
            collect_names(otherwise, out);
        }
    }
}
