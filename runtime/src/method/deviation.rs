//! A non-affine ensemble's members as deviations from one base motion.
//!
//! The base (the first member) is integrated once, tighter than the
//! members' tolerance, and kept as its continuous extension `x_b(t)`. Each
//! member's state is `x = x_b(t) + d`, and its deviation obeys
//!
//! `d' = X(t, x_b(t) + d) − X(t, x_b(t))`,
//!
//! the member's own motion in shifted variables: exact for any distance
//! from the base (no linearisation, no frames), and it costs each member
//! one right side a stage and O(N) work. All members are integrated by
//! DOP853's tableau on ONE sequence of steps, so that `x_b` and `X(t, x_b)`
//! at each stage time are computed once for all of them. Each member's
//! error is DOP853's own estimate on `d`, measured in the norm of the state
//! (`atol + rtol·|x|`): since `d` and its derivatives are of the size of the
//! spread, a member at spread 1e-2 needs `d` to relative accuracy
//! `rtol/spread` only, and the shared steps are about `spread^(-1/8)` times
//! a direct run's. The worst member sets the step; one that needs steps
//! much shorter than the others' leaves (its estimate infinite) and the
//! run integrates it on its own ([`crate::run::run_ensemble`]).
//!
//! The base's extension is a polynomial within each of its steps and
//! continuous across them; its derivative jumps there by the base's local
//! defect, which enters `d'` only through `X_x(x_b + d) − X_x(x_b)` (of the
//! spread times the base's tolerance): the shared steps are not tied to the
//! base's. The base's own error enters each member as it enters the base
//! (a member's error is the base's defect carried along the member's
//! motion), hence the base's tighter tolerance.
//!
//! Samples between the shared steps come from DOP853's continuous
//! extension (`contd8`) of `d`, three more right sides a member on the steps
//! that hold a sample, not extra steps.
//!
//! A member's step on the shared steps is `deviation/member.rs`'s, one
//! member at a time or four in SIMD lanes (one step over either number).

mod member;

use crate::ensemble::States;
use crate::failure::Failure;
use crate::lanes::WIDTH;
use crate::model::DynModel;
use crate::ode::dop853::tableau::{A_EXTRA, C, C_EXTRA, D, STAGES};
use crate::ode::tolerance::Tolerance;
use member::{group_step, member_step, LaneBuffers};

/// A member leaves the shared steps when its error is this many times the
/// error of the member at the 90th percentile (and above 1): it would need
/// steps more than twice shorter (`256^(1/8) = 2`) than nine in ten others.
const LEAVE: f64 = 256.0;
/// The most a shared step grows from one to the next: the largest error
/// of many members jumps from step to step more than one motion's does.
const GROWTH: f64 = 3.0;
/// The shortest shared step, relative to the span: members still beyond
/// the tolerance there leave (their own integrations report the cause).
const SHORTEST: f64 = 1e-12;
/// How many of last step's worst members are stepped first.
const FIRST: usize = 8;

/// The base's motion: its continuous extension at any time of its span
/// (the run's [`crate::run::solution::Solution`]; this module sits below
/// the run).
pub trait Base {
    fn at(&self, t: f64, out: &mut [f64]);
    /// Its steps' median length: the shared steps' first try (the base's
    /// first step is DOP853's cautious start, at a tighter tolerance).
    fn typical_step(&self) -> Option<f64>;
}

/// The base at a stage time: `x_b(t)` and `X(t, x_b(t))`.
#[derive(Clone)]
struct Point {
    t: f64,
    x: Vec<f64>,
    rate: Vec<f64>,
}

impl Point {
    fn new(n: usize) -> Point {
        Point {
            t: f64::NAN,
            x: vec![0.0; n],
            rate: vec![0.0; n],
        }
    }

    fn set(&mut self, model: &dyn DynModel, base: &dyn Base, t: f64) -> Result<(), Failure> {
        self.t = t;
        base.at(t, &mut self.x);
        model.rhs(t, &self.x, &mut self.rate)
    }

    /// `g = X(t, x_b + d) − X(t, x_b)`; `x` is scratch.
    fn rate(
        &self,
        model: &dyn DynModel,
        d: &[f64],
        x: &mut [f64],
        g: &mut [f64],
    ) -> Result<(), Failure> {
        for ((x, b), d) in x.iter_mut().zip(&self.x).zip(d) {
            *x = b + d;
        }
        model.rhs(self.t, x, g)?;
        for (g, r) in g.iter_mut().zip(&self.rate) {
            *g -= r;
        }
        // A non-finite rate makes the member's error estimate non-finite:
        // it leaves there (checked once a step, not once a stage).
        Ok(())
    }
}

/// Where a member left the shared steps: the time and its state there
/// (`None`: it did not, or it left at the start).
pub type Left = Option<(f64, Vec<f64>)>;

/// What following the members did.
#[derive(Clone, Debug)]
pub struct Followed {
    /// The largest local error of each member, in units of the tolerance
    /// (infinite: it left, to be integrated on its own).
    pub estimates: Vec<f64>,
    /// Where each member that left did so after its start: the time and
    /// its state there (to be integrated on its own from there).
    pub left: Vec<Left>,
    /// Shared steps accepted and rejected.
    pub steps: usize,
    pub rejected: usize,
    /// Members' steps tried, accepted or not (a step rejected early
    /// stepped only the members that were worst at the last one).
    pub member_steps: usize,
}

/// Follows `members` (the first is the base, `base` its tight solution
/// from `t0`) to `t1` at `tol`, every member's state at each time of
/// `times` pushed onto `samples` (ascending, within `(t0, t1]`; those at
/// `t0` are the caller's).
pub fn follow(
    model: &dyn DynModel,
    base: &dyn Base,
    tol: Tolerance,
    members: &States,
    (t0, t1): (f64, f64),
    times: &[f64],
    samples: &mut Vec<(f64, States)>,
) -> Result<Followed, Failure> {
    let n = members.n;
    let count = members.len();
    let mut estimates = vec![0.0; count];
    let mut left = vec![None; count];
    let (mut steps, mut rejected, mut member_steps) = (0, 0, 0);
    // Points of the base: the step's start, its stages, its end (the
    // last stage is at `t + h`), and the continuous extension's three.
    let mut start = Point::new(n);
    start.set(model, base, t0)?;
    let mut stages: Vec<Point> = (0..STAGES).map(|_| Point::new(n)).collect();
    let mut extra: Vec<Point> = (0..3).map(|_| Point::new(n)).collect();
    let mut x = vec![0.0; n];
    let mut stage = vec![0.0; n];
    // Each member's deviation, and its stages of the step tried
    // (Hairer's numbering: `k[0]` the start rate, `k[12]` the end rate,
    // which becomes the next step's `k[0]`), for the continuous extension.
    let mut d = vec![0.0; count * n];
    let mut k = vec![0.0; count * (STAGES + 1) * n];
    for m in 0..count {
        let r = m * n..(m + 1) * n;
        for ((d, xm), b) in d[r.clone()].iter_mut().zip(members.row(m)).zip(&start.x) {
            *d = xm - b;
        }
        let k0 = &mut k[m * (STAGES + 1) * n..][..n];
        if start.rate(model, &d[r], &mut x, k0).is_err() {
            estimates[m] = f64::INFINITY;
        }
    }
    let mut d1 = vec![0.0; count * n];
    let mut errs = vec![0.0; count];
    let (mut e3, mut e5) = (vec![0.0; n], vec![0.0; n]);
    let (mut x0, mut x1) = (vec![0.0; n], vec![0.0; n]);
    let mut sorted = Vec::with_capacity(count);
    let mut order: Vec<usize> = (0..count).filter(|&m| estimates[m].is_finite()).collect();
    let mut cont = vec![0.0; count * 8 * n];
    let mut ks = vec![0.0; 3 * n];
    // Members four at a time through the model's right side over lanes,
    // when it has one (its default loop over lanes would gain nothing).
    let mut lanes = model.has_lanes().then(|| LaneBuffers::new(n));
    let span = t1 - t0;
    // The base's typical step (the controller takes it from there; a
    // first try too long is rejected after the first few members).
    let mut h = base.typical_step().unwrap_or(span).min(span);
    let mut next = times.partition_point(|&s| s <= t0);
    let mut t = t0;
    while t < t1 {
        let last = t + 1.0000001 * h >= t1;
        let h_try = if last { t1 - t } else { h };
        let t_new = if last { t1 } else { t + h_try };
        for (s, point) in stages.iter_mut().enumerate().skip(1) {
            let ts = if s == STAGES - 1 {
                t_new
            } else {
                t + C[s] * h_try
            };
            point.set(model, base, ts)?;
        }
        errs.fill(0.0);
        // The members that were worst last step, first: when one of them
        // fails (and would not leave), the step is rejected without
        // stepping the others. (Rejecting at the first member that
        // fails, wherever it is, took 9 % fewer member steps on the
        // double pendulum but longer accepted steps, its factor set by
        // that member rather than the worst: 1.05-3.6x farther from tight
        // runs, BENCHMARKS §4a.)
        let (head, tail) = order.split_at(order.len().min(FIRST));
        let mut ctx = Stepping {
            model,
            stages: &stages,
            start: &start,
            h: h_try,
            tol,
            lanes: lanes.as_mut(),
            // The stages between the ends are read only by the continuous
            // extension, on a step that holds a sample before its end.
            inner: next < times.len() && times[next] < t_new,
            x: &mut x,
            scratch: [&mut e3, &mut e5, &mut x0, &mut x1],
        };
        member_steps += ctx.step(
            head,
            (&d, &mut d1, &mut k),
            &mut errs,
            (&mut estimates, &mut left),
        );
        let mut early = false;
        if !tail.is_empty() {
            let first = live_max(&errs, &estimates);
            early = first > 1.0 && first <= LEAVE;
            if !early {
                member_steps += ctx.step(
                    tail,
                    (&d, &mut d1, &mut k),
                    &mut errs,
                    (&mut estimates, &mut left),
                );
            }
        }
        let mut worst = live_max(&errs, &estimates);
        if worst > 1.0 && !early {
            // Members whose steps would be much shorter than the others'
            // leave rather than set everyone's; below the shortest
            // step, all beyond 1 do.
            let bar = if h_try < SHORTEST * span {
                1.0
            } else {
                sorted.clear();
                sorted.extend(
                    (0..count)
                        .filter(|&m| estimates[m].is_finite())
                        .map(|m| errs[m]),
                );
                leaving_bar(&mut sorted)
            };
            for m in 0..count {
                if estimates[m].is_finite() && errs[m] > bar {
                    leave(&mut estimates, &mut left, m, &start, &d);
                }
            }
            worst = live_max(&errs, &estimates);
        }
        let factor = if worst > 0.0 {
            (0.9 * worst.powf(-0.125)).clamp(0.3, GROWTH)
        } else {
            GROWTH
        };
        if worst > 1.0 {
            h = h_try * factor;
            rejected += 1;
            continue;
        }
        // Accepted: the samples inside the step from the continuous
        // extension (made once a step, for the steps that hold one), at
        // its end from the step itself.
        let mut extended = false;
        while next < times.len() && times[next] <= t_new {
            let ts = times[next];
            let mut states = States {
                n,
                data: vec![0.0; count * n],
            };
            if ts < t_new && !extended {
                extended = true;
                for (e, point) in extra.iter_mut().enumerate() {
                    point.set(model, base, t + C_EXTRA[e] * h_try)?;
                }
                for m in 0..count {
                    if !estimates[m].is_finite() {
                        continue;
                    }
                    let r = m * n..(m + 1) * n;
                    let km = &k[m * (STAGES + 1) * n..(m + 1) * (STAGES + 1) * n];
                    let made = extension(
                        model,
                        &extra,
                        h_try,
                        (&d[r.clone()], &d1[r]),
                        km,
                        &mut cont[m * 8 * n..(m + 1) * 8 * n],
                        &mut ks,
                        (&mut x, &mut stage),
                    );
                    let block = &cont[m * 8 * n..(m + 1) * 8 * n];
                    if made.is_err() || !block.iter().all(|v| v.is_finite()) {
                        leave(&mut estimates, &mut left, m, &start, &d);
                    }
                }
            }
            if ts >= t_new {
                for m in 0..count {
                    let r = m * n..(m + 1) * n;
                    for ((o, b), d) in states.data[r.clone()]
                        .iter_mut()
                        .zip(&stages[STAGES - 1].x)
                        .zip(&d1[r])
                    {
                        *o = b + d;
                    }
                }
            } else {
                base.at(ts, &mut x0);
                let theta = (ts - t) / h_try;
                for m in 0..count {
                    let out = &mut states.data[m * n..(m + 1) * n];
                    contd8(&cont[m * 8 * n..(m + 1) * 8 * n], n, theta, out);
                    for (o, b) in out.iter_mut().zip(&x0) {
                        *o += b;
                    }
                }
            }
            samples.push((ts, states));
            next += 1;
        }
        for m in 0..count {
            if estimates[m].is_finite() {
                estimates[m] = estimates[m].max(errs[m]);
                let km = &mut k[m * (STAGES + 1) * n..(m + 1) * (STAGES + 1) * n];
                km.copy_within(STAGES * n.., 0);
            }
        }
        order.retain(|&m| estimates[m].is_finite());
        if order.len() > FIRST {
            order.select_nth_unstable_by(FIRST, |&a, &b| errs[b].total_cmp(&errs[a]));
        }
        std::mem::swap(&mut d, &mut d1);
        std::mem::swap(&mut start, &mut stages[STAGES - 1]);
        t = t_new;
        steps += 1;
        if !last {
            h = h_try * factor;
        }
    }
    Ok(Followed {
        estimates,
        left,
        steps,
        rejected,
        member_steps,
    })
}

/// One shared step's work on the members: the base's points and the
/// step, and the scratch the members' steps share.
struct Stepping<'a> {
    model: &'a dyn DynModel,
    stages: &'a [Point],
    start: &'a Point,
    h: f64,
    tol: Tolerance,
    lanes: Option<&'a mut LaneBuffers>,
    /// The members' inner stages are kept (for the continuous extension).
    inner: bool,
    x: &'a mut [f64],
    scratch: [&'a mut Vec<f64>; 4],
}

impl Stepping<'_> {
    /// Steps the members of `list` still on the shared steps (deviations
    /// `d`, stages `k`, ends into `d1`), their errors into `errs`; a
    /// member whose step fails or is not finite leaves. Returns how many
    /// members were stepped. With lanes, four at a time (a last one alone
    /// by the scalar step): each member's numbers are those of its scalar
    /// step, whatever its group.
    fn step(
        &mut self,
        list: &[usize],
        (d, d1, k): (&[f64], &mut [f64], &mut [f64]),
        errs: &mut [f64],
        (estimates, left): (&mut [f64], &mut [Left]),
    ) -> usize {
        let n = self.start.x.len();
        let mut at = 0;
        let mut stepped = 0;
        loop {
            let mut group = [0; WIDTH];
            let mut count = 0;
            while count < WIDTH && at < list.len() {
                let m = list[at];
                at += 1;
                if estimates[m].is_finite() {
                    group[count] = m;
                    count += 1;
                }
            }
            if count == 0 {
                return stepped;
            }
            stepped += count;
            let grouped = match self.lanes.as_deref_mut() {
                Some(buffers) if count > 1 => {
                    // Lanes past the group's members repeat its first (their
                    // results are not kept).
                    for l in count..WIDTH {
                        group[l] = group[0];
                    }
                    let result = group_step(
                        self.model,
                        (self.stages, &self.start.x),
                        (self.h, self.tol),
                        &group,
                        (d, &mut *k),
                        buffers,
                    );
                    match result {
                        Ok(found) => {
                            for (l, &m) in group.iter().enumerate().take(count) {
                                buffers.scatter(l, m, n, (d1, k), self.inner);
                                if found[l].is_finite() {
                                    errs[m] = found[l];
                                } else {
                                    leave(estimates, left, m, self.start, d);
                                }
                            }
                            true
                        }
                        // A failure in one lane: each member by its scalar
                        // step, which fails for that member alone.
                        Err(_) => false,
                    }
                }
                _ => false,
            };
            if grouped {
                continue;
            }
            for &m in &group[..count] {
                let r = m * n..(m + 1) * n;
                let km = &mut k[m * (STAGES + 1) * n..(m + 1) * (STAGES + 1) * n];
                let [a, b, c, e] = &mut self.scratch;
                match member_step(
                    self.model,
                    (self.stages, &self.start.x),
                    (self.h, self.tol),
                    &d[r.clone()],
                    km,
                    &mut d1[r],
                    self.x,
                    [&mut a[..], &mut b[..], &mut c[..], &mut e[..]],
                ) {
                    Ok(err) if err.is_finite() => errs[m] = err,
                    _ => leave(estimates, left, m, self.start, d),
                }
            }
        }
    }
}

/// Member `m` leaves the shared steps at `start` with deviation
/// `d[m·n..]` there.
fn leave(estimates: &mut [f64], left: &mut [Left], m: usize, start: &Point, d: &[f64]) {
    let n = start.x.len();
    estimates[m] = f64::INFINITY;
    let x = start
        .x
        .iter()
        .zip(&d[m * n..(m + 1) * n])
        .map(|(b, d)| b + d);
    left[m] = Some((start.t, x.collect()));
}

/// The error above which members leave the shared steps, from the
/// errors `errs` of the members on them at one step: `LEAVE` times the
/// 90th percentile's (or 1): a few members far from the rest do not set
/// everyone's steps.
fn leaving_bar(errs: &mut [f64]) -> f64 {
    if errs.is_empty() {
        return f64::INFINITY;
    }
    let i = (errs.len() * 9 / 10).min(errs.len() - 1);
    let typical = *errs.select_nth_unstable_by(i, f64::total_cmp).1;
    LEAVE * typical.max(1.0)
}

/// The largest error among the members still on the shared steps.
fn live_max(errs: &[f64], estimates: &[f64]) -> f64 {
    errs.iter()
        .zip(estimates)
        .filter(|(_, e)| e.is_finite())
        .fold(0.0_f64, |w, (v, _)| w.max(*v))
}

/// A member's continuous extension over the accepted step `(d0, d1)`:
/// DOP853's `contd8` coefficients (8 blocks of `n`) into `cont`, its three
/// extra stages (into `ks`) at the base's points `extra`, `k` the step's
/// 13 stages (Hairer's numbering).
#[allow(clippy::too_many_arguments)]
fn extension(
    model: &dyn DynModel,
    extra: &[Point],
    h: f64,
    (d0, d1): (&[f64], &[f64]),
    k: &[f64],
    cont: &mut [f64],
    ks: &mut [f64],
    (x, stage): (&mut [f64], &mut [f64]),
) -> Result<(), Failure> {
    let n = d0.len();
    for e in 0..3 {
        stage.copy_from_slice(d0);
        for &(j, a) in A_EXTRA[e] {
            let kj = if j >= 13 {
                &ks[(j - 13) * n..(j - 12) * n]
            } else {
                &k[j * n..(j + 1) * n]
            };
            for (v, kv) in stage.iter_mut().zip(kj) {
                *v += h * a * kv;
            }
        }
        let (_, rest) = ks.split_at_mut(e * n);
        extra[e].rate(model, stage, x, &mut rest[..n])?;
    }
    const USED: [usize; 12] = [0, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15];
    for i in 0..n {
        let diff = d1[i] - d0[i];
        let c2 = h * k[i] - diff;
        let mut r = [0.0; 4];
        for &j in &USED {
            let v = if j >= 13 {
                ks[(j - 13) * n + i]
            } else {
                k[j * n + i]
            };
            for (row, rv) in r.iter_mut().enumerate() {
                *rv += D[row][j] * v;
            }
        }
        cont[i] = d0[i];
        cont[n + i] = diff;
        cont[2 * n + i] = c2;
        cont[3 * n + i] = diff - h * k[STAGES * n + i] - c2;
        for (row, rv) in r.iter().enumerate() {
            cont[(4 + row) * n + i] = h * rv;
        }
    }
    Ok(())
}

/// Hairer's `contd8`: the continuous extension at `θ = (t − t_old)/h`.
fn contd8(c: &[f64], n: usize, s: f64, out: &mut [f64]) {
    let s1 = 1.0 - s;
    for (i, o) in out.iter_mut().enumerate().take(n) {
        let conf1 = c[4 * n + i] + s * (c[5 * n + i] + s1 * (c[6 * n + i] + s * c[7 * n + i]));
        *o = c[i] + s * (c[n + i] + s1 * (c[2 * n + i] + s * (c[3 * n + i] + s1 * conf1)));
    }
}
