//! What every integrator shares: tolerances, work counters, Hairer's error
//! norm, the initial step guess, and stepping to a given time.

use super::error::{Failure, FailureKind};
use super::system::Motion;

/// Mixed error tolerance: component `i` is accepted when its local error
/// is below `atol + rtol·|x_i|`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tolerance {
    pub rtol: f64,
    pub atol: f64,
}

impl Default for Tolerance {
    fn default() -> Self {
        Tolerance {
            rtol: 1e-10,
            atol: 1e-12,
        }
    }
}

/// Work done by an integrator.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Stats {
    pub accepted_steps: usize,
    pub rejected_steps: usize,
    pub rhs_evaluations: usize,
    pub jacobian_evaluations: usize,
    pub lu_decompositions: usize,
    /// Matrix exponentials (the Magnus integrator of the field method).
    pub matrix_exponentials: usize,
}

impl std::ops::AddAssign for Stats {
    fn add_assign(&mut self, other: Stats) {
        self.accepted_steps += other.accepted_steps;
        self.rejected_steps += other.rejected_steps;
        self.rhs_evaluations += other.rhs_evaluations;
        self.jacobian_evaluations += other.jacobian_evaluations;
        self.lu_decompositions += other.lu_decompositions;
        self.matrix_exponentials += other.matrix_exponentials;
    }
}

/// A one-step integrator holding its current time and state.
pub trait Stepper {
    fn time(&self) -> f64;
    fn state(&self) -> &[f64];
    fn stats(&self) -> Stats;
    /// The length the next step will try.
    fn proposed_step(&self) -> f64;
    /// Replaces the next step's length, e.g. by the one that worked before
    /// a restart (a restarted field otherwise guesses it anew).
    fn propose_step(&mut self, h: f64);
    /// Takes one accepted step that does not pass `t_limit`; when the step
    /// is cut to reach `t_limit`, the time is set to `t_limit` exactly.
    fn step<M: Motion + ?Sized>(&mut self, system: &M, t_limit: f64) -> Result<(), Failure>;

    /// The time at which an explicit integrator found its step held by
    /// stability rather than accuracy, repeatedly (the system is stiff
    /// there); `None` if it never did or the method is stiff itself.
    fn stiffness_detected(&self) -> Option<f64> {
        None
    }

    /// Steps until the time is exactly `t_target`; stops with a
    /// step-budget failure after [`MAX_STEPS`] steps in all.
    fn advance_to<M: Motion + ?Sized>(&mut self, system: &M, t_target: f64) -> Result<(), Failure> {
        while self.time() < t_target {
            within_step_budget(self.time(), &self.stats())?;
            self.step(system, t_target)?;
        }
        Ok(())
    }
}

/// The most steps one integration may take. Each accepted step may add a
/// local error up to the tolerance; millions of them can add up to a global
/// error far above it (RODAS4 on the mass-loss spring, whose frequency
/// sweeps 100-fold: 10.5 million steps at rtol 1e-10 gave an error of
/// 2e-4). Stopping with a clear message beats a silently wrong answer.
pub const MAX_STEPS: usize = 1_000_000;

/// `Err` once `stats` count [`MAX_STEPS`] steps (accepted and rejected).
pub fn within_step_budget(t: f64, stats: &Stats) -> Result<(), Failure> {
    let steps = stats.accepted_steps + stats.rejected_steps;
    if steps >= MAX_STEPS {
        return Err(Failure::new(t, FailureKind::StepBudgetExhausted { steps }));
    }
    Ok(())
}

/// The step to try from `t` with proposed length `h` toward `t_limit`:
/// `(length, reaches_limit)`, the length cut to land on `t_limit` exactly
/// when the proposed step would reach or pass it.
pub fn step_toward(t: f64, h: f64, t_limit: f64) -> (f64, bool) {
    if t + h >= t_limit {
        (t_limit - t, true)
    } else {
        (h, false)
    }
}

/// The smallest step allowed at time `t` (Hairer's `16·eps·|t|` test).
pub fn underflows(t: f64, h: f64) -> bool {
    h.abs() < 16.0 * f64::EPSILON * t.abs().max(f64::MIN_POSITIVE)
}

pub fn underflow_failure(t: f64, h: f64) -> Failure {
    Failure::new(t, FailureKind::StepSizeUnderflow { step: h })
}

/// The index of the first non-finite component, if any.
pub fn first_non_finite(values: &[f64]) -> Option<usize> {
    values.iter().position(|v| !v.is_finite())
}

/// Root-mean-square of `err_i / (atol + rtol·max(|y0_i|, |y1_i|))`.
pub fn rms_norm(err: &[f64], y0: &[f64], y1: &[f64], tol: Tolerance) -> f64 {
    let n = err.len().max(1) as f64;
    let sum: f64 = err
        .iter()
        .zip(y0.iter().zip(y1))
        .map(|(e, (a, b))| {
            let scale = tol.atol + tol.rtol * a.abs().max(b.abs());
            (e / scale).powi(2)
        })
        .sum();
    (sum / n).sqrt()
}

/// Hairer's initial step guess (HNW I, II.4) for a method of order `order`,
/// costing one evaluation of the right side.
pub fn initial_step<M: Motion + ?Sized>(
    system: &M,
    t0: f64,
    y0: &[f64],
    f0: &[f64],
    tol: Tolerance,
    order: i32,
    h_max: f64,
) -> Result<f64, Failure> {
    let d0 = rms_norm(y0, y0, y0, tol);
    let d1 = rms_norm(f0, y0, y0, tol);
    let mut h0 = if d0 < 1e-5 || d1 < 1e-5 {
        1e-6
    } else {
        0.01 * d0 / d1
    };
    h0 = h0.min(h_max);
    let y1: Vec<f64> = y0.iter().zip(f0).map(|(y, f)| y + h0 * f).collect();
    let mut f1 = vec![0.0; y0.len()];
    system.rhs(t0 + h0, &y1, &mut f1)?;
    let diff: Vec<f64> = f1.iter().zip(f0).map(|(a, b)| a - b).collect();
    let d2 = rms_norm(&diff, y0, y0, tol) / h0;
    let h1 = if d1.max(d2) <= 1e-15 {
        (h0 * 1e-3).max(1e-6)
    } else {
        (0.01 / d1.max(d2)).powf(1.0 / f64::from(order + 1))
    };
    let h = (100.0 * h0).min(h1).min(h_max);
    Ok(if h.is_finite() && h > 0.0 { h } else { 1e-6 })
}
