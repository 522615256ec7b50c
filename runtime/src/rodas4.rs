//! RODAS4: the stiffly accurate, L-stable Rosenbrock method of order 4 with
//! an embedded order-3 solution and a continuous extension of order 3
//! (HNW II, VI.4; Hairer's `rodas.f`, the RODAS4 coefficient set), using
//! the exact Jacobian `∂X/∂x`, the exact time partial `∂X/∂t` and one LU
//! factorisation per step. Formulation without the Jacobian in the right
//! sides: `(I/(γh) − J) k_i = X(t + α_i h, y + Σ a_ij k_j) + Σ c_ij k_j / h
//! + γ_i h X_t`; the `k_i` are increments.

// The coefficients are kept as Hairer printed them.
#![allow(clippy::excessive_precision, clippy::unreadable_literal)]

use crate::budget::Budget;
use crate::controller::Controller;
use crate::failure::{Failure, FailureKind};
use crate::linalg::{Lu, Matrix};
use crate::stepper::{DenseKind, DenseStep, ErrorMeasure, StepOutcome, Stepper};
use crate::system::System;
use crate::tolerance::{
    first_non_finite, initial_step, rms_norm, step_toward, underflows, Stats, Tolerance,
};

const GAMMA: f64 = 0.25;
const ALPHA: [f64; 6] = [0.0, 0.386, 0.21, 0.63, 1.0, 1.0];
/// `γ_i`, the weights of `h·∂X/∂t` in stages 1–4.
const GAMMA_T: [f64; 6] = [0.25, -0.1043, 0.1035, -0.3620000000000023e-01, 0.0, 0.0];
/// Rows of `a_ij` (strictly lower triangular); stage 6 starts from the
/// stage-5 state plus `k_5`, which the last row encodes.
const A: [[f64; 5]; 6] = [
    [0.0; 5],
    [0.1544000000000000e+01, 0.0, 0.0, 0.0, 0.0],
    [
        0.9466785280815826e+00,
        0.2557011698983284e+00,
        0.0,
        0.0,
        0.0,
    ],
    [
        0.3314825187068521e+01,
        0.2896124015972201e+01,
        0.9986419139977817e+00,
        0.0,
        0.0,
    ],
    [
        0.1221224509226641e+01,
        0.6019134481288629e+01,
        0.1253708332932087e+02,
        -0.6878860361058950e+00,
        0.0,
    ],
    [
        0.1221224509226641e+01,
        0.6019134481288629e+01,
        0.1253708332932087e+02,
        -0.6878860361058950e+00,
        1.0,
    ],
];
/// Rows of `c_ij` (strictly lower triangular).
const CC: [[f64; 5]; 6] = [
    [0.0; 5],
    [-0.5668800000000000e+01, 0.0, 0.0, 0.0, 0.0],
    [
        -0.2430093356833875e+01,
        -0.2063599157091915e+00,
        0.0,
        0.0,
        0.0,
    ],
    [
        -0.1073529058151375e+00,
        -0.9594562251023355e+01,
        -0.2047028614809616e+02,
        0.0,
        0.0,
    ],
    [
        0.7496443313967647e+01,
        -0.1024680431464352e+02,
        -0.3399990352819905e+02,
        0.1170890893206160e+02,
        0.0,
    ],
    [
        0.8083246795921522e+01,
        -0.7981132988064893e+01,
        -0.3152159432874371e+02,
        0.1631930543123136e+02,
        -0.6058818238834054e+01,
    ],
];

/// The continuous extension (`rodas.f`): `y(θ) = y0 (1 − θ) + θ (y1 +
/// (1 − θ)(d2·k + θ d3·k))` with the rows below over `k_1..k_5`.
const D2: [f64; 5] = [
    0.1012623508344586e+02,
    -0.7487995877610167e+01,
    -0.3480091861555747e+02,
    -0.7992771707568823e+01,
    0.1025137723295662e+01,
];
const D3: [f64; 5] = [
    -0.6762803392801253e+00,
    0.6087714651680015e+01,
    0.1643084320892478e+02,
    0.2476722511418386e+02,
    -0.6594389125716872e+01,
];

/// The RODAS4 integrator at time `t` with state `y`.
pub struct Rodas4 {
    tol: Tolerance,
    t: f64,
    y: Vec<f64>,
    /// `X(t, y)`.
    slope: Vec<f64>,
    h: f64,
    controller: Controller,
    stats: Stats,
    /// Scratch: the stage increments of the last attempt.
    k: Vec<Vec<f64>>,
    y_new: Vec<f64>,
    jacobian: Matrix,
    time_partial: Vec<f64>,
    /// The last accepted step: start, length, start state, and the
    /// continuous extension's two coefficient vectors.
    t_old: f64,
    h_old: f64,
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
        if let Some(i) = first_non_finite(y0) {
            return Err(Failure::non_finite(t0, system.component_name(i)));
        }
        let mut slope = vec![0.0; n];
        system.rhs(t0, y0, &mut slope)?;
        if let Some(i) = first_non_finite(&slope) {
            return Err(Failure::non_finite_rate(t0, system.rate_name(i)));
        }
        let mut stats = Stats {
            rhs_evaluations: 1,
            ..Stats::default()
        };
        let h = match h0 {
            Some(h) if h.is_finite() && h > 0.0 => h.min(h_max),
            _ => {
                stats.rhs_evaluations += 1;
                initial_step(system, t0, y0, &slope, tol, 4, h_max)?
            }
        };
        Ok(Rodas4 {
            tol,
            t: t0,
            y: y0.to_vec(),
            slope,
            h,
            controller: Controller::rodas4(),
            stats,
            k: vec![vec![0.0; n]; 6],
            y_new: vec![0.0; n],
            jacobian: Matrix::zeros(n, n),
            time_partial: vec![0.0; n],
            t_old: t0,
            h_old: 0.0,
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
        self.stats.lu_decompositions += 1;
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
                system.rhs(self.t + ALPHA[s] * h, &stage_state, &mut stage_slope)?;
                self.stats.rhs_evaluations += 1;
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

/// The RMS norm of RODAS4's error estimate, scaled by the tolerance.
struct RmsMeasure(Tolerance);

impl ErrorMeasure for RmsMeasure {
    fn measure(
        &mut self,
        _t0: f64,
        h: f64,
        y0: &[f64],
        y1: &[f64],
        _e3: &[f64],
        e5: &[f64],
    ) -> Option<f64> {
        let e: Vec<f64> = e5.iter().map(|v| v * h).collect();
        Some(rms_norm(&e, y0, y1, self.0))
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
        system.jacobian(self.t, &self.y, &mut self.jacobian)?;
        self.time_partial.fill(0.0);
        system.time_partial(self.t, &self.y, &mut self.time_partial)?;
        self.stats.jacobian_evaluations += 1;
        let mut broken: Option<usize> = None;
        let mut rate_broken: Option<usize> = None;
        let mut estimate = vec![0.0; self.y.len()];
        loop {
            budget.draw(self.t)?;
            let (h, reaches_limit) = step_toward(self.t, self.h, t_limit);
            if underflows(self.t, h) && !reaches_limit {
                return Err(match (broken, rate_broken) {
                    (Some(i), _) => Failure::non_finite(self.t, system.component_name(i)),
                    (None, Some(i)) => Failure::non_finite_rate(self.t, system.rate_name(i)),
                    (None, None) => {
                        Failure::new(self.t, FailureKind::StepSizeUnderflow { step: h })
                    }
                });
            }
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
                    match measure.measure(self.t, h, &self.y, &self.y_new, &estimate, &estimate) {
                        Some(error) => error,
                        None => {
                            self.stats.rejected_steps += 1;
                            return Ok(StepOutcome::Declined);
                        }
                    }
                }
            };
            if error <= 1.0 {
                let h_next = self.controller.accept(h, error);
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
                let t_new = if reaches_limit { t_limit } else { self.t + h };
                system.rhs(t_new, &self.y_new, &mut estimate)?;
                self.stats.rhs_evaluations += 1;
                if let Some(i) = first_non_finite(&estimate) {
                    // The step ends where the rates are not defined (a
                    // force infinite just ahead): retry shorter, so that
                    // the motion stops at the boundary, not beyond it.
                    self.stats.rejected_steps += 1;
                    self.h = 0.25 * h;
                    rate_broken = Some(i);
                    continue;
                }
                self.slope.copy_from_slice(&estimate);
                self.y_old.copy_from_slice(&self.y);
                std::mem::swap(&mut self.y, &mut self.y_new);
                self.t_old = self.t;
                self.h_old = h;
                self.t = t_new;
                self.h = if reaches_limit {
                    h_next.max(self.h)
                } else {
                    h_next
                };
                self.stats.accepted_steps += 1;
                return Ok(StepOutcome::Accepted);
            }
            self.stats.rejected_steps += 1;
            self.h = self.controller.reject(h, error);
        }
    }

    /// The last accepted step's continuous extension, detached.
    pub fn dense_step(&self) -> DenseStep {
        DenseStep {
            t_old: self.t_old,
            t_new: self.t,
            h: self.h_old,
            kind: DenseKind::Rodas4 {
                y_old: self.y_old.clone(),
                y: self.y.clone(),
                d2: self.dense_d2.clone(),
                d3: self.dense_d3.clone(),
            },
        }
    }
}

/// RODAS4's continuous extension at `θ`.
pub(crate) fn eval_dense(
    y_old: &[f64],
    y: &[f64],
    d2: &[f64],
    d3: &[f64],
    s: f64,
    out: &mut [f64],
) {
    let s1 = 1.0 - s;
    for (i, o) in out.iter_mut().enumerate() {
        *o = y_old[i] * s1 + s * (y[i] + s1 * (d2[i] + s * d3[i]));
    }
}

impl Stepper for Rodas4 {
    fn time(&self) -> f64 {
        self.t
    }

    fn state(&self) -> &[f64] {
        &self.y
    }

    fn previous_time(&self) -> f64 {
        self.t_old
    }

    fn stats(&self) -> Stats {
        self.stats
    }

    fn proposed_step(&self) -> f64 {
        self.h
    }

    fn propose_step(&mut self, h: f64) {
        if h.is_finite() && h > 0.0 {
            self.h = h;
        }
    }

    fn step<S: System + ?Sized>(
        &mut self,
        system: &S,
        t_limit: f64,
        budget: &Budget,
    ) -> Result<(), Failure> {
        let mut measure = RmsMeasure(self.tol);
        self.step_measured(system, t_limit, budget, &mut measure)
            .map(|_| ())
    }

    fn dense<S: System + ?Sized>(
        &mut self,
        _system: &S,
        t: f64,
        out: &mut [f64],
    ) -> Result<(), Failure> {
        let step = (self.t_old, self.t, self.h_old);
        if let Some(end) = crate::stepper::outside_last_step(t, step, &self.y_old, &self.y) {
            out.copy_from_slice(end);
            return Ok(());
        }
        let s = (t - self.t_old) / self.h_old;
        eval_dense(&self.y_old, &self.y, &self.dense_d2, &self.dense_d3, s, out);
        Ok(())
    }
}
