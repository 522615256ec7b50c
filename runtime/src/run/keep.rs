//! Keeping the constraints (SPEC §2.3): the state components a constraint
//! fixes (the dependent velocities of first-order constraints) are
//! integrated as free state, so they drift from the values the constraint
//! requires wherever its right side depends on a dependent coordinate —
//! the residual `e = q_d' − φ` obeys `e' = −φ_{q_d} e` and grows
//! exponentially where that partial keeps its sign (a four-bar's closure
//! lost 7 % by t = 15 with exit 0; shared/notes/constraint-drift.md).
//!
//! The remedy is projection (Hairer, Lubich, Wanner, *Geometric Numerical
//! Integration*, IV.4): after an accepted step whose residual has grown to
//! a fraction of the tolerance, the state is put back on the constraints
//! and the method goes on from there, its step sizes kept (a projection
//! is no discontinuity); every output is projected, so no sample is off
//! the constraints. The error estimate of a step is taken before its
//! projection, so the integrator's order is kept.
//!
//! The projection moves the velocities along the constraints' normals
//! (Gauss–Newton on `h_c = v_{d_c} − φ_c(t, q, v) = 0`, the smallest
//! correction), not the dependent velocity alone: near a poor pivot (a
//! knife edge heading across y) the constraint's value `φ = tan θ x'`
//! multiplies the error of `x'`, and moving `y'` onto it made the circling
//! knife edge 3× less accurate than leaving it.
//!
//! The holonomic constraints' projection (`closure::project`) is along
//! their normals too, except where the independent coordinates' highest
//! derivatives are constant (a bead sliding down a helical wire): there it
//! is partitioned, the independent coordinates kept as integrated and the
//! mode's dependents solved from the constraints (`partition.rs`, which
//! says why, and docs/BENCHMARKS.md §10v for the measurements: partitioned
//! everywhere, a particle on a circle was 20–550× less accurate by direct).

mod one;
mod partition;

use crate::closure::Dependents;
use crate::failure::{Failure, FailureKind};
use crate::linalg::{Lu, Matrix};
use crate::model::{DynModel, Initial};
use crate::ode::tolerance::Tolerance;

/// The residual (relative to the tolerance) above which the state after a
/// step is projected. Below it the drift is left to grow: a projection
/// re-anchors the field, and the residual seeded by one step is usually a
/// small fraction of the tolerance. A tenth keeps every carried residual
/// an order below what the step's own error may be.
pub const PROJECT_ABOVE: f64 = 0.1;

/// A correction this many times the tolerance, and above
/// [`BROKEN_ABOVE`] of its component's size, is no drift that an accepted
/// step can carry: the motion left the constraint (its branch ended, or it
/// passed a singular point of it). Projected, it would go on as another
/// motion with exit 0 — the explicit rising branch `y' = sqrt(c² − x'²)`
/// went on past its apex to speed² 77 where the constraint holds it at 1.
pub const BROKEN_TIMES_TOLERANCE: f64 = 1e4;
pub const BROKEN_ABOVE: f64 = 1e-6;

/// Gauss–Newton iterations of one projection: constraints affine in the
/// velocities (the usual case) take one, and the second confirms it.
const ITERATIONS: usize = 6;

/// The constraints' residuals along one run, and the projections made.
#[derive(Clone, Debug)]
pub struct Keeper {
    tol: Tolerance,
    /// The fixed components of `mode` (state indices).
    mode: Option<usize>,
    fixed: Vec<usize>,
    /// The holonomic projection of `mode`: partitioned by these dependents,
    /// or along the normals (`partition::choose`).
    partition: Option<Dependents>,
    /// The velocity block `q^(u−1)` (state indices), which projections move.
    velocities: std::ops::Range<usize>,
    /// The constrained values, then the last projection's result (one
    /// buffer of two states: a small model's solve is a few microseconds,
    /// and each allocation and free in it about 1 % of the paper's,
    /// docs/BENCHMARKS.md §10h).
    states: Vec<f64>,
    gradient: Matrix,
    /// The two projected states of [`Keeper::kept_part`], one after the
    /// other.
    probe: Vec<f64>,
    /// Buffers of a projection (residual and multipliers, one per
    /// constraint, then the Gram matrix), kept from step to step: most
    /// steps only measure the residual, and allocations were a third of a
    /// small model's cost of keeping.
    scratch: Vec<f64>,
    /// The Gram matrix's factorisation, in storage kept from step to step
    /// (a solve of two or more constraints allocated two buffers).
    lu: Lu,
    largest: f64,
    largest_absolute: f64,
    largest_at: f64,
    projections: usize,
}

/// What the summary says of the constraints kept.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Kept {
    /// The largest distance from the constraints that the integration
    /// carried (the correction of a projection), relative to the
    /// tolerance `atol + rtol·|x|`, and absolute.
    pub largest: f64,
    pub largest_absolute: f64,
    pub largest_at: f64,
    /// Projections after steps (every output is projected too).
    pub projections: usize,
}

impl Keeper {
    /// `None` for a model that fixes no state component.
    pub fn new(model: &dyn DynModel, tol: Tolerance) -> Option<Keeper> {
        Keeper::new_reusing(model, tol, None)
    }

    /// [`Keeper::new`] in the storage of `spare`, an earlier solve's
    /// keeper: the same keeper (its buffers are scratch, written before
    /// they are read, and cleared or zeroed here as `new` makes them), no
    /// allocation when the sizes are the same (docs/BENCHMARKS.md §10i).
    pub fn new_reusing(
        model: &dyn DynModel,
        tol: Tolerance,
        spare: Option<Keeper>,
    ) -> Option<Keeper> {
        let n = model.dim();
        let coordinates = model.coordinates();
        if !(model.keeps_constraints() || model.keeps_positions()) {
            return None;
        }
        let (mut fixed, mut states, mut gradient, mut probe, mut scratch, lu) = match spare {
            Some(k) => (k.fixed, k.states, k.gradient, k.probe, k.scratch, k.lu),
            None => (
                Vec::new(),
                Vec::new(),
                Matrix::zeros(0, 0),
                Vec::new(),
                Vec::new(),
                Lu::empty(),
            ),
        };
        fixed.clear();
        states.clear();
        states.resize(2 * n, 0.0);
        if gradient.rows() != n || gradient.cols() != n {
            gradient = Matrix::zeros(n, n);
        }
        gradient.fill(0.0);
        probe.clear();
        probe.reserve(2 * n);
        scratch.clear();
        Some(Keeper {
            tol,
            mode: None,
            fixed,
            partition: None,
            velocities: n.saturating_sub(coordinates)..n,
            states,
            gradient,
            probe,
            scratch,
            // Refactored from scratch at every use (`Lu::refactor`).
            lu,
            largest: 0.0,
            largest_absolute: 0.0,
            largest_at: f64::NAN,
            projections: 0,
        })
    }

    /// After an accepted step in `mode`: `Some(projected state)` when the
    /// state has drifted past [`PROJECT_ABOVE`] of the tolerance.
    pub fn after_step(
        &mut self,
        model: &dyn DynModel,
        mode: usize,
        t: f64,
        x: &[f64],
    ) -> Result<Option<&[f64]>, Failure> {
        // Most steps end on the constraint (the paper and the knife edge
        // project after none of their steps): with one constraint, its
        // measure alone first, without the projection's copies and frame
        // (the measure `project_from` starts with, the same distance
        // recorded). Past `PROJECT_ABOVE`, `project_from` measures again
        // and projects.
        if self.mode == Some(mode) && one::applies(self, model) {
            if let Some(relative) = self.settled_one(model, t, x) {
                if relative <= PROJECT_ABOVE {
                    return Ok(None);
                }
            }
        }
        if self.project_from(model, mode, t, x, true, true)? > PROJECT_ABOVE {
            self.projections += 1;
            Ok(Some(self.projected()))
        } else {
            Ok(None)
        }
    }

    /// Whether `x` at `t` in `mode`, a state inside a method's advance
    /// (a step of a field window), has drifted from the holonomic
    /// constraints (positions and their derivatives) past
    /// [`PROJECT_ABOVE`], where [`Keeper::after_step`] would project it.
    /// Measured only: not recorded, projected or judged (the advance's
    /// end is, by `after_step`). Velocity constraints' drift is left to
    /// the advance's end (`method::field::quasilinear`, where the window
    /// asks, says why).
    pub fn drifted(
        &mut self,
        model: &dyn DynModel,
        mode: usize,
        t: f64,
        x: &[f64],
    ) -> Result<bool, Failure> {
        if !model.keeps_positions() {
            return Ok(false);
        }
        self.enter_mode(model, mode, t, x);
        let half = self.states.len() / 2;
        let projected = &mut self.states[half..];
        projected.copy_from_slice(x);
        let ((relative, _), _) =
            closure_distance(model, self.tol, self.partition, t, x, projected)?;
        Ok(relative > PROJECT_ABOVE)
    }

    /// The components `mode` fixes and its holonomic projection, where
    /// the mode changed since the last measure.
    fn enter_mode(&mut self, model: &dyn DynModel, mode: usize, t: f64, x: &[f64]) {
        if self.mode != Some(mode) {
            fixed_components(model, mode, &mut self.fixed);
            self.mode = Some(mode);
            self.partition = partition::choose(model, &self.fixed, self.velocities.clone(), t, x);
        }
    }

    /// Projects `x` (an output, or the state at an event) onto the
    /// constraints in place.
    pub fn project(
        &mut self,
        model: &dyn DynModel,
        mode: usize,
        t: f64,
        x: &mut [f64],
    ) -> Result<(), Failure> {
        self.project_in_place(model, mode, t, x, true)
    }

    /// Puts a state that was made, not integrated (an ensemble's member
    /// moved off the model's initial state, the field's reference carried
    /// alongside its run), on the constraints: no distance is recorded or
    /// judged.
    pub fn put_on(
        &mut self,
        model: &dyn DynModel,
        mode: usize,
        t: f64,
        x: &mut [f64],
    ) -> Result<(), Failure> {
        self.project_in_place(model, mode, t, x, false)
    }

    fn project_in_place(
        &mut self,
        model: &dyn DynModel,
        mode: usize,
        t: f64,
        x: &mut [f64],
        judged: bool,
    ) -> Result<(), Failure> {
        self.project_from(model, mode, t, x, judged, false)?;
        x.copy_from_slice(self.projected());
        Ok(())
    }

    /// The last projection's result.
    fn projected(&self) -> &[f64] {
        &self.states[self.states.len() / 2..]
    }

    /// Replaces `d`, a small change of the state `x` (a step's local
    /// error), by the part of it that the holonomic constraints keep: the
    /// derivative at `x` of their projection (positions and their
    /// derivatives along the normals, `closure::project`) applied to `d`,
    /// by a central difference `(P(x + s d) − P(x − s d)) / 2s` with `s d`
    /// of relative size `√eps` (its rounding and its curvature both `√eps`
    /// of `d`). An error normal to these constraints is removed by the
    /// projections (after a step, and of every output) and what it
    /// integrates into while it lasts is normal too, so it never reaches
    /// the run's answer: near a poor pivot it is most of a step's error
    /// estimate (the bead in a spinning tube as its pivot's cosine falls
    /// to 0.07: 1.5e-10 across the tube, 1e-12 along it). Velocity
    /// constraints are left out: an error across one integrates into
    /// positions they do not constrain before a projection removes it
    /// (removing it made the estimate of the circling knife edge fall
    /// below its error, 5.5 against 12.9 rtol). `d` is left as it is on
    /// failure.
    pub fn kept_part(
        &mut self,
        model: &dyn DynModel,
        t: f64,
        x: &[f64],
        d: &mut [f64],
    ) -> Result<(), Failure> {
        if !model.keeps_positions() {
            return Ok(());
        }
        // The motion's components alone: what a system carries beside it
        // (the sensitivities) keeps its whole error, a bound on the part
        // its own projection keeps, for a fraction of the cost (the
        // projection's derivative for every column at every step was
        // most of a holonomic model's sensitivity run).
        let motion = model.motion_dim();
        let (x, d) = (&x[..motion], &mut d[..motion]);
        let size = crate::ode::dop853::global_error::relative(d, x);
        if !(size > 0.0 && size.is_finite()) {
            return Ok(());
        }
        let s = f64::EPSILON.sqrt() / size;
        let mut probe = std::mem::take(&mut self.probe);
        probe.clear();
        probe.extend(x.iter().zip(d.iter()).map(|(x, d)| x + s * d));
        probe.extend(x.iter().zip(d.iter()).map(|(x, d)| x - s * d));
        let (plus, minus) = probe.split_at_mut(x.len());
        let result = model
            .project_closure(t, plus, self.partition)
            .and_then(|_| model.project_closure(t, minus, self.partition));
        if result.is_ok() {
            for ((d, p), m) in d.iter_mut().zip(&*plus).zip(&*minus) {
                *d = (p - m) / (2.0 * s);
            }
        }
        self.probe = probe;
        result
    }

    /// Replaces `d`, a small change of the state `x` at `t` (an error
    /// carried along the motion), by the part of it that the run's whole
    /// projection keeps — holonomic constraints and velocity constraints
    /// in `mode` — its derivative at `x` applied to `d` by a central
    /// difference, as [`Keeper::kept_part`] does for the holonomic ones.
    /// Unlike a step's local error (whose velocity part across a velocity
    /// constraint integrates into unconstrained positions before a
    /// projection removes it), a carried error is carried over a step
    /// first and then projected, as the run's state is: the part across
    /// the constraints never reaches the answer, and left in, the reduced
    /// system's drift off them (`e' = −φ_{q_d} e`) grows it without bound
    /// (1e9× rtol on the knife edge, `dop853::global_error`). `d` is left
    /// as it is on failure.
    pub fn tangent(
        &mut self,
        model: &dyn DynModel,
        mode: usize,
        t: f64,
        x: &[f64],
        d: &mut [f64],
    ) -> Result<(), Failure> {
        let size = crate::ode::dop853::global_error::relative(d, x);
        if !(size > 0.0 && size.is_finite()) {
            return Ok(());
        }
        let s = f64::EPSILON.sqrt() / size;
        // The probe buffers of `kept_part`, taken out while the
        // projections borrow the keeper.
        let mut probe = std::mem::take(&mut self.probe);
        probe.clear();
        probe.extend(x.iter().zip(d.iter()).map(|(x, d)| x + s * d));
        probe.extend(x.iter().zip(d.iter()).map(|(x, d)| x - s * d));
        let (plus, minus) = probe.split_at_mut(x.len());
        let result = self
            .project_in_place(model, mode, t, plus, false)
            .and_then(|_| self.project_in_place(model, mode, t, minus, false));
        if result.is_ok() {
            for ((d, p), m) in d.iter_mut().zip(&*plus).zip(&*minus) {
                *d = (p - m) / (2.0 * s);
            }
        }
        self.probe = probe;
        result
    }

    pub fn kept(&self) -> Kept {
        Kept {
            largest: self.largest,
            largest_absolute: self.largest_absolute,
            largest_at: self.largest_at,
            projections: self.projections,
        }
    }

    /// `x` projected onto the constraints, into [`Keeper::projected`]; the
    /// distance (the first correction) relative to the tolerance, recorded
    /// and judged when `judged` (a state the integration carried). With
    /// `bounded`, a state whose residual bounds its distance below
    /// [`PROJECT_ABOVE`] is left as it is, and the bound is the distance
    /// recorded: the normals' Gram matrix `I + G Gᵀ` is at least the
    /// identity, so no component of the correction exceeds `‖h‖₂` (most
    /// steps end there, and this saves them the partials and the solve).
    fn project_from(
        &mut self,
        model: &dyn DynModel,
        mode: usize,
        t: f64,
        x: &[f64],
        judged: bool,
        bounded: bool,
    ) -> Result<f64, Failure> {
        self.enter_mode(model, mode, t, x);
        if one::applies(self, model) {
            return self.project_one(model, t, x, judged, bounded);
        }
        self.project_general(model, t, x, judged, bounded)
    }

    /// [`Keeper::project_from`] for any constraints (the mode's fixed
    /// components known).
    fn project_general(
        &mut self,
        model: &dyn DynModel,
        t: f64,
        x: &[f64],
        judged: bool,
        bounded: bool,
    ) -> Result<f64, Failure> {
        let half = self.states.len() / 2;
        let (kept, projected) = self.states.split_at_mut(half);
        projected.copy_from_slice(x);
        // Holonomic constraints first: the positions and their derivatives
        // along the constraints' normals (the same in every mode).
        let mut closure = (0.0_f64, 0.0_f64);
        if model.keeps_positions() {
            let motion = model.motion_dim();
            let partition = self.partition;
            let worst;
            (closure, worst) = closure_distance(model, self.tol, partition, t, x, projected)?;
            let size = x[worst].abs().max(projected[worst].abs()).max(1.0);
            if judged && closure.0 > BROKEN_TIMES_TOLERANCE && closure.1 > BROKEN_ABOVE * size {
                return Err(Failure::new(
                    t,
                    FailureKind::ConstraintLeft {
                        component: model.state_names()[worst].to_string(),
                        residual: closure.1,
                    },
                ));
            }
            if motion < x.len() && !(bounded && closure.0 <= PROJECT_ABOVE) {
                projected.copy_from_slice(x);
                model.project_closure(t, projected, partition)?;
            }
        }
        let m = self.fixed.len();
        if self.scratch.len() != m * (m + 2) {
            self.scratch.resize(m * (m + 2), 0.0);
        }
        // The fields borrowed apart, the scratch buffers in place (taking
        // them out and back, and the closure over the whole keeper, were a
        // tenth of a measuring call, docs/BENCHMARKS.md §10h).
        let Keeper {
            tol,
            fixed,
            velocities,
            gradient,
            scratch,
            lu,
            largest,
            largest_absolute,
            largest_at,
            ..
        } = self;
        let fixed: &[usize] = fixed;
        let (residual, rest) = scratch.split_at_mut(m);
        let (lambda, normal_gram) = rest.split_at_mut(m);
        let mut distance: Option<(f64, f64)> = None;
        let mut last = (0.0_f64, 0.0_f64);
        for _ in 0..ITERATIONS {
            kept.copy_from_slice(projected);
            model.constrained(t, projected, kept)?;
            for (c, &j) in fixed.iter().enumerate() {
                if !kept[j].is_finite() {
                    return Err(Failure::new(
                        t,
                        FailureKind::ConstraintUndefined {
                            component: model.state_names()[j].to_string(),
                        },
                    ));
                }
                residual[c] = projected[j] - kept[j];
            }
            if bounded && distance.is_none() {
                let record = (&mut *largest, &mut *largest_absolute, &mut *largest_at);
                if let Some(relative) =
                    settled(residual, velocities.clone(), x, tol, closure, t, record)
                {
                    return Ok(relative);
                }
            }
            gradient.fill(0.0);
            model.kept_gradient(t, projected, gradient)?;
            // The normals J_c = e_{d_c} − ∂φ_c/∂v over the velocities; the
            // smallest correction is Δv = −Jᵀ (J Jᵀ)⁻¹ h.
            let normal = |c: usize, i: usize| -> f64 {
                let j = fixed[c];
                f64::from(u8::from(i == j)) - gradient[(j, i)]
            };
            for a in 0..m {
                for b in 0..m {
                    normal_gram[a * m + b] = velocities
                        .clone()
                        .map(|i| normal(a, i) * normal(b, i))
                        .sum();
                }
            }
            lambda.copy_from_slice(residual);
            let solved = if m == 1 {
                lambda[0] /= normal_gram[0];
                lambda[0].is_finite()
            } else {
                // What `linalg::solve_dense` does, in kept storage.
                lu.refactor(m, |a| {
                    for i in 0..m {
                        for j in 0..m {
                            a[(i, j)] = normal_gram[i * m + j];
                        }
                    }
                });
                lu.solve_in_place(lambda) && lambda.iter().all(|v| v.is_finite())
            };
            let (mut relative, mut absolute) = (0.0_f64, 0.0_f64);
            let mut worst = fixed.first().copied().unwrap_or(0);
            for i in velocities.clone() {
                let delta = if solved {
                    -(0..m).map(|c| normal(c, i) * lambda[c]).sum::<f64>()
                } else {
                    // Normals that are not independent: the dependent
                    // components take their values.
                    match fixed.iter().position(|&j| j == i) {
                        Some(c) => -residual[c],
                        None => 0.0,
                    }
                };
                let v = projected[i];
                projected[i] = v + delta;
                let scale = tol.atol + tol.rtol * v.abs().max(projected[i].abs());
                if delta.abs() / scale > relative {
                    worst = i;
                }
                relative = relative.max(delta.abs() / scale);
                absolute = absolute.max(delta.abs());
            }
            if distance.is_none() {
                let size = x[worst].abs().max(projected[worst].abs()).max(1.0);
                if judged && relative > BROKEN_TIMES_TOLERANCE && absolute > BROKEN_ABOVE * size {
                    return Err(left(model, fixed, t, residual, absolute));
                }
                distance = Some((relative, absolute));
            }
            last = (relative, absolute);
            if relative <= 1e-3 {
                break;
            }
        }
        // Gauss–Newton that does not settle within the tolerance: no point
        // of the constraints near the state (a branch that ends).
        if last.0 > 1.0 {
            return Err(left(model, fixed, t, residual, last.1));
        }
        let (relative, absolute) = distance.unwrap_or((0.0, 0.0));
        let (relative, absolute) = if closure.0 > relative {
            closure
        } else {
            (relative, absolute)
        };
        if judged && relative > *largest {
            *largest = relative;
            *largest_absolute = absolute;
            *largest_at = t;
        }
        Ok(relative)
    }
}

/// The holonomic constraints' projection of the motion's part of `x`
/// (into `projected[..motion]`, which holds `x` on entry), and its
/// distance `(relative to the tolerance, absolute)` with the component
/// where it is largest. The distance is the motion's: what a system
/// carries beside it (the sensitivities) is moved by the projection's
/// derivative, whose size is no distance from the constraints, and which
/// is worth its cost only where the state is moved.
fn closure_distance(
    model: &dyn DynModel,
    tol: Tolerance,
    partition: Option<Dependents>,
    t: f64,
    x: &[f64],
    projected: &mut [f64],
) -> Result<((f64, f64), usize), Failure> {
    let motion = model.motion_dim();
    model.project_closure(t, &mut projected[..motion], partition)?;
    let (mut closure, mut worst) = ((0.0_f64, 0.0_f64), 0);
    for (i, (&before, &after)) in x.iter().zip(&*projected).take(motion).enumerate() {
        let delta = (after - before).abs();
        let scale = tol.atol + tol.rtol * before.abs().max(after.abs());
        if delta / scale > closure.0 {
            worst = i;
        }
        closure = (closure.0.max(delta / scale), closure.1.max(delta));
    }
    Ok((closure, worst))
}

/// The failure of a state that has left the constraints, naming the
/// fixed component (of `fixed`) with the largest residual.
fn left(model: &dyn DynModel, fixed: &[usize], t: f64, residual: &[f64], distance: f64) -> Failure {
    let c = (0..residual.len())
        .max_by(|&a, &b| residual[a].abs().total_cmp(&residual[b].abs()))
        .unwrap_or(0);
    Failure::new(
        t,
        FailureKind::ConstraintLeft {
            component: model.state_names()[fixed[c]].to_string(),
            residual: distance,
        },
    )
}

/// Checks the components that `mode` fixes but the initial values give
/// (the candidate of a non-linear constraint, kept as written: its value
/// chooses the root the motion starts on): each must be the root of its
/// constraint near it, found by iterating the kept value (Newton's
/// `v − f/f_v`) from it. A value off the constraint is the user's
/// (`--init`, `--param`), and a run from it would start off the
/// constraint: it stops before the run, naming the root near it.
///
/// `Ok(false)`, unless `strict`, where the mode's roots are not numbers
/// (its candidate has no pivot at the start: a particle at constant speed,
/// `x'^2 + y'^2 = c^2 for y' or x'`, thrown level, `y' = 0`): the caller
/// checks in the mode the run starts in (`regime::check_initial_candidates`).
pub fn check_given_fixed(
    model: &dyn DynModel,
    mode: usize,
    t0: f64,
    x0: &[f64],
    strict: bool,
) -> Result<bool, Failure> {
    let Some((given, x)) = given_roots(model, mode, t0, x0)? else {
        return Ok(true);
    };
    if !strict && given.iter().any(|&j| !x[j].is_finite()) {
        return Ok(false);
    }
    for &j in &given {
        crate::model::check_stated(t0, model.state_names()[j], x0[j], x[j])?;
    }
    Ok(true)
}

/// The components a mode fixes that the initial values give, and the
/// state with each moved onto its root near the given value.
type GivenRoots = (Vec<usize>, Vec<f64>);

/// The components `mode` fixes that the initial values give, and the
/// state with each moved onto its root near the given value (Newton's
/// kept value iterated); `None` where it fixes none of them.
fn given_roots(
    model: &dyn DynModel,
    mode: usize,
    t0: f64,
    x0: &[f64],
) -> Result<Option<GivenRoots>, Failure> {
    let Some(fixed) = model.fixed_components().get(mode) else {
        return Ok(None);
    };
    let given: Vec<usize> = fixed
        .iter()
        .copied()
        .filter(|&j| model.initial_kinds().get(j) == Some(&Initial::Given))
        .collect();
    if given.is_empty() {
        return Ok(None);
    }
    let mut x = x0.to_vec();
    let mut kept = x0.to_vec();
    for _ in 0..50 {
        model.constrained(t0, &x, &mut kept)?;
        let mut moved = 0.0_f64;
        for &j in &given {
            moved = moved.max((kept[j] - x[j]).abs() / x[j].abs().max(1.0));
            x[j] = kept[j];
        }
        if !(moved > 4.0 * f64::EPSILON) {
            break;
        }
    }
    Ok(Some((given, x)))
}

/// The state components the constraints fix in `mode`: the generated
/// table's (a crate of several modes has one for each), else those the
/// initial values take as fixed (a single mode).
/// Into `out` (cleared first; its storage kept from solve to solve).
pub(crate) fn fixed_components(model: &dyn DynModel, mode: usize, out: &mut Vec<usize>) {
    out.clear();
    if let Some(fixed) = model.fixed_components().get(mode) {
        out.extend_from_slice(fixed);
        return;
    }
    out.extend((0..model.dim()).filter(|&j| model.initial_kinds()[j] == Initial::Constraint));
}

/// Whether a state whose constraints' residual is `residual` is on them
/// already, within `PROJECT_ABOVE` of the smallest of its velocities'
/// tolerances: then its distance relative to that tolerance (or the
/// holonomic constraints' correction `closure`, already in the state, if
/// larger), recorded in `(largest, largest_absolute, largest_at)` where it
/// is the largest so far. The general projection's and the one
/// constraint's (`one.rs`).
pub(super) fn settled(
    residual: &[f64],
    velocities: std::ops::Range<usize>,
    x: &[f64],
    tol: &Tolerance,
    closure: (f64, f64),
    t: f64,
    (largest, largest_absolute, largest_at): (&mut f64, &mut f64, &mut f64),
) -> Option<f64> {
    let norm = residual.iter().map(|h| h * h).sum::<f64>().sqrt();
    let smallest = velocities
        .map(|i| tol.atol + tol.rtol * x[i].abs())
        .fold(f64::INFINITY, f64::min);
    if norm > PROJECT_ABOVE * smallest {
        return None;
    }
    let (relative, absolute) = if closure.0 > norm / smallest {
        closure
    } else {
        (norm / smallest, norm)
    };
    if relative > *largest {
        (*largest, *largest_absolute, *largest_at) = (relative, absolute, t);
    }
    Some(relative)
}
