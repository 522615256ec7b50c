//! The quantity a run-time failure is about, as a value: a program that
//! catches a failure (the Python module's `IntegrationError.quantity`)
//! reads it without parsing the message.

use crate::failure::{Failure, FailureKind};

impl Failure {
    /// What failed, by the model's own name where it has one (a mass law,
    /// a state component, a constraint as written, a constraint's
    /// argument), else the method's quantity in words (`mass matrix`,
    /// `step size`, …).
    pub fn quantity(&self) -> String {
        match &self.kind {
            FailureKind::MassVanishes { mass, .. } => mass.clone(),
            FailureKind::NonFiniteState { component }
            | FailureKind::NonFiniteRate { component }
            | FailureKind::ConstraintUndefined { component }
            | FailureKind::ConstraintLeft { component, .. }
            | FailureKind::ConstraintKink { component, .. }
            | FailureKind::InconsistentInitialValue { component, .. }
            | FailureKind::NonFiniteInitialValue { component }
            | FailureKind::ResetOfFixedComponent { component, .. } => component.clone(),
            FailureKind::ConstraintPivotVanishes { constraint, .. }
            | FailureKind::PositionsLeftConstraint { constraint, .. }
            | FailureKind::SingularConfiguration { constraint, .. }
            | FailureKind::InitialCandidateVanishes { constraint, .. }
            | FailureKind::InitialPositionsOffConstraint { constraint, .. } => constraint.clone(),
            FailureKind::ConstraintDomainEnds { argument, .. } => argument.clone(),
            FailureKind::ImpactHoldsAtStart { condition, .. } => format!("when {condition}"),
            FailureKind::SingularMassMatrix { .. } => "mass matrix".to_string(),
            FailureKind::StepSizeUnderflow { .. } => "step size".to_string(),
            FailureKind::SingularConditionMatrix { .. }
            | FailureKind::ConditionMatrixCrossedSingularity { .. } => {
                "condition matrix".to_string()
            }
            FailureKind::StepBudgetExhausted { .. } => "step budget".to_string(),
            FailureKind::NewtonNonConvergence { .. } => "highest derivatives".to_string(),
            FailureKind::FieldNotConverging { .. } => "field".to_string(),
            FailureKind::BadTimeSpan { .. } | FailureKind::OutsideSpan { .. } => {
                "time span".to_string()
            }
            FailureKind::AnchorCancels { .. } => "anchor".to_string(),
            FailureKind::NotAffine => "coefficient system".to_string(),
            FailureKind::Unsupported { .. } => "request".to_string(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_named_quantity_is_the_models_name() {
        let mass = Failure::new(
            1.0,
            FailureKind::MassVanishes {
                mass: "M".to_string(),
                value: 0.0,
            },
        );
        assert_eq!(mass.quantity(), "M");
        assert_eq!(Failure::non_finite(0.5, "q1'").quantity(), "q1'");
        let singular = Failure::new(1.0, FailureKind::SingularMassMatrix { condition: 1e20 });
        assert_eq!(singular.quantity(), "mass matrix");
    }
}
