//! DOP853: the explicit Runge–Kutta method of order 8 of Dormand and Prince
//! with Hairer's combined 5th/3rd-order error estimate (HNW I, II.10).
//! Coefficients as in Hairer's `dop853.f`.

// The coefficients are kept to the digits Hairer published them with.
#![allow(clippy::excessive_precision)]

use super::error::Failure;
use super::stepper::{
    first_non_finite, initial_step, step_toward, underflow_failure, underflows, Stats, Stepper,
    Tolerance,
};
use super::system::Motion;

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

/// Hairer's stiffness test (`dop853.f`): `h·ρ` estimated from the last
/// stage, `h ‖X(t+h, y₁) − X(t+h, ŷ)‖ / ‖y₁ − ŷ‖`, past the edge of
/// DOP853's stability region (≈ 6.1 on the negative real axis) on
/// `STIFF_STEPS` tests, not interrupted by `NON_STIFF_STEPS` tests below it.
const STIFF_H_RHO: f64 = 6.1;
const STIFF_STEPS: usize = 15;
const NON_STIFF_STEPS: usize = 6;

const SAFETY: f64 = 0.9;
const MIN_SCALE: f64 = 0.333;
const MAX_SCALE: f64 = 6.0;

/// The DOP853 integrator at time `t` with state `y`.
pub struct Dop853 {
    tol: Tolerance,
    t: f64,
    y: Vec<f64>,
    /// `k[0]` is `X(t, y)` (first same as last); the others are scratch.
    k: Vec<Vec<f64>>,
    y_trial: Vec<f64>,
    stage_state: Vec<f64>,
    h: f64,
    stats: Stats,
    stiff_tests: usize,
    non_stiff_tests: usize,
    stiffness_detected: Option<f64>,
}

impl Dop853 {
    /// Starts at `(t0, y0)`; `h_max` bounds the first step guess.
    pub fn new<M: Motion + ?Sized>(
        system: &M,
        t0: f64,
        y0: &[f64],
        tol: Tolerance,
        h_max: f64,
    ) -> Result<Self, Failure> {
        let n = y0.len();
        if let Some(i) = first_non_finite(y0) {
            return Err(Failure::non_finite(t0, system.component_name(i)));
        }
        let mut k = vec![vec![0.0; n]; STAGES];
        system.rhs(t0, y0, &mut k[0])?;
        if let Some(i) = first_non_finite(&k[0]) {
            return Err(Failure::non_finite(
                t0,
                format!("{}'", system.component_name(i)),
            ));
        }
        let h = initial_step(system, t0, y0, &k[0], tol, 8, h_max)?;
        Ok(Dop853 {
            tol,
            t: t0,
            y: y0.to_vec(),
            k,
            y_trial: vec![0.0; n],
            stage_state: vec![0.0; n],
            h,
            stats: Stats {
                rhs_evaluations: 2,
                ..Stats::default()
            },
            stiff_tests: 0,
            non_stiff_tests: 0,
            stiffness_detected: None,
        })
    }

    /// Hairer's test after an accepted step of length `h`: `y` is the new
    /// state, `k[0] = X(t, y)`, and the last stage `k[11] = X(t, y₁)` was
    /// evaluated at the same time (node 1) at `stage_state = y₁`.
    fn test_stiffness(&mut self, h: f64) {
        let (mut numerator, mut denominator) = (0.0, 0.0);
        for i in 0..self.y.len() {
            numerator += (self.k[0][i] - self.k[STAGES - 1][i]).powi(2);
            denominator += (self.y[i] - self.stage_state[i]).powi(2);
        }
        if denominator <= 0.0 || !numerator.is_finite() {
            return;
        }
        let h_rho = h.abs() * (numerator / denominator).sqrt();
        if h_rho > STIFF_H_RHO {
            self.non_stiff_tests = 0;
            self.stiff_tests += 1;
            if self.stiff_tests >= STIFF_STEPS && self.stiffness_detected.is_none() {
                self.stiffness_detected = Some(self.t);
            }
        } else {
            self.non_stiff_tests += 1;
            if self.non_stiff_tests >= NON_STIFF_STEPS {
                self.stiff_tests = 0;
            }
        }
    }

    /// Computes the stages and `y_trial` for step `h`; returns the scaled
    /// error, or `None` when a stage is not finite.
    fn attempt<M: Motion + ?Sized>(&mut self, system: &M, h: f64) -> Result<Option<f64>, Failure> {
        let n = self.y.len();
        for s in 1..STAGES {
            for i in 0..n {
                let increment: f64 = A[s].iter().map(|&(j, a)| a * self.k[j][i]).sum();
                self.stage_state[i] = self.y[i] + h * increment;
            }
            system.rhs(self.t + C[s] * h, &self.stage_state, &mut self.k[s])?;
            self.stats.rhs_evaluations += 1;
        }
        let (mut err3, mut err5) = (0.0, 0.0);
        for i in 0..n {
            let slope: f64 = B.iter().map(|&(j, b)| b * self.k[j][i]).sum();
            self.y_trial[i] = self.y[i] + h * slope;
            let e3 = slope - BHH.iter().map(|&(j, b)| b * self.k[j][i]).sum::<f64>();
            let e5: f64 = ER.iter().map(|&(j, e)| e * self.k[j][i]).sum();
            let scale = self.tol.atol + self.tol.rtol * self.y[i].abs().max(self.y_trial[i].abs());
            err3 += (e3 / scale).powi(2);
            err5 += (e5 / scale).powi(2);
        }
        if first_non_finite(&self.y_trial).is_some() || !err5.is_finite() || !err3.is_finite() {
            return Ok(None);
        }
        let denominator = if err5 + 0.01 * err3 > 0.0 {
            err5 + 0.01 * err3
        } else {
            1.0
        };
        Ok(Some(
            h.abs() * err5 * (1.0 / (n as f64 * denominator)).sqrt(),
        ))
    }
}

impl Stepper for Dop853 {
    fn time(&self) -> f64 {
        self.t
    }

    fn state(&self) -> &[f64] {
        &self.y
    }

    fn stats(&self) -> Stats {
        self.stats
    }

    fn proposed_step(&self) -> f64 {
        self.h
    }

    fn propose_step(&mut self, h: f64) {
        if h.is_finite() && h > 0.0 {
            self.h = h;
        }
    }

    fn stiffness_detected(&self) -> Option<f64> {
        self.stiffness_detected
    }

    fn step<M: Motion + ?Sized>(&mut self, system: &M, t_limit: f64) -> Result<(), Failure> {
        let mut last_rejected = false;
        let mut last_non_finite = false;
        loop {
            let (h, reaches_limit) = step_toward(self.t, self.h, t_limit);
            if underflows(self.t, h) && !reaches_limit {
                return Err(if last_non_finite {
                    let i = first_non_finite(&self.y_trial).unwrap_or(0);
                    Failure::non_finite(self.t, system.component_name(i))
                } else {
                    underflow_failure(self.t, h)
                });
            }
            match self.attempt(system, h)? {
                None => {
                    // A stage overflowed: the step was too long for a
                    // solution that grows fast; retry shorter.
                    self.stats.rejected_steps += 1;
                    self.h = h * 0.25;
                    last_rejected = true;
                    last_non_finite = true;
                }
                Some(err) if err <= 1.0 => {
                    let scale = if err == 0.0 {
                        MAX_SCALE
                    } else {
                        (SAFETY * err.powf(-1.0 / 8.0)).clamp(MIN_SCALE, MAX_SCALE)
                    };
                    let h_next = if last_rejected {
                        h * scale.min(1.0)
                    } else {
                        h * scale
                    };
                    std::mem::swap(&mut self.y, &mut self.y_trial);
                    self.t = if reaches_limit { t_limit } else { self.t + h };
                    // A step cut short to hit `t_limit` says nothing
                    // against the longer step proposed before.
                    self.h = if reaches_limit {
                        h_next.max(self.h)
                    } else {
                        h_next
                    };
                    system.rhs(self.t, &self.y, &mut self.k[0])?;
                    self.stats.rhs_evaluations += 1;
                    self.stats.accepted_steps += 1;
                    if let Some(i) = first_non_finite(&self.k[0]) {
                        return Err(Failure::non_finite(
                            self.t,
                            format!("{}'", system.component_name(i)),
                        ));
                    }
                    self.test_stiffness(h);
                    return Ok(());
                }
                Some(err) => {
                    self.stats.rejected_steps += 1;
                    self.h = h * (SAFETY * err.powf(-1.0 / 8.0)).max(MIN_SCALE);
                    last_rejected = true;
                    last_non_finite = false;
                }
            }
        }
    }
}
