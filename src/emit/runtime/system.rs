//! The traits the generated code implements.
//!
//! The generated crate holds one struct per system whose fields are the
//! parameters (overridable at run time); it implements [`Motion`] with the
//! reduced system (7) and [`CoefficientSystem`] with the coefficient system
//! of the basic equation (9), all as straight-line symbolic expressions.

use super::error::Failure;
use nalgebra::DMatrix;

/// A first-order system `x' = X(t, x)`: the reduced system (7) with the
/// state (6), `x = (q_1..q_n, q_1'..q_n', …)`, and also every auxiliary
/// system the runtime integrates (e.g. the coefficient system augmented with
/// its sensitivities).
///
/// Methods return `Err` for failures only the system can see (a singular
/// mass matrix, Newton non-convergence); the integrators themselves check
/// for non-finite values, so implementations need not.
pub trait Motion {
    /// `N`, the number of state components.
    fn dim(&self) -> usize;

    /// `dx = X(t, x)`.
    fn rhs(&self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), Failure>;

    /// `jac = ∂X/∂x (t, x)`, an `N × N` matrix (already sized and zeroed
    /// by the caller: only non-zero entries need be written). Used by the
    /// stiff direct method and by the local field method.
    fn jacobian(&self, t: f64, x: &[f64], jac: &mut DMatrix<f64>) -> Result<(), Failure>;

    /// `dxdt = ∂X/∂t (t, x)`, needed by Rosenbrock methods for
    /// non-autonomous systems and by the local field method. An
    /// autonomous system writes zeros (the caller zeroes `dxdt`).
    fn time_partial(&self, t: f64, x: &[f64], dxdt: &mut [f64]) -> Result<(), Failure>;

    /// The name of component `i` in messages (`q1'`, …).
    fn component_name(&self, i: usize) -> String {
        format!("x{}", i + 1)
    }
}

/// The coefficient system `f' = F(t, f)` of the field ansatz (10),
/// `x_1 = f_1(t) + Σ_{A=2..N} f_A(t) x_A`: `f = (f_1, f_2..f_N)` has as many
/// components as the state. Index 0 is the free term `f_1`; index `A - 1`
/// is the coefficient of `x_A`.
pub trait CoefficientSystem {
    /// `N`, the number of coefficients (= the state dimension).
    fn dim(&self) -> usize;

    /// `df = F(t, f)`.
    fn rhs(&self, t: f64, f: &[f64], df: &mut [f64]) -> Result<(), Failure>;

    /// `jac = ∂F/∂f (t, f)` (sized and zeroed by the caller), for the
    /// sensitivities `S' = (∂F/∂f) S`.
    fn jacobian(&self, t: f64, f: &[f64], jac: &mut DMatrix<f64>) -> Result<(), Failure>;

    /// `dfdt = ∂F/∂t (t, f)` (zeroed by the caller), for the stiff
    /// integrator of linear coefficient systems.
    fn time_partial(&self, t: f64, f: &[f64], dfdt: &mut [f64]) -> Result<(), Failure>;

    /// True when `F` is affine in `f` (no `X_A` depends on `x_1`,
    /// `a_A1 = 0`): then `∂F/∂f` does not depend on `f`, and the augmented
    /// system can be integrated with the exact Jacobian by the stiff method.
    fn is_linear(&self) -> bool;
}
