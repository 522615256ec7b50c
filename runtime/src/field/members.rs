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
//! (the square of the spread) and free of the motion's fast linear part,
//! and it vanishes for an affine model. It is integrated by the
//! Dormand–Prince pair 5(4) on one sequence of steps shared by all
//! members (the frames `x_lin, Φ, Φ⁻¹, p, X(p), A` at each stage time are
//! computed once for all of them), each member's local error — mapped to
//! the state through `Φ` — kept within the tolerance as direct integration
//! keeps its own. A member whose error would need steps much shorter than
//! the field's own (too far from the reference), or whose equations fail,
//! is dropped: the run integrates it on its own.

use crate::ensemble::States;
use crate::failure::Failure;
use crate::linalg::{Lu, Matrix};
use crate::model::DynModel;
use crate::tolerance::Tolerance;

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
    frame.a.mul_vec(&s.d, &mut s.ad);
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

// The Dormand–Prince pair 5(4) (Hairer, Nørsett & Wanner, Table II.5.2).
const C: [f64; 7] = [0.0, 0.2, 0.3, 0.8, 8.0 / 9.0, 1.0, 1.0];
const A: [[f64; 6]; 7] = [
    [0.0; 6],
    [0.2, 0.0, 0.0, 0.0, 0.0, 0.0],
    [3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0, 0.0],
    [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0, 0.0],
    [
        19372.0 / 6561.0,
        -25360.0 / 2187.0,
        64448.0 / 6561.0,
        -212.0 / 729.0,
        0.0,
        0.0,
    ],
    [
        9017.0 / 3168.0,
        -355.0 / 33.0,
        46732.0 / 5247.0,
        49.0 / 176.0,
        -5103.0 / 18656.0,
        0.0,
    ],
    [
        35.0 / 384.0,
        0.0,
        500.0 / 1113.0,
        125.0 / 192.0,
        -2187.0 / 6784.0,
        11.0 / 84.0,
    ],
];
/// The 5th-order weights minus the 4th-order ones.
const E: [f64; 7] = [
    71.0 / 57600.0,
    0.0,
    -71.0 / 16695.0,
    71.0 / 1920.0,
    -17253.0 / 339200.0,
    22.0 / 525.0,
    -1.0 / 40.0,
];

/// One member's DOPRI5 step from `(w0, k1)` over `h` with the frames of
/// the stage times (`frames[s]` at `t + C[s] h`; the last two coincide).
/// Writes `w1`, its rate `k7` and the 4th-order solution's error `e`.
#[allow(clippy::too_many_arguments)]
fn step(
    model: &dyn DynModel,
    frames: &[Frame],
    shift_rows: usize,
    h: f64,
    w0: &[f64],
    k1: &[f64],
    k: &mut [Vec<f64>; 7],
    w1: &mut [f64],
    e: &mut [f64],
    s: &mut Scratch,
) -> Result<(), Failure> {
    let n = w0.len();
    k[0].copy_from_slice(k1);
    let mut stage = std::mem::take(&mut s.stage);
    for st in 1..7 {
        for j in 0..n {
            let mut v = w0[j];
            for (l, kl) in k.iter().enumerate().take(st) {
                v += h * A[st][l] * kl[j];
            }
            stage[j] = v;
        }
        if st == 6 {
            w1.copy_from_slice(&stage);
        }
        let rated = rate(model, &frames[st.min(5)], shift_rows, &stage, &mut k[st], s);
        if let Err(failure) = rated {
            s.stage = stage;
            return Err(failure);
        }
    }
    s.stage = stage;
    for j in 0..n {
        e[j] = h * (0..7).map(|l| E[l] * k[l][j]).sum::<f64>();
    }
    Ok(())
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
    /// The shared steps' size to try next.
    h: Option<f64>,
    /// The accepted window's nodes (for output within it).
    nodes: Vec<Node>,
    /// The shortest shared step before members are dropped (in the
    /// current window).
    floor: f64,
    /// Shared steps taken.
    pub steps: usize,
}

/// How much shorter than the field's own steps the members' steps may get
/// before the members that force them are dropped.
const FLOOR: f64 = 0.125;

impl Members {
    pub fn new(states: States) -> Members {
        let count = states.len();
        Members {
            states,
            estimates: vec![0.0; count],
            h: None,
            nodes: Vec::new(),
            floor: 0.0,
            steps: 0,
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
        tol: Tolerance,
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
            tol,
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
        tol: Tolerance,
        (w, kk): (&mut Vec<f64>, &mut Vec<f64>),
        (mut t, t_end): (f64, f64),
        f0: Frame,
        mut h: f64,
        mut nodes: Option<&mut Vec<Node>>,
    ) -> Result<(Frame, f64), Failure> {
        let n = self.states.n;
        let count = self.states.len();
        let shift_rows = n.saturating_sub(model.coordinates());
        let mut s = Scratch::new(n);
        let mut frames_buf: Vec<Frame> = (0..6).map(|_| Frame::new(n)).collect();
        frames_buf[0] = f0;
        let mut k: [Vec<f64>; 7] = std::array::from_fn(|_| vec![0.0; n]);
        let (mut w1, mut e) = (vec![0.0; count * n], vec![0.0; count * n]);
        let mut k_new = kk.clone();
        let mut errs = vec![0.0; count];
        let (mut x0, mut x1, mut ex) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        while t < t_end {
            let last = t + 1.0000001 * h >= t_end;
            let h_try = if last { t_end - t } else { h };
            for (st, frame) in frames_buf.iter_mut().enumerate().skip(1) {
                let ts = match st {
                    5 if last => t_end,
                    5 => t + h_try,
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
                let stepped = step(
                    model,
                    &frames_buf,
                    shift_rows,
                    h_try,
                    &w[r.clone()],
                    &kk[r.clone()],
                    &mut k,
                    &mut w1[r.clone()],
                    &mut e[r.clone()],
                    &mut s,
                );
                if stepped.is_err() {
                    self.estimates[m] = f64::INFINITY;
                    continue;
                }
                // The error as the state's, scaled as direct integration's.
                frames_buf[0].state(&w[r.clone()], &mut x0);
                frames_buf[5].state(&w1[r.clone()], &mut x1);
                frames_buf[5].map(&e[r.clone()], &mut ex);
                let sum: f64 = (0..n)
                    .map(|j| {
                        let sc = tol.atol + tol.rtol * x0[j].abs().max(x1[j].abs());
                        (ex[j] / sc).powi(2)
                    })
                    .sum();
                errs[m] = (sum / n as f64).sqrt();
                if !errs[m].is_finite() {
                    self.estimates[m] = f64::INFINITY;
                    errs[m] = 0.0;
                }
                // The new rate is the last stage's (FSAL).
                k_new[r].copy_from_slice(&k[6]);
            }
            let worst = (0..count)
                .filter(|&m| self.live(m))
                .map(|m| errs[m])
                .fold(0.0_f64, f64::max);
            let factor = if worst > 0.0 {
                (0.9 * worst.powf(-0.2)).clamp(0.2, 5.0)
            } else {
                5.0
            };
            if worst > 1.0 {
                let shorter = h_try * factor;
                if shorter >= self.floor {
                    h = shorter;
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
            t = if last { t_end } else { t + h_try };
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
            frames_buf.swap(0, 5);
            if !last {
                h = h_try * factor.min(if worst > 1.0 { 1.0 } else { 5.0 });
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
        tol: Tolerance,
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
            self.integrate(
                frames,
                model,
                tol,
                (&mut w, &mut kk),
                (t_node, t),
                f0,
                h,
                None,
            )?
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
