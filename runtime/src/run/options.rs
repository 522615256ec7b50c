//! What a run is asked to do ([`Options`]) and what it did ([`Outcome`],
//! [`Ending`]).

use crate::choice::{IntegratorChoice, Method};
use crate::method::field::Anchor;
use crate::method::solver::Report;
use crate::model::DynModel;
use crate::ode::tolerance::Tolerance;

/// How to integrate.
#[derive(Clone, Debug, PartialEq)]
pub struct Options {
    pub method: Method,
    /// `None`: the model's `integrator` statement, or `Auto`.
    pub integrator: Option<IntegratorChoice>,
    pub tol: Tolerance,
    pub anchor: Anchor,
    pub reanchor: bool,
    /// The work budget: steps of every kind.
    pub max_steps: usize,
    /// Show progress on stderr (when it is a terminal) for long runs.
    pub progress: bool,
    /// Cut the steps to land on every time the caller advances to (what
    /// SUNDIALS calls a stop time, DifferentialEquations.jl `tstops`): the
    /// samples carry the step's error instead of the continuous
    /// extension's, at the price of steps that depend on the output. Off
    /// by default: output times never change the answer.
    pub step_to_times: bool,
    /// Estimate the global error along the run (the summary's line; on by
    /// default), by either method. Off for a run whose estimate nobody
    /// reads (`--no-global-error`): the sensitivities' augmented run, where
    /// the error carried through the projection of every column was two
    /// thirds of a holonomic model's run at rtol 1e-12 (cartesian_pendulum,
    /// 33 ms against 2.5 ms at 1e-11), or sweeps and comparisons of
    /// integrators that read the states only. Off, the states are the
    /// same, bit for bit: the estimate only reports.
    pub global_error: bool,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            method: Method::Field,
            integrator: None,
            tol: Tolerance::default(),
            anchor: Anchor::Zero,
            reanchor: true,
            max_steps: crate::ode::budget::DEFAULT_MAX_STEPS,
            progress: false,
            step_to_times: false,
            global_error: true,
        }
    }
}

impl Options {
    /// The integrator choice: the option, else the model's statement,
    /// else `Auto`; with where it came from, in words.
    pub fn choice(&self, model: &dyn DynModel) -> (IntegratorChoice, String) {
        let choice = self.integrator_choice(model);
        match (self.integrator, model.declared_integrator()) {
            (Some(c), _) => (choice, format!("--integrator {}", c.name())),
            (None, Some(c)) => (choice, format!("declared {} in the model", c.name())),
            (None, None) => (choice, "auto, the default".to_string()),
        }
    }

    /// The integrator choice of [`Options::choice`] without the words (no
    /// allocation: every solve asks).
    pub fn integrator_choice(&self, model: &dyn DynModel) -> IntegratorChoice {
        self.integrator
            .or_else(|| model.declared_integrator())
            .unwrap_or(IntegratorChoice::Auto)
    }
}

/// Why the run ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Ending {
    /// At the end of the time span.
    End,
    /// `stop when` became true at this time.
    Stopped(f64),
    /// The impacts of the `when` whose condition is `impact` left the
    /// motion on its boundary at `at`: they accumulate at `accumulation`
    /// (a ball with restitution below 1 comes to rest there), or (`None`)
    /// the last one stopped the motion instead of turning it back. The
    /// run ends at `at`, its last row the state after that impact.
    Rest {
        impact: &'static str,
        at: f64,
        accumulation: Option<f64>,
    },
}

/// What a run did.
#[derive(Clone, Debug, PartialEq)]
pub struct Outcome {
    pub report: Report,
    pub ending: Ending,
    /// Events located (switches and candidate changes).
    pub events: usize,
    /// Steps drawn from the budget.
    pub budget_used: usize,
    /// The constraints' residuals and projections (models whose
    /// constraints fix state components).
    pub kept: Option<crate::run::keep::Kept>,
}
