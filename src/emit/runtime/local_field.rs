//! The local field method for systems not affine in `x_2..x_N` (SPEC §1.5):
//! on each window `[t_r, t_r + H]` the system is linearised about the
//! current state in `x` and in `t`,
//! `X ≈ a x + b(t)`, `a = ∂X/∂x (t_r, x_r)`, `b(t) = X_r − a x_r + ∂X/∂t·(t − t_r)`,
//! the linearisation is integrated exactly by its own field (re-anchored at
//! every window), and the next window starts from the result.
//!
//! Order: the frozen linearisation is the exponential Rosenbrock–Euler
//! method, local error `O(H³)`, global order 2. Each window is also done as
//! two half windows (the second linearised at the midpoint); their
//! difference estimates the error for the window-size control, and the
//! accepted state is the Richardson combination `x_half + (x_half − x_full)/3`
//! (local error `O(H⁴)`, global order 3; the error is estimated
//! conservatively by the
//! order-2 difference).

use super::error::Failure;
use super::field::{solve_field, FieldOptions};
use super::stepper::{
    first_non_finite, rms_norm, step_toward, underflow_failure, underflows, Stats,
};
use super::system::{CoefficientSystem, Motion};
use nalgebra::{DMatrix, DVector};

/// The coefficient system of the affine system `x' = a x + b(t)` with
/// `b(t) = b0 + b_slope·(t − t_r)`, by SPEC §1.5's formulas:
/// `f_1' = b_1 − Σ_A f_A b_A + λ f_1`, `f_B' = a_1B − Σ_A f_A a_AB + λ f_B`,
/// `λ = a_11 − Σ_A f_A a_A1`.
pub struct AffineCoefficients {
    pub a: DMatrix<f64>,
    pub b0: DVector<f64>,
    pub b_slope: DVector<f64>,
    pub t_r: f64,
}

impl AffineCoefficients {
    fn b(&self, t: f64) -> DVector<f64> {
        &self.b0 + &self.b_slope * (t - self.t_r)
    }

    fn lambda(&self, f: &[f64]) -> f64 {
        let n = f.len();
        self.a[(0, 0)] - (1..n).map(|k| f[k] * self.a[(k, 0)]).sum::<f64>()
    }
}

impl CoefficientSystem for AffineCoefficients {
    fn dim(&self) -> usize {
        self.a.nrows()
    }

    fn rhs(&self, t: f64, f: &[f64], df: &mut [f64]) -> Result<(), Failure> {
        let n = f.len();
        let b = self.b(t);
        let lambda = self.lambda(f);
        df[0] = b[0] - (1..n).map(|k| f[k] * b[k]).sum::<f64>() + lambda * f[0];
        for col in 1..n {
            df[col] = self.a[(0, col)] - (1..n).map(|k| f[k] * self.a[(k, col)]).sum::<f64>()
                + lambda * f[col];
        }
        Ok(())
    }

    fn jacobian(&self, t: f64, f: &[f64], jac: &mut DMatrix<f64>) -> Result<(), Failure> {
        let n = f.len();
        let b = self.b(t);
        let lambda = self.lambda(f);
        // ∂λ/∂f_1 = 0, ∂λ/∂f_k = −a_k1.
        jac[(0, 0)] = lambda;
        for k in 1..n {
            jac[(0, k)] = -b[k] - self.a[(k, 0)] * f[0];
        }
        for row in 1..n {
            for k in 1..n {
                jac[(row, k)] = -self.a[(k, row)] - self.a[(k, 0)] * f[row];
            }
            jac[(row, row)] += lambda;
        }
        Ok(())
    }

    fn time_partial(&self, _t: f64, f: &[f64], dfdt: &mut [f64]) -> Result<(), Failure> {
        let n = f.len();
        dfdt[0] = self.b_slope[0] - (1..n).map(|k| f[k] * self.b_slope[k]).sum::<f64>();
        Ok(())
    }

    fn is_linear(&self) -> bool {
        (1..self.a.nrows()).all(|k| self.a[(k, 0)] == 0.0)
    }
}

/// What the local field method did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LocalFieldReport {
    /// Work of all window fields together.
    pub field_stats: Stats,
    pub accepted_windows: usize,
    pub rejected_windows: usize,
    /// Evaluations of `X`, `∂X/∂x` and `∂X/∂t` (one per linearisation).
    pub linearisations: usize,
    pub largest_condition: f64,
}

/// Integrates `motion` by the local field method, calling `on_sample` at
/// every sample time. `options.tol` controls both the window size and the
/// window fields (which run `100×` tighter, so that the linearisation
/// error dominates and the estimate sees it).
pub fn solve_local_field<M: Motion + ?Sized>(
    motion: &M,
    options: &FieldOptions,
    times: &[f64],
    x0: &[f64],
    mut on_sample: impl FnMut(f64, &[f64]),
) -> Result<LocalFieldReport, Failure> {
    let mut report = LocalFieldReport {
        largest_condition: 1.0,
        ..LocalFieldReport::default()
    };
    let Some((&t0, rest)) = times.split_first() else {
        return Ok(report);
    };
    let mut inner = options.clone();
    inner.tol.rtol *= 0.01;
    inner.tol.atol *= 0.01;
    // A window is short and its linearisation frozen: DOP853 crosses it in
    // a step or two, where the Magnus integrator's three matrix
    // exponentials per step cost more (debug test: 1.7 s vs 5.6 s).
    inner.magnus = false;
    let (mut t, mut x) = (t0, x0.to_vec());
    let mut window = 1e-3 * times.last().map_or(1.0, |t1| (t1 - t0).abs().max(1e-300));
    on_sample(t0, x0);
    for &target in rest {
        while t < target {
            let (h, reaches) = step_toward(t, window, target);
            if underflows(t, h) && !reaches {
                return Err(underflow_failure(t, h));
            }
            let full = linearised_window(motion, &inner, t, &x, h, &mut report)?;
            let mid = linearised_window(motion, &inner, t, &x, 0.5 * h, &mut report)?;
            let half = linearised_window(motion, &inner, t + 0.5 * h, &mid, 0.5 * h, &mut report)?;
            let difference: Vec<f64> = half.iter().zip(&full).map(|(a, b)| a - b).collect();
            let error = rms_norm(&difference, &x, &half, options.tol) / 3.0;
            let scale = if error == 0.0 {
                5.0
            } else {
                (0.9 * error.powf(-1.0 / 3.0)).clamp(0.2, 5.0)
            };
            if error <= 1.0 {
                x = half
                    .iter()
                    .zip(&difference)
                    .map(|(v, d)| v + d / 3.0)
                    .collect();
                if let Some(i) = first_non_finite(&x) {
                    return Err(Failure::non_finite(t + h, motion.component_name(i)));
                }
                t = if reaches { target } else { t + h };
                window = if reaches {
                    window.max(h * scale)
                } else {
                    h * scale
                };
                report.accepted_windows += 1;
            } else {
                window = h * scale;
                report.rejected_windows += 1;
            }
        }
        on_sample(target, &x);
    }
    Ok(report)
}

/// The state at `t_r + h` of the system linearised at `(t_r, x_r)`, by its
/// field.
fn linearised_window<M: Motion + ?Sized>(
    motion: &M,
    options: &FieldOptions,
    t_r: f64,
    x_r: &[f64],
    h: f64,
    report: &mut LocalFieldReport,
) -> Result<Vec<f64>, Failure> {
    let n = x_r.len();
    let mut a = DMatrix::zeros(n, n);
    motion.jacobian(t_r, x_r, &mut a)?;
    let mut slope = vec![0.0; n];
    motion.rhs(t_r, x_r, &mut slope)?;
    let mut b_slope = DVector::zeros(n);
    motion.time_partial(t_r, x_r, b_slope.as_mut_slice())?;
    report.linearisations += 1;
    let b0 = DVector::from_column_slice(&slope) - &a * DVector::from_column_slice(x_r);
    let coefficients = AffineCoefficients {
        a,
        b0,
        b_slope,
        t_r,
    };
    let mut end = x_r.to_vec();
    let field = solve_field(&coefficients, options, &[t_r, t_r + h], x_r, |_, x| {
        end.copy_from_slice(x)
    })?;
    report.field_stats += field.stats;
    report.largest_condition = report.largest_condition.max(field.largest_condition);
    Ok(end)
}
