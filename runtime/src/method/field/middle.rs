//! The quasilinear field's output between steps, judged at each piece's
//! middle (`quasilinear.rs` builds the pieces: one DOP853 step of the
//! motion linearised along the window's predictor, pinned to the two
//! recovered states). A piece is cut in two at its middle where it stands
//! off a DOP853 half step from its start (`halve`); that half step (12
//! evaluations of the linearised motion, each a linearisation of the
//! model) is taken only where the piece's own defect shows its middle
//! past the gate (`defect_estimate`, 4 linearisations).

use crate::linalg::Matrix;
use crate::math::GAUSS_LEGENDRE_4;
use crate::ode::dense::DenseStep;
use crate::ode::dop853::{dense_step_between, one_step};
use crate::ode::system::System;
use crate::ode::tolerance::Tolerance;
use std::sync::OnceLock;

/// How far the output's extension may stand off a half step's state at
/// its piece's middle, in tolerances (the largest component's), before
/// the piece is cut in two there.
const MIDDLE_GATE: f64 = 0.1;
/// The defect's estimate keeps a piece without the half step below this
/// fraction of [`MIDDLE_GATE`]. The estimate stood 0.67–1.14× the half
/// step's verdict over every piece of eight models at rtol 1e-6 … 1e-12
/// and 11 … 1001 samples, within 1 % at all but 1e-12 (docs/BENCHMARKS.md
/// §0, h-mid): below 0.8 of the gate no piece is kept that the half step
/// would cut, so the output is the half step's. At the gate itself (0.8
/// → 1) raindrop_of_distance at rtol 1e-11 kept a piece 0.09997 by the
/// estimate, 0.10004 by the half step: one sample 0.001 → 0.075 rtol off.
const KEEP_BELOW: f64 = 0.8;
/// How many times a piece may be halved by the middle test.
const MOST_HALVINGS: usize = 3;

/// `pieces` (`dense_steps_between`'s, each pinned to its end), each cut
/// in two at its middle while its extension there stands more than
/// `MIDDLE_GATE` tolerances off one DOP853 step of half its length from
/// its start (12 evaluations; that step's own error is about 1/512 of
/// the whole piece's) — judged first by the piece's defect
/// ([`defect_estimate`], 4 evaluations), the half step taken only where
/// that shows the middle past the gate: the first half then ends on the
/// half step's state, the second starts there. Why: a field step is as long as the smooth
/// coefficients allow, often longer than one explicit step of the
/// motion, and the order-7 extension's error in mid-step is not bounded
/// by its end's miss (order 8), which alone decided the pieces:
/// raindrop_of_distance at rtol 1e-10 had ends missed by 1e-6 … 1e-2
/// tolerances and samples 0.6 rtol off, the gravity-turn rocket's longer
/// steps up to 6× its ends' error (docs/BENCHMARKS.md §0, h-gturn2).
///
/// `x_new` is the last piece's end (the recovered state); the others' ends
/// are the next pieces' starts, which their extensions give exactly.
pub(super) fn refined<S: System + ?Sized>(
    system: &S,
    pieces: Vec<DenseStep>,
    x_new: &[f64],
    tol: Tolerance,
    scratch: &mut MiddleScratch,
) -> Vec<DenseStep> {
    let n = x_new.len();
    let mut out = Vec::with_capacity(pieces.len());
    let count = pieces.len();
    let mut pieces = pieces.into_iter().peekable();
    let mut end = vec![0.0; n];
    while let Some(piece) = pieces.next() {
        match pieces.peek() {
            Some(next) => next.eval(next.t_old, &mut end),
            None => end.copy_from_slice(x_new),
        }
        halve(system, piece, &end, tol, MOST_HALVINGS, scratch, &mut out);
    }
    debug_assert!(out.len() >= count);
    out
}

/// `piece`, ending on `end`, into `out`, halved as [`refined`] says, at
/// most `left` times.
fn halve<S: System + ?Sized>(
    system: &S,
    piece: DenseStep,
    end: &[f64],
    tol: Tolerance,
    left: usize,
    scratch: &mut MiddleScratch,
    out: &mut Vec<DenseStep>,
) {
    let (t_old, t_new) = (piece.t_old, piece.t_new);
    let h = t_new - t_old;
    let t_mid = t_old + 0.5 * h;
    if left == 0 || !(t_mid > t_old && t_mid < t_new) {
        out.push(piece);
        return;
    }
    // Within the gate by the piece's own defect: kept, no half step (the
    // half step is taken to cut, its state the halves' joint, and where
    // the defect is near the gate: `KEEP_BELOW`).
    // After a cut the next piece is most likely cut too (pendulum_3 cuts
    // 84 % of its pieces): the half step alone, no estimate spent first.
    let kept = !scratch.last_cut
        && defect_estimate(system, &piece, t_mid, tol, scratch)
            .is_some_and(|off| off <= KEEP_BELOW * MIDDLE_GATE);
    scratch.last_cut = false;
    if kept {
        out.push(piece);
        return;
    }
    let n = end.len();
    let (mut start, mut middle, mut half) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    // The extension's value at its start is its first coefficient: the
    // start state exactly.
    piece.eval(t_old, &mut start);
    piece.eval(t_mid, &mut middle);
    // A half step that fails or is not finite (into a singularity): the
    // piece as it was.
    if one_step(system, t_old, &start, t_mid - t_old, &mut half).is_err()
        || half.iter().any(|v| !v.is_finite())
    {
        out.push(piece);
        return;
    }
    let off = tol.tolerances_off(&middle, &half);
    if off <= MIDDLE_GATE {
        out.push(piece);
        return;
    }
    scratch.last_cut = true;
    // Halves that fail (not finite): the piece as it was.
    let (Ok(first), Ok(second)) = (
        dense_step_between(system, t_old, t_mid - t_old, &start, &half),
        dense_step_between(system, t_mid, t_new - t_mid, &half, end),
    ) else {
        out.push(piece);
        return;
    };
    // The order-7 extension's error in mid-step shrinks like `h^8`: a
    // half is about 1/256 as far off as the whole. Its own middle is
    // judged only where that may not be enough (by a factor 4 of margin):
    // a judge at every half cost the chaotic pendulum_3, whose pieces are
    // 0.1–3 tolerances off, 2.8× the instructions at 101 samples.
    let left = if off > 64.0 * MIDDLE_GATE {
        left - 1
    } else {
        0
    };
    halve(system, first, &half, tol, left, scratch, out);
    halve(system, second, end, tol, left, scratch, out);
}

/// The transport over half a piece is summed as a series in `τ A` only
/// where `τ ‖A‖₁` is at most this (else no estimate: the half step). At
/// 4 the chaotic pendulum_3's long pieces at rtol 1e-6 had none; at 16
/// they are as close as the others.
const MOST_SPREAD: f64 = 16.0;
/// The extension is a polynomial of degree 7 in `θ`: its values at 8
/// points give it, and its derivative, exactly (up to rounding).
const POINTS: usize = 8;
/// The Chebyshev–Lobatto points `(1 − cos(π j/7))/2` on `[0, 1]` the
/// extension is read at.
const LOBATTO: [f64; POINTS] = [
    0.0,
    0.049_515_566_048_790_43,
    0.188_255_099_070_633_2,
    0.388_739_533_021_842_8,
    0.611_260_466_978_157_2,
    0.811_744_900_929_366_7,
    0.950_484_433_951_209_5,
    1.0,
];

/// Lagrange's basis on [`LOBATTO`]'s points at the Gauss nodes of the
/// first half (`θ = ξ/2`), and its derivative: row `k` weighs the values
/// for node `k`.
struct NodeWeights {
    value: [[f64; POINTS]; 4],
    slope: [[f64; POINTS]; 4],
}

fn node_weights() -> &'static NodeWeights {
    static WEIGHTS: OnceLock<NodeWeights> = OnceLock::new();
    WEIGHTS.get_or_init(|| {
        let mut w = NodeWeights {
            value: [[0.0; POINTS]; 4],
            slope: [[0.0; POINTS]; 4],
        };
        for (k, &(xi, _)) in GAUSS_LEGENDRE_4.iter().enumerate() {
            let theta = 0.5 * xi;
            for j in 0..POINTS {
                let (mut basis, mut sum) = (1.0, 0.0);
                for m in (0..POINTS).filter(|&m| m != j) {
                    basis *= (theta - LOBATTO[m]) / (LOBATTO[j] - LOBATTO[m]);
                    sum += 1.0 / (theta - LOBATTO[m]);
                }
                w.value[k][j] = basis;
                w.slope[k][j] = basis * sum;
            }
        }
        w
    })
}

/// The buffers of [`defect_estimate`], kept by the field across its
/// outputs (the estimate runs at every sample-holding step: allocating
/// them there cost a quarter of it on the small models).
pub(super) struct MiddleScratch {
    /// The extension at [`LOBATTO`]'s points, point by point.
    values: Vec<f64>,
    u: Vec<f64>,
    slope: Vec<f64>,
    rate: Vec<f64>,
    term: Vec<f64>,
    next: Vec<f64>,
    sum: Vec<f64>,
    error: Vec<f64>,
    a: Matrix,
    /// The last piece judged was cut by the half step.
    last_cut: bool,
}

impl MiddleScratch {
    /// As [`MiddleScratch::new`] left it, for another solve (the buffers
    /// are written before they are read).
    pub(super) fn reset(&mut self) {
        self.last_cut = false;
    }

    pub(super) fn new(n: usize) -> MiddleScratch {
        MiddleScratch {
            values: vec![0.0; POINTS * n],
            u: vec![0.0; n],
            slope: vec![0.0; n],
            rate: vec![0.0; n],
            term: vec![0.0; n],
            next: vec![0.0; n],
            sum: vec![0.0; n],
            error: vec![0.0; n],
            a: Matrix::zeros(n, n),
            last_cut: false,
        }
    }
}

/// How many tolerances (as [`Tolerance::tolerances_off`]) the piece's extension `u`
/// stands off the linearised motion's solution from its start at `t_mid`:
/// from its defect `δ = u' − X(t, u)`, since the error `e = u − x` solves
/// `e' = A e + δ` with `e(t_old) = 0`, so `e(t_mid) = ∫ Φ(t_mid, s) δ(s) ds`
/// over the first half, summed at four Gauss nodes with `Φ(t_mid, s) ≈
/// exp((t_mid − s) A(s))` (its series). Four linearisations (the nodes)
/// where the half step takes twelve; the other evaluations at a node
/// reuse its linearisation. `None` where it is not made: an evaluation
/// failed, or the motion moves too much over half the piece for the
/// series (`MOST_SPREAD`).
fn defect_estimate<S: System + ?Sized>(
    system: &S,
    piece: &DenseStep,
    t_mid: f64,
    tol: Tolerance,
    sc: &mut MiddleScratch,
) -> Option<f64> {
    let n = sc.u.len();
    let (t_old, h) = (piece.t_old, piece.h);
    if !(h > 0.0) || sc.values.len() != POINTS * n {
        return None;
    }
    for (v, theta) in sc.values.chunks_exact_mut(n).zip(LOBATTO) {
        piece.eval(t_old + theta * h, v);
    }
    let weights = node_weights();
    let half = t_mid - t_old;
    let values = &sc.values[..POINTS * n];
    let (u, slope, rate) = (&mut sc.u[..n], &mut sc.slope[..n], &mut sc.rate[..n]);
    let (term, next, sum) = (&mut sc.term[..n], &mut sc.next[..n], &mut sc.sum[..n]);
    let error = &mut sc.error[..n];
    error.fill(0.0);
    for (k, &(xi, weight)) in GAUSS_LEGENDRE_4.iter().enumerate() {
        let s = t_old + xi * half;
        u.fill(0.0);
        slope.fill(0.0);
        for j in 0..POINTS {
            let (wv, ws) = (weights.value[k][j], weights.slope[k][j]);
            let v = &values[j * n..j * n + n];
            for i in 0..n {
                u[i] += wv * v[i];
                slope[i] += ws * v[i];
            }
        }
        system.rhs(s, u, rate).ok()?;
        system.jacobian(s, u, &mut sc.a).ok()?;
        let tau = t_mid - s;
        if !(tau * sc.a.one_norm() <= MOST_SPREAD) {
            return None;
        }
        // The defect, then exp(τ A) δ: terms (τ A)^j δ / j! until they no
        // longer count.
        for i in 0..n {
            term[i] = slope[i] / h - rate[i];
            sum[i] = term[i];
        }
        for j in 1..=80 {
            sc.a.mul_vec(term, next);
            let scale = tau / j as f64;
            let (mut largest_term, mut largest_sum) = (0.0_f64, 0.0_f64);
            for i in 0..n {
                term[i] = scale * next[i];
                sum[i] += term[i];
                largest_term = largest_term.max(term[i].abs());
                largest_sum = largest_sum.max(sum[i].abs());
            }
            if largest_term <= 1e-3 * largest_sum {
                break;
            }
        }
        for i in 0..n {
            error[i] += weight * half * sum[i];
        }
    }
    // The middle, and the motion's state there.
    piece.eval(t_mid, u);
    for i in 0..n {
        next[i] = u[i] - error[i];
    }
    Some(tol.tolerances_off(u, next))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::failure::Failure;

    /// `y1' = y2, y2' = −(1 + t) y1 + 1`: linear, its matrix varying in
    /// time, as the linearised motion is.
    struct Varying;

    impl System for Varying {
        fn dim(&self) -> usize {
            2
        }
        fn rhs(&self, t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), Failure> {
            dy[0] = y[1];
            dy[1] = -(1.0 + t) * y[0] + 1.0;
            Ok(())
        }
        fn jacobian(&self, t: f64, _y: &[f64], jac: &mut Matrix) -> Result<(), Failure> {
            jac[(0, 0)] = 0.0;
            jac[(0, 1)] = 1.0;
            jac[(1, 0)] = -(1.0 + t);
            jac[(1, 1)] = 0.0;
            Ok(())
        }
        fn time_partial(&self, _t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), Failure> {
            dydt[0] = 0.0;
            dydt[1] = -y[0];
            Ok(())
        }
    }

    /// The state at `t0 + h` from `y0`, by 256 DOP853 steps: exact here.
    fn reference(t0: f64, y0: &[f64], h: f64) -> Vec<f64> {
        let mut y = y0.to_vec();
        let mut next = vec![0.0; 2];
        for k in 0..256 {
            let t = t0 + h * k as f64 / 256.0;
            one_step(&Varying, t, &y, h / 256.0, &mut next).unwrap();
            y.copy_from_slice(&next);
        }
        y
    }

    /// The defect's estimate of a piece's middle agrees with the half
    /// step's verdict it stands in for, on pieces from well within the
    /// gate to far off it (longer pieces, an end pinned off the motion).
    #[test]
    fn the_defect_estimate_agrees_with_the_half_step() {
        let tol = Tolerance {
            rtol: 1e-10,
            atol: 1e-12,
        };
        let y0 = [1.0, 0.0];
        let mut judged = 0;
        for &h in &[0.1, 0.3, 0.6, 1.2] {
            for &pin in &[0.0, 1e-9] {
                let t0 = 0.5;
                let mut end = reference(t0, &y0, h);
                end[0] += pin;
                let piece = dense_step_between(&Varying, t0, h, &y0, &end).unwrap();
                let t_mid = t0 + 0.5 * h;
                let mut middle = vec![0.0; 2];
                piece.eval(t_mid, &mut middle);
                let mut half = vec![0.0; 2];
                one_step(&Varying, t0, &y0, 0.5 * h, &mut half).unwrap();
                let off = tol.tolerances_off(&middle, &half);
                let estimate =
                    defect_estimate(&Varying, &piece, t_mid, tol, &mut MiddleScratch::new(2))
                        .unwrap();
                if off > 1e-3 {
                    judged += 1;
                    let ratio = estimate / off;
                    assert!(
                        (0.8..1.25).contains(&ratio),
                        "h {h}, pin {pin}: estimate {estimate:e}, half step {off:e}"
                    );
                } else {
                    assert!(estimate < 2e-3, "h {h}: estimate {estimate:e}");
                }
            }
        }
        assert!(judged >= 4, "only {judged} pieces measurably off");
    }
}
