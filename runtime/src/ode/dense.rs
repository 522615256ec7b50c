//! One step's continuous extension as a value detached from its
//! integrator, so that a solution can keep its steps. Each integrator
//! brings its own extension (DOP853's order-7 polynomial in `dop853.rs`,
//! RODAS4's order-3 one in `rodas4.rs`) as an [`Extension`]; this module
//! knows none of them, so a new integrator's dense output touches no file
//! but its own.

use std::fmt::Debug;
use std::sync::Arc;

/// A step's continuous extension over its step, `θ = (t − t_old)/h` in
/// `[0, 1]`. Shared (`Arc`): a solution's steps are cloned with it, and
/// sent to the threads of a batch.
pub trait Extension: Debug + Send + Sync {
    /// The state at `θ` into `out`.
    fn eval(&self, theta: f64, out: &mut [f64]);
}

/// One step's continuous extension, detached from its integrator.
#[derive(Clone, Debug)]
pub struct DenseStep {
    pub t_old: f64,
    pub t_new: f64,
    pub(crate) h: f64,
    extension: Arc<dyn Extension>,
}

impl DenseStep {
    /// The step from `t_old` to `t_new` (length `h`; 0 for none) and its
    /// extension.
    pub fn new(t_old: f64, t_new: f64, h: f64, extension: Arc<dyn Extension>) -> DenseStep {
        DenseStep {
            t_old,
            t_new,
            h,
            extension,
        }
    }

    /// The state at `t` (clamped to the step).
    pub fn eval(&self, t: f64, out: &mut [f64]) {
        let s = if self.h > 0.0 {
            ((t - self.t_old) / self.h).clamp(0.0, 1.0)
        } else {
            1.0
        };
        self.extension.eval(s, out);
    }
}
