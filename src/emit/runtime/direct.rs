//! Direct integration of the reduced system (7), reporting the state at
//! each sample time (the integrator stops exactly on each).

use super::error::Failure;
use super::method::{AnyStepper, Integrator, IntegratorChoice};
use super::stepper::{within_step_budget, Stats, Stepper, Tolerance};
use super::system::Motion;

/// Integrates `motion` from `(times[0], x0)` and calls `on_sample` at every
/// sample time (the first one with `x0` itself).
pub fn solve_direct<M: Motion + ?Sized>(
    motion: &M,
    integrator: Integrator,
    tol: Tolerance,
    times: &[f64],
    x0: &[f64],
    mut on_sample: impl FnMut(f64, &[f64]),
) -> Result<Stats, Failure> {
    let Some((&t0, rest)) = times.split_first() else {
        return Ok(Stats::default());
    };
    let span = times.last().map_or(0.0, |t1| (t1 - t0).abs());
    let h_max = if span > 0.0 { span } else { 1.0 };
    let mut stepper = AnyStepper::new(integrator, motion, t0, x0, tol, h_max)?;
    on_sample(t0, x0);
    for &t in rest {
        stepper.advance_to(motion, t)?;
        on_sample(t, stepper.state());
    }
    Ok(stepper.stats())
}

/// What the direct method did, and which integrator it ended with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DirectReport {
    /// Work of all integrators together.
    pub stats: Stats,
    /// The integrator that finished the run.
    pub integrator: Integrator,
    /// Where DOP853 found the system stiff (Hairer's test), whether or not
    /// the run switched.
    pub stiffness_detected_at: Option<f64>,
    /// Where the run switched from DOP853 to RODAS4 (`Auto` only).
    pub switched_at: Option<f64>,
}

impl DirectReport {
    /// For the summary: `direct (DOP853)`, `direct (DOP853 → RODAS4)`.
    pub fn method_name(&self) -> String {
        match self.switched_at {
            Some(_) => format!(
                "direct ({} → {})",
                Integrator::Explicit.name(),
                self.integrator.name()
            ),
            None => format!("direct ({})", self.integrator.name()),
        }
    }

    /// The line to print on stderr about stiffness, if there is one.
    pub fn note(&self) -> Option<String> {
        match (self.switched_at, self.stiffness_detected_at) {
            (Some(t), _) => Some(format!(
                "direct: switched to {} at t = {t:e} (stiffness detected)",
                Integrator::Stiff.name()
            )),
            (None, Some(t)) => Some(format!(
                "direct: the system looks stiff from t = {t:e} on; {} may be faster \
                 (--integrator stiff or auto)",
                Integrator::Stiff.name()
            )),
            (None, None) => None,
        }
    }
}

/// Integrates `motion` directly with the user's choice of integrator:
/// `Auto` starts with DOP853 and, when Hairer's stiffness test fires,
/// continues from the current state with RODAS4 (with the last step length
/// as its first guess); `Explicit` keeps DOP853 and only reports the
/// detection; `Stiff` is RODAS4 throughout; `Magnus` (a field-only choice)
/// acts as `Auto`.
pub fn solve_direct_choice<M: Motion + ?Sized>(
    motion: &M,
    choice: IntegratorChoice,
    tol: Tolerance,
    times: &[f64],
    x0: &[f64],
    mut on_sample: impl FnMut(f64, &[f64]),
) -> Result<DirectReport, Failure> {
    let first = match choice {
        IntegratorChoice::Stiff => Integrator::Stiff,
        IntegratorChoice::Auto | IntegratorChoice::Explicit | IntegratorChoice::Magnus => {
            Integrator::Explicit
        }
    };
    let mut report = DirectReport {
        stats: Stats::default(),
        integrator: first,
        stiffness_detected_at: None,
        switched_at: None,
    };
    let Some((&t0, rest)) = times.split_first() else {
        return Ok(report);
    };
    let span = times.last().map_or(0.0, |t1| (t1 - t0).abs());
    let h_max = if span > 0.0 { span } else { 1.0 };
    let mut stepper = AnyStepper::new(first, motion, t0, x0, tol, h_max)?;
    on_sample(t0, x0);
    for &t in rest {
        while stepper.time() < t {
            let mut so_far = report.stats;
            so_far += stepper.stats();
            within_step_budget(stepper.time(), &so_far)?;
            stepper.step(motion, t)?;
            if report.stiffness_detected_at.is_none() {
                report.stiffness_detected_at = stepper.stiffness_detected();
                let switches = matches!(choice, IntegratorChoice::Auto | IntegratorChoice::Magnus);
                if report.stiffness_detected_at.is_some() && switches {
                    let (now, h) = (stepper.time(), stepper.proposed_step());
                    report.stats += stepper.stats();
                    let state = stepper.state().to_vec();
                    stepper = AnyStepper::new(Integrator::Stiff, motion, now, &state, tol, h_max)?;
                    stepper.propose_step(h);
                    report.integrator = Integrator::Stiff;
                    report.switched_at = Some(now);
                }
            }
        }
        on_sample(t, stepper.state());
    }
    report.stats += stepper.stats();
    Ok(report)
}
