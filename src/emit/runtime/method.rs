//! The integrator chosen at run time (`--method`, stiffness).

use super::dop853::Dop853;
use super::error::Failure;
use super::rosenbrock::Rodas4;
use super::stepper::{Stats, Stepper, Tolerance};
use super::system::Motion;

/// Which one-step method integrates a system.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Integrator {
    /// DOP853, explicit, order 8.
    Explicit,
    /// RODAS4, linearly implicit, order 4, for stiff systems.
    Stiff,
}

impl Integrator {
    pub fn name(self) -> &'static str {
        match self {
            Integrator::Explicit => "DOP853",
            Integrator::Stiff => "RODAS4",
        }
    }
}

/// How the motion is computed (`--method`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// Vujanović's field method (local field for non-affine systems).
    Field,
    /// Direct integration of the reduced system (7).
    Direct,
}

impl Method {
    /// `field` or `direct`, as on the command line.
    pub fn parse(text: &str) -> Option<Method> {
        match text {
            "field" => Some(Method::Field),
            "direct" => Some(Method::Direct),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Method::Field => "field",
            Method::Direct => "direct",
        }
    }
}

/// The user's choice of integrator (`--integrator auto|explicit|stiff|magnus`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum IntegratorChoice {
    /// Direct: DOP853, switching to RODAS4 when it detects stiffness.
    /// Field: DOP853 (see `FieldOptions::magnus` for why).
    #[default]
    Auto,
    /// DOP853 throughout (stiffness is only reported).
    Explicit,
    /// RODAS4 throughout (field: linear coefficient systems only).
    Stiff,
    /// Field: the Magnus integrator for linear coefficient systems (DOP853
    /// otherwise). Direct: the same as `Auto` (no exponential integrator).
    Magnus,
}

impl IntegratorChoice {
    pub fn parse(text: &str) -> Option<IntegratorChoice> {
        match text {
            "auto" => Some(IntegratorChoice::Auto),
            "explicit" => Some(IntegratorChoice::Explicit),
            "stiff" => Some(IntegratorChoice::Stiff),
            "magnus" => Some(IntegratorChoice::Magnus),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            IntegratorChoice::Auto => "auto",
            IntegratorChoice::Explicit => "explicit",
            IntegratorChoice::Stiff => "stiff",
            IntegratorChoice::Magnus => "magnus",
        }
    }
}

pub enum AnyStepper {
    Explicit(Dop853),
    Stiff(Rodas4),
}

impl AnyStepper {
    pub fn new<M: Motion + ?Sized>(
        integrator: Integrator,
        system: &M,
        t0: f64,
        y0: &[f64],
        tol: Tolerance,
        h_max: f64,
    ) -> Result<Self, Failure> {
        Ok(match integrator {
            Integrator::Explicit => AnyStepper::Explicit(Dop853::new(system, t0, y0, tol, h_max)?),
            Integrator::Stiff => AnyStepper::Stiff(Rodas4::new(system, t0, y0, tol, h_max)?),
        })
    }
}

impl Stepper for AnyStepper {
    fn time(&self) -> f64 {
        match self {
            AnyStepper::Explicit(s) => s.time(),
            AnyStepper::Stiff(s) => s.time(),
        }
    }

    fn state(&self) -> &[f64] {
        match self {
            AnyStepper::Explicit(s) => s.state(),
            AnyStepper::Stiff(s) => s.state(),
        }
    }

    fn stats(&self) -> Stats {
        match self {
            AnyStepper::Explicit(s) => s.stats(),
            AnyStepper::Stiff(s) => s.stats(),
        }
    }

    fn proposed_step(&self) -> f64 {
        match self {
            AnyStepper::Explicit(s) => s.proposed_step(),
            AnyStepper::Stiff(s) => s.proposed_step(),
        }
    }

    fn propose_step(&mut self, h: f64) {
        match self {
            AnyStepper::Explicit(s) => s.propose_step(h),
            AnyStepper::Stiff(s) => s.propose_step(h),
        }
    }

    fn step<M: Motion + ?Sized>(&mut self, system: &M, t_limit: f64) -> Result<(), Failure> {
        match self {
            AnyStepper::Explicit(s) => s.step(system, t_limit),
            AnyStepper::Stiff(s) => s.step(system, t_limit),
        }
    }

    fn stiffness_detected(&self) -> Option<f64> {
        match self {
            AnyStepper::Explicit(s) => s.stiffness_detected(),
            AnyStepper::Stiff(s) => s.stiffness_detected(),
        }
    }
}
