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

/// The budget's second half advanced the time by less than this fraction
/// of what its first half did: the steps stalled.
const STALL_RATIO: f64 = 1e-2;

#[derive(Debug)]
pub struct Budget {
    limit: usize,
    used: Cell<usize>,
    /// The time of the first draw, the furthest time any draw has reached
    /// (the field's predictor runs ahead of its windows, and a window that
    /// is tried again starts over), and how far that was halfway through
    /// the budget.
    first: Cell<f64>,
    reached: Cell<f64>,
    halfway: Cell<f64>,
}

impl Budget {
    pub fn new(limit: usize) -> Budget {
        Budget {
            limit,
            used: Cell::new(0),
            first: Cell::new(f64::NAN),
            reached: Cell::new(f64::NAN),
            halfway: Cell::new(f64::NAN),
        }
    }

    /// Draws one step at time `t`; `Err` once the budget is spent.
    pub fn draw(&self, t: f64) -> Result<(), Failure> {
        let used = self.used.get();
        if used >= self.limit {
            return Err(Failure::new(
                t,
                FailureKind::StepBudgetExhausted {
                    steps: used,
                    stalled_since: self.stalled_since(),
                },
            ));
        }
        if used == 0 {
            self.first.set(t);
            self.reached.set(t);
        }
        // Spans run forward: the furthest time is the largest.
        self.reached.set(self.reached.get().max(t));
        if used == self.limit / 2 {
            self.halfway.set(self.reached.get());
        }
        self.used.set(used + 1);
        Ok(())
    }

    /// Where the steps stalled, when the budget runs out: the furthest time
    /// reached halfway through it, if the second half of the steps moved
    /// that by less than [`STALL_RATIO`] of what the first half did — a motion
    /// that chatters at a point where it is not smooth (a rate that
    /// switches with the sign of a velocity that reaches zero) or that
    /// runs into a singularity, rather than one that merely needs many
    /// steps.
    fn stalled_since(&self) -> Option<f64> {
        let (first, halfway) = (self.first.get(), self.halfway.get());
        let before = halfway - first;
        let after = self.reached.get() - halfway;
        (before > 0.0 && after <= STALL_RATIO * before).then_some(halfway)
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

    fn exhaust(budget: &Budget, time_of_draw: impl Fn(usize) -> f64) -> FailureKind {
        let mut i = 0;
        loop {
            if let Err(failure) = budget.draw(time_of_draw(i)) {
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
                stalled_since: None
            }
        );
        // Steps that shrink geometrically toward t = 1 (a singularity or
        // chattering): the second half hardly moves.
        let kind = exhaust(&Budget::new(1000), |i| 1.0 - 0.9_f64.powi(i as i32));
        match kind {
            FailureKind::StepBudgetExhausted {
                steps: 1000,
                stalled_since: Some(since),
            } => assert!((since - 1.0).abs() < 1e-10, "{since}"),
            other => panic!("{other:?}"),
        }
        // A predictor that ran ahead to t = 1 and windows that keep
        // starting over from 0 behind it: the furthest time stalls.
        let kind = exhaust(&Budget::new(1000), |i| {
            if i < 400 {
                i as f64 / 400.0
            } else {
                (i % 7) as f64 / 7.0
            }
        });
        assert!(matches!(
            kind,
            FailureKind::StepBudgetExhausted {
                stalled_since: Some(_),
                ..
            }
        ));
    }
}
