//! What the one-step integrators integrate: a first-order system
//! `y' = F(t, y)` with its Jacobians. The model's reduced system (7) is one
//! ([`ModelSystem`]); so are the field method's coefficient systems with
//! their sensitivities.

use crate::failure::Failure;
use crate::linalg::Matrix;
use crate::model::DynModel;

pub trait System {
    /// The number of components.
    fn dim(&self) -> usize;

    /// `dy = F(t, y)`.
    fn rhs(&self, t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), Failure>;

    /// `jac = ∂F/∂y` (sized and zeroed by the caller).
    fn jacobian(&self, t: f64, y: &[f64], jac: &mut Matrix) -> Result<(), Failure>;

    /// `dydt = ∂F/∂t` (zeroed by the caller).
    fn time_partial(&self, t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), Failure>;

    /// The name of component `i` in messages.
    fn component_name(&self, i: usize) -> String {
        format!("y{}", i + 1)
    }

    /// The name of the rate of component `i` (`q1''` for the state's `q1'`).
    fn rate_name(&self, i: usize) -> String {
        format!("{}'", self.component_name(i))
    }
}

/// A model's reduced system (7) in its current regime.
pub struct ModelSystem<'a>(pub &'a dyn DynModel);

impl System for ModelSystem<'_> {
    fn dim(&self) -> usize {
        self.0.dim()
    }

    fn rhs(&self, t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), Failure> {
        self.0.rhs(t, y, dy)
    }

    fn jacobian(&self, t: f64, y: &[f64], jac: &mut Matrix) -> Result<(), Failure> {
        self.0.jacobian(t, y, jac)
    }

    fn time_partial(&self, t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), Failure> {
        self.0.time_partial(t, y, dydt)
    }

    fn component_name(&self, i: usize) -> String {
        self.0
            .state_names()
            .get(i)
            .map_or_else(|| format!("x{}", i + 1), |s| (*s).to_string())
    }
}
