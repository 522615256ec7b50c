//! Forward sensitivities (issue 27): `S = ∂x(t)/∂(y0, p)`, one column per
//! initial value the model states and per param, by the variational
//! equations `S' = J S + ∂X/∂p` integrated with the motion as one
//! augmented system (the direct method on `N + N·m` components). The
//! sensitivities are ordinary components of that system, so they are
//! inside the error control (CVODES' `errconS`), and the dense output,
//! the step control and the failures are the run's own.
//!
//! [`Augmented`] is that system as a [`DynModel`] over the model: `J` and
//! `∂X/∂p` are the model's exact symbolic partials (`jacobian`,
//! `param_jacobian`); only what RODAS4 needs beyond them — the partials of
//! `J S + ∂X/∂p` in `x` and `t`, second derivatives of the motion — are
//! central differences of those exact partials.
//!
//! Events: at a switch or an impact at `τ` the sensitivities jump,
//! `S⁺ = R_x S⁻ + R_p + (R_x f⁻ − f⁺) dτ` (the identity `R` at a switch;
//! `Augmented::jump`, called by the run through `DynModel::event_jump`).
//! Where impacts accumulate (a ball at rest) the motion has no derivative
//! in its start and the command line writes `NaN` there.
//!
//! Run-time candidates (`for y' or x'`): every mode integrates the same
//! state, and the modes' right sides agree on the constraints (so do their
//! Jacobians along them, params included), where `S` lies; a change of
//! candidates is made at a step's end without a located event, so `S`
//! goes on unchanged across it (checked against differences of runs on
//! knife_edge_turning and chaplygin_sleigh).
//!
//! Holonomic constraints (positions kept on `f(t, q, p) = 0` by the
//! run's projection, `project_closure`): the start's columns come from
//! the model's completion of the start (Newton on the closure), moved
//! value by value, or, where a move contradicts a value the model states,
//! from the tangent through the projection's derivative (`tangent`);
//! the augmented run projects as the run does, `x ← P(x)` and
//! `S ← P_x S + P_p dp/dp` (`Augmented::project`). Without that, the
//! columns' part across the constraints grows as the motion's drift does
//! (the four-bar's augmented run failed at t = 47 with nothing projected,
//! at t = 76 with `x` alone projected; docs/SENSITIVITY.md).
//!
//! What is not covered is refused ([`unsupported`]): inputs following a
//! schedule, and models without `param_jacobian`. Velocity constraints
//! the run keeps by projection are not kept on the augmented system: its
//! motion is the reduced system's own (on which they are invariant), and
//! the command line prints the state from the ordinary run beside it.

use std::cell::RefCell;

use crate::choice::{IntegratorChoice, Method};
use crate::closure::Dependents;
use crate::failure::Failure;
use crate::linalg::Matrix;
use crate::model::{Candidates, Domain, DynModel, Initial, Inputs, Regime};
use crate::run::options::{Ending, Options};
use crate::run::regime::{best_mode, initial_branches};
use crate::run::run;

/// Why `--sensitivity` is refused for this model, or `None`.
pub fn unsupported(model: &dyn DynModel) -> Option<String> {
    if !model.param_names().is_empty() && !model.has_param_jacobian() {
        return Some(format!(
            "`--sensitivity`: the model `{}` was built without `∂X/∂p` (a mass law that \
             switches)",
            model.name()
        ));
    }
    None
}

/// The columns of `S`: the state components the model states (`Y0`, or
/// `Y(t0)` where a param is called `Y0`), then the params.
pub fn column_names(model: &dyn DynModel) -> Vec<String> {
    let params = model.param_names();
    let mut names: Vec<String> = given_components(model)
        .into_iter()
        .map(|i| {
            let y = model.state_names()[i];
            let short = format!("{y}0");
            if params.contains(&short.as_str()) {
                format!("{y}(t0)")
            } else {
                short
            }
        })
        .collect();
    names.extend(model.param_names().iter().map(|p| p.to_string()));
    names
}

/// The CSV headers `d(X)/d(Y0)`, `d(X)/d(P)`, column by column of `S`
/// (each column's state components in order).
pub fn headers(model: &dyn DynModel) -> Vec<String> {
    let mut out = Vec::new();
    for y in column_names(model) {
        for x in model.state_names() {
            out.push(format!("d({x})/d({y})"));
        }
    }
    out
}

/// The components whose initial values the model states.
pub fn given_components(model: &dyn DynModel) -> Vec<usize> {
    (0..model.dim())
        .filter(|&i| model.initial_kinds().get(i) == Some(&Initial::Given))
        .collect()
}

/// A central difference refined by one Richardson step (error `O(h⁴)`):
/// for the algebraic maps at the start (the initial state, the params
/// computed from others, the time span), where the values are cheap and
/// smooth. At `h = 1e-3·max(|v|, floor)` (`1e-3` at 0) the truncation is
/// `~1e-12` relative for maps of the size of their arguments, and rounding
/// `~1e-13`. Params move relative to their value (floor 0: a param of
/// 1e-6 is not moved through 0), state components and `t` by at least
/// 1e-3 (floor 1: a height of 1e-17 at a bounce is not a scale).
fn derivative(
    v: f64,
    floor: f64,
    f: &mut dyn FnMut(f64) -> Result<Vec<f64>, Failure>,
) -> Result<Vec<f64>, Failure> {
    let h = 1e-3 * v.abs().max(floor);
    let h = if h > 0.0 { h } else { 1e-3 };
    let central = |f: &mut dyn FnMut(f64) -> Result<Vec<f64>, Failure>,
                   h: f64|
     -> Result<Vec<f64>, Failure> {
        let (a, b) = (f(v + h)?, f(v - h)?);
        Ok(a.iter().zip(&b).map(|(a, b)| (a - b) / (2.0 * h)).collect())
    };
    let coarse = central(f, h)?;
    let fine = central(f, h / 2.0)?;
    Ok(fine
        .iter()
        .zip(&coarse)
        .map(|(f, c)| (4.0 * f - c) / 3.0)
        .collect())
}

/// What the sensitivities need of an invocation: the params it overrides
/// and the initial values it states (as `prepare` takes them).
pub struct Start<'a> {
    pub prototype: &'a dyn DynModel,
    pub overrides: &'a [Option<f64>],
    pub given: &'a [Option<f64>],
}

/// The augmented system's start: `chain` (`dp_k/dp_j`, row-major) and the
/// initial sensitivities `S(t0)` (column-major, `N × m`), for the model
/// `model` made from `start` with initial state `x0` at `t0`.
pub fn initial(
    model: &dyn DynModel,
    start: &Start,
    t0: f64,
    x0: &[f64],
) -> Result<(Vec<f64>, Vec<f64>), Failure> {
    let n = model.dim();
    let given = given_components(model);
    let np = model.param_names().len();
    let mut s0 = Vec::with_capacity(n * (given.len() + np));
    // The values the components stated take at the start, held while one
    // of them moves: the others, fixed by the constraints, follow.
    let held: Vec<Option<f64>> = (0..n)
        .map(|i| given.contains(&i).then_some(x0[i]))
        .collect();
    // (Newton on a closure may overwrite a given position: never unit
    // columns where positions are kept.)
    let all_given = given.len() == n && !model.keeps_positions();
    // Each column through the model's own completion of the start (Newton
    // on the closure, the constraints' derivatives): the implicit function
    // theorem, differentiated as the runs see it. A completion can refuse
    // a moved value ([`tangent`]).
    let completed: Vec<Result<Vec<f64>, Failure>> = given
        .iter()
        .map(|&j| {
            if all_given {
                let mut unit = vec![0.0; n];
                unit[j] = 1.0;
                return Ok(unit);
            }
            let mut moved = held.clone();
            derivative(x0[j], 0.0, &mut |v| {
                moved[j] = Some(v);
                model.initial_state(&moved)
            })
        })
        .collect();
    // The components the completion holds (a value it overwrites, a
    // position Newton puts on the closure, has a zero column).
    let free: Vec<usize> = given
        .iter()
        .zip(&completed)
        .filter(|(&j, c)| c.as_ref().map_or(true, |c| (c[j] - 1.0).abs() < 1e-6))
        .map(|(&j, _)| j)
        .collect();
    for (&j, column) in given.iter().zip(completed) {
        let column = match column {
            Ok(column) => column,
            Err(failure) if refused_move(&failure) && model.keeps_positions() => {
                tangent(model, t0, x0, &free, j)?
            }
            Err(failure) => return Err(not_differentiable(model, j, failure)),
        };
        s0.extend(column);
    }
    // A param moves the params computed from it, the initial values that
    // are its expressions, and `t0` (then `x(t)` moves by `−X(t0, x0)·dt0`).
    let params = start.prototype.parameters(start.overrides);
    // `X(t0, x0)` in the regime the run starts in (the model's default
    // branches may be the others).
    let mut at_start = model.boxed_clone();
    at_start.set_regime(&Regime {
        mode: best_mode(model, t0, x0).0,
        branches: initial_branches(model, t0, x0),
    });
    let mut f0 = vec![0.0; n];
    at_start.rhs(t0, x0, &mut f0)?;
    let mut chain = vec![0.0; np * np];
    for k in 0..np {
        let mut overrides = start.overrides.to_vec();
        // [params…, t0, x0…] with param k at `v`.
        let column = derivative(params[k], 0.0, &mut |v| {
            overrides[k] = Some(v);
            let p = start.prototype.parameters(&overrides);
            let moved = start.prototype.with_params(&p);
            let (t0, _) = moved.time_span();
            let mut out = p;
            out.push(t0);
            out.extend(moved.initial_state(start.given)?);
            Ok(out)
        })?;
        for (l, &d) in column[..np].iter().enumerate() {
            chain[l * np + k] = d;
        }
        let dt0 = column[np];
        s0.extend(column[np + 1..].iter().zip(&f0).map(|(dx, f)| dx - f * dt0));
    }
    Ok((chain, s0))
}

/// A completion that refuses a moved value: a value the model states
/// for a component the constraints fix no longer agrees (the bead in a
/// spinning tube states `y' = r0 w`, the tube's speed at `x0 = r0`).
/// Why the start has no derivative with respect to initial value `j`:
/// moved by a rounding's size it cannot be completed on the constraints
/// (a pendulum in x, y released level with its pivot: moving `x` past `l`
/// leaves `x² + y² = l²` with no `y`; the base said only that Newton
/// found no positions, not why a sensitivity run needed them).
fn not_differentiable(model: &dyn DynModel, j: usize, failure: Failure) -> Failure {
    let name = model.state_names().get(j).copied().unwrap_or("?");
    Failure::new(
        failure.time,
        crate::failure::FailureKind::Unsupported {
            message: format!(
                "--sensitivity: the start has no derivative with respect to the initial \
                 value of `{name}`: moved by a rounding's size, it cannot be completed on \
                 the constraints ({failure}). A start that cannot be moved is on a singular point of the \
                 constraints, where a dependent's pivot vanishes and the dependent \
                 moves infinitely fast with `{name}` (a pendulum in x, y released level \
                 with its pivot: y = ±√(l² − x²) at x = l). Ask the sensitivities at a \
                 start off the singular point (--init), or write the model in coordinates \
                 regular there (an angle)"
            ),
        },
    )
}

fn refused_move(failure: &Failure) -> bool {
    matches!(
        failure.kind,
        crate::failure::FailureKind::InconsistentInitialValue { .. }
    )
}

/// The tangent to the holonomic constraints at the start `x0` whose free
/// components (`free`, those the start's completion holds) are the unit
/// vector `e_j`: the column of a given value that no run can move alone
/// (its move contradicts a value the model states). The derivative `B`
/// of the run's projection (`project_closure`) at a point on the
/// constraints is idempotent with the tangent space as its range, so the
/// tangent is `B c` over the free columns with `(B c)_free = e_j`, the
/// implicit function theorem with the dependents solved by the
/// projection instead of the completion.
fn tangent(
    model: &dyn DynModel,
    t0: f64,
    x0: &[f64],
    free: &[usize],
    j: usize,
) -> Result<Vec<f64>, Failure> {
    let n = x0.len();
    let k = free.len();
    let mut columns = Vec::with_capacity(k);
    let mut moved = x0.to_vec();
    for &f in free {
        columns.push(derivative(x0[f], 1.0, &mut |v| {
            moved.copy_from_slice(x0);
            moved[f] = v;
            model.project_closure(t0, &mut moved, None)?;
            Ok(moved.clone())
        })?);
    }
    let mut block = Matrix::zeros(k, k);
    for (b, column) in columns.iter().enumerate() {
        for (a, &f) in free.iter().enumerate() {
            block[(a, b)] = column[f];
        }
    }
    let mut c: Vec<f64> = free.iter().map(|&f| f64::from(u8::from(f == j))).collect();
    let lu = crate::linalg::Lu::new(&block);
    if lu.is_singular() || !lu.solve_in_place(&mut c) {
        return Err(Failure::new(
            t0,
            crate::failure::FailureKind::Unsupported {
                message: format!(
                    "`--sensitivity`: the start's given values do not determine a tangent \
                     to the constraints along `{}`",
                    model.state_names()[j]
                ),
            },
        ));
    }
    Ok((0..n)
        .map(|i| columns.iter().zip(&c).map(|(col, c)| col[i] * c).sum())
        .collect())
}

/// Values computed from a model (a switching function, a reset).
type Values<'a> = dyn Fn(&dyn DynModel) -> Result<Vec<f64>, Failure> + 'a;

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(a, b)| a * b).sum()
}

/// The sensitivities at every time of `times` (each row `S` column by
/// column, `S[c·N + i] = ∂x_i/∂column c`) and a note for the summary: the
/// augmented system by the direct method whatever `options.method` says
/// (the integrator is the options'), from `model`'s start `(t0, x0)` made
/// as `start` says.
#[allow(clippy::too_many_arguments)]
pub fn sample(
    start: &Start,
    model: &dyn DynModel,
    options: &Options,
    t0: f64,
    t1: f64,
    x0: &[f64],
    times: &[f64],
) -> Result<(Vec<Vec<f64>>, String), Failure> {
    let (rows, note) = sample_until_failure(start, model, options, t0, t1, x0, times);
    note.map(|note| (rows, note))
}

/// [`sample`], keeping the rows made before a failure: the rows at the
/// times the augmented run reached (all of them when it did not fail), and
/// the note or the failure. A run that stops on a failure writes the rows
/// before it, with their sensitivities, as a run without them does.
#[allow(clippy::too_many_arguments)]
pub fn sample_until_failure(
    start: &Start,
    model: &dyn DynModel,
    options: &Options,
    t0: f64,
    t1: f64,
    x0: &[f64],
    times: &[f64],
) -> (Vec<Vec<f64>>, Result<String, Failure>) {
    let mut rows = Vec::with_capacity(times.len());
    let note = augmented_run(start, model, options, t0, t1, x0, times, &mut rows);
    (rows, note)
}

#[allow(clippy::too_many_arguments)]
fn augmented_run(
    start: &Start,
    model: &dyn DynModel,
    options: &Options,
    t0: f64,
    t1: f64,
    x0: &[f64],
    times: &[f64],
    rows: &mut Vec<Vec<f64>>,
) -> Result<String, Failure> {
    let (chain, s0) = initial(model, start, t0, x0)?;
    let mut augmented = Augmented::new(model.boxed_clone(), chain);
    let mut z0 = x0.to_vec();
    z0.extend(s0);
    let options = Options {
        method: Method::Direct,
        progress: false,
        // The augmented run's own estimate is not read (the sensitivities'
        // note is the summary's), and carried through the projection of
        // every column it cost most of a holonomic model's run.
        global_error: false,
        ..options.clone()
    };
    let n = model.dim();
    let mut last = t0;
    let outcome = run(&mut augmented, &options, t0, t1, &z0, times, |_, t, z| {
        rows.push(z[n..].to_vec());
        last = t;
        Ok(())
    })?;
    if let Ending::Rest { at, .. } = outcome.ending {
        // Where impacts accumulate the motion has no derivative in its
        // start: the row there is not a number, not the blown-up value.
        if last == at {
            if let Some(row) = rows.last_mut() {
                row.fill(f64::NAN);
            }
        }
    }
    let note = format!(
        "sensitivities: {} columns, the augmented system ({} components) by direct \
         integration ({}): {} steps, {} rejected",
        augmented.columns(),
        z0.len(),
        outcome.report.method,
        outcome.report.stats.accepted_steps,
        outcome.report.stats.rejected_steps
    );
    Ok(note)
}

/// The motion with its sensitivities: state `[x; S e_1; …; S e_m]`.
pub struct Augmented {
    inner: Box<dyn DynModel>,
    n: usize,
    /// The number of columns: the given initial values, then the params.
    columns: usize,
    given: usize,
    /// `dp_k/dp_j`, row-major `np × np`.
    chain: Vec<f64>,
    names: &'static [&'static str],
    /// No component of the augmented state is fixed by a velocity
    /// constraint in any mode (one empty slice per mode of the model): the
    /// holonomic constraints are kept by `Augmented::project` alone.
    unfixed: &'static [&'static [usize]],
    /// `variational`'s buffers: it runs a dozen times a step, and making
    /// `J` and `∂X/∂p` anew each time was a third of the bouncing ball's
    /// sensitivity run (perf: malloc and free; docs/BENCHMARKS.md §15).
    scratch: RefCell<Scratch>,
}

/// `J` (`N × N`), `∂X/∂p` and its chained total (`N × np`).
struct Scratch {
    jac: Matrix,
    partial: Matrix,
    total: Matrix,
}

impl Scratch {
    fn new(n: usize, np: usize) -> RefCell<Scratch> {
        RefCell::new(Scratch {
            jac: Matrix::zeros(n, n),
            partial: Matrix::zeros(n, np),
            total: Matrix::zeros(n, np),
        })
    }
}

impl Augmented {
    /// The augmented system of `inner` with this chain of params.
    pub fn new(inner: Box<dyn DynModel>, chain: Vec<f64>) -> Augmented {
        let n = inner.dim();
        let given = given_components(&*inner).len();
        let columns = given + inner.param_names().len();
        // The names live as long as the run's process (one small leak per
        // sensitivity run; `DynModel` hands out `'static` names).
        let mut names: Vec<&'static str> = inner.state_names().to_vec();
        for h in headers(&*inner) {
            names.push(Box::leak(h.into_boxed_str()));
        }
        let modes = inner.fixed_components().len().max(1);
        let unfixed: Vec<&'static [usize]> = vec![&[]; modes];
        Augmented {
            inner,
            n,
            columns,
            given,
            chain,
            names: Box::leak(names.into_boxed_slice()),
            unfixed: Box::leak(unfixed.into_boxed_slice()),
            scratch: Scratch::new(n, columns - given),
        }
    }

    /// The number of sensitivity columns.
    pub fn columns(&self) -> usize {
        self.columns
    }

    fn copy(&self) -> Augmented {
        Augmented {
            inner: self.inner.boxed_clone(),
            n: self.n,
            columns: self.columns,
            given: self.given,
            chain: self.chain.clone(),
            names: self.names,
            unfixed: self.unfixed,
            scratch: Scratch::new(self.n, self.columns - self.given),
        }
    }

    /// `total = ∂X/∂p · dp/dp` (`N × np`, the chain applied), `partial`
    /// holding `∂X/∂p`.
    fn param_partials(
        &self,
        t: f64,
        x: &[f64],
        partial: &mut Matrix,
        total: &mut Matrix,
    ) -> Result<(), Failure> {
        let np = self.columns - self.given;
        if np == 0 {
            return Ok(());
        }
        partial.fill(0.0);
        self.inner.param_jacobian(t, x, partial)?;
        total.fill(0.0);
        for j in 0..np {
            for k in 0..np {
                let c = self.chain[k * np + j];
                if c == 0.0 {
                    continue;
                }
                for i in 0..self.n {
                    total[(i, j)] += partial[(i, k)] * c;
                }
            }
        }
        Ok(())
    }

    /// The params' columns of `dp`-chained partials of `f(model) ∈ R^k`:
    /// `out[c][i] = Σ_k ∂f_i/∂p_k · dp_k/dp_c`, each partial a refined
    /// central difference over the model made with param `k` moved.
    fn param_slopes(&self, f: &Values<'_>) -> Result<Vec<Vec<f64>>, Failure> {
        let np = self.columns - self.given;
        let values = self.inner.param_values().to_vec();
        let mut partial = Vec::with_capacity(np);
        for k in 0..np {
            let mut moved = values.clone();
            partial.push(derivative(values[k], 0.0, &mut |v| {
                moved[k] = v;
                f(&*self.inner.with_params(&moved))
            })?);
        }
        let len = partial.first().map_or(0, Vec::len);
        Ok((0..np)
            .map(|c| {
                (0..len)
                    .map(|i| {
                        (0..np)
                            .map(|k| partial[k][i] * self.chain[k * np + c])
                            .sum()
                    })
                    .collect()
            })
            .collect())
    }

    /// The sensitivities' jump at an event where `g = switching function
    /// switched[0]` reaches zero at `τ` (a transversal crossing): with
    /// `dτ = −(∂g/∂x S⁻ + ∂g/∂p)/(∂g/∂x f⁻ + ∂g/∂t)` and the resets `R` of
    /// the impacts that fired (the identity at a switch),
    /// `S⁺ = R_x S⁻ + R_p + (R_x f⁻ − f⁺) dτ`. The partials of `g` and `R`
    /// are refined central differences (both are cheap algebraic maps).
    fn jump(
        &self,
        before: &Regime,
        switched: &[usize],
        t: f64,
        x_before: &[f64],
        x: &mut [f64],
    ) -> Result<(), Failure> {
        let n = self.n;
        let m = self.columns;
        let Some(&k) = switched.first() else {
            return Ok(());
        };
        let (xm, sm) = x_before.split_at(n);
        let mut old = self.inner.boxed_clone();
        old.set_regime(before);
        let old = &*old;
        let mut f_minus = vec![0.0; n];
        old.rhs(t, xm, &mut f_minus)?;
        let mut f_plus = vec![0.0; n];
        self.inner.rhs(t, &x[..n], &mut f_plus)?;
        let count = self.inner.switches();
        let g_of = |model: &dyn DynModel, t: f64, x: &[f64]| -> f64 {
            let mut g = vec![0.0; count];
            model.switching_functions(t, x, &mut g);
            g[k]
        };
        // ∂g/∂x, ∂g/∂t and ∂g/∂p, before the event.
        let mut g_x = vec![0.0; n];
        let mut moved = xm.to_vec();
        for j in 0..n {
            g_x[j] = derivative(xm[j], 1.0, &mut |v| {
                moved[j] = v;
                let g = g_of(old, t, &moved);
                moved[j] = xm[j];
                Ok(vec![g])
            })?[0];
        }
        let g_t = derivative(t, 1.0, &mut |v| Ok(vec![g_of(old, v, xm)]))?[0];
        // The impacts that fired: the resets `R`, applied in order.
        let fired = crate::run::impacts::fired(old, &before.branches, switched);
        if !fired.is_empty() && !self.inner.impact_targets().is_empty() {
            // The run recomputes what the mode after such an impact fixes
            // (`run::impacts`), which the augmented system does not carry.
            return Err(Failure::new(
                t,
                crate::failure::FailureKind::Unsupported {
                    message: "--sensitivity through an impact of a model whose implicit \
                              constraints have several candidates is not computed"
                        .to_string(),
                },
            ));
        }
        let reset = |model: &dyn DynModel, state: &[f64]| -> Vec<f64> {
            crate::run::impacts::reset(model, before, &fired, t, state)
        };
        // `∂g/∂p` and `∂R/∂p` in one pass over the models with a param
        // moved (making each is most of an event's cost on a small model).
        let slopes = self.param_slopes(&|model| {
            let mut regime = model.boxed_clone();
            regime.set_regime(before);
            let mut out = vec![g_of(&*regime, t, xm)];
            if !fired.is_empty() {
                out.extend(reset(model, xm));
            }
            Ok(out)
        })?;
        let rate = dot(&g_x, &f_minus) + g_t;
        if !(rate.abs() > 0.0) || !rate.is_finite() {
            return Err(Failure::new(
                t,
                crate::failure::FailureKind::Unsupported {
                    message: format!(
                        "`--sensitivity`: at t = {t} the switching function {} touches zero \
                         without crossing it (a grazing event): the sensitivities are not \
                         defined there",
                        k + 1
                    ),
                },
            ));
        }
        // R_x, column by column (the identity where nothing fired).
        let mut r_x = Matrix::identity(n);
        let r_p: Vec<Vec<f64>> = slopes
            .iter()
            .map(|s| match s.len() {
                1 => vec![0.0; n],
                _ => s[1..].to_vec(),
            })
            .collect();
        if !fired.is_empty() {
            let mut moved = xm.to_vec();
            for j in 0..n {
                let column = derivative(xm[j], 1.0, &mut |v| {
                    moved[j] = v;
                    let y = reset(old, &moved);
                    moved[j] = xm[j];
                    Ok(y)
                })?;
                r_x.column_mut(j).copy_from_slice(&column);
            }
        }
        let mut r_f = vec![0.0; n];
        r_x.mul_vec(&f_minus, &mut r_f);
        let mut column = vec![0.0; n];
        for c in 0..m {
            let s_minus = &sm[c * n..(c + 1) * n];
            let mut slope = dot(&g_x, s_minus);
            if c >= self.given {
                slope += slopes[c - self.given][0];
            }
            let d_tau = -slope / rate;
            r_x.mul_vec(s_minus, &mut column);
            for i in 0..n {
                let mut v = column[i] + (r_f[i] - f_plus[i]) * d_tau;
                if c >= self.given {
                    v += r_p[c - self.given][i];
                }
                x[n + c * n + i] = v;
            }
        }
        Ok(())
    }

    /// The run's projection onto the holonomic constraints
    /// (`project_closure`, positions and their derivatives along the
    /// normals, or partitioned by `partition` as the keeper chose) and its
    /// derivative: `x ← P(x)`, and every column of `S`
    /// by the chain rule through it, `S ← P_x S + P_p dp/dp`. `P_x S` is
    /// a directional derivative of `P` along the column and `P_p` one
    /// over the model with the param moved, each a refined central
    /// difference (`P` is Gauss–Newton to rounding, smooth near the
    /// constraints). The columns that start tangent stay tangent to
    /// rounding while `P` only removes the integration's drift; the
    /// projection is what the motion's own run does, so the columns are
    /// the derivatives of that run.
    fn project(&self, t: f64, z: &mut [f64], partition: Option<Dependents>) -> Result<(), Failure> {
        let n = self.n;
        let (x, s) = z.split_at_mut(n);
        let before = x.to_vec();
        let size = before.iter().fold(1.0_f64, |m, v| m.max(v.abs()));
        let mut moved = vec![0.0; n];
        for c in 0..self.columns {
            let column = &mut s[c * n..(c + 1) * n];
            let length = column.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
            let mut projected = vec![0.0; n];
            if length > 0.0 && length.is_finite() {
                // Along `x + σ v`, `σ` scaled so that `σ v` moves `x` by
                // about 1e-3 of its size (as `derivative` moves a value).
                let v = column.to_vec();
                let unit = size / length;
                projected = derivative(0.0, unit, &mut |sigma| {
                    for ((m, b), v) in moved.iter_mut().zip(&before).zip(&v) {
                        *m = b + sigma * v;
                    }
                    self.inner.project_closure(t, &mut moved, partition)?;
                    Ok(moved.clone())
                })?;
            }
            column.copy_from_slice(&projected);
        }
        if self.columns > self.given {
            let slopes = self.param_slopes(&|model| {
                let mut y = before.clone();
                model.project_closure(t, &mut y, partition)?;
                Ok(y)
            })?;
            for (c, slope) in slopes.iter().enumerate() {
                let column = &mut s[(self.given + c) * n..(self.given + c + 1) * n];
                for (v, d) in column.iter_mut().zip(slope) {
                    *v += d;
                }
            }
        }
        self.inner.project_closure(t, x, partition)
    }

    /// `J S + ∂X/∂p` at `(t, x)` for the sensitivities `s`, into `out`.
    fn variational(&self, t: f64, x: &[f64], s: &[f64], out: &mut [f64]) -> Result<(), Failure> {
        let n = self.n;
        let mut scratch = self.scratch.borrow_mut();
        let Scratch {
            jac,
            partial,
            total: fp,
        } = &mut *scratch;
        jac.fill(0.0);
        self.inner.jacobian(t, x, jac)?;
        self.param_partials(t, x, partial, fp)?;
        for c in 0..self.columns {
            let column = &s[c * n..(c + 1) * n];
            let target = &mut out[c * n..(c + 1) * n];
            jac.mul_vec(column, target);
            if c >= self.given {
                for (v, p) in target.iter_mut().zip(fp.column(c - self.given)) {
                    *v += p;
                }
            }
        }
        Ok(())
    }
}

// What this does not state is a model's without the feature (the
// trait's defaults): no outputs, no candidates, no kept constraints, no
// coefficient system, no exact solution, no pivots: the augmented
// system is integrated directly (`unsupported` names the models it
// cannot serve).
impl DynModel for Augmented {
    fn name(&self) -> &'static str {
        self.inner.name()
    }
    fn source_hash(&self) -> &'static str {
        self.inner.source_hash()
    }
    fn param_names(&self) -> &'static [&'static str] {
        self.inner.param_names()
    }
    fn state_names(&self) -> &'static [&'static str] {
        self.names
    }
    fn motion_dim(&self) -> usize {
        self.n
    }
    fn coordinates(&self) -> usize {
        // No `x_i' = x_{i+n}` structure is promised for the whole system.
        self.names.len()
    }
    fn initial_kinds(&self) -> &'static [Initial] {
        self.inner.initial_kinds()
    }
    fn mass_names(&self) -> &'static [&'static str] {
        self.inner.mass_names()
    }
    fn input_names(&self) -> &'static [&'static str] {
        self.inner.input_names()
    }
    fn input_defaults(&self) -> &'static [f64] {
        self.inner.input_defaults()
    }
    fn declared_integrator(&self) -> Option<IntegratorChoice> {
        self.inner.declared_integrator()
    }
    fn switches(&self) -> usize {
        self.inner.switches()
    }
    fn impacts(&self) -> &'static [&'static str] {
        self.inner.impacts()
    }
    fn parameters(&self, overrides: &[Option<f64>]) -> Vec<f64> {
        self.inner.parameters(overrides)
    }
    fn with_params(&self, params: &[f64]) -> Box<dyn DynModel> {
        let mut copy = self.copy();
        copy.inner = self.inner.with_params(params);
        Box::new(copy)
    }
    fn boxed_clone(&self) -> Box<dyn DynModel> {
        Box::new(self.copy())
    }
    fn param_values(&self) -> &[f64] {
        self.inner.param_values()
    }
    fn time_span(&self) -> (f64, f64) {
        self.inner.time_span()
    }
    fn initial_state(&self, given: &[Option<f64>]) -> Result<Vec<f64>, Failure> {
        self.inner.initial_state(&given[..self.n.min(given.len())])
    }
    fn set_regime(&mut self, regime: &Regime) {
        self.inner.set_regime(regime);
    }
    fn set_inputs(&mut self, inputs: &Inputs) {
        self.inner.set_inputs(inputs);
    }
    fn rhs(&self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), Failure> {
        let n = self.n;
        let (x, s) = x.split_at(n);
        let (dx, ds) = dx.split_at_mut(n);
        self.inner.rhs(t, x, dx)?;
        self.variational(t, x, s, ds)
    }
    fn jacobian(&self, t: f64, x: &[f64], jac: &mut Matrix) -> Result<(), Failure> {
        let n = self.n;
        let total = x.len();
        let mut inner = Matrix::zeros(n, n);
        self.inner.jacobian(t, &x[..n], &mut inner)?;
        // The diagonal blocks: `J` for `x` and for every column of `S`.
        for b in 0..=self.columns {
            for c in 0..n {
                for r in 0..n {
                    jac[(b * n + r, b * n + c)] = inner[(r, c)];
                }
            }
        }
        // `∂(J S + ∂X/∂p)/∂x`: central differences of the exact partials.
        let (mut ahead, mut behind) = (vec![0.0; total - n], vec![0.0; total - n]);
        let mut shifted = x[..n].to_vec();
        for c in 0..n {
            let h = f64::EPSILON.cbrt() * x[c].abs().max(1.0);
            shifted[c] = x[c] + h;
            self.variational(t, &shifted, &x[n..], &mut ahead)?;
            shifted[c] = x[c] - h;
            self.variational(t, &shifted, &x[n..], &mut behind)?;
            shifted[c] = x[c];
            for (r, (a, b)) in ahead.iter().zip(&behind).enumerate() {
                jac[(n + r, c)] = (a - b) / (2.0 * h);
            }
        }
        Ok(())
    }
    fn time_partial(&self, t: f64, x: &[f64], dxdt: &mut [f64]) -> Result<(), Failure> {
        let n = self.n;
        let (dx, ds) = dxdt.split_at_mut(n);
        self.inner.time_partial(t, &x[..n], dx)?;
        let (mut ahead, mut behind) = (vec![0.0; ds.len()], vec![0.0; ds.len()]);
        let h = f64::EPSILON.cbrt() * t.abs().max(1.0);
        self.variational(t + h, &x[..n], &x[n..], &mut ahead)?;
        self.variational(t - h, &x[..n], &x[n..], &mut behind)?;
        for (d, (a, b)) in ds.iter_mut().zip(ahead.iter().zip(&behind)) {
            *d = (a - b) / (2.0 * h);
        }
        Ok(())
    }
    fn switching_functions(&self, t: f64, x: &[f64], g: &mut [f64]) {
        self.inner.switching_functions(t, &x[..self.n], g);
    }
    fn keeps_positions(&self) -> bool {
        self.inner.keeps_positions()
    }
    fn fixed_components(&self) -> &'static [&'static [usize]] {
        self.unfixed
    }
    fn project_closure(
        &self,
        t: f64,
        x: &mut [f64],
        partition: Option<Dependents>,
    ) -> Result<(), Failure> {
        if x.len() == self.n {
            // The motion alone (the keeper's share of a step's error).
            return self.inner.project_closure(t, x, partition);
        }
        if self.inner.keeps_positions() {
            self.project(t, x, partition)
        } else {
            Ok(())
        }
    }
    fn constraints(&self) -> &'static [Candidates] {
        // The run chooses and changes the candidates on the motion's
        // pivots, as for the model alone; `S` goes on unchanged (see the
        // module's comment).
        self.inner.constraints()
    }
    fn pivots(&self, t: f64, x: &[f64], out: &mut [f64]) {
        self.inner.pivots(t, &x[..self.n], out);
    }
    fn stop(&self, branches: &[bool]) -> bool {
        self.inner.stop(branches)
    }
    fn impact_holds(&self, w: usize, branches: &[bool]) -> bool {
        self.inner.impact_holds(w, branches)
    }
    fn impact_reset(&self, w: usize, t: f64, x: &[f64], out: &mut [f64]) {
        // The motion's components; the sensitivities jump in `event_jump`,
        // which sees the state before and after.
        let n = self.n;
        self.inner.impact_reset(w, t, &x[..n], &mut out[..n]);
    }
    fn event_jump(
        &self,
        before: &Regime,
        switched: &[usize],
        t: f64,
        x_before: &[f64],
        x: &mut [f64],
    ) -> Result<(), Failure> {
        self.jump(before, switched, t, x_before, x)
    }
    fn domains(&self) -> &'static [Domain] {
        self.inner.domains()
    }
    fn domain_values(&self, t: f64, x: &[f64], out: &mut [f64]) {
        self.inner.domain_values(t, &x[..self.n], out);
    }
    fn masses(&self, t: f64, x: &[f64], out: &mut [f64]) {
        self.inner.masses(t, &x[..self.n], out);
    }
    fn mass_matrix(&self, t: f64, x: &[f64]) -> Option<Matrix> {
        self.inner.mass_matrix(t, &x[..self.n])
    }
}
