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

pub fn affine_jacobian<M: Model>(
    model: &M,
    t: f64,
    f: &[f64],
    jac: &mut Matrix,
) -> Result<(), Failure> {
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

/// Each value given, else its default: the parameters from their
/// overrides, the initial state from the values given.
pub fn given_or(given: &[Option<f64>], defaults: &[f64]) -> Vec<f64> {
    defaults
        .iter()
        .enumerate()
        .map(|(i, &d)| given.get(i).copied().flatten().unwrap_or(d))
        .collect()
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
#[derive(Clone, Debug)]
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
        given_or(overrides, &[2.0, 10.0])
    }
    fn new(params: &[f64]) -> Self {
        Oscillator {
            params: params.to_vec(),
        }
    }
    fn param_values(&self) -> &[f64] {
        &self.params
    }
    fn time_span(&self) -> (f64, f64) {
        (0.0, self.params[1])
    }
    fn initial_state(&self, given: &[Option<f64>]) -> Result<Vec<f64>, Failure> {
        Ok(given_or(given, &[1.0, 0.0]))
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
#[derive(Clone, Debug)]
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
        Ok(given_or(given, &[1.0, 0.0]))
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
#[derive(Clone, Debug)]
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
        given_or(overrides, &[10.0])
    }
    fn new(params: &[f64]) -> Self {
        SphericalPendulum {
            params: params.to_vec(),
        }
    }
    fn param_values(&self) -> &[f64] {
        &self.params
    }
    fn time_span(&self) -> (f64, f64) {
        (0.0, self.params[0])
    }
    fn initial_state(&self, given: &[Option<f64>]) -> Result<Vec<f64>, Failure> {
        Ok(given_or(given, &[1.0, 0.0, 0.0, 2.0]))
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

/// `x'' + 1000 x' + x = 0` (stiffness ratio 1e6), x(0) = 1, x'(0) = 0:
/// `x = A e^{r1 t} + B e^{r2 t}`. Affine; its adjoint grows like e^{+1000t}.
#[derive(Clone, Debug)]
pub struct StiffDamped {
    pub params: Vec<f64>,
}

impl StiffDamped {
    pub fn exact_at(t: f64) -> [f64; 2] {
        let (g, w2): (f64, f64) = (1000.0, 1.0);
        let d = (g * g - 4.0 * w2).sqrt();
        let (r1, r2) = ((-g + d) / 2.0, (-g - d) / 2.0);
        let (x0, v0) = (1.0, 0.0);
        let a = (v0 - r2 * x0) / (r1 - r2);
        let b = (r1 * x0 - v0) / (r1 - r2);
        [
            a * (r1 * t).exp() + b * (r2 * t).exp(),
            a * r1 * (r1 * t).exp() + b * r2 * (r2 * t).exp(),
        ]
    }
}

impl Model for StiffDamped {
    const NAME: &'static str = "stiff_damped";
    const SOURCE_HASH: &'static str = "test";
    const PARAMS: &'static [&'static str] = &[];
    const STATE: &'static [&'static str] = &["x", "x'"];
    const COORDINATES: usize = 1;
    const INITIAL: &'static [Initial] = &[Initial::Given, Initial::Given];
    const AFFINE: bool = true;
    const EXACT: bool = true;

    fn parameters(_o: &[Option<f64>]) -> Vec<f64> {
        Vec::new()
    }
    fn new(_p: &[f64]) -> Self {
        StiffDamped { params: Vec::new() }
    }
    fn param_values(&self) -> &[f64] {
        &self.params
    }
    fn time_span(&self) -> (f64, f64) {
        (0.0, 2.0)
    }
    fn initial_state(&self, given: &[Option<f64>]) -> Result<Vec<f64>, Failure> {
        Ok(given_or(given, &[1.0, 0.0]))
    }
    fn rhs(&self, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), Failure> {
        dx[0] = x[1];
        dx[1] = -x[0] - 1000.0 * x[1];
        Ok(())
    }
    fn jacobian(&self, _t: f64, _x: &[f64], jac: &mut Matrix) -> Result<(), Failure> {
        jac[(0, 1)] = 1.0;
        jac[(1, 0)] = -1.0;
        jac[(1, 1)] = -1000.0;
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
        let e = Self::exact_at(t);
        out[0] = Some(e[0]);
        out[1] = Some(e[1]);
    }
}

/// A ball thrown upward against quadratic drag, `z'' = −g − c z'|z'|`,
/// until it lands (`stop when z < 0`): the kink of `|z'|` at the top and
/// the landing are events. g = 9.81, c = 0.05, z(0) = 0, z'(0) = 20.
#[derive(Clone, Debug)]
pub struct ThrownBall {
    pub params: Vec<f64>,
    pub rising: bool,
}

impl ThrownBall {
    pub const G: f64 = 9.81;
    pub const C: f64 = 0.05;
    pub const V0: f64 = 20.0;

    fn k() -> f64 {
        (Self::G * Self::C).sqrt()
    }

    pub fn top_time() -> f64 {
        (Self::V0 * (Self::C / Self::G).sqrt()).atan() / Self::k()
    }

    pub fn top_height() -> f64 {
        (1.0 + Self::C * Self::V0 * Self::V0 / Self::G).ln() / (2.0 * Self::C)
    }

    pub fn landing_time() -> f64 {
        Self::top_time() + (Self::C * Self::top_height()).exp().acosh() / Self::k()
    }

    /// The closed form of both phases.
    pub fn exact_at(t: f64) -> [f64; 2] {
        let (g, c, k) = (Self::G, Self::C, Self::k());
        let vt = (g / c).sqrt();
        let phi = (Self::V0 / vt).atan();
        if t <= Self::top_time() {
            let a = phi - k * t;
            [(a.cos() / phi.cos()).ln() / c, vt * a.tan()]
        } else {
            let s = k * (t - Self::top_time());
            [Self::top_height() - s.cosh().ln() / c, -vt * s.tanh()]
        }
    }
}

impl Model for ThrownBall {
    const NAME: &'static str = "thrown_ball";
    const SOURCE_HASH: &'static str = "test";
    const PARAMS: &'static [&'static str] = &[];
    const STATE: &'static [&'static str] = &["z", "z'"];
    const COORDINATES: usize = 1;
    const INITIAL: &'static [Initial] = &[Initial::Given, Initial::Given];
    const SWITCHES: usize = 2;
    const EXACT: bool = true;

    fn parameters(_o: &[Option<f64>]) -> Vec<f64> {
        Vec::new()
    }
    fn new(_p: &[f64]) -> Self {
        ThrownBall {
            params: Vec::new(),
            rising: true,
        }
    }
    fn param_values(&self) -> &[f64] {
        &self.params
    }
    fn time_span(&self) -> (f64, f64) {
        (0.0, 10.0)
    }
    fn initial_state(&self, given: &[Option<f64>]) -> Result<Vec<f64>, Failure> {
        Ok(given_or(given, &[0.0, Self::V0]))
    }
    fn set_regime(&mut self, regime: &lagc_runtime::model::Regime) {
        self.rising = regime.branches[0];
    }
    fn rhs(&self, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), Failure> {
        let v = x[1];
        let abs_v = if self.rising { v } else { -v };
        dx[0] = v;
        dx[1] = -Self::G - Self::C * v * abs_v;
        Ok(())
    }
    fn jacobian(&self, _t: f64, x: &[f64], jac: &mut Matrix) -> Result<(), Failure> {
        let sign = if self.rising { 1.0 } else { -1.0 };
        jac[(0, 1)] = 1.0;
        jac[(1, 1)] = -2.0 * Self::C * sign * x[1];
        Ok(())
    }
    fn time_partial(&self, _t: f64, _x: &[f64], _dxdt: &mut [f64]) -> Result<(), Failure> {
        Ok(())
    }
    fn switching_functions(&self, _t: f64, x: &[f64], g: &mut [f64]) {
        g[0] = x[1];
        g[1] = x[0];
    }
    fn stop(&self, branches: &[bool]) -> bool {
        !branches[1]
    }
    fn exact(&self, t: f64, out: &mut [Option<f64>]) {
        let e = Self::exact_at(t);
        out[0] = Some(e[0]);
        out[1] = Some(e[1]);
    }
}

/// A knife edge turning at a constant rate through every heading, with the
/// implicit constraint `sin(th) x' = cos(th) y'` and two candidates for the
/// dependent derivative (`y'`: mode 0; `x'`: mode 1). Speed v = 1,
/// th = t: `x = sin t`, `y = 1 − cos t`.
#[derive(Clone, Debug)]
pub struct KnifeEdge {
    pub params: Vec<f64>,
    pub mode: usize,
}

impl KnifeEdge {
    pub fn exact_at(t: f64) -> [f64; 6] {
        [t.sin(), 1.0 - t.cos(), t, t.cos(), t.sin(), 1.0]
    }
}

impl Model for KnifeEdge {
    const NAME: &'static str = "knife_edge_turning";
    const SOURCE_HASH: &'static str = "test";
    const PARAMS: &'static [&'static str] = &[];
    const STATE: &'static [&'static str] = &["x", "y", "th", "x'", "y'", "th'"];
    const COORDINATES: usize = 3;
    const INITIAL: &'static [Initial] = &[
        Initial::Given,
        Initial::Given,
        Initial::Given,
        Initial::Given,
        Initial::Constraint,
        Initial::Given,
    ];
    const CONSTRAINTS: &'static [lagc_runtime::model::Candidates] =
        &[lagc_runtime::model::Candidates {
            text: "sin(th) * x' = cos(th) * y'",
            names: &["y'", "x'"],
        }];
    const EXACT: bool = true;

    fn parameters(_o: &[Option<f64>]) -> Vec<f64> {
        Vec::new()
    }
    fn new(_p: &[f64]) -> Self {
        KnifeEdge {
            params: Vec::new(),
            mode: 0,
        }
    }
    fn param_values(&self) -> &[f64] {
        &self.params
    }
    fn time_span(&self) -> (f64, f64) {
        (0.0, 10.0)
    }
    fn initial_state(&self, given: &[Option<f64>]) -> Result<Vec<f64>, Failure> {
        let e = Self::exact_at(0.0);
        let mut x = given_or(given, &e[..6]);
        x[4] = x[2].tan() * x[3];
        Ok(x)
    }
    fn set_regime(&mut self, regime: &lagc_runtime::model::Regime) {
        self.mode = regime.mode;
    }
    fn rhs(&self, _t: f64, s: &[f64], dx: &mut [f64]) -> Result<(), Failure> {
        let (th, xd, yd, thd) = (s[2], s[3], s[4], s[5]);
        dx[0] = xd;
        dx[1] = yd;
        dx[2] = thd;
        dx[5] = 0.0;
        if self.mode == 0 {
            let x2 = -th.tan() * thd * xd;
            dx[3] = x2;
            dx[4] = thd * xd / th.cos().powi(2) + th.tan() * x2;
        } else {
            let y2 = thd * yd / th.tan();
            dx[4] = y2;
            dx[3] = -thd * yd / th.sin().powi(2) + y2 / th.tan();
        }
        Ok(())
    }
    fn jacobian(&self, t: f64, s: &[f64], jac: &mut Matrix) -> Result<(), Failure> {
        // Central differences are enough for a test model's Jacobian.
        let mut plus = [0.0; 6];
        let mut minus = [0.0; 6];
        let mut x = s.to_vec();
        for k in 0..6 {
            let h = 1e-6 * s[k].abs().max(1.0);
            x[k] = s[k] + h;
            self.rhs(t, &x, &mut plus)?;
            x[k] = s[k] - h;
            self.rhs(t, &x, &mut minus)?;
            x[k] = s[k];
            for i in 0..6 {
                jac[(i, k)] = (plus[i] - minus[i]) / (2.0 * h);
            }
        }
        Ok(())
    }
    fn time_partial(&self, _t: f64, _x: &[f64], _dxdt: &mut [f64]) -> Result<(), Failure> {
        Ok(())
    }
    fn pivots(&self, _t: f64, x: &[f64], out: &mut [f64]) {
        out[0] = -x[2].cos();
        out[1] = x[2].sin();
    }
    fn exact(&self, t: f64, out: &mut [Option<f64>]) {
        for (o, e) in out.iter_mut().zip(Self::exact_at(t)) {
            *o = Some(e);
        }
    }
}

/// The double pendulum (unit masses and lengths, g = 9.81) in angles `a`,
/// `b`, through its mass matrix `[[2, cos Δ], [cos Δ, 1]]` as generated
/// code does it, with the exact Jacobian by implicit differentiation.
/// a(0) = 1, b(0) = 0.5, at rest; t ∈ [0, 10].
#[derive(Clone, Debug)]
pub struct DoublePendulum {
    pub params: Vec<f64>,
}

impl DoublePendulum {
    const G: f64 = 9.81;

    fn accelerations(x: &[f64]) -> ([f64; 2], [[f64; 2]; 2], [f64; 2]) {
        let (a, b, ad, bd) = (x[0], x[1], x[2], x[3]);
        let (s, c) = (a - b).sin_cos();
        let m = [[2.0, c], [c, 1.0]];
        let f = [
            -s * bd * bd - 2.0 * Self::G * a.sin(),
            s * ad * ad - Self::G * b.sin(),
        ];
        let det = 2.0 - c * c;
        let z = [
            (f[0] * m[1][1] - m[0][1] * f[1]) / det,
            (m[0][0] * f[1] - m[1][0] * f[0]) / det,
        ];
        (z, m, f)
    }

    pub fn energy(x: &[f64]) -> f64 {
        let (a, b, ad, bd) = (x[0], x[1], x[2], x[3]);
        ad * ad + 0.5 * bd * bd + ad * bd * (a - b).cos() - Self::G * (2.0 * a.cos() + b.cos())
    }
}

impl Model for DoublePendulum {
    const NAME: &'static str = "double_pendulum";
    const SOURCE_HASH: &'static str = "test";
    const PARAMS: &'static [&'static str] = &["T"];
    const STATE: &'static [&'static str] = &["a", "b", "a'", "b'"];
    const COORDINATES: usize = 2;
    const INITIAL: &'static [Initial] = &[Initial::Given; 4];

    fn parameters(overrides: &[Option<f64>]) -> Vec<f64> {
        given_or(overrides, &[10.0])
    }
    fn new(params: &[f64]) -> Self {
        DoublePendulum {
            params: params.to_vec(),
        }
    }
    fn param_values(&self) -> &[f64] {
        &self.params
    }
    fn time_span(&self) -> (f64, f64) {
        (0.0, self.params[0])
    }
    fn initial_state(&self, given: &[Option<f64>]) -> Result<Vec<f64>, Failure> {
        Ok(given_or(given, &[1.0, 0.5, 0.0, 0.0]))
    }
    fn rhs(&self, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), Failure> {
        let (z, _, _) = Self::accelerations(x);
        dx[0] = x[2];
        dx[1] = x[3];
        dx[2] = z[0];
        dx[3] = z[1];
        Ok(())
    }
    fn jacobian(&self, _t: f64, x: &[f64], jac: &mut Matrix) -> Result<(), Failure> {
        let (z, m, _) = Self::accelerations(x);
        let (a, b, ad, bd) = (x[0], x[1], x[2], x[3]);
        let (s, c) = (a - b).sin_cos();
        // ∂f/∂x and ∂M/∂x · z, columns a, b, a', b'.
        let df = [
            [
                -c * bd * bd - 2.0 * Self::G * a.cos(),
                c * bd * bd,
                0.0,
                -2.0 * s * bd,
            ],
            [
                c * ad * ad,
                -c * ad * ad - Self::G * b.cos(),
                2.0 * s * ad,
                0.0,
            ],
        ];
        let dmz = [
            [-s * z[1], s * z[1], 0.0, 0.0],
            [-s * z[0], s * z[0], 0.0, 0.0],
        ];
        let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
        jac[(0, 2)] = 1.0;
        jac[(1, 3)] = 1.0;
        for k in 0..4 {
            let r = [df[0][k] - dmz[0][k], df[1][k] - dmz[1][k]];
            jac[(2, k)] = (r[0] * m[1][1] - m[0][1] * r[1]) / det;
            jac[(3, k)] = (m[0][0] * r[1] - m[1][0] * r[0]) / det;
        }
        Ok(())
    }
    fn linearize(
        &self,
        t: f64,
        x: &[f64],
        dx: &mut [f64],
        jac: &mut Matrix,
    ) -> Result<(), Failure> {
        self.rhs(t, x, dx)?;
        self.jacobian(t, x, jac)
    }
    fn time_partial(&self, _t: f64, _x: &[f64], _dxdt: &mut [f64]) -> Result<(), Failure> {
        Ok(())
    }
}

/// `M x'' = −k x` with `M = 10 − t`: the mass reaches zero at t = 10 (the
/// span runs to 12).
#[derive(Clone, Debug)]
pub struct VanishingMass {
    pub params: Vec<f64>,
}

impl Model for VanishingMass {
    const NAME: &'static str = "vanishing_mass";
    const SOURCE_HASH: &'static str = "test";
    const PARAMS: &'static [&'static str] = &[];
    const STATE: &'static [&'static str] = &["x", "x'"];
    const COORDINATES: usize = 1;
    const INITIAL: &'static [Initial] = &[Initial::Given, Initial::Given];
    const MASSES: &'static [&'static str] = &["M"];

    fn parameters(_o: &[Option<f64>]) -> Vec<f64> {
        Vec::new()
    }
    fn new(_p: &[f64]) -> Self {
        VanishingMass { params: Vec::new() }
    }
    fn param_values(&self) -> &[f64] {
        &self.params
    }
    fn time_span(&self) -> (f64, f64) {
        (0.0, 12.0)
    }
    fn initial_state(&self, given: &[Option<f64>]) -> Result<Vec<f64>, Failure> {
        Ok(given_or(given, &[1.0, 0.0]))
    }
    fn rhs(&self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), Failure> {
        dx[0] = x[1];
        dx[1] = -x[0] / (10.0 - t);
        Ok(())
    }
    fn jacobian(&self, t: f64, _x: &[f64], jac: &mut Matrix) -> Result<(), Failure> {
        jac[(0, 1)] = 1.0;
        jac[(1, 0)] = -1.0 / (10.0 - t);
        Ok(())
    }
    fn time_partial(&self, t: f64, x: &[f64], dxdt: &mut [f64]) -> Result<(), Failure> {
        dxdt[1] = -x[0] / (10.0 - t).powi(2);
        Ok(())
    }
    fn masses(&self, t: f64, out: &mut [f64]) {
        out[0] = 10.0 - t;
    }
}

/// Cayley's chain thrown back onto its heap: `x'' = g − x'^2/x` with the
/// mass of the state `M = rho x` (`g = 9.81`, `rho = 2`), from `x = 1`,
/// `x' = −3`. With `x² x'² = 2g x³/3 + 2C` the chain is back on the heap,
/// `M = 0`, at `t* = ∫_0^1 x dx / √(2g x³/3 + 2C) = 0.23531632015820`
/// (`C = 1.23`; SciPy's quad). The span runs to 1.
#[derive(Clone, Debug)]
pub struct ChainOntoHeap {
    pub params: Vec<f64>,
}

impl ChainOntoHeap {
    pub const T_STAR: f64 = 0.235_316_320_158_2;
}

impl Model for ChainOntoHeap {
    const NAME: &'static str = "chain_onto_heap";
    const SOURCE_HASH: &'static str = "test";
    const PARAMS: &'static [&'static str] = &[];
    const STATE: &'static [&'static str] = &["x", "x'"];
    const COORDINATES: usize = 1;
    const INITIAL: &'static [Initial] = &[Initial::Given, Initial::Given];
    const MASSES: &'static [&'static str] = &["M"];

    fn parameters(_o: &[Option<f64>]) -> Vec<f64> {
        Vec::new()
    }
    fn new(_p: &[f64]) -> Self {
        ChainOntoHeap { params: Vec::new() }
    }
    fn param_values(&self) -> &[f64] {
        &self.params
    }
    fn time_span(&self) -> (f64, f64) {
        (0.0, 1.0)
    }
    fn initial_state(&self, given: &[Option<f64>]) -> Result<Vec<f64>, Failure> {
        Ok(given_or(given, &[1.0, -3.0]))
    }
    fn rhs(&self, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), Failure> {
        dx[0] = x[1];
        dx[1] = 9.81 - x[1] * x[1] / x[0];
        Ok(())
    }
    fn jacobian(&self, _t: f64, x: &[f64], jac: &mut Matrix) -> Result<(), Failure> {
        jac[(0, 1)] = 1.0;
        jac[(1, 0)] = x[1] * x[1] / (x[0] * x[0]);
        jac[(1, 1)] = -2.0 * x[1] / x[0];
        Ok(())
    }
    fn time_partial(&self, _t: f64, _x: &[f64], dxdt: &mut [f64]) -> Result<(), Failure> {
        dxdt.fill(0.0);
        Ok(())
    }
    fn masses_at(&self, _t: f64, x: &[f64], out: &mut [f64]) {
        out[0] = 2.0 * x[0];
    }
}
