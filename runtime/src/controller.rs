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
}

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
        }
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

    /// The next step after accepting a step of length `h` with scaled error
    /// `err ≤ 1`.
    pub fn accept(&mut self, h: f64, err: f64) -> f64 {
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
        let scale = if err.is_finite() {
            (self.safety * err.powf(-self.inverse_order)).max(self.min_scale)
        } else {
            0.25
        };
        h * scale.min(1.0)
    }

    /// Forgets the history (after a restart at an event or an anchor).
    pub fn reset(&mut self) {
        self.ln_previous_error = LN_ERROR_FLOOR;
        self.rejected = false;
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
}
