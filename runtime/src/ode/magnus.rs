//! The Magnus integrator of order 6 for linear systems `Y' = B(t) Y`: the
//! field method's coefficient system in projective form (SPEC §1.5: "a
//! stable integrator for the coefficient system … Magnus/matrix
//! exponential for linear coefficient systems").
//!
//! One step: `B` at the three Gauss–Legendre nodes, combined into
//! `α₁ = h B₂`, `α₂ = (√15 h/3)(B₃ − B₁)`, `α₃ = (10 h/3)(B₃ − 2B₂ + B₁)`
//! (`αᵢ = hⁱ aᵢ + …`, `aᵢ` the Taylor coefficients of `B` at the step's
//! middle), then `Y ← exp(Ω₆) Y` with Blanes, Casas and Ros's
//! (BIT 40, 2000; Phys. Rep. 470, 2009, §5) sixth-order
//! `C₁ = [α₁, α₂]`, `C₂ = −[α₁, 2α₃ + C₁]/60`,
//! `Ω₆ = α₁ + α₃/12 + [−20α₁ − α₃ + C₁, α₂ + C₂]/240`. Why: the coefficient
//! system is the adjoint of the motion, so a fast decaying mode of the
//! motion is a fast growing mode here, and a fast oscillation stays one; an
//! exponential integrator follows both exactly for constant `B`, so its
//! step is limited by how `B(t)` varies, not by the modes' speed.
//!
//! Error control by embedded steps from the same three evaluations, of
//! order 4, `Ω₄ = α₁ + α₃/12 − C₁/12`, and order 2, `Ω₂ = α₁`:
//! `(exp(Ω₆) − exp(Ω₄)) Y` and `(exp(Ω₆) − exp(Ω₂)) Y` are their local
//! errors, `O(h⁵)` and `O(h³)`, passed to the measure as DOP853 passes its
//! fifth- and third-order estimates, so that Hairer's combination
//! `e₄²/√(e₄² + 0.01 e₂²)` is `O(h⁷)`, the kept sixth-order step's (local
//! extrapolation, as DOP853). Why: the fourth-order estimate alone held the
//! step to what the fourth order allows (stiff joint, rtol 1e-8: 1,861
//! steps, where step doubling of the order-4 step took 1,511). Why not
//! step doubling, as before: six evaluations of `B` and three exponentials
//! a step for a fifth-order result; this takes three and one for a
//! sixth-order one. Measured on tests/data/stiff_joint.lag
//! (docs/BENCHMARKS.md §0). The orders are checked in this file's tests.

use crate::failure::{Failure, FailureKind};
use crate::linalg::{expm, Matrix};
use crate::ode::budget::Budget;
use crate::ode::controller::Controller;
use crate::ode::dop853::HairerMeasure;
use crate::ode::stepper::{Clock, Clocked, DenseStep, ErrorMeasure, StepOutcome, Stepper};
use crate::ode::tolerance::{first_non_finite, Stats, Tolerance};

/// Offset of the outer Gauss–Legendre nodes from the midpoint, in units of
/// `h`: `√15/10`.
const GAUSS_OFFSET: f64 = 0.387_298_334_620_741_7;
/// `√15/3`: `α₂`'s weight.
const SLOPE_WEIGHT: f64 = 1.290_994_448_735_805_6;

/// A linear system `Y' = B(t) Y` with `Y` an `m × k` matrix stored column
/// by column in the integrator's state (the field's: `k = m − 1`).
pub trait LinearGenerator {
    /// `m`.
    fn order(&self) -> usize;
    /// `b = B(t)` (zeroed by the caller).
    fn generator(&self, t: f64, b: &mut Matrix) -> Result<(), Failure>;
}

/// The matrices of one step, kept between steps (no allocation but the
/// exponentials').
struct Scratch {
    b: [Matrix; 3],
    alpha: [Matrix; 3],
    c1: Matrix,
    c2: Matrix,
    left: Matrix,
    right: Matrix,
    product: Matrix,
    omega6: Matrix,
    /// `Ω₆ − Ω₄` and `Ω₆ − Ω₂` (`Ω₂ = α₁`, the midpoint rule).
    difference: Matrix,
    difference2: Matrix,
}

impl Scratch {
    fn new(m: usize) -> Scratch {
        let z = || Matrix::zeros(m, m);
        Scratch {
            b: [z(), z(), z()],
            alpha: [z(), z(), z()],
            c1: z(),
            c2: z(),
            left: z(),
            right: z(),
            product: z(),
            omega6: z(),
            difference: z(),
            difference2: z(),
        }
    }

    fn order(&self) -> usize {
        self.c1.rows()
    }
}

/// `out = x y − y x`.
fn commutator(x: &Matrix, y: &Matrix, out: &mut Matrix, product: &mut Matrix) {
    x.mul_to(y, out);
    y.mul_to(x, product);
    for (o, p) in out.as_mut_slice().iter_mut().zip(product.as_slice()) {
        *o -= p;
    }
}

/// `Ω₆`, `Ω₆ − Ω₄` and `Ω₆ − Ω₂` over `[t, t + h]` into the scratch
/// (three evaluations of the generator).
fn omegas<G: LinearGenerator + ?Sized>(
    system: &G,
    t: f64,
    h: f64,
    s: &mut Scratch,
) -> Result<(), Failure> {
    let mid = t + 0.5 * h;
    let nodes = [mid - GAUSS_OFFSET * h, mid, mid + GAUSS_OFFSET * h];
    for (b, node) in s.b.iter_mut().zip(nodes) {
        b.fill(0.0);
        system.generator(node, b)?;
    }
    let [b1, b2, b3] = &s.b;
    let [a1, a2, a3] = &mut s.alpha;
    for i in 0..a1.as_slice().len() {
        let (x1, x2, x3) = (b1.as_slice()[i], b2.as_slice()[i], b3.as_slice()[i]);
        a1.as_mut_slice()[i] = h * x2;
        a2.as_mut_slice()[i] = SLOPE_WEIGHT * h * (x3 - x1);
        a3.as_mut_slice()[i] = (10.0 / 3.0) * h * (x3 - 2.0 * x2 + x1);
    }
    let [a1, a2, a3] = &s.alpha;
    commutator(a1, a2, &mut s.c1, &mut s.product);
    // C₂ = −[α₁, 2α₃ + C₁]/60.
    for ((r, x), c) in s
        .right
        .as_mut_slice()
        .iter_mut()
        .zip(a3.as_slice())
        .zip(s.c1.as_slice())
    {
        *r = 2.0 * x + c;
    }
    commutator(a1, &s.right, &mut s.c2, &mut s.product);
    s.c2.as_mut_slice().iter_mut().for_each(|c| *c /= -60.0);
    // [−20α₁ − α₃ + C₁, α₂ + C₂].
    for i in 0..a1.as_slice().len() {
        s.left.as_mut_slice()[i] = -20.0 * a1.as_slice()[i] - a3.as_slice()[i] + s.c1.as_slice()[i];
        s.right.as_mut_slice()[i] = a2.as_slice()[i] + s.c2.as_slice()[i];
    }
    let (left, right) = (&s.left, &s.right);
    commutator(left, right, &mut s.omega6, &mut s.product);
    for i in 0..a1.as_slice().len() {
        let high = s.omega6.as_slice()[i] / 240.0;
        s.difference.as_mut_slice()[i] = high + s.c1.as_slice()[i] / 12.0;
        s.difference2.as_mut_slice()[i] = a3.as_slice()[i] / 12.0 + high;
        s.omega6.as_mut_slice()[i] = a1.as_slice()[i] + s.difference2.as_slice()[i];
    }
    Ok(())
}

/// `(exp(Ω₆) − exp(Ω₄)) Y` into `out`, from `p = exp(Ω₆)`, `y6 = p Y` and
/// `Δ = Ω₆ − Ω₄`: to first order in `Δ` (which is `O(h⁵)`) the
/// difference is `∫₀¹ e^{sΩ} Δ e^{(1−s)Ω} ds · Y`, taken by the
/// trapezoidal rule, `(Δ p + p Δ) Y / 2` — exact where `Δ` and `Ω₆`
/// commute, and within a factor near 1 for the `‖Ω‖ ≲ 1` a step keeps.
/// Why not `exp(Ω₄)` itself: a second exponential was 40 % of a step.
fn estimate(p: &Matrix, delta: &Matrix, y: &[f64], y6: &[f64], work: &mut [f64], out: &mut [f64]) {
    apply(delta, y, work);
    apply(p, work, out);
    apply(delta, y6, work);
    for (o, w) in out.iter_mut().zip(work.iter()) {
        *o = 0.5 * (*o + w);
    }
}

/// `out = p Y` for `Y` given column by column.
fn apply(p: &Matrix, y: &[f64], out: &mut [f64]) {
    let m = p.rows();
    for (column, target) in y.chunks_exact(m).zip(out.chunks_exact_mut(m)) {
        p.mul_vec(column, target);
    }
}

/// `exp(Ω₆)` over `[t, t + h]`: the order-6 Magnus propagator (three
/// evaluations of the generator and one matrix exponential).
pub fn propagator<G: LinearGenerator + ?Sized>(
    system: &G,
    t: f64,
    h: f64,
) -> Result<Matrix, Failure> {
    let mut scratch = Scratch::new(system.order());
    omegas(system, t, h, &mut scratch)?;
    Ok(expm(&scratch.omega6))
}

/// `exp(Ω₆) Y` over `[t, t + h]` from `y` (`Y` column by column), into
/// `out`: the state a step of length `h` reaches, for output inside an
/// accepted step (a shorter step than the accepted one, so at least as
/// accurate).
pub fn propagate<G: LinearGenerator + ?Sized>(
    system: &G,
    t: f64,
    h: f64,
    y: &[f64],
    out: &mut [f64],
) -> Result<(), Failure> {
    apply(&propagator(system, t, h)?, y, out);
    Ok(())
}

pub struct Magnus {
    tol: Tolerance,
    clock: Clock,
    y: Vec<f64>,
    y_old: Vec<f64>,
    /// The trial step of order 6, a work vector, and the errors per unit
    /// step of the embedded steps of orders 2 and 4.
    y6: Vec<f64>,
    work: Vec<f64>,
    per_unit2: Vec<f64>,
    per_unit: Vec<f64>,
    scratch: Option<Scratch>,
}

impl Clocked for Magnus {
    fn clock(&self) -> &Clock {
        &self.clock
    }

    fn clock_mut(&mut self) -> &mut Clock {
        &mut self.clock
    }
}

impl Magnus {
    /// At `(t0, y0)`, about to try a step of `h0`; `tol` is its own
    /// measure's ([`Stepper::step`]: the field measures the state instead).
    pub fn new(t0: f64, y0: &[f64], h0: f64, tol: Tolerance) -> Magnus {
        let n = y0.len();
        Magnus {
            tol,
            clock: Clock::new(
                t0,
                h0,
                // Hairer's combination of the estimates is O(h⁷); the
                // integral gain DOP853's (0.08 left `α = 1/7 − 0.06` so
                // near it that a step whose error was 1e-5 of the
                // tolerance did not grow: stiff joint, 2,136 steps at
                // rtol 1e-6 where 0.04 takes 441).
                Controller::new(7.0, 0.04, 0.2, 5.0),
                Stats::default(),
            ),
            y: y0.to_vec(),
            y_old: y0.to_vec(),
            y6: vec![0.0; n],
            work: vec![0.0; n],
            per_unit2: vec![0.0; n],
            per_unit: vec![0.0; n],
            scratch: None,
        }
    }

    pub fn state(&self) -> &[f64] {
        &self.y
    }

    /// The state at the last step's start.
    pub fn previous_state(&self) -> &[f64] {
        &self.y_old
    }

    /// The scratch for a generator of order `m`.
    fn scratch(&mut self, m: usize) -> Scratch {
        match self.scratch.take() {
            Some(s) if s.order() == m => s,
            _ => Scratch::new(m),
        }
    }

    /// One accepted step under `measure` (the order-2 and order-4 steps'
    /// errors per unit step passed as `e3` and `e5`).
    pub fn step_measured<G: LinearGenerator + ?Sized, E: ErrorMeasure + ?Sized>(
        &mut self,
        system: &G,
        t_limit: f64,
        budget: &Budget,
        measure: &mut E,
    ) -> Result<StepOutcome, Failure> {
        let mut scratch = self.scratch(system.order());
        let outcome = self.attempts(system, t_limit, budget, measure, &mut scratch);
        self.scratch = Some(scratch);
        outcome
    }

    fn attempts<G: LinearGenerator + ?Sized, E: ErrorMeasure + ?Sized>(
        &mut self,
        system: &G,
        t_limit: f64,
        budget: &Budget,
        measure: &mut E,
        scratch: &mut Scratch,
    ) -> Result<StepOutcome, Failure> {
        loop {
            let (h, reaches) = self.clock.attempt(t_limit, budget, |h| {
                Failure::new(self.clock.t, FailureKind::StepSizeUnderflow { step: h })
            })?;
            self.clock.stats.rhs_evaluations += 3;
            self.clock.stats.matrix_exponentials += 1;
            omegas(system, self.clock.t, h, scratch)?;
            let p = expm(&scratch.omega6);
            apply(&p, &self.y, &mut self.y6);
            let (y, y6, work) = (&self.y, &self.y6, &mut self.work);
            estimate(&p, &scratch.difference, y, y6, work, &mut self.per_unit);
            estimate(&p, &scratch.difference2, y, y6, work, &mut self.per_unit2);
            self.per_unit.iter_mut().for_each(|e| *e /= h);
            self.per_unit2.iter_mut().for_each(|e| *e /= h);
            let error = if first_non_finite(&self.y6).is_some() {
                f64::INFINITY
            } else {
                match measure.measure(
                    self.clock.t,
                    h,
                    &self.y,
                    &self.y6,
                    &self.per_unit2,
                    &self.per_unit,
                ) {
                    Some(e) => e,
                    None => return Ok(self.clock.decline()),
                }
            };
            if error <= 1.0 {
                let h_next = self.clock.controller.accept(h, error);
                std::mem::swap(&mut self.y_old, &mut self.y);
                std::mem::swap(&mut self.y, &mut self.y6);
                let t_new = self.clock.end(h, reaches, t_limit);
                self.clock.accept(h, t_new, h_next, reaches);
                return Ok(StepOutcome::Accepted);
            }
            self.clock.reject(h, error);
        }
    }

    /// The state at `t` within the last step: the Magnus propagator from
    /// the step's start (order 6, three evaluations and one exponential).
    pub fn dense<G: LinearGenerator + ?Sized>(
        &mut self,
        system: &G,
        t: f64,
        out: &mut [f64],
    ) -> Result<(), Failure> {
        let step = self.clock.last_step();
        if let Some(end) = crate::ode::stepper::outside_last_step(t, step, &self.y_old, &self.y) {
            out.copy_from_slice(end);
            return Ok(());
        }
        self.clock.stats.rhs_evaluations += 3;
        self.clock.stats.matrix_exponentials += 1;
        propagate(
            system,
            self.clock.t_old,
            t - self.clock.t_old,
            &self.y_old,
            out,
        )
    }
}

impl<G: LinearGenerator + ?Sized> Stepper<G> for Magnus {
    fn state(&self) -> &[f64] {
        &self.y
    }

    fn step(&mut self, system: &G, t_limit: f64, budget: &Budget) -> Result<(), Failure> {
        // Hairer's measure, as the field's: it combines the two estimates.
        let mut measure = HairerMeasure(self.tol);
        // The inherent step, with this measure's type: no dynamic call
        // per attempt.
        Magnus::step_measured(self, system, t_limit, budget, &mut measure).map(|_| ())
    }

    fn step_measured(
        &mut self,
        system: &G,
        t_limit: f64,
        budget: &Budget,
        measure: &mut dyn ErrorMeasure,
    ) -> Result<StepOutcome, Failure> {
        Magnus::step_measured(self, system, t_limit, budget, measure)
    }

    fn dense(&mut self, system: &G, t: f64, out: &mut [f64]) -> Result<(), Failure> {
        Magnus::dense(self, system, t, out)
    }

    fn dense_step(&mut self, _system: &G) -> Result<Option<DenseStep>, Failure> {
        Ok(None)
    }

    fn as_any(&self) -> &dyn std::any::Any {
        self
    }

    fn as_any_mut(&mut self) -> &mut dyn std::any::Any {
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `B(t) = M₀ + sin(3t) M₁ + t² M₂`: no two values commute.
    struct Varying;

    impl LinearGenerator for Varying {
        fn order(&self) -> usize {
            3
        }

        fn generator(&self, t: f64, b: &mut Matrix) -> Result<(), Failure> {
            let m0 = [[0.3, -1.2, 0.5], [0.8, -0.1, 0.9], [-0.7, 0.4, 0.2]];
            let m1 = [[0.1, 0.6, -0.3], [-0.5, 0.2, 0.4], [0.9, -0.8, 0.0]];
            let m2 = [[-0.4, 0.1, 0.7], [0.3, 0.5, -0.6], [0.2, 0.0, -0.9]];
            for i in 0..3 {
                for j in 0..3 {
                    b[(i, j)] = m0[i][j] + (3.0 * t).sin() * m1[i][j] + t * t * m2[i][j];
                }
            }
            Ok(())
        }
    }

    /// `Y(1)` from `Y(0) = I` in `n` propagator steps.
    fn solve(n: usize) -> Vec<f64> {
        let mut y = Matrix::identity(3).as_slice().to_vec();
        let mut next = y.clone();
        let h = 1.0 / n as f64;
        for k in 0..n {
            propagate(&Varying, k as f64 * h, h, &y, &mut next).unwrap();
            std::mem::swap(&mut y, &mut next);
        }
        y
    }

    fn distance(a: &[f64], b: &[f64]) -> f64 {
        a.iter()
            .zip(b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max)
    }

    /// The propagator's global error falls as `h⁶` (measured 5.93, 5.98
    /// between 4, 8 and 16 steps in the Python prototype of the same
    /// formula; a wrong coefficient drops it to 2 or 4).
    #[test]
    fn the_propagator_is_of_order_six() {
        let reference = solve(1024);
        let errors: Vec<f64> = [4, 8, 16]
            .iter()
            .map(|&n| distance(&solve(n), &reference))
            .collect();
        for pair in errors.windows(2) {
            let order = (pair[0] / pair[1]).log2();
            assert!((5.7..6.5).contains(&order), "orders from {errors:?}");
        }
    }

    /// The embedded estimate is the fourth-order step's local error:
    /// `O(h⁵)`, so halving the step divides it by about 32; and it is
    /// `exp(Ω₆) Y − exp(Ω₄) Y` to within 10 % (the trapezoidal rule for the
    /// exponential's derivative).
    #[test]
    fn the_error_estimate_is_of_order_five_and_near_the_difference() {
        let y0 = Matrix::identity(3).as_slice().to_vec();
        let errors = |h: f64| {
            let mut s = Scratch::new(3);
            omegas(&Varying, 0.2, h, &mut s).unwrap();
            let p = expm(&s.omega6);
            let (mut y6, mut work, mut e) = (vec![0.0; 9], vec![0.0; 9], vec![0.0; 9]);
            apply(&p, &y0, &mut y6);
            estimate(&p, &s.difference, &y0, &y6, &mut work, &mut e);
            let mut omega4 = s.omega6.clone();
            for (o, d) in omega4
                .as_mut_slice()
                .iter_mut()
                .zip(s.difference.as_slice())
            {
                *o -= d;
            }
            let mut y4 = vec![0.0; 9];
            apply(&expm(&omega4), &y0, &mut y4);
            let exact: Vec<f64> = y6.iter().zip(&y4).map(|(a, b)| a - b).collect();
            (
                distance(&e, &[0.0; 9]),
                distance(&e, &exact) / distance(&exact, &[0.0; 9]),
            )
        };
        let (e1, e2, e3) = (errors(0.4), errors(0.2), errors(0.1));
        for ratio in [e1.0 / e2.0, e2.0 / e3.0] {
            let order = ratio.log2();
            assert!((4.6..5.4).contains(&order), "{e1:?} {e2:?} {e3:?}");
        }
        for (_, relative) in [e1, e2, e3] {
            assert!(relative < 0.1, "{e1:?} {e2:?} {e3:?}");
        }
    }

    /// Hairer's combination of the order-2 and order-4 steps' errors
    /// falls as `h⁷`, the sixth-order step's local error (halving the step
    /// divides it by about 128), where the order-4 error alone falls as
    /// `h⁵`.
    #[test]
    fn the_combined_estimate_is_of_order_seven() {
        let y0 = Matrix::identity(3).as_slice().to_vec();
        let combined = |h: f64| {
            let mut s = Scratch::new(3);
            omegas(&Varying, 0.2, h, &mut s).unwrap();
            let p = expm(&s.omega6);
            let (mut y6, mut work) = (vec![0.0; 9], vec![0.0; 9]);
            let (mut e4, mut e2) = (vec![0.0; 9], vec![0.0; 9]);
            apply(&p, &y0, &mut y6);
            estimate(&p, &s.difference, &y0, &y6, &mut work, &mut e4);
            estimate(&p, &s.difference2, &y0, &y6, &mut work, &mut e2);
            let square = |e: &[f64]| e.iter().map(|v| v * v).sum::<f64>();
            let (s4, s2) = (square(&e4), square(&e2));
            s4 / (s4 + 0.01 * s2).sqrt()
        };
        let (c1, c2, c3) = (combined(0.2), combined(0.1), combined(0.05));
        for ratio in [c1 / c2, c2 / c3] {
            let order = ratio.log2();
            assert!((6.5..7.5).contains(&order), "{c1:e} {c2:e} {c3:e}");
        }
    }
}
