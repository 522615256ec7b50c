//! Direct integration's states inside an accepted DOP853 step, with the
//! continuous extension judged before it is trusted.
//!
//! Why: the extension (`contd8`, order 7) is not the step. Its error in
//! mid-step is bounded by the step's accepted error only while the step is
//! short against the motion's fastest decay. Once a motion settles, the
//! step grows until stability holds it (Hairer's `h·ρ` 4–8): the step's
//! ends stay within the tolerance, but the extension's polynomial in `θ`
//! amplifies the damped fast modes between them. A two-link arm under PD
//! control (`tests/data/arm_pd_settling.lag`) had its samples in the
//! settled stretch 14 / 88 / 1,340 rtol off at rtol 1e-10 / 1e-11 /
//! 1e-12 while its step ends were within 3e-11 (docs/BENCHMARKS.md §10,
//! h-dense2) — a silent wrong answer, the run saying "within". A rule by
//! the step's `h·ρ` (the one-stage estimate of the stiffness test) does not
//! tell those steps: it scatters 30× from step to step.
//!
//! The judge: the first time a state strictly inside the last accepted
//! step is read, the extension at the step's middle is set against one
//! DOP853 step of half the length from the step's start (11 evaluations:
//! its first stage is the step's own first rate). That half step is
//! inside the stability region wherever the whole one was, and its own
//! error is about 1/512 of the whole step's (order 8), so the difference
//! is the extension's error there. Past [`EXTENSION_GATE`] every state
//! inside that step is read by such a step from its start to the state's
//! time instead (11 evaluations a read); within it, by the extension.
//! The half step is taken only where a cheaper estimate (4 evaluations:
//! the extension against the integral of the right side along it) does
//! not keep the extension well within the gate ([`KEEP_BELOW`]).

use super::{plain_step, Dop853, STAGES};
use crate::failure::Failure;
use crate::math::GAUSS_LEGENDRE_4;
use crate::ode::stepper::outside_last_step;
use crate::ode::system::System;

/// How far the extension may stand off the half step at the step's middle
/// before the step's inside is read by steps, in tolerances of the largest
/// component (a sample is read component by component). The summary
/// promises samples between steps within a few rtol of the step ends; the
/// arm's settled steps stand 10–1000 tolerances off, its free steps mostly
/// below 1, and the peers' models' extensions (vertical_rocket's) at
/// 0.8–1.1. At 1 (first measured) vertical_rocket's 11-sample runs took
/// +18 … +33 % evaluations; at 2, +8 … +20 %, with the arm's samples the
/// same (at 101 samples 2.0e-11 / 1.2e-11 / 1.2e-11 against SciPy at rtol
/// 1e-10 / 1e-11 / 1e-12) and a pendulum at rtol 1e-5 (501 samples) 103 →
/// 15.6 rtol either way (lead, §10x h-dense2).
pub(super) const EXTENSION_GATE: f64 = 2.0;

/// The extension is kept without the half step where its quadrature's
/// estimate stands below this fraction of [`EXTENSION_GATE`]. Over every
/// judged step of the settling arm (rtol 1e-10 … 1e-12, 5001 samples) and
/// the peers' models (paper, knife_edge, vertical_rocket; 1e-6 … 1e-12,
/// 101 samples) the estimate stood 0.57–1.26× the half step's verdict, at
/// least 0.996× on every step past the gate; the steps it kept below 0.5
/// stood at most 0.43 tolerance off by the half step (§10x h-dense2).
const KEEP_BELOW: f64 = 0.5;

/// The judge's verdict on the last accepted step and its storage, kept
/// from step to step (a sample inside most steps: no allocation a read).
#[derive(Debug, Default)]
pub(super) struct Inside {
    /// `None`: the last accepted step not yet judged; then whether its
    /// inside is read by steps of its own.
    pub(super) by_steps: Option<bool>,
    k: Vec<f64>,
    stage_state: Vec<f64>,
    state: Vec<f64>,
}

impl Inside {
    /// Forgets the verdict: a new step was accepted.
    pub(super) fn new_step(&mut self) {
        self.by_steps = None;
    }
}

impl Dop853 {
    /// The state at `t` by the last accepted step, as direct integration
    /// reads it: the step's ends outside it, inside it the continuous
    /// extension once judged close enough to a step at its middle, else a
    /// DOP853 step from the step's start to `t` (module docs). The trait's
    /// [`crate::ode::stepper::Stepper::dense`] stays the extension alone
    /// (the field's windows read their own systems' steps and judge their
    /// output pieces themselves, `method::field::middle`).
    pub fn dense_judged<S: System + ?Sized>(
        &mut self,
        system: &S,
        t: f64,
        out: &mut [f64],
    ) -> Result<(), Failure> {
        let step = crate::ode::stepper::Clocked::clock(self).last_step();
        if let Some(end) = outside_last_step(t, step, &self.y_old, &self.y) {
            out.copy_from_slice(end);
            return Ok(());
        }
        let (t_old, h) = (self.clock.t_old, self.clock.h_old);
        let by_steps = match self.inside.by_steps {
            Some(verdict) => verdict,
            None => {
                let off = self.extension_off_at_middle(system, out)?;
                let verdict = !(off <= EXTENSION_GATE);
                self.inside.by_steps = Some(verdict);
                verdict
            }
        };
        if by_steps {
            self.step_inside(system, t - t_old, out)
        } else {
            if !self.dense_ready {
                self.prepare_dense(system)?;
            }
            super::contd8(self.cont(), self.y.len(), (t - t_old) / h, out);
            Ok(())
        }
    }

    /// How many tolerances the extension at the last step's middle stands
    /// off a half step from its start (the largest component's; not
    /// finite: infinitely off), that half step taken only where the
    /// extension's own quadrature ([`Dop853::quadrature_off_at_middle`])
    /// does not already keep it well within the gate (then that estimate).
    /// `work` is scratch of the state's size.
    fn extension_off_at_middle<S: System + ?Sized>(
        &mut self,
        system: &S,
        work: &mut [f64],
    ) -> Result<f64, Failure> {
        if !self.dense_ready {
            self.prepare_dense(system)?;
        }
        let estimate = self.quadrature_off_at_middle(system, work)?;
        if estimate <= KEEP_BELOW * EXTENSION_GATE {
            return Ok(estimate);
        }
        let n = self.y.len();
        super::contd8(self.cont(), n, 0.5, work);
        let half = 0.5 * self.clock.h_old;
        self.step_inside(system, half, &mut [])?;
        Ok(self.tol.tolerances_off(work, &self.inside.state))
    }

    /// The extension `p` at the middle against the step's start plus the
    /// integral of the right side along `p` (Gauss–Legendre, 4 points: 4
    /// evaluations), in tolerances of the largest component. The two
    /// differ by the integral of `p`'s defect `p' − X(t, p)`: the
    /// extension's error in mid-step where the motion is not stiff, and
    /// more than it where the extension wiggles across a fast decaying
    /// mode (its defect then carries `J e`, `h·ρ` times the error).
    fn quadrature_off_at_middle<S: System + ?Sized>(
        &mut self,
        system: &S,
        work: &mut [f64],
    ) -> Result<f64, Failure> {
        let n = self.y.len();
        let (t_old, h) = (self.clock.t_old, self.clock.h_old);
        let half = 0.5 * h;
        let inside = &mut self.inside;
        inside.k.resize(super::STAGES * n, 0.0);
        inside.stage_state.resize(n, 0.0);
        inside.state.resize(n, 0.0);
        let cont = &self.k[super::CONT * n..super::BLOCKS * n];
        // ∫ X(t, p) over the half step, into `state`.
        inside.state.fill(0.0);
        let (point, rate) = inside.k.split_at_mut(n);
        let rate = &mut rate[..n];
        for (node, weight) in GAUSS_LEGENDRE_4 {
            let theta = 0.5 * node;
            super::contd8(cont, n, theta, point);
            system.rhs(t_old + theta * h, point, rate)?;
            for i in 0..n {
                inside.state[i] += half * weight * rate[i];
            }
        }
        self.clock.stats.rhs_evaluations += GAUSS_LEGENDRE_4.len();
        super::contd8(cont, n, 0.5, work);
        for i in 0..n {
            inside.stage_state[i] = self.y_old[i] + inside.state[i];
        }
        Ok(self.tol.tolerances_off(work, &inside.stage_state))
    }

    /// One DOP853 step of length `h` (inside the last accepted step) from
    /// its start, into `out` (empty: into the judge's own state). No error
    /// control: the whole step was accepted, its part is shorter.
    fn step_inside<S: System + ?Sized>(
        &mut self,
        system: &S,
        h: f64,
        out: &mut [f64],
    ) -> Result<(), Failure> {
        let n = self.y.len();
        let inside = &mut self.inside;
        inside.k.resize(STAGES * n, 0.0);
        inside.stage_state.resize(n, 0.0);
        inside.state.resize(n, 0.0);
        // The step's first rate, kept at k[12] for the extension.
        inside.k[..n].copy_from_slice(&self.k[12 * n..13 * n]);
        let target = if out.is_empty() {
            &mut inside.state[..]
        } else {
            out
        };
        plain_step(
            system,
            self.clock.t_old,
            &self.y_old,
            h,
            &mut inside.k,
            &mut inside.stage_state,
            target,
        )?;
        self.clock.stats.rhs_evaluations += STAGES - 1;
        Ok(())
    }
}
