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

#[derive(Debug)]
pub struct Budget {
    limit: usize,
    used: Cell<usize>,
}

impl Budget {
    pub fn new(limit: usize) -> Budget {
        Budget {
            limit,
            used: Cell::new(0),
        }
    }

    /// Draws one step at time `t`; `Err` once the budget is spent.
    pub fn draw(&self, t: f64) -> Result<(), Failure> {
        let used = self.used.get();
        if used >= self.limit {
            return Err(Failure::new(
                t,
                FailureKind::StepBudgetExhausted { steps: used },
            ));
        }
        self.used.set(used + 1);
        Ok(())
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
