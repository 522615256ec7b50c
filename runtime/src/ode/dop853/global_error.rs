//! A global error estimate carried along a DOP853 integration: the sum of
//! its steps' local errors, each relative to the state's size,
//! `E = Σ_n max_i |ℓ_n,i| / max(|x_n,i|, 1)` (the measure of the
//! summary's error against an exact solution).
//!
//! The local error control bounds each step's error, not their sum: over
//! a long horizon they add up (an undamped oscillator over 160 periods at
//! rtol 1e-10 ends 24× rtol off). The sum is the global error's bound
//! (Dahlquist's, with logarithmic norm 0) for a motion that neither
//! amplifies nor damps errors, as a conservative mechanical motion does
//! on average; it over-states where the motion damps them, and does not
//! bound a chaotic motion's, whose errors grow.
//!
//! The local errors: Hairer's estimate `ℓ̂_n` (the vector whose scaled norm
//! is the `err` the step was accepted with) is at hand but of order 8,
//! where the error of the solution DOP853 carries is of order 9: on the
//! oscillator at rtol 1e-10 the true local error is 0.07× the estimate.
//! So once the sum of the estimates passes [`BOUND`]`·rtol` (a run whose
//! sum stays below it is within the bound already, and pays nothing), and
//! every
//! [`CALIBRATION_STRIDE`] steps after, a step's local error is measured by
//! Richardson extrapolation (`Dop853::local_error_by_halves`, 23
//! evaluations), and the ratio `κ = ℓ / ℓ̂` it gives scales the estimates
//! of the steps until the next measure — by `h / h_κ` too, since the ratio
//! of an order-9 error to an order-8 estimate goes as the step. The sum
//! before the first measure is scaled by its `κ`. `κ` is kept at most 1:
//! above the order-8 estimate a measure is rounding or a step across a
//! kink (Coulomb friction at rtol 1e-12 gave κ ≈ 100).
//!
//! Propagating the errors by the exact Jacobian instead (the linearised
//! error equation) was tried and dropped: the reduced system's drift off
//! the constraints made the propagated error grow without bound on the
//! knife edge and the particle on a circle (1e9× rtol), where the run
//! itself is kept on them.

pub mod growth;

/// The bound the summary holds the estimate to, in units of rtol: below
/// it the unscaled sum (an over-estimate) already says the run is within.
pub const BOUND: f64 = 10.0;

/// A carried global error at least this large (relative to
/// `max(|x|, 1)`) is past the state's own size: the summary reports it
/// as amplification, not as a number, and the errors are no longer
/// carried (`growth::Growth::saturated`).
pub const AMPLIFIED: f64 = 1.0;

/// Steps between two measures of the local error.
pub const CALIBRATION_STRIDE: usize = 32;

/// The smallest local error a Richardson difference resolves (relative,
/// a few roundings of the state).
const MEASURE_FLOOR: f64 = 16.0 * f64::EPSILON;

/// The carried estimate of one run.
#[derive(Clone, Debug, Default)]
pub struct GlobalError {
    sum: f64,
    /// The same sum in the motion's own scale, and its largest reading
    /// where the state is small ([`GlobalError::swing`]).
    swing_sum: f64,
    swing_read: f64,
    /// The last measure: `κ` and the step it was taken on.
    ratio: Option<(f64, f64)>,
    /// Steps since the last measure.
    since: usize,
    /// False once a step was not accounted for (a stiff integrator's):
    /// the estimate then covers only part of the run.
    complete: bool,
}

/// `max_i |ℓ_i| / max(|x_i|, 1)`.
pub fn relative(local: &[f64], x: &[f64]) -> f64 {
    let mut worst = 0.0_f64;
    for (l, x) in local.iter().zip(x) {
        worst = worst.max(l.abs() / x.abs().max(1.0));
    }
    worst
}

/// `max_i |e_i| / max(m_i, 1)`, `m_i` the smallest `|x_i|` over a step
/// from `x0` to `x1`: 0 where the component changes sign (it passes zero
/// between the ends, where a sample reads it against 1), else the smaller
/// end's. An error read at the step's ends alone misses the samples
/// between: a velocity of amplitude 12 read 2–5 at the ends around its
/// turning point.
pub fn relative_over_step(e: &[f64], x0: &[f64], x1: &[f64]) -> f64 {
    let mut worst = 0.0_f64;
    for ((e, a), b) in e.iter().zip(x0).zip(x1) {
        worst = worst.max(e.abs() / smallest_over_step(*a, *b).max(1.0));
    }
    worst
}

/// The smallest `|x|` a component takes over a step from `a` to `b`, as
/// far as its ends tell: 0 where it changes sign.
fn smallest_over_step(a: f64, b: f64) -> f64 {
    if a * b <= 0.0 {
        0.0
    } else {
        a.abs().min(b.abs())
    }
}

/// The sum of the local errors in the motion's own scale, read where the
/// state is small. Why: the sum relative to `max(|x|, 1)` (the summary's
/// measure) bounds the error in the scale of the state where each step
/// was taken, but an oscillation turns an error made at full swing into a
/// phase error, which a sample at the component's turning point reads
/// against 1, not against the swing: a ball rolling inside a cylinder
/// (`th'` swinging ±11.8) by DOP853 at rtol 1e-6 summed 3.4 rtol and was
/// 25 rtol off at `th'`'s turning points (3.5 rtol in the swing's scale);
/// a pendulum released at 60° at rtol 1e-5, 8.7 rtol summed, 15.6 off.
/// So each step's error is taken relative to each component's swing (the
/// largest `|x_i|` over its current and last half swing, between changes
/// of sign: a damped swing's scale follows its decay), summed, and the
/// sum read as a bound on the error in every component's swing, against 1
/// where a component passes zero over a step. A component that keeps its
/// sign over a step (a rocket's speed, an angle that grows, a speed drag
/// slows down) is read there by the relative sum, in its own scale: a
/// motion that damps its errors (drag) is not charged the swing it no
/// longer has (a component that only dips towards zero without passing
/// it is read at the steps' ends, as before).
///
/// The swings are kept beside the estimate ([`Swings`]), not in it:
/// direct integration keeps a copy of the estimate before each step (to
/// drop a step taken again), and copying two vectors a step was a third
/// of the swing's cost; a step taken again leaves its swing in them (the
/// run passed near there).
#[derive(Clone, Debug, Default)]
pub struct Swings {
    /// Per component: the largest `|x_i|` since it last changed sign, and
    /// over the half swing before.
    peak: Vec<f64>,
    last_peak: Vec<f64>,
    /// Per component: the changes of sign so far (a start at 0 counts).
    passes: Vec<u32>,
}

/// The changes of sign a component makes before its swing is read where
/// it passes zero: a start at rest and one turning point are not yet an
/// oscillation. A rocket that rises from 0, turns at its apex and lands
/// (`rocket_burnout_landing`) read 700 rtol for an error of 4.9 at rtol
/// 1e-6 where its speed and height first passed zero: their errors shear
/// with the flight, they do not turn into a phase bounded by the swing.
const PASSES_BEFORE_READING: u32 = 3;

impl Swings {
    /// None yet (a new run's).
    pub fn clear(&mut self) {
        self.peak.clear();
        self.last_peak.clear();
        self.passes.clear();
    }
}

impl GlobalError {
    pub fn new() -> GlobalError {
        GlobalError {
            sum: 0.0,
            swing_sum: 0.0,
            swing_read: 0.0,
            ratio: None,
            since: 0,
            complete: true,
        }
    }

    /// The estimated global error so far, relative to `max(|x|, 1)`
    /// component by component.
    pub fn estimate(&self) -> f64 {
        self.sum
    }

    /// The estimate the summary reads: the sum, or, where a component
    /// passes zero, the sum in the motion's own scale read there
    /// ([`Swings`]), whichever is larger (a run that never called
    /// [`GlobalError::swing`] reads its sum).
    pub fn read(&self) -> f64 {
        self.sum.max(self.swing_read)
    }

    /// The step from `x0` to `x1` whose local error vector is `local`, of
    /// which [`GlobalError::add`] or [`GlobalError::add_measured`] just
    /// put `added` into the sum for the relative `estimated`: the same
    /// step, scaled as the sum scaled it, in the motion's own scale, the
    /// components' swings so far in `swings` ([`Swings`]).
    pub fn swing(
        &mut self,
        swings: &mut Swings,
        local: &[f64],
        (x0, x1): (&[f64], &[f64]),
        estimated: f64,
        added: f64,
    ) {
        if swings.peak.len() != x1.len() {
            swings.peak = vec![0.0; x1.len()];
            swings.last_peak = vec![0.0; x1.len()];
            swings.passes = vec![0; x1.len()];
        }
        let (mut term, mut factor) = (0.0_f64, 1.0_f64);
        let peaks = swings.peak.iter_mut().zip(swings.last_peak.iter_mut());
        let states = local.iter().zip(x0).zip(x1);
        for ((((l, a), b), (peak, last_peak)), passes) in states.zip(peaks).zip(&mut swings.passes)
        {
            let larger = a.abs().max(b.abs());
            let passes_zero = a * b <= 0.0;
            if passes_zero {
                *last_peak = *peak;
                *peak = larger;
                *passes = passes.saturating_add(1);
            } else {
                *peak = peak.max(larger);
            }
            let swing = peak.max(*last_peak).max(1.0);
            term = term.max(l.abs() / swing);
            if passes_zero && *passes >= PASSES_BEFORE_READING {
                factor = factor.max(swing);
            }
        }
        let scale = if estimated > 0.0 && added.is_finite() {
            added / estimated
        } else {
            0.0
        };
        self.swing_sum += scale * term;
        if self.swing_sum.is_finite() {
            self.swing_read = self.swing_read.max(self.swing_sum * factor);
        }
    }

    /// Whether a measure has calibrated the sum.
    pub fn calibrated(&self) -> bool {
        self.ratio.is_some()
    }

    /// Whether every step of the run was accounted for.
    pub fn complete(&self) -> bool {
        self.complete
    }

    /// A step the estimate cannot account for.
    pub fn skip(&mut self) {
        self.complete = false;
    }

    /// Whether the next step's local error should be measured (see the
    /// module's comment), for a run at relative tolerance `rtol`.
    pub fn wants_measure(&self, rtol: f64) -> bool {
        match self.ratio {
            None => self.sum > BOUND * rtol,
            Some(_) => self.since >= CALIBRATION_STRIDE,
        }
    }

    /// An accepted step of length `h` whose local error Hairer's estimate
    /// puts at `estimated` (relative, [`relative`]); what it added.
    pub fn add(&mut self, estimated: f64, h: f64) -> f64 {
        if !estimated.is_finite() {
            self.complete = false;
            return 0.0;
        }
        let scale = match self.ratio {
            Some((kappa, h_kappa)) if h_kappa > 0.0 => kappa * (h / h_kappa).clamp(0.125, 8.0),
            _ => 1.0,
        };
        self.sum += scale * estimated;
        self.since += 1;
        scale * estimated
    }

    /// An accepted step of length `h` whose local error was measured:
    /// `measured`, against Hairer's `estimated` (both relative); what it
    /// added.
    pub fn add_measured(&mut self, estimated: f64, measured: f64, h: f64) -> f64 {
        if !(measured.is_finite() && estimated > 0.0) {
            return self.add(estimated, h);
        }
        // Below a few roundings a difference measures nothing, and above
        // Hairer's estimate it is rounding or a step across a kink: the
        // order-8 estimate bounds the order-9 error where the steps are
        // in their asymptotic range.
        let kappa = (measured.max(MEASURE_FLOOR) / estimated).min(1.0);
        let measured = kappa * estimated;
        if self.ratio.is_none() {
            self.sum *= kappa;
            self.swing_sum *= kappa;
            self.swing_read *= kappa;
        }
        self.ratio = Some((kappa, h.abs()));
        self.sum += measured;
        self.since = 0;
        measured
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sums_relative_local_errors_and_scales_them_by_the_measured_ratio() {
        let mut g = GlobalError::new();
        // Relative to max(|x|, 1): 2e-10 / 2 and 3e-10 / 1.
        g.add(relative(&[2e-10, -1e-11], &[2.0, 0.5]), 1.0);
        g.add(relative(&[1e-12, -3e-10], &[0.1, 0.0]), 1.0);
        assert!((g.estimate() - 4e-10).abs() < 1e-24, "{}", g.estimate());
        assert!(!g.wants_measure(1e-10) && g.wants_measure(1e-11));
        // A measure at a tenth of the estimate scales what came before.
        g.add_measured(1e-10, 1e-11, 1.0);
        assert!((g.estimate() - 5e-11).abs() < 1e-24, "{}", g.estimate());
        // ... and the next estimates, by the step's length too.
        g.add(1e-10, 2.0);
        assert!((g.estimate() - 7e-11).abs() < 1e-24, "{}", g.estimate());
        assert!(!g.wants_measure(1e-10));
        for _ in 0..CALIBRATION_STRIDE {
            g.add(0.0, 1.0);
        }
        assert!(g.wants_measure(1e-10));
        assert!(g.complete());
        g.add(f64::NAN, 1.0);
        assert!(!g.complete());
    }

    /// Adds one step from `x0` to `x1` with local error `local`, as
    /// direct integration does.
    fn step(g: &mut GlobalError, swings: &mut Swings, local: &[f64], x0: &[f64], x1: &[f64]) {
        let estimated = relative(local, x1);
        let added = g.add(estimated, 1.0);
        g.swing(swings, local, (x0, x1), estimated, added);
    }

    #[test]
    fn an_oscillations_sum_is_read_in_its_swing_where_it_passes_zero() {
        // x = 10 cos t, v = −10 sin t, in quarter periods: each step's
        // error 1e-9 in both, 1e-10 of the swing. Every step ends with a
        // component at 0, where the relative sum reads it against 1.
        let (mut g, mut swings) = (GlobalError::new(), Swings::default());
        let states = [
            [10.0, 0.0],
            [0.0, -10.0],
            [-10.0, 0.0],
            [0.0, 10.0],
            [10.0, 0.0],
        ];
        for w in states.windows(2) {
            step(&mut g, &mut swings, &[1e-9, 1e-9], &w[0], &w[1]);
        }
        // The relative sum: each step's larger share, 1e-9 / max(0, 1).
        assert!((g.estimate() - 4e-9).abs() < 1e-22, "{}", g.estimate());
        // Swing-scaled, 4 × 1e-10, read against 1 where a component passes
        // zero: 4e-9, no less than the sum.
        assert!((g.read() - 4e-9).abs() < 1e-22, "{}", g.read());
        // Steps whose ends are away from zero (swing 8, |x| ≥ 6 at every
        // end), two turns: the relative sum says 8 × 1e-9 / 6, but each
        // step passes a component through zero, where a sample reads the
        // error against 1: 8 × 1e-9 / 8 in the swing, read there ×8 once
        // the component has passed zero `PASSES_BEFORE_READING` times.
        let (mut g, mut swings) = (GlobalError::new(), Swings::default());
        let turn = [[8.0, -6.0], [-6.0, -8.0], [-8.0, 6.0], [6.0, 8.0]];
        let states: Vec<[f64; 2]> = turn
            .iter()
            .chain(&turn)
            .chain(&turn[..1])
            .copied()
            .collect();
        for (k, w) in states.windows(2).enumerate() {
            step(&mut g, &mut swings, &[1e-9, 1e-9], &w[0], &w[1]);
            if k < 4 {
                // Two passes each: not yet read.
                assert_eq!(g.read(), g.estimate());
            }
        }
        assert!(
            (g.estimate() - 8e-9 / 6.0).abs() < 1e-22,
            "{}",
            g.estimate()
        );
        assert!((g.read() - 8e-9).abs() < 1e-22, "{}", g.read());
    }

    #[test]
    fn a_component_that_keeps_its_sign_reads_its_own_sum() {
        // A speed growing from 1 to 1000 and one decaying from 1000 to 10
        // (drag): no turning point, no swing to read.
        for speeds in [[1.0, 10.0, 100.0, 1000.0], [1000.0, 100.0, 30.0, 10.0]] {
            let (mut g, mut swings) = (GlobalError::new(), Swings::default());
            for w in speeds.windows(2) {
                step(&mut g, &mut swings, &[1e-10 * w[1]], &[w[0]], &[w[1]]);
            }
            assert!((g.estimate() - 3e-10).abs() < 1e-22, "{}", g.estimate());
            assert_eq!(g.read(), g.estimate());
        }
    }

    #[test]
    fn over_a_step_a_component_that_changes_sign_is_read_against_one() {
        assert_eq!(
            relative_over_step(&[1e-9, 0.0], &[5.0, 1.0], &[-5.0, 1.0]),
            1e-9
        );
        assert_eq!(
            relative_over_step(&[1e-9, 0.0], &[5.0, 1.0], &[4.0, 1.0]),
            2.5e-10
        );
        assert_eq!(relative_over_step(&[1e-9], &[5.0], &[0.0]), 1e-9);
    }
}
