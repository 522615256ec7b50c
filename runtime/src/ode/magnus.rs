//! The Magnus integrator of order 4 for linear systems `Y' = B(t) Y`: the
//! field method's coefficient system in projective form (SPEC §1.5: "a
//! stable integrator for the coefficient system … Magnus/matrix
//! exponential for linear coefficient systems").
//!
//! One step: `Ω = h/2 (B₁ + B₂) + (√3/12) h² [B₂, B₁]` with `B` at the two
//! Gauss points, `Y ← exp(Ω) Y`. Why: the coefficient system is the
//! adjoint of the motion, so a fast decaying mode of the motion is a fast
//! growing mode here, and a fast oscillation stays one; an exponential
//! integrator follows both exactly for constant `B`, so its step is limited
//! by how `B(t)` varies, not by the modes' speed.
//!
//! Error control by step doubling: one step of `h` against two of `h/2`;
//! their difference `/15` estimates the error of the two half steps, and
//! the accepted state is the Richardson combination.

use crate::failure::{Failure, FailureKind};
use crate::linalg::{expm, Matrix};
use crate::ode::budget::Budget;
use crate::ode::controller::Controller;
use crate::ode::stepper::{
    Clock, Clocked, DenseStep, ErrorMeasure, RmsMeasure, StepOutcome, Stepper,
};
use crate::ode::tolerance::{first_non_finite, Stats, Tolerance};

/// Offset of the two Gauss–Legendre nodes from the midpoint, in units of `h`.
const GAUSS_OFFSET: f64 = 0.288_675_134_594_812_9; // √3/6
const COMMUTATOR_WEIGHT: f64 = 0.144_337_567_297_406_43; // √3/12

/// A linear system `Y' = B(t) Y` with `Y` an `m × k` matrix stored column
/// by column in the integrator's state (the field's: `k = m − 1`).
pub trait LinearGenerator {
    /// `m`.
    fn order(&self) -> usize;
    /// `b = B(t)` (zeroed by the caller).
    fn generator(&self, t: f64, b: &mut Matrix) -> Result<(), Failure>;
}

/// `exp(Ω)` over `[t, t + h]`: the order-4 Magnus propagator (two
/// evaluations of the generator and one matrix exponential).
pub fn propagator<G: LinearGenerator + ?Sized>(
    system: &G,
    t: f64,
    h: f64,
) -> Result<Matrix, Failure> {
    let m = system.order();
    let mid = t + 0.5 * h;
    let mut b1 = Matrix::zeros(m, m);
    let mut b2 = Matrix::zeros(m, m);
    system.generator(mid - GAUSS_OFFSET * h, &mut b1)?;
    system.generator(mid + GAUSS_OFFSET * h, &mut b2)?;
    let commutator = {
        let mut c = b2.mul(&b1);
        let d = b1.mul(&b2);
        for (x, y) in c.as_mut_slice().iter_mut().zip(d.as_slice()) {
            *x -= y;
        }
        c
    };
    let mut omega = Matrix::zeros(m, m);
    for (i, o) in omega.as_mut_slice().iter_mut().enumerate() {
        *o = 0.5 * h * (b1.as_slice()[i] + b2.as_slice()[i])
            + COMMUTATOR_WEIGHT * h * h * commutator.as_slice()[i];
    }
    Ok(expm(&omega))
}

/// `exp(Ω) Y` over `[t, t + h]` from `y` (`Y` column by column), into
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
    let m = system.order();
    let p = propagator(system, t, h)?;
    let yy = Matrix::from_column_major(m, y.len() / m, y.to_vec());
    out.copy_from_slice(p.mul(&yy).as_slice());
    Ok(())
}

pub struct Magnus {
    tol: Tolerance,
    clock: Clock,
    y: Vec<f64>,
    y_old: Vec<f64>,
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
        Magnus {
            tol,
            clock: Clock::new(
                t0,
                h0,
                Controller::new(4.0, 0.08, 0.2, 5.0),
                Stats::default(),
            ),
            y: y0.to_vec(),
            y_old: y0.to_vec(),
        }
    }

    pub fn state(&self) -> &[f64] {
        &self.y
    }

    /// The state at the last step's start.
    pub fn previous_state(&self) -> &[f64] {
        &self.y_old
    }

    /// `exp(Ω)` over `[t, t + h]`.
    fn propagator<G: LinearGenerator + ?Sized>(
        &mut self,
        system: &G,
        t: f64,
        h: f64,
    ) -> Result<Matrix, Failure> {
        self.clock.stats.rhs_evaluations += 2;
        self.clock.stats.matrix_exponentials += 1;
        propagator(system, t, h)
    }

    /// One accepted step under `measure` (the error estimate per unit step
    /// passed as both `e3` and `e5`).
    pub fn step_measured<G: LinearGenerator + ?Sized, E: ErrorMeasure + ?Sized>(
        &mut self,
        system: &G,
        t_limit: f64,
        budget: &Budget,
        measure: &mut E,
    ) -> Result<StepOutcome, Failure> {
        let m = system.order();
        loop {
            let (h, reaches) = self.clock.attempt(t_limit, budget, |h| {
                Failure::new(self.clock.t, FailureKind::StepSizeUnderflow { step: h })
            })?;
            let apply = |p: &Matrix, y: &[f64]| -> Vec<f64> {
                let yy = Matrix::from_column_major(m, y.len() / m, y.to_vec());
                p.mul(&yy).as_slice().to_vec()
            };
            let full = self.propagator(system, self.clock.t, h)?;
            let first = self.propagator(system, self.clock.t, 0.5 * h)?;
            let second = self.propagator(system, self.clock.t + 0.5 * h, 0.5 * h)?;
            let y_full = apply(&full, &self.y);
            let y_half = apply(&second, &apply(&first, &self.y));
            let estimate: Vec<f64> = y_half
                .iter()
                .zip(&y_full)
                .map(|(a, b)| (a - b) / 15.0)
                .collect();
            let y_new: Vec<f64> = y_half.iter().zip(&estimate).map(|(a, e)| a + e).collect();
            let per_unit: Vec<f64> = estimate.iter().map(|e| e / h).collect();
            let error = if first_non_finite(&y_new).is_some() {
                f64::INFINITY
            } else {
                match measure.measure(self.clock.t, h, &self.y, &y_new, &per_unit, &per_unit) {
                    Some(e) => e,
                    None => return Ok(self.clock.decline()),
                }
            };
            if error <= 1.0 {
                let h_next = self.clock.controller.accept(h, error);
                self.y_old = std::mem::replace(&mut self.y, y_new);
                let t_new = self.clock.end(h, reaches, t_limit);
                self.clock.accept(h, t_new, h_next, reaches);
                return Ok(StepOutcome::Accepted);
            }
            self.clock.reject(h, error);
        }
    }

    /// The state at `t` within the last step: the Magnus propagator from
    /// the step's start (order 4, two evaluations and one exponential).
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
        let m = system.order();
        let p = self.propagator(system, self.clock.t_old, t - self.clock.t_old)?;
        let yy = Matrix::from_column_major(m, self.y_old.len() / m, self.y_old.clone());
        out.copy_from_slice(p.mul(&yy).as_slice());
        Ok(())
    }
}

impl<G: LinearGenerator + ?Sized> Stepper<G> for Magnus {
    fn state(&self) -> &[f64] {
        &self.y
    }

    fn step(&mut self, system: &G, t_limit: f64, budget: &Budget) -> Result<(), Failure> {
        let mut measure = RmsMeasure(self.tol);
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
