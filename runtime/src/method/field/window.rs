//! One window of the field method: from an anchor state `(t_r, x_r)` the
//! coefficients start at `f = c` (`c_1 = x_1r − Σ_A c_A x_Ar`, (12)) and
//! their sensitivities at `S = I`; the augmented system is integrated by
//! DOP853 and after every step the conditions (13) give the state.
//!
//! The step size is controlled by the error of the recovered state (the
//! error estimates of `(f, S)` mapped through the conditions), so the
//! tolerance means for the field what it means for direct integration. A
//! step whose conditions degrade past the options' limits is declined:
//! the window ends and the caller re-anchors.

use super::coefficients::FieldSystem;
use super::conditions::{recover, recover_into, recover_state_into, Recovered};
use super::FieldOptions;
use crate::ensemble::States;
use crate::failure::{Failure, FailureKind};
use crate::linalg::Matrix;
use crate::method::segment::Segment;
use crate::ode::budget::Budget;
use crate::ode::dop853::{hairer_error, Dop853, RawStep};
use crate::ode::magnus::{LinearGenerator, Magnus};
use crate::ode::stepper::{Clocked, DenseStep, ErrorMeasure, Family, StepOutcome, StepperOf};
use crate::ode::tolerance::{Stats, Tolerance};
use crate::ode::Integrator;

/// The free anchor values `c_2..c_N` used at every (re-)anchoring.
#[derive(Clone, Debug, Default, PartialEq)]
pub enum Anchor {
    /// `c_A = 0`: the field starts as `x_1 = x_1r`, the smallest
    /// coefficients there are, so a Riccati coefficient system starts as
    /// far from its poles as it can.
    #[default]
    Zero,
    /// Given values `c_2..c_N` (missing ones are 0).
    Given(Vec<f64>),
}

/// The anchor `c` at state `x`: `c_A` by the rule, `c_1` by (12).
pub fn anchor_values(anchor: &Anchor, x: &[f64]) -> Vec<f64> {
    let n = x.len();
    let mut c = vec![0.0; n];
    if let Anchor::Given(values) = anchor {
        for (c_a, value) in c.iter_mut().skip(1).zip(values) {
            *c_a = *value;
        }
    }
    c[0] = x[0] - (1..n).map(|a| c[a] * x[a]).sum::<f64>();
    c
}

/// How large the bound on the conditions' rounding may grow before a
/// window's step is declined (and the window ends): a hundredth of the
/// tolerance, but never less than a thousand roundings. At tolerances near
/// the precision (rtol 1e-12: a hundredth is 45 roundings) the bound was
/// past that after one or two steps of a rotating body's windows, each
/// decline a rejected step: a ball on a turntable in Euler angles took
/// 19768 steps + 26700 declined in 9482 windows, 1.7 s, against direct's
/// 3142 steps (helper-24's diagnosis, 2026-11-25). Loosened at every
/// tolerance (a whole tolerance) the stiff joint at rtol 1e-10 lost
/// accuracy (1.2e-9 -> 7.5e-9, its windows 1019 -> 13), so only the floor
/// moved.
const ROUNDING_FLOOR: f64 = 1000.0 * f64::EPSILON;

/// The relative rounding error of `x_1 = f_1 + Σ_A f_A x_A` over the
/// precision it needs: large when huge coefficients cancel (an anchor
/// like `c_A = 1e300` recovers `x_1` as the difference of huge numbers).
pub fn cancellation(f: &[f64], x: &[f64], tol: Tolerance) -> f64 {
    let magnitude: f64 = f[0].abs() + (1..f.len()).map(|a| (f[a] * x[a]).abs()).sum::<f64>();
    magnitude * f64::EPSILON / (tol.atol + tol.rtol * x[0].abs())
}

/// Scratch of the error measure, kept with the window (a step would
/// otherwise allocate six vectors).
struct Buffers {
    /// Output between steps: the coefficients there, and the state's
    /// recovery (storage reused from sample to sample).
    y: Vec<f64>,
    output: Recovered,
    dx3: Vec<f64>,
    dx5: Vec<f64>,
    f: Vec<f64>,
    s: Vec<f64>,
    df: Vec<f64>,
    ds: Vec<f64>,
    /// The free term's row's rounding of the conditions' right sides, its
    /// bound in the state, and one column of `M⁻¹` (the rounding watch).
    dr: Vec<f64>,
    dr_x: Vec<f64>,
    column: Vec<f64>,
}

impl Buffers {
    fn new(n: usize) -> Buffers {
        Buffers {
            y: Vec::new(),
            output: Recovered::empty(),
            dx3: vec![0.0; n],
            dx5: vec![0.0; n],
            f: vec![0.0; n],
            s: vec![0.0; n * n],
            df: vec![0.0; n],
            ds: vec![0.0; n * n],
            dr: vec![0.0; n],
            dr_x: vec![0.0; n],
            column: Vec::with_capacity(n),
        }
    }
}

/// The field's error measure: the state's error, from the coefficients'.
struct StateMeasure<'a, F: FieldSystem + ?Sized> {
    system: &'a F,
    tol: Tolerance,
    options: &'a FieldOptions,
    anchor_x: &'a [f64],
    /// The state at the start of the step being tried.
    start: &'a [f64],
    /// The recovered state at the last trial's end (storage reused from
    /// step to step), and whether it holds one.
    trial: &'a mut Recovered,
    trial_ok: bool,
    /// Why the last trial was declined.
    declined: Option<Decline>,
    /// The last trial's rounding bound over its limit (the watch's ratio;
    /// 0 when the trial's conditions could not be formed).
    watch: f64,
    b: &'a mut Buffers,
}

/// Why a window's step was declined.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Decline {
    /// The conditions are singular or their precision would be lost.
    Conditions,
    /// `x_1 = f_1 + Σ f_A x_A` would cancel (`digits` lost beyond the
    /// tolerance): huge coefficients, from the anchor.
    Cancellation { digits: f64, at_zero_anchor: bool },
}

impl<F: FieldSystem + ?Sized> ErrorMeasure for StateMeasure<'_, F> {
    fn measure(
        &mut self,
        _t0: f64,
        h: f64,
        _y0: &[f64],
        y1: &[f64],
        e3: &[f64],
        e5: &[f64],
    ) -> Option<f64> {
        let b = &mut *self.b;
        self.trial_ok = false;
        let Some(loss) = self.system.field(y1, &mut b.f, &mut b.s) else {
            self.declined = Some(Decline::Conditions);
            return None;
        };
        if !recover_into(&b.f, &b.s, self.anchor_x, self.trial) {
            self.declined = Some(Decline::Conditions);
            return None;
        }
        let rec = &*self.trial;
        // Rounding in S, amplified by the conditions, must stay well below
        // the tolerance (a bound: the product of the worst cases). The free
        // term's row apart, measured against the state's tolerance; the
        // larger of the two bounds, as the factor takes the larger of its
        // growth and its cancellation (the sum ended the stiff joint's
        // windows where neither alone reached the bound: at rtol 1e-10
        // 1,019 -> 1,221 windows, 1e-11 4,410 -> 6,584).
        let rounding = (loss * rec.formation * rec.condition * f64::EPSILON).max(
            free_term_rounding(self.system, y1, rec, self.start, self.tol, b),
        );
        let cancelled = cancellation(&b.f, &rec.state, self.tol);
        let limit = (0.01 * self.tol.rtol).max(ROUNDING_FLOOR);
        self.watch = rounding / limit;
        let within = rec.condition <= self.options.max_condition
            && rec.growth <= self.options.max_growth
            && rec.determinant > 0.0
            && rounding <= limit
            && cancelled <= 0.1;
        if !within && self.options.reanchor {
            self.declined = Some(if cancelled > 0.1 {
                Decline::Cancellation {
                    digits: (cancelled / 0.1).log10(),
                    at_zero_anchor: self.options.anchor == Anchor::Zero,
                }
            } else {
                Decline::Conditions
            });
            return None;
        }
        self.system.field_change(y1, e3, &mut b.df, &mut b.ds);
        rec.map_error(&b.f, self.anchor_x, &b.df, &b.ds, &mut b.dx3);
        self.system.field_change(y1, e5, &mut b.df, &mut b.ds);
        rec.map_error(&b.f, self.anchor_x, &b.df, &b.ds, &mut b.dx5);
        let err = hairer_error(self.tol, h, self.start, &rec.state, &b.dx3, &b.dx5);
        self.trial_ok = true;
        Some(err)
    }
}

/// The rounding of the free term's row of the field (where `field`'s
/// factor leaves it out, [`FieldSystem::free_term_rounding`]) as it
/// reaches the recovered state through the conditions, relative to the
/// state's tolerance and in units of `rtol` (comparable with the rest of
/// the watch's product, which is relative to 1): `max_i δx_i · rtol /
/// (atol + rtol |x_i|)`. That row enters `x` additively, through the right
/// sides `r_A`, in the units of `x_A`: what matters is its rounding
/// against the state, not its size against the anchor's unit vectors.
fn free_term_rounding<F: FieldSystem + ?Sized>(
    system: &F,
    y: &[f64],
    rec: &Recovered,
    start: &[f64],
    tol: Tolerance,
    b: &mut Buffers,
) -> f64 {
    if !system.free_term_rounding(y, &mut b.dr) {
        return 0.0;
    }
    rec.right_side_bound(&b.f, &b.dr, &mut b.dr_x, &mut b.column);
    let mut worst = 0.0_f64;
    for ((d, x), x0) in b.dr_x.iter().zip(&rec.state).zip(start) {
        // The step's error measure's scale (`hairer_error`'s).
        let scale = tol.atol + tol.rtol * x.abs().max(x0.abs());
        if *d > 0.0 {
            worst = worst.max(if scale > 0.0 {
                d * tol.rtol / scale
            } else {
                f64::INFINITY
            });
        }
    }
    worst
}

/// What [`Window::step`] did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WindowStep {
    Accepted,
    /// The conditions degraded: the window ends at its current time.
    Ended,
}

/// Which integrator a window uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StepperKind {
    Explicit,
    Stiff,
    Magnus,
}

/// The field systems a window steps, over the borrow each call makes:
/// its integrator is one object (`StepperOf<OfField>`) for all of them.
pub struct OfField;

impl Family for OfField {
    type System<'a> = dyn FieldSystem + 'a;
}

/// A field system's projective form as the Magnus integrator sees it.
impl LinearGenerator for dyn FieldSystem + '_ {
    fn order(&self) -> usize {
        self.coefficients() + 1
    }

    fn generator(&self, t: f64, b: &mut Matrix) -> Result<(), Failure> {
        FieldSystem::generator(self, t, b).unwrap_or(Err(Failure::new(t, FailureKind::NotAffine)))
    }
}

/// A window's step kept for later dense output: DOP853's continuous
/// extension is built only when asked for; RODAS4's costs nothing more.
#[derive(Clone, Debug)]
pub enum StoredStep {
    Raw(RawStep),
    Ready(DenseStep),
    /// A Magnus step: its start, from which a shorter Magnus step gives
    /// the coefficients anywhere inside it ([`crate::ode::magnus::propagate`]).
    Exponential {
        t_old: f64,
        t_new: f64,
        y_old: Vec<f64>,
    },
}

impl Default for StoredStep {
    fn default() -> StoredStep {
        StoredStep::Raw(RawStep::default())
    }
}

impl StoredStep {
    pub fn t_old(&self) -> f64 {
        match self {
            StoredStep::Raw(r) => r.t_old,
            StoredStep::Ready(d) => d.t_old,
            StoredStep::Exponential { t_old, .. } => *t_old,
        }
    }

    /// A step of DOP853 (explicit), whose size the motion's stability does
    /// not limit beyond an explicit method's.
    pub fn is_explicit(&self) -> bool {
        matches!(self, StoredStep::Raw(_))
    }

    pub fn t_new(&self) -> f64 {
        match self {
            StoredStep::Raw(r) => r.t_new,
            StoredStep::Ready(d) => d.t_new,
            StoredStep::Exponential { t_new, .. } => *t_new,
        }
    }

    /// The continuous extension (three evaluations of `system` for a raw
    /// DOP853 step; `system` must be the one the step was taken on);
    /// `None` for a Magnus step, which has none (see
    /// [`StoredStep::exponential_at`]).
    pub fn prepare<F: FieldSystem + ?Sized>(
        &self,
        system: &F,
    ) -> Result<Option<DenseStep>, Failure> {
        match self {
            StoredStep::Raw(r) => r.prepare(system).map(Some),
            StoredStep::Ready(d) => Ok(Some(d.clone())),
            StoredStep::Exponential { .. } => Ok(None),
        }
    }

    /// A Magnus step's coefficients at `t` inside it (a Magnus step from
    /// its start); `false` for the other kinds.
    pub fn exponential_at(
        &self,
        system: &dyn FieldSystem,
        t: f64,
        out: &mut [f64],
    ) -> Result<bool, Failure> {
        let StoredStep::Exponential { t_old, y_old, .. } = self else {
            return Ok(false);
        };
        crate::ode::magnus::propagate(system, *t_old, t - t_old, y_old, out)?;
        Ok(true)
    }
}

/// One anchored field.
pub struct Window {
    pub anchor_t: f64,
    pub anchor_x: Vec<f64>,
    /// The integrator of the coefficients (one dynamic call per step;
    /// the coefficient system is a `dyn FieldSystem` in any case, as the
    /// affine field's always was), and which one it is.
    stepper: StepperOf<OfField>,
    kind: StepperKind,
    /// The recovered state at the stepper's time, and its conditioning.
    current: Recovered,
    /// Storage for the next step's trial, swapped with `current` when it
    /// is accepted.
    spare: Recovered,
    previous_state: Vec<f64>,
    steps: usize,
    buffers: Buffers,
    declined: Option<Decline>,
    /// The rounding watch's ratio at the last accepted step's end.
    watched: f64,
    /// The last accepted step was the retry of a declined one.
    retried: bool,
}

impl Window {
    /// Anchors a field at `(t, x)`; `h0` is the first step to try.
    pub fn open(
        system: &dyn FieldSystem,
        options: &FieldOptions,
        t: f64,
        x: &[f64],
        h0: Option<f64>,
        h_max: f64,
        kind: StepperKind,
    ) -> Result<Window, Failure> {
        let n = x.len();
        let c = anchor_values(&options.anchor, x);
        let y = system.anchored(&c);
        let mut identity = vec![0.0; n * n];
        for i in 0..n {
            identity[i * n + i] = 1.0;
        }
        let current = recover(&c, &identity, x).ok_or_else(|| {
            Failure::new(
                t,
                FailureKind::SingularConditionMatrix {
                    condition: f64::INFINITY,
                },
            )
        })?;
        // The anchor's coefficients against the state's typical size (a
        // component that is 0 now will not stay 0): what the recovery of
        // x_1 will cancel once the motion moves.
        let typical = x.iter().fold(1.0_f64, |m, v| m.max(v.abs()));
        let moved: Vec<f64> = x.iter().map(|v| v.abs().max(typical)).collect();
        let lost = cancellation(&c, &moved, options.tol)
            * (options.tol.atol + options.tol.rtol * moved[0])
            / (options.tol.atol + options.tol.rtol * x[0].abs());
        if lost > 0.1 {
            return Err(Failure::new(
                t,
                FailureKind::AnchorCancels {
                    digits: (lost / 0.1).log10().max(0.0),
                    at_zero_anchor: options.anchor == Anchor::Zero,
                },
            ));
        }
        // Asked only for a Magnus window: it linearises (the same
        // linearisation the integrator's first evaluation then reuses) and
        // allocates, at every window.
        let magnus_possible =
            || FieldSystem::generator(system, t, &mut Matrix::zeros(n + 1, n + 1)).is_some();
        let (stepper, kind): (StepperOf<OfField>, _) = match kind {
            StepperKind::Stiff => (
                Integrator::Stiff.start::<OfField>(system, t, &y, options.tol, h_max, h0)?,
                StepperKind::Stiff,
            ),
            StepperKind::Magnus if magnus_possible() => {
                let h = match h0 {
                    Some(h) => h,
                    None => {
                        let mut slope = vec![0.0; y.len()];
                        system.rhs(t, &y, &mut slope)?;
                        crate::ode::tolerance::initial_step(
                            system,
                            t,
                            &y,
                            &slope,
                            options.tol,
                            4,
                            h_max,
                        )?
                    }
                };
                (
                    Box::new(Magnus::new(t, &y, h, options.tol)),
                    StepperKind::Magnus,
                )
            }
            _ => (
                Integrator::Explicit.start::<OfField>(system, t, &y, options.tol, h_max, h0)?,
                StepperKind::Explicit,
            ),
        };
        Ok(Window {
            anchor_t: t,
            anchor_x: x.to_vec(),
            stepper,
            kind,
            previous_state: x.to_vec(),
            current,
            spare: Recovered::empty(),
            steps: 0,
            buffers: Buffers::new(n),
            declined: None,
            watched: 0.0,
            retried: false,
        })
    }

    /// [`Window::open`] in this window's storage: afterwards the window is
    /// the one `open` would make from the same arguments (its DOP853
    /// restarted in its own buffers, `Dop853::restart_at`, the anchor's
    /// recovery in the spare `Recovered`), without a box, a stepper and a
    /// dozen vectors allocated and freed at every re-anchoring (a third
    /// of mass_gain_1000's field, whose windows hold one step or two).
    /// Only an explicit window continued explicitly; any other is opened
    /// anew. On failure the window is left at its end, as it was, but for
    /// its integrator's scratch (the run stops there).
    #[allow(clippy::too_many_arguments)]
    pub fn reopen(
        &mut self,
        system: &dyn FieldSystem,
        options: &FieldOptions,
        t: f64,
        x: &[f64],
        h0: Option<f64>,
        h_max: f64,
        kind: StepperKind,
    ) -> Result<(), Failure> {
        let n = x.len();
        let reusable = kind == StepperKind::Explicit
            && self.kind == StepperKind::Explicit
            && self.anchor_x.len() == n
            && self.stepper.as_any().is::<Dop853>();
        if !reusable {
            *self = Window::open(system, options, t, x, h0, h_max, kind)?;
            return Ok(());
        }
        // As `open`, step by step.
        let c = anchor_values(&options.anchor, x);
        let y = system.anchored(&c);
        let b = &mut self.buffers;
        b.s.fill(0.0);
        for i in 0..n {
            b.s[i * n + i] = 1.0;
        }
        if !recover_into(&c, &b.s, x, &mut self.spare) {
            return Err(Failure::new(
                t,
                FailureKind::SingularConditionMatrix {
                    condition: f64::INFINITY,
                },
            ));
        }
        let typical = x.iter().fold(1.0_f64, |m, v| m.max(v.abs()));
        b.f.clear();
        b.f.extend(x.iter().map(|v| v.abs().max(typical)));
        let moved = &b.f;
        let lost = cancellation(&c, moved, options.tol)
            * (options.tol.atol + options.tol.rtol * moved[0])
            / (options.tol.atol + options.tol.rtol * x[0].abs());
        if lost > 0.1 {
            return Err(Failure::new(
                t,
                FailureKind::AnchorCancels {
                    digits: (lost / 0.1).log10().max(0.0),
                    at_zero_anchor: options.anchor == Anchor::Zero,
                },
            ));
        }
        let dop853 = self
            .stepper
            .as_any_mut()
            .downcast_mut::<Dop853>()
            .expect("checked above");
        dop853.restart_at(system, t, &y, options.tol, h_max, h0)?;
        std::mem::swap(&mut self.current, &mut self.spare);
        self.anchor_t = t;
        self.anchor_x.copy_from_slice(x);
        self.previous_state.copy_from_slice(x);
        self.steps = 0;
        self.declined = None;
        self.watched = 0.0;
        self.retried = false;
        Ok(())
    }

    pub fn time(&self) -> f64 {
        self.stepper.time()
    }

    pub fn previous_time(&self) -> f64 {
        self.stepper.previous_time()
    }

    /// Whether DOP853 found the coefficient system stiff.
    pub fn stiffness_detected(&self) -> bool {
        self.stepper.stiffness_detected().is_some()
    }

    /// The integrator this window uses.
    pub fn kind(&self) -> StepperKind {
        self.kind
    }

    pub fn state(&self) -> &[f64] {
        &self.current.state
    }

    /// The state at the last step's start.
    pub fn previous_state(&self) -> &[f64] {
        &self.previous_state
    }

    /// The last accepted step's local error in the state, into `out`: the
    /// coefficients' error estimates mapped through the conditions, as
    /// DOP853's `local_error` makes the vector whose scaled norm the step
    /// was accepted with (Hairer's share of the 5th-order estimate). Only
    /// an explicit window's estimates are of that kind: `false` for the
    /// others.
    pub fn local_error(&self, tol: Tolerance, out: &mut [f64]) -> bool {
        if self.kind != StepperKind::Explicit || self.steps == 0 {
            return false;
        }
        let b = &self.buffers;
        let (x0, x1) = (&self.previous_state, &self.current.state);
        let (mut err3, mut err5) = (0.0, 0.0);
        for i in 0..x1.len() {
            let inverse = 1.0 / (tol.atol + tol.rtol * x0[i].abs().max(x1[i].abs()));
            err3 += (b.dx3[i] * inverse).powi(2);
            err5 += (b.dx5[i] * inverse).powi(2);
        }
        let denominator = err5 + 0.01 * err3;
        let share = if denominator > 0.0 {
            (err5 / denominator).sqrt()
        } else {
            0.0
        };
        let h = (self.time() - self.previous_time()).abs();
        for (o, d) in out.iter_mut().zip(&b.dx5) {
            *o = h * share * d;
        }
        out.iter().all(|v| v.is_finite())
    }

    pub fn recovered(&self) -> &Recovered {
        &self.current
    }

    /// The failure to report when even the shortest first step is declined.
    pub fn degraded(&self) -> Failure {
        let t = self.time();
        match self.declined {
            Some(Decline::Cancellation {
                digits,
                at_zero_anchor,
            }) => Failure::new(
                t,
                FailureKind::AnchorCancels {
                    digits,
                    at_zero_anchor,
                },
            ),
            _ => Failure::new(
                t,
                FailureKind::SingularConditionMatrix {
                    condition: self.current.condition,
                },
            ),
        }
    }

    /// Accepted steps since the anchor.
    pub fn steps(&self) -> usize {
        self.steps
    }

    pub fn proposed_step(&self) -> f64 {
        self.stepper.proposed_step()
    }

    pub fn propose_step(&mut self, h: f64) {
        self.stepper.propose_step(h)
    }

    pub fn stats(&self) -> Stats {
        self.stepper.stats()
    }

    /// One step of the field; [`WindowStep::Ended`] when the conditions
    /// would degrade past the limits (then nothing changed).
    pub fn step(
        &mut self,
        system: &dyn FieldSystem,
        options: &FieldOptions,
        t_limit: f64,
        budget: &Budget,
    ) -> Result<WindowStep, Failure> {
        // The last step was a declined step's retry, fitted to just under
        // the rounding watch's limit: the next one would pass it as the
        // window's sensitivities go on growing, and its decline would
        // cost a whole attempt. End the window here instead (its next one
        // starts from a quarter of the proposed step, as after a decline).
        if std::mem::take(&mut self.retried) && options.reanchor && self.watched > 0.5 {
            self.declined = Some(Decline::Conditions);
            let h = 0.25 * self.stepper.proposed_step();
            self.stepper.propose_step(h);
            return Ok(WindowStep::Ended);
        }
        let mut measure = StateMeasure {
            system,
            tol: options.tol,
            options,
            anchor_x: &self.anchor_x,
            start: &self.current.state,
            trial: &mut self.spare,
            trial_ok: false,
            declined: None,
            watch: 0.0,
            b: &mut self.buffers,
        };
        let mut outcome = self
            .stepper
            .step_measured(system, t_limit, budget, &mut measure)?;
        // A step the conditions decline may fit shorter (the sensitivities'
        // growth rises with the step): try it once more before ending the
        // window, whose fresh start costs more. In a quasilinear window
        // (`FieldSystem::fits_retry`) declined by the rounding watch, whose
        // ratio rises smoothly along a window, the retry is the fraction of
        // the step where that ratio, interpolated between the last step's
        // end and the declined trial's, reaches 0.9 of the limit — no
        // retry where that is under a fifth of the step; any other decline
        // retries a quarter. (A quarter, blindly, was
        // accepted and then declined again, or declined itself: on the
        // stiff joint at rtol 1e-10, 4,160 of 12,382 attempts were the
        // watch's declines, 3.8 a window, and 22 the error's; h-stiff3,
        // docs/BENCHMARKS.md §0.)
        if outcome == StepOutcome::Declined && self.steps > 0 {
            let h = self.stepper.proposed_step();
            let (before, trial) = (self.watched, measure.watch);
            let fits = system.fits_retry();
            let fraction = if fits && trial.is_finite() && trial > 1.0 && before < 1.0 {
                0.9 * (1.0 - before) / (trial - before)
            } else {
                0.25
            };
            if fraction < 0.2 {
                self.stepper.propose_step(0.25 * h);
            } else {
                self.stepper.propose_step(fraction * h);
                outcome = self
                    .stepper
                    .step_measured(system, t_limit, budget, &mut measure)?;
                if fits && outcome == StepOutcome::Declined {
                    // The next window starts from a quarter, as before.
                    self.stepper.propose_step(0.25 * h);
                }
                self.retried = fits;
            }
        }
        self.declined = measure.declined;
        let trial_ok = measure.trial_ok;
        let watch = measure.watch;
        match outcome {
            StepOutcome::Declined => Ok(WindowStep::Ended),
            StepOutcome::Accepted => {
                if !trial_ok {
                    return Ok(WindowStep::Ended);
                }
                if !options.reanchor {
                    check_without_reanchoring(
                        &self.spare,
                        options,
                        self.previous_time(),
                        self.time(),
                    )?;
                }
                self.previous_state.copy_from_slice(&self.current.state);
                std::mem::swap(&mut self.current, &mut self.spare);
                self.steps += 1;
                self.watched = watch;
                Ok(WindowStep::Accepted)
            }
        }
    }

    /// The state at `t` within the last step (the coefficients' continuous
    /// extension, then the conditions at `t`).
    pub fn dense(
        &mut self,
        system: &dyn FieldSystem,
        t: f64,
        out: &mut [f64],
    ) -> Result<(), Failure> {
        if t >= self.time() {
            out.copy_from_slice(&self.current.state);
            return Ok(());
        }
        if t <= self.previous_time() || self.steps == 0 {
            out.copy_from_slice(&self.previous_state);
            return Ok(());
        }
        let b = &mut self.buffers;
        b.y.resize(system.dim(), 0.0);
        self.stepper.dense(system, t, &mut b.y)?;
        let singular = || {
            Failure::new(
                t,
                FailureKind::SingularConditionMatrix {
                    condition: f64::INFINITY,
                },
            )
        };
        if system.field(&b.y, &mut b.f, &mut b.s).is_none() {
            return Err(singular());
        }
        if !recover_state_into(&b.f, &b.s, &self.anchor_x, &mut b.output) {
            return Err(singular());
        }
        out.copy_from_slice(&b.output.state);
        Ok(())
    }

    /// The states of other initial states through this field at the
    /// window's current time: `anchors[m]` is member `m`'s state at the
    /// window's anchor time.
    pub fn members(
        &mut self,
        system: &dyn FieldSystem,
        options: &FieldOptions,
        anchors: &States,
        out: &mut States,
    ) -> Result<(), Failure> {
        let t = self.time();
        self.members_at(system, options, t, anchors, out)
    }

    /// [`Window::members`] at a time `t` within the last step.
    pub fn members_at(
        &mut self,
        system: &dyn FieldSystem,
        options: &FieldOptions,
        t: f64,
        anchors: &States,
        out: &mut States,
    ) -> Result<(), Failure> {
        let (y, reference, t) = if t >= self.time() || self.steps == 0 {
            let y = self.stepper.state().to_vec();
            (y, self.current.clone(), self.time())
        } else {
            let mut y = vec![0.0; system.dim()];
            self.stepper.dense(system, t, &mut y)?;
            let b = &mut self.buffers;
            let reference = system
                .field(&y, &mut b.f, &mut b.s)
                .and_then(|_| recover(&b.f, &b.s, &self.anchor_x))
                .ok_or_else(|| {
                    Failure::new(
                        t,
                        FailureKind::SingularConditionMatrix {
                            condition: f64::INFINITY,
                        },
                    )
                })?;
            (y, reference, t)
        };
        let shared = SharedField {
            system,
            options,
            anchor_x: &self.anchor_x,
            reference: &reference,
            y: &y,
            t,
        };
        member_states(&shared, anchors, out)
    }

    /// The last step's continuous extension as a value.
    pub fn segment(&mut self, system: &dyn FieldSystem) -> Result<Segment, Failure> {
        let anchor = self.anchor_x.clone();
        let y = match self.stepper.dense_step(system)? {
            Some(y) => y,
            None => {
                // No continuous extension of its own (Magnus): the state
                // at the step's Chebyshev points.
                let (a, b) = (self.previous_time(), self.time());
                let n = anchor.len();
                let mut t = Vec::with_capacity(8);
                let mut x = Vec::with_capacity(8);
                for k in 0..8 {
                    let c = 0.5 - 0.5 * (std::f64::consts::PI * k as f64 / 7.0).cos();
                    let tk = a + c * (b - a);
                    let mut state = vec![0.0; n];
                    self.dense(system, tk, &mut state)?;
                    t.push(tk);
                    x.push(state);
                }
                return Ok(Segment::Points { t, x });
            }
        };
        Ok(if system.is_projective() {
            Segment::Projective { y, anchor }
        } else {
            Segment::Coefficients { y, anchor }
        })
    }

    /// The last step, kept for dense output later, into `dst` (its
    /// storage reused).
    pub fn store_step(
        &mut self,
        system: &dyn FieldSystem,
        dst: &mut StoredStep,
    ) -> Result<(), Failure> {
        // DOP853's stages, its extension built only for the steps output
        // asks for; a Magnus step's start (it has no extension of its
        // own); another integrator's extension now.
        if let Some(s) = self.stepper.as_any().downcast_ref::<Dop853>() {
            if !matches!(dst, StoredStep::Raw(_)) {
                *dst = StoredStep::Raw(RawStep::default());
            }
            if let StoredStep::Raw(raw) = dst {
                s.raw_step_into(raw);
            }
        } else if let Some(s) = self.stepper.as_any().downcast_ref::<Magnus>() {
            // A Magnus step: its start, from which a shorter Magnus step
            // gives the output within it.
            let mut y_old = match std::mem::take(dst) {
                StoredStep::Exponential { y_old, .. } => y_old,
                _ => Vec::new(),
            };
            y_old.clear();
            y_old.extend_from_slice(s.previous_state());
            *dst = StoredStep::Exponential {
                t_old: s.previous_time(),
                t_new: s.time(),
                y_old,
            };
        } else if let Some(dense) = self.stepper.dense_step(system)? {
            *dst = StoredStep::Ready(dense);
        }
        Ok(())
    }
}

/// With re-anchoring off (`--no-reanchor`), degraded conditions are a
/// failure rather than a reason to re-anchor.
fn check_without_reanchoring(
    rec: &Recovered,
    options: &FieldOptions,
    since: f64,
    t: f64,
) -> Result<(), Failure> {
    if rec.determinant <= 0.0 {
        return Err(Failure::new(
            t,
            FailureKind::ConditionMatrixCrossedSingularity { since },
        ));
    }
    if rec.condition > options.max_condition {
        return Err(Failure::new(
            t,
            FailureKind::SingularConditionMatrix {
                condition: rec.condition,
            },
        ));
    }
    Ok(())
}

/// What every ensemble member's state is computed from: the field `y` of
/// the reference anchored at `anchor_x`, recovered as `reference`, at `t`.
pub struct SharedField<'a, F: FieldSystem + ?Sized> {
    pub system: &'a F,
    pub options: &'a FieldOptions,
    pub anchor_x: &'a [f64],
    pub reference: &'a Recovered,
    pub y: &'a [f64],
    pub t: f64,
}

/// Every member's state through the shared field, into `out`.
pub fn member_states<F: FieldSystem + ?Sized>(
    shared: &SharedField<'_, F>,
    anchors: &States,
    out: &mut States,
) -> Result<(), Failure> {
    let n = shared.anchor_x.len();
    // The field's system is affine (the model's, or the window's
    // linearisation), so a member's state is an affine function of its
    // initial state: x(t) = x_b(t) + Φ(t) (x0 − x_b0). With more members
    // than N + 1, N + 1 conditioned solutions give x_b and Φ, and every
    // member then costs N² multiply-adds instead of a field and a solve.
    if anchors.len() <= n + 1 {
        return member_states_each(shared, anchors, out);
    }
    let base = anchors.row(0);
    let (mut x_b, mut phi) = (Vec::new(), Vec::new());
    propagator(shared, base, &mut x_b, &mut phi)?;
    out.n = n;
    out.data.clear();
    out.data.reserve(anchors.data.len());
    affine_map(&x_b, &phi, base, &anchors.data, &mut out.data);
    Ok(())
}

/// The affine map of the shared field from the anchor time to its time,
/// `x(t) = x_b(t) + Φ(t) (x0 − base)`: `x_b` the state of `base`,
/// `phi[i·n + j] = ∂x_j(t)/∂x0_i`, from `N + 1` conditioned solutions (the
/// map is affine, so the differences are exact but for rounding).
pub fn propagator<F: FieldSystem + ?Sized>(
    shared: &SharedField<'_, F>,
    base: &[f64],
    x_b: &mut Vec<f64>,
    phi: &mut Vec<f64>,
) -> Result<(), Failure> {
    let n = base.len();
    let mut probes = States {
        n,
        data: Vec::with_capacity((n + 1) * n),
    };
    probes.data.extend_from_slice(base);
    let mut deltas = Vec::with_capacity(n);
    for i in 0..n {
        let delta = base[i].abs().max(1.0);
        let start = probes.data.len();
        probes.data.extend_from_slice(base);
        probes.data[start + i] += delta;
        deltas.push(delta);
    }
    let mut solved = States::default();
    member_states_each(shared, &probes, &mut solved)?;
    x_b.clear();
    x_b.extend_from_slice(solved.row(0));
    phi.clear();
    phi.resize(n * n, 0.0);
    for i in 0..n {
        for j in 0..n {
            phi[i * n + j] = (solved.row(i + 1)[j] - x_b[j]) / deltas[i];
        }
    }
    Ok(())
}

/// `x = x_b + Φᵀ (x0 − base)` for every row `x0` of `from`, appended to
/// `to` (appended, not written over zeros: the fill would cost as much as
/// the map); `phi[i·n + j] = ∂x_j/∂x0_i`. Small state dimensions get a
/// loop of fixed length, which the compiler unrolls and vectorises: this is
/// all an ensemble member costs.
fn affine_map(x_b: &[f64], phi: &[f64], base: &[f64], from: &[f64], to: &mut Vec<f64>) {
    fn fixed<const N: usize>(
        x_b: &[f64],
        phi: &[f64],
        base: &[f64],
        from: &[f64],
        to: &mut Vec<f64>,
    ) {
        let mut rows = [[0.0; N]; N];
        for (i, row) in rows.iter_mut().enumerate() {
            row.copy_from_slice(&phi[i * N..(i + 1) * N]);
        }
        // x = (x_b − Φᵀ base) + Φᵀ x0: N² multiply-adds a member.
        let mut offset: [f64; N] = x_b.try_into().expect("N components");
        for i in 0..N {
            for j in 0..N {
                offset[j] -= rows[i][j] * base[i];
            }
        }
        for x0 in from.chunks_exact(N) {
            let mut v = offset;
            for i in 0..N {
                for j in 0..N {
                    v[j] += rows[i][j] * x0[i];
                }
            }
            to.extend_from_slice(&v);
        }
    }
    let n = x_b.len();
    match n {
        1 => fixed::<1>(x_b, phi, base, from, to),
        2 => fixed::<2>(x_b, phi, base, from, to),
        3 => fixed::<3>(x_b, phi, base, from, to),
        4 => fixed::<4>(x_b, phi, base, from, to),
        5 => fixed::<5>(x_b, phi, base, from, to),
        6 => fixed::<6>(x_b, phi, base, from, to),
        8 => fixed::<8>(x_b, phi, base, from, to),
        _ => {
            for x0 in from.chunks_exact(n) {
                let at = to.len();
                to.extend_from_slice(x_b);
                let x = &mut to[at..];
                for i in 0..n {
                    let d = x0[i] - base[i];
                    for (xj, p) in x.iter_mut().zip(&phi[i * n..(i + 1) * n]) {
                        *xj += p * d;
                    }
                }
            }
        }
    }
}

/// [`member_states`] by one conditioned solution per member.
fn member_states_each<F: FieldSystem + ?Sized>(
    shared: &SharedField<'_, F>,
    anchors: &States,
    out: &mut States,
) -> Result<(), Failure> {
    let SharedField {
        system,
        options,
        anchor_x,
        reference,
        y,
        t,
    } = *shared;
    let n = anchor_x.len();
    let c_ref = anchor_values(&options.anchor, anchor_x)[0];
    let (mut f, mut s) = (vec![0.0; n], vec![0.0; n * n]);
    let mut shifted = y.to_vec();
    out.n = n;
    out.data.clear();
    for x0 in anchors.rows() {
        shifted.copy_from_slice(y);
        system.shift_free_term(&mut shifted, anchor_values(&options.anchor, x0)[0] - c_ref);
        system.field(&shifted, &mut f, &mut s).ok_or_else(|| {
            Failure::new(
                t,
                FailureKind::SingularConditionMatrix {
                    condition: f64::INFINITY,
                },
            )
        })?;
        out.data.extend(reference.member(&f, &s, x0));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::affine_map;

    /// The unrolled maps of small dimensions and the general loop compute
    /// the same `x_b + Φᵀ (x0 − base)`, checked against a plain evaluation.
    #[test]
    fn affine_map_is_the_same_map_for_every_dimension() {
        for n in 1..=9 {
            let x_b: Vec<f64> = (0..n).map(|j| 0.5 + j as f64).collect();
            let base: Vec<f64> = (0..n).map(|i| 1.0 - 0.25 * i as f64).collect();
            let phi: Vec<f64> = (0..n * n)
                .map(|k| ((k * 7 % 11) as f64 - 5.0) / 3.0)
                .collect();
            let from: Vec<f64> = (0..3 * n).map(|k| (k as f64 * 0.37).sin()).collect();
            let mut to = Vec::new();
            affine_map(&x_b, &phi, &base, &from, &mut to);
            assert_eq!(to.len(), from.len());
            for (x0, x) in from.chunks(n).zip(to.chunks(n)) {
                for j in 0..n {
                    let expected = x_b[j]
                        + (0..n)
                            .map(|i| phi[i * n + j] * (x0[i] - base[i]))
                            .sum::<f64>();
                    assert!((x[j] - expected).abs() < 1e-13, "n = {n}, component {j}");
                }
            }
        }
    }
}
