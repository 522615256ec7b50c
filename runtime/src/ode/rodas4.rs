//! RODAS4: the stiffly accurate, L-stable Rosenbrock method of order 4 with
//! an embedded order-3 solution and a continuous extension of order 3
//! (HNW II, VI.4; Hairer's `rodas.f`, the RODAS4 coefficient set), using
//! the exact Jacobian `∂X/∂x`, the exact time partial `∂X/∂t` and one LU
//! factorisation per step. Formulation without the Jacobian in the right
//! sides: `(I/(γh) − J) k_i = X(t + α_i h, y + Σ a_ij k_j) + Σ c_ij k_j / h
//! + γ_i h X_t`; the `k_i` are increments.

// The coefficients are kept as Hairer printed them.
#![allow(clippy::excessive_precision, clippy::unreadable_literal)]

use crate::failure::Failure;
use crate::linalg::{Lu, Matrix};
use crate::ode::budget::Budget;
use crate::ode::controller::Controller;
use crate::ode::dense::{DenseStep, Extension};
use crate::ode::stepper::{
    stalled, Clock, Clocked, ErrorMeasure, RmsMeasure, Start, StepOutcome, Stepper,
};
use crate::ode::system::System;
use crate::ode::tolerance::{first_non_finite, Tolerance};

mod tableau;
use tableau::*;

/// The RODAS4 integrator at time `t` with state `y`.
pub struct Rodas4 {
    tol: Tolerance,
    clock: Clock,
    y: Vec<f64>,
    /// `X(t, y)`.
    slope: Vec<f64>,
    /// Scratch: the stage increments of the last attempt.
    k: Vec<Vec<f64>>,
    y_new: Vec<f64>,
    jacobian: Matrix,
    time_partial: Vec<f64>,
    /// The last accepted step's start state and the continuous
    /// extension's two coefficient vectors.
    y_old: Vec<f64>,
    dense_d2: Vec<f64>,
    dense_d3: Vec<f64>,
}

enum Attempt {
    Done,
    /// A stage was not finite or the iteration matrix was singular.
    Broken {
        component: usize,
    },
}

impl Rodas4 {
    pub fn new<S: System + ?Sized>(
        system: &S,
        t0: f64,
        y0: &[f64],
        tol: Tolerance,
        h_max: f64,
        h0: Option<f64>,
    ) -> Result<Self, Failure> {
        let n = y0.len();
        let mut slope = vec![0.0; n];
        let controller = Controller::rodas4();
        let clock = Clock::start(system, t0, y0, &mut slope, tol, 4, h_max, h0, controller)?;
        Ok(Rodas4 {
            tol,
            clock,
            y: y0.to_vec(),
            slope,
            k: vec![vec![0.0; n]; 6],
            y_new: vec![0.0; n],
            jacobian: Matrix::zeros(n, n),
            time_partial: vec![0.0; n],
            y_old: y0.to_vec(),
            dense_d2: vec![0.0; n],
            dense_d3: vec![0.0; n],
        })
    }

    fn attempt<S: System + ?Sized>(&mut self, system: &S, h: f64) -> Result<Attempt, Failure> {
        let n = self.y.len();
        let mut iteration = Matrix::zeros(n, n);
        for j in 0..n {
            for i in 0..n {
                iteration[(i, j)] = -self.jacobian[(i, j)];
            }
            iteration[(j, j)] += 1.0 / (GAMMA * h);
        }
        let lu = Lu::in_place(iteration);
        self.clock.stats.lu_decompositions += 1;
        if lu.is_singular() {
            return Ok(Attempt::Broken { component: 0 });
        }
        let mut stage_state = vec![0.0; n];
        let mut stage_slope = self.slope.clone();
        for s in 0..6 {
            if s > 0 {
                for i in 0..n {
                    let mut v = self.y[i];
                    for j in 0..s {
                        v += A[s][j] * self.k[j][i];
                    }
                    stage_state[i] = v;
                }
                system.rhs(self.clock.t + ALPHA[s] * h, &stage_state, &mut stage_slope)?;
                self.clock.stats.rhs_evaluations += 1;
            }
            let mut right = stage_slope.clone();
            for i in 0..n {
                let mut v = right[i] + GAMMA_T[s] * h * self.time_partial[i];
                for j in 0..s {
                    v += CC[s][j] / h * self.k[j][i];
                }
                right[i] = v;
            }
            lu.solve_in_place(&mut right);
            if let Some(i) = first_non_finite(&right) {
                return Ok(Attempt::Broken { component: i });
            }
            self.k[s] = right;
        }
        // Stiffly accurate: y_new = y + Σ a_6j k_j + k_6, error = k_6.
        for i in 0..n {
            let mut v = self.y[i] + self.k[5][i];
            for j in 0..5 {
                v += A[5][j] * self.k[j][i];
            }
            self.y_new[i] = v;
        }
        Ok(Attempt::Done)
    }
}

impl Rodas4 {
    /// One accepted step under `measure`, which sees the error estimate
    /// per unit step (twice, as `e3` and `e5`), or
    /// [`StepOutcome::Declined`] when the measure declines it.
    pub fn step_measured<S: System + ?Sized, E: ErrorMeasure + ?Sized>(
        &mut self,
        system: &S,
        t_limit: f64,
        budget: &Budget,
        measure: &mut E,
    ) -> Result<StepOutcome, Failure> {
        self.jacobian.fill(0.0);
        system.jacobian(self.clock.t, &self.y, &mut self.jacobian)?;
        self.time_partial.fill(0.0);
        system.time_partial(self.clock.t, &self.y, &mut self.time_partial)?;
        self.clock.stats.jacobian_evaluations += 1;
        let mut broken: Option<usize> = None;
        let mut rate_broken: Option<usize> = None;
        let mut estimate = vec![0.0; self.y.len()];
        loop {
            let (h, reaches_limit) = self.clock.attempt(t_limit, budget, |h| {
                stalled(system, self.clock.t, h, broken, rate_broken)
            })?;
            let error = match self.attempt(system, h)? {
                Attempt::Broken { component } => {
                    broken = Some(component);
                    f64::INFINITY
                }
                Attempt::Done => {
                    broken = None;
                    for (e, k) in estimate.iter_mut().zip(&self.k[5]) {
                        *e = k / h;
                    }
                    match measure.measure(
                        self.clock.t,
                        h,
                        &self.y,
                        &self.y_new,
                        &estimate,
                        &estimate,
                    ) {
                        Some(error) => error,
                        None => return Ok(self.clock.decline()),
                    }
                }
            };
            if error <= 1.0 {
                let h_next = self.clock.controller.accept(h, error);
                for i in 0..self.y.len() {
                    let mut d2 = 0.0;
                    let mut d3 = 0.0;
                    for j in 0..5 {
                        d2 += D2[j] * self.k[j][i];
                        d3 += D3[j] * self.k[j][i];
                    }
                    self.dense_d2[i] = d2;
                    self.dense_d3[i] = d3;
                }
                let t_new = self.clock.end(h, reaches_limit, t_limit);
                system.rhs(t_new, &self.y_new, &mut estimate)?;
                self.clock.stats.rhs_evaluations += 1;
                if let Some(i) = first_non_finite(&estimate) {
                    self.clock.reject_short(h);
                    rate_broken = Some(i);
                    continue;
                }
                self.slope.copy_from_slice(&estimate);
                self.y_old.copy_from_slice(&self.y);
                std::mem::swap(&mut self.y, &mut self.y_new);
                self.clock.accept(h, t_new, h_next, reaches_limit);
                return Ok(StepOutcome::Accepted);
            }
            self.clock.reject(h, error);
        }
    }

    /// The last accepted step's continuous extension, detached.
    pub fn dense_step(&self) -> DenseStep {
        DenseStep::new(
            self.clock.t_old,
            self.clock.t,
            self.clock.h_old,
            std::sync::Arc::new(Rodas4Extension {
                y_old: self.y_old.clone(),
                y: self.y.clone(),
                d2: self.dense_d2.clone(),
                d3: self.dense_d3.clone(),
            }),
        )
    }
}

impl Clocked for Rodas4 {
    fn clock(&self) -> &Clock {
        &self.clock
    }

    fn clock_mut(&mut self) -> &mut Clock {
        &mut self.clock
    }
}

impl<S: System + ?Sized> Stepper<S> for Rodas4 {
    fn state(&self) -> &[f64] {
        &self.y
    }

    fn step(&mut self, system: &S, t_limit: f64, budget: &Budget) -> Result<(), Failure> {
        let mut measure = RmsMeasure(self.tol);
        // The inherent step, with this measure's type: no dynamic call
        // per attempt.
        Rodas4::step_measured(self, system, t_limit, budget, &mut measure).map(|_| ())
    }

    fn step_measured(
        &mut self,
        system: &S,
        t_limit: f64,
        budget: &Budget,
        measure: &mut dyn ErrorMeasure,
    ) -> Result<StepOutcome, Failure> {
        Rodas4::step_measured(self, system, t_limit, budget, measure)
    }

    fn dense(&mut self, _system: &S, t: f64, out: &mut [f64]) -> Result<(), Failure> {
        let step = self.clock.last_step();
        if let Some(end) = crate::ode::stepper::outside_last_step(t, step, &self.y_old, &self.y) {
            out.copy_from_slice(end);
            return Ok(());
        }
        let s = (t - self.clock.t_old) / self.clock.h_old;
        rodas4_dense(&self.y_old, &self.y, &self.dense_d2, &self.dense_d3, s, out);
        Ok(())
    }

    fn dense_step(&mut self, _system: &S) -> Result<Option<DenseStep>, Failure> {
        Ok(Some(Rodas4::dense_step(self)))
    }

    fn as_any(&self) -> &dyn std::any::Any {
        self
    }

    fn as_any_mut(&mut self) -> &mut dyn std::any::Any {
        self
    }
}

/// RODAS4's continuous extension of order 3, detached.
#[derive(Debug)]
struct Rodas4Extension {
    y_old: Vec<f64>,
    y: Vec<f64>,
    d2: Vec<f64>,
    d3: Vec<f64>,
}

impl Extension for Rodas4Extension {
    fn eval(&self, theta: f64, out: &mut [f64]) {
        rodas4_dense(&self.y_old, &self.y, &self.d2, &self.d3, theta, out);
    }
}

/// RODAS4's continuous extension at `θ`.
fn rodas4_dense(y_old: &[f64], y: &[f64], d2: &[f64], d3: &[f64], s: f64, out: &mut [f64]) {
    let s1 = 1.0 - s;
    for (i, o) in out.iter_mut().enumerate() {
        *o = y_old[i] * s1 + s * (y[i] + s1 * (d2[i] + s * d3[i]));
    }
}

impl Start for Rodas4 {
    const NAME: &'static str = "RODAS4";

    fn start<S: System + ?Sized>(
        system: &S,
        t0: f64,
        y0: &[f64],
        tol: Tolerance,
        h_max: f64,
        h0: Option<f64>,
    ) -> Result<Self, Failure> {
        Rodas4::new(system, t0, y0, tol, h_max, h0)
    }
}
