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

use crate::ensemble::States;
use crate::failure::Failure;
use crate::lanes::{Lanes, WIDTH};
use crate::model::DynModel;
use crate::ode::dop853::hairer_error;
use crate::ode::dop853::tableau::{A, A_EXTRA, B, BHH, C, C_EXTRA, D, ER, STAGES};
use crate::ode::tolerance::Tolerance;

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

/// A group's members side by side, one lane each: the deviation at the
/// step's start, the stages (Hairer's numbering, as `k`), the shifted
/// state, the end, and the end's terms of the error.
struct LaneBuffers {
    d0: Vec<Lanes>,
    k: Vec<Lanes>,
    x: Vec<Lanes>,
    d1: Vec<Lanes>,
    e3: Vec<Lanes>,
    e5: Vec<Lanes>,
    y0: Vec<Lanes>,
    y1: Vec<Lanes>,
    /// One lane's `y0, y1, e3, e5` for [`hairer_error`].
    lane: [Vec<f64>; 4],
}

impl LaneBuffers {
    fn new(n: usize) -> LaneBuffers {
        let v = || vec![Lanes::default(); n];
        LaneBuffers {
            d0: v(),
            k: vec![Lanes::default(); (STAGES + 1) * n],
            x: v(),
            d1: v(),
            e3: v(),
            e5: v(),
            y0: v(),
            y1: v(),
            lane: std::array::from_fn(|_| vec![0.0; n]),
        }
    }

    /// Lane `l`'s step back into member `m`'s places: its end into `d1`,
    /// its end rate into `k` and, with `inner`, the stages between (the
    /// first is already there; the others are only read by the continuous
    /// extension).
    fn scatter(
        &self,
        l: usize,
        m: usize,
        n: usize,
        (d1, k): (&mut [f64], &mut [f64]),
        inner: bool,
    ) {
        for (o, v) in d1[m * n..(m + 1) * n].iter_mut().zip(&self.d1) {
            *o = v.0[l];
        }
        let from = if inner { 1 } else { STAGES };
        let km = &mut k[m * (STAGES + 1) * n..(m + 1) * (STAGES + 1) * n];
        for (o, v) in km[from * n..].iter_mut().zip(&self.k[from * n..]) {
            *o = v.0[l];
        }
    }
}

/// [`member_step`] of the four members `group` at once (their deviations
/// in `d`, their start rates in `k`), in `buffers`; returns each lane's
/// error (`scatter` moves the results into the members' places).
/// Dispatched on the state's size as `member_step` is.
fn group_step(
    model: &dyn DynModel,
    (stages, x0): (&[Point], &[f64]),
    (h, tol): (f64, Tolerance),
    group: &[usize; WIDTH],
    (d, k): (&[f64], &[f64]),
    buffers: &mut LaneBuffers,
) -> Result<[f64; WIDTH], Failure> {
    macro_rules! sized {
        ($($n:literal)*) => {
            match x0.len() {
                $($n => lanes_of(Fixed::<$n>, model, (stages, x0), (h, tol), group, (d, k), buffers),)*
                n => lanes_of(Any(n), model, (stages, x0), (h, tol), group, (d, k), buffers),
            }
        };
    }
    sized!(2 4 6 8 10 12)
}

/// [`group_step`] for `dim` components: [`step_of`]'s arithmetic, each
/// operation lane by lane in the same order (so each lane's numbers are
/// its member's scalar step's, bit for bit).
#[inline(always)]
fn lanes_of<D: Dim>(
    dim: D,
    model: &dyn DynModel,
    (stages, x0): (&[Point], &[f64]),
    (h, tol): (f64, Tolerance),
    group: &[usize; WIDTH],
    (d, k): (&[f64], &[f64]),
    buffers: &mut LaneBuffers,
) -> Result<[f64; WIDTH], Failure> {
    let n = dim.n();
    let LaneBuffers {
        d0,
        k: kl,
        x,
        d1,
        e3,
        e5,
        y0,
        y1,
        lane,
    } = buffers;
    let (d0, x, d1, x0) = (&mut d0[..n], &mut x[..n], &mut d1[..n], &x0[..n]);
    let kl = &mut kl[..(STAGES + 1) * n];
    for (l, &m) in group.iter().enumerate() {
        let (dm, km) = (&d[m * n..][..n], &k[m * (STAGES + 1) * n..][..n]);
        for i in 0..n {
            d0[i].0[l] = dm[i];
            kl[i].0[l] = km[i];
        }
    }
    macro_rules! stage {
        ($s:literal) => {{
            let point = &stages[$s];
            let b = &point.x[..n];
            for i in 0..n {
                let mut acc = Lanes::splat(0.0);
                for &(j, a) in A[$s] {
                    acc = acc + a * kl[j * n + i];
                }
                x[i] = b[i] + (d0[i] + h * acc);
            }
            let (_, rest) = kl.split_at_mut($s * n);
            let (g, r) = (&mut rest[..n], &point.rate[..n]);
            model.rhs_lanes(point.t, x, g)?;
            for i in 0..n {
                g[i] = g[i] - r[i];
            }
        }};
    }
    stage!(1);
    stage!(2);
    stage!(3);
    stage!(4);
    stage!(5);
    stage!(6);
    stage!(7);
    stage!(8);
    stage!(9);
    stage!(10);
    stage!(11);
    let end = &stages[STAGES - 1].x[..n];
    let (e3, e5, y0, y1) = (&mut e3[..n], &mut e5[..n], &mut y0[..n], &mut y1[..n]);
    for i in 0..n {
        let (mut b, mut e) = (Lanes::splat(0.0), Lanes::splat(0.0));
        for &(l, c) in &B {
            b = b + c * kl[l * n + i];
        }
        for &(l, c) in &ER {
            e = e + c * kl[l * n + i];
        }
        let mut b3 = b;
        for &(l, c) in &BHH {
            b3 = b3 - c * kl[l * n + i];
        }
        e3[i] = b3;
        e5[i] = e;
        d1[i] = d0[i] + h * b;
        y0[i] = x0[i] + d0[i];
        y1[i] = end[i] + d1[i];
    }
    let (_, last) = kl.split_at_mut(STAGES * n);
    let (g, point) = (&mut last[..n], &stages[STAGES - 1]);
    for i in 0..n {
        x[i] = end[i] + d1[i];
    }
    model.rhs_lanes(point.t, x, g)?;
    for i in 0..n {
        g[i] = g[i] - point.rate[i];
    }
    let mut errs = [0.0; WIDTH];
    let [ly0, ly1, le3, le5] = lane;
    for (l, err) in errs.iter_mut().enumerate() {
        for i in 0..n {
            ly0[i] = y0[i].0[l];
            ly1[i] = y1[i].0[l];
            le3[i] = e3[i].0[l];
            le5[i] = e5[i].0[l];
        }
        *err = hairer_error(tol, h, &ly0[..n], &ly1[..n], &le3[..n], &le5[..n]);
    }
    Ok(errs)
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

/// A member's number of state components: a constant for the usual
/// sizes (its loops then unrolled, its bounds checks gone), or any.
trait Dim: Copy {
    fn n(self) -> usize;
}

#[derive(Clone, Copy)]
struct Fixed<const N: usize>;

impl<const N: usize> Dim for Fixed<N> {
    #[inline(always)]
    fn n(self) -> usize {
        N
    }
}

#[derive(Clone, Copy)]
struct Any(usize);

impl Dim for Any {
    #[inline(always)]
    fn n(self) -> usize {
        self.0
    }
}

/// One member's DOP853 step over `h` from `d0` (`k[0..n]` its rate there,
/// `x0` the base's state at the start): the stages into `k` (Hairer's
/// numbering, `k[12]` the rate at the end), the end into `d1`; returns
/// DOP853's error of the step in the state's norm (`x_b + d` at both ends).
/// `x` and `scratch` are scratch. Dispatched on the state's size, so that the usual ones
/// (mechanics' even sizes up to 12) run with their loops unrolled.
#[allow(clippy::too_many_arguments)]
fn member_step(
    model: &dyn DynModel,
    (stages, x0): (&[Point], &[f64]),
    (h, tol): (f64, Tolerance),
    d0: &[f64],
    k: &mut [f64],
    d1: &mut [f64],
    x: &mut [f64],
    scratch: [&mut [f64]; 4],
) -> Result<f64, Failure> {
    macro_rules! sized {
        ($($n:literal)*) => {
            match d0.len() {
                $($n => step_of(Fixed::<$n>, model, (stages, x0), (h, tol), d0, k, d1, x, scratch),)*
                n => step_of(Any(n), model, (stages, x0), (h, tol), d0, k, d1, x, scratch),
            }
        };
    }
    sized!(2 4 6 8 10 12)
}

/// [`member_step`] for `dim` components.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn step_of<D: Dim>(
    dim: D,
    model: &dyn DynModel,
    (stages, x0): (&[Point], &[f64]),
    (h, tol): (f64, Tolerance),
    d0: &[f64],
    k: &mut [f64],
    d1: &mut [f64],
    x: &mut [f64],
    scratch: [&mut [f64]; 4],
) -> Result<f64, Failure> {
    let n = dim.n();
    let (d0, d1, x, x0) = (&d0[..n], &mut d1[..n], &mut x[..n], &x0[..n]);
    let k = &mut k[..(STAGES + 1) * n];
    // Each stage summed component by component in registers, straight
    // into the shifted state `x_b + d`, with the row's coefficients and
    // (for the usual sizes) the member's size known at compile time: a
    // loop over the row's pairs with the size at run time cost the member
    // step about twice DOP853's own work (callgrind on the double
    // pendulum, BENCHMARKS §4a).
    macro_rules! stage {
        ($s:literal) => {{
            let point = &stages[$s];
            let b = &point.x[..n];
            for i in 0..n {
                let mut acc = 0.0;
                for &(j, a) in A[$s] {
                    acc += a * k[j * n + i];
                }
                x[i] = b[i] + (d0[i] + h * acc);
            }
            let (_, rest) = k.split_at_mut($s * n);
            let (g, r) = (&mut rest[..n], &point.rate[..n]);
            model.rhs(point.t, x, g)?;
            for i in 0..n {
                g[i] -= r[i];
            }
        }};
    }
    stage!(1);
    stage!(2);
    stage!(3);
    stage!(4);
    stage!(5);
    stage!(6);
    stage!(7);
    stage!(8);
    stage!(9);
    stage!(10);
    stage!(11);
    // The end, and DOP853's 3rd- and 5th-order estimates in the norm of
    // the state at both ends.
    let end = &stages[STAGES - 1].x[..n];
    let [e3, e5, y0, y1] = scratch.map(|v| &mut v[..n]);
    for i in 0..n {
        let (mut b, mut e) = (0.0, 0.0);
        for &(l, c) in &B {
            b += c * k[l * n + i];
        }
        for &(l, c) in &ER {
            e += c * k[l * n + i];
        }
        let mut b3 = b;
        for &(l, c) in &BHH {
            b3 -= c * k[l * n + i];
        }
        e3[i] = b3;
        e5[i] = e;
        d1[i] = d0[i] + h * b;
        y0[i] = x0[i] + d0[i];
        y1[i] = end[i] + d1[i];
    }
    let (_, last) = k.split_at_mut(STAGES * n);
    let (g, point) = (&mut last[..n], &stages[STAGES - 1]);
    for i in 0..n {
        x[i] = end[i] + d1[i];
    }
    model.rhs(point.t, x, g)?;
    for i in 0..n {
        g[i] -= point.rate[i];
    }
    Ok(hairer_error(tol, h, y0, y1, e3, e5))
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::Matrix;
    use crate::model::{Initial, Model};

    /// Two coupled nonlinear oscillators: four components, a size the
    /// member step has unrolled.
    #[derive(Clone)]
    struct Coupled;

    impl Model for Coupled {
        const NAME: &'static str = "coupled";
        const SOURCE_HASH: &'static str = "test";
        const PARAMS: &'static [&'static str] = &[];
        const STATE: &'static [&'static str] = &["a", "b", "a'", "b'"];
        const COORDINATES: usize = 2;
        const INITIAL: &'static [Initial] = &[Initial::Given; 4];
        fn parameters(_: &[Option<f64>]) -> Vec<f64> {
            Vec::new()
        }
        fn new(_: &[f64]) -> Self {
            Coupled
        }
        fn param_values(&self) -> &[f64] {
            &[]
        }
        fn time_span(&self) -> (f64, f64) {
            (0.0, 1.0)
        }
        fn initial_state(&self, _: &[Option<f64>]) -> Result<Vec<f64>, Failure> {
            Ok(vec![1.0, 0.5, 0.0, 0.0])
        }
        fn rhs(&self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), Failure> {
            dx[0] = x[2];
            dx[1] = x[3];
            dx[2] = -x[0].sin() + 0.3 * (x[1] - x[0]) * t.cos();
            dx[3] = -x[1].sin() * x[0] - 0.1 * x[3];
            Ok(())
        }
        const LANES: bool = true;
        /// `rhs` over lanes, written as the emitter prints it.
        fn rhs_lanes(&self, t: f64, x: &[Lanes], dx: &mut [Lanes]) -> Result<(), Failure> {
            dx[0] = x[2];
            dx[1] = x[3];
            dx[2] = -x[0].sin() + 0.3 * (x[1] - x[0]) * t.cos();
            dx[3] = -x[1].sin() * x[0] - 0.1 * x[3];
            Ok(())
        }
        fn jacobian(&self, _: f64, _: &[f64], _: &mut Matrix) -> Result<(), Failure> {
            unreachable!("not used by the member step")
        }
        fn time_partial(&self, _: f64, _: &[f64], _: &mut [f64]) -> Result<(), Failure> {
            unreachable!("not used by the member step")
        }
    }

    /// The base at a step's stage times (4 components, a step of 0.07
    /// from t = 0.2) and the tolerance, for the member step's tests.
    fn base_stages(model: &Coupled) -> (usize, f64, Tolerance, Vec<Point>) {
        let n = 4;
        let h = 0.07;
        let tol = Tolerance {
            rtol: 1e-8,
            atol: 1e-10,
        };
        let mut stages: Vec<Point> = (0..STAGES).map(|_| Point::new(n)).collect();
        for (s, point) in stages.iter_mut().enumerate() {
            point.t = 0.2 + C[s] * h;
            point.x = (0..n).map(|i| 0.3 * i as f64 + point.t.sin()).collect();
            Model::rhs(model, point.t, &point.x, &mut point.rate).unwrap();
        }
        (n, h, tol, stages)
    }

    /// The unrolled member step (a size known at compile time) and the
    /// one for any size give the same numbers, bit for bit: the sizes the
    /// dispatch does not unroll run the same arithmetic.
    #[test]
    fn the_unrolled_member_step_is_the_step_for_any_size() {
        let model = Coupled;
        let (n, h, tol, stages) = base_stages(&model);
        let x0 = stages[0].x.clone();
        let d0 = [0.01, -0.02, 0.03, 0.005];
        let run = |fixed: bool| {
            let mut k = vec![0.0; (STAGES + 1) * n];
            let mut x = vec![0.0; n];
            stages[0].rate(&model, &d0, &mut x, &mut k[..n]).unwrap();
            let mut d1 = vec![0.0; n];
            let mut s: [Vec<f64>; 4] = std::array::from_fn(|_| vec![0.0; n]);
            let [a, b, c, e] = &mut s;
            let scratch = [&mut a[..], &mut b[..], &mut c[..], &mut e[..]];
            let args = (&stages[..], &x0[..]);
            let err = if fixed {
                step_of(
                    Fixed::<4>,
                    &model,
                    args,
                    (h, tol),
                    &d0,
                    &mut k,
                    &mut d1,
                    &mut x,
                    scratch,
                )
            } else {
                step_of(
                    Any(4),
                    &model,
                    args,
                    (h, tol),
                    &d0,
                    &mut k,
                    &mut d1,
                    &mut x,
                    scratch,
                )
            }
            .unwrap();
            (k, d1, err)
        };
        let (fixed, any) = (run(true), run(false));
        assert!(fixed.2 > 0.0 && fixed.2.is_finite(), "{}", fixed.2);
        assert_eq!(fixed.0, any.0);
        assert_eq!(fixed.1, any.1);
        assert_eq!(fixed.2.to_bits(), any.2.to_bits());
        // And the step moved the deviation.
        assert!(fixed.1.iter().zip(&d0).any(|(a, b)| a != b));
    }

    /// Four members stepped in lanes give each member's scalar step, bit
    /// for bit: its stages, its end and its error (the ensemble's CSVs do
    /// not depend on whether the model has a right side over lanes).
    #[test]
    fn a_group_in_lanes_is_each_members_scalar_step() {
        let model = Coupled;
        let (n, h, tol, stages) = base_stages(&model);
        let x0 = stages[0].x.clone();
        // Five members; the group holds 4, 0, 2 and 1 (any order).
        let count = 5;
        let d: Vec<f64> = (0..count * n)
            .map(|i| 0.01 * ((i * 7 % 11) as f64 - 5.0))
            .collect();
        let mut k = vec![0.0; count * (STAGES + 1) * n];
        let mut x = vec![0.0; n];
        for m in 0..count {
            let km = &mut k[m * (STAGES + 1) * n..][..n];
            stages[0]
                .rate(&model, &d[m * n..][..n], &mut x, km)
                .unwrap();
        }
        let group = [4, 0, 2, 1];
        let mut buffers = LaneBuffers::new(n);
        let errs = group_step(
            &model,
            (&stages, &x0),
            (h, tol),
            &group,
            (&d, &k),
            &mut buffers,
        )
        .unwrap();
        let (mut lane_d1, mut lane_k) = (vec![0.0; count * n], k.clone());
        for (l, &m) in group.iter().enumerate() {
            buffers.scatter(l, m, n, (&mut lane_d1, &mut lane_k), true);
        }
        for (l, &m) in group.iter().enumerate() {
            let mut km = k[m * (STAGES + 1) * n..][..(STAGES + 1) * n].to_vec();
            let mut d1 = vec![0.0; n];
            let mut s: [Vec<f64>; 4] = std::array::from_fn(|_| vec![0.0; n]);
            let [a, b, c, e] = &mut s;
            let err = member_step(
                &model,
                (&stages, &x0),
                (h, tol),
                &d[m * n..][..n],
                &mut km,
                &mut d1,
                &mut x,
                [&mut a[..], &mut b[..], &mut c[..], &mut e[..]],
            )
            .unwrap();
            assert!(err > 0.0 && err.is_finite(), "{err}");
            assert_eq!(errs[l].to_bits(), err.to_bits(), "member {m}");
            assert_eq!(&lane_d1[m * n..][..n], &d1[..], "member {m}");
            assert_eq!(&lane_k[m * (STAGES + 1) * n..][..(STAGES + 1) * n], &km[..]);
        }
        // Member 3, not in the group, is untouched.
        assert!(lane_d1[3 * n..][..n].iter().all(|&v| v == 0.0));
        // Without the inner stages (no sample inside the step): the end
        // and the end rate, the stages between left as they were.
        let (mut d1, mut k2) = (vec![0.0; count * n], k.clone());
        buffers.scatter(0, 4, n, (&mut d1, &mut k2), false);
        let block = 4 * (STAGES + 1) * n;
        assert_eq!(&d1[4 * n..][..n], &lane_d1[4 * n..][..n]);
        assert_eq!(&k2[..block + STAGES * n], &k[..block + STAGES * n]);
        assert_eq!(
            &k2[block + STAGES * n..][..n],
            &lane_k[block + STAGES * n..][..n]
        );
    }
}
