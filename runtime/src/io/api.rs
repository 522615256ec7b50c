//! The library API of generated crates, model-independent half: options
//! with a builder, and `solve` returning the whole [`Solution`]. A
//! generated crate adds, by the model's own names,
//!
//! - `Params`: one `f64` field per param, `Default` the file's values;
//! - `Initial`: one `Option<f64>` field per state component, a coordinate
//!   `q` as `q`, its derivatives `q'`, `q''`, `q'''` as `q_dot`, `q_ddot`,
//!   `q_d3` (a clash numbered: `q_dot_2`); `Default` is all `None`, the
//!   model's own initial state. Each field's doc comment says whether the
//!   model states the value or the constraints (or, for constraints of
//!   order k ≥ 3, the equations of motion) fix it; a fixed value may stay
//!   `None` and is checked, not imposed, when given;
//! - `solve(&Params, &Initial, &Options)`, which hands them over to
//!   [`solve`] by index.
//!
//! [`integration`] (and [`integration_of`] for a model made already) gives
//! the same run as a steppable [`Integration`]: `advance_to(t)`, the state
//! there, `restart_from(t, x)`.
//!
//! ```ignore
//! use lag_double_pendulum_energy::{solve, Initial, Method, Options, Params};
//!
//! let solution = solve(
//!     &Params { m2: 2.0, ..Params::default() },
//!     &Initial { a_dot: Some(0.5), ..Initial::default() },
//!     &Options::default().rtol(1e-9).method(Method::Direct),
//! )?;
//! println!("{:?}", solution.at(2.5));
//! ```

use crate::choice::{IntegratorChoice, Method};
use crate::failure::{Failure, FailureKind};
use crate::method::field::Anchor;
use crate::model::{DynModel, Initial, Model};
use crate::run::integration::Integration;
use crate::run::options::Options;
use crate::run::solution::Solution;
use crate::run::solve as solve_run;

impl Options {
    /// The field method or direct integration.
    pub fn method(mut self, method: Method) -> Self {
        self.method = method;
        self
    }

    /// The integrator (`None`: the model's `integrator` statement, or auto).
    pub fn integrator(mut self, choice: IntegratorChoice) -> Self {
        self.integrator = Some(choice);
        self
    }

    /// The relative tolerance (per step; atol stays unless set).
    pub fn rtol(mut self, rtol: f64) -> Self {
        self.tol.rtol = rtol;
        self
    }

    /// The absolute tolerance.
    pub fn atol(mut self, atol: f64) -> Self {
        self.tol.atol = atol;
        self
    }

    /// The field's free anchor values `c_2..c_N`.
    pub fn anchor(mut self, values: Vec<f64>) -> Self {
        self.anchor = Anchor::Given(values);
        self
    }

    /// The work budget (steps of every kind).
    pub fn max_steps(mut self, steps: usize) -> Self {
        self.max_steps = steps;
        self
    }

    /// Whether the global error is estimated along the run (default
    /// true; `Solution`'s report then has no estimate, and the run costs
    /// what the integration alone costs).
    pub fn global_error(mut self, estimate: bool) -> Self {
        self.global_error = estimate;
        self
    }
}

/// Solves `M` with these param values (in [`Model::PARAMS`] order) and
/// initial values (`given[i]` replaces the model's value of state
/// component `i`, in [`Model::STATE`] order, when it is one the model
/// states; values the constraints fix are checked against them), with the
/// checks the command line applies. Generated crates call it from their
/// typed `solve(&Params, &Initial, &Options)`.
pub fn solve<M: Model + 'static>(
    params: &[f64],
    given: &[Option<f64>],
    options: &Options,
) -> Result<Solution, Failure> {
    solve_model(&mut M::new(params), given, options)
}

/// [`solve`] for a model made already: the work, compiled once here.
pub fn solve_model(
    model: &mut dyn DynModel,
    given: &[Option<f64>],
    options: &Options,
) -> Result<Solution, Failure> {
    let (t0, t1, x0) = initial(&*model, given)?;
    solve_run(model, &quiet(options), t0, t1, &x0)
}

/// A solution with its forward sensitivities ([`solve_sensitivity`]):
/// `at(t)` gives the state and `S = ∂x(t)/∂(y0, p)`.
#[derive(Clone, Debug)]
pub struct Sensitivities {
    /// The augmented system's solution: the state, then `S` column by
    /// column.
    pub solution: Solution,
    /// The state's dimension `N`.
    pub dim: usize,
    /// The columns of `S`: the initial values the model states (`Y0`),
    /// then every param.
    pub columns: Vec<String>,
}

impl Sensitivities {
    /// The state at `t` and `S` (`N × columns`, column-major: `S[c·N + i]`
    /// is `∂x_i/∂columns[c]`).
    pub fn at(&self, t: f64) -> (Vec<f64>, Vec<f64>) {
        let mut z = self.solution.at(t);
        let s = z.split_off(self.dim);
        (z, s)
    }
}

/// [`solve_model`] with the forward sensitivities (the same as
/// `--sensitivity` on the command line, by direct integration of the
/// augmented system whatever `options.method` says): every param is
/// independent here (the values passed are all given), so `∂x/∂p` holds
/// the params computed from the others fixed.
pub fn solve_sensitivity(
    model: &mut dyn DynModel,
    given: &[Option<f64>],
    options: &Options,
) -> Result<Sensitivities, Failure> {
    use crate::run::sensitivity::{
        column_names, initial as start_of, unsupported, Augmented, Start,
    };
    if let Some(message) = unsupported(&*model) {
        return Err(Failure::new(
            model.time_span().0,
            FailureKind::Unsupported { message },
        ));
    }
    let (t0, t1, x0) = initial(&*model, given)?;
    let overrides: Vec<Option<f64>> = model.param_values().iter().map(|&v| Some(v)).collect();
    let stated: Vec<Option<f64>> = given
        .iter()
        .zip(model.initial_kinds())
        .map(|(g, kind)| if *kind == Initial::Given { *g } else { None })
        .collect();
    let start = Start {
        prototype: &*model,
        overrides: &overrides,
        given: &stated,
    };
    let (chain, s0) = start_of(&*model, &start, t0, &x0)?;
    let mut augmented = Augmented::new(model.boxed_clone(), chain);
    let mut z0 = x0.clone();
    z0.extend(s0);
    let options = Options {
        method: Method::Direct,
        ..quiet(options)
    };
    let solution = solve_run(&mut augmented, &options, t0, t1, &z0)?;
    Ok(Sensitivities {
        solution,
        dim: x0.len(),
        columns: column_names(&*model),
    })
}

/// A steppable [`Integration`] of `M` with these param values and initial
/// values (as [`solve`] takes them) over the model's time span: advance it
/// to any time, read the state, restart it from a changed state.
pub fn integration<M: Model + 'static>(
    params: &[f64],
    given: &[Option<f64>],
    options: &Options,
) -> Result<Integration<'static>, Failure> {
    integration_of(Box::new(M::new(params)), given, options)
}

/// [`integration`] for a model made already (for example by
/// [`DynModel::with_params`]), which the integration owns.
pub fn integration_of(
    model: Box<dyn DynModel>,
    given: &[Option<f64>],
    options: &Options,
) -> Result<Integration<'static>, Failure> {
    let (t0, t1, x0) = initial(&*model, given)?;
    Ok(Integration::owned(model, &quiet(options), t0, t1, &x0))
}

/// A library call shows no progress.
fn quiet(options: &Options) -> Options {
    Options {
        progress: false,
        ..options.clone()
    }
}

/// The time span and the initial state, with the checks the command line
/// applies (`run::start`): `given[i]` replaces a value the model states;
/// one the constraints fix is checked against them.
fn initial(model: &dyn DynModel, given: &[Option<f64>]) -> Result<(f64, f64, Vec<f64>), Failure> {
    let (t0, t1) = crate::run::start::time_span(model)?;
    let x0 = crate::run::start::initial_state(model, t0, given)?;
    Ok((t0, t1, x0))
}
