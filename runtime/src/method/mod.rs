//! The integrators a run can use, and the user's choice among them.

pub mod direct;
pub mod field;
pub mod segment;
pub mod solver;

use crate::budget::Budget;
use crate::dop853::Dop853;
use crate::failure::Failure;
use crate::rodas4::Rodas4;
use crate::stepper::{Clock, Clocked, Stepper};
use crate::system::System;
use crate::tolerance::Tolerance;

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
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Method {
    /// Vujanović's field method.
    #[default]
    Field,
    /// Direct integration of the reduced system (7).
    Direct,
}

impl Method {
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

/// The user's choice of integrator (`integrator …;`, `--integrator`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum IntegratorChoice {
    /// Direct: DOP853, switching to RODAS4 when it detects stiffness.
    /// Field: DOP853 for the coefficients, RODAS4 for the window's
    /// predictor when the motion is stiff.
    #[default]
    Auto,
    /// DOP853 throughout (stiffness is only reported).
    Explicit,
    /// RODAS4 throughout.
    Stiff,
    /// Field: the Magnus integrator for linear coefficient systems
    /// (DOP853 otherwise). Direct: the same as `Auto`.
    Magnus,
}

impl IntegratorChoice {
    pub const ALL: [IntegratorChoice; 4] = [
        IntegratorChoice::Auto,
        IntegratorChoice::Explicit,
        IntegratorChoice::Stiff,
        IntegratorChoice::Magnus,
    ];

    pub fn parse(text: &str) -> Option<IntegratorChoice> {
        IntegratorChoice::ALL.into_iter().find(|c| c.name() == text)
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

/// DOP853 or RODAS4 behind one type.
pub enum AnyStepper {
    Explicit(Dop853),
    Stiff(Rodas4),
}

impl AnyStepper {
    pub fn new<S: System + ?Sized>(
        integrator: Integrator,
        system: &S,
        t0: f64,
        y0: &[f64],
        tol: Tolerance,
        h_max: f64,
        h0: Option<f64>,
    ) -> Result<Self, Failure> {
        Ok(match integrator {
            Integrator::Explicit => {
                AnyStepper::Explicit(Dop853::new(system, t0, y0, tol, h_max, h0)?)
            }
            Integrator::Stiff => AnyStepper::Stiff(Rodas4::new(system, t0, y0, tol, h_max, h0)?),
        })
    }

    /// The last step's continuous extension, detached.
    pub fn dense_step<S: System + ?Sized>(
        &mut self,
        system: &S,
    ) -> Result<crate::stepper::DenseStep, Failure> {
        match self {
            AnyStepper::Explicit(s) => s.dense_step(system),
            AnyStepper::Stiff(s) => Ok(s.dense_step()),
        }
    }

    pub fn integrator(&self) -> Integrator {
        match self {
            AnyStepper::Explicit(_) => Integrator::Explicit,
            AnyStepper::Stiff(_) => Integrator::Stiff,
        }
    }
}

macro_rules! each {
    ($self:ident, $s:ident => $e:expr) => {
        match $self {
            AnyStepper::Explicit($s) => $e,
            AnyStepper::Stiff($s) => $e,
        }
    };
}

impl Clocked for AnyStepper {
    fn clock(&self) -> &Clock {
        each!(self, s => s.clock())
    }

    fn clock_mut(&mut self) -> &mut Clock {
        each!(self, s => s.clock_mut())
    }
}

impl Stepper for AnyStepper {
    fn state(&self) -> &[f64] {
        each!(self, s => s.state())
    }

    fn step<S: System + ?Sized>(
        &mut self,
        system: &S,
        t_limit: f64,
        budget: &Budget,
    ) -> Result<(), Failure> {
        each!(self, s => s.step(system, t_limit, budget))
    }

    fn dense<S: System + ?Sized>(
        &mut self,
        system: &S,
        t: f64,
        out: &mut [f64],
    ) -> Result<(), Failure> {
        each!(self, s => s.dense(system, t, out))
    }

    fn stiffness_detected(&self) -> Option<f64> {
        each!(self, s => s.stiffness_detected())
    }
}
