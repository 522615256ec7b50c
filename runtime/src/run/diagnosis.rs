//! A failure named after its physical cause where the model can see it:
//! a mass at or below zero, a singular mass matrix, a constraint undefined
//! where the motion stands, a singular configuration of a linkage.

use crate::failure::{Failure, FailureKind};
use crate::model::DynModel;
use crate::run::regime::pivot_volumes;

/// A failure of the integration (a step size that underflows, a value
/// that is not finite) or of keeping the constraints near a singular
/// configuration is named as that: the equations divide by the vanishing
/// determinants there.
pub fn near_singular_configuration(
    model: &dyn DynModel,
    failure: Failure,
    x: &[f64],
    start: &[f64],
) -> Failure {
    if !matches!(
        failure.kind,
        FailureKind::StepSizeUnderflow { .. }
            | FailureKind::NonFiniteState { .. }
            | FailureKind::NonFiniteRate { .. }
            | FailureKind::ConstraintLeft { .. }
            | FailureKind::ConstraintUndefined { .. }
            | FailureKind::PositionsLeftConstraint { .. }
    ) || model.constraints().is_empty()
        || !x.iter().all(|v| v.is_finite())
    {
        return failure;
    }
    let t = failure.time;
    let now = pivot_volumes(model, t, x);
    for ((c, &now), &start) in model.constraints().iter().zip(&now).zip(start) {
        if c.names.len() > 1 && start > 0.0 && now < 1e-3 * start {
            return Failure::new(
                t,
                FailureKind::SingularConfiguration {
                    constraint: c.text.to_string(),
                    ratio: now / start,
                },
            );
        }
    }
    failure
}

/// A mass law at or below zero at `(t, x)` stops the run (the equations
/// divide by it; a law of the state, `rho * x`, needs the state).
pub fn check_masses(model: &dyn DynModel, t: f64, x: &[f64]) -> Result<(), Failure> {
    if model.mass_names().is_empty() {
        return Ok(());
    }
    // On the stack for the usual few masses: every solve checks them, and
    // an allocation is about 1 % of a short solve (docs/BENCHMARKS.md
    // §10i).
    let count = model.mass_names().len();
    let mut small = [0.0; 8];
    let mut large = Vec::new();
    let masses: &mut [f64] = if count <= small.len() {
        &mut small[..count]
    } else {
        large.resize(count, 0.0);
        &mut large
    };
    model.masses(t, x, masses);
    match masses.iter().position(|&m| !(m > 0.0)) {
        Some(i) => Err(Failure::new(
            t,
            FailureKind::MassVanishes {
                mass: model.mass_names()[i].to_string(),
                value: masses[i],
            },
        )),
        None => Ok(()),
    }
}

/// The mass matrix's smallest scale `1/‖M⁻¹‖₁` at the start of a run: a
/// mass matrix is singular where that has shrunk by many orders of
/// magnitude (for one coordinate the condition number is always 1).
#[derive(Clone, Copy)]
pub struct MassScale(Option<f64>);

impl MassScale {
    pub fn at(model: &dyn DynModel, t: f64, x: &[f64]) -> MassScale {
        MassScale(model.mass_matrix(t, x).map(|m| smallest_scale(&m)))
    }
}

fn smallest_scale(m: &crate::linalg::Matrix) -> f64 {
    let lu = crate::linalg::Lu::new(m);
    1.0 / lu.inverse_one_norm_estimate()
}

/// The physical cause of a failure where the model can see it: a mass
/// that reaches zero, a mass matrix that becomes singular — the integrator
/// usually stops first with a step-size underflow or a non-finite value as
/// the motion blows up toward them.
pub fn diagnose(model: &dyn DynModel, failure: Failure, x: &[f64], scale: &MassScale) -> Failure {
    if matches!(
        failure.kind,
        FailureKind::InconsistentInitialValue { .. }
            | FailureKind::BadTimeSpan { .. }
            | FailureKind::StepBudgetExhausted { stalled: None, .. }
            | FailureKind::AnchorCancels { .. }
            | FailureKind::ConstraintPivotVanishes { .. }
            | FailureKind::SingularConfiguration { .. }
            | FailureKind::ConstraintUndefined { .. }
            | FailureKind::ConstraintLeft { .. }
    ) {
        return failure;
    }
    // Steps that stall may stall at a mass reaching zero (a law of the
    // state, `rho * x`, whose motion the field's windows chase to it).
    let t = failure.time;
    if !model.mass_names().is_empty() {
        let mut now = vec![0.0; model.mass_names().len()];
        let mut ahead = vec![0.0; model.mass_names().len()];
        model.masses(t, x, &mut now);
        // The integrator gives up just before the mass reaches zero; a law
        // of the state (`rho * x`) is looked at ahead along the state's
        // rate where that is finite.
        let dt = 1e-6 * t.abs().max(1e-3);
        let mut rate = vec![0.0; x.len()];
        let x_ahead: Vec<f64> = match model.rhs(t, x, &mut rate) {
            Ok(()) if rate.iter().all(|r| r.is_finite()) => {
                x.iter().zip(&rate).map(|(&xi, &ri)| xi + dt * ri).collect()
            }
            _ => x.to_vec(),
        };
        model.masses(t + dt, &x_ahead, &mut ahead);
        // A law of the state is NaN at a state that is not finite: that
        // names the state, not the mass.
        let finite = x.iter().all(|v| v.is_finite());
        let vanishes = |m: f64| !(m > 0.0) && (finite || !m.is_nan());
        for (i, (&m, &a)) in now.iter().zip(&ahead).enumerate() {
            if vanishes(m) || vanishes(a) {
                return Failure::new(
                    t,
                    FailureKind::MassVanishes {
                        mass: model.mass_names()[i].to_string(),
                        value: m,
                    },
                );
            }
        }
    }
    if matches!(
        failure.kind,
        FailureKind::StepSizeUnderflow { .. }
            | FailureKind::NonFiniteState { .. }
            | FailureKind::NonFiniteRate { .. }
            | FailureKind::SingularMassMatrix { .. }
            | FailureKind::SingularConditionMatrix { .. }
            | FailureKind::FieldNotConverging { .. }
    ) && x.iter().all(|v| v.is_finite())
    {
        // A constraint whose value or slope is not finite where the motion
        // stands (the root of `y' = sqrt(c² − x'²)` at its apex, where its
        // slope is infinite and so is the mass matrix): the constraint is
        // the cause, not the matrix it makes singular.
        if let Some(component) = undefined_constraint(model, t, x) {
            return Failure::new(t, FailureKind::ConstraintUndefined { component });
        }
    }
    if matches!(
        failure.kind,
        FailureKind::StepSizeUnderflow { .. }
            | FailureKind::NonFiniteState { .. }
            | FailureKind::NonFiniteRate { .. }
    ) && x.iter().all(|v| v.is_finite())
    {
        if let (Some(m), Some(start)) = (model.mass_matrix(t, x), scale.0) {
            let now = smallest_scale(&m);
            let condition = crate::highest::mass_condition(&m);
            if !(now > 1e-6 * start) || !(condition < 1e12) {
                return Failure::new(
                    t,
                    FailureKind::SingularMassMatrix {
                        condition: condition.max(start / now),
                    },
                );
            }
        }
    }
    failure
}

/// The fixed component whose constrained value, or its slope in the
/// velocities, is not finite at `(t, x)`.
fn undefined_constraint(model: &dyn DynModel, t: f64, x: &[f64]) -> Option<String> {
    if !model.keeps_constraints() {
        return None;
    }
    let n = x.len();
    let mut kept = x.to_vec();
    let mut gradient = crate::linalg::Matrix::zeros(n, n);
    model.constrained(t, x, &mut kept).ok()?;
    model.kept_gradient(t, x, &mut gradient).ok()?;
    let row =
        (0..n).find(|&j| !kept[j].is_finite() || (0..n).any(|i| !gradient[(j, i)].is_finite()))?;
    Some(model.state_names()[row].to_string())
}
