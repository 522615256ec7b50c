//! The steps' local errors carried along the motion, as the motion
//! carries them: `e_{n+1} = Φ_n e_n ± ℓ_n`, with `Φ_n e_n` the derivative
//! of a DOP853 step over step `n` in the direction of the carried error
//! (a difference of two steps, [`crate::ode::dop853::step_derivative`]).
//!
//! Why: the sum of the local errors ([`super::GlobalError`]) is the global
//! error only where the motion neither amplifies nor damps errors. A
//! motion whose period depends on its energy turns an energy error into a
//! phase error that grows with time: two soft walls bounced off 400 times
//! (`tests/data/v2/soft_walls.lag`, rtol 1e-10) end 4.9e-6 off where the
//! sum of the local errors is 1.6e-8.
//!
//! Why the step's own derivative and not a cheaper linearised flow: the
//! soft walls' flow over a period has a double eigenvalue 1 (errors grow
//! linearly, not exponentially), and any error in the propagator tips it
//! to a pair `1 ± √ε`, an exponential growth. The trapezoidal rule on
//! `e' = J e` (a Jacobian a step) was tried first: its phase error in the
//! walls (`(hω)³/12` a step) made the carried error 1e31 after 400
//! bounces. A difference of DOP853 steps is the step's derivative to about
//! √eps, so `ε` is about 1e-8 and the growth stays linear over thousands
//! of periods.
//!
//! The local errors: with their signs. Whether an energy error made at
//! one bounce adds to the last one's or cancels it decides the growth
//! (the soft walls at rtol 1e-12 lose almost no energy over 800 events,
//! where their summed local errors are 800 rtol), so the vectors are the
//! steps' measured errors (a Richardson difference for direct
//! integration, a reference step for the field), not Hairer's estimates,
//! whose sign is the lower-order solution's: with those (added with their
//! sign, or with the sign that makes them add) the soft walls' estimate
//! ranged from 0.012 to 138 × the error over rtol 1e-6 … 1e-12
//! (docs/BENCHMARKS.md §10c).
//!
//! Events: a step is propagated when the next one begins, over as much of
//! it as the motion kept: an event cuts it at its time ([`Growth::cut`],
//! in the old regime), and the error of the state the run restarts from
//! (read from the step's continuous extension, of order 7) is measured
//! there. The error is then carried through the event by the saltation
//! of its time and the impact's reset ([`Growth::jump`],
//! `run::saltation`: direct integration; the field's carried error goes
//! through unchanged).
//!
//! Cost: 12 evaluations a step where the step is one DOP853 took from
//! its start to its end (direct integration's, not cut by an event): the
//! derivative is differenced against that step, and only the step from
//! the moved start is new ([`crate::ode::dop853::step_derivative_from_accepted`],
//! the same one-sided difference as two new steps, to the difference's
//! own √eps; the soft walls' estimate over rtol 1e-6 … 1e-12 moved by at
//! most 0.7 %); 24 for another method's step or a cut one, or none for
//! the field's steps carried by a reference alongside the run
//! ([`Growth::step_alongside`]: 24 a step for the measure and the
//! propagation together). And the
//! measure of the step's error, spent only once the calibrated sum of the local errors passes
//! [`FROM`]`·rtol` for the field ([`past_bound`]; from the first step on
//! a motion that is not affine, the field's `global_error`), where the
//! summary warns already, and [`FROM_DIRECT`]`·rtol` for direct integration,
//! where a motion that shears its errors may still take them past the
//! bound, or from its first step into a poor pivot taken again (where
//! Hairer's estimate is blind: `method::direct`'s `retake`); below it a
//! run pays nothing. The errors before are not carried (at most that
//! much, in the sum): the carried error starts at zero there.
//!
//! Constraints: in a run that keeps them, the carried error is projected
//! at every step as the state is ([`Growth::step_kept`]).
//!
//! Past the state's own size ([`super::AMPLIFIED`], a chaotic motion's
//! errors) the carrying stops ([`Growth::saturated`]): the summary says
//! amplification from there whatever follows.

use super::relative_over_step;
use crate::failure::Failure;
use crate::ode::dop853::{
    step_by_halves, step_by_halves_in, step_derivative, step_derivative_from_accepted,
    HalvesScratch,
};
use crate::ode::system::System;

/// The sum of the local errors, in units of rtol, from which the carried
/// error is propagated (the summary's bound).
pub const FROM: f64 = super::BOUND;

/// The calibrated sum, in units of rtol, from which direct integration
/// carries its errors along the motion: a tenth of the bound. A motion
/// whose period depends on its energy shears its errors: errors made
/// before the carrying starts are not carried, and they are the ones
/// that grow most. A slider-crank turning 30 times (rtol 1e-6 … 1e-10)
/// ended 9–34× its summed local errors off, its sum just under the bound
/// ("within"); carried from a tenth of the bound its estimate was
/// 0.46–1.1× its error, warned at every tolerance. The cost: every step
/// measured and propagated from there, 12 + 23 + 12 evaluations a step
/// (up to about 3.3× the evaluations of a run that does not carry, the
/// long ones; 4× while the derivative took two new steps).
pub const FROM_DIRECT: f64 = super::BOUND / 10.0;

/// Whether the calibrated sum passes `from`·rtol ([`FROM`] or
/// [`FROM_DIRECT`]).
pub fn past(global: &super::GlobalError, rtol: f64, from: f64) -> bool {
    global.calibrated() && global.estimate() > from * rtol
}

/// Whether the calibrated sum passes the bound: from there the errors are
/// carried along the motion (an uncalibrated sum, Hairer's estimates, is
/// often 10× the error: the first measure scales it first, or a run
/// within the bound pays for the carrying, 3.4× the evaluations of
/// bit_identity's third_order_constraint).
pub fn past_bound(global: &super::GlobalError, rtol: f64) -> bool {
    global.calibrated() && global.estimate() > FROM * rtol
}

/// The derivative of a run's projection onto its constraints at `(t, x)`
/// applied to a change `d` of the state, in place.
pub type Keep<'a> = dyn FnMut(f64, &[f64], &mut [f64]) -> Result<(), Failure> + 'a;

/// A run's projection onto its constraints at `t`, of a state in place
/// (the reference of [`Growth::step_alongside`]).
pub type Project<'a> = dyn FnMut(f64, &mut [f64]) -> Result<(), Failure> + 'a;

/// The carried error of one run.
#[derive(Clone, Debug)]
pub struct Growth {
    e: Vec<f64>,
    /// The last step, propagated when the next begins or an event cuts it.
    pending: Option<Step>,
    /// The largest carried error relative to `max(|x|, 1)` so far.
    largest: f64,
    moved: Vec<f64>,
    /// Evaluations spent.
    evaluations: usize,
    started: bool,
    /// Storage kept from step to step for [`Growth::step_alongside`]
    /// (scratch only: no value read from one step to the next): the last
    /// flushed step, the reference's start, its half-steps' stages.
    spare: Option<Step>,
    start: Vec<f64>,
    halves: HalvesScratch,
}

#[derive(Clone, Debug)]
struct Step {
    t0: f64,
    x0: Vec<f64>,
    t1: f64,
    local: Vec<f64>,
    /// A DOP853 step the run took: its length and end state, against
    /// which the step's derivative is differenced.
    accepted: Option<(f64, Vec<f64>)>,
    /// A step carried by a reference alongside ([`Growth::step_alongside`]).
    alongside: Option<Alongside>,
}

/// A step whose error is carried by a reference stepped alongside the
/// run: the run's state at the step's end, and the reference's there
/// (`None`: the reference failed, the error is left as it was).
#[derive(Clone, Debug)]
struct Alongside {
    x1: Vec<f64>,
    r1: Option<Vec<f64>>,
}

/// A step the run took with DOP853 from its start: its length `h` and the
/// state it ended on, as the stepper computed them (the derivative over
/// it then costs one step from a moved start, not two,
/// [`step_derivative_from_accepted`]).
#[derive(Clone, Copy, Debug)]
pub struct Accepted<'a> {
    pub h: f64,
    pub end: &'a [f64],
}

impl Growth {
    pub fn new(n: usize) -> Growth {
        Growth {
            e: vec![0.0; n],
            pending: None,
            largest: 0.0,
            moved: vec![0.0; n],
            evaluations: 0,
            started: false,
            spare: None,
            start: Vec::new(),
            halves: HalvesScratch::default(),
        }
    }

    /// Makes this one [`Growth::new`]`(n)` (an earlier solve's, its
    /// storage reused): every field named, as `new` sets it.
    pub fn renew(&mut self, n: usize) {
        let Growth {
            e,
            pending,
            largest,
            moved,
            evaluations,
            started,
            // Scratch: whatever an earlier solve left is overwritten
            // before it is read.
            spare: _,
            start: _,
            halves: _,
        } = self;
        for v in [e, moved] {
            v.clear();
            v.resize(n, 0.0);
        }
        *pending = None;
        *largest = 0.0;
        *evaluations = 0;
        *started = false;
    }

    /// The largest carried error over the run, relative to `max(|x|, 1)`
    /// component by component.
    pub fn largest(&self) -> f64 {
        self.largest
    }

    /// Whether the carried error has passed the state's own size
    /// ([`super::AMPLIFIED`]): from there the summary reports the run as
    /// amplifying its errors whatever comes after (the largest error is
    /// kept), so no step is measured or propagated any more (a chaotic
    /// double pendulum paid 3.7× DOP853's evaluations for the carrying).
    pub fn saturated(&self) -> bool {
        self.largest >= super::AMPLIFIED
    }

    /// Whether a step was carried: from then on every step is (the sum
    /// that started it may fall back below the bound when a measure
    /// scales it).
    pub fn started(&self) -> bool {
        self.started
    }

    /// The right-side evaluations the propagation cost.
    pub fn evaluations(&self) -> usize {
        self.evaluations
    }

    /// The step from `(t0, x0)` to `t1` whose local error is `local` (a
    /// vector with its sign): the carried error is propagated over it and
    /// the step's error added when the next step begins or an event cuts
    /// it. The step before it is done now.
    pub fn step<S: System + ?Sized>(
        &mut self,
        system: &S,
        (t0, x0): (f64, &[f64]),
        t1: f64,
        local: &[f64],
    ) {
        self.step_kept(system, (t0, x0), t1, local, None, None);
    }

    /// [`Growth::step`] in a run kept on constraints: the carried error,
    /// once at `(t0, x0)`, is replaced by the part of it that the run's
    /// projection keeps (`keep(t, x, e)`, the projection's derivative),
    /// as the run's state is projected there. Without it the reduced
    /// system's drift off the constraints grows the carried error without
    /// bound (the module's comment in `global_error`). `accepted`: the
    /// step is a DOP853 step the run took from `x0` ([`Accepted`]).
    pub fn step_kept<S: System + ?Sized>(
        &mut self,
        system: &S,
        (t0, x0): (f64, &[f64]),
        t1: f64,
        local: &[f64],
        keep: Option<&mut Keep<'_>>,
        accepted: Option<Accepted<'_>>,
    ) {
        if self.saturated() {
            self.pending = None;
            return;
        }
        self.flush(system, f64::INFINITY, keep.map(|k| (k, t0, x0)));
        self.started = true;
        self.pending = Some(Step {
            t0,
            x0: x0.to_vec(),
            t1,
            local: local.to_vec(),
            accepted: accepted.map(|a| (a.h, a.end.to_vec())),
            alongside: None,
        });
    }

    /// The step of another method (the field's) from `(t0, x0)` to
    /// `(t1, x1)`, its error carried by a reference alongside the run: the
    /// reference `x0 − e` (`e` the carried error at the step's start) is
    /// stepped by two DOP853 half-steps ([`step_by_halves`], 24
    /// evaluations) to `r1`, and the carried error at the step's end is
    /// `x1 − r1`: the step's own error with its sign and the error before
    /// it carried by the flow, in one. Where the run is kept on its
    /// constraints, `project` puts the last step's reference on them at
    /// `(t0, x0)` as the run's state is put there, and the error carried
    /// on is `x0 − P(r1)`.
    ///
    /// Why: [`Growth::step_kept`] with a measured local error costs 48
    /// evaluations for the same (the measure from `x0`, 24, and the
    /// derivative, two new steps, 24). And why the projection itself, not
    /// its derivative ([`Keep`]) applied to the carried error: a four-bar
    /// kept by velocity constraints (`four_bar_velocity`, rtol 1e-6) ends
    /// 1.6e-2 off, a phase error of tenths of a radian in its crank's
    /// angle, and the derivative of the projection applied to an error
    /// that size put the reference off the constraints, whose motion
    /// then left the run's: the carried error stopped growing half way
    /// (0.48× the error at the end; the projection itself: 1.23×).
    ///
    /// What this does not do: scale a step's error down to its estimate
    /// (the field's `at_most_estimated`), for the step's error is never
    /// apart from the carried one here.
    pub fn step_alongside<S: System + ?Sized>(
        &mut self,
        system: &S,
        (t0, x0): (f64, &[f64]),
        (t1, x1): (f64, &[f64]),
        project: Option<&mut Project<'_>>,
    ) {
        if self.saturated() {
            self.pending = None;
            return;
        }
        if let (Some(project), Some(step)) = (project, self.pending.as_mut()) {
            if let Some(Alongside { x1, r1: Some(r1) }) = step.alongside.as_mut() {
                // A projection that fails leaves the reference where it
                // was: the estimate never fails the run.
                let mut projected = r1.clone();
                if project(t0, &mut projected).is_ok() {
                    *r1 = projected;
                    x1.copy_from_slice(x0);
                }
            }
        }
        self.flush(system, f64::INFINITY, None);
        self.started = true;
        // The last flushed step's storage, reused (at every step of a
        // field run once carried: seven allocations a step).
        let mut step = self.spare.take().unwrap_or_else(|| Step {
            t0,
            x0: Vec::new(),
            t1,
            local: Vec::new(),
            accepted: None,
            alongside: None,
        });
        let mut alongside = step.alongside.take().unwrap_or(Alongside {
            x1: Vec::new(),
            r1: None,
        });
        let mut reference = std::mem::take(&mut self.start);
        reference.clear();
        reference.extend(x0.iter().zip(&self.e).map(|(x, e)| x - e));
        let mut r1 = alongside.r1.take().unwrap_or_default();
        r1.clear();
        r1.resize(x0.len(), 0.0);
        self.evaluations += 24;
        // A reference that fails leaves the error as it is: the estimate
        // never fails the run.
        let stepped = step_by_halves_in(system, t0, &reference, t1 - t0, &mut r1, &mut self.halves);
        self.start = reference;
        alongside.r1 = match stepped {
            Ok(true) => Some(r1),
            _ => None,
        };
        alongside.x1.clear();
        alongside.x1.extend_from_slice(x1);
        step.t0 = t0;
        step.x0.clear();
        step.x0.extend_from_slice(x0);
        step.t1 = t1;
        step.local.clear();
        step.accepted = None;
        step.alongside = Some(alongside);
        self.pending = Some(step);
    }

    /// At the run's end: the pending step propagated over and added, as
    /// the next step would do (without projecting the carried error: no
    /// state follows to be projected).
    pub fn finish<S: System + ?Sized>(&mut self, system: &S) {
        if self.saturated() {
            self.pending = None;
            return;
        }
        self.flush(system, f64::INFINITY, None);
    }

    /// Before the first step: the error the carrying starts from, `e` at
    /// `(t, x)` (an error measured before, whose steps were not carried),
    /// projected by `keep` as the run's state is there.
    pub fn seed(&mut self, e: &[f64], keep: Option<(&mut Keep<'_>, f64, &[f64])>) {
        if self.started || self.pending.is_some() {
            return;
        }
        self.e.copy_from_slice(e);
        if let Some((keep, t, x)) = keep {
            // As in `flush`: a projection's derivative that fails leaves
            // the error whole.
            let _ = keep(t, x, &mut self.e);
        }
    }

    /// The pending step is not the motion (taken again from its start,
    /// `Solver::retake`): it is neither propagated over nor added.
    /// The carried error changed by `jump` at an event (after
    /// [`Growth::cut`], nothing pending), where one is carried: `jump`
    /// failing leaves it as it was.
    pub fn jump(&mut self, jump: &mut dyn FnMut(&mut [f64]) -> Result<(), Failure>) {
        if !self.started || self.saturated() || self.pending.is_some() {
            return;
        }
        let mut e = self.e.clone();
        if jump(&mut e).is_ok() && e.iter().all(|v| v.is_finite()) {
            self.e = e;
        }
    }

    pub fn discard_pending(&mut self) {
        self.pending = None;
    }

    /// The model may have changed since the pending step was taken (a
    /// regime switch, which restarts the run without an event's cut): its
    /// derivative is then taken by two new steps in the model as it is
    /// when the next step begins, as before [`Accepted`] (the accepted
    /// step, of the old regime, differenced against a step of the new
    /// one would measure the regimes' difference, not the motion's).
    pub fn forget_accepted(&mut self) {
        if let Some(step) = self.pending.as_mut() {
            step.accepted = None;
        }
    }

    /// An event at `t`, where the run goes on from `x` (the step's
    /// continuous extension there): the last step's motion ends at `t`
    /// (called in the regime the step was taken in), and its error is
    /// that of `x`, measured against two DOP853 half-steps from the
    /// step's start (24 evaluations): the extension's error, which no
    /// step's estimate holds, is the error the run restarts with.
    pub fn cut<S: System + ?Sized>(&mut self, system: &S, t: f64, x: &[f64]) {
        if self.saturated() {
            self.pending = None;
            return;
        }
        if let Some(step) = self.pending.as_mut() {
            let h = t - step.t0;
            let mut reference = vec![0.0; x.len()];
            if let Some(alongside) = step.alongside.as_mut() {
                // The reference stepped from the step's start to `t` only,
                // against the state the run goes on from.
                if h <= 0.0 {
                    alongside.r1 = None;
                } else if t <= step.t1 {
                    self.evaluations += 24;
                    let start: Vec<f64> = step.x0.iter().zip(&self.e).map(|(x, e)| x - e).collect();
                    alongside.x1 = x.to_vec();
                    alongside.r1 = match step_by_halves(system, step.t0, &start, h, &mut reference)
                    {
                        Ok(true) => Some(reference),
                        _ => None,
                    };
                    step.t1 = t;
                }
            } else if h > 0.0 && t <= step.t1 {
                self.evaluations += 24;
                if let Ok(true) = step_by_halves(system, step.t0, &step.x0, h, &mut reference) {
                    for ((l, x), r) in step.local.iter_mut().zip(x).zip(&reference) {
                        *l = x - r;
                    }
                }
            }
        }
        self.flush(system, t, None);
    }

    /// Propagates the pending step over `[t0, min(t1, t_end)]` and adds its
    /// error.
    fn flush<S: System + ?Sized>(
        &mut self,
        system: &S,
        t_end: f64,
        keep: Option<(&mut Keep<'_>, f64, &[f64])>,
    ) {
        let Some(step) = self.pending.take() else {
            return;
        };
        let h = step.t1.min(t_end) - step.t0;
        if let Some(alongside) = &step.alongside {
            // Carried by the reference (an event's cut moved the step's
            // end to the event, `cut`).
            if let Some(r1) = &alongside.r1 {
                for ((e, x), r) in self.e.iter_mut().zip(&alongside.x1).zip(r1) {
                    *e = x - r;
                }
            }
        } else if h > 0.0 && self.e.iter().any(|&v| v != 0.0) {
            // A derivative that fails leaves the error as it is: the
            // estimate never fails the run. Over the whole of a step the
            // run took, against that step; over part of it (an event's
            // cut) or another method's step, two new steps.
            let derivative = match &step.accepted {
                Some((h, end)) if step.t1 <= t_end => {
                    self.evaluations += 12;
                    step_derivative_from_accepted(
                        system,
                        (step.t0, &step.x0),
                        *h,
                        end,
                        &self.e,
                        &mut self.moved,
                    )
                }
                _ => {
                    self.evaluations += 24;
                    step_derivative(system, step.t0, &step.x0, h, &self.e, &mut self.moved)
                }
            };
            if let Ok(true) = derivative {
                self.e.copy_from_slice(&self.moved);
            }
        }
        for (e, l) in self.e.iter_mut().zip(&step.local) {
            *e += l;
        }
        if let Some((keep, t, x)) = keep {
            // A projection's derivative that fails leaves the error whole
            // (a bound on the kept part): the estimate never fails the run.
            let _ = keep(t, x, &mut self.e);
        }
        // Read over the step, where a sample may find a component at
        // zero (`relative_over_step`), against the end it reached.
        let end = match (&step.accepted, &step.alongside) {
            (Some((_, end)), _) if step.t1 <= t_end => end,
            (_, Some(alongside)) => &alongside.x1,
            _ => &step.x0,
        };
        let size = relative_over_step(&self.e, &step.x0, end);
        if size.is_finite() {
            self.largest = self.largest.max(size);
        }
        self.spare = Some(step);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::failure::Failure;

    /// `x' = v, v' = −ω² x` (ω = 0 is the soft walls' free flight).
    use crate::ode::test_systems::Spring as Oscillator;

    #[test]
    fn a_velocity_error_grows_into_a_position_error_and_errors_add_with_their_signs() {
        let free = Oscillator(0.0);
        let mut g = Growth::new(2);
        let x = [0.0, 1.0];
        // One velocity error, then 10 s of free flight: 10× in position.
        g.step(&free, (0.0, &x), 0.0, &[0.0, 1e-10]);
        g.step(&free, (0.0, &x), 10.0, &[0.0, 0.0]);
        g.step(&free, (10.0, &x), 10.0, &[0.0, 0.0]);
        assert!((g.largest() - 1e-9).abs() < 1e-16, "{}", g.largest());
        // An error of the other sign cancels (the velocity's stays).
        g.step(&free, (10.0, &x), 10.0, &[-1e-9, 0.0]);
        g.cut(&free, 10.0, &x);
        assert!((g.largest() - 1e-9).abs() < 1e-16, "{}", g.largest());
        assert!(g.e[0].abs() < 1e-16 && g.e[1] == 1e-10, "{:?}", g.e);
        // An event cuts a step: its motion ends there.
        let mut h = Growth::new(2);
        h.step(&free, (0.0, &x), 0.0, &[0.0, 1e-10]);
        h.step(&free, (0.0, &x), 10.0, &[0.0, 0.0]);
        // The state the run goes on from, 1e-12 off the motion there.
        h.cut(&free, 5.0, &[5.0 + 1e-12, 1.0]);
        // (5 + 1e-12 holds the 1e-12 to an ulp of 5, 9e-16.)
        assert!((h.largest() - 5.01e-10).abs() < 1e-14, "{}", h.largest());
        assert!((h.e[0] - (5e-10 + 1e-12)).abs() < 1e-14, "{:?}", h.e);
        assert_eq!(h.evaluations(), 48);
    }

    #[test]
    fn a_seeded_error_is_carried_from_the_first_step_and_only_before_it() {
        let free = Oscillator(0.0);
        let mut g = Growth::new(2);
        let x = [0.0, 1.0];
        g.seed(&[0.0, 1e-10], None);
        g.step(&free, (0.0, &x), 10.0, &[0.0, 0.0]);
        g.step(&free, (10.0, &x), 10.0, &[0.0, 0.0]);
        assert!((g.largest() - 1e-9).abs() < 1e-16, "{}", g.largest());
        // Once the carrying started, a seed changes nothing.
        g.seed(&[1.0, 1.0], None);
        assert!(
            (g.e[0] - 1e-9).abs() < 1e-16 && g.e[1] == 1e-10,
            "{:?}",
            g.e
        );
    }

    #[test]
    fn a_step_the_run_took_is_differenced_against_unless_forgotten() {
        let free = Oscillator(0.0);
        let x = [0.0, 1.0];
        // The free flight's step of 10 s ends at [10, 1] exactly.
        let end = [10.0, 1.0];
        let accepted = Some(Accepted { h: 10.0, end: &end });
        let run = |forget: bool| {
            let mut g = Growth::new(2);
            g.step(&free, (0.0, &x), 0.0, &[0.0, 1e-10]);
            g.step_kept(&free, (0.0, &x), 10.0, &[0.0, 0.0], None, accepted);
            if forget {
                g.forget_accepted();
            }
            g.step(&free, (10.0, &end), 10.0, &[0.0, 0.0]);
            (g.largest(), g.evaluations())
        };
        let ((against, spent), (anew, spent_anew)) = (run(false), run(true));
        assert_eq!((spent, spent_anew), (12, 24));
        // 1e-9 in position either way, to the difference's √eps.
        assert!((against - 1e-9).abs() < 1e-16 && (anew - 1e-9).abs() < 1e-16);
    }

    /// The run's states in free flight from `(0, 1)` whose first step
    /// (to t = 1) made a velocity error `delta`: the state at `t`.
    fn off_by(delta: f64, t: f64) -> [f64; 2] {
        [1.0 + (t - 1.0) * (1.0 + delta), 1.0 + delta]
    }

    #[test]
    fn a_reference_alongside_carries_a_step_s_error_and_the_errors_before() {
        let free = Oscillator(0.0);
        let delta = 1e-10;
        let mut g = Growth::new(2);
        g.step_alongside(&free, (0.0, &[0.0, 1.0]), (1.0, &off_by(delta, 1.0)), None);
        for k in 1..10 {
            let (t0, t1) = (k as f64, k as f64 + 1.0);
            g.step_alongside(
                &free,
                (t0, &off_by(delta, t0)),
                (t1, &off_by(delta, t1)),
                None,
            );
        }
        // At t = 9 (the last step pending): the velocity error, and 8 s
        // of it in position; against the reference (9, 1).
        assert!(
            (g.e[0] - 8e-10).abs() < 1e-14 && (g.e[1] - delta).abs() < 1e-15,
            "{:?}",
            g.e
        );
        assert_eq!(g.evaluations(), 240);
        // An event at t = 9.5 cuts the last step: the reference is stepped
        // to it only, against the state the run goes on from.
        g.cut(&free, 9.5, &off_by(delta, 9.5));
        assert!((g.e[0] - 8.5e-10).abs() < 1e-14, "{:?}", g.e);
        // (Relative to max(|x|, 1): the velocity's 1e-10 is the largest.)
        assert!((g.largest() - delta).abs() < 1e-15, "{}", g.largest());
        assert_eq!(g.evaluations(), 264);
    }

    #[test]
    fn at_the_end_the_pending_step_is_carried_without_a_new_evaluation() {
        let free = Oscillator(0.0);
        let delta = 1e-10;
        let mut g = Growth::new(2);
        g.step_alongside(&free, (0.0, &[0.0, 1.0]), (1.0, &off_by(delta, 1.0)), None);
        g.step_alongside(
            &free,
            (1.0, &off_by(delta, 1.0)),
            (3.0, &off_by(delta, 3.0)),
            None,
        );
        // The last step pending: the velocity error only, not yet its 2 s
        // in position.
        assert!((g.largest() - delta).abs() < 1e-15, "{}", g.largest());
        g.finish(&free);
        assert!((g.largest() - 2.0 * delta).abs() < 1e-14, "{}", g.largest());
        assert_eq!(g.evaluations(), 48);
        // Nothing is left pending: a second finish changes nothing.
        g.finish(&free);
        assert!((g.largest() - 2.0 * delta).abs() < 1e-14, "{}", g.largest());
    }

    /// The carried error, its steps in storage kept from step to step, is
    /// bit for bit the same arithmetic done in fresh storage (`e ← x1 −
    /// halves(x0 − e)`): on a spring, whose errors go round and change
    /// sign, over 40 steps.
    #[test]
    fn a_reference_alongside_in_reused_storage_is_the_same_arithmetic() {
        let spring = Oscillator(1.0);
        let mut g = Growth::new(2);
        let mut e = vec![0.0; 2];
        let (mut t, h) = (0.0, 0.4);
        // The run: the exact motion, a little off at each step's end.
        let run = |t: f64, k: usize| {
            let off = 1e-9 * if k.is_multiple_of(3) { -1.0 } else { 1.0 };
            [t.cos() + off, -t.sin() - off]
        };
        let mut x0 = [1.0, 0.0];
        for k in 0..40 {
            let x1 = run(t + h, k);
            g.step_alongside(&spring, (t, &x0), (t + h, &x1), None);
            // The step before the pending one is carried now.
            assert_eq!(g.e, e, "step {k}");
            let start: Vec<f64> = x0.iter().zip(&e).map(|(x, e)| x - e).collect();
            let mut r1 = vec![0.0; 2];
            // (The step's length as the run's times give it.)
            let step = (t + h) - t;
            assert_eq!(
                step_by_halves(&spring, t, &start, step, &mut r1).ok(),
                Some(true)
            );
            e = x1.iter().zip(&r1).map(|(x, r)| x - r).collect();
            (t, x0) = (t + h, x1);
        }
        g.cut(&spring, t, &x0);
        assert_eq!(g.e, e);
        assert!(g.largest() > 1e-9, "{}", g.largest());
    }

    #[test]
    fn a_reference_alongside_is_put_on_the_constraints_as_the_run_s_state_is() {
        let free = Oscillator(0.0);
        let delta = 1e-10;
        // The constraint: velocity 1 (the run's state put back on it at
        // t = 1, and the reference with it).
        let mut project = |_t: f64, x: &mut [f64]| -> Result<(), Failure> {
            x[1] = 1.0;
            Ok(())
        };
        let mut g = Growth::new(2);
        g.step_alongside(&free, (0.0, &[0.0, 1.0]), (1.0, &off_by(delta, 1.0)), None);
        let kept = [1.0, 1.0];
        g.step_alongside(&free, (1.0, &kept), (2.0, &[2.0, 1.0]), Some(&mut project));
        assert!(g.e[0].abs() < 1e-15 && g.e[1] == 0.0, "{:?}", g.e);
    }

    #[test]
    fn past_the_state_s_size_nothing_is_carried_and_the_largest_stays() {
        let free = Oscillator(0.0);
        let mut g = Growth::new(2);
        let x = [0.0, 1.0];
        // A velocity error of 0.1 over 20 s of free flight: 2 in position.
        g.step(&free, (0.0, &x), 0.0, &[0.0, 0.1]);
        g.step(&free, (0.0, &x), 20.0, &[0.0, 0.0]);
        assert!(!g.saturated());
        g.step(&free, (20.0, &x), 20.0, &[0.0, 0.0]);
        assert!(
            g.saturated() && (g.largest() - 2.0).abs() < 1e-6,
            "{}",
            g.largest()
        );
        let (largest, spent) = (g.largest(), g.evaluations());
        g.step(&free, (20.0, &x), 40.0, &[-5.0, 0.0]);
        g.step(&free, (40.0, &x), 60.0, &[0.0, 0.0]);
        g.cut(&free, 50.0, &x);
        assert_eq!((g.largest(), g.evaluations()), (largest, spent));
    }

    #[test]
    fn an_oscillation_keeps_the_error_s_size() {
        let spring = Oscillator(1.0);
        let mut g = Growth::new(2);
        let x = [0.0, 0.0];
        g.step(&spring, (0.0, &x), 0.0, &[1e-10, 0.0]);
        let mut t = 0.0;
        while t < 20.0 * std::f64::consts::PI {
            g.step(&spring, (t, &x), t + 0.3, &[0.0, 0.0]);
            t += 0.3;
        }
        g.cut(&spring, t, &[0.0, 0.0]);
        assert!((g.largest() - 1e-10).abs() < 1e-16, "{}", g.largest());
    }
}
