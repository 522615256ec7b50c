//! Ensemble members of a non-affine motion, corrected to the tolerance.
//!
//! A quasilinear window carries the field of the motion linearised along
//! the reference's predictor `p(t)`: `x' = A(t) x + b(t)`, whose solutions
//! are `x_lin(t) + Φ(t) (x0 − x_r)` (the reference's linear motion and its
//! propagator, both read off the one field). Through that map alone a
//! member is first order in its distance from the reference. Here each
//! member's true motion is written in the frame of that map,
//! `x(t) = x_lin(t) + Φ(t) w(t)`, so that
//!
//! `w' = Φ⁻¹ (X(t, x) − X(t, p) − A (x − p))`
//!
//! (the linear part cancels: `x_lin' = A x_lin + b`, `Φ' = A Φ`). The
//! right side is the linearisation's remainder, `½ X_xx (x − p)²`: small
//! (the square of the spread), and it vanishes for an affine model. It is
//! integrated by DOP853's tableau (8th order, its 5th- and 3rd-order error
//! estimates) on one sequence of steps shared by all members (the frames
//! `x_lin, Φ, Φ⁻¹, p, X(p), A` at each stage time are computed once for
//! all of them), each member's local error — mapped to the state through
//! `Φ` — kept within the tolerance as direct integration keeps its own.
//! The steps end on the field's step ends: the frames come from each field
//! step's own continuous extension, smooth within a step and not across
//! (steps across them lost DOP853's order where its estimate did not see
//! it: a double pendulum 0.5 away, 1.6e-5 off against direct's 2.9e-6).
//! A member whose error would need steps much shorter than the field's
//! own (too far from the reference), or whose equations fail, is dropped:
//! the run integrates it on its own ([`crate::run::run_ensemble`]).

use crate::ensemble::States;
use crate::failure::Failure;
use crate::linalg::{Lu, Matrix};
use crate::model::DynModel;
use crate::ode::dop853::hairer_error;
use crate::ode::dop853::tableau::{A, B, BHH, C, ER, STAGES};
use crate::ode::tolerance::Tolerance;

/// What a member needs of the window at time `t`.
#[derive(Clone, Debug)]
pub struct Frame {
    pub t: f64,
    /// The reference's linear motion `x_lin(t)`.
    pub x_lin: Vec<f64>,
    /// `phi[i·n + j] = ∂x_j(t)/∂x_i(t_r)`.
    pub phi: Vec<f64>,
    /// `inverse[i·n + j] = (Φ⁻¹)_ij` in the same orientation as the
    /// solve `Φ g = r` with `(Φ g)_j = Σ_i phi[i·n + j] g_i`.
    pub inverse: Vec<f64>,
    /// The linearisation point `p(t)`, `X(t, p)` and `A = ∂X/∂x (t, p)`.
    pub p: Vec<f64>,
    pub xp: Vec<f64>,
    pub a: Matrix,
}

impl Frame {
    pub fn new(n: usize) -> Frame {
        Frame {
            t: f64::NAN,
            x_lin: vec![0.0; n],
            phi: vec![0.0; n * n],
            inverse: vec![0.0; n * n],
            p: vec![0.0; n],
            xp: vec![0.0; n],
            a: Matrix::zeros(n, n),
        }
    }

    /// `inverse` from `phi`; `false` when `Φ` is singular.
    pub fn invert(&mut self) -> bool {
        let n = self.x_lin.len();
        // Column-major data `phi[i·n + j]` is the matrix M(j, i) = ∂x_j/∂x0_i.
        let m = Matrix::from_column_major(n, n, self.phi.clone());
        let Some(inv) = Lu::in_place(m).inverse() else {
            return false;
        };
        for i in 0..n {
            for j in 0..n {
                self.inverse[i * n + j] = inv[(i, j)];
            }
        }
        true
    }

    /// `x = x_lin + Φ w`.
    fn state(&self, w: &[f64], x: &mut [f64]) {
        let n = w.len();
        x.copy_from_slice(&self.x_lin);
        for (i, wi) in w.iter().enumerate() {
            for (xj, p) in x.iter_mut().zip(&self.phi[i * n..(i + 1) * n]) {
                *xj += p * wi;
            }
        }
    }

    /// `out = Φ v` (a change of `w` as a change of the state).
    fn map(&self, v: &[f64], out: &mut [f64]) {
        let n = v.len();
        out.fill(0.0);
        for (i, vi) in v.iter().enumerate() {
            for (o, p) in out.iter_mut().zip(&self.phi[i * n..(i + 1) * n]) {
                *o += p * vi;
            }
        }
    }
}

/// The window's frames at any time within it.
pub trait Frames {
    fn frame(&mut self, t: f64, out: &mut Frame) -> Result<(), Failure>;
    /// The ends of the field's steps: the frames are smooth between them
    /// (each step's own continuous extension), not across.
    fn breaks(&self) -> Vec<f64>;
}

/// Scratch of one member's right side.
struct Scratch {
    x: Vec<f64>,
    rate: Vec<f64>,
    d: Vec<f64>,
    ad: Vec<f64>,
    r: Vec<f64>,
    stage: Vec<f64>,
}

impl Scratch {
    fn new(n: usize) -> Scratch {
        Scratch {
            x: vec![0.0; n],
            rate: vec![0.0; n],
            d: vec![0.0; n],
            ad: vec![0.0; n],
            r: vec![0.0; n],
            stage: vec![0.0; n],
        }
    }
}

/// `g = w'` at the frame's time (`shift_rows`: the rows `x_i' = x_{i+n}`,
/// linear, whose remainder is exactly 0).
fn rate(
    model: &dyn DynModel,
    frame: &Frame,
    shift_rows: usize,
    w: &[f64],
    g: &mut [f64],
    s: &mut Scratch,
) -> Result<(), Failure> {
    let n = w.len();
    frame.state(w, &mut s.x);
    model.rhs(frame.t, &s.x, &mut s.rate)?;
    for j in 0..n {
        s.d[j] = s.x[j] - frame.p[j];
    }
    // A (x − p), A column-major.
    s.ad.fill(0.0);
    for (column, d) in frame.a.as_slice().chunks_exact(n).zip(&s.d) {
        for (v, a) in s.ad.iter_mut().zip(column) {
            *v += a * d;
        }
    }
    for j in 0..n {
        s.r[j] = if j < shift_rows {
            0.0
        } else {
            s.rate[j] - frame.xp[j] - s.ad[j]
        };
    }
    for (i, gi) in g.iter_mut().enumerate() {
        *gi = frame.inverse[i * n..(i + 1) * n]
            .iter()
            .zip(&s.r)
            .map(|(a, b)| a * b)
            .sum();
    }
    if g.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(Failure::non_finite(frame.t, "an ensemble member's rate"))
    }
}

/// One member's DOP853 step from `(w0, k[0])` over `h` with the frames of
/// the stage times (`frames[s]` at `t + C[s] h`, `frames[11]` at `t + h`).
/// Writes `w1`, its rate `k[12]` and the 3rd- and 5th-order error
/// estimates `e3`, `e5` (of `w`, without the factor `h`, as DOP853's).
#[allow(clippy::too_many_arguments)]
fn step(
    model: &dyn DynModel,
    frames: &[Frame],
    shift_rows: usize,
    h: f64,
    w0: &[f64],
    k: &mut [Vec<f64>; STAGES + 1],
    w1: &mut [f64],
    (e3, e5): (&mut [f64], &mut [f64]),
    s: &mut Scratch,
) -> Result<(), Failure> {
    let n = w0.len();
    let mut stage = std::mem::take(&mut s.stage);
    let mut stepped = Ok(());
    for st in 1..STAGES {
        // Whole-vector updates, one per stage used (they vectorise).
        stage.copy_from_slice(w0);
        for &(l, a) in A[st] {
            let c = h * a;
            for (v, kl) in stage.iter_mut().zip(&k[l]) {
                *v += c * kl;
            }
        }
        stepped = rate(model, &frames[st], shift_rows, &stage, &mut k[st], s);
        if stepped.is_err() {
            break;
        }
    }
    s.stage = stage;
    stepped?;
    let mut b = std::mem::take(&mut s.d);
    b.fill(0.0);
    e5.fill(0.0);
    for &(l, c) in &B {
        for (v, kl) in b.iter_mut().zip(&k[l]) {
            *v += c * kl;
        }
    }
    for &(l, c) in &ER {
        for (v, kl) in e5.iter_mut().zip(&k[l]) {
            *v += c * kl;
        }
    }
    e3.copy_from_slice(&b);
    for &(l, c) in &BHH {
        for (v, kl) in e3.iter_mut().zip(&k[l]) {
            *v -= c * kl;
        }
    }
    for j in 0..n {
        w1[j] = w0[j] + h * b[j];
    }
    s.d = b;
    rate(
        model,
        &frames[STAGES - 1],
        shift_rows,
        w1,
        &mut k[STAGES],
        s,
    )
}

/// One accepted point of the shared steps: every member's `w` and rate.
#[derive(Clone, Debug)]
struct Node {
    t: f64,
    w: Vec<f64>,
    k: Vec<f64>,
}

/// The members of an ensemble, followed window by window.
#[derive(Clone, Debug)]
pub struct Members {
    /// The states at the current window's anchor.
    pub states: States,
    /// The largest local error met by each member, in units of the
    /// tolerance (infinite: dropped, to be integrated on its own).
    pub estimates: Vec<f64>,
    /// The members' tolerance (the field's own is tighter: see
    /// [`crate::run::run_ensemble`]).
    tol: Tolerance,
    /// The shared steps' size to try next.
    h: Option<f64>,
    /// The accepted window's nodes (for output within it).
    nodes: Vec<Node>,
    /// The shortest shared step before members are dropped (in the
    /// current window).
    floor: f64,
    /// Shared steps taken, and rejected.
    pub steps: usize,
    pub rejected: usize,
}

/// How much shorter than the field's own steps the members' steps may get
/// before the members that force them are dropped.
const FLOOR: f64 = 0.125;
/// The most a shared step grows from one to the next.
const GROWTH: f64 = 2.0;

impl Members {
    pub fn new(states: States, tol: Tolerance) -> Members {
        let count = states.len();
        Members {
            states,
            estimates: vec![0.0; count],
            tol,
            h: None,
            nodes: Vec::new(),
            floor: 0.0,
            steps: 0,
            rejected: 0,
        }
    }

    fn live(&self, m: usize) -> bool {
        self.estimates[m].is_finite()
    }

    /// Follows the members through a window `[t_r, t_e]` whose field took
    /// `field_steps` steps: their states at `t_e` into `self.states`, the
    /// shared steps kept for [`Members::at`].
    pub fn through(
        &mut self,
        frames: &mut dyn Frames,
        model: &dyn DynModel,
        (t_r, t_e): (f64, f64),
        field_steps: usize,
    ) -> Result<(), Failure> {
        let n = self.states.n;
        let count = self.states.len();
        let shift_rows = n.saturating_sub(model.coordinates());
        let mut s = Scratch::new(n);
        let mut f0 = Frame::new(n);
        frames.frame(t_r, &mut f0)?;
        // w(t_r) = Φ(t_r)⁻¹ (x(t_r) − x_lin(t_r)) (Φ(t_r) is I but for
        // rounding).
        let mut w = vec![0.0; count * n];
        let mut kk = vec![0.0; count * n];
        for m in 0..count {
            let x = self.states.row(m);
            let d: Vec<f64> = x.iter().zip(&f0.x_lin).map(|(a, b)| a - b).collect();
            for i in 0..n {
                w[m * n + i] = (0..n).map(|j| f0.inverse[i * n + j] * d[j]).sum();
            }
            if !self.live(m) {
                continue;
            }
            let r = m * n..(m + 1) * n;
            if rate(model, &f0, shift_rows, &w[r.clone()], &mut kk[r], &mut s).is_err() {
                self.estimates[m] = f64::INFINITY;
            }
        }
        self.nodes.clear();
        self.nodes.push(Node {
            t: t_r,
            w: w.clone(),
            k: kk.clone(),
        });
        let typical = (t_e - t_r) / field_steps.max(1) as f64;
        self.floor = FLOOR * typical;
        let h = self.h.unwrap_or(typical);
        let mut nodes = std::mem::take(&mut self.nodes);
        let integrated = self.integrate(
            frames,
            model,
            (&mut w, &mut kk),
            (t_r, t_e),
            f0,
            h,
            Some(&mut nodes),
        );
        self.nodes = nodes;
        let (end, h) = integrated?;
        self.h = Some(h);
        for m in 0..count {
            let mut x = vec![0.0; n];
            end.state(&w[m * n..(m + 1) * n], &mut x);
            self.states.data[m * n..(m + 1) * n].copy_from_slice(&x);
        }
        Ok(())
    }

    /// The shared steps from `(t, w, kk)` (`f0`: the frame at `t`) to
    /// `t_end`, each member's local error held within the tolerance;
    /// accepted points appended to `nodes` when given. Returns the frame
    /// at `t_end` and the step to try next.
    #[allow(clippy::too_many_arguments)]
    fn integrate(
        &mut self,
        frames: &mut dyn Frames,
        model: &dyn DynModel,
        (w, kk): (&mut Vec<f64>, &mut Vec<f64>),
        (mut t, t_end): (f64, f64),
        f0: Frame,
        mut h: f64,
        mut nodes: Option<&mut Vec<Node>>,
    ) -> Result<(Frame, f64), Failure> {
        let n = self.states.n;
        let count = self.states.len();
        let tol = self.tol;
        let shift_rows = n.saturating_sub(model.coordinates());
        let mut s = Scratch::new(n);
        let mut frames_buf: Vec<Frame> = (0..STAGES).map(|_| Frame::new(n)).collect();
        frames_buf[0] = f0;
        let mut k: [Vec<f64>; STAGES + 1] = std::array::from_fn(|_| vec![0.0; n]);
        let mut w1 = vec![0.0; count * n];
        let (mut e3, mut e5) = (vec![0.0; n], vec![0.0; n]);
        let mut k_new = kk.clone();
        let mut errs = vec![0.0; count];
        let (mut x0, mut x1) = (vec![0.0; n], vec![0.0; n]);
        let (mut e3x, mut e5x) = (vec![0.0; n], vec![0.0; n]);
        let last_stage = STAGES - 1;
        let breaks = frames.breaks();
        while t < t_end {
            // A step ends on the next break of the frames if it would
            // cross it: DOP853's order needs a smooth right side.
            let stop = breaks
                .iter()
                .copied()
                .find(|&b| b > t * (1.0 + 1e-15) + 1e-300 && b < t_end)
                .unwrap_or(t_end);
            let last = t + 1.0000001 * h >= stop;
            let h_try = if last { stop - t } else { h };
            for (st, frame) in frames_buf.iter_mut().enumerate().skip(1) {
                let ts = match st {
                    _ if st == last_stage && last => stop,
                    _ if st == last_stage => t + h_try,
                    _ => t + C[st] * h_try,
                };
                frames.frame(ts, frame)?;
            }
            for m in 0..count {
                errs[m] = 0.0;
                if !self.live(m) {
                    continue;
                }
                let r = m * n..(m + 1) * n;
                k[0].copy_from_slice(&kk[r.clone()]);
                let stepped = step(
                    model,
                    &frames_buf,
                    shift_rows,
                    h_try,
                    &w[r.clone()],
                    &mut k,
                    &mut w1[r.clone()],
                    (&mut e3, &mut e5),
                    &mut s,
                );
                if stepped.is_err() {
                    self.estimates[m] = f64::INFINITY;
                    continue;
                }
                // The error as the state's, measured as direct DOP853
                // measures its own.
                let end = &frames_buf[last_stage];
                frames_buf[0].state(&w[r.clone()], &mut x0);
                end.state(&w1[r.clone()], &mut x1);
                end.map(&e3, &mut e3x);
                end.map(&e5, &mut e5x);
                errs[m] = hairer_error(tol, h_try, &x0, &x1, &e3x, &e5x);
                if !errs[m].is_finite() {
                    self.estimates[m] = f64::INFINITY;
                    errs[m] = 0.0;
                }
                // The new point's rate, the next step's first stage.
                k_new[r].copy_from_slice(&k[STAGES]);
            }
            let worst = (0..count)
                .filter(|&m| self.live(m))
                .map(|m| errs[m])
                .fold(0.0_f64, f64::max);
            // The largest error of many members jumps from step to step
            // more than one motion's: growth is capped lower than DOP853's
            // (6), or a third of the steps were rejected.
            let factor = if worst > 0.0 {
                (0.85 * worst.powf(-0.125)).clamp(1.0 / 6.0, GROWTH)
            } else {
                GROWTH
            };
            if worst > 1.0 {
                let shorter = h_try * factor;
                if shorter >= self.floor {
                    h = shorter;
                    self.rejected += 1;
                    continue;
                }
                // The members that need steps this short are too far from
                // the reference for its field: they go on their own.
                for m in 0..count {
                    if self.live(m) && errs[m] > 1.0 {
                        self.estimates[m] = f64::INFINITY;
                    }
                }
            }
            for m in 0..count {
                if self.live(m) {
                    self.estimates[m] = self.estimates[m].max(errs[m]);
                }
            }
            t = if last { stop } else { t + h_try };
            std::mem::swap(w, &mut w1);
            std::mem::swap(kk, &mut k_new);
            self.steps += 1;
            if let Some(nodes) = nodes.as_deref_mut() {
                nodes.push(Node {
                    t,
                    w: w.clone(),
                    k: kk.clone(),
                });
            }
            frames_buf.swap(0, last_stage);
            if !last {
                h = h_try * factor.min(if worst > 1.0 { 1.0 } else { GROWTH });
            }
        }
        let end = frames_buf.swap_remove(0);
        Ok((end, h))
    }

    /// Every member's state at `t` within the last window: from the shared
    /// point before `t`, by steps within the tolerance (their errors
    /// counted in the estimates).
    pub fn at(
        &mut self,
        frames: &mut dyn Frames,
        model: &dyn DynModel,
        t: f64,
        out: &mut States,
    ) -> Result<(), Failure> {
        let n = self.states.n;
        let count = self.states.len();
        out.n = n;
        out.data.clear();
        let Some(i) = self.nodes.iter().rposition(|node| node.t <= t) else {
            out.data.extend_from_slice(&self.states.data);
            return Ok(());
        };
        let (t_node, mut w, mut kk) = {
            let node = &self.nodes[i];
            (node.t, node.w.clone(), node.k.clone())
        };
        let mut f0 = Frame::new(n);
        frames.frame(t_node, &mut f0)?;
        let end = if t > t_node {
            let h = t - t_node;
            self.integrate(frames, model, (&mut w, &mut kk), (t_node, t), f0, h, None)?
                .0
        } else {
            f0
        };
        out.data.resize(count * n, 0.0);
        for m in 0..count {
            end.state(&w[m * n..(m + 1) * n], &mut out.data[m * n..(m + 1) * n]);
        }
        Ok(())
    }
}
