//! A global error estimate carried along a DOP853 integration: the sum of
//! its steps' local errors, each relative to the state's size,
//! `E = Σ_n max_i |ℓ_n,i| / max(|x_n,i|, 1)` (the measure of the
//! summary's error against an exact solution).
//!
//! The local error control bounds each step's error, not their sum: over
//! a long horizon they add up (an undamped oscillator over 160 periods at
//! rtol 1e-10 ends 24× rtol off). The sum is the global error's bound
//! (Dahlquist's, with logarithmic norm 0) for a motion that neither
//! amplifies nor damps errors, as a conservative mechanical motion does
//! on average; it over-states where the motion damps them, and does not
//! bound a chaotic motion's, whose errors grow.
//!
//! The local errors: Hairer's estimate `ℓ̂_n` (the vector whose scaled norm
//! is the `err` the step was accepted with) is at hand but of order 8,
//! where the error of the solution DOP853 carries is of order 9: on the
//! oscillator at rtol 1e-10 the true local error is 0.07× the estimate.
//! So once the sum of the estimates passes [`BOUND`]`·rtol` (a run whose
//! sum stays below it is within the bound already, and pays nothing), and
//! every
//! [`CALIBRATION_STRIDE`] steps after, a step's local error is measured by
//! Richardson extrapolation (`Dop853::local_error_by_halves`, 23
//! evaluations), and the ratio `κ = ℓ / ℓ̂` it gives scales the estimates
//! of the steps until the next measure — by `h / h_κ` too, since the ratio
//! of an order-9 error to an order-8 estimate goes as the step. The sum
//! before the first measure is scaled by its `κ`. `κ` is kept at most 1:
//! above the order-8 estimate a measure is rounding or a step across a
//! kink (Coulomb friction at rtol 1e-12 gave κ ≈ 100).
//!
//! Propagating the errors by the exact Jacobian instead (the linearised
//! error equation) was tried and dropped: the reduced system's drift off
//! the constraints made the propagated error grow without bound on the
//! knife edge and the particle on a circle (1e9× rtol), where the run
//! itself is kept on them.

pub mod growth;

/// The bound the summary holds the estimate to, in units of rtol: below
/// it the unscaled sum (an over-estimate) already says the run is within.
pub const BOUND: f64 = 10.0;

/// A carried global error at least this large (relative to
/// `max(|x|, 1)`) is past the state's own size: the summary reports it
/// as amplification, not as a number, and the errors are no longer
/// carried (`growth::Growth::saturated`).
pub const AMPLIFIED: f64 = 1.0;

/// Steps between two measures of the local error.
pub const CALIBRATION_STRIDE: usize = 32;

/// The smallest local error a Richardson difference resolves (relative,
/// a few roundings of the state).
const MEASURE_FLOOR: f64 = 16.0 * f64::EPSILON;

/// The carried estimate of one run.
#[derive(Clone, Debug, Default)]
pub struct GlobalError {
    sum: f64,
    /// The last measure: `κ` and the step it was taken on.
    ratio: Option<(f64, f64)>,
    /// Steps since the last measure.
    since: usize,
    /// False once a step was not accounted for (a stiff integrator's):
    /// the estimate then covers only part of the run.
    complete: bool,
}

/// `max_i |ℓ_i| / max(|x_i|, 1)`.
pub fn relative(local: &[f64], x: &[f64]) -> f64 {
    let mut worst = 0.0_f64;
    for (l, x) in local.iter().zip(x) {
        worst = worst.max(l.abs() / x.abs().max(1.0));
    }
    worst
}

impl GlobalError {
    pub fn new() -> GlobalError {
        GlobalError {
            sum: 0.0,
            ratio: None,
            since: 0,
            complete: true,
        }
    }

    /// The estimated global error so far, relative to `max(|x|, 1)`
    /// component by component.
    pub fn estimate(&self) -> f64 {
        self.sum
    }

    /// Whether a measure has calibrated the sum.
    pub fn calibrated(&self) -> bool {
        self.ratio.is_some()
    }

    /// Whether every step of the run was accounted for.
    pub fn complete(&self) -> bool {
        self.complete
    }

    /// A step the estimate cannot account for.
    pub fn skip(&mut self) {
        self.complete = false;
    }

    /// Whether the next step's local error should be measured (see the
    /// module's comment), for a run at relative tolerance `rtol`.
    pub fn wants_measure(&self, rtol: f64) -> bool {
        match self.ratio {
            None => self.sum > BOUND * rtol,
            Some(_) => self.since >= CALIBRATION_STRIDE,
        }
    }

    /// An accepted step of length `h` whose local error Hairer's estimate
    /// puts at `estimated` (relative, [`relative`]); what it added.
    pub fn add(&mut self, estimated: f64, h: f64) -> f64 {
        if !estimated.is_finite() {
            self.complete = false;
            return 0.0;
        }
        let scale = match self.ratio {
            Some((kappa, h_kappa)) if h_kappa > 0.0 => kappa * (h / h_kappa).clamp(0.125, 8.0),
            _ => 1.0,
        };
        self.sum += scale * estimated;
        self.since += 1;
        scale * estimated
    }

    /// An accepted step of length `h` whose local error was measured:
    /// `measured`, against Hairer's `estimated` (both relative); what it
    /// added.
    pub fn add_measured(&mut self, estimated: f64, measured: f64, h: f64) -> f64 {
        if !(measured.is_finite() && estimated > 0.0) {
            return self.add(estimated, h);
        }
        // Below a few roundings a difference measures nothing, and above
        // Hairer's estimate it is rounding or a step across a kink: the
        // order-8 estimate bounds the order-9 error where the steps are
        // in their asymptotic range.
        let kappa = (measured.max(MEASURE_FLOOR) / estimated).min(1.0);
        let measured = kappa * estimated;
        if self.ratio.is_none() {
            self.sum *= kappa;
        }
        self.ratio = Some((kappa, h.abs()));
        self.sum += measured;
        self.since = 0;
        measured
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sums_relative_local_errors_and_scales_them_by_the_measured_ratio() {
        let mut g = GlobalError::new();
        // Relative to max(|x|, 1): 2e-10 / 2 and 3e-10 / 1.
        g.add(relative(&[2e-10, -1e-11], &[2.0, 0.5]), 1.0);
        g.add(relative(&[1e-12, -3e-10], &[0.1, 0.0]), 1.0);
        assert!((g.estimate() - 4e-10).abs() < 1e-24, "{}", g.estimate());
        assert!(!g.wants_measure(1e-10) && g.wants_measure(1e-11));
        // A measure at a tenth of the estimate scales what came before.
        g.add_measured(1e-10, 1e-11, 1.0);
        assert!((g.estimate() - 5e-11).abs() < 1e-24, "{}", g.estimate());
        // ... and the next estimates, by the step's length too.
        g.add(1e-10, 2.0);
        assert!((g.estimate() - 7e-11).abs() < 1e-24, "{}", g.estimate());
        assert!(!g.wants_measure(1e-10));
        for _ in 0..CALIBRATION_STRIDE {
            g.add(0.0, 1.0);
        }
        assert!(g.wants_measure(1e-10));
        assert!(g.complete());
        g.add(f64::NAN, 1.0);
        assert!(!g.complete());
    }
}
