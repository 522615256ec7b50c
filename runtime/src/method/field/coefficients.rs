//! Coefficient systems of the field method and their sensitivities, as one
//! first-order system `y = (f, S)` (SPEC §1.5): `f' = F(t, f)`,
//! `S' = (∂F/∂f) S`, `S = ∂f/∂c` stored column by column.
//!
//! Two sources of `F`:
//! - [`SymbolicCoefficients`]: the model's own coefficient system, derived
//!   symbolically by lagc for an affine reduced system (the field method
//!   proper);
//! - [`LinearizedCoefficients`]: the coefficient system of the motion
//!   linearised along an iterate `x^k(t)`, `x' = A(t) x + b(t)` with
//!   `A = ∂X/∂x (t, x^k)`, `b = X(t, x^k) − A x^k`, by SPEC's formulas
//!   `f_1' = b_1 − Σ_A f_A b_A + λ f_1`, `f_B' = a_1B − Σ_A f_A a_AB + λ f_B`,
//!   `λ = a_11 − Σ_A f_A a_A1` (the quasilinear field method).

use crate::failure::Failure;
use crate::linalg::Matrix;
use crate::model::DynModel;
use crate::ode::system::System;
use std::cell::RefCell;

/// A first-order system whose state `y` represents the field's
/// coefficients `f` and sensitivities `S` (directly, or in the projective
/// form of [`ProjectiveCoefficients`]).
pub trait FieldSystem: System {
    /// The number of coefficients `N` (the motion's state dimension).
    fn coefficients(&self) -> usize;
    /// `y` at an anchor `c` (`f = c`, `S = I`).
    fn anchored(&self, c: &[f64]) -> Vec<f64>;
    /// `f` and `S` from `y`, and the factor by which computing them
    /// amplified rounding (1 when `y` holds them directly); `None` where
    /// they are not defined (a pole).
    fn field(&self, y: &[f64], f: &mut [f64], s: &mut [f64]) -> Option<f64>;
    /// The first-order change `(df, ds)` of `(f, S)` for a change `dy` of
    /// `y` at `y`.
    fn field_change(&self, y: &[f64], dy: &[f64], df: &mut [f64], ds: &mut [f64]);

    /// Bounds of the rounding errors of `f` and `S` as computed from `y`,
    /// entry by entry (`field` must have been called on `y`, with its
    /// results in `f` and `s`).
    fn rounding(&self, _y: &[f64], f: &[f64], s: &[f64], df: &mut [f64], ds: &mut [f64]) {
        for (d, v) in df.iter_mut().zip(f) {
            *d = f64::EPSILON * v.abs();
        }
        for (d, v) in ds.iter_mut().zip(s) {
            *d = f64::EPSILON * v.abs();
        }
    }

    /// Bounds of the rounding of the conditions' right sides that `field`'s
    /// factor leaves out, into `dr[a]` for `a ≥ 1` (the rounding of
    /// `S_1A = ∂f_1/∂c_A`, A = a + 1, in the units of `x_A`; `dr[0]` is
    /// not read), and `true`; `false` (the default) where the factor counts
    /// every entry (`y` holds `(f, S)` directly).
    fn free_term_rounding(&self, _y: &[f64], _dr: &mut [f64]) -> bool {
        false
    }

    /// `B(t)` of `y' = B(t) y` viewed as `Y' = B Y` (`Y` the `(N+1)²` state
    /// as a square matrix), when the representation is linear so (the
    /// projective form); `None` otherwise.
    fn generator(&self, _t: f64, _b: &mut Matrix) -> Option<Result<(), Failure>> {
        None
    }

    /// `y` is the projective form `(w, P)` rather than `(f, S)`.
    fn is_projective(&self) -> bool {
        false
    }

    /// A window of this system retries a step the rounding watch declined
    /// at the fraction of the step where the watch's ratio reaches 0.9 of
    /// its limit, and ends after that retry (`window.rs`, `Window::step`);
    /// `false`: a quarter, as before. The quasilinear field's windows
    /// (each a predictor and its linearisations: a fresh window costs
    /// more); the affine field's re-anchor in place, and there the fitted
    /// retry moved the steps under the samples of a bead in a spinning
    /// tube at rtol 1e-8 from 0.43 to 1.8 rtol off (h-stiff3).
    fn fits_retry(&self) -> bool {
        false
    }

    /// `y` for the anchor's free term `c_1` moved by `delta` (exact: `f` is
    /// affine in `c_1` for an affine motion, and the other coefficients do
    /// not depend on it) — another initial state through the same field.
    fn shift_free_term(&self, y: &mut [f64], delta: f64);
}

/// A coefficient system with the product of its Jacobian and `S`.
pub trait CoefficientSource {
    /// `N`, the number of coefficients (the state dimension).
    fn dim(&self) -> usize;

    /// `df = F(t, f)` and `ds = (∂F/∂f)(t, f) · S`.
    fn augmented(
        &self,
        t: f64,
        f: &[f64],
        s: &[f64],
        df: &mut [f64],
        ds: &mut [f64],
    ) -> Result<(), Failure>;

    /// `∂F/∂f` (sized and zeroed by the caller), for a stiff integrator.
    fn jacobian(&self, t: f64, f: &[f64], jac: &mut Matrix) -> Result<(), Failure>;

    /// `F` is affine in `f` (then `∂F/∂f` does not depend on `f`).
    fn is_linear(&self) -> bool;
}

/// `y = (f, S)` as a [`System`] for the integrators.
pub struct Augmented<'a, C: CoefficientSource + ?Sized>(pub &'a C);

impl<C: CoefficientSource + ?Sized> Augmented<'_, C> {
    /// The augmented state at an anchor `c`: `f = c`, `S = I`.
    pub fn anchored(c: &[f64]) -> Vec<f64> {
        let n = c.len();
        let mut y = vec![0.0; n + n * n];
        y[..n].copy_from_slice(c);
        for i in 0..n {
            y[n + i * n + i] = 1.0;
        }
        y
    }
}

impl<C: CoefficientSource + ?Sized> System for Augmented<'_, C> {
    fn dim(&self) -> usize {
        let n = self.0.dim();
        n + n * n
    }

    fn rhs(&self, t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), Failure> {
        let n = self.0.dim();
        let (f, s) = y.split_at(n);
        let (df, ds) = dy.split_at_mut(n);
        self.0.augmented(t, f, s, df, ds)
    }

    /// Block diagonal: `∂F/∂f` for `f` and for every column of `S` — exact
    /// for a linear coefficient system only, where `∂(JS)/∂f = 0`.
    fn jacobian(&self, t: f64, y: &[f64], jac: &mut Matrix) -> Result<(), Failure> {
        let n = self.0.dim();
        let mut block = Matrix::zeros(n, n);
        self.0.jacobian(t, &y[..n], &mut block)?;
        for k in 0..=n {
            for j in 0..n {
                for i in 0..n {
                    jac[(k * n + i, k * n + j)] = block[(i, j)];
                }
            }
        }
        Ok(())
    }

    /// By central differences: used only by the stiff integrator of a
    /// linear coefficient system, once per step.
    fn time_partial(&self, t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), Failure> {
        central_time_partial(self, t, y, dydt)
    }

    /// The coefficients are named for what they are to the motion: a
    /// failure of the field is reported in terms of the state.
    fn component_name(&self, i: usize) -> String {
        let n = self.0.dim();
        if i < n {
            format!("the field coefficient f{}", i + 1)
        } else {
            let k = i - n;
            format!("the field sensitivity S{}{}", k % n + 1, k / n + 1)
        }
    }
}

impl<C: CoefficientSource + ?Sized> FieldSystem for Augmented<'_, C> {
    fn coefficients(&self) -> usize {
        self.0.dim()
    }

    fn anchored(&self, c: &[f64]) -> Vec<f64> {
        Augmented::<C>::anchored(c)
    }

    fn field(&self, y: &[f64], f: &mut [f64], s: &mut [f64]) -> Option<f64> {
        let n = f.len();
        f.copy_from_slice(&y[..n]);
        s.copy_from_slice(&y[n..]);
        Some(1.0)
    }

    fn field_change(&self, _y: &[f64], dy: &[f64], df: &mut [f64], ds: &mut [f64]) {
        let n = df.len();
        df.copy_from_slice(&dy[..n]);
        ds.copy_from_slice(&dy[n..]);
    }

    /// Used only with a linear coefficient system, where `S` does not
    /// depend on the anchor and `f_1` moves by `S_11 δc_1`.
    fn shift_free_term(&self, y: &mut [f64], delta: f64) {
        let n = self.0.dim();
        y[0] += delta * y[n];
    }
}

/// The model's symbolic coefficient system (affine models).
pub struct SymbolicCoefficients<'a> {
    model: &'a dyn DynModel,
    scratch: RefCell<Matrix>,
}

impl<'a> SymbolicCoefficients<'a> {
    pub fn new(model: &'a dyn DynModel) -> Self {
        let n = model.dim();
        SymbolicCoefficients {
            model,
            scratch: RefCell::new(Matrix::zeros(n, n)),
        }
    }
}

impl CoefficientSource for SymbolicCoefficients<'_> {
    fn dim(&self) -> usize {
        self.model.dim()
    }

    fn augmented(
        &self,
        t: f64,
        f: &[f64],
        s: &[f64],
        df: &mut [f64],
        ds: &mut [f64],
    ) -> Result<(), Failure> {
        let n = f.len();
        self.model.coefficients(t, f, df)?;
        let mut jac = self.scratch.borrow_mut();
        jac.fill(0.0);
        self.model.coefficient_jacobian(t, f, &mut jac)?;
        // ds = J S, column by column, skipping zero entries of J (the
        // coefficient systems of mechanics are sparse).
        ds.fill(0.0);
        for k in 0..n {
            let column = jac.column(k);
            for j in 0..n {
                let skj = s[j * n + k];
                if skj == 0.0 {
                    continue;
                }
                let target = &mut ds[j * n..(j + 1) * n];
                for (t, &a) in target.iter_mut().zip(column) {
                    *t += a * skj;
                }
            }
        }
        Ok(())
    }

    fn jacobian(&self, t: f64, f: &[f64], jac: &mut Matrix) -> Result<(), Failure> {
        self.model.coefficient_jacobian(t, f, jac)
    }

    fn is_linear(&self) -> bool {
        self.model.coefficients_linear()
    }
}

/// An iterate `x^k(t)` of the motion over a window, for the linearisation.
pub trait Iterate {
    fn eval(&self, t: f64, out: &mut [f64]) -> Result<(), Failure>;

    /// The iterate is `x = 0` at every time (an affine motion's: any state
    /// serves), so `b = X(t, 0)` needs no product with `A`.
    fn is_origin(&self) -> bool {
        false
    }
}

/// The buffers of one linearisation; a solver that builds its field
/// system at every step keeps one and lends it ([`ProjectiveCoefficients::
/// with_scratch`]) rather than allocating seven buffers a step.
pub struct LinearizationScratch {
    x: Vec<f64>,
    rate: Vec<f64>,
    b: Vec<f64>,
    a: Matrix,
    g: Vec<f64>,
    r: Vec<f64>,
    /// For the projective form's rates (`adjoint_rates`): its vectors
    /// `w_x` as rows (entry `i` of vector `k` at `i·N + k`, `N²` numbers)
    /// and one running sum per vector (`N` more).
    batch: Vec<f64>,
    /// The time (its bits) at which `x`, `rate` and `a` were evaluated,
    /// and at which `b` was formed from them: DOP853 evaluates twice at
    /// the step's end (its last stage, `c = 1`, and the rate at the new
    /// state), and the iterate and the model give the same bits again.
    evaluated_at: Option<u64>,
    formed_at: Option<u64>,
    /// `x` holds the origin, written by an iterate that is the origin at
    /// every time (an affine motion's): not written again at every stage.
    x_origin: bool,
    /// The model (its address, as a number: the buffers stay `Send`)
    /// whose frozen linearisation (see `LinearizedCoefficients::frozen`)
    /// the buffers hold, for a system built on them again
    /// ([`ProjectiveCoefficients::with_kept_scratch`]).
    frozen_model: Option<usize>,
}

impl LinearizationScratch {
    pub fn new(n: usize) -> RefCell<LinearizationScratch> {
        RefCell::new(LinearizationScratch {
            x: vec![0.0; n],
            rate: vec![0.0; n],
            b: vec![0.0; n],
            a: Matrix::zeros(n, n),
            g: vec![0.0; n],
            r: vec![0.0; n],
            batch: vec![0.0; n * (n + 1)],
            evaluated_at: None,
            formed_at: None,
            x_origin: false,
            frozen_model: None,
        })
    }

    /// Forgets what the buffers hold (a kept frozen linearisation
    /// included): the next system evaluates afresh.
    pub fn forget(&mut self) {
        self.evaluated_at = None;
        self.formed_at = None;
        self.frozen_model = None;
    }
}

/// The address of `model`, to tell whether buffers hold its linearisation.
fn model_address(model: &dyn DynModel) -> usize {
    model as *const dyn DynModel as *const () as usize
}

/// A linearisation's buffers, its own or lent. Not boxed: one value per
/// system, and a box would be one more allocation for each.
#[allow(clippy::large_enum_variant)]
enum Scratch<'a> {
    Owned(RefCell<LinearizationScratch>),
    Lent(&'a RefCell<LinearizationScratch>),
}

impl Scratch<'_> {
    fn borrow_mut(&self) -> std::cell::RefMut<'_, LinearizationScratch> {
        match self {
            Scratch::Owned(cell) => cell.borrow_mut(),
            Scratch::Lent(cell) => cell.borrow_mut(),
        }
    }
}

/// The coefficient system of the motion linearised along an iterate.
pub struct LinearizedCoefficients<'a, I: Iterate + ?Sized> {
    model: &'a dyn DynModel,
    iterate: &'a I,
    scratch: Scratch<'a>,
    evaluations: std::cell::Cell<usize>,
    /// The linearisation is the same at every time: an autonomous model
    /// ([`crate::model::Model::AUTONOMOUS`]) linearised at the origin at
    /// every time (an affine motion's iterate). Its `A` and `b` are then
    /// evaluated once per system rather than at every stage (the same
    /// numbers: the model's `linearize` does not read `t`); 10 of the
    /// 12 evaluations of a DOP853 step of an oscillator's field.
    frozen: bool,
}

impl<'a, I: Iterate + ?Sized> LinearizedCoefficients<'a, I> {
    pub fn new(model: &'a dyn DynModel, iterate: &'a I) -> Self {
        LinearizedCoefficients {
            model,
            iterate,
            scratch: Scratch::Owned(LinearizationScratch::new(model.dim())),
            evaluations: std::cell::Cell::new(0),
            frozen: model.autonomous() && iterate.is_origin(),
        }
    }

    /// [`LinearizedCoefficients::new`] on lent buffers (of the model's
    /// size). Another system (iterate) on the same buffers: nothing in
    /// them holds for it.
    fn lent(
        model: &'a dyn DynModel,
        iterate: &'a I,
        scratch: &'a RefCell<LinearizationScratch>,
    ) -> Self {
        Self::lent_keeping(model, iterate, scratch, false)
    }

    /// [`LinearizedCoefficients::lent`]; with `keep`, a frozen
    /// linearisation of the same model that the buffers hold is kept
    /// (the caller builds every system on them from the same model and
    /// an iterate at the origin, and forgets them where that may change).
    fn lent_keeping(
        model: &'a dyn DynModel,
        iterate: &'a I,
        scratch: &'a RefCell<LinearizationScratch>,
        keep: bool,
    ) -> Self {
        let frozen = model.autonomous() && iterate.is_origin();
        {
            let mut sc = scratch.borrow_mut();
            let kept = keep && frozen && sc.frozen_model == Some(model_address(model));
            if !kept {
                sc.forget();
            }
        }
        LinearizedCoefficients {
            model,
            iterate,
            scratch: Scratch::Lent(scratch),
            evaluations: std::cell::Cell::new(0),
            frozen,
        }
    }

    /// How many linearisations (`X` with `∂X/∂x`) were evaluated.
    pub fn linearizations(&self) -> usize {
        self.evaluations.get()
    }

    /// The iterate `x0`, `X(t, x0)` and `A = ∂X/∂x (t, x0)` at `t`, into
    /// the scratch.
    fn evaluate(&self, t: f64, sc: &mut LinearizationScratch) -> Result<(), Failure> {
        if sc.evaluated_at == Some(t.to_bits()) || (self.frozen && sc.evaluated_at.is_some()) {
            return Ok(());
        }
        sc.evaluated_at = None;
        sc.formed_at = None;
        if !(sc.x_origin && self.iterate.is_origin()) {
            self.iterate.eval(t, &mut sc.x)?;
            sc.x_origin = self.iterate.is_origin();
        }
        sc.a.fill(0.0);
        self.model.linearize(t, &sc.x, &mut sc.rate, &mut sc.a)?;
        self.evaluations.set(self.evaluations.get() + 1);
        sc.evaluated_at = Some(t.to_bits());
        sc.frozen_model = self.frozen.then(|| model_address(self.model));
        Ok(())
    }

    /// `A` and `b` at `t`, into the scratch.
    fn linearize(&self, t: f64, sc: &mut LinearizationScratch) -> Result<(), Failure> {
        self.evaluate(t, sc)?;
        if sc.formed_at == Some(t.to_bits()) || (self.frozen && sc.formed_at.is_some()) {
            return Ok(());
        }
        if self.iterate.is_origin() {
            sc.b.copy_from_slice(&sc.rate);
        } else {
            // b = X − A x
            sc.a.mul_vec(&sc.x, &mut sc.b);
            for (b, r) in sc.b.iter_mut().zip(&sc.rate) {
                *b = r - *b;
            }
        }
        sc.formed_at = Some(t.to_bits());
        Ok(())
    }
}

/// `out_B = Σ_i a_iB g_i` (`Aᵀ g`), with the first `N − n` rows of `A` the
/// shifts `x_i' = x_{i+n}` (`a_{i,i+n} = 1`), which are not read.
fn transpose_times(a: &Matrix, g: &[f64], shift: usize, out: &mut [f64]) {
    let n = g.len();
    let shifted = n - shift;
    for (b, o) in out.iter_mut().enumerate() {
        let column = a.column(b);
        let mut v: f64 = column[shifted..]
            .iter()
            .zip(&g[shifted..])
            .map(|(x, y)| x * y)
            .sum();
        if b >= shift {
            v += g[b - shift];
        }
        *o = v;
    }
}

impl<I: Iterate + ?Sized> CoefficientSource for LinearizedCoefficients<'_, I> {
    fn dim(&self) -> usize {
        self.model.dim()
    }

    fn augmented(
        &self,
        t: f64,
        f: &[f64],
        s: &[f64],
        df: &mut [f64],
        ds: &mut [f64],
    ) -> Result<(), Failure> {
        let n = f.len();
        let shift = self.model.coordinates();
        let mut guard = self.scratch.borrow_mut();
        let sc = &mut *guard;
        self.linearize(t, sc)?;
        // g = (1, −f_2..−f_N); r = Aᵀ g; λ = r_1.
        sc.g[0] = 1.0;
        for a in 1..n {
            sc.g[a] = -f[a];
        }
        transpose_times(&sc.a, &sc.g, shift, &mut sc.r);
        let lambda = sc.r[0];
        let gb: f64 = sc.g.iter().zip(&sc.b).map(|(x, y)| x * y).sum();
        df[0] = gb + lambda * f[0];
        for b in 1..n {
            df[b] = sc.r[b] + lambda * f[b];
        }
        // For each column v of S: δg = (0, −v_2..), δr = Aᵀ δg,
        // δλ = δr_1, δF_1 = δg·b + δλ f_1 + λ v_1,
        // δF_B = δr_B + δλ f_B + λ v_B.
        for j in 0..n {
            let v = &s[j * n..(j + 1) * n];
            sc.g[0] = 0.0;
            for a in 1..n {
                sc.g[a] = -v[a];
            }
            transpose_times(&sc.a, &sc.g, shift, &mut sc.r);
            let d_lambda = sc.r[0];
            let dgb: f64 = sc.g.iter().zip(&sc.b).map(|(x, y)| x * y).sum();
            let out = &mut ds[j * n..(j + 1) * n];
            out[0] = dgb + d_lambda * f[0] + lambda * v[0];
            for b in 1..n {
                out[b] = sc.r[b] + d_lambda * f[b] + lambda * v[b];
            }
        }
        Ok(())
    }

    fn jacobian(&self, t: f64, f: &[f64], jac: &mut Matrix) -> Result<(), Failure> {
        let n = f.len();
        let mut guard = self.scratch.borrow_mut();
        let sc = &mut *guard;
        self.linearize(t, sc)?;
        let a = &sc.a;
        let lambda = a[(0, 0)] - (1..n).map(|k| f[k] * a[(k, 0)]).sum::<f64>();
        jac[(0, 0)] = lambda;
        for k in 1..n {
            jac[(0, k)] = -sc.b[k] - a[(k, 0)] * f[0];
        }
        for row in 1..n {
            for k in 1..n {
                jac[(row, k)] = -a[(k, row)] - a[(k, 0)] * f[row];
            }
            jac[(row, row)] += lambda;
        }
        Ok(())
    }

    fn is_linear(&self) -> bool {
        false
    }
}

/// The motion linearised along an iterate, `x' = A(t) x + b(t)`, as a
/// system of the state: the field's solution satisfies it exactly, so one
/// step of it between two recovered states gives the field's output
/// between them (`dop853::dense_step_between`).
pub struct LinearizedMotion<'a, I: Iterate + ?Sized> {
    linear: LinearizedCoefficients<'a, I>,
}

impl<'a, I: Iterate + ?Sized> LinearizedMotion<'a, I> {
    pub fn new(model: &'a dyn DynModel, iterate: &'a I) -> Self {
        LinearizedMotion {
            linear: LinearizedCoefficients::new(model, iterate),
        }
    }

    /// [`LinearizedMotion::new`] on lent buffers (of the model's size):
    /// the field's output between steps builds one at every step output
    /// asks for.
    pub fn with_scratch(
        model: &'a dyn DynModel,
        iterate: &'a I,
        scratch: &'a RefCell<LinearizationScratch>,
    ) -> Self {
        LinearizedMotion {
            linear: LinearizedCoefficients::lent(model, iterate, scratch),
        }
    }

    pub fn linearizations(&self) -> usize {
        self.linear.linearizations()
    }
}

impl<I: Iterate + ?Sized> System for LinearizedMotion<'_, I> {
    fn dim(&self) -> usize {
        self.linear.model.dim()
    }

    fn rhs(&self, t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), Failure> {
        let mut guard = self.linear.scratch.borrow_mut();
        let sc = &mut *guard;
        self.linear.evaluate(t, sc)?;
        // X(t, x0) + A (x − x0): one product, not two (b = X − A x0 first).
        for ((g, x), x0) in sc.g.iter_mut().zip(y).zip(&sc.x) {
            *g = x - x0;
        }
        sc.a.mul_vec(&sc.g, dy);
        for (d, r) in dy.iter_mut().zip(&sc.rate) {
            *d += r;
        }
        Ok(())
    }

    fn jacobian(&self, t: f64, _y: &[f64], jac: &mut Matrix) -> Result<(), Failure> {
        let mut guard = self.linear.scratch.borrow_mut();
        let sc = &mut *guard;
        self.linear.evaluate(t, sc)?;
        jac.as_mut_slice().copy_from_slice(sc.a.as_slice());
        Ok(())
    }

    fn time_partial(&self, t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), Failure> {
        central_time_partial(self, t, y, dydt)
    }

    fn component_name(&self, i: usize) -> String {
        crate::ode::system::ModelSystem(self.linear.model).component_name(i)
    }
}

/// The coefficient system in projective (linear) form: the field's
/// hyperplane `f_1 + Σ_A f_A x_A − x_1 = 0` has the homogeneous normal
/// `w ∝ (f_1, −1, f_2, …, f_N)` (index 0 the constant term), which the
/// motion `x' = A x + b` transports linearly,
///
/// `w_0' = −b · w_x`,  `w_x' = −Aᵀ w_x`,
///
/// and the coefficients are the ratios `f_1 = −w_0/w_1`, `f_A = −w_A/w_1`.
/// That is the classical linearisation of the Riccati coefficient system
/// (SPEC §1.5): the same `f(t)` exactly, but integrated as a linear system
/// whose solutions are as smooth as the motion, where the Riccati form has
/// poles (the oscillator's `f_2 = tan(ωt)/ω`) that hold an integrator's
/// steps to a fraction of the motion's. The sensitivities `∂w/∂c_j` are
/// columns `P_j` of the same linear flow, and `S = ∂f/∂c` follows by the
/// quotient rule. Where `w_1` nears zero the coefficients grow without
/// bound and the field is re-anchored, as before.
///
/// Layout: `y = (w, P_2, …, P_N)`, each of length `N + 1`; `P_j = ∂w/∂c_j`
/// with `c_1` the free term. `P_1` is not stored: the free term enters
/// `w_0` alone, and `w_0` enters no rate, so `P_1 = e_0` for ever
/// (`sensitivity`). `N(N + 1)` numbers are integrated, not `(N + 1)²`.
pub struct ProjectiveCoefficients<'a, I: Iterate + ?Sized> {
    linear: LinearizedCoefficients<'a, I>,
    /// The model's `N` and coordinates, asked once rather than at every
    /// evaluation (two dynamic calls).
    dim: usize,
    shift: usize,
    /// One degree of freedom's frozen `A` (its 4 numbers as the buffers
    /// hold them) and `b` (2), copied out of the buffers where a kept
    /// linearisation is there when the system is built
    /// ([`ProjectiveCoefficients::with_kept_scratch`]): every stage's
    /// rates then borrow nothing (the affine field's oscillators).
    frozen_one: Option<[f64; 6]>,
    /// Built for a quasilinear window ([`ProjectiveCoefficients::new`]):
    /// [`FieldSystem::fits_retry`].
    fits_retry: bool,
}

impl<'a, I: Iterate + ?Sized> ProjectiveCoefficients<'a, I> {
    pub fn new(model: &'a dyn DynModel, iterate: &'a I) -> Self {
        ProjectiveCoefficients {
            linear: LinearizedCoefficients::new(model, iterate),
            dim: model.dim(),
            shift: model.coordinates(),
            frozen_one: None,
            fits_retry: true,
        }
    }

    /// [`ProjectiveCoefficients::new`] on lent buffers (of the model's size).
    pub fn with_scratch(
        model: &'a dyn DynModel,
        iterate: &'a I,
        scratch: &'a RefCell<LinearizationScratch>,
    ) -> Self {
        ProjectiveCoefficients {
            linear: LinearizedCoefficients::lent(model, iterate, scratch),
            dim: model.dim(),
            shift: model.coordinates(),
            frozen_one: None,
            fits_retry: false,
        }
    }

    /// [`ProjectiveCoefficients::with_scratch`] for a solver that builds
    /// its system on the same buffers, model and iterate at the origin at
    /// every step (the affine field): a frozen linearisation (an
    /// autonomous model, `A` and `b` the same at every time) already in
    /// the buffers is kept rather than evaluated again at every step (the
    /// same numbers: the model's `linearize` reads no time). The lender
    /// forgets the buffers ([`LinearizationScratch::forget`]) where the
    /// model may have changed.
    pub fn with_kept_scratch(
        model: &'a dyn DynModel,
        iterate: &'a I,
        scratch: &'a RefCell<LinearizationScratch>,
    ) -> Self {
        let linear = LinearizedCoefficients::lent_keeping(model, iterate, scratch, true);
        let (dim, shift) = (model.dim(), model.coordinates());
        let frozen_one = if linear.frozen && (dim, shift) == (2, 1) {
            let sc = scratch.borrow();
            match (sc.formed_at, sc.a.as_slice(), &sc.b[..]) {
                (Some(_), &[a0, a1, a2, a3], &[b0, b1]) => Some([a0, a1, a2, a3, b0, b1]),
                _ => None,
            }
        } else {
            None
        };
        ProjectiveCoefficients {
            linear,
            dim,
            shift,
            frozen_one,
            fits_retry: false,
        }
    }

    pub fn linearizations(&self) -> usize {
        self.linear.linearizations()
    }

    /// The iterate `x0`, `X(t, x0)` and `A = ∂X/∂x (t, x0)` copied out
    /// where the last linearisation evaluated was at `t` (its bits); false
    /// where it was not. Why: a DOP853 step of a quasilinear window ends
    /// with its stages at the step's end, where Newton's defect
    /// (`QuasilinearField::defect`) needs that same linearisation again —
    /// the same model, iterate and time, so the same bits, one
    /// linearisation and one read of the predictor fewer an accepted step.
    pub fn linearization_at(
        &self,
        t: f64,
        x0: &mut [f64],
        rate: &mut [f64],
        a: &mut Matrix,
    ) -> bool {
        let sc = self.linear.scratch.borrow_mut();
        // A frozen linearisation (an affine motion's) is stamped with the
        // time of its one evaluation: not read here.
        if self.linear.frozen || sc.evaluated_at != Some(t.to_bits()) {
            return false;
        }
        x0.copy_from_slice(&sc.x);
        rate.copy_from_slice(&sc.rate);
        a.as_mut_slice().copy_from_slice(sc.a.as_slice());
        true
    }

    /// The index in `w` of coefficient `i` (0: the free term).
    fn slot(i: usize) -> usize {
        if i == 0 {
            0
        } else {
            i + 1
        }
    }
}

/// The projective form's rates for all its vectors `(w_0, w_x)` (each
/// `N + 1` long, in `y`): `w_0' = −b · w_x`, `w_x' = −Aᵀ w_x`, the first
/// `N − n` rows of `A` the shifts `x_i' = x_{i+n}` (`a_{i,i+n} = 1`),
/// which are not read. All vectors at once, walking `A` once: their
/// entries gathered as rows (`rows[i·m + k]` = entry `i` of `w_x` of
/// vector `k`), so the innermost loop runs over the vectors, contiguous.
/// Each sum is accumulated in the order of a dot product per vector (from
/// −0.0, over `i` ascending): the same bits.
#[inline]
fn adjoint_rates(
    a: &Matrix,
    b: &[f64],
    shift: usize,
    y: &[f64],
    dy: &mut [f64],
    rows: &mut [f64],
    sums: &mut [f64],
) {
    let n = b.len();
    if y.len() == n * (n + 1) {
        // The coordinates' count known too where it is the usual half of
        // the state (second-order equations): the loop over `A`'s rows
        // below the shifts then has constant bounds and unrolls fully.
        let a = a.as_slice();
        match (n, shift) {
            (2, 1) => return adjoint_rates_small::<2, 1>(a, b, shift, y, dy),
            (4, 2) => return adjoint_rates_small::<4, 2>(a, b, shift, y, dy),
            (2, _) => return adjoint_rates_small::<2, ANY>(a, b, shift, y, dy),
            (3, _) => return adjoint_rates_small::<3, ANY>(a, b, shift, y, dy),
            (4, _) => return adjoint_rates_small::<4, ANY>(a, b, shift, y, dy),
            _ => {}
        }
    }
    adjoint_rates_large(a, b, shift, y, dy, rows, sums)
}

/// [`adjoint_rates`] for `N` > 4 or more vectors than coefficients: a
/// function of its own, so that its frame (the unrolled variants' arrays)
/// is not set up for the small systems' calls.
#[inline(never)]
fn adjoint_rates_large(
    a: &Matrix,
    b: &[f64],
    shift: usize,
    y: &[f64],
    dy: &mut [f64],
    rows: &mut [f64],
    sums: &mut [f64],
) {
    let n = b.len();
    if y.len() == n * (n + 1) {
        // Second-order equations (the coordinates half the state): the
        // shift a constant too, so that the loop over `A`'s rows below it
        // unrolls (knife_edge, N = 6: about 900 → 400 instructions a call).
        match (n, shift) {
            (6, 3) => return adjoint_rates_fixed::<6, 3>(a, b, shift, y, dy),
            (8, 4) => return adjoint_rates_fixed::<8, 4>(a, b, shift, y, dy),
            (10, 5) => return adjoint_rates_fixed::<10, 5>(a, b, shift, y, dy),
            (12, 6) => return adjoint_rates_fixed::<12, 6>(a, b, shift, y, dy),
            (5, _) => return adjoint_rates_fixed::<5, ANY>(a, b, shift, y, dy),
            (6, _) => return adjoint_rates_fixed::<6, ANY>(a, b, shift, y, dy),
            (7, _) => return adjoint_rates_fixed::<7, ANY>(a, b, shift, y, dy),
            (8, _) => return adjoint_rates_fixed::<8, ANY>(a, b, shift, y, dy),
            (10, _) => return adjoint_rates_fixed::<10, ANY>(a, b, shift, y, dy),
            (12, _) => return adjoint_rates_fixed::<12, ANY>(a, b, shift, y, dy),
            _ => {}
        }
    }
    let m = y.len() / (n + 1);
    let rows = &mut rows[..n * m];
    let sums = &mut sums[..m];
    for (k, v) in y.chunks_exact(n + 1).enumerate() {
        for (i, &x) in v[1..].iter().enumerate() {
            rows[i * m + k] = x;
        }
    }
    let accumulate = |sums: &mut [f64], factor: f64, row: &[f64]| {
        for (s, &x) in sums.iter_mut().zip(row) {
            *s += factor * x;
        }
    };
    sums.fill(-0.0);
    for (i, row) in rows.chunks_exact(m).enumerate() {
        accumulate(sums, b[i], row);
    }
    for (k, s) in sums.iter().enumerate() {
        dy[k * (n + 1)] = -*s;
    }
    let shifted = n - shift;
    for col in 0..n {
        let column = a.column(col);
        sums.fill(-0.0);
        for i in shifted..n {
            accumulate(sums, column[i], &rows[i * m..(i + 1) * m]);
        }
        if col >= shift {
            let row = &rows[(col - shift) * m..(col - shift + 1) * m];
            for (s, &x) in sums.iter_mut().zip(row) {
                *s += x;
            }
        }
        for (k, s) in sums.iter().enumerate() {
            dy[k * (n + 1) + 1 + col] = -*s;
        }
    }
}

/// `SHIFT` of [`adjoint_rates_small`] read at run time.
const ANY: usize = usize::MAX;

/// [`adjoint_rates`] for `N` vectors of `N + 1`, `N` ≤ 4: one vector at a
/// time, every slice's length known, so that nothing is checked or
/// gathered at run time (one degree of freedom: 130 instructions a call
/// before, the same sums in the same order). `SHIFT` is the coordinates'
/// count `shift` when known at compile time ([`ANY`]: read at run time);
/// the same sums in the same order either way.
#[inline(never)]
fn adjoint_rates_small<const N: usize, const SHIFT: usize>(
    a: &[f64],
    b: &[f64],
    shift: usize,
    y: &[f64],
    dy: &mut [f64],
) {
    adjoint_rates_small_inline::<N, SHIFT>(a, b, shift, y, dy)
}

/// [`adjoint_rates_small`]'s body, inlined into the right side itself for
/// one degree of freedom (`ProjectiveCoefficients::rhs`: a call and a
/// dispatch fewer at every stage).
#[inline(always)]
fn adjoint_rates_small_inline<const N: usize, const SHIFT: usize>(
    a: &[f64],
    b: &[f64],
    shift: usize,
    y: &[f64],
    dy: &mut [f64],
) {
    let shift = if SHIFT == ANY { shift } else { SHIFT };
    let (a, b) = (&a[..N * N], &b[..N]);
    let (y, dy) = (&y[..N * (N + 1)], &mut dy[..N * (N + 1)]);
    let shifted = N - shift;
    for (v, d) in y.chunks_exact(N + 1).zip(dy.chunks_exact_mut(N + 1)) {
        let w: &[f64; N] = v[1..].try_into().expect("N entries");
        let mut sum = -0.0;
        for i in 0..N {
            sum += b[i] * w[i];
        }
        d[0] = -sum;
        for col in 0..N {
            let column = &a[col * N..col * N + N];
            let mut sum = -0.0;
            for i in shifted..N {
                sum += column[i] * w[i];
            }
            if col >= shift {
                sum += w[col - shift];
            }
            d[1 + col] = -sum;
        }
    }
}

/// [`adjoint_rates`] for `N` vectors of `N + 1`, unrolled (`N` up to 8, and
/// 10 and 12: five or six coordinates). `SHIFT` as in
/// [`adjoint_rates_small`]: the same sums in the same order either way.
fn adjoint_rates_fixed<const N: usize, const SHIFT: usize>(
    a: &Matrix,
    b: &[f64],
    shift: usize,
    y: &[f64],
    dy: &mut [f64],
) {
    let shift = if SHIFT == ANY { shift } else { SHIFT };
    let mut rows = [[0.0; N]; N];
    for (k, v) in y.chunks_exact(N + 1).enumerate().take(N) {
        for i in 0..N {
            rows[i][k] = v[1 + i];
        }
    }
    let b: &[f64; N] = b.try_into().expect("N components");
    let mut sums = [-0.0; N];
    for i in 0..N {
        for k in 0..N {
            sums[k] += b[i] * rows[i][k];
        }
    }
    for k in 0..N {
        dy[k * (N + 1)] = -sums[k];
    }
    let shifted = N - shift;
    for col in 0..N {
        let column: &[f64; N] = a.column(col).try_into().expect("N rows");
        let mut sums = [-0.0; N];
        for i in shifted..N {
            for k in 0..N {
                sums[k] += column[i] * rows[i][k];
            }
        }
        if col >= shift {
            for k in 0..N {
                sums[k] += rows[col - shift][k];
            }
        }
        for k in 0..N {
            dy[k * (N + 1) + 1 + col] = -sums[k];
        }
    }
}

impl<I: Iterate + ?Sized> System for ProjectiveCoefficients<'_, I> {
    fn dim(&self) -> usize {
        let n = self.linear.model.dim();
        n * (n + 1)
    }

    fn rhs(&self, t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), Failure> {
        if let (Some(ab), 6) = (&self.frozen_one, y.len()) {
            // `adjoint_rates`' case (2, 1) on the kept linearisation.
            adjoint_rates_small_inline::<2, 1>(&ab[..4], &ab[4..], 1, y, dy);
            return Ok(());
        }
        let (n, shift) = (self.dim, self.shift);
        let mut guard = self.linear.scratch.borrow_mut();
        let sc = &mut *guard;
        // Frozen and formed: nothing to ask of `linearize` (a call and two
        // checks at every stage).
        if !(self.linear.frozen && sc.formed_at.is_some()) {
            self.linear.linearize(t, sc)?;
        }
        if n == 2 && shift == 1 && y.len() == 6 {
            // One degree of freedom, at every stage of the field's steps:
            // `adjoint_rates`' case (2, 1), inlined here.
            adjoint_rates_small_inline::<2, 1>(sc.a.as_slice(), &sc.b, shift, y, dy);
            return Ok(());
        }
        let (rows, sums) = sc.batch.split_at_mut(n * n);
        adjoint_rates(&sc.a, &sc.b, shift, y, dy, rows, sums);
        Ok(())
    }

    fn jacobian(&self, t: f64, _y: &[f64], jac: &mut Matrix) -> Result<(), Failure> {
        let n = self.linear.model.dim();
        let mut guard = self.linear.scratch.borrow_mut();
        let sc = &mut *guard;
        self.linear.linearize(t, sc)?;
        for k in 0..n {
            let base = k * (n + 1);
            for i in 0..n {
                jac[(base, base + 1 + i)] = -sc.b[i];
                for j in 0..n {
                    jac[(base + 1 + j, base + 1 + i)] = -sc.a[(i, j)];
                }
            }
        }
        Ok(())
    }

    fn time_partial(&self, t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), Failure> {
        central_time_partial(self, t, y, dydt)
    }

    fn component_name(&self, i: usize) -> String {
        format!("the field's normal w{}", i + 1)
    }
}

impl<I: Iterate + ?Sized> FieldSystem for ProjectiveCoefficients<'_, I> {
    fn coefficients(&self) -> usize {
        self.linear.model.dim()
    }

    fn anchored(&self, c: &[f64]) -> Vec<f64> {
        let n = c.len();
        let mut y = vec![0.0; n * (n + 1)];
        y[0] = c[0];
        y[1] = -1.0;
        y[2..=n].copy_from_slice(&c[1..]);
        for j in 1..n {
            y[j * (n + 1) + Self::slot(j)] = 1.0;
        }
        y
    }

    /// The rounding amplification is that of the differences
    /// `P_kj w_1 − w_k P_1j`: where one mode of the adjoint dominates (the
    /// adjoint of a fast decaying mode grows like `e^{+|λ|t}`), the columns
    /// align and the differences cancel to noise although `S` looks
    /// harmless.
    fn field(&self, y: &[f64], f: &mut [f64], s: &mut [f64]) -> Option<f64> {
        // One and two degrees of freedom with their size known at compile
        // time: the same operations, the loops unrolled and the
        // sensitivities' branches on `j` and `k` folded.
        match f.len() {
            2 => projective_field_measured::<2>(y, f, s),
            4 => projective_field_measured::<4>(y, f, s),
            _ => projective_field_measured::<0>(y, f, s),
        }
    }

    fn is_projective(&self) -> bool {
        true
    }

    fn fits_retry(&self) -> bool {
        self.fits_retry
    }

    /// Row 0 of each `P_A`, `∂w_0/∂c_A`, is the free term's accumulator
    /// (`w_0' = −b·w_x` enters no rate): it reaches the state only through
    /// `S_1A = −(P_A0 w_1 − w_0 P_A1)/w_1²`, the right side of condition A,
    /// in the units of `x_A` (at the anchor `r_A = x_A0`). Its rounding is
    /// that of the two products, an absolute error in those units, which
    /// the window measures through the conditions against the state's
    /// tolerance: not as a growth from the anchor's unit vectors, which
    /// it is not (a rocket 10 km downrange has row 0 at 1e5 where the
    /// adjoint's rows are at 800, and no digit of the state is lost).
    fn free_term_rounding(&self, y: &[f64], dr: &mut [f64]) -> bool {
        let n = dr.len();
        let (w0, w1) = (y[0], y[1]);
        let w1_sq = w1 * w1;
        for (a, d) in dr.iter_mut().enumerate().skip(1) {
            let (p0, p1) = (y[a * (n + 1)], y[a * (n + 1) + 1]);
            *d = f64::EPSILON * ((p0 * w1).abs() + (w0 * p1).abs()) / w1_sq;
        }
        true
    }

    /// `S_ij = −(P_kj w_1 − w_k P_1j)/w_1²` is a difference: its rounding
    /// is that of its terms, which may be far larger than it where the
    /// adjoint's modes align (a fast decaying mode of the motion).
    fn rounding(&self, y: &[f64], f: &[f64], s: &[f64], df: &mut [f64], ds: &mut [f64]) {
        let n = f.len();
        let w = &y[..=n];
        let w1 = w[1];
        for (d, v) in df.iter_mut().zip(f) {
            *d = 2.0 * f64::EPSILON * v.abs();
        }
        for j in 0..n {
            for i in 0..n {
                let k = Self::slot(i);
                let terms =
                    (sensitivity(y, n, j, k) * w1).abs() + (w[k] * sensitivity(y, n, j, 1)).abs();
                ds[j * n + i] = 2.0 * f64::EPSILON * (terms / (w1 * w1) + s[j * n + i].abs());
            }
        }
    }

    /// `Y = (w, P_1, …, P_N)` column by column obeys `Y' = −Ãᵀ Y`.
    fn generator(&self, t: f64, b: &mut Matrix) -> Option<Result<(), Failure>> {
        let n = self.linear.model.dim();
        let mut guard = self.linear.scratch.borrow_mut();
        let sc = &mut *guard;
        if let Err(failure) = self.linear.linearize(t, sc) {
            return Some(Err(failure));
        }
        for i in 0..n {
            b[(0, i + 1)] = -sc.b[i];
            for j in 0..n {
                b[(j + 1, i + 1)] = -sc.a[(i, j)];
            }
        }
        Some(Ok(()))
    }

    fn shift_free_term(&self, y: &mut [f64], delta: f64) {
        // w_0 moves along P_1 = ∂w/∂c_1 = e_0.
        y[0] += delta;
    }

    fn field_change(&self, y: &[f64], dy: &[f64], df: &mut [f64], ds: &mut [f64]) {
        // As `field`: the sizes of one and two degrees of freedom known.
        match df.len() {
            2 => projective_field_change::<2>(y, dy, df, ds),
            4 => projective_field_change::<4>(y, dy, df, ds),
            _ => projective_field_change::<0>(y, dy, df, ds),
        }
    }
}

/// [`ProjectiveCoefficients`]' `field` for `N` coefficients (`N = 0`: any
/// number, read at run time), with the rounding amplification of the
/// differences `P_kj w_1 − w_k P_1j` (see there).
#[inline(always)]
fn projective_field_measured<const N: usize>(
    y: &[f64],
    f: &mut [f64],
    s: &mut [f64],
) -> Option<f64> {
    let n = if N == 0 { f.len() } else { N };
    let w = &y[..=n];
    let w1 = w[1];
    if w1 == 0.0 || !w1.is_finite() {
        return None;
    }
    for i in 0..n {
        f[i] = -w[slot_of(i)] / w1;
    }
    let w1_sq = w1 * w1;
    let (mut magnitude, mut value) = (0.0_f64, 0.0_f64);
    // How far the sensitivities of the normal grew from the anchor's
    // unit vectors: where one adjoint mode dominates they align, and
    // the state the conditions recover loses as many digits (measured:
    // without this bound the stiff x'' + 1000x' + x = 0 ended 1e-6 off
    // at rtol 1e-8). The adjoint's rows only (k ≥ 1): row 0, the free
    // term's accumulator, is no mode and is measured in the state's units
    // (`free_term_rounding`), as are the cancellations of its entries
    // `S_1A` (i = 0) below.
    let growth = y[n + 1..]
        .chunks_exact(n + 1)
        .fold(1.0_f64, |m, p| p[1..].iter().fold(m, |m, v| m.max(v.abs())));
    for j in 0..n {
        for i in 0..n {
            let k = slot_of(i);
            let (a, b) = (sensitivity(y, n, j, k) * w1, w[k] * sensitivity(y, n, j, 1));
            if i > 0 {
                magnitude = magnitude.max(a.abs() + b.abs());
                value = value.max((a - b).abs());
            }
            s[j * n + i] = -(a - b) / w1_sq;
        }
    }
    let loss = if value > 0.0 {
        magnitude / value
    } else {
        f64::INFINITY
    };
    let loss = loss.max(growth);
    loss.is_finite().then_some(loss)
}

/// [`ProjectiveCoefficients`]' `field_change` for `N` coefficients (`N =
/// 0`: any number, read at run time): the first-order change of `(f, S)`
/// when `y` changes by `dy`.
#[inline(always)]
fn projective_field_change<const N: usize>(y: &[f64], dy: &[f64], df: &mut [f64], ds: &mut [f64]) {
    let n = if N == 0 { df.len() } else { N };
    let (w, dw) = (&y[..=n], &dy[..=n]);
    let w1 = w[1];
    let dw1 = dw[1];
    for i in 0..n {
        let k = slot_of(i);
        df[i] = -(dw[k] * w1 - w[k] * dw1) / (w1 * w1);
    }
    for j in 0..n {
        let p = |k: usize| sensitivity(y, n, j, k);
        // P_1 is constant: its change is zero.
        let dp = |k: usize| if j == 0 { 0.0 } else { dy[j * (n + 1) + k] };
        for i in 0..n {
            let k = slot_of(i);
            let s = -(p(k) * w1 - w[k] * p(1)) / (w1 * w1);
            let d_numerator = dp(k) * w1 + p(k) * dw1 - dw[k] * p(1) - w[k] * dp(1);
            ds[j * n + i] = -d_numerator / (w1 * w1) - 2.0 * s * dw1 / w1;
        }
    }
}

/// The index in `w` of coefficient `i` (0: the free term), as
/// [`ProjectiveCoefficients`]' `slot`.
#[inline(always)]
fn slot_of(i: usize) -> usize {
    if i == 0 {
        0
    } else {
        i + 1
    }
}

/// `f` and `S` from a projective state `y = (w, P)` (see
/// [`ProjectiveCoefficients`]); `false` at a pole.
pub fn projective_field(y: &[f64], f: &mut [f64], s: &mut [f64]) -> bool {
    let n = f.len();
    let slot = |i: usize| if i == 0 { 0 } else { i + 1 };
    let w = &y[..=n];
    let w1 = w[1];
    if w1 == 0.0 || !w1.is_finite() {
        return false;
    }
    for i in 0..n {
        f[i] = -w[slot(i)] / w1;
    }
    for j in 0..n {
        for i in 0..n {
            let k = slot(i);
            let (p_k, p_1) = (sensitivity(y, n, j, k), sensitivity(y, n, j, 1));
            s[j * n + i] = -(p_k * w1 - w[k] * p_1) / (w1 * w1);
        }
    }
    true
}

/// Entry `k` of `P_j = ∂w/∂c_j` (`j` from 0) in the projective layout
/// `y = (w, P_2, …, P_N)`: `P_1` is the constant `e_0` and not stored
/// (see [`ProjectiveCoefficients`]).
#[inline]
fn sensitivity(y: &[f64], n: usize, j: usize, k: usize) -> f64 {
    if j == 0 {
        if k == 0 {
            1.0
        } else {
            0.0
        }
    } else {
        y[j * (n + 1) + k]
    }
}

/// `∂F/∂t` of a coefficient system by central differences (step
/// `eps^{1/3}·max(|t|, 1)`, error ~ eps^{2/3}): used only by RODAS4 on
/// the field's coefficient systems, once per step.
fn central_time_partial<S: System + ?Sized>(
    system: &S,
    t: f64,
    y: &[f64],
    dydt: &mut [f64],
) -> Result<(), Failure> {
    let m = y.len();
    let h = f64::EPSILON.cbrt() * t.abs().max(1.0);
    let mut plus = vec![0.0; m];
    let mut minus = vec![0.0; m];
    system.rhs(t + h, y, &mut plus)?;
    system.rhs(t - h, y, &mut minus)?;
    for i in 0..m {
        dydt[i] = (plus[i] - minus[i]) / (2.0 * h);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The unrolled rates are the general loop's, bit for bit, and both
    /// are the dot products they stand for.
    #[test]
    fn adjoint_rates_are_the_same_bits_for_every_dimension() {
        for n in 1..=13 {
            for shift in [n / 2, n] {
                let mut a = Matrix::zeros(n, n);
                for c in 0..n {
                    for r in 0..n {
                        a[(r, c)] = ((r * 5 + c * 3) % 7) as f64 / 3.0 - 1.0;
                    }
                }
                let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.7).cos()).collect();
                let y: Vec<f64> = (0..n * (n + 1)).map(|k| (k as f64 * 0.37).sin()).collect();
                let mut fast = vec![0.0; y.len()];
                let (mut rows, mut sums) = (vec![0.0; n * n], vec![0.0; n]);
                adjoint_rates(&a, &b, shift, &y, &mut fast, &mut rows, &mut sums);
                let mut general = vec![0.0; y.len()];
                // The general loop, as for more vectors than coefficients.
                let mut wide = y.clone();
                wide.extend(std::iter::repeat_n(0.0, n + 1));
                let mut wide_out = vec![0.0; wide.len()];
                let (mut rows, mut sums) = (vec![0.0; n * (n + 1)], vec![0.0; n + 1]);
                adjoint_rates(&a, &b, shift, &wide, &mut wide_out, &mut rows, &mut sums);
                general.copy_from_slice(&wide_out[..y.len()]);
                let mut expected = vec![0.0; y.len()];
                for (v, e) in y.chunks(n + 1).zip(expected.chunks_mut(n + 1)) {
                    e[0] = -b.iter().zip(&v[1..]).map(|(b, w)| b * w).sum::<f64>();
                    let mut r = vec![0.0; n];
                    transpose_times(&a, &v[1..], shift, &mut r);
                    for (e, r) in e[1..].iter_mut().zip(&r) {
                        *e = -r;
                    }
                }
                let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&fast), bits(&expected), "n = {n}, shift = {shift}");
                assert_eq!(bits(&general), bits(&expected), "n = {n}, shift = {shift}");
            }
        }
    }
}
