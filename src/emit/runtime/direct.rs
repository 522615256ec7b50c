//! Direct integration of the reduced system (7), reporting the state at
//! each sample time (the integrator stops exactly on each).

use super::error::Failure;
use super::method::{AnyStepper, Integrator};
use super::stepper::{Stats, Stepper, Tolerance};
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
