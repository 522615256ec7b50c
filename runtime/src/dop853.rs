//! DOP853: the explicit Runge–Kutta method of order 8 of Dormand and Prince
//! with Hairer's combined 5th/3rd-order error estimate and his continuous
//! extension of order 7 (HNW I, II.10; `dop853.f`, `contd8`), under the
//! PI step-size controller. Dense output costs three more evaluations per
//! step, spent only for steps whose interior is asked for.

// The coefficients are kept to the digits Hairer published them with.
#![allow(clippy::excessive_precision, clippy::unreadable_literal)]

use crate::budget::Budget;
use crate::controller::Controller;
use crate::dense::{contd8, DenseKind};
use crate::failure::Failure;
use crate::stepper::{stalled, Clock, Clocked, ErrorMeasure, StepOutcome, Stepper};
use crate::system::System;
use crate::tolerance::{first_non_finite, Tolerance};

const STAGES: usize = 12;

/// Nodes `c_i` of the twelve stages.
const C: [f64; STAGES] = [
    0.0,
    0.526001519587677318785587544488e-01,
    0.789002279381515978178381316732e-01,
    0.118350341907227396726757197510e+00,
    0.281649658092772603273242802490e+00,
    0.333333333333333333333333333333e+00,
    0.25e+00,
    0.307692307692307692307692307692e+00,
    0.651282051282051282051282051282e+00,
    0.6e+00,
    0.857142857142857142857142857142e+00,
    1.0,
];

/// The non-zero entries `(j, a_ij)` of row `i` of the Butcher matrix.
const A: [&[(usize, f64)]; STAGES] = [
    &[],
    &[(0, 5.26001519587677318785587544488e-2)],
    &[
        (0, 1.97250569845378994544595329183e-2),
        (1, 5.91751709536136983633785987549e-2),
    ],
    &[
        (0, 2.95875854768068491816892993775e-2),
        (2, 8.87627564304205475450678981324e-2),
    ],
    &[
        (0, 2.41365134159266685502369798665e-1),
        (2, -8.84549479328286085344864962717e-1),
        (3, 9.24834003261792003115737966543e-1),
    ],
    &[
        (0, 3.7037037037037037037037037037e-2),
        (3, 1.70828608729473871279604482173e-1),
        (4, 1.25467687566822425016691814123e-1),
    ],
    &[
        (0, 3.7109375e-2),
        (3, 1.70252211019544039314978060272e-1),
        (4, 6.02165389804559606850219397283e-2),
        (5, -1.7578125e-2),
    ],
    &[
        (0, 3.70920001185047927108779319836e-2),
        (3, 1.70383925712239993810214054705e-1),
        (4, 1.07262030446373284651809199168e-1),
        (5, -1.53194377486244017527936158236e-2),
        (6, 8.27378916381402288758473766002e-3),
    ],
    &[
        (0, 6.24110958716075717114429577812e-1),
        (3, -3.36089262944694129406857109825e0),
        (4, -8.68219346841726006818189891453e-1),
        (5, 2.75920996994467083049415600797e1),
        (6, 2.01540675504778934086186788979e1),
        (7, -4.34898841810699588477366255144e1),
    ],
    &[
        (0, 4.77662536438264365890433908527e-1),
        (3, -2.48811461997166764192642586468e0),
        (4, -5.90290826836842996371446475743e-1),
        (5, 2.12300514481811942347288949897e1),
        (6, 1.52792336328824235832596922938e1),
        (7, -3.32882109689848629194453265587e1),
        (8, -2.03312017085086261358222928593e-2),
    ],
    &[
        (0, -9.3714243008598732571704021658e-1),
        (3, 5.18637242884406370830023853209e0),
        (4, 1.09143734899672957818500254654e0),
        (5, -8.14978701074692612513997267357e0),
        (6, -1.85200656599969598641566180701e1),
        (7, 2.27394870993505042818970056734e1),
        (8, 2.49360555267965238987089396762e0),
        (9, -3.0467644718982195003823669022e0),
    ],
    &[
        (0, 2.27331014751653820792359768449e0),
        (3, -1.05344954667372501984066689879e1),
        (4, -2.00087205822486249909675718444e0),
        (5, -1.79589318631187989172765950534e1),
        (6, 2.79488845294199600508499808837e1),
        (7, -2.85899827713502369474065508674e0),
        (8, -8.87285693353062954433549289258e0),
        (9, 1.23605671757943030647266201528e1),
        (10, 6.43392746015763530355970484046e-1),
    ],
];

/// Weights of the 8th-order solution.
const B: [(usize, f64); 8] = [
    (0, 5.42937341165687622380535766363e-2),
    (5, 4.45031289275240888144113950566e0),
    (6, 1.89151789931450038304281599044e0),
    (7, -5.8012039600105847814672114227e0),
    (8, 3.1116436695781989440891606237e-1),
    (9, -1.52160949662516078556178806805e-1),
    (10, 2.01365400804030348374776537501e-1),
    (11, 4.47106157277725905176885569043e-2),
];

/// The 3rd-order estimate: `B·k − BHH·k`.
const BHH: [(usize, f64); 3] = [
    (0, 0.244094488188976377952755905512e+00),
    (8, 0.733846688281611857341361741547e+00),
    (11, 0.220588235294117647058823529412e-01),
];

/// The 5th-order error estimate.
const ER: [(usize, f64); 8] = [
    (0, 0.1312004499419488073250102996e-01),
    (5, -0.1225156446376204440720569753e+01),
    (6, -0.4957589496572501915214079952e+00),
    (7, 0.1664377182454986536961530415e+01),
    (8, -0.3503288487499736816886487290e+00),
    (9, 0.3341791187130174790297318841e+00),
    (10, 0.8192320648511571246570742613e-01),
    (11, -0.2235530786388629525884427845e-01),
];

/// The three extra stages of the continuous extension: node, then the
/// non-zero `(j, a_ij)` with `j` indexing `k[0..12]`, `k_new = k[12]`
/// (`X(t + h, y_new)`), and the extra stages `k[13]`, `k[14]`.
const C_EXTRA: [f64; 3] = [0.1, 0.2, 0.777777777777777777777777777778];
const A_EXTRA: [&[(usize, f64)]; 3] = [
    &[
        (0, 5.61675022830479523392909219681e-2),
        (6, 2.53500210216624811088794765333e-1),
        (7, -2.46239037470802489917441475441e-1),
        (8, -1.24191423263816360469010140626e-1),
        (9, 1.5329179827876569731206322685e-1),
        (10, 8.20105229563468988491666602057e-3),
        (11, 7.56789766054569976138603589584e-3),
        (12, -8.298e-3),
    ],
    &[
        (0, 3.18346481635021405060768473261e-2),
        (5, 2.83009096723667755288322961402e-2),
        (6, 5.35419883074385676223797384372e-2),
        (7, -5.49237485713909884646569340306e-2),
        (10, -1.08347328697249322858509316994e-4),
        (11, 3.82571090835658412954920192323e-4),
        (12, -3.40465008687404560802977114492e-4),
        (13, 1.41312443674632500278074618366e-1),
    ],
    &[
        (0, -4.28896301583791923408573538692e-1),
        (5, -4.69762141536116384314449447206e0),
        (6, 7.68342119606259904184240953878e0),
        (7, 4.06898981839711007970213554331e0),
        (8, 3.56727187455281109270669543021e-1),
        (12, -1.39902416515901462129418009734e-3),
        (13, 2.9475147891527723389556272149e0),
        (14, -9.15095847217987001081870187138e0),
    ],
];

/// The rows `d4..d7` of the continuous extension over `k[0..16]`.
const D: [[f64; 16]; 4] = [
    [
        -0.84289382761090128651353491142e+01,
        0.0,
        0.0,
        0.0,
        0.0,
        0.56671495351937776962531783590e+00,
        -0.30689499459498916912797304727e+01,
        0.23846676565120698287728149680e+01,
        0.21170345824450282767155149946e+01,
        -0.87139158377797299206789907490e+00,
        0.22404374302607882758541771650e+01,
        0.63157877876946881815570249290e+00,
        -0.88990336451333310820698117400e-01,
        0.18148505520854727256656404962e+02,
        -0.91946323924783554000451984436e+01,
        -0.44360363875948939664310572000e+01,
    ],
    [
        0.10427508642579134603413151009e+02,
        0.0,
        0.0,
        0.0,
        0.0,
        0.24228349177525818288430175319e+03,
        0.16520045171727028198505394887e+03,
        -0.37454675472269020279518312152e+03,
        -0.22113666853125306036270938578e+02,
        0.77334326684722638389603898808e+01,
        -0.30674084731089398182061213626e+02,
        -0.93321305264302278729567221706e+01,
        0.15697238121770843886131091075e+02,
        -0.31139403219565177677282850411e+02,
        -0.93529243588444783865713862664e+01,
        0.35816841486394083752465898540e+02,
    ],
    [
        0.19985053242002433820987653617e+02,
        0.0,
        0.0,
        0.0,
        0.0,
        -0.38703730874935176555105901742e+03,
        -0.18917813819516756882830838328e+03,
        0.52780815920542364900561016686e+03,
        -0.11573902539959630126141871134e+02,
        0.68812326946963000169666922661e+01,
        -0.10006050966910838403183860980e+01,
        0.77771377980534432092869265740e+00,
        -0.27782057523535084065932004339e+01,
        -0.60196695231264120758267380846e+02,
        0.84320405506677161018159903784e+02,
        0.11992291136182789328035130030e+02,
    ],
    [
        -0.25693933462703749003312586129e+02,
        0.0,
        0.0,
        0.0,
        0.0,
        -0.15418974869023643374053993627e+03,
        -0.23152937917604549567536039109e+03,
        0.35763911791061412378285349910e+03,
        0.93405324183624310003907691704e+02,
        -0.37458323136451633156875139351e+02,
        0.10409964950896230045147246184e+03,
        0.29840293426660503123344363579e+02,
        -0.43533456590011143754432175058e+02,
        0.96324553959188282948394950600e+02,
        -0.39177261675615439165231486172e+02,
        -0.14972683625798562581422125276e+03,
    ],
];

/// Hairer's stiffness test (`dop853.f`): `h·ρ` estimated from the last
/// stage, `h ‖X(t+h, y₁) − X(t+h, ŷ)‖ / ‖y₁ − ŷ‖`, past the edge of
/// DOP853's stability region (≈ 6.1 on the negative real axis) on
/// `STIFF_STEPS` tests, not interrupted by `NON_STIFF_STEPS` tests below it.
const STIFF_H_RHO: f64 = 6.1;
const STIFF_STEPS: usize = 15;
const NON_STIFF_STEPS: usize = 6;

/// Hairer's measure (`dop853.f`): `|h| ε₅ / √(n (ε₅² + 0.01 ε₃²))`, the
/// sums scaled by `atol + rtol·max(|y0|, |y1|)`.
pub struct HairerMeasure(pub Tolerance);

impl ErrorMeasure for HairerMeasure {
    fn measure(
        &mut self,
        _t0: f64,
        h: f64,
        y0: &[f64],
        y1: &[f64],
        e3: &[f64],
        e5: &[f64],
    ) -> Option<f64> {
        Some(hairer_error(self.0, h, y0, y1, e3, e5))
    }

    fn hairer_tolerance(&self) -> Option<Tolerance> {
        Some(self.0)
    }
}

/// Hairer's combined error norm of DOP853.
pub fn hairer_error(tol: Tolerance, h: f64, y0: &[f64], y1: &[f64], e3: &[f64], e5: &[f64]) -> f64 {
    let n = y0.len();
    let (y1, e3, e5) = (&y1[..n], &e3[..n], &e5[..n]);
    let (mut err3, mut err5) = (0.0, 0.0);
    for i in 0..n {
        let inverse = 1.0 / (tol.atol + tol.rtol * y0[i].abs().max(y1[i].abs()));
        let (a, b) = (e3[i] * inverse, e5[i] * inverse);
        err3 += a * a;
        err5 += b * b;
    }
    hairer_combine(h, n, err3, err5)
}

/// Hairer's norm from the sums of squares of the scaled 3rd- and
/// 5th-order estimates over `n` components.
#[inline]
fn hairer_combine(h: f64, n: usize, err3: f64, err5: f64) -> f64 {
    let denominator = if err5 + 0.01 * err3 > 0.0 {
        err5 + 0.01 * err3
    } else {
        1.0
    };
    let err = h.abs() * err5 * (1.0 / (n.max(1) as f64 * denominator)).sqrt();
    if err.is_finite() {
        err
    } else {
        f64::INFINITY
    }
}

/// Blocks of `n` numbers in [`Dop853`]'s stage buffer after the 16 stages:
/// the state at which a stage is evaluated;
const STAGE_STATE: usize = STAGES + 4;
/// the 3rd- and 5th-order error estimates of the last attempt, per unit
/// step (multiply by `h`);
const ERROR3: usize = STAGE_STATE + 1;
const ERROR5: usize = ERROR3 + 1;
/// the 8 blocks of the continuous extension's coefficients.
const CONT: usize = ERROR5 + 1;
const BLOCKS: usize = CONT + 8;

/// The DOP853 integrator at time `t` with state `y`.
pub struct Dop853 {
    tol: Tolerance,
    clock: Clock,
    y: Vec<f64>,
    /// Stages, `n` numbers each in one buffer (stage `j` at `j n`):
    /// `k[0] = X(t, y)` (first same as last), `k[1..12]` the stages of the
    /// last step, `k[12]` the rate at the last step's start after a step is
    /// accepted (kept for the continuous extension), `k[13..16]` its extra
    /// stages; then, in the same buffer (one allocation a solver, not
    /// five: a small model's solve is a few microseconds), the blocks at
    /// [`STAGE_STATE`], [`ERROR3`], [`ERROR5`] and [`CONT`].
    k: Vec<f64>,
    y_trial: Vec<f64>,
    /// The last accepted step's start state.
    y_old: Vec<f64>,
    /// The continuous extension's coefficients (the 8 blocks at [`CONT`])
    /// are those of the last accepted step.
    dense_ready: bool,
    stiff_tests: usize,
    non_stiff_tests: usize,
    stiffness_detected: Option<f64>,
}

impl Dop853 {
    /// Starts at `(t0, y0)`; `h_max` bounds the first step guess; `h0`, when
    /// given, replaces the guess (a restart keeps the step that worked).
    pub fn new<S: System + ?Sized>(
        system: &S,
        t0: f64,
        y0: &[f64],
        tol: Tolerance,
        h_max: f64,
        h0: Option<f64>,
    ) -> Result<Self, Failure> {
        let n = y0.len();
        let mut k = vec![0.0; BLOCKS * n];
        let controller = Controller::dop853();
        let clock = Clock::start(system, t0, y0, &mut k[..n], tol, 8, h_max, h0, controller)?;
        Ok(Dop853 {
            tol,
            clock,
            y: y0.to_vec(),
            k,
            y_trial: vec![0.0; n],
            y_old: y0.to_vec(),
            dense_ready: false,
            stiff_tests: 0,
            non_stiff_tests: 0,
            stiffness_detected: None,
        })
    }

    /// The slope `X(t, y)` at the current state.
    pub fn slope(&self) -> &[f64] {
        &self.k[..self.y.len()]
    }

    /// One accepted step under `measure` (see [`Stepper::step`]), or
    /// [`StepOutcome::Declined`] when the measure declines it.
    pub fn step_measured<S: System + ?Sized, E: ErrorMeasure + ?Sized>(
        &mut self,
        system: &S,
        t_limit: f64,
        budget: &Budget,
        measure: &mut E,
    ) -> Result<StepOutcome, Failure> {
        let mut last_non_finite = false;
        let mut rate_broken: Option<usize> = None;
        loop {
            let (h, reaches_limit) = self.clock.attempt(t_limit, budget, |h| {
                let component =
                    last_non_finite.then(|| first_non_finite(&self.y_trial).unwrap_or(0));
                stalled(system, self.clock.t, h, component, rate_broken)
            })?;
            let fused = measure.hairer_tolerance();
            let (finite, fused_error) = self.attempt(system, h, fused)?;
            let err = if !finite {
                f64::INFINITY
            } else if fused.is_some() {
                fused_error
            } else {
                self.clock.controller.end_ramp();
                let n = self.y.len();
                match measure.measure(
                    self.clock.t,
                    h,
                    &self.y,
                    &self.y_trial,
                    &self.k[ERROR3 * n..(ERROR3 + 1) * n],
                    &self.k[ERROR5 * n..(ERROR5 + 1) * n],
                ) {
                    Some(err) => err,
                    None => return Ok(self.clock.decline()),
                }
            };
            if !finite {
                // A stage overflowed: the step was too long for a solution
                // that grows fast, or it reached past where the rates are
                // defined (a force infinite at a finite state); retry
                // shorter, and remember which, for the diagnosis should the
                // step underflow.
                self.clock.reject(h, f64::INFINITY);
                match self.broken_rate(h) {
                    Some(i) => {
                        rate_broken = Some(i);
                        last_non_finite = false;
                    }
                    None => last_non_finite = true,
                }
            } else if err <= 1.0 {
                let t_new = self.clock.end(h, reaches_limit, t_limit);
                // The slope at the step's end (kept in k[12] until the
                // step is taken: it is the next step's first stage).
                let n = self.y.len();
                let end_slope = &mut self.k[12 * n..13 * n];
                system.rhs(t_new, &self.y_trial, end_slope)?;
                self.clock.stats.rhs_evaluations += 1;
                if let Some(i) = first_non_finite(end_slope) {
                    self.clock.reject_short(h);
                    rate_broken = Some(i);
                    last_non_finite = false;
                    continue;
                }
                let h_next = self.clock.controller.accept(h, err);
                // y_old ← y ← y_trial without copying.
                std::mem::swap(&mut self.y_old, &mut self.y);
                std::mem::swap(&mut self.y, &mut self.y_trial);
                self.clock.accept(h, t_new, h_next, reaches_limit);
                // k[0] becomes the new slope; X(t_old) moves to k[12] for
                // the continuous extension.
                let (start, rest) = self.k.split_at_mut(12 * n);
                start[..n].swap_with_slice(&mut rest[..n]);
                self.dense_ready = false;
                self.test_stiffness(h);
                return Ok(StepOutcome::Accepted);
            } else {
                self.clock.reject(h, err);
                last_non_finite = false;
            }
        }
    }

    /// Hairer's test after an accepted step of length `h`: `y` is the new
    /// state, `k[0] = X(t, y)`, and the last stage `k[11] = X(t, y₁)` was
    /// evaluated at the same time at `stage_state = y₁`.
    fn test_stiffness(&mut self, h: f64) {
        let (mut numerator, mut denominator) = (0.0, 0.0);
        let n = self.y.len();
        let (slope, last) = (&self.k[..n], &self.k[(STAGES - 1) * n..STAGES * n]);
        let (y, y1) = (
            &self.y[..n],
            &self.k[STAGE_STATE * n..(STAGE_STATE + 1) * n],
        );
        for i in 0..n {
            let (a, b) = (slope[i] - last[i], y[i] - y1[i]);
            numerator += a * a;
            denominator += b * b;
        }
        if denominator <= 0.0 || !numerator.is_finite() {
            return;
        }
        let h_rho = h.abs() * (numerator / denominator).sqrt();
        if h_rho > STIFF_H_RHO {
            self.non_stiff_tests = 0;
            self.stiff_tests += 1;
            if self.stiff_tests >= STIFF_STEPS && self.stiffness_detected.is_none() {
                self.stiffness_detected = Some(self.clock.t);
            }
        } else {
            self.non_stiff_tests += 1;
            if self.non_stiff_tests >= NON_STIFF_STEPS {
                self.stiff_tests = 0;
            }
        }
    }

    /// After an attempt of step `h` that was not finite: the component of
    /// the first stage whose rate is not finite although its state is (a
    /// force or mass law undefined ahead), `None` when a state overflowed
    /// first (the motion grows without bound). Recomputes the stage
    /// states, so it costs nothing on the way of finite steps.
    fn broken_rate(&mut self, h: f64) -> Option<usize> {
        let n = self.y.len();
        let (k, scratch) = self.k.split_at_mut(STAGE_STATE * n);
        let stage_state = &mut scratch[..n];
        for s in 1..STAGES {
            stage_state.copy_from_slice(&self.y);
            for &(j, a) in A[s] {
                axpy(h * a, &k[j * n..(j + 1) * n], stage_state);
            }
            if first_non_finite(stage_state).is_some() {
                return None;
            }
            if let Some(i) = first_non_finite(&k[s * n..(s + 1) * n]) {
                return Some(i);
            }
        }
        None
    }

    /// Computes the stages, `y_trial` and the two error estimates (per
    /// unit step) for step `h`: `false` when a stage is not finite; with
    /// `hairer`, Hairer's norm of the step under that tolerance, computed
    /// in the same pass (else `0`).
    ///
    /// Each stage state is one pass over the components summing the
    /// stage's row with its coefficients known at compile time (Hairer's
    /// `dop853.f` loops), and `y_trial` with both error estimates one more
    /// pass: for the small systems of mechanics (n = 2…12) a whole-vector
    /// `axpy` per coefficient cost more in loop overhead than the
    /// arithmetic, and the loops vectorise as well for the field's large
    /// coefficient systems.
    fn attempt<S: System + ?Sized>(
        &mut self,
        system: &S,
        h: f64,
        hairer: Option<Tolerance>,
    ) -> Result<(bool, f64), Failure> {
        let n = self.y.len();
        let t = self.clock.t;
        let y = &self.y[..n];
        let (k, scratch) = self.k.split_at_mut(STAGE_STATE * n);
        let (ys, scratch) = scratch.split_at_mut(n);
        let (error3, scratch) = scratch.split_at_mut(n);
        let error5 = &mut scratch[..n];
        macro_rules! stage {
            ($s:literal, $r:literal) => {{
                let (done, rest) = k.split_at_mut($s * n);
                let row: [(f64, &[f64]); $r] = std::array::from_fn(|m| {
                    let j = A[$s][m].0;
                    (A[$s][m].1, &done[j * n..(j + 1) * n])
                });
                combine(ys, y, h, &row);
                system.rhs(t + C[$s] * h, ys, &mut rest[..n])?;
            }};
        }
        stage!(1, 1);
        stage!(2, 2);
        stage!(3, 2);
        stage!(4, 3);
        stage!(5, 3);
        stage!(6, 4);
        stage!(7, 5);
        stage!(8, 6);
        stage!(9, 7);
        stage!(10, 8);
        stage!(11, 9);
        self.clock.stats.rhs_evaluations += STAGES - 1;
        let ks: [&[f64]; STAGES] = std::array::from_fn(|j| &k[j * n..(j + 1) * n]);
        let y_trial = &mut self.y_trial[..n];
        // 0·v is 0 for every finite v and NaN otherwise: one sum tells
        // whether every number of the step is finite.
        let mut poison = 0.0;
        let (mut err3, mut err5) = (0.0, 0.0);
        for i in 0..n {
            let mut b = 0.0;
            for &(j, w) in &B {
                b += w * ks[j][i];
            }
            let mut e5 = 0.0;
            for &(j, w) in &ER {
                e5 += w * ks[j][i];
            }
            let e3 = b
                - BHH[0].1 * ks[BHH[0].0][i]
                - BHH[1].1 * ks[BHH[1].0][i]
                - BHH[2].1 * ks[BHH[2].0][i];
            let y1 = y[i] + h * b;
            y_trial[i] = y1;
            error3[i] = e3;
            error5[i] = e5;
            poison += 0.0 * y1 + 0.0 * e3 + 0.0 * e5;
            if let Some(tol) = hairer {
                let inverse = 1.0 / (tol.atol + tol.rtol * y[i].abs().max(y1.abs()));
                let (a, b) = (e3 * inverse, e5 * inverse);
                err3 += a * a;
                err5 += b * b;
            }
        }
        let err = if hairer.is_some() {
            hairer_combine(h, n, err3, err5)
        } else {
            0.0
        };
        Ok((poison == 0.0, err))
    }

    /// The continuous extension of the last step (Hairer's `dop853.f`,
    /// `IOUT ≥ 2`): three more stages and the coefficients `cont`.
    fn prepare_dense<S: System + ?Sized>(&mut self, system: &S) -> Result<(), Failure> {
        let n = self.y.len();
        let (stages, rest) = self.k.split_at_mut(13 * n);
        let (extra, rest) = rest.split_at_mut((STAGE_STATE - 13) * n);
        let (stage_state, rest) = rest.split_at_mut(n);
        let cont = &mut rest[(CONT - STAGE_STATE - 1) * n..(BLOCKS - STAGE_STATE - 1) * n];
        continuous_extension(
            system,
            self.clock.t_old,
            self.clock.h_old,
            &self.y_old,
            &self.y,
            &FlatStages { data: stages, n },
            extra,
            stage_state,
            cont,
        )?;
        self.clock.stats.rhs_evaluations += 3;
        self.dense_ready = true;
        Ok(())
    }

    /// The last accepted step as data, to build its continuous extension
    /// later (the field method keeps the steps of a window until the window
    /// is accepted, and prepares only those that output asks for).
    pub fn raw_step(&self) -> RawStep {
        let mut step = RawStep::default();
        self.raw_step_into(&mut step);
        step
    }

    /// [`Dop853::raw_step`] into an existing value, reusing its storage.
    pub fn raw_step_into(&self, dst: &mut RawStep) {
        dst.t_old = self.clock.t_old;
        dst.h = self.clock.h_old;
        dst.t_new = self.clock.t;
        dst.data.clear();
        dst.data.reserve(15 * self.y.len());
        dst.data.extend_from_slice(&self.y_old);
        dst.data.extend_from_slice(&self.y);
        dst.data.extend_from_slice(&self.k[..13 * self.y.len()]);
    }

    /// The prepared continuous extension of the last accepted step, as a
    /// value that outlives the integrator's next step.
    pub fn dense_step<S: System + ?Sized>(&mut self, system: &S) -> Result<DenseStep, Failure> {
        if !self.dense_ready {
            self.prepare_dense(system)?;
        }
        Ok(DenseStep::dop853(
            self.clock.t_old,
            self.clock.t,
            self.clock.h_old,
            self.cont().to_vec(),
        ))
    }

    /// The continuous extension's coefficients (valid when `dense_ready`).
    fn cont(&self) -> &[f64] {
        let n = self.y.len();
        &self.k[CONT * n..BLOCKS * n]
    }
}

impl Clocked for Dop853 {
    fn clock(&self) -> &Clock {
        &self.clock
    }

    fn clock_mut(&mut self) -> &mut Clock {
        &mut self.clock
    }
}

impl Stepper for Dop853 {
    fn state(&self) -> &[f64] {
        &self.y
    }

    fn stiffness_detected(&self) -> Option<f64> {
        self.stiffness_detected
    }

    fn step<S: System + ?Sized>(
        &mut self,
        system: &S,
        t_limit: f64,
        budget: &Budget,
    ) -> Result<(), Failure> {
        let mut measure = HairerMeasure(self.tol);
        self.step_measured(system, t_limit, budget, &mut measure)
            .map(|_| ())
    }

    fn dense<S: System + ?Sized>(
        &mut self,
        system: &S,
        t: f64,
        out: &mut [f64],
    ) -> Result<(), Failure> {
        let n = self.y.len();
        let step = self.clock.last_step();
        if let Some(end) = crate::stepper::outside_last_step(t, step, &self.y_old, &self.y) {
            out.copy_from_slice(end);
            return Ok(());
        }
        if !self.dense_ready {
            self.prepare_dense(system)?;
        }
        contd8(
            self.cont(),
            n,
            (t - self.clock.t_old) / self.clock.h_old,
            out,
        );
        Ok(())
    }
}

pub use crate::dense::DenseStep;

impl DenseStep {
    fn dop853(t_old: f64, t_new: f64, h: f64, cont: Vec<f64>) -> DenseStep {
        DenseStep {
            t_old,
            t_new,
            h,
            kind: DenseKind::Dop853 { cont },
        }
    }
}

/// Stage `j` of Hairer's numbering (`0` the rate at the step's start,
/// `12` at its end, `13..16` the extra stages of the extension) in this
/// module's storage (`k[0]` the end rate, `k[12]` the start rate).
fn stage<'a, K: Stages + ?Sized>(k: &'a K, extra: &'a [f64], j: usize) -> &'a [f64] {
    match j {
        0 => k.stage(12),
        12 => k.stage(0),
        13.. => {
            let n = extra.len() / 3;
            &extra[(j - 13) * n..(j - 12) * n]
        }
        _ => k.stage(j),
    }
}

/// The 13 stages of a step as this module stores them (`k[0]` the end
/// rate, `k[12]` the start rate): the stepper's vectors, or a stored
/// step's one buffer.
trait Stages {
    fn stage(&self, j: usize) -> &[f64];
}

/// Stages stored one after another, `n` numbers each.
struct FlatStages<'a> {
    data: &'a [f64],
    n: usize,
}

impl Stages for FlatStages<'_> {
    fn stage(&self, j: usize) -> &[f64] {
        &self.data[j * self.n..(j + 1) * self.n]
    }
}

/// Computes the three extra stages into `extra` and the coefficients
/// `cont` (8 blocks of `n`) of the 7th-order continuous extension, with
/// `k` the 13 stages of the step as the stepper keeps them. Written as
/// whole-vector updates (one `axpy` per stage) so that it vectorises: the
/// field's coefficient systems have `(N+1)²` components.
#[allow(clippy::too_many_arguments)]
fn continuous_extension<S: System + ?Sized, K: Stages + ?Sized>(
    system: &S,
    t_old: f64,
    h: f64,
    y_old: &[f64],
    y: &[f64],
    k: &K,
    extra: &mut [f64],
    stage_state: &mut [f64],
    cont: &mut [f64],
) -> Result<(), Failure> {
    let n = y.len();
    let (y, y_old) = (&y[..n], &y_old[..n]);
    let stage_state = &mut stage_state[..n];
    let extra = &mut extra[..3 * n];
    macro_rules! extra_stage {
        ($e:literal, $r:literal) => {{
            let (done, rest) = extra.split_at_mut($e * n);
            let row: [(f64, &[f64]); $r] = std::array::from_fn(|m| {
                let j = A_EXTRA[$e][m].0;
                let stage = if j >= 13 {
                    &done[(j - 13) * n..(j - 12) * n]
                } else {
                    &stage(k, &[], j)[..n]
                };
                (A_EXTRA[$e][m].1, stage)
            });
            combine(stage_state, y_old, h, &row);
            system.rhs(t_old + C_EXTRA[$e] * h, stage_state, &mut rest[..n])?;
        }};
    }
    extra_stage!(0, 8);
    extra_stage!(1, 8);
    extra_stage!(2, 8);
    // The stages D uses (Hairer's numbering), as slices of length n.
    const USED: [usize; 12] = [0, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15];
    let extra = &*extra;
    let used: [&[f64]; 12] = std::array::from_fn(|m| &stage(k, extra, USED[m])[..n]);
    let (start_rate, end_rate) = (&k.stage(12)[..n], &k.stage(0)[..n]);
    let (c0, rest) = cont.split_at_mut(n);
    let (c1, rest) = rest.split_at_mut(n);
    let (c2, rest) = rest.split_at_mut(n);
    let (c3, rest) = rest.split_at_mut(n);
    let (c4, rest) = rest.split_at_mut(n);
    let (c5, rest) = rest.split_at_mut(n);
    let (c6, c7) = rest.split_at_mut(n);
    let c7 = &mut c7[..n];
    for i in 0..n {
        let y_diff = y[i] - y_old[i];
        let bspl = h * start_rate[i] - y_diff;
        c0[i] = y_old[i];
        c1[i] = y_diff;
        c2[i] = bspl;
        c3[i] = y_diff - h * end_rate[i] - bspl;
        let mut d = [0.0; 4];
        for (m, stage) in used.iter().enumerate() {
            let v = stage[i];
            for r in 0..4 {
                d[r] += D[r][USED[m]] * v;
            }
        }
        c4[i] = h * d[0];
        c5[i] = h * d[1];
        c6[i] = h * d[2];
        c7[i] = h * d[3];
    }
    Ok(())
}

/// The 7th-order continuous extension over `[t_old, t_old + h]` of one
/// DOP853 step of `system` from `y_old`, pinned to the end state `y_new`
/// given by the caller (a more accurate one than this step's own: the field
/// method's recovered state). 16 evaluations of `system`. The field method
/// uses it for its output between steps, on the motion linearised along
/// its predictor: the coefficients' extension, recovered through the
/// conditions, was up to 30× less accurate between the steps than at them.
pub fn dense_step_between<S: System + ?Sized>(
    system: &S,
    t_old: f64,
    h: f64,
    y_old: &[f64],
    y_new: &[f64],
) -> Result<DenseStep, Failure> {
    dense_step_between_measured(system, t_old, h, y_old, y_new, None).map(|(step, _)| step)
}

/// [`dense_step_between`], and with `tol` how far the step's own end
/// misses `y_new` (Hairer's scaled RMS norm; `0` without `tol`): above 1
/// the step is too long for one explicit step of `system`, and so is its
/// continuous extension.
pub fn dense_step_between_measured<S: System + ?Sized>(
    system: &S,
    t_old: f64,
    h: f64,
    y_old: &[f64],
    y_new: &[f64],
    tol: Option<Tolerance>,
) -> Result<(DenseStep, f64), Failure> {
    let n = y_old.len();
    // Hairer's stage numbering: k[0] the start rate, k[1..12] the stages.
    let mut k = vec![0.0; (STAGES + 1) * n];
    system.rhs(t_old, y_old, &mut k[..n])?;
    let mut stage_state = vec![0.0; n];
    for s in 1..STAGES {
        stage_state.copy_from_slice(y_old);
        for &(j, a) in A[s] {
            axpy(h * a, &k[j * n..(j + 1) * n], &mut stage_state);
        }
        system.rhs(t_old + C[s] * h, &stage_state, &mut k[s * n..(s + 1) * n])?;
    }
    let miss = match tol {
        Some(tol) => {
            let own_end: Vec<f64> = (0..n)
                .map(|i| y_old[i] + h * B.iter().map(|&(j, w)| w * k[j * n + i]).sum::<f64>())
                .collect();
            let miss: Vec<f64> = own_end.iter().zip(y_new).map(|(a, b)| a - b).collect();
            crate::tolerance::rms_norm(&miss, y_old, y_new, tol)
        }
        None => 0.0,
    };
    system.rhs(t_old + h, y_new, &mut k[STAGES * n..])?;
    // This module's storage: k[0] the end rate, k[12] the start rate.
    let (start, rest) = k.split_at_mut(STAGES * n);
    start[..n].swap_with_slice(&mut rest[..n]);
    let mut extra = vec![0.0; 3 * n];
    let mut cont = vec![0.0; 8 * n];
    continuous_extension(
        system,
        t_old,
        h,
        y_old,
        y_new,
        &FlatStages { data: &k, n },
        &mut extra,
        &mut stage_state,
        &mut cont,
    )?;
    if first_non_finite(&cont).is_some() {
        return Err(Failure::non_finite(t_old, system.component_name(0)));
    }
    Ok((DenseStep::dop853(t_old, t_old + h, h, cont), miss))
}

/// An accepted step as data (see [`Dop853::raw_step`]): one buffer of
/// `15 n` numbers, `y_old`, `y` and the 13 stages (`k[0]` the end rate,
/// `k[1..12]` the stages, `k[12]` the start rate) — one allocation a
/// stored step, not fifteen.
#[derive(Clone, Debug, Default)]
pub struct RawStep {
    pub t_old: f64,
    pub t_new: f64,
    h: f64,
    data: Vec<f64>,
}

impl RawStep {
    fn n(&self) -> usize {
        self.data.len() / 15
    }

    /// The state at the step's end.
    pub fn end_state(&self) -> &[f64] {
        let n = self.n();
        &self.data[n..2 * n]
    }

    /// The step's continuous extension (three evaluations of `system`,
    /// which must be the system the step was taken on).
    pub fn prepare<S: System + ?Sized>(&self, system: &S) -> Result<DenseStep, Failure> {
        let n = self.n();
        let (y_old, rest) = self.data.split_at(n);
        let (y, stages) = rest.split_at(n);
        let mut extra = vec![0.0; 3 * n];
        let mut stage_state = vec![0.0; n];
        let mut cont = vec![0.0; 8 * n];
        continuous_extension(
            system,
            self.t_old,
            self.h,
            y_old,
            y,
            &FlatStages { data: stages, n },
            &mut extra,
            &mut stage_state,
            &mut cont,
        )?;
        Ok(DenseStep::dop853(self.t_old, self.t_new, self.h, cont))
    }
}

/// `dst = base + h Σ_m a_m k_m` component by component; `R` is a
/// compile-time row length, so the inner sum unrolls.
#[inline(always)]
fn combine<const R: usize>(dst: &mut [f64], base: &[f64], h: f64, row: &[(f64, &[f64]); R]) {
    let n = dst.len();
    let base = &base[..n];
    for i in 0..n {
        let mut acc = 0.0;
        for (a, k) in row {
            acc += a * k[i];
        }
        dst[i] = base[i] + h * acc;
    }
}

/// `y += a x`.
#[inline]
fn axpy(a: f64, x: &[f64], y: &mut [f64]) {
    for (yi, xi) in y.iter_mut().zip(x) {
        *yi += a * xi;
    }
}
