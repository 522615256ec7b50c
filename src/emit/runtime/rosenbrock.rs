//! RODAS4: the stiffly accurate, L-stable Rosenbrock method of order 4 with
//! an embedded order-3 solution (HNW II, VI.4), using the analytic Jacobian
//! `∂X/∂x` and `∂X/∂t` of the system and an LU factorisation per step.
//! Coefficients as in Hairer's `rodas.f` (the RODAS4 set), in the
//! formulation without the Jacobian in the right sides:
//! `(I/(γh) − J) k_i = X(t + α_i h, y + Σ a_ij k_j) + Σ c_ij k_j / h + γ_i h X_t`.

// The coefficients are kept as Hairer printed them (trailing zeros included).
#![allow(clippy::excessive_precision)]

use super::error::Failure;
use super::stepper::{
    first_non_finite, initial_step, rms_norm, step_toward, underflow_failure, underflows, Stats,
    Stepper, Tolerance,
};
use super::system::Motion;
use nalgebra::{DMatrix, DVector};

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

const SAFETY: f64 = 0.9;
const MIN_SCALE: f64 = 0.2;
const MAX_SCALE: f64 = 6.0;

/// The RODAS4 integrator at time `t` with state `y`.
pub struct Rodas4 {
    tol: Tolerance,
    t: f64,
    y: Vec<f64>,
    /// `X(t, y)`.
    slope: Vec<f64>,
    h: f64,
    stats: Stats,
}

enum Attempt {
    Done {
        y_new: Vec<f64>,
        error: f64,
    },
    /// A stage was not finite or the iteration matrix was singular.
    Broken {
        component: usize,
    },
}

impl Rodas4 {
    pub fn new<M: Motion + ?Sized>(
        system: &M,
        t0: f64,
        y0: &[f64],
        tol: Tolerance,
        h_max: f64,
    ) -> Result<Self, Failure> {
        if let Some(i) = first_non_finite(y0) {
            return Err(Failure::non_finite(t0, system.component_name(i)));
        }
        let mut slope = vec![0.0; y0.len()];
        system.rhs(t0, y0, &mut slope)?;
        if let Some(i) = first_non_finite(&slope) {
            return Err(Failure::non_finite(
                t0,
                format!("{}'", system.component_name(i)),
            ));
        }
        let h = initial_step(system, t0, y0, &slope, tol, 4, h_max)?;
        Ok(Rodas4 {
            tol,
            t: t0,
            y: y0.to_vec(),
            slope,
            h,
            stats: Stats {
                rhs_evaluations: 2,
                ..Stats::default()
            },
        })
    }

    fn attempt<M: Motion + ?Sized>(
        &mut self,
        system: &M,
        h: f64,
        jacobian: &DMatrix<f64>,
        time_partial: &DVector<f64>,
    ) -> Result<Attempt, Failure> {
        let n = self.y.len();
        let mut iteration = -jacobian.clone();
        for i in 0..n {
            iteration[(i, i)] += 1.0 / (GAMMA * h);
        }
        let lu = iteration.lu();
        self.stats.lu_decompositions += 1;
        let y0 = DVector::from_column_slice(&self.y);
        let mut k: Vec<DVector<f64>> = Vec::with_capacity(6);
        let mut stage_slope = DVector::from_column_slice(&self.slope);
        for s in 0..6 {
            if s > 0 {
                let mut stage_state = y0.clone();
                for (j, kj) in k.iter().enumerate() {
                    stage_state.axpy(A[s][j], kj, 1.0);
                }
                system.rhs(
                    self.t + ALPHA[s] * h,
                    stage_state.as_slice(),
                    stage_slope.as_mut_slice(),
                )?;
                self.stats.rhs_evaluations += 1;
            }
            let mut right = stage_slope.clone();
            right.axpy(GAMMA_T[s] * h, time_partial, 1.0);
            for (j, kj) in k.iter().enumerate() {
                right.axpy(CC[s][j] / h, kj, 1.0);
            }
            if !lu.solve_mut(&mut right) {
                return Ok(Attempt::Broken { component: 0 });
            }
            if let Some(i) = first_non_finite(right.as_slice()) {
                return Ok(Attempt::Broken { component: i });
            }
            k.push(right);
        }
        // Stiffly accurate: y_new = y + Σ a_6j k_j + k_6, error = k_6.
        let mut y_new = y0;
        for (j, kj) in k.iter().take(5).enumerate() {
            y_new.axpy(A[5][j], kj, 1.0);
        }
        y_new += &k[5];
        let y_new: Vec<f64> = y_new.iter().copied().collect();
        let error = rms_norm(k[5].as_slice(), &self.y, &y_new, self.tol);
        Ok(Attempt::Done { y_new, error })
    }
}

impl Stepper for Rodas4 {
    fn time(&self) -> f64 {
        self.t
    }

    fn state(&self) -> &[f64] {
        &self.y
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

    fn step<M: Motion + ?Sized>(&mut self, system: &M, t_limit: f64) -> Result<(), Failure> {
        let n = self.y.len();
        let mut jacobian = DMatrix::zeros(n, n);
        system.jacobian(self.t, &self.y, &mut jacobian)?;
        let mut time_partial = DVector::zeros(n);
        system.time_partial(self.t, &self.y, time_partial.as_mut_slice())?;
        self.stats.jacobian_evaluations += 1;
        let mut last_rejected = false;
        let mut broken: Option<usize> = None;
        loop {
            let (h, reaches_limit) = step_toward(self.t, self.h, t_limit);
            if underflows(self.t, h) && !reaches_limit {
                return Err(match broken {
                    Some(i) => Failure::non_finite(self.t, system.component_name(i)),
                    None => underflow_failure(self.t, h),
                });
            }
            match self.attempt(system, h, &jacobian, &time_partial)? {
                Attempt::Broken { component } => {
                    self.stats.rejected_steps += 1;
                    self.h = h * 0.25;
                    last_rejected = true;
                    broken = Some(component);
                }
                Attempt::Done { y_new, error } if error <= 1.0 => {
                    let scale = if error == 0.0 {
                        MAX_SCALE
                    } else {
                        (SAFETY * error.powf(-0.25)).clamp(MIN_SCALE, MAX_SCALE)
                    };
                    let h_next = if last_rejected {
                        h * scale.min(1.0)
                    } else {
                        h * scale
                    };
                    self.y = y_new;
                    self.t = if reaches_limit { t_limit } else { self.t + h };
                    self.h = if reaches_limit {
                        h_next.max(self.h)
                    } else {
                        h_next
                    };
                    system.rhs(self.t, &self.y, &mut self.slope)?;
                    self.stats.rhs_evaluations += 1;
                    self.stats.accepted_steps += 1;
                    if let Some(i) = first_non_finite(&self.slope) {
                        return Err(Failure::non_finite(
                            self.t,
                            format!("{}'", system.component_name(i)),
                        ));
                    }
                    return Ok(());
                }
                Attempt::Done { error, .. } => {
                    self.stats.rejected_steps += 1;
                    self.h = h * (SAFETY * error.powf(-0.25)).max(MIN_SCALE);
                    last_rejected = true;
                    broken = None;
                }
            }
        }
    }
}
