//! A global error estimate carried along a DOP853 integration: the sum of
//! its steps' local error estimates, each relative to the state's size,
//! `E = Σ_n max_i |ℓ_n,i| / max(|x_n,i|, 1)` with `ℓ_n` the step's local
//! error as the controller estimates it (Hairer's combined estimate, the
//! vector whose scaled norm is the `err` the step was accepted with).
//!
//! The local error control bounds each step's error, not their sum: over
//! a long horizon they add up (an undamped oscillator over 160 periods at
//! rtol 1e-10 ends 24× rtol off). The sum is the global error's bound
//! (Dahlquist's, with logarithmic norm 0) for a motion that neither
//! amplifies nor damps errors, as a conservative mechanical motion does
//! on average; it over-states where the motion damps them, and does not
//! bound a chaotic motion's, whose errors grow. It costs nothing: the
//! local estimates are at hand.
//!
//! It is an over-estimate for a second reason: Hairer's estimate is of
//! order 8 where the step's error is of order 9, so it over-states each
//! local error (about 15× on the oscillator at rtol 1e-10, measured
//! against the exact step), the more so the shorter the steps.
//! Propagating the errors by the exact Jacobian instead (the linearised
//! error equation) was tried and dropped: the reduced system's drift off
//! the constraints made the propagated error grow without bound on the
//! knife edge and the particle on a circle (1e9× rtol), where the run
//! itself is kept on them.

/// The carried estimate of one run.
#[derive(Clone, Debug, Default)]
pub struct GlobalError {
    sum: f64,
    /// False once a step was not accounted for (a stiff integrator's):
    /// the estimate then covers only part of the run.
    complete: bool,
}

impl GlobalError {
    pub fn new() -> GlobalError {
        GlobalError {
            sum: 0.0,
            complete: true,
        }
    }

    /// The estimated global error so far, relative to `max(|x|, 1)`
    /// component by component (the measure of the summary's error against
    /// an exact solution).
    pub fn estimate(&self) -> f64 {
        self.sum
    }

    /// Whether every step of the run was accounted for.
    pub fn complete(&self) -> bool {
        self.complete
    }

    /// A step the estimate cannot account for.
    pub fn skip(&mut self) {
        self.complete = false;
    }

    /// One accepted step ending at `x` with local error `local`.
    pub fn add(&mut self, local: &[f64], x: &[f64]) {
        let mut worst = 0.0_f64;
        for (l, x) in local.iter().zip(x) {
            worst = worst.max(l.abs() / x.abs().max(1.0));
        }
        if worst.is_finite() {
            self.sum += worst;
        } else {
            self.complete = false;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sums_the_largest_relative_local_error_of_each_step() {
        let mut g = GlobalError::new();
        // Relative to max(|x|, 1): 2e-10 / 2 and 3e-10 / 1.
        g.add(&[2e-10, -1e-11], &[2.0, 0.5]);
        g.add(&[1e-12, -3e-10], &[0.1, 0.0]);
        assert!((g.estimate() - 4e-10).abs() < 1e-24, "{}", g.estimate());
        assert!(g.complete());
        g.add(&[f64::NAN, 0.0], &[1.0, 1.0]);
        assert!(!g.complete());
        assert!((g.estimate() - 4e-10).abs() < 1e-24);
    }
}
