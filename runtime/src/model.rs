//! The one trait a generated crate implements: everything the methods,
//! the events and the command line need to know about one model.
//!
//! Generated code holds only the model's own functions (the right side of
//! the reduced system (7), its exact Jacobians, the coefficient system of
//! the field method, initial values, outputs, switching functions); every
//! model-independent line lives in this crate. Methods that a model does
//! not need keep their defaults, so a model without events, outputs or a
//! coefficient system emits nothing for them.

use crate::choice::IntegratorChoice;
use crate::closure::Dependents;
use crate::failure::Failure;
use crate::lanes::{Lanes, WIDTH};
use crate::linalg::Matrix;

/// How a state component's initial value is found (SPEC §1.4).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Initial {
    /// Stated in the model (`initial q1 = …;`), overridable by `--init`.
    Given,
    /// Fixed by a constraint (or its derivatives) from the given values.
    Constraint,
    /// An independent derivative of order 2..k−1 (k ≥ 3), solved from the
    /// equations of motion at `t0`.
    Solved,
}

/// One implicit constraint whose dependent derivative is chosen at run
/// time among `candidates` (`constraint … for y' or x';`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Candidates {
    /// The constraint as written, for messages.
    pub text: &'static str,
    /// The candidate dependent derivatives, as written (`y'`, `x'`).
    pub names: &'static [&'static str],
}

pub use crate::domain::DomainKind;

/// Where a constraint as written is defined: its `argument` positive (a
/// pole: non-zero). The run stops naming the constraint where a branch
/// ends, instead of passing it silently (issue 28).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Domain {
    /// The constraint as written.
    pub constraint: &'static str,
    pub kind: DomainKind,
    /// The argument, as text.
    pub argument: &'static str,
}

/// The discrete state of a run between two events: which reduced system
/// (mode) is integrated and which branch every switch is on. Within a
/// segment the right side is smooth; an event changes the regime and
/// restarts the integrator.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Regime {
    /// The candidate combination: the index of the reduced system, mixed
    /// radix over [`Model::CONSTRAINTS`] (the first constraint's choice is
    /// the lowest digit). 0 for models without candidates.
    pub mode: usize,
    /// `branches[k]`: switching function `g_k` is positive on this segment.
    pub branches: Vec<bool>,
}

/// Every input's value on the current segment (issue 26; the signals and
/// the runs that set them are `crate::inputs`): input `i` is
/// `values[i] + rates[i] · (t − from)`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Inputs {
    values: Vec<f64>,
    rates: Vec<f64>,
    from: f64,
}

impl Inputs {
    /// Inputs held at `values`.
    pub fn held(values: &[f64]) -> Inputs {
        Inputs {
            values: values.to_vec(),
            rates: vec![0.0; values.len()],
            from: 0.0,
        }
    }

    /// Inputs moving along lines: `values` at `from`, with these `rates`.
    pub fn lines(values: &[f64], rates: &[f64], from: f64) -> Inputs {
        Inputs {
            values: values.to_vec(),
            rates: rates.to_vec(),
            from,
        }
    }

    /// Input `i` at `t`.
    #[inline]
    pub fn at(&self, i: usize, t: f64) -> f64 {
        self.values[i] + self.rates[i] * (t - self.from)
    }

    /// Input `i`'s rate on the segment.
    #[inline]
    pub fn rate(&self, i: usize) -> f64 {
        self.rates[i]
    }

    /// The number of inputs.
    pub fn len(&self) -> usize {
        self.values.len()
    }

    /// No inputs.
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }
}

/// A model compiled by lagc.
///
/// Matrices are [`Matrix`] (column-major), sized and zeroed by the caller:
/// implementations write only their non-zero entries. Methods return
/// `Err` for failures only the model can see (a singular mass matrix,
/// Newton without a root); the integrators check for non-finite values
/// themselves.
pub trait Model: Clone {
    /// The model's name (its file's stem), for messages.
    const NAME: &'static str;
    /// A hash of the model's source and lagc's version: `lagc run` checks
    /// it to be sure a binary belongs to the model it is asked to run.
    const SOURCE_HASH: &'static str;
    /// The params, in declaration order (`--param NAME=VALUE`).
    const PARAMS: &'static [&'static str];
    /// The state (6), `x = (q, q', …, q^(u−1))`: the CSV columns after `t`.
    const STATE: &'static [&'static str];
    /// The number of coordinates `n`: the state is `u` blocks of `n`, and
    /// its first `N − n` rows are `x_i' = x_{i+n}` (the methods use this
    /// structure of `∂X/∂x`).
    const COORDINATES: usize;
    /// How each state component's initial value is found.
    const INITIAL: &'static [Initial];
    /// Extra CSV columns after the state (`output` statements, a vector
    /// output flattened to `p.x`, `p.y`).
    const OUTPUTS: &'static [&'static str] = &[];
    /// The inputs (`input u = 0;`), in declaration order.
    const INPUTS: &'static [&'static str] = &[];
    /// Their defaults.
    const INPUT_DEFAULTS: &'static [f64] = &[];
    /// The mass laws, for naming a mass that reaches zero.
    const MASSES: &'static [&'static str] = &[];
    /// The model's `integrator` statement.
    const DECLARED_INTEGRATOR: Option<IntegratorChoice> = None;
    /// The number of switching functions (kinks and switches of `if`,
    /// `abs`, `sign`, `min`, `max`, and the comparisons of `stop when`).
    const SWITCHES: usize = 0;
    /// Implicit constraints with run-time candidates.
    const CONSTRAINTS: &'static [Candidates] = &[];
    /// The conditions of the model's `when` statements (impacts), as
    /// written, in order.
    const IMPACTS: &'static [&'static str] = &[];
    /// Where the constraints as written end ([`Model::domain_values`]).
    const DOMAINS: &'static [Domain] = &[];
    /// The reduced system (7) is affine in the state: the linear field
    /// ansatz is a complete solution and [`Model::coefficients`] is given.
    const AFFINE: bool = false;
    /// The coefficient system is linear in the coefficients (no `X_A`
    /// depends on `x_1`); otherwise it is of Riccati type.
    const COEFFICIENTS_LINEAR: bool = false;
    /// The reduced system's right side and its Jacobian do not depend on
    /// time (no `t`, mass law or input in them): [`Model::linearize`] at a
    /// state gives the same numbers at every time, so the affine field,
    /// which linearises at the origin, needs it once per system built
    /// rather than at every stage. Set only for affine models; `false`
    /// is always safe.
    const AUTONOMOUS: bool = false;
    /// The model states exact solutions (`exact` lines).
    const EXACT: bool = false;
    /// Constraints fix some state components (the dependent velocities of
    /// first-order constraints): [`Model::constrained`] is given, and the
    /// run keeps the state on them (SPEC §2.3).
    const KEEPS_CONSTRAINTS: bool = false;
    /// Holonomic constraints (SPEC §2.3): [`Model::project_closure`] is
    /// given, and the run keeps the positions (and their derivatives) on
    /// them.
    const KEEPS_POSITIONS: bool = false;
    /// For each mode, the state components the constraints fix (the
    /// indices [`Model::constrained`] writes); empty for a model of one
    /// mode: those [`Model::INITIAL`] marks `Constraint`.
    const FIXED: &'static [&'static [usize]] = &[];
    /// [`Model::param_jacobian`] is given (forward sensitivities).
    const PARAM_JACOBIAN: bool = false;
    /// For each `when` ([`Model::IMPACTS`]), the state components it
    /// resets: given by a model of several modes, whose
    /// [`Model::impact_reset`] writes the resets only (the run chooses the
    /// mode the state goes on in and recomputes what that mode fixes,
    /// `run::impacts`); empty otherwise.
    const IMPACT_TARGETS: &'static [&'static [usize]] = &[];

    /// Every param's value: param `i` is `overrides[i]` when given, else
    /// its expression evaluated with the values before it (so an override
    /// recomputes the params computed from it).
    fn parameters(overrides: &[Option<f64>]) -> Vec<f64>;

    /// The model with these param values (as [`Model::parameters`] gives).
    fn new(params: &[f64]) -> Self;

    /// The param values the model was made with.
    fn param_values(&self) -> &[f64];

    /// The time span `(t0, t1)` (it may depend on params).
    fn time_span(&self) -> (f64, f64);

    /// The initial state (6) at `t0`. `given[i]`, when present, replaces
    /// the model's value of a [`Initial::Given`] component. Values the model
    /// states for dependent components are checked against the
    /// constraints (an [`crate::failure::FailureKind::InconsistentInitialValue`]).
    fn initial_state(&self, given: &[Option<f64>]) -> Result<Vec<f64>, Failure>;

    /// Selects the reduced system and the branches for the next segment.
    fn set_regime(&mut self, _regime: &Regime) {}

    /// Sets the inputs for the next segment (a model without inputs
    /// ignores it; a new model holds its defaults).
    fn set_inputs(&mut self, _inputs: &Inputs) {}

    /// `dx = X(t, x)`, the right side of the reduced system (7).
    fn rhs(&self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), Failure>;

    /// [`Model::rhs_lanes`] is the right side's own body over lanes (not
    /// the default's loop): an ensemble steps its members four at a time.
    const LANES: bool = false;

    /// [`Model::rhs`] of four states at once, lane `l` of `x` the `l`-th
    /// state, each lane's values bit for bit `rhs`'s. Generated for models
    /// that can run an ensemble; this default calls `rhs` once per lane.
    fn rhs_lanes(&self, t: f64, x: &[Lanes], dx: &mut [Lanes]) -> Result<(), Failure> {
        lane_by_lane(|x: &[f64], dx: &mut [f64]| self.rhs(t, x, dx), x, dx)
    }

    /// `jac = ∂X/∂x (t, x)`, exact.
    fn jacobian(&self, t: f64, x: &[f64], jac: &mut Matrix) -> Result<(), Failure>;

    /// `dxdt = ∂X/∂t (t, x)`: the whole explicit time dependence, mass laws
    /// included (zeroed by the caller).
    fn time_partial(&self, t: f64, x: &[f64], dxdt: &mut [f64]) -> Result<(), Failure>;

    /// `X` and `∂X/∂x` at once, sharing their common subexpressions: the
    /// field method linearises the motion at every stage.
    fn linearize(
        &self,
        t: f64,
        x: &[f64],
        dx: &mut [f64],
        jac: &mut Matrix,
    ) -> Result<(), Failure> {
        self.rhs(t, x, dx)?;
        self.jacobian(t, x, jac)
    }

    /// `jac = ∂X/∂p (t, x)`, exact, one column per param (zeroed by the
    /// caller; the partial in each param symbol, the params computed from
    /// it held). Given when [`Model::PARAM_JACOBIAN`].
    fn param_jacobian(&self, _t: f64, _x: &[f64], _jac: &mut Matrix) -> Result<(), Failure> {
        Ok(())
    }

    /// The coefficient system `df = F(t, f)` of the field ansatz (10)
    /// (affine models only): `f[0]` is the free term `f_1`, `f[A − 1]` the
    /// coefficient of `x_A`.
    fn coefficients(&self, t: f64, _f: &[f64], _df: &mut [f64]) -> Result<(), Failure> {
        Err(Failure::not_affine(t))
    }

    /// `∂F/∂f`.
    fn coefficient_jacobian(&self, t: f64, _f: &[f64], _jac: &mut Matrix) -> Result<(), Failure> {
        Err(Failure::not_affine(t))
    }

    /// `∂F/∂t` (zeroed by the caller).
    fn coefficient_time_partial(
        &self,
        t: f64,
        _f: &[f64],
        _dfdt: &mut [f64],
    ) -> Result<(), Failure> {
        Err(Failure::not_affine(t))
    }

    /// The exact solution at `t`, for the components the model states.
    fn exact(&self, _t: f64, _out: &mut [Option<f64>]) {}

    /// The values the current mode's constraints require of the state
    /// components they fix, written into `kept` at those components'
    /// indices (the others are left as they are).
    fn constrained(&self, _t: f64, _x: &[f64], _kept: &mut [f64]) -> Result<(), Failure> {
        Ok(())
    }

    /// `jac[(j, i)] = ∂kept_j/∂x_i`: the partials of the values
    /// [`Model::constrained`] writes in the velocities (zeroed by the
    /// caller; rows of the fixed components, columns of the velocities).
    fn kept_gradient(&self, _t: f64, _x: &[f64], _jac: &mut Matrix) -> Result<(), Failure> {
        Ok(())
    }

    /// Projects the state `x` in place onto the holonomic constraints
    /// (positions, then each derivative block): along their normals, or
    /// partitioned by `partition`, the dependents solved for and the other
    /// coordinates kept (`closure::project`; the keeper's choice,
    /// `run/keep/partition.rs`).
    fn project_closure(
        &self,
        _t: f64,
        _x: &mut [f64],
        _partition: Option<Dependents>,
    ) -> Result<(), Failure> {
        Ok(())
    }

    /// The `output` columns at `(t, x)` in the current regime.
    fn outputs(&self, _t: f64, _x: &[f64], _out: &mut [f64]) {}

    /// The switching functions `g_k(t, x)`; an event is a sign change.
    fn switching_functions(&self, _t: f64, _x: &[f64], _g: &mut [f64]) {}

    /// Whether `stop when` holds with these branches.
    fn stop(&self, _branches: &[bool]) -> bool {
        false
    }

    /// Whether the condition of impact `w` ([`Model::IMPACTS`]) holds with
    /// these branches.
    fn impact_holds(&self, _w: usize, _branches: &[bool]) -> bool {
        false
    }

    /// Impact `w`'s resets: `out` holds the state `x` before the impact on
    /// entry; the reset components are written with their new values (all
    /// read from `x`), then, in a model of one mode, every component the
    /// constraints fix is recomputed from the new state (a model of
    /// several modes leaves that to the run, [`Model::IMPACT_TARGETS`]).
    fn impact_reset(&self, _w: usize, _t: f64, _x: &[f64], _out: &mut [f64]) {}

    /// The pivots `∂h/∂dep` of every candidate of every implicit
    /// constraint, flattened in [`Model::CONSTRAINTS`] order.
    fn pivots(&self, _t: f64, _x: &[f64], _out: &mut [f64]) {}

    /// Every [`Model::DOMAINS`] argument's value and its scale (the sum of
    /// its terms' magnitudes), as pairs: `out[2 i]`, `out[2 i + 1]`.
    fn domain_values(&self, _t: f64, _x: &[f64], _out: &mut [f64]) {}

    /// The mass laws' values at `t`, in [`Model::MASSES`] order.
    fn masses(&self, _t: f64, _out: &mut [f64]) {}

    /// The mass laws' values at `(t, x)`, in [`Model::MASSES`] order: a
    /// model with a law of the state (`rho * x`) implements this one; by
    /// default the laws of `t`, [`Model::masses`].
    fn masses_at(&self, t: f64, _x: &[f64], out: &mut [f64]) {
        self.masses(t, out);
    }

    /// The mass matrix of the highest derivatives at `(t, x)`, for naming
    /// a singular one as the cause of a failure (evaluated only then, and
    /// once at the start for scale).
    fn mass_matrix(&self, _t: f64, _x: &[f64]) -> Option<Matrix> {
        None
    }
}

/// A right side over lanes by `rhs` once per lane (the default of
/// [`Model::rhs_lanes`]).
fn lane_by_lane<F>(rhs: F, x: &[Lanes], dx: &mut [Lanes]) -> Result<(), Failure>
where
    F: Fn(&[f64], &mut [f64]) -> Result<(), Failure>,
{
    let n = x.len();
    let (mut xl, mut dl) = (vec![0.0; n], vec![0.0; n]);
    for l in 0..WIDTH {
        for (v, x) in xl.iter_mut().zip(x) {
            *v = x.0[l];
        }
        rhs(&xl, &mut dl)?;
        for (d, v) in dx.iter_mut().zip(&dl) {
            d.0[l] = *v;
        }
    }
    Ok(())
}

/// The initial value a constraint's first candidate fixes, or the value
/// the model states where that is not finite (the candidate's pivot
/// vanishes at the start: a pendulum in `x, y` released level with its
/// pivot, `y' = -x x'/y` = 0/0). The run checks a state so completed
/// against the constraints in the mode it starts in
/// (`crate::run::regime::check_first_candidates`).
pub fn finite_or_stated(fixed: f64, stated: f64) -> f64 {
    if fixed.is_finite() {
        fixed
    } else {
        stated
    }
}

/// Checks a value the model states for a component the constraints fix
/// (`name`'s `stated` value against the `required` one), after overrides.
pub fn check_stated(t0: f64, name: &str, stated: f64, required: f64) -> Result<(), Failure> {
    if (stated - required).abs() <= 1e-9 * required.abs().max(1.0) {
        Ok(())
    } else {
        Err(Failure::new(
            t0,
            crate::failure::FailureKind::InconsistentInitialValue {
                component: name.to_string(),
                stated,
                required,
            },
        ))
    }
}

/// The state dimension of a model.
pub fn dimension<M: Model>() -> usize {
    M::STATE.len()
}

/// The object-safe face of a [`Model`]: its constants as methods, so that
/// every method, the driver and the command line take `&dyn DynModel` and
/// are compiled once, in this crate. A generated crate then compiles only
/// its model's own functions and this thin forwarding impl: a new model
/// builds in about a second instead of instantiating the whole runtime
/// again (the `lagc run` latency of a model never built before).
///
/// Every model gives its names, dimensions, params, time span, initial
/// state, right side with its Jacobian and time partial, and copies; the
/// rest defaults as in [`Model`] to a model without the feature (no
/// outputs, switches, constraints, coefficient system, …), so a wrapper
/// (`crate::run::sensitivity::Augmented`) states only what it changes.
pub trait DynModel {
    /// [`Model::NAME`].
    fn name(&self) -> &'static str;
    /// [`Model::SOURCE_HASH`].
    fn source_hash(&self) -> &'static str;
    /// [`Model::PARAMS`].
    fn param_names(&self) -> &'static [&'static str];
    /// [`Model::STATE`].
    fn state_names(&self) -> &'static [&'static str];
    /// The state's dimension `N`.
    fn dim(&self) -> usize {
        self.state_names().len()
    }
    /// The components that are the motion's own, on which the
    /// constraints are kept and their distance judged: all `N` of a
    /// model; a system that carries more beside the motion (the
    /// sensitivities, `crate::run::sensitivity`) says how many come first.
    fn motion_dim(&self) -> usize {
        self.dim()
    }
    /// [`Model::COORDINATES`].
    fn coordinates(&self) -> usize;
    /// [`Model::INITIAL`].
    fn initial_kinds(&self) -> &'static [Initial];
    /// [`Model::OUTPUTS`].
    fn output_names(&self) -> &'static [&'static str] {
        &[]
    }
    /// [`Model::MASSES`].
    fn mass_names(&self) -> &'static [&'static str] {
        &[]
    }
    /// [`Model::INPUTS`].
    fn input_names(&self) -> &'static [&'static str] {
        &[]
    }
    /// [`Model::INPUT_DEFAULTS`].
    fn input_defaults(&self) -> &'static [f64] {
        &[]
    }
    /// [`Model::DECLARED_INTEGRATOR`].
    fn declared_integrator(&self) -> Option<IntegratorChoice> {
        None
    }
    /// [`Model::SWITCHES`].
    fn switches(&self) -> usize {
        0
    }
    /// [`Model::CONSTRAINTS`].
    fn constraints(&self) -> &'static [Candidates] {
        &[]
    }
    /// [`Model::IMPACTS`].
    fn impacts(&self) -> &'static [&'static str] {
        &[]
    }
    /// [`Model::AFFINE`].
    fn affine(&self) -> bool {
        false
    }
    /// [`Model::COEFFICIENTS_LINEAR`].
    fn coefficients_linear(&self) -> bool {
        false
    }
    /// [`Model::AUTONOMOUS`].
    fn autonomous(&self) -> bool {
        false
    }
    /// [`Model::EXACT`].
    fn states_exact(&self) -> bool {
        false
    }
    /// [`Model::KEEPS_CONSTRAINTS`].
    fn keeps_constraints(&self) -> bool {
        false
    }
    /// [`Model::KEEPS_POSITIONS`].
    fn keeps_positions(&self) -> bool {
        false
    }
    /// [`Model::FIXED`].
    fn fixed_components(&self) -> &'static [&'static [usize]] {
        &[]
    }
    /// [`Model::PARAM_JACOBIAN`].
    fn has_param_jacobian(&self) -> bool {
        false
    }
    /// [`Model::IMPACT_TARGETS`].
    fn impact_targets(&self) -> &'static [&'static [usize]] {
        &[]
    }
    /// [`Model::param_jacobian`].
    fn param_jacobian(&self, _t: f64, _x: &[f64], _jac: &mut Matrix) -> Result<(), Failure> {
        Ok(())
    }

    /// [`Model::parameters`].
    fn parameters(&self, overrides: &[Option<f64>]) -> Vec<f64>;
    /// The same model with other param values ([`Model::new`]).
    fn with_params(&self, params: &[f64]) -> Box<dyn DynModel>;
    /// A copy (the model in another regime).
    fn boxed_clone(&self) -> Box<dyn DynModel>;

    /// [`Model::param_values`].
    fn param_values(&self) -> &[f64];
    /// [`Model::time_span`].
    fn time_span(&self) -> (f64, f64);
    /// [`Model::initial_state`].
    fn initial_state(&self, given: &[Option<f64>]) -> Result<Vec<f64>, Failure>;
    /// [`Model::set_regime`].
    fn set_regime(&mut self, _regime: &Regime) {}
    /// [`Model::set_inputs`].
    fn set_inputs(&mut self, _inputs: &Inputs) {}
    /// [`Model::rhs`].
    fn rhs(&self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), Failure>;
    /// [`Model::LANES`].
    fn has_lanes(&self) -> bool {
        false
    }
    /// [`Model::rhs_lanes`].
    fn rhs_lanes(&self, t: f64, x: &[Lanes], dx: &mut [Lanes]) -> Result<(), Failure> {
        lane_by_lane(|x: &[f64], dx: &mut [f64]| self.rhs(t, x, dx), x, dx)
    }
    /// [`Model::jacobian`].
    fn jacobian(&self, t: f64, x: &[f64], jac: &mut Matrix) -> Result<(), Failure>;
    /// [`Model::time_partial`].
    fn time_partial(&self, t: f64, x: &[f64], dxdt: &mut [f64]) -> Result<(), Failure>;
    /// [`Model::linearize`].
    fn linearize(
        &self,
        t: f64,
        x: &[f64],
        dx: &mut [f64],
        jac: &mut Matrix,
    ) -> Result<(), Failure> {
        self.rhs(t, x, dx)?;
        self.jacobian(t, x, jac)
    }
    /// [`Model::coefficients`].
    fn coefficients(&self, t: f64, _f: &[f64], _df: &mut [f64]) -> Result<(), Failure> {
        Err(Failure::not_affine(t))
    }
    /// [`Model::coefficient_jacobian`].
    fn coefficient_jacobian(&self, t: f64, _f: &[f64], _jac: &mut Matrix) -> Result<(), Failure> {
        Err(Failure::not_affine(t))
    }
    /// [`Model::coefficient_time_partial`].
    fn coefficient_time_partial(
        &self,
        t: f64,
        _f: &[f64],
        _dfdt: &mut [f64],
    ) -> Result<(), Failure> {
        Err(Failure::not_affine(t))
    }
    /// [`Model::exact`].
    fn exact(&self, _t: f64, _out: &mut [Option<f64>]) {}
    /// [`Model::constrained`].
    fn constrained(&self, _t: f64, _x: &[f64], _kept: &mut [f64]) -> Result<(), Failure> {
        Ok(())
    }
    /// [`Model::kept_gradient`].
    fn kept_gradient(&self, _t: f64, _x: &[f64], _jac: &mut Matrix) -> Result<(), Failure> {
        Ok(())
    }
    /// [`Model::project_closure`].
    fn project_closure(
        &self,
        _t: f64,
        _x: &mut [f64],
        _partition: Option<Dependents>,
    ) -> Result<(), Failure> {
        Ok(())
    }
    /// [`Model::outputs`].
    fn outputs(&self, _t: f64, _x: &[f64], _out: &mut [f64]) {}
    /// [`Model::switching_functions`].
    fn switching_functions(&self, _t: f64, _x: &[f64], _g: &mut [f64]) {}
    /// [`Model::stop`].
    fn stop(&self, _branches: &[bool]) -> bool {
        false
    }
    /// [`Model::impact_holds`].
    fn impact_holds(&self, _w: usize, _branches: &[bool]) -> bool {
        false
    }
    /// [`Model::impact_reset`].
    fn impact_reset(&self, _w: usize, _t: f64, _x: &[f64], _out: &mut [f64]) {}
    /// [`Model::pivots`].
    fn pivots(&self, _t: f64, _x: &[f64], _out: &mut [f64]) {}
    /// [`Model::DOMAINS`].
    fn domains(&self) -> &'static [Domain] {
        &[]
    }
    /// [`Model::domain_values`].
    fn domain_values(&self, _t: f64, _x: &[f64], _out: &mut [f64]) {}
    /// [`Model::masses_at`].
    fn masses(&self, _t: f64, _x: &[f64], _out: &mut [f64]) {}
    /// [`Model::mass_matrix`].
    fn mass_matrix(&self, _t: f64, _x: &[f64]) -> Option<Matrix> {
        None
    }

    /// At an event at `t` (the switches `switched` changed sign, the
    /// regime was `before` and is now the model's own, the state was
    /// `x_before` and is `x` after any resets): a system that carries more
    /// than the motion (the sensitivities, `crate::sensitivity`) updates
    /// it in `x`. Nothing for a model.
    fn event_jump(
        &self,
        _before: &Regime,
        _switched: &[usize],
        _t: f64,
        _x_before: &[f64],
        _x: &mut [f64],
    ) -> Result<(), Failure> {
        Ok(())
    }
}

impl<M: Model + 'static> DynModel for M {
    fn name(&self) -> &'static str {
        M::NAME
    }
    fn source_hash(&self) -> &'static str {
        M::SOURCE_HASH
    }
    fn param_names(&self) -> &'static [&'static str] {
        M::PARAMS
    }
    fn state_names(&self) -> &'static [&'static str] {
        M::STATE
    }
    fn coordinates(&self) -> usize {
        M::COORDINATES
    }
    fn initial_kinds(&self) -> &'static [Initial] {
        M::INITIAL
    }
    fn output_names(&self) -> &'static [&'static str] {
        M::OUTPUTS
    }
    fn mass_names(&self) -> &'static [&'static str] {
        M::MASSES
    }
    fn input_names(&self) -> &'static [&'static str] {
        M::INPUTS
    }
    fn input_defaults(&self) -> &'static [f64] {
        M::INPUT_DEFAULTS
    }
    fn declared_integrator(&self) -> Option<IntegratorChoice> {
        M::DECLARED_INTEGRATOR
    }
    fn switches(&self) -> usize {
        M::SWITCHES
    }
    fn constraints(&self) -> &'static [Candidates] {
        M::CONSTRAINTS
    }
    fn impacts(&self) -> &'static [&'static str] {
        M::IMPACTS
    }
    fn affine(&self) -> bool {
        M::AFFINE
    }
    fn coefficients_linear(&self) -> bool {
        M::COEFFICIENTS_LINEAR
    }
    fn autonomous(&self) -> bool {
        M::AUTONOMOUS
    }
    fn states_exact(&self) -> bool {
        M::EXACT
    }
    fn keeps_constraints(&self) -> bool {
        M::KEEPS_CONSTRAINTS
    }
    fn keeps_positions(&self) -> bool {
        M::KEEPS_POSITIONS
    }
    fn fixed_components(&self) -> &'static [&'static [usize]] {
        M::FIXED
    }
    fn has_param_jacobian(&self) -> bool {
        M::PARAM_JACOBIAN
    }
    fn impact_targets(&self) -> &'static [&'static [usize]] {
        M::IMPACT_TARGETS
    }
    fn param_jacobian(&self, t: f64, x: &[f64], jac: &mut Matrix) -> Result<(), Failure> {
        Model::param_jacobian(self, t, x, jac)
    }
    fn parameters(&self, overrides: &[Option<f64>]) -> Vec<f64> {
        M::parameters(overrides)
    }
    fn with_params(&self, params: &[f64]) -> Box<dyn DynModel> {
        Box::new(M::new(params))
    }
    fn boxed_clone(&self) -> Box<dyn DynModel> {
        Box::new(self.clone())
    }
    fn param_values(&self) -> &[f64] {
        Model::param_values(self)
    }
    fn time_span(&self) -> (f64, f64) {
        Model::time_span(self)
    }
    fn initial_state(&self, given: &[Option<f64>]) -> Result<Vec<f64>, Failure> {
        Model::initial_state(self, given)
    }
    fn set_regime(&mut self, regime: &Regime) {
        Model::set_regime(self, regime);
    }
    fn set_inputs(&mut self, inputs: &Inputs) {
        Model::set_inputs(self, inputs);
    }
    fn rhs(&self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), Failure> {
        Model::rhs(self, t, x, dx)
    }
    fn has_lanes(&self) -> bool {
        M::LANES
    }
    fn rhs_lanes(&self, t: f64, x: &[Lanes], dx: &mut [Lanes]) -> Result<(), Failure> {
        Model::rhs_lanes(self, t, x, dx)
    }
    fn jacobian(&self, t: f64, x: &[f64], jac: &mut Matrix) -> Result<(), Failure> {
        Model::jacobian(self, t, x, jac)?;
        repair_jacobian(self, t, x, jac)
    }
    fn time_partial(&self, t: f64, x: &[f64], dxdt: &mut [f64]) -> Result<(), Failure> {
        Model::time_partial(self, t, x, dxdt)
    }
    fn linearize(
        &self,
        t: f64,
        x: &[f64],
        dx: &mut [f64],
        jac: &mut Matrix,
    ) -> Result<(), Failure> {
        Model::linearize(self, t, x, dx, jac)?;
        repair_jacobian(self, t, x, jac)
    }
    fn coefficients(&self, t: f64, f: &[f64], df: &mut [f64]) -> Result<(), Failure> {
        Model::coefficients(self, t, f, df)
    }
    fn coefficient_jacobian(&self, t: f64, f: &[f64], jac: &mut Matrix) -> Result<(), Failure> {
        Model::coefficient_jacobian(self, t, f, jac)
    }
    fn coefficient_time_partial(&self, t: f64, f: &[f64], dfdt: &mut [f64]) -> Result<(), Failure> {
        Model::coefficient_time_partial(self, t, f, dfdt)
    }
    fn exact(&self, t: f64, out: &mut [Option<f64>]) {
        Model::exact(self, t, out);
    }
    fn constrained(&self, t: f64, x: &[f64], kept: &mut [f64]) -> Result<(), Failure> {
        Model::constrained(self, t, x, kept)
    }
    fn kept_gradient(&self, t: f64, x: &[f64], jac: &mut Matrix) -> Result<(), Failure> {
        Model::kept_gradient(self, t, x, jac)
    }
    fn project_closure(
        &self,
        t: f64,
        x: &mut [f64],
        partition: Option<Dependents>,
    ) -> Result<(), Failure> {
        Model::project_closure(self, t, x, partition)
    }
    fn outputs(&self, t: f64, x: &[f64], out: &mut [f64]) {
        Model::outputs(self, t, x, out);
    }
    fn switching_functions(&self, t: f64, x: &[f64], g: &mut [f64]) {
        Model::switching_functions(self, t, x, g);
    }
    fn stop(&self, branches: &[bool]) -> bool {
        Model::stop(self, branches)
    }
    fn impact_holds(&self, w: usize, branches: &[bool]) -> bool {
        Model::impact_holds(self, w, branches)
    }
    fn impact_reset(&self, w: usize, t: f64, x: &[f64], out: &mut [f64]) {
        Model::impact_reset(self, w, t, x, out);
    }
    fn pivots(&self, t: f64, x: &[f64], out: &mut [f64]) {
        Model::pivots(self, t, x, out);
    }
    fn domains(&self) -> &'static [Domain] {
        M::DOMAINS
    }
    fn domain_values(&self, t: f64, x: &[f64], out: &mut [f64]) {
        Model::domain_values(self, t, x, out);
    }
    fn masses(&self, t: f64, x: &[f64], out: &mut [f64]) {
        Model::masses_at(self, t, x, out);
    }
    fn mass_matrix(&self, t: f64, x: &[f64]) -> Option<Matrix> {
        Model::mass_matrix(self, t, x)
    }
}

/// Replaces the columns of an exact Jacobian that are not finite at a
/// finite state by central differences of the right side. The symbolic
/// derivative of a right side that is smooth there can be `0/0`: drag
/// `|v| v_x` written `sqrt(x'^2 + y'^2) * x'` has `∂/∂x' = |v| + x'^2/|v|`,
/// NaN for a body at rest, where its limit is 0 (the field method, which
/// linearises at every stage, stopped at t = 0 on every such model started
/// from rest). Costs one pass over the entries where all are finite.
fn repair_jacobian<M: Model>(
    model: &M,
    t: f64,
    x: &[f64],
    jac: &mut Matrix,
) -> Result<(), Failure> {
    if jac.is_finite() || x.iter().any(|v| !v.is_finite()) {
        return Ok(());
    }
    let n = x.len();
    let (mut shifted, mut ahead, mut behind) = (x.to_vec(), vec![0.0; n], vec![0.0; n]);
    for j in 0..n {
        if jac.column(j).iter().all(|v| v.is_finite()) {
            continue;
        }
        // The step that balances truncation and rounding for a central
        // difference.
        let h = f64::EPSILON.cbrt() * x[j].abs().max(1.0);
        shifted[j] = x[j] + h;
        model.rhs(t, &shifted, &mut ahead)?;
        shifted[j] = x[j] - h;
        model.rhs(t, &shifted, &mut behind)?;
        shifted[j] = x[j];
        for (i, (a, b)) in ahead.iter().zip(&behind).enumerate() {
            jac[(i, j)] = (a - b) / (2.0 * h);
        }
    }
    Ok(())
}
