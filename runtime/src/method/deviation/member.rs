//! One member's DOP853 step on the shared steps, for one member in
//! `f64`s or four side by side in [`Lanes`]: the same step, generic over
//! the number ([`Member`]) and the state's size ([`Dim`]), so that a
//! member's numbers are the same bit for bit in either (BENCHMARKS §4a.1,
//! §4a.2).

use super::Point;
use crate::failure::Failure;
use crate::lanes::{Lanes, WIDTH};
use crate::model::DynModel;
use crate::ode::dop853::hairer_error;
use crate::ode::dop853::tableau::{A, B, BHH, ER, STAGES};
use crate::ode::tolerance::Tolerance;
use std::ops::{Add, Mul, Sub};

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

/// `$body` with `$dim` the [`Dim`] of `$n` components: [`Fixed`] for
/// mechanics' usual sizes (even, up to 12), so that those run with their
/// loops unrolled, [`Any`] for the rest (the same code).
macro_rules! by_size {
    ($n:expr, $dim:ident => $body:expr) => {
        by_size!($n, $dim => $body; 2 4 6 8 10 12)
    };
    ($n:expr, $dim:ident => $body:expr; $($size:literal)*) => {
        match $n {
            $($size => {
                let $dim = Fixed::<$size>;
                $body
            })*
            n => {
                let $dim = Any(n);
                $body
            }
        }
    };
}

/// One member's DOP853 step over `h` from `d0` (`k[0..n]` its rate there,
/// `x0` the base's state at the start): the stages into `k` (Hairer's
/// numbering, `k[12]` the rate at the end), the end into `d1`; returns
/// DOP853's error of the step in the state's norm (`x_b + d` at both ends).
/// `x` and `scratch` are scratch.
#[allow(clippy::too_many_arguments)]
pub(super) fn member_step(
    model: &dyn DynModel,
    (stages, x0): (&[Point], &[f64]),
    (h, tol): (f64, Tolerance),
    d0: &[f64],
    k: &mut [f64],
    d1: &mut [f64],
    x: &mut [f64],
    scratch: [&mut [f64]; 4],
) -> Result<f64, Failure> {
    let [e3, e5, y0, y1] = scratch;
    by_size!(d0.len(), dim => {
        let n = dim.n();
        let errors = [&mut *e3, &mut *e5, &mut *y0, &mut *y1];
        dop853_step(dim, model, (stages, x0), h, d0, k, d1, x, errors)?;
        Ok(hairer_error(tol, h, &y0[..n], &y1[..n], &e3[..n], &e5[..n]))
    })
}

/// A group's members side by side, one lane each: the deviation at the
/// step's start, the stages (Hairer's numbering, as `k`), the shifted
/// state, the end, and the end's terms of the error.
pub(super) struct LaneBuffers {
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
    pub(super) fn new(n: usize) -> LaneBuffers {
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
    #[inline]
    pub(super) fn scatter(
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
/// in `d`, their start rates in `k`), in `buffers`: gathered into lanes,
/// [`dop853_step`] over lanes (each lane's numbers its member's scalar
/// step's, bit for bit); returns each lane's error (`scatter` moves the
/// results into the members' places).
pub(super) fn group_step(
    model: &dyn DynModel,
    (stages, x0): (&[Point], &[f64]),
    (h, tol): (f64, Tolerance),
    group: &[usize; WIDTH],
    (d, k): (&[f64], &[f64]),
    buffers: &mut LaneBuffers,
) -> Result<[f64; WIDTH], Failure> {
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
    by_size!(x0.len(), dim => {
        let n = dim.n();
        let (d0, kl) = (&mut d0[..n], &mut kl[..(STAGES + 1) * n]);
        for (l, &m) in group.iter().enumerate() {
            let (dm, km) = (&d[m * n..][..n], &k[m * (STAGES + 1) * n..][..n]);
            for i in 0..n {
                d0[i].0[l] = dm[i];
                kl[i].0[l] = km[i];
            }
        }
        let errors = [&mut e3[..], &mut e5[..], &mut y0[..], &mut y1[..]];
        dop853_step(dim, model, (stages, x0), h, d0, kl, d1, x, errors)?;
        let (e3, e5, y0, y1) = (&e3[..n], &e5[..n], &y0[..n], &y1[..n]);
        let mut errs = [0.0; WIDTH];
        let [ly0, ly1, le3, le5] = &mut *lane;
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
    })
}

/// The numbers a member step computes with: one member's `f64`, or four
/// members' [`Lanes`] (each operation the `f64` one lane by lane), with
/// the model's right side over them. One step serves both, so that a
/// member's numbers do not depend on whether it went in a group.
trait Member:
    Copy + From<f64> + Add<Output = Self> + Sub<Output = Self> + Sub<f64, Output = Self>
{
    fn rhs(model: &dyn DynModel, t: f64, x: &[Self], dx: &mut [Self]) -> Result<(), Failure>;
}

impl Member for f64 {
    #[inline(always)]
    fn rhs(model: &dyn DynModel, t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), Failure> {
        model.rhs(t, x, dx)
    }
}

impl Member for Lanes {
    #[inline(always)]
    fn rhs(model: &dyn DynModel, t: f64, x: &[Lanes], dx: &mut [Lanes]) -> Result<(), Failure> {
        model.rhs_lanes(t, x, dx)
    }
}

/// DOP853's step over `h` from the deviation `d0` (`k[0..n]` its rate
/// there, `x0` the base's state at the start) for `dim` components: the
/// stages into `k` (Hairer's numbering, `k[12]` the rate at the end), the
/// end into `d1`, and the error's terms into `[e3, e5, y0, y1]` (DOP853's
/// 3rd- and 5th-order estimates, the state `x_b + d` at both ends); `x` is
/// scratch.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn dop853_step<D: Dim, T: Member>(
    dim: D,
    model: &dyn DynModel,
    (stages, x0): (&[Point], &[f64]),
    h: f64,
    d0: &[T],
    k: &mut [T],
    d1: &mut [T],
    x: &mut [T],
    scratch: [&mut [T]; 4],
) -> Result<(), Failure>
where
    f64: Add<T, Output = T> + Mul<T, Output = T>,
{
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
                let mut acc = T::from(0.0);
                for &(j, a) in A[$s] {
                    acc = acc + a * k[j * n + i];
                }
                x[i] = b[i] + (d0[i] + h * acc);
            }
            let (_, rest) = k.split_at_mut($s * n);
            let (g, r) = (&mut rest[..n], &point.rate[..n]);
            T::rhs(model, point.t, x, g)?;
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
    // The end, and DOP853's 3rd- and 5th-order estimates in the norm of
    // the state at both ends.
    let end = &stages[STAGES - 1].x[..n];
    let [e3, e5, y0, y1] = scratch;
    let (e3, e5, y0, y1) = (&mut e3[..n], &mut e5[..n], &mut y0[..n], &mut y1[..n]);
    for i in 0..n {
        let (mut b, mut e) = (T::from(0.0), T::from(0.0));
        for &(l, c) in &B {
            b = b + c * k[l * n + i];
        }
        for &(l, c) in &ER {
            e = e + c * k[l * n + i];
        }
        let mut b3 = b;
        for &(l, c) in &BHH {
            b3 = b3 - c * k[l * n + i];
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
    T::rhs(model, point.t, x, g)?;
    for i in 0..n {
        g[i] = g[i] - point.rate[i];
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::Matrix;
    use crate::model::{Initial, Model};
    use crate::ode::dop853::tableau::C;

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
        let (_, h, tol, stages) = base_stages(&model);
        let d0 = [0.01, -0.02, 0.03, 0.005];
        // The step from `d0` (the base's start `stages[0].x`): its stages,
        // its end, its error's terms and its error.
        type Step = (Vec<f64>, Vec<f64>, [Vec<f64>; 4], f64);
        fn run<D: Dim>(
            dim: D,
            model: &Coupled,
            stages: &[Point],
            (h, tol): (f64, Tolerance),
            d0: &[f64],
        ) -> Step {
            let n = d0.len();
            let mut k = vec![0.0; (STAGES + 1) * n];
            let mut x = vec![0.0; n];
            stages[0].rate(model, d0, &mut x, &mut k[..n]).unwrap();
            let mut d1 = vec![0.0; n];
            let mut terms: [Vec<f64>; 4] = std::array::from_fn(|_| vec![0.0; n]);
            let [a, b, c, e] = &mut terms;
            let scratch = [&mut a[..], &mut b[..], &mut c[..], &mut e[..]];
            let args = (stages, &stages[0].x[..]);
            dop853_step(dim, model, args, h, d0, &mut k, &mut d1, &mut x, scratch).unwrap();
            let [e3, e5, y0, y1] = &terms;
            let err = hairer_error(tol, h, y0, y1, e3, e5);
            (k, d1, terms, err)
        }
        let fixed = run(Fixed::<4>, &model, &stages, (h, tol), &d0);
        let any = run(Any(4), &model, &stages, (h, tol), &d0);
        assert!(fixed.3 > 0.0 && fixed.3.is_finite(), "{}", fixed.3);
        assert_eq!(fixed.0, any.0);
        assert_eq!(fixed.1, any.1);
        assert_eq!(fixed.2, any.2);
        assert_eq!(fixed.3.to_bits(), any.3.to_bits());
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
