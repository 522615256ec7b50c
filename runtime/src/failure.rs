//! Run-time failures: each stops the run with a message naming the time and
//! the physical quantity (never an internal symbol of a method), and the
//! binary exits with status 3 (2 for a bad initial value, which is the
//! user's input rather than the numerics).

use std::fmt;

/// Exit status of a run that stopped on a numerical [`Failure`].
pub const FAILURE_EXIT_STATUS: u8 = 3;
/// Exit status of bad command-line usage (including overrides that make
/// the model inconsistent).
pub const USAGE_EXIT_STATUS: u8 = 2;

/// A failure at time `time`: nothing after it can be trusted.
#[derive(Clone, Debug, PartialEq)]
pub struct Failure {
    pub time: f64,
    pub kind: FailureKind,
}

#[derive(Clone, Debug, PartialEq)]
pub enum FailureKind {
    /// The mass matrix of the highest derivatives is singular (or nearly:
    /// `condition` is its condition number, infinite when exactly singular).
    SingularMassMatrix { condition: f64 },
    /// Mass law `mass` reached zero (or below): the equations of motion
    /// divide by it.
    MassVanishes { mass: String, value: f64 },
    /// A state component became NaN or infinite: the motion blows up.
    NonFiniteState { component: String },
    /// The equations of motion give a non-finite value for `component`
    /// (a rate such as `q1''`) at a finite state: a force, the Lagrangian
    /// or a mass law is not defined there.
    NonFiniteRate { component: String },
    /// The step size fell below `16·eps·|t|`.
    StepSizeUnderflow { step: f64 },
    /// The field's conditions (13) are singular and re-anchoring could not
    /// restore them.
    SingularConditionMatrix { condition: f64 },
    /// The field's condition matrix passed through singularity (its
    /// determinant changed sign) after `since`, with re-anchoring off.
    ConditionMatrixCrossedSingularity { since: f64 },
    /// The run used its whole work budget (`steps` steps of every kind).
    StepBudgetExhausted {
        steps: usize,
        /// How far the run's solution had been accepted with half the
        /// budget left, and at its end, when the steps since hardly moved
        /// it.
        stalled: Option<(f64, f64)>,
    },
    /// Newton's method for the highest derivatives did not converge.
    NewtonNonConvergence { residual: f64, iterations: usize },
    /// The field method's quasilinearisation did not converge on a window
    /// even at the shortest window length.
    FieldNotConverging { correction: f64 },
    /// The pivot `∂h/∂dep` of an implicit constraint vanished and no other
    /// candidate is better.
    ConstraintPivotVanishes { constraint: String, pivot: f64 },
    /// Newton found no positions on the holonomic constraints near the
    /// integrated ones: the motion has left them (or reached a point where
    /// their Jacobian in the dependent coordinates is singular).
    PositionsLeftConstraint {
        constraint: String,
        residual: f64,
        singular: bool,
    },
    /// A group of constraints solved together reached a singular
    /// configuration: every choice of dependents vanishes (their Jacobian
    /// lost rank; `ratio`: the pivots' volume against the run's start).
    SingularConfiguration { constraint: String, ratio: f64 },
    /// The constraint that fixes `component` has no finite value at the
    /// state reached: its branch ends there (the root of a negative
    /// number, a division by zero).
    ConstraintUndefined { component: String },
    /// Within one accepted step the state left the constraint that fixes
    /// `component` by `residual`, far beyond any drift the tolerance lets
    /// a step carry.
    ConstraintLeft { component: String, residual: f64 },
    /// A position constraint changes branch at a switch with a kink (`abs`,
    /// `if`): `component`, which it fixes (its velocity, or the position
    /// itself where the branch jumps), would jump from `before` to `after`,
    /// an impulse the model does not say how to take.
    ConstraintKink {
        component: String,
        constraint: String,
        before: f64,
        after: f64,
    },
    /// A constraint as written reaches an end of its domain: the argument
    /// of a square root, logarithm, arcsine or arccosine reaches 0 (its
    /// branch ends) or passes it (not defined), or a failure happened at
    /// a pole of it (`argument`, what it divides by, vanishes).
    ConstraintDomainEnds {
        constraint: String,
        kind: crate::domain::DomainKind,
        argument: String,
        value: f64,
    },
    /// At the initial state a constraint hardly determines its first
    /// candidate, the one the initial values take as fixed (its pivot a
    /// vanishing fraction of another's): that value is not determined.
    InitialCandidateVanishes {
        constraint: String,
        candidate: String,
        better: String,
        ratio: f64,
    },
    /// Newton found no initial positions on the holonomic constraints
    /// near the given ones (`singular`: their Jacobian in the dependent
    /// coordinates is singular there).
    InitialPositionsOffConstraint {
        constraint: String,
        residual: f64,
        singular: bool,
    },
    /// A stated initial value of a dependent component disagrees with the
    /// value the constraints require.
    InconsistentInitialValue {
        component: String,
        stated: f64,
        required: f64,
    },
    /// The time span is empty, reversed or not finite (after overrides).
    BadTimeSpan { t0: f64, t1: f64 },
    /// An initial value is not finite (after overrides).
    NonFiniteInitialValue { component: String },
    /// The condition of a `when` holds at the start, not only within
    /// rounding of its boundary: the state starts inside the region the
    /// impact forbids (`values`: the components it reads, `y = -0.1`).
    ImpactHoldsAtStart { condition: String, values: String },
    /// An impact resets `component`, which every mode whose pivots are
    /// good at the impact fixes through `constraint`: the reset would
    /// contradict the constraint (or the mode that leaves it free hardly
    /// determines the others).
    ResetOfFixedComponent {
        condition: String,
        component: String,
        constraint: String,
    },
    /// The anchor makes `x_1 = f_1 + Σ f_A x_A` the difference of huge
    /// numbers: `digits` more digits would be lost than the tolerance allows.
    /// From the zero anchor (the default) the coefficients are as small as
    /// they can be, and the cause is a tolerance below f64's rounding.
    AnchorCancels { digits: f64, at_zero_anchor: bool },
    /// The field method proper was asked of a model that is not affine.
    NotAffine,
    /// An `Integration` was asked to advance to a
    /// time before where it stands or past the end of its span.
    OutsideSpan { from: f64, to: f64 },
    /// A request the runtime does not compute for this model (e.g.
    /// sensitivities through events), in words.
    Unsupported { message: String },
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

    pub fn non_finite_rate(time: f64, component: impl Into<String>) -> Self {
        Failure::new(
            time,
            FailureKind::NonFiniteRate {
                component: component.into(),
            },
        )
    }

    pub fn not_affine(time: f64) -> Self {
        Failure::new(time, FailureKind::NotAffine)
    }

    /// The exit status of a run that stopped on this failure.
    pub fn exit_status(&self) -> u8 {
        match self.kind {
            FailureKind::InconsistentInitialValue { .. }
            | FailureKind::InitialPositionsOffConstraint { .. }
            | FailureKind::InitialCandidateVanishes { .. }
            | FailureKind::BadTimeSpan { .. }
            | FailureKind::NonFiniteInitialValue { .. }
            | FailureKind::ImpactHoldsAtStart { .. }
            | FailureKind::OutsideSpan { .. }
            | FailureKind::AnchorCancels { .. } => USAGE_EXIT_STATUS,
            _ => FAILURE_EXIT_STATUS,
        }
    }
}

impl fmt::Display for Failure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let t = self.time;
        match &self.kind {
            FailureKind::SingularMassMatrix { condition } => write!(
                f,
                "at t = {t:e}: the mass matrix of the highest derivatives is singular \
                 (condition number {condition:.3e}): the equations of motion do not \
                 determine the accelerations here: the coordinates may be singular here \
                 (Euler angles with two rotation axes aligned, a polar angle at its pole) \
                 or an inertia vanishes; start away from there, or choose coordinates \
                 regular along the motion"
            ),
            FailureKind::MassVanishes { mass, value } => write!(
                f,
                "at t = {t:e}: the mass `{mass}` reaches zero ({mass} = {value:.3e}); \
                 the motion is not defined past it (shorten the time span or change \
                 the mass law)"
            ),
            FailureKind::NonFiniteState { component } => write!(
                f,
                "at t = {t:e}: `{component}` is not finite: the motion blows up here"
            ),
            FailureKind::NonFiniteRate { component } => write!(
                f,
                "at t = {t:e}: the equations of motion give a non-finite `{component}` at \
                 a finite state: a force, the Lagrangian or a mass law is not defined here"
            ),
            FailureKind::StepSizeUnderflow { step } => write!(
                f,
                "at t = {t:e}: the step size {step:.3e} underflows (below 16·eps·|t|): \
                 the motion cannot be followed further at this tolerance; it may blow \
                 up or be singular here"
            ),
            FailureKind::SingularConditionMatrix { condition } => write!(
                f,
                "at t = {t:e}: the field's conditions (13) are singular (condition \
                 number {condition:.3e}): they no longer determine the motion here \
                 (re-anchoring, when on, did not restore them)"
            ),
            FailureKind::ConditionMatrixCrossedSingularity { since } => write!(
                f,
                "at t = {t:e}: the field's condition matrix passed through singularity \
                 after t = {since:e} (its determinant changed sign) and re-anchoring \
                 was off"
            ),
            FailureKind::StepBudgetExhausted {
                steps,
                stalled: Some((from, to)),
            } => write!(
                f,
                "at t = {t:e}: the work budget is exhausted ({steps} steps), and its \
                 second half moved the solution only from t = {from:e} to {to:e}: the \
                 steps stall there. The motion may reach a point where its rates are not smooth \
                 (a force or constraint with |v| or sign(v) at a velocity that \
                 reaches zero, switching without end) or a singularity; a looser \
                 tolerance or a larger budget will likely not get past it"
            ),
            FailureKind::StepBudgetExhausted {
                steps,
                stalled: None,
            } => write!(
                f,
                "at t = {t:e}: the work budget is exhausted ({steps} steps): the local \
                 errors of so many steps may add up beyond the tolerance; try another \
                 integrator (--integrator), a looser tolerance, or raise the budget \
                 (--max-steps)"
            ),
            FailureKind::NewtonNonConvergence {
                residual,
                iterations,
            } => write!(
                f,
                "at t = {t:e}: Newton's method found no highest derivatives satisfying \
                 the equations of motion (residual {residual:.3e} after {iterations} \
                 iterations)"
            ),
            FailureKind::FieldNotConverging { correction } => write!(
                f,
                "at t = {t:e}: the field method's linearisation along the motion does \
                 not converge even on the shortest window (Newton's error bound above \
                 {correction:.1e} of the tolerance on every first step). The motion may \
                 not be smooth here (a force or constraint with |v| or sign(v) at a \
                 velocity that reaches zero, switching without end) or may reach a \
                 singularity"
            ),
            FailureKind::ConstraintPivotVanishes { constraint, pivot } => write!(
                f,
                "at t = {t:e}: the constraint `{constraint}` no longer determines its \
                 dependent derivative (pivot {pivot:.3e}); name another candidate with \
                 `for … or …`"
            ),
            FailureKind::PositionsLeftConstraint {
                constraint,
                residual,
                singular,
            } => write!(
                f,
                "at t = {t:e}: the positions cannot be brought back onto the constraint \
                 `{constraint}` ({}, residual {residual:.3e}): the motion has left it",
                if *singular {
                    "its Jacobian in the dependent coordinates is singular there"
                } else {
                    "Newton does not converge"
                }
            ),
            FailureKind::SingularConfiguration { constraint, ratio } => write!(
                f,
                "at t = {t:e}: the constraints `{constraint}` reach a singular \
                 configuration: no choice of dependent coordinates determines them \
                 (their Jacobian loses rank; the pivots' volume is {ratio:.1e} of its \
                 value at the start). The motion cannot be followed through it: a \
                 change point of a linkage, where branches of motion meet"
            ),
            FailureKind::ConstraintUndefined { component } => write!(
                f,
                "at t = {t:e}: the constraint that fixes `{component}` has no finite value \
                 here: its branch ends (a root of a negative number, or a division by \
                 zero); the motion past this point is not on it. Write the constraint \
                 implicitly (`… for {component} or …`) to let it pass onto another \
                 branch, or end the time span before"
            ),
            FailureKind::ConstraintLeft {
                component,
                residual,
            } => write!(
                f,
                "at t = {t:e}: the motion left the constraint that fixes `{component}` \
                 (its residual {residual:.3e} in one step, far beyond the tolerance): the \
                 constraint's branch ends here or the motion passes a singular point of \
                 it. An explicit root (`y' = sqrt(…)`) holds one branch only: write the \
                 constraint implicitly (`… for {component} or …`) to pass onto the other"
            ),
            FailureKind::ConstraintKink {
                component,
                constraint,
                before,
                after,
            } => write!(
                f,
                "at t = {t:e}: `{constraint}` changes branch with a kink here: `{component}`, \
                 which it fixes, would jump from {before:.6e} to {after:.6e}, an impulse \
                 the model does not say how to take (which velocities change, and whether \
                 energy is lost); write the impact as a `when` with its resets, or a \
                 constraint without the kink"
            ),
            FailureKind::ConstraintDomainEnds {
                constraint,
                kind,
                argument,
                value,
            } => domain_end(f, t, constraint, *kind, argument, *value),
            FailureKind::InitialCandidateVanishes {
                constraint,
                candidate,
                better,
                ratio,
            } => {
                // A holonomic constraint's candidates are coordinates: the
                // value to give instead is the velocity its position's
                // Newton start does not fix.
                let given = if candidate.ends_with('\'') {
                    candidate.clone()
                } else {
                    format!("{candidate}'")
                };
                write!(
                    f,
                    "at t = {t:e}: the initial state hardly determines `{candidate}` through \
                     the constraint `{constraint}` (its pivot is {ratio:.1e} of `{better}`'s), \
                     and the initial values take `{candidate}`, its first candidate, as the \
                     one it fixes. Start where `{candidate}` is determined, or name `{better}` \
                     first in the model (`for {better} or {candidate}`) and give `{given}`"
                )
            }
            FailureKind::InitialPositionsOffConstraint {
                constraint,
                residual,
                singular,
            } => write!(
                f,
                "at t = {t:e}: Newton finds no initial positions on the constraint \
                 `{constraint}` near the given ones ({}, residual {residual:.3e}); give \
                 the dependent coordinates closer to a configuration that satisfies it",
                if *singular {
                    "its Jacobian in the dependent coordinates is singular there"
                } else {
                    "no convergence"
                }
            ),
            // A required value that is not a number: the kept value is
            // Newton's `v − f/f_v` of a constraint kept as written, and
            // `f_v` vanishes at the start (`x'^2 + y'^2 = 1 for y'` with
            // `y' = 0`): the start sits where the constraint's branches
            // meet, and "which require y' = NaN" said nothing of that.
            FailureKind::InconsistentInitialValue {
                component,
                stated,
                required,
            } if !required.is_finite() => write!(
                f,
                "at t = {t:e}: the constraints do not determine `{component}` at the start \
                 (`{component} = {stated}`): the constraint that fixes it does not vary \
                 with it there (its derivative in `{component}` vanishes: the end of a \
                 branch, where two roots meet); start the motion off that point, or let \
                 the constraint fix another candidate"
            ),
            FailureKind::InconsistentInitialValue {
                component,
                stated,
                required,
            } => write!(
                f,
                "at t = {t:e}: the initial value `{component} = {stated}` violates the \
                 constraints, which require {component} = {required}"
            ),
            FailureKind::BadTimeSpan { t0, t1 } => write!(
                f,
                "the time span {t0} .. {t1} is empty, reversed or not finite"
            ),
            FailureKind::NonFiniteInitialValue { component } => {
                write!(f, "the initial value of `{component}` is not finite")
            }
            FailureKind::ImpactHoldsAtStart { condition, values } => write!(
                f,
                "at t = {t:e}: the condition of `when {condition}` already holds at the start \
                 ({values}): the motion starts inside the region the impact forbids, where \
                 no impact fires (one fires only where the motion enters it); give initial \
                 values on its other side"
            ),
            FailureKind::ResetOfFixedComponent {
                condition,
                component,
                constraint,
            } => write!(
                f,
                "at t = {t:e}: `when {condition}` resets `{component}`, which the constraint \
                 `{constraint}` fixes here: every choice of its dependent that leaves \
                 `{component}` free has a poor pivot at this state, so the reset would \
                 contradict the constraint (or leave the other components undetermined); \
                 reset a component the constraint leaves free here"
            ),
            FailureKind::AnchorCancels {
                at_zero_anchor: true,
                ..
            } => write!(
                f,
                "at t = {t:e}: the field's recovery `x1 = f1 + Σ fA·xA` rounds past the \
                 tolerance even from the zero anchor: the tolerance is below what f64 \
                 keeps there (the field reaches about rtol 1e-14); loosen --rtol, or use \
                 --method direct"
            ),
            FailureKind::AnchorCancels { digits, .. } => write!(
                f,
                "at t = {t:e}: this anchor makes the field recover `x1 = f1 + Σ fA·xA` as \
                 the difference of huge numbers, losing {digits:.1} more digits than the \
                 tolerance allows; use a smaller --anchor (the default 0 is best)"
            ),
            FailureKind::NotAffine => write!(
                f,
                "at t = {t:e}: the field method proper needs an affine system (internal)"
            ),
            FailureKind::OutsideSpan { from, to } => write!(
                f,
                "t = {t} is outside what the integration can reach from where it stands: \
                 {from} .. {to}"
            ),
            FailureKind::Unsupported { message } => write!(f, "{message}"),
        }
    }
}

impl std::error::Error for Failure {}

/// [`FailureKind::ConstraintDomainEnds`] in words.
fn domain_end(
    f: &mut fmt::Formatter<'_>,
    t: f64,
    constraint: &str,
    kind: crate::domain::DomainKind,
    argument: &str,
    value: f64,
) -> fmt::Result {
    use crate::domain::DomainKind;
    let function = match kind {
        DomainKind::Root => "square root",
        DomainKind::Power => "fractional power",
        DomainKind::Logarithm => "logarithm",
        DomainKind::Arcsine => "arcsine",
        DomainKind::Arccosine => "arccosine",
        DomainKind::Pole => {
            return write!(
                f,
                "at t = {t:e}: the constraint `{constraint}` is singular here: it divides \
                 by `{argument}`, which vanishes ({argument} = {value:.3e}), so it no longer \
                 determines its dependent derivative; write it implicitly with another \
                 candidate (`… for y' or x'`)"
            );
        }
    };
    let negative = value < 0.0 || value.is_nan();
    match (kind, negative) {
        (DomainKind::Arcsine | DomainKind::Arccosine, true) => write!(
            f,
            "at t = {t:e}: the constraint `{constraint}` is not defined here: the \
             argument of its {function} is outside [-1, 1] (`{argument}` = {value:.3e}); \
             its branch ended where that reached 0, and the motion past it is not on \
             this branch"
        ),
        (DomainKind::Arcsine | DomainKind::Arccosine, false) => write!(
            f,
            "at t = {t:e}: the constraint `{constraint}` reaches the end of its branch: \
             the argument of its {function} reaches ±1 (`{argument}` falls to \
             {value:.3e}; 0 ends it: the constraint's derivative is infinite there); \
             past it the {function} is not defined, and the motion is not on this branch"
        ),
        (_, true) => write!(
            f,
            "at t = {t:e}: the constraint `{constraint}` is not defined here: the \
             {function} of a negative number (`{argument}` = {value:.3e}); its branch \
             ended where that reached 0, and the motion past it is not on this branch"
        ),
        (_, false) => write!(
            f,
            "at t = {t:e}: the constraint `{constraint}` reaches the end of its branch: \
             `{argument}` under its {function} falls to {value:.3e} (0 ends it: the \
             constraint's derivative is infinite there); past it the {function} of a \
             negative number, and the motion is not on this branch"
        ),
    }
}
