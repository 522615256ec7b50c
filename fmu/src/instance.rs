//! One FMU instance: the FMI 2.0 co-simulation state machine over a
//! lagc model, in safe Rust (the C layer, `ffi.rs`, only converts).
//!
//! Value references number the model's variables in one sequence, the
//! order lagc writes them into modelDescription.xml: the params
//! (`Model::PARAMS`), the state (`Model::STATE`: `q1`, `der(q1)`, …), the
//! outputs (`Model::OUTPUTS`), the inputs (`Model::INPUTS`).

use lagc_runtime::driver::{Ending, Options};
use lagc_runtime::failure::{Failure, FailureKind};
use lagc_runtime::integration::{Advance, Integration};
use lagc_runtime::model::{DynModel, Initial, Inputs};

/// Where an instance stands in FMI's state machine.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    Instantiated,
    Initialization,
    Stepping,
    /// `stop when` ended the motion (the importer sees fmi2Terminated).
    Ended,
    Terminated,
    /// A failure: only fmi2Reset, fmi2FreeInstance and the getters help.
    Failed,
}

/// What a variable's value reference names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Variable {
    Param(usize),
    State(usize),
    Output(usize),
    Input(usize),
}

/// An error: the message goes to the importer's logger, the status is
/// fmi2Error (a bad call or a failure of the motion).
#[derive(Clone, Debug, PartialEq)]
pub struct Error(pub String);

impl From<Failure> for Error {
    fn from(failure: Failure) -> Error {
        Error(failure.to_string())
    }
}

/// A step's result short of an error.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Stepped {
    /// At the communication point asked for.
    Done,
    /// `stop when` ended the motion at this time (fmi2Discard, and
    /// fmi2Terminated in the status).
    Ended(f64),
}

/// A saved instance (fmi2GetFMUstate).
pub struct Saved {
    phase: Phase,
    t: f64,
    x: Vec<f64>,
    inputs: Vec<f64>,
    overrides: Vec<Option<f64>>,
    changed: bool,
}

/// The bytes of a serialized state start with these (and a format
/// number), so that foreign bytes are refused, not misread.
const SERIAL_MAGIC: &[u8; 8] = b"lagcFMU1";

impl Saved {
    /// The saved instance (and the time `stop when` ended it at, if it
    /// did) as bytes (fmi2SerializeFMUstate): little-endian numbers
    /// after [`SERIAL_MAGIC`], the phase and flags, then `t`, the
    /// state, the inputs and the param overrides, each list after its
    /// length.
    pub fn to_bytes(&self, ended_at: Option<f64>) -> Vec<u8> {
        let mut out = SERIAL_MAGIC.to_vec();
        let phase = PHASES.iter().position(|p| *p == self.phase).unwrap_or(0);
        out.extend([phase as u8, u8::from(self.changed)]);
        let mut number = |v: f64| out.extend(v.to_le_bytes());
        number(self.t);
        number(ended_at.unwrap_or(f64::NAN));
        for list in [&self.x, &self.inputs] {
            number(list.len() as f64);
            list.iter().for_each(|&v| number(v));
        }
        number(self.overrides.len() as f64);
        for o in &self.overrides {
            // A param the importer did not set is NaN (a set one is finite).
            number(o.unwrap_or(f64::NAN));
        }
        out
    }

    /// [`Saved::to_bytes`] read back, checked against this instance's
    /// model (its dimension, inputs and params): an error in words for
    /// bytes of another model or none of lagc's.
    pub fn from_bytes(bytes: &[u8], instance: &Instance) -> Result<(Saved, Option<f64>), Error> {
        let refuse = |why: &str| Error(format!("the serialized FMU state is {why}"));
        let rest = bytes
            .strip_prefix(SERIAL_MAGIC.as_slice())
            .ok_or_else(|| refuse("not one of this FMU's"))?;
        let (&[phase, changed], rest) = rest
            .split_first_chunk::<2>()
            .ok_or_else(|| refuse("cut short"))?;
        let phase = *PHASES
            .get(phase as usize)
            .ok_or_else(|| refuse("corrupt"))?;
        let mut numbers = rest
            .chunks_exact(8)
            .map(|c| f64::from_le_bytes(c.try_into().unwrap_or([0; 8])));
        if rest.len() % 8 != 0 {
            return Err(refuse("corrupt"));
        }
        let mut next = || numbers.next().ok_or_else(|| refuse("cut short"));
        let t = next()?;
        let ended_at = Some(next()?).filter(|v| !v.is_nan());
        let m = &*instance.prototype;
        let sizes = [m.dim(), m.input_names().len(), m.param_names().len()];
        let mut lists: Vec<Vec<f64>> = Vec::new();
        for size in sizes {
            let len = next()?;
            if len != size as f64 {
                return Err(refuse("of another model"));
            }
            lists.push((0..size).map(|_| next()).collect::<Result<_, _>>()?);
        }
        if next().is_ok() {
            return Err(refuse("longer than a state of this model"));
        }
        let overrides = lists.pop().unwrap_or_default();
        let inputs = lists.pop().unwrap_or_default();
        let x = lists.pop().unwrap_or_default();
        let saved = Saved {
            phase,
            t,
            x,
            inputs,
            overrides: overrides
                .into_iter()
                .map(|v| (!v.is_nan()).then_some(v))
                .collect(),
            changed: changed != 0,
        };
        Ok((saved, ended_at))
    }
}

/// The phases by their number in a serialized state.
const PHASES: [Phase; 6] = [
    Phase::Instantiated,
    Phase::Initialization,
    Phase::Stepping,
    Phase::Ended,
    Phase::Terminated,
    Phase::Failed,
];

/// One instance of a model.
pub struct Instance {
    prototype: Box<dyn DynModel>,
    pub phase: Phase,
    /// Params the importer set (the others follow from them).
    overrides: Vec<Option<f64>>,
    /// Initial values the importer set (state components the model states).
    given: Vec<Option<f64>>,
    inputs: Vec<f64>,
    /// `tunable[i]`: param `i` may be set between steps.
    tunable: Vec<bool>,
    /// An input or a tuned param changed and the integration has not
    /// restarted with it yet (set before initialization ended, or saved
    /// so).
    changed: bool,
    pub options: Options,
    start: Option<f64>,
    stop: Option<f64>,
    /// The model's integration (it owns the model with the params), from
    /// initialization on: every fmi2DoStep advances it, so the steps are
    /// the integrator's own, never cut at communication points.
    integration: Option<Integration<'static>>,
    /// Provisional initial state (during initialization mode).
    x: Vec<f64>,
    pub t: f64,
    outputs: Vec<f64>,
}

impl Instance {
    /// A new instance of the model `prototype` is one of.
    pub fn new(prototype: Box<dyn DynModel>) -> Instance {
        let inputs = prototype.input_defaults().to_vec();
        let params = prototype.param_names().len();
        let dim = prototype.dim();
        let outputs = prototype.output_names().len();
        Instance {
            phase: Phase::Instantiated,
            overrides: vec![None; params],
            given: vec![None; dim],
            inputs,
            tunable: vec![false; params],
            changed: false,
            options: Options::default(),
            start: None,
            stop: None,
            integration: None,
            t: prototype.time_span().0,
            x: vec![f64::NAN; dim],
            outputs: vec![f64::NAN; outputs],
            prototype,
        }
    }

    /// The instance with params `tunable` (by index) settable between
    /// steps.
    pub fn with_tunable(mut self, tunable: &[usize]) -> Instance {
        for &i in tunable {
            if let Some(t) = self.tunable.get_mut(i) {
                *t = true;
            }
        }
        self
    }

    /// The model's source hash: the FMU's GUID.
    pub fn source_hash(&self) -> &'static str {
        self.prototype.source_hash()
    }

    /// Back to the state after instantiation (fmi2Reset).
    pub fn reset(&mut self) {
        let prototype = self.prototype.boxed_clone();
        let tunable = std::mem::take(&mut self.tunable);
        *self = Instance::new(prototype);
        self.tunable = tunable;
    }

    /// The variable of value reference `vr`.
    pub fn variable(&self, vr: u32) -> Result<Variable, Error> {
        let m = &*self.prototype;
        let sizes = [
            m.param_names().len(),
            m.dim(),
            m.output_names().len(),
            m.input_names().len(),
        ];
        let mut rest = vr as usize;
        for (kind, size) in sizes.into_iter().enumerate() {
            if rest < size {
                return Ok(match kind {
                    0 => Variable::Param(rest),
                    1 => Variable::State(rest),
                    2 => Variable::Output(rest),
                    _ => Variable::Input(rest),
                });
            }
            rest -= size;
        }
        Err(Error(format!("no variable has the value reference {vr}")))
    }

    /// fmi2SetupExperiment: the tolerance (relative; the absolute one is
    /// scaled with it) and the span.
    pub fn setup(
        &mut self,
        tolerance: Option<f64>,
        start: f64,
        stop: Option<f64>,
    ) -> Result<(), Error> {
        self.expect(&[Phase::Instantiated], "fmi2SetupExperiment")?;
        if let Some(rtol) = tolerance {
            if rtol.is_nan() || rtol <= 0.0 || rtol >= 1.0 {
                return Err(Error(format!("the tolerance {rtol} is not in (0, 1)")));
            }
            let default = Options::default().tol;
            self.options.tol.rtol = rtol;
            self.options.tol.atol = default.atol * rtol / default.rtol;
        }
        let t0 = self.prototype.time_span().0;
        if start != t0 {
            return Err(Error(format!(
                "the start time {start} is not the model's t0 = {t0}, where its initial \
                 values are stated"
            )));
        }
        if let Some(stop) = stop {
            if stop.partial_cmp(&start) != Some(std::cmp::Ordering::Greater) {
                return Err(Error(format!("the stop time {stop} is not after {start}")));
            }
        }
        self.start = Some(start);
        self.stop = stop;
        Ok(())
    }

    pub fn enter_initialization(&mut self) -> Result<(), Error> {
        self.expect(&[Phase::Instantiated], "fmi2EnterInitializationMode")?;
        self.phase = Phase::Initialization;
        Ok(())
    }

    /// The model with the params set and its initial state under the
    /// initial values and inputs set, checked as `--param`/`--init` are;
    /// with `start`, its integration from there.
    fn initialize(&mut self, start: bool) -> Result<(), Error> {
        let params = self.prototype.parameters(&self.overrides);
        let mut model = self.prototype.with_params(&params);
        model.set_inputs(&Inputs::held(&self.inputs));
        let (t0, t1) = model.time_span();
        if !(t0.is_finite() && t1.is_finite() && t1 > t0) {
            return Err(Failure::new(t0, FailureKind::BadTimeSpan { t0, t1 }).into());
        }
        let x0 = model.initial_state(&self.given)?;
        if let Some(i) = x0.iter().position(|v| !v.is_finite()) {
            return Err(Failure::new(
                t0,
                FailureKind::NonFiniteInitialValue {
                    component: model.state_names()[i].to_string(),
                },
            )
            .into());
        }
        lagc_runtime::driver::check_initial_candidates(&*model, t0, &x0)?;
        self.t = t0;
        self.x.clone_from(&x0);
        if start {
            // The steps may reach the stop time the importer gave, else
            // the model's own span.
            let end = self.stop.unwrap_or(t1);
            self.integration = Some(Integration::owned(model, &self.options, t0, end, &x0));
        }
        self.changed = false;
        Ok(())
    }

    pub fn exit_initialization(&mut self) -> Result<(), Error> {
        self.expect(&[Phase::Initialization], "fmi2ExitInitializationMode")?;
        self.initialize(true)?;
        self.phase = Phase::Stepping;
        Ok(())
    }

    pub fn terminate(&mut self) -> Result<(), Error> {
        self.expect(&[Phase::Stepping, Phase::Ended], "fmi2Terminate")?;
        self.phase = Phase::Terminated;
        Ok(())
    }

    fn expect(&self, phases: &[Phase], call: &str) -> Result<(), Error> {
        if phases.contains(&self.phase) {
            Ok(())
        } else {
            Err(Error(format!(
                "{call} is not allowed now (the instance is {:?})",
                self.phase
            )))
        }
    }

    pub fn get_real(&mut self, vr: u32) -> Result<f64, Error> {
        let variable = self.variable(vr)?;
        let outputs = &mut self.outputs;
        Ok(match (variable, &self.integration) {
            (Variable::Param(i), _) => self.prototype.parameters(&self.overrides)[i],
            (Variable::Input(i), _) => self.inputs[i],
            (Variable::State(i), Some(integration)) => integration.state()[i],
            (Variable::Output(i), Some(integration)) => {
                integration
                    .model()
                    .outputs(integration.t(), integration.state(), outputs);
                outputs[i]
            }
            (Variable::State(i), None) if self.phase == Phase::Initialization => {
                // The initial state as it stands (calculated values follow
                // the params and start values set so far).
                self.initialize(false)?;
                self.x[i]
            }
            (Variable::State(i), None) => self.given[i].unwrap_or(f64::NAN),
            (Variable::Output(_), None) => f64::NAN,
        })
    }

    /// The Integer variables, structural parameters of the run: value
    /// reference 0 the method (0 the field method, 1 direct integration),
    /// 1 the integrator (0 the model's `integrator` statement, else auto;
    /// 1 auto, 2 explicit, 3 stiff, 4 Magnus).
    pub fn get_integer(&self, vr: u32) -> Result<i32, Error> {
        use lagc_runtime::method::{IntegratorChoice, Method};
        match vr {
            0 => Ok(match self.options.method {
                Method::Field => 0,
                Method::Direct => 1,
            }),
            1 => Ok(match self.options.integrator {
                None => 0,
                Some(IntegratorChoice::Auto) => 1,
                Some(IntegratorChoice::Explicit) => 2,
                Some(IntegratorChoice::Stiff) => 3,
                Some(IntegratorChoice::Magnus) => 4,
            }),
            _ => Err(Error(format!(
                "no Integer variable has the value reference {vr}"
            ))),
        }
    }

    pub fn set_integer(&mut self, vr: u32, value: i32) -> Result<(), Error> {
        use lagc_runtime::method::{IntegratorChoice, Method};
        if !matches!(self.phase, Phase::Instantiated | Phase::Initialization) {
            return Err(Error(
                "the method and the integrator are fixed after initialization".to_string(),
            ));
        }
        match (vr, value) {
            (0, 0) => self.options.method = Method::Field,
            (0, 1) => self.options.method = Method::Direct,
            (1, 0) => self.options.integrator = None,
            (1, 1) => self.options.integrator = Some(IntegratorChoice::Auto),
            (1, 2) => self.options.integrator = Some(IntegratorChoice::Explicit),
            (1, 3) => self.options.integrator = Some(IntegratorChoice::Stiff),
            (1, 4) => self.options.integrator = Some(IntegratorChoice::Magnus),
            (0 | 1, _) => {
                return Err(Error(format!(
                    "{value} is no {} (see the variable's description)",
                    if vr == 0 { "method" } else { "integrator" }
                )))
            }
            _ => {
                return Err(Error(format!(
                    "no Integer variable has the value reference {vr}"
                )))
            }
        }
        Ok(())
    }

    pub fn set_real(&mut self, vr: u32, value: f64) -> Result<(), Error> {
        let variable = self.variable(vr)?;
        let before = matches!(self.phase, Phase::Instantiated | Phase::Initialization);
        let name = |names: &[&str], i: usize| names.get(i).copied().unwrap_or("?").to_string();
        if !value.is_finite() {
            return Err(Error(format!(
                "{value} is not a finite value (reference {vr})"
            )));
        }
        match variable {
            Variable::Param(i) if before => self.overrides[i] = Some(value),
            Variable::Param(i) if self.phase == Phase::Stepping && self.tunable[i] => {
                // The integration restarts with it (and the params
                // computed from it), as at an input's change.
                if self.overrides[i] != Some(value) {
                    self.overrides[i] = Some(value);
                    self.changed = true;
                }
            }
            Variable::Param(i) => {
                return Err(Error(format!(
                    "the param `{}` is fixed after initialization{}",
                    name(self.prototype.param_names(), i),
                    if self.tunable[i] {
                        ""
                    } else {
                        " (it enters the Lagrangian, a mass law, a position, a holonomic \
                         constraint, a `when` or the time span, where a jump would be an \
                         impulse the restart does not model)"
                    }
                )))
            }
            Variable::State(i) if before && self.prototype.initial_kinds()[i] == Initial::Given => {
                self.given[i] = Some(value)
            }
            Variable::State(i) => {
                return Err(Error(format!(
                    "`{}` cannot be set: {}",
                    name(self.prototype.state_names(), i),
                    if before {
                        "the constraints (or the equations of motion) fix it"
                    } else {
                        "the state is the motion's after initialization"
                    }
                )))
            }
            Variable::Output(i) => {
                return Err(Error(format!(
                    "the output `{}` cannot be set",
                    name(self.prototype.output_names(), i)
                )))
            }
            Variable::Input(i) => {
                if self.inputs[i] != value {
                    self.inputs[i] = value;
                    self.changed = true;
                }
            }
        }
        if self.phase == Phase::Stepping {
            // At once, so that outputs read before the next step see the
            // new values (an output of an input is direct feedthrough).
            self.apply_changes()?;
        }
        Ok(())
    }

    /// New inputs, or tuned params, while stepping: a discontinuity, the
    /// integration restarts where it stands (the components the
    /// constraints fix recomputed, the others carried over).
    fn apply_changes(&mut self) -> Result<(), Error> {
        let Some(integration) = self.integration.as_mut().filter(|_| self.changed) else {
            return Ok(());
        };
        let params = self.prototype.parameters(&self.overrides);
        let inputs = Inputs::held(&self.inputs);
        if integration.model().param_values() == params.as_slice() {
            integration.set_inputs(&inputs)?;
        } else {
            let model = self.prototype.with_params(&params);
            let (t, x) = (integration.t(), integration.state().to_vec());
            integration.restart_with_model(model, t, &x, &inputs)?;
        }
        self.changed = false;
        Ok(())
    }

    /// fmi2DoStep from `t` (which must be where the instance stands) over
    /// `h`. Inputs and tuned params set while stepping restarted the
    /// integration when they were set; one still pending (a restored
    /// state saved so) restarts it here first.
    pub fn do_step(&mut self, t: f64, h: f64) -> Result<Stepped, Error> {
        self.expect(&[Phase::Stepping], "fmi2DoStep")?;
        let scale = t.abs().max(h.abs()).max(1.0);
        if (t - self.t).abs() > 1e-12 * scale {
            return Err(Error(format!(
                "fmi2DoStep from t = {t}, but the instance stands at t = {}",
                self.t
            )));
        }
        if !h.is_finite() || h <= 0.0 {
            return Err(Error(format!("the step size {h} is not positive")));
        }
        let end = self.t + h;
        if let Some(stop) = self.stop {
            if end > stop + 1e-12 * scale {
                return Err(Error(format!("t = {end} is past the stop time {stop}")));
            }
        }
        self.apply_changes()?;
        let integration = self
            .integration
            .as_mut()
            .expect("stepping has an integration");
        // A last step that lands on the stop time up to rounding ends there.
        let end = end.min(integration.end());
        match integration.advance_to(end)? {
            Advance::Reached(_) => {
                self.t = end;
                Ok(Stepped::Done)
            }
            Advance::Ended(ending) => {
                let at = match ending {
                    Ending::Stopped(at) | Ending::Rest { at, .. } => at,
                    Ending::End => integration.t(),
                };
                self.t = integration.t();
                self.phase = Phase::Ended;
                Ok(Stepped::Ended(at))
            }
        }
    }

    /// The integration's work so far (for the importer's log).
    pub fn outcome(&self) -> Option<lagc_runtime::driver::Outcome> {
        self.integration.as_ref().map(|i| i.outcome())
    }

    pub fn save(&self) -> Saved {
        let x = match &self.integration {
            Some(integration) => integration.state().to_vec(),
            None => self.x.clone(),
        };
        Saved {
            phase: self.phase,
            t: self.t,
            x,
            inputs: self.inputs.clone(),
            overrides: self.overrides.clone(),
            changed: self.changed,
        }
    }

    /// Goes back to a saved instance: the integration restarts from the
    /// saved state (the importer rolled the time back), under the inputs
    /// and param values saved with it.
    pub fn restore(&mut self, saved: &Saved) -> Result<(), Error> {
        if self.integration.is_none() && matches!(saved.phase, Phase::Stepping | Phase::Ended) {
            // A stepping state set on an instance not yet stepping (FMI
            // allows it after instantiation; a deserialized state): its
            // integration made first, under the saved values.
            self.overrides.clone_from(&saved.overrides);
            self.inputs.clone_from(&saved.inputs);
            self.initialize(true)?;
        }
        if let Some(integration) = self.integration.as_mut() {
            let inputs = Inputs::held(&saved.inputs);
            let params = self.prototype.parameters(&saved.overrides);
            if integration.model().param_values() == params.as_slice() {
                integration.restart_with_inputs(saved.t, &saved.x, &inputs)?;
            } else {
                let model = self.prototype.with_params(&params);
                integration.restart_with_model(model, saved.t, &saved.x, &inputs)?;
            }
        }
        self.overrides.clone_from(&saved.overrides);
        self.phase = saved.phase;
        self.t = saved.t;
        self.x.clone_from(&saved.x);
        self.inputs.clone_from(&saved.inputs);
        self.changed = saved.changed;
        Ok(())
    }
}
