//! One field for many initial states (affine systems).
//!
//! For an affine motion `x' = a(t) x + b(t)` the coefficient system never
//! lets `f_1` into the equations of `f_2..f_N` (SPEC §1.5), and `f_1` enters
//! its own equation linearly. So with the free anchor `c_2..c_N` shared by
//! every initial state:
//!
//! - `f_A`, `S_BA` (A, B ≥ 2) are the same for every initial state, and
//!   `S_B1 = ∂f_B/∂c_1 = 0` exactly: the condition matrix of (13),
//!   `S_BA − S_B1 x_A0 = S_BA`, is shared — one factorisation per sample;
//! - `f_1`, `S_1A` are affine in the one member-dependent number
//!   `c_1 = x_1(t0) − Σ c_A x_A(t0)` (12): `f_1(c_1) = f_1(ĉ_1) + (c_1 − ĉ_1) S_11`,
//!   and `S_11` does not depend on `c_1`. `S_1A` does not depend on `c_1`
//!   either when the coefficient system is linear (`a_A1 = 0`, the
//!   paper's example); in the Riccati case it is affine in `c_1` with a
//!   slope only a second integration (at `ĉ_1 + δ`) gives.
//!
//! Hence the augmented system is integrated once (twice, stacked into one
//! system, in the Riccati case) and each member costs one right side of the
//! shared factorised matrix per sample. The member-dependent right side is
//! `−(S_1A(c_1) − S_11 x_A0)` with the member's own anchor state `x_A0`.
//! Re-anchoring (by the shared condition matrix and growth) restarts every
//! member from its state at the last good step.

use super::error::{Failure, FailureKind};
use super::field::{anchor_values, FieldOptions};
use super::method::{AnyStepper, Integrator};
use super::sensitivity::Sensitized;
use super::stepper::{Stats, Stepper};
use super::system::{CoefficientSystem, Motion};
use nalgebra::{DMatrix, DMatrixView};

/// What the ensemble's field did (the work is that of the one shared
/// integration, whatever the number of members).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EnsembleReport {
    pub stats: Stats,
    pub largest_condition: f64,
    pub reanchorings: usize,
    /// 1 for a linear coefficient system, 2 for a Riccati one.
    pub copies: usize,
}

/// `copies` copies of the augmented system `(f, S)`, stacked, integrated
/// as one system so that they share their steps.
struct Stacked<'a, C: CoefficientSystem + ?Sized> {
    sensitized: Sensitized<'a, C>,
    copies: usize,
    block: usize,
}

impl<C: CoefficientSystem + ?Sized> Motion for Stacked<'_, C> {
    fn dim(&self) -> usize {
        self.copies * self.block
    }

    fn rhs(&self, t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), Failure> {
        for (y, dy) in y.chunks(self.block).zip(dy.chunks_mut(self.block)) {
            self.sensitized.rhs(t, y, dy)?;
        }
        Ok(())
    }

    fn jacobian(&self, t: f64, y: &[f64], jac: &mut DMatrix<f64>) -> Result<(), Failure> {
        let b = self.block;
        for (i, y) in y.chunks(b).enumerate() {
            let mut block = DMatrix::zeros(b, b);
            self.sensitized.jacobian(t, y, &mut block)?;
            jac.view_mut((i * b, i * b), (b, b)).copy_from(&block);
        }
        Ok(())
    }

    fn time_partial(&self, t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), Failure> {
        for (y, d) in y.chunks(self.block).zip(dydt.chunks_mut(self.block)) {
            self.sensitized.time_partial(t, y, d)?;
        }
        Ok(())
    }

    fn component_name(&self, i: usize) -> String {
        self.sensitized.component_name(i % self.block)
    }
}

/// One anchoring of every member.
struct Window {
    t: f64,
    /// The members' states at the anchor, member `k` at `k·N..(k+1)·N`.
    anchors: Vec<f64>,
    /// Each member's `c_1` (12).
    c1: Vec<f64>,
    /// The anchors of the stacked copies: `c_1` of member 0, then `+ δ`.
    copy_c: Vec<Vec<f64>>,
}

impl Window {
    fn new(options: &FieldOptions, t: f64, anchors: Vec<f64>, n: usize, copies: usize) -> Self {
        let base = anchor_values(&options.anchor, &anchors[..n]);
        // (12) for every member with the shared c_2..c_N.
        let c1: Vec<f64> = anchors
            .chunks(n)
            .map(|x| x[0] - (1..n).map(|a| base[a] * x[a]).sum::<f64>())
            .collect();
        let mut copy_c = vec![base.clone()];
        if copies == 2 {
            let mut shifted = base;
            shifted[0] += shifted[0].abs().max(1.0);
            copy_c.push(shifted);
        }
        Window {
            t,
            anchors,
            c1,
            copy_c,
        }
    }

    fn initial_state(&self) -> Vec<f64> {
        self.copy_c
            .iter()
            .flat_map(|c| Sensitized::<dyn CoefficientSystem>::anchored_state(c))
            .collect()
    }
}

/// The shared condition matrix `M[A][B] = S_BA` (A, B ≥ 2) of copy 0 and
/// `max |S|`; `Err` when it is not finite.
fn shared_matrix(t: f64, s: DMatrixView<'_, f64>) -> Result<(DMatrix<f64>, f64, f64), Failure> {
    let n = s.nrows();
    let growth = s.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    let m = DMatrix::from_fn(n - 1, n - 1, |row, col| s[(col + 1, row + 1)]);
    let singular =
        |condition: f64| Failure::new(t, FailureKind::SingularConditionMatrix { condition });
    if !growth.is_finite() || m.iter().any(|v| !v.is_finite()) {
        return Err(singular(f64::INFINITY));
    }
    let values = m.clone().singular_values();
    let condition = if values.min() > 0.0 {
        values.max() / values.min()
    } else {
        f64::INFINITY
    };
    Ok((m, condition, growth))
}

/// Every member's state at time `t` from the stacked augmented state `y`.
fn members_at(t: f64, y: &[f64], window: &Window, n: usize) -> Result<Vec<f64>, Failure> {
    let block = n + n * n;
    let f = &y[..n];
    let s = Sensitized::<dyn CoefficientSystem>::sensitivities(y, n);
    let members = window.c1.len();
    let base_c1 = window.copy_c[0][0];
    let mut states = vec![0.0; members * n];
    if n == 1 {
        for (k, &c1) in window.c1.iter().enumerate() {
            states[k] = f[0] + (c1 - base_c1) * s[(0, 0)];
        }
        return Ok(states);
    }
    // The slope of S_1A in c_1 (Riccati case only).
    let slope: Vec<f64> = match window.copy_c.get(1) {
        Some(shifted) => {
            let s1 = Sensitized::<dyn CoefficientSystem>::sensitivities(&y[block..], n);
            let delta = shifted[0] - base_c1;
            (1..n).map(|a| (s1[(0, a)] - s[(0, a)]) / delta).collect()
        }
        None => vec![0.0; n - 1],
    };
    let (matrix, condition, _) = shared_matrix(t, s)?;
    let lu = matrix.lu();
    if !lu.is_invertible() {
        return Err(Failure::new(
            t,
            FailureKind::SingularConditionMatrix { condition },
        ));
    }
    // All members' right sides as the columns of one matrix: one
    // factorisation, one blocked solve.
    let mut right = DMatrix::zeros(n - 1, members);
    for (k, column) in right.column_iter_mut().enumerate() {
        let d = window.c1[k] - base_c1;
        let anchor = &window.anchors[k * n..(k + 1) * n];
        for (row, value) in column.into_iter().enumerate() {
            let a = row + 1;
            *value = -(s[(0, a)] + d * slope[row] - s[(0, 0)] * anchor[a]);
        }
    }
    lu.solve_mut(&mut right);
    for (k, (x, solution)) in states.chunks_mut(n).zip(right.column_iter()).enumerate() {
        let d = window.c1[k] - base_c1;
        x[0] = f[0] + d * s[(0, 0)];
        for a in 1..n {
            x[a] = solution[a - 1];
            x[0] += f[a] * x[a];
        }
    }
    if states.iter().any(|v| !v.is_finite()) {
        return Err(Failure::new(
            t,
            FailureKind::SingularConditionMatrix { condition },
        ));
    }
    Ok(states)
}

/// How many times the first step after an anchor is shortened (as in
/// `field::solve_field`).
const MAX_SHORTENINGS: usize = 40;

/// Integrates every member of `members` (initial states at `times[0]`) by
/// one field, calling `on_sample(t, states)` at every sample time with the
/// members' states (member `k` at `k·N..(k+1)·N`).
pub fn solve_ensemble<C: CoefficientSystem + ?Sized>(
    coefficients: &C,
    options: &FieldOptions,
    times: &[f64],
    members: &[Vec<f64>],
    mut on_sample: impl FnMut(f64, &[f64]),
) -> Result<EnsembleReport, Failure> {
    let n = coefficients.dim();
    let copies = if coefficients.is_linear() { 1 } else { 2 };
    let mut report = EnsembleReport {
        largest_condition: 1.0,
        copies,
        ..EnsembleReport::default()
    };
    let Some((&t0, rest)) = times.split_first() else {
        return Ok(report);
    };
    if members.is_empty() {
        return Ok(report);
    }
    let system = Stacked {
        sensitized: Sensitized::new(coefficients),
        copies,
        block: n + n * n,
    };
    let integrator = if coefficients.is_linear() {
        options.integrator
    } else {
        Integrator::Explicit
    };
    let span = times.last().map_or(0.0, |t1| (t1 - t0).abs());
    let h_max = if span > 0.0 { span } else { 1.0 };
    let start = |window: &Window| {
        AnyStepper::new(
            integrator,
            &system,
            window.t,
            &window.initial_state(),
            options.tol,
            h_max,
        )
    };
    let initial: Vec<f64> = members.iter().flatten().copied().collect();
    let mut window = Window::new(options, t0, initial, n, copies);
    let mut stepper = start(&window)?;
    let (mut good_t, mut good_y) = (t0, stepper.state().to_vec());
    let mut step_cap: Option<f64> = None;
    let mut shortenings = 0;
    on_sample(t0, &window.anchors);
    for &target in rest {
        while good_t < target {
            let limit = step_cap.map_or(target, |cap| (good_t + cap).min(target));
            let outcome = stepper.step(&system, limit).and_then(|()| {
                let s = Sensitized::<C>::sensitivities(stepper.state(), n);
                if n == 1 {
                    let growth = s[(0, 0)].abs();
                    Ok((1.0, growth))
                } else {
                    shared_matrix(stepper.time(), s).map(|(_, c, g)| (c, g))
                }
            });
            let within = |(c, g): (f64, f64)| c <= options.max_condition && g <= options.max_growth;
            match outcome {
                Ok(checked) if within(checked) || !options.reanchor => {
                    let condition = checked.0;
                    if !options.reanchor && condition > options.max_condition {
                        return Err(Failure::new(
                            stepper.time(),
                            FailureKind::SingularConditionMatrix { condition },
                        ));
                    }
                    report.largest_condition = report.largest_condition.max(condition);
                    good_t = stepper.time();
                    good_y.clear();
                    good_y.extend_from_slice(stepper.state());
                    step_cap = None;
                    shortenings = 0;
                }
                Err(failure) if !options.reanchor => return Err(failure),
                Err(failure) if good_t == window.t => return Err(failure),
                outcome => {
                    if good_t == window.t {
                        shortenings += 1;
                        if shortenings > MAX_SHORTENINGS {
                            let condition = outcome.map_or(f64::INFINITY, |(c, _)| c);
                            return Err(Failure::new(
                                good_t,
                                FailureKind::SingularConditionMatrix { condition },
                            ));
                        }
                        step_cap = Some(0.25 * (stepper.time() - window.t));
                    } else {
                        report.reanchorings += 1;
                        let states = members_at(good_t, &good_y, &window, n)?;
                        window = Window::new(options, good_t, states, n, copies);
                    }
                    report.stats += stepper.stats();
                    let proposed = stepper.proposed_step();
                    stepper = start(&window)?;
                    stepper.propose_step(proposed);
                    good_y.clear();
                    good_y.extend_from_slice(stepper.state());
                }
            }
        }
        on_sample(target, &members_at(good_t, &good_y, &window, n)?);
    }
    report.stats += stepper.stats();
    Ok(report)
}
