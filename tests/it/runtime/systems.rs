//! Hand-written systems with their hand-derived coefficient systems (from
//! SPEC §1.5's affine formulas, each checked against the basic equation (9)
//! `Φ_t + Σ_A Φ_{x_A} X_A − X_1 = 0` with `Φ = f_1 + Σ_A f_A x_A`) and their
//! exact motions.

use super::rt::error::Failure;
use super::rt::system::{CoefficientSystem, Motion};
use nalgebra::DMatrix;

/// SPEC §1.6: `x = (q1, q2, q1', q2')`, `x3' = p x3`, `x4' = r x3` with
/// `p = α − t/(1+t²)`, `r = αt + 1/(1+t²)`.
pub struct PaperExample {
    pub alpha: f64,
}

impl PaperExample {
    fn p(&self, t: f64) -> f64 {
        self.alpha - t / (1.0 + t * t)
    }
    fn r(&self, t: f64) -> f64 {
        self.alpha * t + 1.0 / (1.0 + t * t)
    }
    fn dp(&self, t: f64) -> f64 {
        -(1.0 - t * t) / (1.0 + t * t).powi(2)
    }
    fn dr(&self, t: f64) -> f64 {
        self.alpha - 2.0 * t / (1.0 + t * t).powi(2)
    }

    /// `q1' = q1'0 e^{αt}/√(1+t²)`, `q2' = t q1'`, and `q1`, `q2` by
    /// adaptive Simpson quadrature of SPEC §1.6's integrals.
    pub fn exact(&self, t: f64, x0: &[f64]) -> Vec<f64> {
        let alpha = self.alpha;
        let speed = move |tau: f64| (alpha * tau).exp() / (1.0 + tau * tau).sqrt();
        let v = x0[2] * speed(t);
        vec![
            x0[0] + x0[2] * integrate(&speed, 0.0, t),
            x0[1] + x0[2] * integrate(&|tau| tau * speed(tau), 0.0, t),
            v,
            t * v,
        ]
    }
}

impl Motion for PaperExample {
    fn dim(&self) -> usize {
        4
    }
    fn rhs(&self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), Failure> {
        dx[0] = x[2];
        dx[1] = x[3];
        dx[2] = self.p(t) * x[2];
        dx[3] = self.r(t) * x[2];
        Ok(())
    }
    fn jacobian(&self, t: f64, _x: &[f64], jac: &mut DMatrix<f64>) -> Result<(), Failure> {
        jac[(0, 2)] = 1.0;
        jac[(1, 3)] = 1.0;
        jac[(2, 2)] = self.p(t);
        jac[(3, 2)] = self.r(t);
        Ok(())
    }
    fn time_partial(&self, t: f64, x: &[f64], dxdt: &mut [f64]) -> Result<(), Failure> {
        dxdt[2] = self.dp(t) * x[2];
        dxdt[3] = self.dr(t) * x[2];
        Ok(())
    }
}

/// a_A1 = 0 and b = 0, so λ = 0 and the system is linear:
/// `f1' = 0`, `f2' = a_12 − Σ f_A a_A2 = 0`,
/// `f3' = a_13 − f3 a_33 − f4 a_43 = 1 − p f3 − r f4`,
/// `f4' = a_14 − f2 a_24 = −f2`.
impl CoefficientSystem for PaperExample {
    fn dim(&self) -> usize {
        4
    }
    fn rhs(&self, t: f64, f: &[f64], df: &mut [f64]) -> Result<(), Failure> {
        df[0] = 0.0;
        df[1] = 0.0;
        df[2] = 1.0 - self.p(t) * f[2] - self.r(t) * f[3];
        df[3] = -f[1];
        Ok(())
    }
    fn jacobian(&self, t: f64, _f: &[f64], jac: &mut DMatrix<f64>) -> Result<(), Failure> {
        jac[(2, 2)] = -self.p(t);
        jac[(2, 3)] = -self.r(t);
        jac[(3, 1)] = -1.0;
        Ok(())
    }
    fn time_partial(&self, t: f64, f: &[f64], dfdt: &mut [f64]) -> Result<(), Failure> {
        dfdt[2] = -self.dp(t) * f[2] - self.dr(t) * f[3];
        Ok(())
    }
    fn is_linear(&self) -> bool {
        true
    }
}

/// `x = (q, q')`, `q'' = −ω² q`.
pub struct Oscillator {
    pub omega: f64,
}

impl Oscillator {
    pub fn exact(&self, t: f64, x0: &[f64]) -> Vec<f64> {
        let w = self.omega;
        let (s, c) = (w * t).sin_cos();
        vec![x0[0] * c + x0[1] / w * s, -x0[0] * w * s + x0[1] * c]
    }
}

impl Motion for Oscillator {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), Failure> {
        dx[0] = x[1];
        dx[1] = -self.omega.powi(2) * x[0];
        Ok(())
    }
    fn jacobian(&self, _t: f64, _x: &[f64], jac: &mut DMatrix<f64>) -> Result<(), Failure> {
        jac[(0, 1)] = 1.0;
        jac[(1, 0)] = -self.omega.powi(2);
        Ok(())
    }
    fn time_partial(&self, _t: f64, _x: &[f64], _dxdt: &mut [f64]) -> Result<(), Failure> {
        Ok(())
    }
}

/// a_21 = −ω², so λ = ω² f2 (Riccati): `f1' = ω² f2 f1`,
/// `f2' = a_12 + λ f2 = 1 + ω² f2²` (f2 = tan(ωt + C)/ω).
impl CoefficientSystem for Oscillator {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, _t: f64, f: &[f64], df: &mut [f64]) -> Result<(), Failure> {
        let w2 = self.omega.powi(2);
        df[0] = w2 * f[1] * f[0];
        df[1] = 1.0 + w2 * f[1] * f[1];
        Ok(())
    }
    fn jacobian(&self, _t: f64, f: &[f64], jac: &mut DMatrix<f64>) -> Result<(), Failure> {
        let w2 = self.omega.powi(2);
        jac[(0, 0)] = w2 * f[1];
        jac[(0, 1)] = w2 * f[0];
        jac[(1, 1)] = 2.0 * w2 * f[1];
        Ok(())
    }
    fn time_partial(&self, _t: f64, _f: &[f64], _dfdt: &mut [f64]) -> Result<(), Failure> {
        Ok(())
    }
    fn is_linear(&self) -> bool {
        false
    }
}

/// `q'' = −ω² q − 2ζω q'` (underdamped, ζ < 1).
pub struct DampedOscillator {
    pub omega: f64,
    pub zeta: f64,
}

impl DampedOscillator {
    pub fn exact(&self, t: f64, x0: &[f64]) -> Vec<f64> {
        let decay = self.zeta * self.omega;
        let wd = self.omega * (1.0 - self.zeta * self.zeta).sqrt();
        let (a, b) = (x0[0], (x0[1] + decay * x0[0]) / wd);
        let (s, c) = (wd * t).sin_cos();
        let e = (-decay * t).exp();
        vec![
            e * (a * c + b * s),
            e * ((-decay * a + wd * b) * c + (-decay * b - wd * a) * s),
        ]
    }
}

impl Motion for DampedOscillator {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), Failure> {
        dx[0] = x[1];
        dx[1] = -self.omega.powi(2) * x[0] - 2.0 * self.zeta * self.omega * x[1];
        Ok(())
    }
    fn jacobian(&self, _t: f64, _x: &[f64], jac: &mut DMatrix<f64>) -> Result<(), Failure> {
        jac[(0, 1)] = 1.0;
        jac[(1, 0)] = -self.omega.powi(2);
        jac[(1, 1)] = -2.0 * self.zeta * self.omega;
        Ok(())
    }
    fn time_partial(&self, _t: f64, _x: &[f64], _dxdt: &mut [f64]) -> Result<(), Failure> {
        Ok(())
    }
}

/// λ = ω² f2: `f1' = ω² f2 f1`, `f2' = 1 − f2 a_22 + λ f2 = 1 + 2ζω f2 + ω² f2²`.
impl CoefficientSystem for DampedOscillator {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, _t: f64, f: &[f64], df: &mut [f64]) -> Result<(), Failure> {
        let w2 = self.omega.powi(2);
        df[0] = w2 * f[1] * f[0];
        df[1] = 1.0 + 2.0 * self.zeta * self.omega * f[1] + w2 * f[1] * f[1];
        Ok(())
    }
    fn jacobian(&self, _t: f64, f: &[f64], jac: &mut DMatrix<f64>) -> Result<(), Failure> {
        let w2 = self.omega.powi(2);
        jac[(0, 0)] = w2 * f[1];
        jac[(0, 1)] = w2 * f[0];
        jac[(1, 1)] = 2.0 * self.zeta * self.omega + 2.0 * w2 * f[1];
        Ok(())
    }
    fn time_partial(&self, _t: f64, _f: &[f64], _dfdt: &mut [f64]) -> Result<(), Failure> {
        Ok(())
    }
    fn is_linear(&self) -> bool {
        false
    }
}

/// A stiff pair: `x1' = x2 − x1`, `x2' = −k x2` (k = `rate`).
pub struct StiffPair {
    pub rate: f64,
}

impl StiffPair {
    pub fn exact(&self, t: f64, x0: &[f64]) -> Vec<f64> {
        let k = self.rate;
        let fast = (-k * t).exp();
        let slow = (-t).exp();
        vec![
            x0[0] * slow + x0[1] * (slow - fast) / (k - 1.0),
            x0[1] * fast,
        ]
    }
}

impl Motion for StiffPair {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), Failure> {
        dx[0] = x[1] - x[0];
        dx[1] = -self.rate * x[1];
        Ok(())
    }
    fn jacobian(&self, _t: f64, _x: &[f64], jac: &mut DMatrix<f64>) -> Result<(), Failure> {
        jac[(0, 0)] = -1.0;
        jac[(0, 1)] = 1.0;
        jac[(1, 1)] = -self.rate;
        Ok(())
    }
    fn time_partial(&self, _t: f64, _x: &[f64], _dxdt: &mut [f64]) -> Result<(), Failure> {
        Ok(())
    }
}

/// a_21 = 0, λ = a_11 = −1: `f1' = −f1`, `f2' = 1 + (k − 1) f2` — the
/// adjoint of the fast mode grows like `e^{(k−1)t}`.
impl CoefficientSystem for StiffPair {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, _t: f64, f: &[f64], df: &mut [f64]) -> Result<(), Failure> {
        df[0] = -f[0];
        df[1] = 1.0 + (self.rate - 1.0) * f[1];
        Ok(())
    }
    fn jacobian(&self, _t: f64, _f: &[f64], jac: &mut DMatrix<f64>) -> Result<(), Failure> {
        jac[(0, 0)] = -1.0;
        jac[(1, 1)] = self.rate - 1.0;
        Ok(())
    }
    fn time_partial(&self, _t: f64, _f: &[f64], _dfdt: &mut [f64]) -> Result<(), Failure> {
        Ok(())
    }
    fn is_linear(&self) -> bool {
        true
    }
}

/// `x' = (s x)²`: blows up at `t = 1/(s² x0)`.
pub struct Quadratic {
    pub scale: f64,
}

impl Motion for Quadratic {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), Failure> {
        dx[0] = (self.scale * x[0]).powi(2);
        Ok(())
    }
    fn jacobian(&self, _t: f64, x: &[f64], jac: &mut DMatrix<f64>) -> Result<(), Failure> {
        jac[(0, 0)] = 2.0 * self.scale * self.scale * x[0];
        Ok(())
    }
    fn time_partial(&self, _t: f64, _x: &[f64], _dxdt: &mut [f64]) -> Result<(), Failure> {
        Ok(())
    }
}

/// `x' = diag(0, k, 0) x`: `f1' = 0`, `f2' = −k f2`, `f3' = 0`.
pub struct Diverging {
    pub rate: f64,
}

impl Diverging {
    pub fn exact(&self, t: f64, x0: &[f64]) -> Vec<f64> {
        vec![x0[0], x0[1] * (self.rate * t).exp(), x0[2]]
    }
}

impl CoefficientSystem for Diverging {
    fn dim(&self) -> usize {
        3
    }
    fn rhs(&self, _t: f64, f: &[f64], df: &mut [f64]) -> Result<(), Failure> {
        df[0] = 0.0;
        df[1] = -self.rate * f[1];
        df[2] = 0.0;
        Ok(())
    }
    fn jacobian(&self, _t: f64, _f: &[f64], jac: &mut DMatrix<f64>) -> Result<(), Failure> {
        jac[(1, 1)] = -self.rate;
        Ok(())
    }
    fn time_partial(&self, _t: f64, _f: &[f64], _dfdt: &mut [f64]) -> Result<(), Failure> {
        Ok(())
    }
    fn is_linear(&self) -> bool {
        true
    }
}

/// `∫_a^b g` by adaptive Simpson with Richardson correction, to ~1e-15.
pub fn integrate(g: &dyn Fn(f64) -> f64, a: f64, b: f64) -> f64 {
    if a == b {
        return 0.0;
    }
    let (ga, gm, gb) = (g(a), g(0.5 * (a + b)), g(b));
    let whole = (b - a) / 6.0 * (ga + 4.0 * gm + gb);
    simpson(g, a, b, ga, gm, gb, whole, 1e-15, 50)
}

#[allow(clippy::too_many_arguments)]
fn simpson(
    g: &dyn Fn(f64) -> f64,
    a: f64,
    b: f64,
    ga: f64,
    gm: f64,
    gb: f64,
    whole: f64,
    tol: f64,
    depth: u32,
) -> f64 {
    let m = 0.5 * (a + b);
    let (lm, rm) = (0.5 * (a + m), 0.5 * (m + b));
    let (glm, grm) = (g(lm), g(rm));
    let left = (m - a) / 6.0 * (ga + 4.0 * glm + gm);
    let right = (b - m) / 6.0 * (gm + 4.0 * grm + gb);
    let delta = left + right - whole;
    if depth == 0 || delta.abs() <= 15.0 * tol {
        return left + right + delta / 15.0;
    }
    simpson(g, a, m, ga, glm, gm, left, tol / 2.0, depth - 1)
        + simpson(g, m, b, gm, grm, gb, right, tol / 2.0, depth - 1)
}

/// `q'' = 2 q³` (not affine): `q = 1/(c − t)` when `q0 = 1/c`, `q0' = 1/c²`.
pub struct Cubic;

impl Cubic {
    pub fn exact(&self, t: f64, x0: &[f64]) -> Vec<f64> {
        let c = 1.0 / x0[0];
        vec![1.0 / (c - t), 1.0 / (c - t).powi(2)]
    }
}

impl Motion for Cubic {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), Failure> {
        dx[0] = x[1];
        dx[1] = 2.0 * x[0].powi(3);
        Ok(())
    }
    fn jacobian(&self, _t: f64, x: &[f64], jac: &mut DMatrix<f64>) -> Result<(), Failure> {
        jac[(0, 1)] = 1.0;
        jac[(1, 0)] = 6.0 * x[0] * x[0];
        Ok(())
    }
    fn time_partial(&self, _t: f64, _x: &[f64], _dxdt: &mut [f64]) -> Result<(), Failure> {
        Ok(())
    }
}

/// A linear coefficient system whose condition matrix passes through
/// singularity without its condition number ever showing it:
/// `f1' = 0`, `f2' = −k f1`, so `S = [[1, 0], [−k t, 1]]` and the 1 × 1
/// condition matrix is `S_22 − S_21 x_20 = 1 + k t x_20`, zero at
/// `t = −1/(k x_20)` (its condition number is 1 on both sides).
///
/// The SPEC's coefficient systems never do this (their `f_B'` do not
/// involve `f_1`, so the matrix is a block of a fundamental matrix, whose
/// determinant is positive by Liouville); this one is made to, to test the
/// runtime's guard (an `f_1` in `f_2'` comes from a term `x_1 x_2` in the
/// motion, which the linear ansatz does not solve).
pub struct SingularCrossing {
    pub rate: f64,
}

impl CoefficientSystem for SingularCrossing {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, _t: f64, f: &[f64], df: &mut [f64]) -> Result<(), Failure> {
        df[0] = 0.0;
        df[1] = -self.rate * f[0];
        Ok(())
    }
    fn jacobian(&self, _t: f64, _f: &[f64], jac: &mut DMatrix<f64>) -> Result<(), Failure> {
        jac[(1, 0)] = -self.rate;
        Ok(())
    }
    fn time_partial(&self, _t: f64, _f: &[f64], _dfdt: &mut [f64]) -> Result<(), Failure> {
        Ok(())
    }
    fn is_linear(&self) -> bool {
        true
    }
}
