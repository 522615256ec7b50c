//! What every integrator shares: tolerances, work counters, the error norm
//! and the initial step guess.

use crate::failure::Failure;
use crate::ode::system::System;

/// Mixed error tolerance: component `i` of a local error is acceptable
/// when it is below `atol + rtol·|x_i|`. A per-step tolerance: the global
/// error of a run is usually a modest multiple of it, more over long
/// horizons (direct integration's summary estimates it,
/// `dop853::global_error`; `--estimate-error` measures it).
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

impl Tolerance {
    /// How many tolerances `a` stands off `b`: the largest component's
    /// distance, each scaled by `atol + rtol·max(|a|, |b|)`, not the RMS
    /// norm, since a sample is read component by component (the
    /// gravity-turn rocket's altitude near the ground was 0.27 tolerances
    /// off in mid-step at rtol 1e-8, its RMS over the four components
    /// 0.06). Not finite: infinitely off. The outputs' middle checks
    /// (the field's pieces, direct DOP853's steps).
    pub fn tolerances_off(self, a: &[f64], b: &[f64]) -> f64 {
        a.iter()
            .zip(b)
            .map(|(x, y)| {
                let off = (x - y).abs() / (self.atol + self.rtol * x.abs().max(y.abs()));
                if off.is_nan() {
                    f64::INFINITY
                } else {
                    off
                }
            })
            .fold(0.0_f64, f64::max)
    }

    /// The tolerance scaled by `factor` (both parts).
    pub fn scaled(self, factor: f64) -> Tolerance {
        Tolerance {
            rtol: self.rtol * factor,
            atol: self.atol * factor,
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

impl std::ops::Add for Stats {
    type Output = Stats;
    fn add(mut self, other: Stats) -> Stats {
        self += other;
        self
    }
}

/// The index of the first non-finite value, if any.
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

/// The smallest step allowed at time `t` (Hairer's `16·eps·|t|` test).
pub fn underflows(t: f64, h: f64) -> bool {
    h.abs() < 16.0 * f64::EPSILON * t.abs().max(f64::MIN_POSITIVE)
}

/// The step to try from `t` with proposed length `h` toward `t_limit`:
/// `(length, reaches_limit)`, cut to land on `t_limit` exactly when the
/// proposed step would reach or pass it.
pub fn step_toward(t: f64, h: f64, t_limit: f64) -> (f64, bool) {
    if t + h >= t_limit {
        (t_limit - t, true)
    } else {
        (h, false)
    }
}

/// Hairer's initial step guess (HNW I, II.4) for a method of order
/// `order`, costing one evaluation of the right side.
pub fn initial_step<S: System + ?Sized>(
    system: &S,
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
    // One buffer: the Euler step's state, then the slope there (a small
    // model's whole solve costs a few microseconds), on the stack up to
    // 16 components (an allocation and its free were about 1 % of the
    // paper's 6-step solve, docs/BENCHMARKS.md §10i).
    let n = y0.len();
    let mut small = [0.0; 32];
    let mut large = Vec::new();
    let work: &mut [f64] = if 2 * n <= small.len() {
        &mut small[..2 * n]
    } else {
        large.resize(2 * n, 0.0);
        &mut large
    };
    let (y1, f1) = work.split_at_mut(n);
    for ((y1, y), f) in y1.iter_mut().zip(y0).zip(f0) {
        *y1 = y + h0 * f;
    }
    system.rhs(t0 + h0, y1, f1)?;
    // The slope's change, in place.
    for (d, f) in f1.iter_mut().zip(f0) {
        *d -= f;
    }
    let d2 = rms_norm(f1, y0, y0, tol) / h0;
    let h1 = if d1.max(d2) <= 1e-15 {
        (h0 * 1e-3).max(1e-6)
    } else {
        (0.01 / d1.max(d2)).powf(1.0 / f64::from(order + 1))
    };
    let h = (100.0 * h0).min(h1).min(h_max);
    Ok(if h.is_finite() && h > 0.0 { h } else { 1e-6 })
}
