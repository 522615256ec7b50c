//! Hand-written models for the runtime's tests, each with a known motion
//! (a closed form, or a reference by another integrator).

#![allow(dead_code)]

use lagc_runtime::failure::Failure;
use lagc_runtime::linalg::Matrix;
use lagc_runtime::model::{Initial, Model};

/// The coefficient system of an affine model from its own `A(t)`, `b(t)`
/// (SPEC §1.5's formulas), for hand models that have no symbolic one.
pub fn affine_coefficients<M: Model>(
    model: &M,
    t: f64,
    f: &[f64],
    df: &mut [f64],
) -> Result<(), Failure> {
    let n = f.len();
    let (a, b) = affine_parts(model, t)?;
    let lambda = a[(0, 0)] - (1..n).map(|k| f[k] * a[(k, 0)]).sum::<f64>();
    df[0] = b[0] - (1..n).map(|k| f[k] * b[k]).sum::<f64>() + lambda * f[0];
    for col in 1..n {
        df[col] = a[(0, col)] - (1..n).map(|k| f[k] * a[(k, col)]).sum::<f64>() + lambda * f[col];
    }
    Ok(())
}

pub fn affine_jacobian<M: Model>(model: &M, t: f64, f: &[f64], jac: &mut Matrix) -> Result<(), Failure> {
    let n = f.len();
    let (a, b) = affine_parts(model, t)?;
    let lambda = a[(0, 0)] - (1..n).map(|k| f[k] * a[(k, 0)]).sum::<f64>();
    jac[(0, 0)] = lambda;
    for k in 1..n {
        jac[(0, k)] = -b[k] - a[(k, 0)] * f[0];
    }
    for row in 1..n {
        for k in 1..n {
            jac[(row, k)] = -a[(k, row)] - a[(k, 0)] * f[row];
        }
        jac[(row, row)] += lambda;
    }
    Ok(())
}

fn affine_parts<M: Model>(model: &M, t: f64) -> Result<(Matrix, Vec<f64>), Failure> {
    let n = M::STATE.len();
    let mut a = Matrix::zeros(n, n);
    let zero = vec![0.0; n];
    model.jacobian(t, &zero, &mut a)?;
    let mut b = vec![0.0; n];
    model.rhs(t, &zero, &mut b)?;
    Ok((a, b))
}

/// `x'' = −ω² x`, x(0) = 1, x'(0) = 0: `x = cos ωt` (affine; its
/// coefficient system is of Riccati type with poles every half period).
#[derive(Clone)]
pub struct Oscillator {
    pub params: Vec<f64>,
}

impl Model for Oscillator {
    const NAME: &'static str = "oscillator";
    const SOURCE_HASH: &'static str = "test";
    const PARAMS: &'static [&'static str] = &["w", "T"];
    const STATE: &'static [&'static str] = &["x", "x'"];
    const COORDINATES: usize = 1;
    const INITIAL: &'static [Initial] = &[Initial::Given, Initial::Given];
    const AFFINE: bool = true;
    const EXACT: bool = true;

    fn parameters(overrides: &[Option<f64>]) -> Vec<f64> {
        vec![overrides[0].unwrap_or(2.0), overrides[1].unwrap_or(10.0)]
    }
    fn new(params: &[f64]) -> Self {
        Oscillator { params: params.to_vec() }
    }
    fn param_values(&self) -> &[f64] {
        &self.params
    }
    fn time_span(&self) -> (f64, f64) {
        (0.0, self.params[1])
    }
    fn initial_state(&self, given: &[Option<f64>]) -> Result<Vec<f64>, Failure> {
        Ok(vec![given[0].unwrap_or(1.0), given[1].unwrap_or(0.0)])
    }
    fn rhs(&self, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), Failure> {
        let w = self.params[0];
        dx[0] = x[1];
        dx[1] = -w * w * x[0];
        Ok(())
    }
    fn jacobian(&self, _t: f64, _x: &[f64], jac: &mut Matrix) -> Result<(), Failure> {
        let w = self.params[0];
        jac[(0, 1)] = 1.0;
        jac[(1, 0)] = -w * w;
        Ok(())
    }
    fn time_partial(&self, _t: f64, _x: &[f64], _dxdt: &mut [f64]) -> Result<(), Failure> {
        Ok(())
    }
    fn coefficients(&self, t: f64, f: &[f64], df: &mut [f64]) -> Result<(), Failure> {
        affine_coefficients(self, t, f, df)
    }
    fn coefficient_jacobian(&self, t: f64, f: &[f64], jac: &mut Matrix) -> Result<(), Failure> {
        affine_jacobian(self, t, f, jac)
    }
    fn exact(&self, t: f64, out: &mut [Option<f64>]) {
        let w = self.params[0];
        out[0] = Some((w * t).cos());
        out[1] = Some(-w * (w * t).sin());
    }
}

/// `x'' = −sin(x)/(10 − t/2)`: the pendulum whose mass decreases
/// (non-affine, explicitly time dependent). x(0) = 1, x'(0) = 0, t ∈ [0, 10].
#[derive(Clone)]
pub struct MassLossPendulum {
    pub params: Vec<f64>,
}

impl Model for MassLossPendulum {
    const NAME: &'static str = "mass_loss_pendulum";
    const SOURCE_HASH: &'static str = "test";
    const PARAMS: &'static [&'static str] = &[];
    const STATE: &'static [&'static str] = &["x", "x'"];
    const COORDINATES: usize = 1;
    const INITIAL: &'static [Initial] = &[Initial::Given, Initial::Given];

    fn parameters(_overrides: &[Option<f64>]) -> Vec<f64> {
        Vec::new()
    }
    fn new(_params: &[f64]) -> Self {
        MassLossPendulum { params: Vec::new() }
    }
    fn param_values(&self) -> &[f64] {
        &self.params
    }
    fn time_span(&self) -> (f64, f64) {
        (0.0, 10.0)
    }
    fn initial_state(&self, given: &[Option<f64>]) -> Result<Vec<f64>, Failure> {
        Ok(vec![given[0].unwrap_or(1.0), given[1].unwrap_or(0.0)])
    }
    fn rhs(&self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), Failure> {
        dx[0] = x[1];
        dx[1] = -x[0].sin() / (10.0 - 0.5 * t);
        Ok(())
    }
    fn jacobian(&self, t: f64, x: &[f64], jac: &mut Matrix) -> Result<(), Failure> {
        jac[(0, 1)] = 1.0;
        jac[(1, 0)] = -x[0].cos() / (10.0 - 0.5 * t);
        Ok(())
    }
    fn time_partial(&self, t: f64, x: &[f64], dxdt: &mut [f64]) -> Result<(), Failure> {
        let m = 10.0 - 0.5 * t;
        dxdt[1] = -x[0].sin() * 0.5 / (m * m);
        Ok(())
    }
}

/// The spherical pendulum (g/l = 9.81): θ'' = sinθ cosθ φ'² − 9.81 sinθ,
/// φ'' = −2 cotθ θ' φ'; θ(0) = 1, φ(0) = 0, θ'(0) = 0, φ'(0) = 2. Energy
/// and `sin²θ φ'` are conserved.
#[derive(Clone)]
pub struct SphericalPendulum {
    pub params: Vec<f64>,
}

impl SphericalPendulum {
    pub fn energy(x: &[f64]) -> f64 {
        let (th, thd, phd) = (x[0], x[2], x[3]);
        0.5 * (thd * thd + th.sin().powi(2) * phd * phd) - 9.81 * th.cos()
    }
}

impl Model for SphericalPendulum {
    const NAME: &'static str = "spherical_pendulum";
    const SOURCE_HASH: &'static str = "test";
    const PARAMS: &'static [&'static str] = &["T"];
    const STATE: &'static [&'static str] = &["th", "ph", "th'", "ph'"];
    const COORDINATES: usize = 2;
    const INITIAL: &'static [Initial] = &[Initial::Given; 4];

    fn parameters(overrides: &[Option<f64>]) -> Vec<f64> {
        vec![overrides.first().copied().flatten().unwrap_or(10.0)]
    }
    fn new(params: &[f64]) -> Self {
        SphericalPendulum { params: params.to_vec() }
    }
    fn param_values(&self) -> &[f64] {
        &self.params
    }
    fn time_span(&self) -> (f64, f64) {
        (0.0, self.params[0])
    }
    fn initial_state(&self, given: &[Option<f64>]) -> Result<Vec<f64>, Failure> {
        let d = [1.0, 0.0, 0.0, 2.0];
        Ok((0..4).map(|i| given[i].unwrap_or(d[i])).collect())
    }
    fn rhs(&self, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), Failure> {
        let (th, thd, phd) = (x[0], x[2], x[3]);
        let (s, c) = th.sin_cos();
        dx[0] = thd;
        dx[1] = phd;
        dx[2] = s * c * phd * phd - 9.81 * s;
        dx[3] = -2.0 * c / s * thd * phd;
        Ok(())
    }
    fn jacobian(&self, _t: f64, x: &[f64], jac: &mut Matrix) -> Result<(), Failure> {
        let (th, thd, phd) = (x[0], x[2], x[3]);
        let (s, c) = th.sin_cos();
        jac[(0, 2)] = 1.0;
        jac[(1, 3)] = 1.0;
        jac[(2, 0)] = (c * c - s * s) * phd * phd - 9.81 * c;
        jac[(2, 3)] = 2.0 * s * c * phd;
        jac[(3, 0)] = 2.0 / (s * s) * thd * phd;
        jac[(3, 2)] = -2.0 * c / s * phd;
        jac[(3, 3)] = -2.0 * c / s * thd;
        Ok(())
    }
    fn time_partial(&self, _t: f64, _x: &[f64], _dxdt: &mut [f64]) -> Result<(), Failure> {
        Ok(())
    }
}
