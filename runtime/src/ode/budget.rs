//! One work budget for a whole run: every attempted step of every
//! integrator (direct steps, the field's coefficient steps, its windows and
//! their predictors) draws on it, so no method and no window loop can run
//! without bound.

use crate::failure::{Failure, FailureKind};
use std::cell::Cell;

/// The default budget: a million steps. Millions of steps each within the
/// tolerance can add up to a global error far above it (RODAS4 on the
/// mass-loss spring once took 10.5 million steps to an error of 2e-4), and
/// a run that needs more is better stopped with a clear message.
pub const DEFAULT_MAX_STEPS: usize = 1_000_000;

/// The budget's second half advanced the run by less than this fraction
/// of what its first half did: the steps stalled.
const STALL_RATIO: f64 = 1e-2;

#[derive(Debug)]
pub struct Budget {
    limit: usize,
    used: Cell<usize>,
    /// Where the run starts, how far its solution has been accepted
    /// ([`Budget::accepted_to`]: the driver's steps, the field's windows —
    /// not the predictor that runs ahead of them), and how far that was
    /// halfway through the budget.
    start: Cell<f64>,
    accepted: Cell<f64>,
    halfway: Cell<f64>,
}

impl Budget {
    pub fn new(limit: usize) -> Budget {
        Budget {
            limit,
            used: Cell::new(0),
            start: Cell::new(f64::NAN),
            accepted: Cell::new(f64::NAN),
            halfway: Cell::new(f64::NAN),
        }
    }

    /// Draws one step at time `t`; `Err` once the budget is spent (the
    /// driver reports it where the solution stands).
    pub fn draw(&self, t: f64) -> Result<(), Failure> {
        let used = self.used.get();
        if used >= self.limit {
            return Err(Failure::new(
                t,
                FailureKind::StepBudgetExhausted {
                    steps: used,
                    stalled: self.stalled(),
                },
            ));
        }
        if used == self.limit / 2 {
            self.halfway.set(self.accepted.get());
        }
        self.used.set(used + 1);
        Ok(())
    }

    /// The run's solution is accepted up to `t` (the first call: where it
    /// starts).
    pub fn accepted_to(&self, t: f64) {
        if self.start.get().is_nan() {
            self.start.set(t);
        }
        self.accepted.set(t);
    }

    /// Where the steps stalled, when the budget runs out: `(from, to)`, how
    /// far the run had been accepted halfway through the budget and now,
    /// if the second half of the steps moved it by less than
    /// [`STALL_RATIO`] of what the first half did (or neither half moved
    /// it at all) — a motion that chatters at a point where it is not
    /// smooth (a rate that switches with the sign of a velocity that
    /// reaches zero) or that runs into a singularity, rather than one that
    /// merely needs many steps.
    fn stalled(&self) -> Option<(f64, f64)> {
        let (start, halfway, now) = (self.start.get(), self.halfway.get(), self.accepted.get());
        let before = (halfway - start).abs();
        let after = (now - halfway).abs();
        let stalled = if before > 0.0 {
            after <= STALL_RATIO * before
        } else {
            after == 0.0
        };
        stalled.then_some((halfway, now))
    }

    pub fn used(&self) -> usize {
        self.used.get()
    }

    pub fn limit(&self) -> usize {
        self.limit
    }
}

impl Default for Budget {
    fn default() -> Budget {
        Budget::new(DEFAULT_MAX_STEPS)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Draws until the budget is spent, the run accepted to `accepted(i)`
    /// before draw `i`.
    fn exhaust(budget: &Budget, accepted: impl Fn(usize) -> f64) -> FailureKind {
        let mut i = 0;
        loop {
            budget.accepted_to(accepted(i));
            if let Err(failure) = budget.draw(accepted(i)) {
                return failure.kind;
            }
            i += 1;
        }
    }

    #[test]
    fn steps_that_stall_are_told_from_steps_that_are_merely_many() {
        // Even progress: many steps, not a stall.
        let kind = exhaust(&Budget::new(1000), |i| i as f64 * 1e-3);
        assert_eq!(
            kind,
            FailureKind::StepBudgetExhausted {
                steps: 1000,
                stalled: None
            }
        );
        // Steps that shrink geometrically toward t = 1 (a singularity or
        // chattering): the second half hardly moves.
        let kind = exhaust(&Budget::new(1000), |i| 1.0 - 0.9_f64.powi(i as i32));
        match kind {
            FailureKind::StepBudgetExhausted {
                steps: 1000,
                stalled: Some((from, to)),
            } => assert!((from - 1.0).abs() < 1e-10 && to >= from, "{from} {to}"),
            other => panic!("{other:?}"),
        }
        // Nothing accepted at all (a field window that never completes,
        // its predictor running ahead): stalled where it started.
        let kind = exhaust(&Budget::new(1000), |_| 0.0);
        assert!(matches!(
            kind,
            FailureKind::StepBudgetExhausted {
                stalled: Some((0.0, 0.0)),
                ..
            }
        ));
        // Never told what was accepted: no verdict.
        let budget = Budget::new(10);
        let kind = loop {
            if let Err(failure) = budget.draw(1.0) {
                break failure.kind;
            }
        };
        assert!(matches!(
            kind,
            FailureKind::StepBudgetExhausted { stalled: None, .. }
        ));
    }
}
