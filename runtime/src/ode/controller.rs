//! The one step-size controller: proportional–integral (Gustafsson's PI
//! controller as Hairer and Wanner use it in `dopri5`/`dop853`, HNW I,
//! IV.2): `h_new = h · safety · err^(−α) · err_prev^β`, `α = 1/k − 0.75 β`,
//! with `k` the order of the error estimate. The integral part damps the
//! oscillation of step sizes where stability, not accuracy, limits them.

/// `ln 1e-4`: the smallest previous error the integral part remembers
/// (Hairer's `facold` floor).
const LN_ERROR_FLOOR: f64 = -9.210340371976182;

/// Step-size control of one integration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Controller {
    /// `1/k`: the exponent of a rejection's step cut.
    inverse_order: f64,
    alpha: f64,
    beta: f64,
    safety: f64,
    min_scale: f64,
    max_scale: f64,
    /// The logarithm of the previous accepted step's error (Hairer's
    /// `facold`): one `ln` and one `exp` a step instead of two `powf`.
    ln_previous_error: f64,
    /// The last attempt was rejected: do not grow the next step.
    rejected: bool,
    /// Ramping up from a guessed first step ([`Controller::guessed_start`]):
    /// no step rejected yet, and every accepted step's error so far below
    /// the tolerance that the usual growth limit held the next step back.
    ramp: bool,
    /// After a step grew past `max_scale` in the ramp: the length the usual
    /// growth would have given, to fall back to if the grown step fails.
    fallback: Option<f64>,
}

/// The largest growth per step while ramping up from a guessed first step
/// (SUNDIALS CVODE allows 10⁴ after its first step, `ETAMX1`): the
/// starting step ([`crate::ode::tolerance::initial_step`]) is a cautious
/// estimate, a hundred to ten thousand times shorter than the tolerance
/// allows where a component starts at zero, and growing from it by
/// `max_scale` per step costs several steps that buy no accuracy.
const RAMP_GROWTH: f64 = 1e4;

impl Controller {
    /// For an error estimate of order `k` (the step's error is
    /// `O(h^k)`), with integral gain `beta`.
    pub fn new(k: f64, beta: f64, min_scale: f64, max_scale: f64) -> Controller {
        Controller {
            inverse_order: 1.0 / k,
            alpha: 1.0 / k - 0.75 * beta,
            beta,
            safety: 0.9,
            min_scale,
            max_scale,
            ln_previous_error: LN_ERROR_FLOOR,
            rejected: false,
            ramp: false,
            fallback: None,
        }
    }

    /// The first step was guessed, not known to work. Until the first
    /// rejection, and while the errors stay so small that the usual limit
    /// `max_scale` would hold the step back, the step grows as far as its
    /// error says (the elementary controller `safety · err^(−1/k)`, up to
    /// 10⁴); if such a grown step fails, the retry is no longer
    /// than the usual growth would have given.
    pub fn guessed_start(mut self) -> Controller {
        self.ramp = true;
        self
    }

    /// DOP853's: error of order 8, `β = 0.04` (as dopri5's default), step
    /// changes within `[1/3, 6]`.
    pub fn dop853() -> Controller {
        Controller::new(8.0, 0.04, 1.0 / 3.0, 6.0)
    }

    /// RODAS4's: the embedded error is of order 4; `β = 0.08`, changes in
    /// `[1/5, 6]`.
    pub fn rodas4() -> Controller {
        Controller::new(4.0, 0.08, 0.2, 6.0)
    }

    /// Ends a ramp ([`Controller::guessed_start`]): for errors that do not
    /// follow the integrator's own `O(h^k)` estimate (the field measures the
    /// state it recovers from its coefficients), the ramp's extrapolation
    /// over many orders of magnitude is not to be trusted.
    pub fn end_ramp(&mut self) {
        self.ramp = false;
    }

    /// The next step after accepting a step of length `h` with scaled error
    /// `err ≤ 1`.
    pub fn accept(&mut self, h: f64, err: f64) -> f64 {
        self.fallback = None;
        if self.ramp {
            let scale = self.safety * err.max(f64::MIN_POSITIVE).powf(-self.inverse_order);
            if scale > self.max_scale {
                self.fallback = Some(h * self.max_scale);
                return h * scale.min(RAMP_GROWTH);
            }
            // The ramp is over; the integral part starts from a neutral
            // history (a previous error of 1), not from the ramp's tiny ones.
            self.ramp = false;
            self.ln_previous_error = 0.0;
        }
        let ln_err = err.max(1e-10).ln();
        let mut scale =
            self.safety * (self.beta * self.ln_previous_error - self.alpha * ln_err).exp();
        scale = scale.clamp(self.min_scale, self.max_scale);
        if self.rejected {
            scale = scale.min(1.0);
        }
        self.ln_previous_error = ln_err.max(LN_ERROR_FLOOR);
        self.rejected = false;
        h * scale
    }

    /// The step to retry after rejecting a step of length `h` with scaled
    /// error `err > 1` (no integral part: the history does not apply).
    pub fn reject(&mut self, h: f64, err: f64) -> f64 {
        self.rejected = true;
        self.ramp = false;
        let scale = if err.is_finite() {
            (self.safety * err.powf(-self.inverse_order)).max(self.min_scale)
        } else {
            0.25
        };
        let retry = h * scale.min(1.0);
        match self.fallback.take() {
            Some(usual) => retry.min(usual),
            None => retry,
        }
    }

    /// Forgets the history (after a restart at an event or an anchor).
    pub fn reset(&mut self) {
        self.ln_previous_error = LN_ERROR_FLOOR;
        self.rejected = false;
        self.ramp = false;
        self.fallback = None;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grows_on_small_errors_shrinks_on_large_and_never_grows_after_a_rejection() {
        let mut c = Controller::dop853();
        let grown = c.accept(1.0, 1e-6);
        assert!(grown > 1.0 && grown <= 6.0);
        let shrunk = c.reject(1.0, 100.0);
        assert!((1.0 / 3.0..1.0).contains(&shrunk));
        let after = c.accept(1.0, 1e-8);
        assert!(after <= 1.0);
        // An error of exactly 1 keeps the step below its length.
        let mut c = Controller::rodas4();
        assert!(c.accept(1.0, 1.0) < 1.0);
    }

    #[test]
    fn a_guessed_start_ramps_up_as_far_as_the_error_says_until_a_rejection() {
        // Without a guessed start, a tiny error grows the step by 6 at most.
        assert!(Controller::dop853().accept(1.0, 1e-16) <= 6.0);
        let mut c = Controller::dop853().guessed_start();
        // 0.9 · (1e-16)^(-1/8) = 90.
        let grown = c.accept(1.0, 1e-16);
        assert!((89.0..91.0).contains(&grown), "{grown}");
        // Still far below the tolerance: the ramp goes on.
        assert!(c.accept(grown, 1e-16) > 6.0 * grown);
        // The grown step fails: the retry is the usual growth's, 6 times
        // the last accepted step, not a third of the failed one.
        let retry = c.reject(90.0 * grown, 1e3);
        assert_eq!(retry, 6.0 * grown);
        // After a rejection the ramp is over.
        assert!(c.accept(retry, 1e-16) <= retry);
        assert!(c.accept(retry, 1e-16) <= 6.0 * retry);
        // An error near the tolerance ends the ramp at once.
        let mut c = Controller::dop853().guessed_start();
        let h = c.accept(1.0, 0.5);
        assert!(h < 6.0);
        assert!(c.accept(h, 1e-16) <= 6.0 * h);
    }
}
