//! The field method (SPEC §1.5, "Numeric conditioned solution").
//!
//! From an anchor state `(t_r, x_r)` the coefficients start at `f = c` with
//! `c_1 = x_1r − Σ_A c_A x_Ar` (12), their sensitivities at `S = I`, and the
//! augmented system is integrated; after every accepted step the conditions
//! (13) give the state. When their condition number or the growth of `S`
//! passes a threshold, or the coefficient integration fails (a Riccati
//! coefficient system blows up in finite time: the oscillator has
//! `f_2 = tan(ωt + C)/ω`), the step is discarded and the field restarts from
//! the last good state with a fresh anchor. The motion does not depend on
//! the anchor; only the conditioning does.

use super::conditioned::{solve_conditions, Conditioned};
use super::error::{Failure, FailureKind};
use super::magnus::Magnus;
use super::method::{AnyStepper, Integrator, IntegratorChoice};
use super::sensitivity::Sensitized;
use super::stepper::{initial_step, underflows, Stats, Stepper, Tolerance};
use super::system::{CoefficientSystem, Motion};

/// The free anchor values `c_2..c_N` used at every (re-)anchoring.
#[derive(Clone, Debug, PartialEq)]
pub enum Anchor {
    /// `c_A = 0`: the field starts as `x_1 = x_1r` (all coefficients of
    /// `x_A` zero), the smallest coefficients there are, so a Riccati
    /// coefficient system starts as far from its poles as it can in both
    /// directions (`tan` at 0 for the oscillator).
    Zero,
    /// Given values `c_2..c_N` (missing ones are 0).
    Given(Vec<f64>),
}

#[derive(Clone, Debug, PartialEq)]
pub struct FieldOptions {
    pub tol: Tolerance,
    /// `Stiff` is honoured only for linear coefficient systems, where the
    /// augmented system's Jacobian is exact; otherwise DOP853 is used.
    /// Ignored for linear coefficient systems when `magnus` is set.
    pub integrator: Integrator,
    pub anchor: Anchor,
    /// Re-anchor when the condition number of the conditions passes this:
    /// the recovered state loses about `condition · rtol` of accuracy.
    pub max_condition: f64,
    /// Re-anchor when `max |S_ij|` passes this (the field nears a blow-up,
    /// or the adjoint of a stiff mode grows like `e^{+|λ|t}`). The default
    /// 1e2 was the cheapest of 1e1..1e4 on the oscillator (SPEC's Riccati
    /// case); the error stays at the integrator's level for all of them.
    pub max_growth: f64,
    /// Without re-anchoring, a condition number above `max_condition` is a
    /// [`FailureKind::SingularConditionMatrix`] failure.
    pub reanchor: bool,
    /// Integrate LINEAR coefficient systems by the Magnus integrator
    /// ([`super::magnus`]) instead of `integrator`. Off by default, by
    /// measurement (`measure_field_integrators_on_stiff_and_paper_cases`,
    /// release, rtol 1e-10): Magnus needs 4–30× fewer right-side
    /// evaluations than DOP853 on the stiff pairs (k = 1e3, 1e6) at the
    /// same error, but each step costs three matrix exponentials, and in
    /// wall time it was 6.5× slower on the paper example and 1–2× slower on
    /// the stiff pairs at the default growth budget (faster only with
    /// `max_growth` ≥ 1e8). Worth it when the right side is expensive.
    pub magnus: bool,
}

impl Default for FieldOptions {
    fn default() -> Self {
        FieldOptions {
            tol: Tolerance::default(),
            integrator: Integrator::Explicit,
            anchor: Anchor::Zero,
            max_condition: 1e4,
            max_growth: 1e2,
            reanchor: true,
            magnus: false,
        }
    }
}

impl FieldOptions {
    /// The options for a user's choice of integrator: `Auto` and
    /// `Explicit` are DOP853 (the default, see `magnus`), `Stiff` is
    /// RODAS4 and `Magnus` the Magnus integrator, both for linear
    /// coefficient systems only (DOP853 otherwise).
    pub fn for_choice(choice: IntegratorChoice, tol: Tolerance, anchor: Anchor) -> Self {
        let (integrator, magnus) = match choice {
            IntegratorChoice::Auto | IntegratorChoice::Explicit => (Integrator::Explicit, false),
            IntegratorChoice::Stiff => (Integrator::Stiff, false),
            IntegratorChoice::Magnus => (Integrator::Explicit, true),
        };
        FieldOptions {
            tol,
            integrator,
            anchor,
            magnus,
            ..FieldOptions::default()
        }
    }

    /// The name of the integrator these options use on `coefficients`.
    pub fn integrator_name<C: CoefficientSystem + ?Sized>(&self, coefficients: &C) -> &'static str {
        match (coefficients.is_linear(), self.magnus, self.integrator) {
            (true, true, _) => MAGNUS_NAME,
            (true, false, integrator) => integrator.name(),
            (false, _, _) => Integrator::Explicit.name(),
        }
    }
}

const MAGNUS_NAME: &str = "Magnus-4";

/// What the field method did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FieldReport {
    /// Work of the augmented coefficient system, summed over all windows
    /// (one right-side evaluation = one `F` and one `∂F/∂f`).
    pub stats: Stats,
    pub largest_condition: f64,
    pub reanchorings: usize,
    /// The integrator of the coefficient system (`Magnus-4`, `DOP853` or
    /// `RODAS4`), for the run summary.
    pub integrator: &'static str,
    /// Re-anchorings because the condition matrix's determinant changed
    /// sign (it passed through singularity between two steps).
    pub singular_crossings: usize,
}

/// How many times the first step after an anchor is shortened (by 4 each
/// time) before the conditions are declared singular.
const MAX_SHORTENINGS: usize = 40;

/// The coefficient integrator of one window.
enum WindowStepper {
    General(AnyStepper),
    Magnus(Magnus),
}

impl WindowStepper {
    fn time(&self) -> f64 {
        match self {
            WindowStepper::General(s) => s.time(),
            WindowStepper::Magnus(s) => s.time(),
        }
    }

    fn state(&self) -> &[f64] {
        match self {
            WindowStepper::General(s) => s.state(),
            WindowStepper::Magnus(s) => s.state(),
        }
    }

    fn stats(&self) -> Stats {
        match self {
            WindowStepper::General(s) => s.stats(),
            WindowStepper::Magnus(s) => s.stats(),
        }
    }

    fn proposed_step(&self) -> f64 {
        match self {
            WindowStepper::General(s) => s.proposed_step(),
            WindowStepper::Magnus(s) => s.proposed_step(),
        }
    }

    fn propose_step(&mut self, h: f64) {
        match self {
            WindowStepper::General(s) => s.propose_step(h),
            WindowStepper::Magnus(s) => s.propose_step(h),
        }
    }

    fn step<C: CoefficientSystem + ?Sized>(
        &mut self,
        system: &Sensitized<'_, C>,
        t_limit: f64,
    ) -> Result<(), Failure> {
        match self {
            WindowStepper::General(s) => s.step(system, t_limit),
            WindowStepper::Magnus(s) => s.step(system.coefficients, t_limit),
        }
    }
}

/// Integrates by the field method from `(times[0], x0)`, calling
/// `on_sample` at every sample time.
pub fn solve_field<C: CoefficientSystem + ?Sized>(
    coefficients: &C,
    options: &FieldOptions,
    times: &[f64],
    x0: &[f64],
    mut on_sample: impl FnMut(f64, &[f64]),
) -> Result<FieldReport, Failure> {
    let mut report = FieldReport {
        largest_condition: 1.0,
        integrator: options.integrator_name(coefficients),
        ..FieldReport::default()
    };
    let Some((&t0, rest)) = times.split_first() else {
        return Ok(report);
    };
    let system = Sensitized::new(coefficients);
    let n = coefficients.dim();
    let linear = coefficients.is_linear();
    let use_magnus = linear && options.magnus;
    let integrator = if linear {
        options.integrator
    } else {
        Integrator::Explicit
    };
    let span = times.last().map_or(0.0, |t1| (t1 - t0).abs());
    let h_max = if span > 0.0 { span } else { 1.0 };
    // Half the growth budget per step: a window then takes at least two
    // steps, and a step rarely overshoots the re-anchoring threshold.
    let growth_per_step = options.max_growth.sqrt().max(2.0);
    let start = |t: f64, x: &[f64], h: Option<f64>| -> Result<WindowStepper, Failure> {
        let c = anchor_values(&options.anchor, x);
        let y = Sensitized::<C>::anchored_state(&c);
        if use_magnus {
            let h0 = match h {
                Some(h) => h,
                None => {
                    // Hairer's guess for order 4, as RODAS4 would make it.
                    let mut slope = vec![0.0; y.len()];
                    system.rhs(t, &y, &mut slope)?;
                    initial_step(&system, t, &y, &slope, options.tol, 4, h_max)?
                }
            };
            let magnus = Magnus::new(t, &y, options.tol, h0, growth_per_step);
            return Ok(WindowStepper::Magnus(magnus));
        }
        let mut stepper = AnyStepper::new(integrator, &system, t, &y, options.tol, h_max)?;
        if let Some(h) = h {
            stepper.propose_step(h);
        }
        Ok(WindowStepper::General(stepper))
    };

    let (mut anchor_t, mut anchor_x) = (t0, x0.to_vec());
    let (mut good_t, mut good_x) = (t0, x0.to_vec());
    let mut stepper = start(t0, x0, None)?;
    let mut step_cap: Option<f64> = None;
    let mut shortenings = 0;
    on_sample(t0, x0);
    for &target in rest {
        while good_t < target {
            let limit = step_cap.map_or(target, |cap| (good_t + cap).min(target));
            let outcome = stepper.step(&system, limit).and_then(|()| {
                let y = stepper.state();
                let s = Sensitized::<C>::sensitivities(y, n);
                solve_conditions(stepper.time(), &y[..n], s, &anchor_x)
            });
            // `det M = 1` at the anchor and is continuous: a non-positive
            // value means it passed through zero since.
            let within = |c: &Conditioned| {
                c.condition <= options.max_condition
                    && c.growth <= options.max_growth
                    && c.determinant > 0.0
            };
            match outcome {
                Ok(c) if within(&c) || !options.reanchor => {
                    if !options.reanchor && c.determinant <= 0.0 {
                        return Err(Failure::new(
                            stepper.time(),
                            FailureKind::ConditionMatrixCrossedSingularity { since: good_t },
                        ));
                    }
                    if !options.reanchor && c.condition > options.max_condition {
                        let condition = c.condition;
                        return Err(Failure::new(
                            stepper.time(),
                            FailureKind::SingularConditionMatrix { condition },
                        ));
                    }
                    report.largest_condition = report.largest_condition.max(c.condition);
                    good_t = stepper.time();
                    good_x = c.state;
                    step_cap = None;
                    shortenings = 0;
                }
                Err(failure) if !options.reanchor => return Err(failure),
                Err(failure) if good_t == anchor_t => return Err(failure),
                outcome => {
                    let crossed = matches!(&outcome, Ok(c) if c.determinant <= 0.0);
                    if good_t == anchor_t {
                        // Already bad one step after a fresh anchor:
                        // shorten that step instead.
                        shortenings += 1;
                        let condition = match outcome {
                            Ok(c) => c.condition,
                            Err(_) => f64::INFINITY,
                        };
                        let cap = 0.25 * (stepper.time() - anchor_t);
                        // A cap that cannot move the time any more: the
                        // conditions are singular right here (e.g. the
                        // state blows up where the matrix passes zero).
                        if shortenings > MAX_SHORTENINGS || underflows(good_t, cap) {
                            let kind = if crossed {
                                FailureKind::ConditionMatrixCrossedSingularity { since: good_t }
                            } else {
                                FailureKind::SingularConditionMatrix { condition }
                            };
                            return Err(Failure::new(good_t, kind));
                        }
                        step_cap = Some(cap);
                    } else {
                        report.reanchorings += 1;
                        report.singular_crossings += usize::from(crossed);
                    }
                    report.stats += stepper.stats();
                    let proposed = stepper.proposed_step();
                    anchor_t = good_t;
                    anchor_x.clone_from(&good_x);
                    stepper = start(anchor_t, &anchor_x, Some(proposed))?;
                }
            }
        }
        on_sample(target, &good_x);
    }
    report.stats += stepper.stats();
    Ok(report)
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
