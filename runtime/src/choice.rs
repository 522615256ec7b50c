//! The user's choices of method and integrator (`--method`,
//! `--integrator`, a model's `integrator` statement): plain values every
//! layer reads, the model's constants among them.

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
