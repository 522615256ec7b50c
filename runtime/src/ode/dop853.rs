//! DOP853: the explicit Runge–Kutta method of order 8 of Dormand and Prince
//! with Hairer's combined 5th/3rd-order error estimate and his continuous
//! extension of order 7 (HNW I, II.10; `dop853.f`, `contd8`), under the
//! PI step-size controller. Dense output costs three more evaluations per
//! step, spent only for steps whose interior is asked for.

// The coefficients are kept to the digits Hairer published them with.
#![allow(clippy::excessive_precision, clippy::unreadable_literal)]

use crate::failure::Failure;
use crate::ode::budget::Budget;
use crate::ode::controller::Controller;
use crate::ode::dense::Extension;
use crate::ode::stepper::{stalled, Clock, Clocked, ErrorMeasure, Start, StepOutcome, Stepper};
use crate::ode::system::System;
use crate::ode::tolerance::{first_non_finite, Tolerance};

pub mod global_error;
mod inside;
pub(crate) mod tableau;
use tableau::*;

/// Hairer's stiffness test (`dop853.f`): `h·ρ` estimated from the last
/// stage, `h ‖X(t+h, y₁) − X(t+h, ŷ)‖ / ‖y₁ − ŷ‖`, past the edge of
/// DOP853's stability region (≈ 6.1 on the negative real axis) on
/// `STIFF_STEPS` tests, not interrupted by `NON_STIFF_STEPS` tests below it.
const STIFF_H_RHO: f64 = 6.1;
const STIFF_STEPS: usize = 15;
const NON_STIFF_STEPS: usize = 6;

/// Hairer's measure (`dop853.f`): `|h| ε₅ / √(n (ε₅² + 0.01 ε₃²))`, the
/// sums scaled by `atol + rtol·max(|y0|, |y1|)`.
pub struct HairerMeasure(pub Tolerance);

impl ErrorMeasure for HairerMeasure {
    fn measure(
        &mut self,
        _t0: f64,
        h: f64,
        y0: &[f64],
        y1: &[f64],
        e3: &[f64],
        e5: &[f64],
    ) -> Option<f64> {
        Some(hairer_error(self.0, h, y0, y1, e3, e5))
    }

    fn hairer_tolerance(&self) -> Option<Tolerance> {
        Some(self.0)
    }
}

/// Hairer's combined error norm of DOP853.
pub fn hairer_error(tol: Tolerance, h: f64, y0: &[f64], y1: &[f64], e3: &[f64], e5: &[f64]) -> f64 {
    let n = y0.len();
    let (y1, e3, e5) = (&y1[..n], &e3[..n], &e5[..n]);
    let (mut err3, mut err5) = (0.0, 0.0);
    for i in 0..n {
        let inverse = 1.0 / (tol.atol + tol.rtol * y0[i].abs().max(y1[i].abs()));
        let (a, b) = (e3[i] * inverse, e5[i] * inverse);
        err3 += a * a;
        err5 += b * b;
    }
    hairer_combine(h, n, err3, err5)
}

/// Hairer's norm from the sums of squares of the scaled 3rd- and
/// 5th-order estimates over `n` components.
#[inline]
fn hairer_combine(h: f64, n: usize, err3: f64, err5: f64) -> f64 {
    let denominator = if err5 + 0.01 * err3 > 0.0 {
        err5 + 0.01 * err3
    } else {
        1.0
    };
    let err = h.abs() * err5 * (1.0 / (n.max(1) as f64 * denominator)).sqrt();
    if err.is_finite() {
        err
    } else {
        f64::INFINITY
    }
}

/// Blocks of `n` numbers in [`Dop853`]'s stage buffer after the 16 stages:
/// the state at which a stage is evaluated;
const STAGE_STATE: usize = STAGES + 4;
/// the 3rd- and 5th-order error estimates of the last attempt, per unit
/// step (multiply by `h`);
const ERROR3: usize = STAGE_STATE + 1;
const ERROR5: usize = ERROR3 + 1;
/// the 8 blocks of the continuous extension's coefficients.
const CONT: usize = ERROR5 + 1;
const BLOCKS: usize = CONT + 8;

/// The DOP853 integrator at time `t` with state `y`.
pub struct Dop853 {
    tol: Tolerance,
    clock: Clock,
    y: Vec<f64>,
    /// Stages, `n` numbers each in one buffer (stage `j` at `j n`):
    /// `k[0] = X(t, y)` (first same as last), `k[1..12]` the stages of the
    /// last step, `k[12]` the rate at the last step's start after a step is
    /// accepted (kept for the continuous extension), `k[13..16]` its extra
    /// stages; then, in the same buffer (one allocation a solver, not
    /// five: a small model's solve is a few microseconds), the blocks at
    /// [`STAGE_STATE`], [`ERROR3`], [`ERROR5`] and [`CONT`].
    k: Vec<f64>,
    y_trial: Vec<f64>,
    /// The last accepted step's start state.
    y_old: Vec<f64>,
    /// The continuous extension's coefficients (the 8 blocks at [`CONT`])
    /// are those of the last accepted step.
    dense_ready: bool,
    stiff_tests: usize,
    non_stiff_tests: usize,
    stiffness_detected: Option<f64>,
    /// The last attempt's scaled sums of squares `(ε₃², ε₅²)` of Hairer's
    /// norm, for [`Dop853::local_error`] (its square root taken there, not
    /// in every attempt).
    hairer_sums: (f64, f64),
    /// The judge of the last accepted step's continuous extension, for
    /// direct integration's reads inside it ([`Dop853::dense_judged`]).
    inside: inside::Inside,
    /// Scratch of [`Dop853::local_error_by_halves`] (the stages, a stage
    /// state and the middle state), kept from measure to measure: direct
    /// integration measures every step longer than any before (a run
    /// allocates nothing per step, `tests/allocations.rs`).
    halves: Vec<f64>,
}

impl Dop853 {
    /// Starts at `(t0, y0)`; `h_max` bounds the first step guess; `h0`, when
    /// given, replaces the guess (a restart keeps the step that worked).
    pub fn new<S: System + ?Sized>(
        system: &S,
        t0: f64,
        y0: &[f64],
        tol: Tolerance,
        h_max: f64,
        h0: Option<f64>,
    ) -> Result<Self, Failure> {
        let n = y0.len();
        let mut k = vec![0.0; BLOCKS * n];
        let controller = Controller::dop853();
        let clock = Clock::start(system, t0, y0, &mut k[..n], tol, 8, h_max, h0, controller)?;
        Ok(Dop853 {
            tol,
            clock,
            y: y0.to_vec(),
            k,
            y_trial: vec![0.0; n],
            y_old: y0.to_vec(),
            dense_ready: false,
            stiff_tests: 0,
            non_stiff_tests: 0,
            stiffness_detected: None,
            hairer_sums: (0.0, 0.0),
            inside: inside::Inside::default(),
            halves: Vec::new(),
        })
    }

    /// [`Dop853::new`] in place: afterwards the stepper is the one `new`
    /// would make from the same arguments (every field as `new` sets it,
    /// the same right side evaluated into the first stage), its buffers
    /// and its box reused. A projection after a step restarts the
    /// integrator, and five allocations a restart were all a drifting
    /// constrained run allocated per step (docs/BENCHMARKS.md §10h). A
    /// failing start changes only the trial state, scratch that a step
    /// writes before it reads.
    pub fn restart_at<S: System + ?Sized>(
        &mut self,
        system: &S,
        t0: f64,
        y0: &[f64],
        tol: Tolerance,
        h_max: f64,
        h0: Option<f64>,
    ) -> Result<(), Failure> {
        let n = y0.len();
        if n != self.y.len() {
            *self = Dop853::new(system, t0, y0, tol, h_max, h0)?;
            return Ok(());
        }
        let controller = Controller::dop853();
        let slope = &mut self.y_trial;
        let clock = Clock::start(system, t0, y0, slope, tol, 8, h_max, h0, controller)?;
        let mut k = std::mem::take(&mut self.k);
        k.fill(0.0);
        k[..n].copy_from_slice(&self.y_trial);
        let mut y_trial = std::mem::take(&mut self.y_trial);
        y_trial.fill(0.0);
        let mut y = std::mem::take(&mut self.y);
        y.copy_from_slice(y0);
        let mut y_old = std::mem::take(&mut self.y_old);
        y_old.copy_from_slice(y0);
        let mut inside = std::mem::take(&mut self.inside);
        inside.new_step();
        let halves = std::mem::take(&mut self.halves);
        *self = Dop853 {
            tol,
            clock,
            y,
            k,
            y_trial,
            y_old,
            dense_ready: false,
            stiff_tests: 0,
            non_stiff_tests: 0,
            stiffness_detected: None,
            hairer_sums: (0.0, 0.0),
            inside,
            halves,
        };
        Ok(())
    }

    /// The current state (also [`Stepper::state`], which needs its system
    /// named where the stepper's type is known).
    pub fn current_state(&self) -> &[f64] {
        &self.y
    }

    /// The state at the last accepted step's start.
    pub fn previous_state(&self) -> &[f64] {
        &self.y_old
    }

    /// The slope `X(t, y)` at the current state.
    pub fn slope(&self) -> &[f64] {
        &self.k[..self.y.len()]
    }

    /// One accepted step under `measure` (see [`Stepper::step`]), or
    /// [`StepOutcome::Declined`] when the measure declines it.
    pub fn step_measured<S: System + ?Sized, E: ErrorMeasure + ?Sized>(
        &mut self,
        system: &S,
        t_limit: f64,
        budget: &Budget,
        measure: &mut E,
    ) -> Result<StepOutcome, Failure> {
        // The state sizes of small mechanical models, known at compile
        // time: the stage loops then unroll and lose their bounds checks
        // and loop overhead, which at n = 2 cost more than the arithmetic
        // (callgrind on vertical_rocket: a quarter of the step's
        // instructions were the loops' counting; BENCHMARKS §10). The same
        // operations in the same order at every size: results are
        // bit-identical.
        match self.y.len() {
            2 => self.step_sized::<S, E, 2>(system, t_limit, budget, measure),
            3 => self.step_sized::<S, E, 3>(system, t_limit, budget, measure),
            4 => self.step_sized::<S, E, 4>(system, t_limit, budget, measure),
            6 => self.step_sized::<S, E, 6>(system, t_limit, budget, measure),
            8 => self.step_sized::<S, E, 8>(system, t_limit, budget, measure),
            // The quasilinear field's projective coefficients of N = 3
            // and 4, N(N + 1) numbers.
            12 => self.step_sized::<S, E, 12>(system, t_limit, budget, measure),
            20 => self.step_sized::<S, E, 20>(system, t_limit, budget, measure),
            _ => self.step_sized::<S, E, 0>(system, t_limit, budget, measure),
        }
    }

    /// [`Dop853::step_measured`] for a state of `N` numbers (`N = 0`: of
    /// any size, read at run time).
    #[inline(always)]
    fn step_sized<S: System + ?Sized, E: ErrorMeasure + ?Sized, const N: usize>(
        &mut self,
        system: &S,
        t_limit: f64,
        budget: &Budget,
        measure: &mut E,
    ) -> Result<StepOutcome, Failure> {
        let n = if N == 0 { self.y.len() } else { N };
        let mut last_non_finite = false;
        let mut rate_broken: Option<usize> = None;
        loop {
            let (h, reaches_limit) = self.clock.attempt(t_limit, budget, |h| {
                let component =
                    last_non_finite.then(|| first_non_finite(&self.y_trial).unwrap_or(0));
                stalled(system, self.clock.t, h, component, rate_broken)
            })?;
            let fused = measure.hairer_tolerance();
            let (finite, fused_error) = self.attempt::<S, N>(system, h, fused)?;
            let err = if !finite {
                f64::INFINITY
            } else if fused.is_some() {
                fused_error
            } else {
                self.clock.controller.end_ramp();
                match measure.measure(
                    self.clock.t,
                    h,
                    &self.y,
                    &self.y_trial,
                    &self.k[ERROR3 * n..(ERROR3 + 1) * n],
                    &self.k[ERROR5 * n..(ERROR5 + 1) * n],
                ) {
                    Some(err) => err,
                    None => return Ok(self.clock.decline()),
                }
            };
            if !finite {
                // A stage overflowed: the step was too long for a solution
                // that grows fast, or it reached past where the rates are
                // defined (a force infinite at a finite state); retry
                // shorter, and remember which, for the diagnosis should the
                // step underflow.
                self.clock.reject(h, f64::INFINITY);
                match self.broken_rate(h) {
                    Some(i) => {
                        rate_broken = Some(i);
                        last_non_finite = false;
                    }
                    None => last_non_finite = true,
                }
            } else if err <= 1.0 {
                let t_new = self.clock.end(h, reaches_limit, t_limit);
                // The slope at the step's end (kept in k[12] until the
                // step is taken: it is the next step's first stage).
                let end_slope = &mut self.k[12 * n..13 * n];
                system.rhs(t_new, &self.y_trial, end_slope)?;
                self.clock.stats.rhs_evaluations += 1;
                if let Some(i) = first_non_finite(end_slope) {
                    self.clock.reject_short(h);
                    rate_broken = Some(i);
                    last_non_finite = false;
                    continue;
                }
                let h_next = self.clock.controller.accept(h, err);
                // y_old ← y ← y_trial without copying.
                std::mem::swap(&mut self.y_old, &mut self.y);
                std::mem::swap(&mut self.y, &mut self.y_trial);
                self.clock.accept(h, t_new, h_next, reaches_limit);
                // k[0] becomes the new slope; X(t_old) moves to k[12] for
                // the continuous extension.
                let (start, rest) = self.k.split_at_mut(12 * n);
                start[..n].swap_with_slice(&mut rest[..n]);
                self.dense_ready = false;
                self.inside.new_step();
                self.test_stiffness::<N>(h);
                return Ok(StepOutcome::Accepted);
            } else {
                self.clock.reject(h, err);
                last_non_finite = false;
            }
        }
    }

    /// The last accepted step's local error as Hairer's estimate sees it:
    /// the vector `h ε₅ √(ε₅² / (ε₅² + 0.01 ε₃²))` whose scaled RMS norm is
    /// the error the step was accepted with (valid right after a step
    /// under [`HairerMeasure`], the error blocks being the accepted
    /// attempt's).
    pub fn local_error(&self, out: &mut [f64]) {
        let n = self.y.len();
        let e5 = &self.k[ERROR5 * n..(ERROR5 + 1) * n];
        let factor = self.local_error_factor();
        for (o, e) in out[..n].iter_mut().zip(e5) {
            *o = factor * e;
        }
    }

    /// [`Dop853::local_error`] relative to the state it ended on, without
    /// the vector: `global_error::relative(local, y)` bit for bit (the same
    /// operations in the same order), for the steps whose error is only
    /// summed (the direct run's bookkeeping at every step, BENCHMARKS
    /// §10a).
    pub fn local_error_relative(&self) -> f64 {
        let n = self.y.len();
        let e5 = &self.k[ERROR5 * n..(ERROR5 + 1) * n];
        let factor = self.local_error_factor();
        let mut worst = 0.0_f64;
        for (e, x) in e5.iter().zip(&self.y[..n]) {
            worst = worst.max((factor * e).abs() / x.abs().max(1.0));
        }
        worst
    }

    /// `h √(ε₅² / (ε₅² + 0.01 ε₃²))`, the factor of `ε₅` in
    /// [`Dop853::local_error`].
    fn local_error_factor(&self) -> f64 {
        let (err3, err5) = self.hairer_sums;
        let denominator = err5 + 0.01 * err3;
        let share = if denominator > 0.0 {
            (err5 / denominator).sqrt()
        } else {
            0.0
        };
        self.clock.h_old * share
    }

    /// The last accepted step's local error by Richardson extrapolation:
    /// the step taken again from its start as two steps of half its
    /// length, whose end is off by `2 (h/2)⁹ C = 1/256` of the step's own
    /// error, so `ℓ = (y − y_halves) · 256/255` (order 9, the error of the
    /// solution DOP853 carries, where Hairer's estimate is of order 8).
    /// 23 evaluations; `Ok(false)` when a stage was not finite (no value).
    pub fn local_error_by_halves<S: System + ?Sized>(
        &mut self,
        system: &S,
        out: &mut [f64],
    ) -> Result<bool, Failure> {
        let n = self.y.len();
        let (t_old, _, h) = self.clock.last_step();
        let half = 0.5 * h;
        self.halves.resize((STAGES + 2) * n, 0.0);
        let (k, rest) = self.halves.split_at_mut(STAGES * n);
        let (stage_state, mid) = rest.split_at_mut(n);
        // The first stage of the first half is the step's start rate, k[12].
        k[..n].copy_from_slice(&self.k[12 * n..13 * n]);
        plain_step(system, t_old, &self.y_old, half, k, stage_state, mid)?;
        system.rhs(t_old + half, mid, &mut k[..n])?;
        plain_step(system, t_old + half, mid, half, k, stage_state, out)?;
        self.clock.stats.rhs_evaluations += 2 * (STAGES - 1) + 1;
        for (o, y) in out[..n].iter_mut().zip(&self.y) {
            *o = (y - *o) * (256.0 / 255.0);
        }
        Ok(first_non_finite(&out[..n]).is_none())
    }

    /// Hairer's test after an accepted step of length `h`: `y` is the new
    /// state, `k[0] = X(t, y)`, and the last stage `k[11] = X(t, y₁)` was
    /// evaluated at the same time at `stage_state = y₁`.
    #[inline(always)]
    fn test_stiffness<const N: usize>(&mut self, h: f64) {
        let (mut numerator, mut denominator) = (0.0, 0.0);
        let n = if N == 0 { self.y.len() } else { N };
        let (slope, last) = (&self.k[..n], &self.k[(STAGES - 1) * n..STAGES * n]);
        let (y, y1) = (
            &self.y[..n],
            &self.k[STAGE_STATE * n..(STAGE_STATE + 1) * n],
        );
        for i in 0..n {
            let (a, b) = (slope[i] - last[i], y[i] - y1[i]);
            numerator += a * a;
            denominator += b * b;
        }
        if denominator <= 0.0 || !numerator.is_finite() {
            return;
        }
        let h_rho = h.abs() * (numerator / denominator).sqrt();
        if h_rho > STIFF_H_RHO {
            self.non_stiff_tests = 0;
            self.stiff_tests += 1;
            if self.stiff_tests >= STIFF_STEPS && self.stiffness_detected.is_none() {
                self.stiffness_detected = Some(self.clock.t);
            }
        } else {
            self.non_stiff_tests += 1;
            if self.non_stiff_tests >= NON_STIFF_STEPS {
                self.stiff_tests = 0;
            }
        }
    }

    /// After an attempt of step `h` that was not finite: the component of
    /// the first stage whose rate is not finite although its state is (a
    /// force or mass law undefined ahead), `None` when a state overflowed
    /// first (the motion grows without bound). Recomputes the stage
    /// states, so it costs nothing on the way of finite steps.
    fn broken_rate(&mut self, h: f64) -> Option<usize> {
        let n = self.y.len();
        let (k, scratch) = self.k.split_at_mut(STAGE_STATE * n);
        let stage_state = &mut scratch[..n];
        for s in 1..STAGES {
            stage_state.copy_from_slice(&self.y);
            for &(j, a) in A[s] {
                axpy(h * a, &k[j * n..(j + 1) * n], stage_state);
            }
            if first_non_finite(stage_state).is_some() {
                return None;
            }
            if let Some(i) = first_non_finite(&k[s * n..(s + 1) * n]) {
                return Some(i);
            }
        }
        None
    }

    /// Computes the stages, `y_trial` and the two error estimates (per
    /// unit step) for step `h`: `false` when a stage is not finite; with
    /// `hairer`, Hairer's norm of the step under that tolerance, computed
    /// in the same pass (else `0`).
    ///
    /// Each stage state is one pass over the components summing the
    /// stage's row with its coefficients known at compile time (Hairer's
    /// `dop853.f` loops), and `y_trial` with both error estimates one more
    /// pass: for the small systems of mechanics (n = 2…12) a whole-vector
    /// `axpy` per coefficient cost more in loop overhead than the
    /// arithmetic, and the loops vectorise as well for the field's large
    /// coefficient systems.
    // Inlined into each step: the stepper's vtable instantiates a second
    // caller (`Stepper::step_measured`, the field's measure), and LLVM
    // then kept this out of line, which cost direct DOP853 about 27 % more
    // instructions on the rocket (callgrind, BENCHMARKS §10).
    #[inline(always)]
    fn attempt<S: System + ?Sized, const N: usize>(
        &mut self,
        system: &S,
        h: f64,
        hairer: Option<Tolerance>,
    ) -> Result<(bool, f64), Failure> {
        let n = if N == 0 { self.y.len() } else { N };
        let t = self.clock.t;
        let y = &self.y[..n];
        let (k, scratch) = self.k.split_at_mut(STAGE_STATE * n);
        let (ys, scratch) = scratch.split_at_mut(n);
        let (error3, scratch) = scratch.split_at_mut(n);
        let error5 = &mut scratch[..n];
        macro_rules! stage {
            ($s:literal, $r:literal) => {{
                let (done, rest) = k.split_at_mut($s * n);
                if N == 0 {
                    let row: [(f64, &[f64]); $r] = std::array::from_fn(|m| {
                        let j = A[$s][m].0;
                        (A[$s][m].1, &done[j * n..(j + 1) * n])
                    });
                    combine(ys, y, h, &row);
                } else {
                    // Every index a constant: `combine`'s sums, each
                    // component's in its order, a stage at a time over
                    // the components (so that they vectorise).
                    let mut acc = [0.0; N];
                    for &(j, a) in A[$s] {
                        for i in 0..N {
                            acc[i] += a * done[j * N + i];
                        }
                    }
                    for i in 0..N {
                        ys[i] = y[i] + h * acc[i];
                    }
                }
                system.rhs(t + C[$s] * h, ys, &mut rest[..n])?;
            }};
        }
        stage!(1, 1);
        stage!(2, 2);
        stage!(3, 2);
        stage!(4, 3);
        stage!(5, 3);
        stage!(6, 4);
        stage!(7, 5);
        stage!(8, 6);
        stage!(9, 7);
        stage!(10, 8);
        stage!(11, 9);
        self.clock.stats.rhs_evaluations += STAGES - 1;
        let stages = &k[..STAGES * n];
        // Stage `j`'s component `i`: through slices made once when the size
        // is read at run time, by constant indices when it is known.
        let ks: [&[f64]; STAGES] = if N == 0 {
            std::array::from_fn(|j| &k[j * n..(j + 1) * n])
        } else {
            [&[]; STAGES]
        };
        let kv = |j: usize, i: usize| {
            if N == 0 {
                ks[j][i]
            } else {
                stages[j * n + i]
            }
        };
        let y_trial = &mut self.y_trial[..n];
        // 0·v is 0 for every finite v and NaN otherwise: one sum tells
        // whether every number of the step is finite.
        let mut poison = 0.0;
        let (mut err3, mut err5) = (0.0, 0.0);
        for i in 0..n {
            let mut b = 0.0;
            for &(j, w) in &B {
                b += w * kv(j, i);
            }
            let mut e5 = 0.0;
            for &(j, w) in &ER {
                e5 += w * kv(j, i);
            }
            let e3 = b
                - BHH[0].1 * kv(BHH[0].0, i)
                - BHH[1].1 * kv(BHH[1].0, i)
                - BHH[2].1 * kv(BHH[2].0, i);
            let y1 = y[i] + h * b;
            y_trial[i] = y1;
            error3[i] = e3;
            error5[i] = e5;
            poison += 0.0 * y1 + 0.0 * e3 + 0.0 * e5;
            if let Some(tol) = hairer {
                let inverse = 1.0 / (tol.atol + tol.rtol * y[i].abs().max(y1.abs()));
                let (a, b) = (e3 * inverse, e5 * inverse);
                err3 += a * a;
                err5 += b * b;
            }
        }
        let err = if hairer.is_some() {
            self.hairer_sums = (err3, err5);
            hairer_combine(h, n, err3, err5)
        } else {
            0.0
        };
        Ok((poison == 0.0, err))
    }

    /// The continuous extension of the last step (Hairer's `dop853.f`,
    /// `IOUT ≥ 2`): three more stages and the coefficients `cont`.
    fn prepare_dense<S: System + ?Sized>(&mut self, system: &S) -> Result<(), Failure> {
        let n = self.y.len();
        let (stages, rest) = self.k.split_at_mut(13 * n);
        let (extra, rest) = rest.split_at_mut((STAGE_STATE - 13) * n);
        let (stage_state, rest) = rest.split_at_mut(n);
        let cont = &mut rest[(CONT - STAGE_STATE - 1) * n..(BLOCKS - STAGE_STATE - 1) * n];
        continuous_extension(
            system,
            self.clock.t_old,
            self.clock.h_old,
            &self.y_old,
            &self.y,
            &FlatStages { data: stages, n },
            extra,
            stage_state,
            cont,
        )?;
        self.clock.stats.rhs_evaluations += 3;
        self.dense_ready = true;
        Ok(())
    }

    /// The last accepted step as data, to build its continuous extension
    /// later (the field method keeps the steps of a window until the window
    /// is accepted, and prepares only those that output asks for).
    pub fn raw_step(&self) -> RawStep {
        let mut step = RawStep::default();
        self.raw_step_into(&mut step);
        step
    }

    /// [`Dop853::raw_step`] into an existing value, reusing its storage.
    pub fn raw_step_into(&self, dst: &mut RawStep) {
        dst.t_old = self.clock.t_old;
        dst.h = self.clock.h_old;
        dst.t_new = self.clock.t;
        dst.data.clear();
        dst.data.reserve(15 * self.y.len());
        dst.data.extend_from_slice(&self.y_old);
        dst.data.extend_from_slice(&self.y);
        dst.data.extend_from_slice(&self.k[..13 * self.y.len()]);
    }

    /// The prepared continuous extension of the last accepted step, as a
    /// value that outlives the integrator's next step.
    pub fn dense_step<S: System + ?Sized>(&mut self, system: &S) -> Result<DenseStep, Failure> {
        if !self.dense_ready {
            self.prepare_dense(system)?;
        }
        Ok(DenseStep::dop853(
            self.clock.t_old,
            self.clock.t,
            self.clock.h_old,
            self.cont().to_vec(),
        ))
    }

    /// The continuous extension's coefficients (valid when `dense_ready`).
    fn cont(&self) -> &[f64] {
        let n = self.y.len();
        &self.k[CONT * n..BLOCKS * n]
    }
}

impl Clocked for Dop853 {
    fn clock(&self) -> &Clock {
        &self.clock
    }

    fn clock_mut(&mut self) -> &mut Clock {
        &mut self.clock
    }
}

impl<S: System + ?Sized> Stepper<S> for Dop853 {
    fn state(&self) -> &[f64] {
        &self.y
    }

    fn stiffness_detected(&self) -> Option<f64> {
        self.stiffness_detected
    }

    fn step(&mut self, system: &S, t_limit: f64, budget: &Budget) -> Result<(), Failure> {
        let mut measure = HairerMeasure(self.tol);
        // The inherent step, with this measure's type: no dynamic call
        // per attempt.
        Dop853::step_measured(self, system, t_limit, budget, &mut measure).map(|_| ())
    }

    fn step_measured(
        &mut self,
        system: &S,
        t_limit: f64,
        budget: &Budget,
        measure: &mut dyn ErrorMeasure,
    ) -> Result<StepOutcome, Failure> {
        Dop853::step_measured(self, system, t_limit, budget, measure)
    }

    fn dense(&mut self, system: &S, t: f64, out: &mut [f64]) -> Result<(), Failure> {
        let n = self.y.len();
        let step = self.clock.last_step();
        if let Some(end) = crate::ode::stepper::outside_last_step(t, step, &self.y_old, &self.y) {
            out.copy_from_slice(end);
            return Ok(());
        }
        if !self.dense_ready {
            self.prepare_dense(system)?;
        }
        contd8(
            self.cont(),
            n,
            (t - self.clock.t_old) / self.clock.h_old,
            out,
        );
        Ok(())
    }

    fn dense_step(&mut self, system: &S) -> Result<Option<DenseStep>, Failure> {
        Dop853::dense_step(self, system).map(Some)
    }

    fn as_any(&self) -> &dyn std::any::Any {
        self
    }

    fn as_any_mut(&mut self) -> &mut dyn std::any::Any {
        self
    }
}

pub use crate::ode::dense::DenseStep;

impl DenseStep {
    fn dop853(t_old: f64, t_new: f64, h: f64, cont: Vec<f64>) -> DenseStep {
        DenseStep::new(t_old, t_new, h, std::sync::Arc::new(Contd8 { cont }))
    }
}

/// DOP853's continuous extension of order 7: Hairer's `contd8`
/// coefficients, 8 blocks of `n`.
#[derive(Debug)]
struct Contd8 {
    cont: Vec<f64>,
}

impl Extension for Contd8 {
    fn eval(&self, theta: f64, out: &mut [f64]) {
        contd8(&self.cont, self.cont.len() / 8, theta, out);
    }
}

/// Hairer's `contd8`: the continuous extension at `θ = (t − t_old)/h`,
/// into the first `n` components of `out`. Compiled for the small models'
/// sizes as the step is (`step_sized`): at n = 4 the loop's indexing and
/// bounds checks were two thirds of a sample's instructions (callgrind on
/// the paper, docs/BENCHMARKS.md §10i). The same operations in the same
/// order at every size: the values are bit-identical.
fn contd8(c: &[f64], n: usize, s: f64, out: &mut [f64]) {
    match n {
        2 => contd8_sized::<2>(c, n, s, out),
        3 => contd8_sized::<3>(c, n, s, out),
        4 => contd8_sized::<4>(c, n, s, out),
        6 => contd8_sized::<6>(c, n, s, out),
        8 => contd8_sized::<8>(c, n, s, out),
        _ => contd8_sized::<0>(c, n, s, out),
    }
}

/// [`contd8`] for `n = N` known at compile time (`N = 0`: any `n`).
#[inline(always)]
fn contd8_sized<const N: usize>(c: &[f64], n: usize, s: f64, out: &mut [f64]) {
    let n = if N == 0 { n } else { N };
    let s1 = 1.0 - s;
    let block = |b: usize| &c[b * n..(b + 1) * n];
    let (c0, c1, c2, c3) = (block(0), block(1), block(2), block(3));
    let (c4, c5, c6, c7) = (block(4), block(5), block(6), block(7));
    for (i, o) in out.iter_mut().enumerate().take(n) {
        let conf1 = c4[i] + s * (c5[i] + s1 * (c6[i] + s * c7[i]));
        *o = c0[i] + s * (c1[i] + s1 * (c2[i] + s * (c3[i] + s1 * conf1)));
    }
}

/// Stage `j` of Hairer's numbering (`0` the rate at the step's start,
/// `12` at its end, `13..16` the extra stages of the extension) in this
/// module's storage (`k[0]` the end rate, `k[12]` the start rate).
fn stage<'a, K: Stages + ?Sized>(k: &'a K, extra: &'a [f64], j: usize) -> &'a [f64] {
    match j {
        0 => k.stage(12),
        12 => k.stage(0),
        13.. => {
            let n = extra.len() / 3;
            &extra[(j - 13) * n..(j - 12) * n]
        }
        _ => k.stage(j),
    }
}

/// The 13 stages of a step as this module stores them (`k[0]` the end
/// rate, `k[12]` the start rate): the stepper's vectors, or a stored
/// step's one buffer.
trait Stages {
    fn stage(&self, j: usize) -> &[f64];
}

/// Stages stored one after another, `n` numbers each.
struct FlatStages<'a> {
    data: &'a [f64],
    n: usize,
}

impl Stages for FlatStages<'_> {
    fn stage(&self, j: usize) -> &[f64] {
        &self.data[j * self.n..(j + 1) * self.n]
    }
}

/// Computes the three extra stages into `extra` and the coefficients
/// `cont` (8 blocks of `n`) of the 7th-order continuous extension, with
/// `k` the 13 stages of the step as the stepper keeps them. Written as
/// whole-vector updates (one `axpy` per stage) so that it vectorises: the
/// field's coefficient systems have `(N+1)²` components.
#[allow(clippy::too_many_arguments)]
fn continuous_extension<S: System + ?Sized, K: Stages + ?Sized>(
    system: &S,
    t_old: f64,
    h: f64,
    y_old: &[f64],
    y: &[f64],
    k: &K,
    extra: &mut [f64],
    stage_state: &mut [f64],
    cont: &mut [f64],
) -> Result<(), Failure> {
    macro_rules! sized {
        ($n:literal) => {
            continuous_extension_sized::<S, K, $n>(
                system,
                t_old,
                h,
                y_old,
                y,
                k,
                extra,
                stage_state,
                cont,
            )
        };
    }
    // Compiled for the smallest sizes, where the coefficients' sums are
    // taken a stage at a time over the components: at n = 4 the general
    // loop's multiply-adds were about 530 of a sampled step's
    // instructions (callgrind on the paper, docs/BENCHMARKS.md §10m); at
    // n = 6 that order cost more than the general loop (the knife edge).
    // The same operations in the same order at every size: the values are
    // bit-identical.
    match y.len() {
        2 => sized!(2),
        3 => sized!(3),
        4 => sized!(4),
        _ => continuous_extension_any(system, t_old, h, y_old, y, k, extra, stage_state, cont),
    }
}

/// [`continuous_extension_sized`] for any `n`, out of line: inlined into
/// the dispatch beside the sized copies it cost the knife edge (n = 6)
/// about 340 more instructions a sampled step than as a function of its
/// own (callgrind, docs/BENCHMARKS.md §10m).
#[allow(clippy::too_many_arguments)]
#[inline(never)]
fn continuous_extension_any<S: System + ?Sized, K: Stages + ?Sized>(
    system: &S,
    t_old: f64,
    h: f64,
    y_old: &[f64],
    y: &[f64],
    k: &K,
    extra: &mut [f64],
    stage_state: &mut [f64],
    cont: &mut [f64],
) -> Result<(), Failure> {
    continuous_extension_sized::<S, K, 0>(system, t_old, h, y_old, y, k, extra, stage_state, cont)
}

/// [`continuous_extension`] for `n = N` known at compile time (`N = 0`:
/// any `n`).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn continuous_extension_sized<S: System + ?Sized, K: Stages + ?Sized, const N: usize>(
    system: &S,
    t_old: f64,
    h: f64,
    y_old: &[f64],
    y: &[f64],
    k: &K,
    extra: &mut [f64],
    stage_state: &mut [f64],
    cont: &mut [f64],
) -> Result<(), Failure> {
    let n = if N == 0 { y.len() } else { N };
    let (y, y_old) = (&y[..n], &y_old[..n]);
    let stage_state = &mut stage_state[..n];
    let extra = &mut extra[..3 * n];
    macro_rules! extra_stage {
        ($e:literal, $r:literal) => {{
            let (done, rest) = extra.split_at_mut($e * n);
            let row: [(f64, &[f64]); $r] = std::array::from_fn(|m| {
                let j = A_EXTRA[$e][m].0;
                let stage = if j >= 13 {
                    &done[(j - 13) * n..(j - 12) * n]
                } else {
                    &stage(k, &[], j)[..n]
                };
                (A_EXTRA[$e][m].1, stage)
            });
            combine(stage_state, y_old, h, &row);
            system.rhs(t_old + C_EXTRA[$e] * h, stage_state, &mut rest[..n])?;
        }};
    }
    extra_stage!(0, 8);
    extra_stage!(1, 8);
    extra_stage!(2, 8);
    // The stages D uses (Hairer's numbering), as slices of length n.
    const USED: [usize; 12] = [0, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15];
    let extra = &*extra;
    let used: [&[f64]; 12] = std::array::from_fn(|m| &stage(k, extra, USED[m])[..n]);
    let (start_rate, end_rate) = (&k.stage(12)[..n], &k.stage(0)[..n]);
    let (c0, rest) = cont.split_at_mut(n);
    let (c1, rest) = rest.split_at_mut(n);
    let (c2, rest) = rest.split_at_mut(n);
    let (c3, rest) = rest.split_at_mut(n);
    let (c4, rest) = rest.split_at_mut(n);
    let (c5, rest) = rest.split_at_mut(n);
    let (c6, c7) = rest.split_at_mut(n);
    let c7 = &mut c7[..n];
    if N != 0 {
        for i in 0..N {
            let y_diff = y[i] - y_old[i];
            let bspl = h * start_rate[i] - y_diff;
            c0[i] = y_old[i];
            c1[i] = y_diff;
            c2[i] = bspl;
            c3[i] = y_diff - h * end_rate[i] - bspl;
        }
        // A stage at a time over the components (so that they vectorise,
        // the 4·N sums held in registers): each component's four sums in
        // the order of the loop below.
        let mut d = [[0.0; N]; 4];
        for (m, stage) in used.iter().enumerate() {
            for (r, d) in d.iter_mut().enumerate() {
                let a = D[r][USED[m]];
                for i in 0..N {
                    d[i] += a * stage[i];
                }
            }
        }
        for i in 0..N {
            c4[i] = h * d[0][i];
            c5[i] = h * d[1][i];
            c6[i] = h * d[2][i];
            c7[i] = h * d[3][i];
        }
        return Ok(());
    }
    for i in 0..n {
        let y_diff = y[i] - y_old[i];
        let bspl = h * start_rate[i] - y_diff;
        c0[i] = y_old[i];
        c1[i] = y_diff;
        c2[i] = bspl;
        c3[i] = y_diff - h * end_rate[i] - bspl;
        let mut d = [0.0; 4];
        for (m, stage) in used.iter().enumerate() {
            let v = stage[i];
            for r in 0..4 {
                d[r] += D[r][USED[m]] * v;
            }
        }
        c4[i] = h * d[0];
        c5[i] = h * d[1];
        c6[i] = h * d[2];
        c7[i] = h * d[3];
    }
    Ok(())
}

/// The 7th-order continuous extension over `[t_old, t_old + h]` of one
/// DOP853 step of `system` from `y_old`, pinned to the end state `y_new`
/// given by the caller (a more accurate one than this step's own: the field
/// method's recovered state). 16 evaluations of `system`. The field method
/// uses it for its output between steps, on the motion linearised along
/// its predictor: the coefficients' extension, recovered through the
/// conditions, was up to 30× less accurate between the steps than at them.
pub fn dense_step_between<S: System + ?Sized>(
    system: &S,
    t_old: f64,
    h: f64,
    y_old: &[f64],
    y_new: &[f64],
) -> Result<DenseStep, Failure> {
    dense_step_between_measured(system, t_old, h, y_old, y_new, None).map(|(step, _)| step)
}

/// The working buffers of [`dense_step_between_measured`] on the stack up
/// to this many numbers (`18 n`: up to `n` = 8).
const SMALL_BETWEEN: usize = 18 * 8;

/// The most pieces [`dense_steps_between`] cuts a step into.
pub const MOST_PIECES: usize = 64;

/// The continuous extension over `[t_old, t_old + h]` of DOP853 on
/// `system` from `y_old`, ending on `y_new` (as [`dense_step_between`]),
/// in as many equal pieces (1, 2, 4, … [`MOST_PIECES`]) as it takes for
/// the chain of steps to meet `y_new` within `tol`: the pieces before the
/// last end where their own step does, the last is pinned to `y_new`.
/// Why: a field step may be far longer than one explicit step of the
/// motion where the motion changes fast and the coefficients do not (a
/// knife edge turning to its singular heading at rtol 1e-6: one field step
/// over the last 0.24 s, its output 2e-5 off in mid-step, 30 rtol, while
/// both of its ends were right to 1e-11). Returns the pieces and the last
/// one's miss (Hairer's scaled RMS norm).
pub fn dense_steps_between<S: System + ?Sized>(
    system: &S,
    t_old: f64,
    h: f64,
    y_old: &[f64],
    y_new: &[f64],
    tol: Tolerance,
) -> Result<(Vec<DenseStep>, f64), Failure> {
    let n = y_old.len();
    let (one, mut miss) = dense_step_between_measured(system, t_old, h, y_old, y_new, Some(tol))?;
    let mut pieces = vec![one];
    if miss <= 1.0 {
        // One piece meets the later state (most steps): no buffers for
        // the chains below.
        return Ok((pieces, miss));
    }
    let mut count = 1;
    let mut k = vec![0.0; STAGES * n];
    let (mut stage_state, mut start, mut end) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    while miss > 1.0 && count < MOST_PIECES {
        count *= 2;
        let piece = h / count as f64;
        let mut chain = Vec::with_capacity(count);
        start.copy_from_slice(y_old);
        for j in 0..count - 1 {
            let t = t_old + j as f64 * piece;
            system.rhs(t, &start, &mut k[..n])?;
            plain_step(system, t, &start, piece, &mut k, &mut stage_state, &mut end)?;
            if first_non_finite(&end).is_some() {
                return Err(Failure::non_finite(t, system.component_name(0)));
            }
            chain.push(dense_step_between(system, t, piece, &start, &end)?);
            std::mem::swap(&mut start, &mut end);
        }
        let t_last = t_old + (count - 1) as f64 * piece;
        let (last, last_miss) = dense_step_between_measured(
            system,
            t_last,
            t_old + h - t_last,
            &start,
            y_new,
            Some(tol),
        )?;
        chain.push(last);
        (pieces, miss) = (chain, last_miss);
    }
    Ok((pieces, miss))
}

/// [`dense_step_between`], and with `tol` how far the step's own end
/// misses `y_new` (Hairer's scaled RMS norm; `0` without `tol`): above 1
/// the step is too long for one explicit step of `system`, and so is its
/// continuous extension.
pub fn dense_step_between_measured<S: System + ?Sized>(
    system: &S,
    t_old: f64,
    h: f64,
    y_old: &[f64],
    y_new: &[f64],
    tol: Option<Tolerance>,
) -> Result<(DenseStep, f64), Failure> {
    let mut cont = Vec::new();
    let miss = dense_step_between_measured_into(system, t_old, h, y_old, y_new, tol, &mut cont)?;
    Ok((DenseStep::dop853(t_old, t_old + h, h, cont), miss))
}

/// [`dense_step_between_measured`] into `cont`'s storage (resized to the
/// extension's `8 n` coefficients): the same numbers without a vector
/// and a shared box allocated and freed at every sample of the affine
/// field's output ([`eval_between`] evaluates it).
pub fn dense_step_between_measured_into<S: System + ?Sized>(
    system: &S,
    t_old: f64,
    h: f64,
    y_old: &[f64],
    y_new: &[f64],
    tol: Option<Tolerance>,
    cont: &mut Vec<f64>,
) -> Result<f64, Failure> {
    let n = y_old.len();
    // The working buffers (the stages, a stage's state, the extension's
    // three extra stages, the miss): on the stack for the small models,
    // whose output between steps takes one such step a sample, else on
    // the heap. Every entry is written before it is read.
    let need = (STAGES + 1) * n + n + 3 * n + n;
    let mut small = [0.0; SMALL_BETWEEN];
    let mut large = Vec::new();
    let buffers: &mut [f64] = if need <= SMALL_BETWEEN {
        &mut small[..need]
    } else {
        large.resize(need, 0.0);
        &mut large
    };
    // Hairer's stage numbering: k[0] the start rate, k[1..12] the stages.
    let (k, rest) = buffers.split_at_mut((STAGES + 1) * n);
    let (stage_state, rest) = rest.split_at_mut(n);
    let (extra, miss_buffer) = rest.split_at_mut(3 * n);
    system.rhs(t_old, y_old, &mut k[..n])?;
    // The sizes of small models known at compile time (the field's output
    // between steps takes one such step a sample): the same operations.
    match n {
        2 => between_stages::<S, 2>(system, t_old, h, y_old, k, stage_state)?,
        3 => between_stages::<S, 3>(system, t_old, h, y_old, k, stage_state)?,
        4 => between_stages::<S, 4>(system, t_old, h, y_old, k, stage_state)?,
        _ => between_stages::<S, 0>(system, t_old, h, y_old, k, stage_state)?,
    }
    let miss = match tol {
        Some(tol) => {
            // The step's own end, less `y_new`.
            for (i, m) in miss_buffer.iter_mut().enumerate() {
                let own_end = y_old[i] + h * B.iter().map(|&(j, w)| w * k[j * n + i]).sum::<f64>();
                *m = own_end - y_new[i];
            }
            crate::ode::tolerance::rms_norm(miss_buffer, y_old, y_new, tol)
        }
        None => 0.0,
    };
    system.rhs(t_old + h, y_new, &mut k[STAGES * n..])?;
    // This module's storage: k[0] the end rate, k[12] the start rate.
    let (start, rest) = k.split_at_mut(STAGES * n);
    start[..n].swap_with_slice(&mut rest[..n]);
    // Every coefficient is written by the extension (zeroed first, as a
    // fresh vector was).
    cont.clear();
    cont.resize(8 * n, 0.0);
    continuous_extension(
        system,
        t_old,
        h,
        y_old,
        y_new,
        &FlatStages { data: k, n },
        extra,
        stage_state,
        cont,
    )?;
    if first_non_finite(cont).is_some() {
        return Err(Failure::non_finite(t_old, system.component_name(0)));
    }
    Ok(miss)
}

/// The extension `cont` of [`dense_step_between_measured_into`] over
/// `[t_old, t_old + h]` at `t` (clamped to the step), into `out`: what
/// [`DenseStep::eval`] does with the step that
/// [`dense_step_between_measured`] returns.
pub fn eval_between(cont: &[f64], t_old: f64, h: f64, t: f64, out: &mut [f64]) {
    let s = if h > 0.0 {
        ((t - t_old) / h).clamp(0.0, 1.0)
    } else {
        1.0
    };
    contd8(cont, cont.len() / 8, s, out);
}

/// The stages 1..12 of [`dense_step_between_measured`] into `k` (its
/// stage 0 given), for `N` components (`N = 0`: any number, read at run
/// time): `y_old + Σ (h a_j) k_j` summed in `A`'s order, as `axpy` does,
/// with every index a constant when `N` is known (the loops' counting was
/// half of the step's instructions at `N = 2`).
#[inline(always)]
fn between_stages<S: System + ?Sized, const N: usize>(
    system: &S,
    t_old: f64,
    h: f64,
    y_old: &[f64],
    k: &mut [f64],
    stage_state: &mut [f64],
) -> Result<(), Failure> {
    let n = if N == 0 { y_old.len() } else { N };
    for s in 1..STAGES {
        stage_state.copy_from_slice(y_old);
        for &(j, a) in A[s] {
            if N == 0 {
                axpy(h * a, &k[j * n..(j + 1) * n], stage_state);
            } else {
                let ha = h * a;
                let (x, y) = (&k[j * N..(j + 1) * N], &mut stage_state[..N]);
                for i in 0..N {
                    y[i] += ha * x[i];
                }
            }
        }
        system.rhs(t_old + C[s] * h, stage_state, &mut k[s * n..(s + 1) * n])?;
    }
    Ok(())
}

/// An accepted step as data (see [`Dop853::raw_step`]): one buffer of
/// `15 n` numbers, `y_old`, `y` and the 13 stages (`k[0]` the end rate,
/// `k[1..12]` the stages, `k[12]` the start rate) — one allocation a
/// stored step, not fifteen.
#[derive(Clone, Debug, Default)]
pub struct RawStep {
    pub t_old: f64,
    pub t_new: f64,
    h: f64,
    data: Vec<f64>,
}

impl RawStep {
    fn n(&self) -> usize {
        self.data.len() / 15
    }

    /// The state at the step's end.
    pub fn end_state(&self) -> &[f64] {
        let n = self.n();
        &self.data[n..2 * n]
    }

    /// The step's continuous extension (three evaluations of `system`,
    /// which must be the system the step was taken on).
    pub fn prepare<S: System + ?Sized>(&self, system: &S) -> Result<DenseStep, Failure> {
        let n = self.n();
        let (y_old, rest) = self.data.split_at(n);
        let (y, stages) = rest.split_at(n);
        let mut extra = vec![0.0; 3 * n];
        let mut stage_state = vec![0.0; n];
        let mut cont = vec![0.0; 8 * n];
        continuous_extension(
            system,
            self.t_old,
            self.h,
            y_old,
            y,
            &FlatStages { data: stages, n },
            &mut extra,
            &mut stage_state,
            &mut cont,
        )?;
        Ok(DenseStep::dop853(self.t_old, self.t_new, self.h, cont))
    }
}

/// One DOP853 step of length `h` from `(t, y)` into `out`, without error
/// control: `k[..n]` holds `X(t, y)` on entry, the other stages are
/// computed into `k`.
fn plain_step<S: System + ?Sized>(
    system: &S,
    t: f64,
    y: &[f64],
    h: f64,
    k: &mut [f64],
    stage_state: &mut [f64],
    out: &mut [f64],
) -> Result<(), Failure> {
    // The sizes of small models known at compile time, as in
    // `step_measured`: the same operations in the same order. These steps
    // are the global error's references and derivatives (two to four a
    // carried step), a tenth of the stiff joint's field at rtol 1e-10.
    match y.len() {
        2 => plain_step_sized::<S, 2>(system, t, y, h, k, stage_state, out),
        3 => plain_step_sized::<S, 3>(system, t, y, h, k, stage_state, out),
        4 => plain_step_sized::<S, 4>(system, t, y, h, k, stage_state, out),
        6 => plain_step_sized::<S, 6>(system, t, y, h, k, stage_state, out),
        8 => plain_step_sized::<S, 8>(system, t, y, h, k, stage_state, out),
        _ => plain_step_sized::<S, 0>(system, t, y, h, k, stage_state, out),
    }
}

/// [`plain_step`] for a state of `N` numbers (`N = 0`: any size).
#[inline(always)]
fn plain_step_sized<S: System + ?Sized, const N: usize>(
    system: &S,
    t: f64,
    y: &[f64],
    h: f64,
    k: &mut [f64],
    stage_state: &mut [f64],
    out: &mut [f64],
) -> Result<(), Failure> {
    let n = if N == 0 { y.len() } else { N };
    between_stages::<S, N>(system, t, h, y, k, stage_state)?;
    out[..n].copy_from_slice(y);
    for &(j, w) in &B {
        if N == 0 {
            axpy(h * w, &k[j * n..(j + 1) * n], &mut out[..n]);
        } else {
            let hw = h * w;
            let (x, o) = (&k[j * N..(j + 1) * N], &mut out[..N]);
            for i in 0..N {
                o[i] += hw * x[i];
            }
        }
    }
    Ok(())
}

/// One DOP853 step of length `h` from `(t, y)` into `out`, without error
/// control: 12 evaluations. The affine field's reference for its output
/// between steps, a step of half the field step's length, whose own error
/// is about 1/512 of the whole one's (`field::affine`).
pub fn one_step<S: System + ?Sized>(
    system: &S,
    t: f64,
    y: &[f64],
    h: f64,
    out: &mut [f64],
) -> Result<(), Failure> {
    let n = y.len();
    let mut k = vec![0.0; STAGES * n];
    let mut stage_state = vec![0.0; n];
    system.rhs(t, y, &mut k[..n])?;
    plain_step(system, t, y, h, &mut k, &mut stage_state, out)
}

/// Two DOP853 steps of length `h/2` from `(t, y)`, into `out`: a
/// reference for a step of length `h` of another method (the field's),
/// whose own error is 1/256 of a whole DOP853 step's. 24 evaluations;
/// `Ok(false)` when a value was not finite.
pub fn step_by_halves<S: System + ?Sized>(
    system: &S,
    t: f64,
    y: &[f64],
    h: f64,
    out: &mut [f64],
) -> Result<bool, Failure> {
    step_by_halves_in(system, t, y, h, out, &mut HalvesScratch::default())
}

/// The storage of [`step_by_halves_in`], kept from call to call by a
/// caller that steps at every step of a run (the carried error's
/// reference alongside the field: three allocations a step).
#[derive(Clone, Debug, Default)]
pub struct HalvesScratch {
    k: Vec<f64>,
    stage_state: Vec<f64>,
    mid: Vec<f64>,
}

/// [`step_by_halves`] in `scratch`'s storage: the same arithmetic.
pub fn step_by_halves_in<S: System + ?Sized>(
    system: &S,
    t: f64,
    y: &[f64],
    h: f64,
    out: &mut [f64],
    scratch: &mut HalvesScratch,
) -> Result<bool, Failure> {
    let n = y.len();
    let half = 0.5 * h;
    let HalvesScratch {
        k,
        stage_state,
        mid,
    } = scratch;
    // Zeroed as fresh storage is (a right side that leaves an entry
    // unwritten reads the same as before).
    for (v, len) in [
        (&mut *k, STAGES * n),
        (&mut *stage_state, n),
        (&mut *mid, n),
    ] {
        v.clear();
        v.resize(len, 0.0);
    }
    system.rhs(t, y, &mut k[..n])?;
    plain_step(system, t, y, half, k, stage_state, mid)?;
    system.rhs(t + half, mid, &mut k[..n])?;
    plain_step(system, t + half, mid, half, k, stage_state, out)?;
    Ok(first_non_finite(&out[..n]).is_none())
}

/// The derivative of one DOP853 step of length `h` from `(t, y)` in the
/// direction `d`, `(step(y + ε d) − step(y)) / ε` with `ε d` about √eps of
/// the state, into `out`: how the step carries a small error
/// (`global_error::growth`). 24 evaluations; `Ok(false)` when a value was
/// not finite.
pub fn step_derivative<S: System + ?Sized>(
    system: &S,
    t: f64,
    y: &[f64],
    h: f64,
    d: &[f64],
    out: &mut [f64],
) -> Result<bool, Failure> {
    step_difference(system, (t, y), h, (plain_step, None), d, out)
}

/// One DOP853 step of length `h` from `(t, y)` into `out` with the
/// arithmetic of an accepted step ([`Dop853::attempt`]: each stage state
/// `y + h Σ a_m k_m`, the end `y + h Σ b_j k_j`, each sum from zero in the
/// tableau's order), so that from the same `(t, y, h)` it ends on the
/// accepted state bit for bit. `k[..n]` holds `X(t, y)` on entry.
fn step_as_accepted<S: System + ?Sized>(
    system: &S,
    t: f64,
    y: &[f64],
    h: f64,
    k: &mut [f64],
    stage_state: &mut [f64],
    out: &mut [f64],
) -> Result<(), Failure> {
    let n = y.len();
    for s in 1..STAGES {
        let (done, rest) = k.split_at_mut(s * n);
        for i in 0..n {
            let mut acc = 0.0;
            for &(j, a) in A[s] {
                acc += a * done[j * n + i];
            }
            stage_state[i] = y[i] + h * acc;
        }
        system.rhs(t + C[s] * h, stage_state, &mut rest[..n])?;
    }
    for i in 0..n {
        let mut b = 0.0;
        for &(j, w) in &B {
            b += w * k[j * n + i];
        }
        out[i] = y[i] + h * b;
    }
    Ok(())
}

/// [`step_derivative`] of an accepted DOP853 step of length `h` from
/// `(t, y)` that ended at `y_end`: the difference is taken against the
/// step already taken, so only the step from `y + ε d` is new (12
/// evaluations where [`step_derivative`] takes 24). The same one-sided
/// difference, with the accepted step's arithmetic on both sides (each
/// stage `y + h Σ a_m k_m`, the end `y + h Σ b_j k_j`, each sum from zero
/// in the tableau's order). `Ok(false)` when a value was not finite.
pub fn step_derivative_from_accepted<S: System + ?Sized>(
    system: &S,
    (t, y): (f64, &[f64]),
    h: f64,
    y_end: &[f64],
    d: &[f64],
    out: &mut [f64],
) -> Result<bool, Failure> {
    step_difference(system, (t, y), h, (step_as_accepted, Some(y_end)), d, out)
}

/// `(step(y + ε d) − step(y)) / ε` into `out`, `ε` from
/// [`difference_size`], `step` one step of length `h` from `(t, ·)` by
/// `arithmetic` ([`plain_step`] or [`step_as_accepted`]: `k[..n]` the
/// rate at its start, `k` and the stage state its scratch), `step(y)`
/// taken here unless `end` gives it (the step already taken): the
/// two derivatives above. `Ok(false)` when a value was not finite.
fn step_difference<S, F>(
    system: &S,
    (t, y): (f64, &[f64]),
    h: f64,
    (arithmetic, end): (F, Option<&[f64]>),
    d: &[f64],
    out: &mut [f64],
) -> Result<bool, Failure>
where
    S: System + ?Sized,
    F: Fn(&S, f64, &[f64], f64, &mut [f64], &mut [f64], &mut [f64]) -> Result<(), Failure>,
{
    let n = y.len();
    let Some(eps) = difference_size(y, d) else {
        out[..n].fill(0.0);
        return Ok(d.iter().all(|&v| v == 0.0));
    };
    let mut k = vec![0.0; STAGES * n];
    let mut stage_state = vec![0.0; n];
    let own;
    let end = match end {
        Some(end) => end,
        None => {
            let mut base = vec![0.0; n];
            system.rhs(t, y, &mut k[..n])?;
            arithmetic(system, t, y, h, &mut k, &mut stage_state, &mut base)?;
            own = base;
            &own[..]
        }
    };
    let moved: Vec<f64> = y.iter().zip(d).map(|(y, d)| y + eps * d).collect();
    system.rhs(t, &moved, &mut k[..n])?;
    arithmetic(system, t, &moved, h, &mut k, &mut stage_state, out)?;
    for (o, b) in out[..n].iter_mut().zip(end) {
        *o = (*o - b) / eps;
    }
    Ok(first_non_finite(&out[..n]).is_none())
}

/// The difference quotient's `ε` for a direction `d` at `y`: `ε d` about
/// √eps of the state (the one-sided difference's balance of truncation,
/// `ε |d|²`, and rounding, `eps |y| / ε`); `None` for a zero or not
/// finite direction.
fn difference_size(y: &[f64], d: &[f64]) -> Option<f64> {
    let size = d.iter().fold(0.0_f64, |a, v| a.max(v.abs()));
    if size == 0.0 || !size.is_finite() {
        return None;
    }
    let scale = y.iter().fold(1.0_f64, |a, v| a.max(v.abs()));
    Some(f64::EPSILON.sqrt() * scale / size)
}

/// `dst = base + h Σ_m a_m k_m` component by component; `R` is a
/// compile-time row length, so the inner sum unrolls.
#[inline(always)]
fn combine<const R: usize>(dst: &mut [f64], base: &[f64], h: f64, row: &[(f64, &[f64]); R]) {
    let n = dst.len();
    let base = &base[..n];
    for i in 0..n {
        let mut acc = 0.0;
        for (a, k) in row {
            acc += a * k[i];
        }
        dst[i] = base[i] + h * acc;
    }
}

/// `y += a x`.
#[inline]
fn axpy(a: f64, x: &[f64], y: &mut [f64]) {
    for (yi, xi) in y.iter_mut().zip(x) {
        *yi += a * xi;
    }
}

impl Start for Dop853 {
    const NAME: &'static str = "DOP853";

    fn start<S: System + ?Sized>(
        system: &S,
        t0: f64,
        y0: &[f64],
        tol: Tolerance,
        h_max: f64,
        h0: Option<f64>,
    ) -> Result<Self, Failure> {
        Dop853::new(system, t0, y0, tol, h_max, h0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::Matrix;

    /// A nonlinear, time-dependent system of any size: every component
    /// coupled to the next.
    struct Ring(usize);

    impl System for Ring {
        fn dim(&self) -> usize {
            self.0
        }
        fn rhs(&self, t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), Failure> {
            let n = self.0;
            for i in 0..n {
                dy[i] = (1.0 + 0.5 * t) * y[(i + 1) % n].sin() - 0.3 * y[i] + 0.1 * i as f64;
            }
            Ok(())
        }
        fn jacobian(&self, _t: f64, _y: &[f64], _jac: &mut Matrix) -> Result<(), Failure> {
            unreachable!()
        }
        fn time_partial(&self, _t: f64, _y: &[f64], _d: &mut [f64]) -> Result<(), Failure> {
            unreachable!()
        }
    }

    use crate::ode::test_systems::Spring;

    /// Two half-steps in storage left by other sizes and states are the
    /// same, bit for bit, as in fresh storage.
    #[test]
    fn half_steps_in_reused_storage_are_those_in_fresh_storage() {
        let mut scratch = HalvesScratch::default();
        for (n, t, h) in [(5, 0.3, 0.7), (2, 1.1, 0.25), (8, -0.4, 1.3), (2, 2.0, 0.5)] {
            let y: Vec<f64> = (0..n).map(|i| 0.2 + 0.37 * i as f64).collect();
            let (mut fresh, mut reused) = (vec![0.0; n], vec![7.0; n]);
            let a = step_by_halves_in(
                &Ring(n),
                t,
                &y,
                h,
                &mut fresh,
                &mut HalvesScratch::default(),
            );
            let b = step_by_halves_in(&Ring(n), t, &y, h, &mut reused, &mut scratch);
            assert_eq!((a.ok(), b.ok()), (Some(true), Some(true)));
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&fresh), bits(&reused), "n = {n}");
        }
    }

    /// A step over three periods of a spring is cut into pieces until the
    /// chain meets the given end; a short step stays one piece.
    #[test]
    fn an_output_step_too_long_for_the_motion_is_cut_into_pieces() {
        let w = 20.0_f64;
        let tol = Tolerance {
            rtol: 1e-8,
            atol: 1e-10,
        };
        let exact = |t: f64| [(w * t).cos(), -w * (w * t).sin()];
        let (pieces, miss) =
            dense_steps_between(&Spring(w), 0.0, 1.0, &exact(0.0), &exact(1.0), tol).unwrap();
        assert!(
            pieces.len() > 1 && pieces.len() <= MOST_PIECES,
            "{}",
            pieces.len()
        );
        assert!(miss <= 1.0, "{miss}");
        let mut x = [0.0; 2];
        for t in [0.013, 0.37, 0.5, 0.999] {
            let piece = pieces.iter().find(|p| t <= p.t_new).unwrap();
            piece.eval(t, &mut x);
            let e = exact(t);
            assert!(
                (x[0] - e[0]).abs() < 1e-7,
                "t {t}: {} against {}",
                x[0],
                e[0]
            );
        }
        let (short, _) =
            dense_steps_between(&Spring(w), 0.0, 0.01, &exact(0.0), &exact(0.01), tol).unwrap();
        assert_eq!(short.len(), 1);
    }

    /// The plain step compiled for a size (`plain_step_sized::<N>`, what
    /// `plain_step` runs for n ∈ {2, 3, 4, 6, 8}: the global error's
    /// references) is the one that reads the size at run time, bit for
    /// bit.
    #[test]
    fn the_plain_step_compiled_for_a_size_is_the_general_one_bit_for_bit() {
        for n in [2, 3, 4, 6, 8] {
            let system = Ring(n);
            let y: Vec<f64> = (0..n).map(|i| 0.3 + 0.7 * (i as f64 * 1.1).sin()).collect();
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            let mut outs = Vec::new();
            for sized in [true, false] {
                let mut k = vec![0.0; STAGES * n];
                let mut stage_state = vec![0.0; n];
                let mut out = vec![0.0; n];
                system.rhs(0.2, &y, &mut k[..n]).unwrap();
                if sized {
                    plain_step(&system, 0.2, &y, 0.37, &mut k, &mut stage_state, &mut out)
                } else {
                    plain_step_sized::<Ring, 0>(
                        &system,
                        0.2,
                        &y,
                        0.37,
                        &mut k,
                        &mut stage_state,
                        &mut out,
                    )
                }
                .unwrap();
                outs.push((bits(&out), bits(&k)));
            }
            assert_eq!(outs[0], outs[1], "n = {n}");
        }
    }

    /// The step compiled for a size (`step_sized::<N>`, what
    /// `step_measured` runs for n ∈ {2, 3, 4, 6, 8, 12, 20}) is the step that
    /// reads the size at run time, bit for bit: states, step sizes,
    /// rejections and error estimates.
    #[test]
    fn the_step_compiled_for_a_size_is_the_general_step_bit_for_bit() {
        fn run(n: usize, sized: bool) -> Vec<u64> {
            let system = Ring(n);
            let y0: Vec<f64> = (0..n).map(|i| 0.3 + 0.7 * i as f64).collect();
            let tol = Tolerance {
                rtol: 1e-9,
                atol: 1e-11,
            };
            let mut dop = Dop853::new(&system, 0.0, &y0, tol, f64::INFINITY, None).unwrap();
            let budget = Budget::default();
            let mut bits = Vec::new();
            while dop.clock.t < 20.0 {
                let mut measure = HairerMeasure(tol);
                if sized {
                    dop.step_measured(&system, 20.0, &budget, &mut measure)
                } else {
                    dop.step_sized::<_, _, 0>(&system, 20.0, &budget, &mut measure)
                }
                .unwrap();
                let mut local = vec![0.0; n];
                dop.local_error(&mut local);
                bits.extend(dop.y.iter().chain(&local).map(|v| v.to_bits()));
                bits.push(dop.clock.t.to_bits());
                bits.push(dop.clock.h.to_bits());
            }
            bits.push(dop.clock.stats.rejected_steps as u64);
            bits.push(dop.clock.stats.rhs_evaluations as u64);
            bits
        }
        for n in [1, 2, 3, 4, 5, 6, 8, 12, 20] {
            let general = run(n, false);
            assert!(general.len() > 50, "n = {n}: {} numbers", general.len());
            assert_eq!(run(n, true), general, "n = {n}");
        }
    }

    /// The summed steps' relative error without the vector is the
    /// vector's, bit for bit.
    #[test]
    fn the_relative_local_error_is_that_of_the_vector_bit_for_bit() {
        for n in [1, 2, 3, 5] {
            let system = Ring(n);
            let y0: Vec<f64> = (0..n).map(|i| 0.3 + 0.7 * i as f64).collect();
            let tol = Tolerance {
                rtol: 1e-9,
                atol: 1e-11,
            };
            let mut dop = Dop853::new(&system, 0.0, &y0, tol, f64::INFINITY, None).unwrap();
            let budget = Budget::default();
            let mut local = vec![0.0; n];
            while dop.clock.t < 5.0 {
                dop.step_measured(&system, 5.0, &budget, &mut HairerMeasure(tol))
                    .unwrap();
                dop.local_error(&mut local);
                let vector = global_error::relative(&local, &dop.y);
                assert!(vector > 0.0);
                assert_eq!(dop.local_error_relative().to_bits(), vector.to_bits());
            }
        }
    }

    /// The step a derivative is differenced against is the step the run
    /// took: taken again from its start with `step_as_accepted` it ends on
    /// the accepted state bit for bit, at every size (the sized and the
    /// general step), at every step, the last one cut to the limit too.
    /// And the derivative against it is the derivative of two new steps
    /// to the difference's own accuracy (about √eps).
    #[test]
    fn the_derivative_against_the_accepted_step_is_the_derivative_of_two_new_steps() {
        for n in [1, 2, 3, 4, 5, 6, 8, 9] {
            let system = Ring(n);
            let y0: Vec<f64> = (0..n).map(|i| 0.3 + 0.7 * i as f64).collect();
            let tol = Tolerance {
                rtol: 1e-7,
                atol: 1e-9,
            };
            let mut dop = Dop853::new(&system, 0.0, &y0, tol, f64::INFINITY, None).unwrap();
            let budget = Budget::default();
            let d: Vec<f64> = (0..n).map(|i| 1e-8 * (1.0 - 0.4 * i as f64)).collect();
            let mut steps = 0;
            while dop.clock.t < 7.3 {
                dop.step_measured(&system, 7.3, &budget, &mut HairerMeasure(tol))
                    .unwrap();
                steps += 1;
                let (t0, _, h) = dop.clock.last_step();
                let mut k = vec![0.0; STAGES * n];
                let (mut stage_state, mut end) = (vec![0.0; n], vec![0.0; n]);
                system.rhs(t0, &dop.y_old, &mut k[..n]).unwrap();
                step_as_accepted(
                    &system,
                    t0,
                    &dop.y_old,
                    h,
                    &mut k,
                    &mut stage_state,
                    &mut end,
                )
                .unwrap();
                let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&end), bits(&dop.y), "n = {n}, step {steps}");
                let (mut one, mut two) = (vec![0.0; n], vec![0.0; n]);
                let y_old = dop.y_old.clone();
                assert!(step_derivative_from_accepted(
                    &system,
                    (t0, &y_old),
                    h,
                    &dop.y,
                    &d,
                    &mut one
                )
                .unwrap());
                assert!(step_derivative(&system, t0, &y_old, h, &d, &mut two).unwrap());
                // The difference's rounding, `eps |y| / ε`, is √eps of the
                // direction's size (a few dozen roundings of the stages).
                let size = d.iter().fold(0.0_f64, |a, v| a.max(v.abs()));
                for (a, b) in one.iter().zip(&two) {
                    assert!(
                        (a - b).abs() <= 1e-6 * size,
                        "n = {n}: {one:?} against {two:?}"
                    );
                }
            }
            assert!(steps > 10, "n = {n}: {steps} steps");
        }
    }

    /// A restart in place (`restart_at`, after a projection) is the new
    /// stepper it replaces: from a state moved off the last step's, both
    /// go on bit for bit (states, step sizes, dense output, evaluations),
    /// whether or not the first step size is given; and a failing start
    /// leaves the state and time as they were.
    #[test]
    fn a_restart_in_place_is_a_new_stepper_bit_for_bit() {
        let system = Ring(4);
        let y0 = [0.3, 1.0, 1.7, 2.4];
        let tol = Tolerance {
            rtol: 1e-9,
            atol: 1e-11,
        };
        let budget = Budget::default();
        let trace = |dop: &mut Dop853| {
            let mut bits = Vec::new();
            let mut out = [0.0; 4];
            for _ in 0..12 {
                let t = dop.clock.t;
                Stepper::step(dop, &system, 20.0, &budget).unwrap();
                Stepper::dense(dop, &system, 0.5 * (t + dop.clock.t), &mut out).unwrap();
                bits.extend(dop.y.iter().chain(&out).map(|v| v.to_bits()));
                bits.push(dop.clock.h.to_bits());
            }
            bits.push(dop.clock.stats.rhs_evaluations as u64);
            bits
        };
        for h0 in [Some(0.05), None] {
            let mut dop = Dop853::new(&system, 0.0, &y0, tol, f64::INFINITY, None).unwrap();
            trace(&mut dop);
            let t = dop.clock.t;
            let moved: Vec<f64> = dop.y.iter().map(|v| v * (1.0 + 1e-7)).collect();
            let mut fresh = Dop853::new(&system, t, &moved, tol, f64::INFINITY, h0).unwrap();
            dop.restart_at(&system, t, &moved, tol, f64::INFINITY, h0)
                .unwrap();
            let expected = trace(&mut fresh);
            assert!(expected.len() > 100);
            assert_eq!(trace(&mut dop), expected, "h0 {h0:?}");
        }
        let mut dop = Dop853::new(&system, 0.0, &y0, tol, f64::INFINITY, None).unwrap();
        trace(&mut dop);
        let (t, y) = (dop.clock.t, dop.y.clone());
        let broken = [f64::NAN, 1.0, 1.0, 1.0];
        assert!(dop
            .restart_at(&system, t, &broken, tol, f64::INFINITY, None)
            .is_err());
        assert_eq!((dop.clock.t, &dop.y), (t, &y));
    }
}
