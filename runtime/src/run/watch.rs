//! The constraints as written, watched along a run (issue 28), so that a
//! run stops naming the constraint where it stops being defined, in every
//! method:
//!
//! - after every accepted step, the arguments of the square roots,
//!   logarithms, arcsines and arccosines in the constraints
//!   ([`Model::DOMAINS`](crate::model::Model::DOMAINS)): one that reaches
//!   0 (to rounding) ends the constraint's branch, and the run stops
//!   there, located within the step. The reduced system need not see it:
//!   `y' = sqrt(c^2 - x'^2)` in gravity reduces to `y'' = −g x'^2/c^2`, so
//!   direct integration ran on past the apex with exit 0, y' = −2 where
//!   the constraint demands 0;
//! - at a failure the methods met (a singular mass matrix or condition
//!   matrix, a non-finite rate, a step that underflows, …), the constraints
//!   at the state where it happened: an end of a domain near 0, a pole, or
//!   the pivots of an implicit constraint fallen to a millionth of their
//!   size at the start make the constraint the failure's name and cause.

use crate::failure::{Failure, FailureKind};
use crate::method::solver::Solver;
use crate::model::{DomainKind, DynModel};

/// An end within this fraction of its argument's scale is reached: the
/// rounding of the argument's terms.
const ROUNDING: f64 = 8.0 * f64::EPSILON;
/// At a failure, a pole within this fraction of its scale, or pivots below
/// this fraction of theirs at the start, name the constraint as its cause.
const NEAR: f64 = 1e-6;
/// At a failure, the argument of a root, logarithm or arcsine within this
/// fraction of its scale names the constraint (the root itself within a
/// hundredth of its scale's: its derivative a hundred times its size).
const NEAR_END: f64 = 1e-4;

/// The constraints' state at the start of a run.
#[derive(Clone, Debug, Default)]
pub struct ConstraintWatch {
    /// Each implicit constraint's largest pivot at the start.
    pivots: Vec<f64>,
}

impl ConstraintWatch {
    /// The watch of a run from `(t0, x0)`: fails where a constraint's
    /// branch has ended already.
    pub fn start(model: &dyn DynModel, t0: f64, x0: &[f64]) -> Result<Self, Failure> {
        if let Some(failure) = ended(model, t0, x0, ROUNDING) {
            return Err(failure);
        }
        let pivots = pivots(model, t0, x0)
            .into_iter()
            .map(|(_, largest)| largest)
            .collect();
        Ok(ConstraintWatch { pivots })
    }

    /// After an accepted step `[ta, tb]`: the failure where a constraint's
    /// branch ended within it (the first time the solver's dense output
    /// shows it, to rounding of the time), if one did.
    // Inlined, the test for a model without domains (most): a call a step
    // saved (BENCHMARKS §10r).
    #[inline]
    pub fn step(
        &self,
        model: &dyn DynModel,
        solver: &mut dyn Solver,
        ta: f64,
        tb: f64,
    ) -> Result<Option<Failure>, Failure> {
        if model.domains().is_empty() {
            return Ok(None);
        }
        Self::step_in_domains(model, solver, ta, tb)
    }

    #[inline(never)]
    fn step_in_domains(
        model: &dyn DynModel,
        solver: &mut dyn Solver,
        ta: f64,
        tb: f64,
    ) -> Result<Option<Failure>, Failure> {
        let mut x = solver.state().to_vec();
        if tb != solver.time() {
            solver.dense(model, tb, &mut x)?;
        }
        let Some(mut failure) = ended(model, tb, &x, ROUNDING) else {
            return Ok(None);
        };
        // Bisection for the first time it shows: ended at `hi`, not at `lo`.
        let (mut lo, mut hi) = (ta, tb);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if !(mid > lo && mid < hi) {
                break;
            }
            solver.dense(model, mid, &mut x)?;
            match ended(model, mid, &x, ROUNDING) {
                Some(found) => {
                    failure = found;
                    hi = mid;
                }
                None => lo = mid,
            }
        }
        Ok(Some(failure))
    }

    /// `failure`, renamed after the constraint that caused it, when the
    /// state where it happened is at an end of a constraint's domain, at a
    /// pole of it, or where its pivots have vanished. `x` is the solution
    /// at `t_x`, its last accepted time; where the failure happened later
    /// (inside a field window), its linear extrapolation to the failure's
    /// time is looked at too.
    pub fn diagnose(&self, model: &dyn DynModel, failure: Failure, t_x: f64, x: &[f64]) -> Failure {
        let numerical = matches!(
            failure.kind,
            FailureKind::SingularMassMatrix { .. }
                | FailureKind::NonFiniteState { .. }
                | FailureKind::NonFiniteRate { .. }
                | FailureKind::StepSizeUnderflow { .. }
                | FailureKind::SingularConditionMatrix { .. }
                | FailureKind::ConditionMatrixCrossedSingularity { .. }
                | FailureKind::FieldNotConverging { .. }
                | FailureKind::NewtonNonConvergence { .. }
                | FailureKind::ConstraintLeft { .. }
                | FailureKind::ConstraintUndefined { .. }
        );
        if !numerical || !x.iter().all(|v| v.is_finite()) {
            return failure;
        }
        let t = failure.time;
        let mut states = vec![x.to_vec()];
        if t != t_x {
            let mut rate = vec![0.0; x.len()];
            if model.rhs(t_x, x, &mut rate).is_ok() {
                let ahead: Vec<f64> = x
                    .iter()
                    .zip(&rate)
                    .map(|(v, r)| v + (t - t_x) * r)
                    .collect();
                if ahead.iter().all(|v| v.is_finite()) {
                    states.insert(0, ahead);
                }
            }
        }
        for x in &states {
            if let Some(named) = ended(model, t, x, NEAR_END) {
                return named;
            }
            for ((text, largest), &start) in pivots(model, t, x).into_iter().zip(&self.pivots) {
                if !(largest > NEAR * start) {
                    return Failure::new(
                        t,
                        FailureKind::ConstraintPivotVanishes {
                            constraint: text.to_string(),
                            pivot: largest,
                        },
                    );
                }
            }
        }
        failure
    }
}

/// The first domain of a constraint that has ended at `(t, x)`: a root's,
/// logarithm's or arcsine's argument at most `near` of its scale (or not a
/// number), a fractional power's below `−near` of it; with `near` above
/// rounding (a failure's diagnosis), also a pole within [`NEAR`].
fn ended(model: &dyn DynModel, t: f64, x: &[f64], near: f64) -> Option<Failure> {
    let domains = model.domains();
    if domains.is_empty() {
        return None;
    }
    let mut values = vec![0.0; 2 * domains.len()];
    model.domain_values(t, x, &mut values);
    for (d, pair) in domains.iter().zip(values.chunks(2)) {
        let (value, scale) = (pair[0], pair[1].abs());
        let bound = near * scale;
        let out = match d.kind {
            DomainKind::Root
            | DomainKind::Logarithm
            | DomainKind::Arcsine
            | DomainKind::Arccosine => !(value > bound),
            DomainKind::Power => !(value >= -bound),
            DomainKind::Pole => near > ROUNDING && !(value.abs() > NEAR * scale),
        };
        if out {
            return Some(Failure::new(
                t,
                FailureKind::ConstraintDomainEnds {
                    constraint: d.constraint.to_string(),
                    kind: d.kind,
                    argument: d.argument.to_string(),
                    value,
                },
            ));
        }
    }
    None
}

/// Each implicit constraint's text and its candidates' largest pivot
/// magnitude at `(t, x)`.
fn pivots(model: &dyn DynModel, t: f64, x: &[f64]) -> Vec<(&'static str, f64)> {
    let constraints = model.constraints();
    if constraints.is_empty() {
        return Vec::new();
    }
    let total: usize = constraints.iter().map(|c| c.names.len()).sum();
    let mut values = vec![0.0; total];
    model.pivots(t, x, &mut values);
    let mut at = 0;
    constraints
        .iter()
        .map(|c| {
            let slice = &values[at..at + c.names.len()];
            at += c.names.len();
            let largest = slice.iter().fold(0.0_f64, |m, p| m.max(p.abs()));
            let largest = if slice.iter().any(|p| p.is_nan()) {
                f64::NAN
            } else {
                largest
            };
            (c.text, largest)
        })
        .collect()
}
