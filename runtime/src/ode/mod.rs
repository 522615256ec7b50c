//! One-step integrators and what they share: the systems they integrate,
//! the stepper interface, tolerances, the step-size controller, the work
//! budget, dense output.

pub mod budget;
pub mod controller;
pub mod dense;
pub mod dop853;
pub mod magnus;
pub mod rodas4;
pub mod stepper;
pub mod system;
pub mod tolerance;

use crate::failure::Failure;
use budget::Budget;
use dop853::Dop853;
use rodas4::Rodas4;
use stepper::{Clock, Clocked, Stepper};
use system::System;
use tolerance::Tolerance;

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
    ) -> Result<crate::ode::stepper::DenseStep, Failure> {
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
