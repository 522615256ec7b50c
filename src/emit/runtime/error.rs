//! Run-time failures of a generated crate: each stops the run with a message
//! naming the time and the quantity, and the binary exits with status 3.

use std::fmt;

/// Exit status of a generated binary that stopped on a [`Failure`].
pub const FAILURE_EXIT_STATUS: i32 = 3;

/// A numerical failure at time `time`: nothing after it can be trusted.
#[derive(Clone, Debug, PartialEq)]
pub struct Failure {
    pub time: f64,
    pub kind: FailureKind,
}

#[derive(Clone, Debug, PartialEq)]
pub enum FailureKind {
    /// The mass matrix `A(t, x)` of the highest derivatives could not be
    /// factorised; `condition` is its estimated condition number
    /// (infinite when exactly singular).
    SingularMassMatrix { condition: f64 },
    /// A state component (or a value derived from it) is NaN or infinite.
    /// `component` names it (e.g. `q1'`, `f_3`, `S_2_1`).
    NonFiniteState { component: String },
    /// The step size fell below `16·eps·|t|`: the solution cannot be
    /// followed further at the requested tolerance.
    StepSizeUnderflow { step: f64 },
    /// The conditions (13) of the field method are singular: the matrix
    /// `∂²Φ̄/∂c_A∂x_B` has condition number `condition` and re-anchoring
    /// could not restore it.
    SingularConditionMatrix { condition: f64 },
    /// The determinant of the field's condition matrix changed sign between
    /// the accepted steps at `since` and at `time`: the matrix passed
    /// through singularity in between, where no step looked (the field
    /// cannot tell the state there) and re-anchoring was off.
    ConditionMatrixCrossedSingularity { since: f64 },
    /// The integration took `steps` steps (the budget) before reaching the
    /// end: the local errors of so many steps may add up beyond the
    /// tolerance.
    StepBudgetExhausted { steps: usize },
    /// Newton's method for non-linear highest derivatives did not converge;
    /// `residual` is the last residual norm after `iterations` iterations.
    NewtonNonConvergence { residual: f64, iterations: usize },
}

impl Failure {
    pub fn new(time: f64, kind: FailureKind) -> Self {
        Failure { time, kind }
    }

    pub fn non_finite(time: f64, component: impl Into<String>) -> Self {
        Failure::new(
            time,
            FailureKind::NonFiniteState {
                component: component.into(),
            },
        )
    }
}

impl fmt::Display for Failure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let t = self.time;
        match &self.kind {
            FailureKind::SingularMassMatrix { condition } => write!(
                f,
                "at t = {t:e}: the mass matrix is singular (condition number {condition:e})"
            ),
            FailureKind::NonFiniteState { component } => {
                write!(
                    f,
                    "at t = {t:e}: `{component}` is not finite (NaN or infinite)"
                )
            }
            FailureKind::StepSizeUnderflow { step } => write!(
                f,
                "at t = {t:e}: the step size {step:e} underflows (below 16·eps·|t|); \
                 the solution may blow up here"
            ),
            FailureKind::SingularConditionMatrix { condition } => write!(
                f,
                "at t = {t:e}: the field's condition matrix is singular \
                 (condition number {condition:e}) and re-anchoring did not help"
            ),
            FailureKind::ConditionMatrixCrossedSingularity { since } => write!(
                f,
                "at t = {t:e}: the field's condition matrix passed through singularity \
                 after t = {since:e} (its determinant changed sign) and re-anchoring was off"
            ),
            FailureKind::StepBudgetExhausted { steps } => write!(
                f,
                "at t = {t:e}: the step budget is exhausted ({steps} steps): the local errors \
                 of so many steps may add up beyond the tolerance; try another integrator \
                 (--integrator) or a looser tolerance"
            ),
            FailureKind::NewtonNonConvergence {
                residual,
                iterations,
            } => write!(
                f,
                "at t = {t:e}: Newton's method did not converge for the highest \
                 derivatives (residual {residual:e} after {iterations} iterations)"
            ),
        }
    }
}

impl std::error::Error for Failure {}
