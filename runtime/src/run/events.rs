//! Locating events on the dense output: the time where a switching
//! function changes sign within a step, by the Illinois variant of regula
//! falsi (superlinear, and never slower than bisection by much).

/// The root of `phi` in `(a, b]` where `phi(a)` and `phi(b)` differ in
/// sign: the end of a bracket no wider than `4·eps·max(|t|, 1)` on the
/// far side of the sign change (so the state there already shows the new
/// sign). `phi` may fail; the failure is passed on.
pub fn locate<E>(
    mut a: f64,
    mut phi_a: f64,
    mut b: f64,
    mut phi_b: f64,
    mut phi: impl FnMut(f64) -> Result<f64, E>,
) -> Result<f64, E> {
    debug_assert!(phi_a.signum() != phi_b.signum() || phi_b == 0.0);
    // The far side's sign. A value exactly 0 belongs to the far side but
    // must not be compared by its own sign (`signum(0.0)` is +1, which
    // would send a bracket from a positive side past the root): it is
    // kept as the far side's smallest value instead.
    let far = if phi_b != 0.0 {
        phi_b.signum()
    } else {
        -phi_a.signum()
    };
    let on_far_side = |v: f64| v == 0.0 || v.signum() == far;
    let far_value = |v: f64| if v == 0.0 { far * f64::MIN_POSITIVE } else { v };
    phi_b = far_value(phi_b);
    // Which end was kept twice in a row (Illinois halves its value).
    let mut kept: i8 = 0;
    for _ in 0..200 {
        let width = b - a;
        if width <= 4.0 * f64::EPSILON * a.abs().max(b.abs()).max(1.0) {
            break;
        }
        let mut t = if phi_b != phi_a {
            b - phi_b * width / (phi_b - phi_a)
        } else {
            a + 0.5 * width
        };
        // Stay strictly inside, away from the ends by a sliver.
        let margin = 0.01 * width;
        if !(t > a + margin && t < b - margin) {
            t = a + 0.5 * width;
        }
        let value = phi(t)?;
        if on_far_side(value) {
            b = t;
            phi_b = far_value(value);
            if kept == -1 {
                phi_a *= 0.5;
            }
            kept = -1;
        } else {
            a = t;
            phi_a = value;
            if kept == 1 {
                phi_b *= 0.5;
            }
            kept = 1;
        }
    }
    Ok(b)
}

/// How far the next step may reach so that no switch changes sign unseen
/// (SPEC: every switch is located). A step's dense output is looked at in
/// a few points only, so a switching function with a time scale of its own
/// — a force switched by a clock, `if sin(20 t) > 0 …`, over a motion that
/// DOP853 integrates exactly in long steps — would change sign and back
/// between them. After each step the pace estimates, from every
/// function's values at the step's start, quarters and end, how soon it
/// may reach zero:
/// - heading toward zero (`g g' < 0`): in `|g / g'|`; the next step may
///   reach [`REACH_PAST_ZERO`] times as far, so that the crossing falls
///   inside it;
/// - curving toward zero (`g g'' < 0`): with `ω = √|g'' / g|` (exact for
///   `g = A sin ωt`), the next step covers at most [`PHASE_PER_STEP`] of
///   its phase;
/// - oscillating about a level, `g = C + A cos(ωt + φ)` (a duty cycle
///   other than a half, `if sin(w t) > 0.5`, where `g'' / g` says nothing):
///   `ω` from the five values (their differences `u` satisfy
///   `u[i-1] + u[i+1] = 2 cos(ω d) u[i]`), and unless the fitted level is
///   well clear of the amplitude the same phase per step.
///
/// A function moving away from zero and curving away (a height that grows
/// as a rocket climbs) does not limit the steps.
#[derive(Clone, Debug, Default)]
pub struct SwitchPace {
    /// The largest rate of the last step's functions (`0`: no limit).
    rate: f64,
}

/// How far past the linearly predicted zero the next step may reach.
pub const REACH_PAST_ZERO: f64 = 1.5;

/// The phase of a switching function's oscillation one step may cover:
/// about four steps a period, the points looked at 0.375 apart, so that a
/// sign change and its return (half a period, π, apart; closer only for a
/// function that barely crosses) are not missed. At 1.0 the rectified
/// forcing of tests/data/v2 took 255 steps at rtol 1e-6, at 1.5 195, and
/// 140 unpaced.
pub const PHASE_PER_STEP: f64 = 1.5;

/// A function's values at a step's start, quarters and end.
pub type Quarters<'a> = [&'a [f64]; 5];

impl SwitchPace {
    /// Learns from a step of length `h` with no sign change.
    pub fn observe(&mut self, h: f64, g: Quarters) {
        if let Some(rate) = fastest(h, g, &[]) {
            self.rate = rate;
        }
    }

    /// Learns, where an event restarts the solution, from the part of the
    /// step before it (its last values those at the event). The functions
    /// that switched there are at zero, so their slope (heading through
    /// zero, not to it) does not count. Every step may end in an event, as
    /// under a fast clock, so the pace learnt before is kept if it was
    /// faster.
    pub fn observe_to_event(&mut self, h: f64, g: Quarters, switched: &[usize]) {
        if let Some(rate) = fastest(h, g, switched) {
            self.rate = self.rate.max(rate);
        }
    }

    /// The faster of this pace and `other`.
    pub fn at_least(&mut self, other: &SwitchPace) {
        self.rate = self.rate.max(other.rate);
    }

    /// The end of the next step from `t`, at most `t_end`.
    pub fn limit(&self, t: f64, t_end: f64) -> f64 {
        if self.rate > 0.0 {
            t_end.min(t + 1.0 / self.rate)
        } else {
            t_end
        }
    }
}

/// The largest [`rate`] of the functions over a step of length `h` (the
/// `switched` ones without their slope), or `None` for an empty step.
fn fastest(h: f64, g: Quarters, switched: &[usize]) -> Option<f64> {
    let d = 0.25 * h.abs();
    if !(d > 0.0) {
        return None;
    }
    let rates = (0..g[4].len()).map(|k| {
        let values = [g[0][k], g[1][k], g[2][k], g[3][k], g[4][k]];
        rate(d, values, !switched.contains(&k))
    });
    Some(rates.fold(0.0, f64::max))
}

/// How fast one function may reach zero, from its values `y` at spacing
/// `d` (the last where the next step starts). `0`: no limit.
fn rate(d: f64, y: [f64; 5], with_slope: bool) -> f64 {
    if y.iter().any(|v| !v.is_finite()) {
        return 0.0;
    }
    let omega = match oscillation(d, y) {
        Oscillation::ClearOfZero => return 0.0,
        Oscillation::At(omega) => omega,
        Oscillation::None => 0.0,
    };
    let [_, _, g2, g1, g0] = y;
    let mut rate = omega / PHASE_PER_STEP;
    // The slope at the end (one-sided, second order).
    if with_slope && g0 != 0.0 {
        let slope = (3.0 * g0 - 4.0 * g1 + g2) / (2.0 * d);
        if g0 * slope < 0.0 {
            rate = rate.max((slope / g0).abs() / REACH_PAST_ZERO);
        }
    }
    // The curvature at three quarters (central), against the value there.
    let curvature = (g0 - 2.0 * g1 + g2) / (d * d);
    if g1 * curvature < 0.0 {
        rate = rate.max((curvature / g1).abs().sqrt() / PHASE_PER_STEP);
    }
    if rate.is_finite() {
        rate
    } else {
        0.0
    }
}

/// What five values say of a function as an oscillation about a level.
enum Oscillation {
    /// Growing, polynomial, or too slow to tell.
    None,
    /// Oscillating at this angular frequency, possibly through zero.
    At(f64),
    /// Oscillating with a level well clear of its amplitude (a clock's
    /// `sin(w t) > 2`): never zero.
    ClearOfZero,
}

/// The oscillation of `y`, from its differences `u`, which satisfy
/// `u[i-1] + u[i+1] = 2 cos(ω d) u[i]` for `C + A cos(ωt + φ)`. Sampled
/// at or beyond the Nyquist rate (`ω d ≥ π`) the frequency is not known:
/// the Nyquist one, so that the next step is shorter and sees it.
fn oscillation(d: f64, y: [f64; 5]) -> Oscillation {
    let u = [y[1] - y[0], y[2] - y[1], y[3] - y[2], y[4] - y[3]];
    let den = 2.0 * (u[1] * u[1] + u[2] * u[2]);
    if !(den > 0.0) {
        return Oscillation::None;
    }
    let cos = ((u[0] + u[2]) * u[1] + (u[1] + u[3]) * u[2]) / den;
    // `1 − cos` must stand clear of what rounding does to it (a function
    // that hardly changes over a short step, `x' ≈ 1` in the first steps
    // of an oscillator: there rounding read as a fast oscillation and
    // shrank the steps); and at `ω d` below 1.4e-6 the limit would be 10⁵
    // steps ahead anyway.
    let scale = y.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    let rounding = 4.0 * f64::EPSILON * scale / (0.5 * den).sqrt();
    if !(1.0 - cos > (10.0 * rounding).max(1e-12)) {
        return Oscillation::None;
    }
    let omega = cos.max(-1.0).acos() / d;
    // Over half a radian the five values determine the level and the
    // amplitude; over less, the limit is several times this step anyway.
    if omega * 4.0 * d >= 0.5 {
        if let Some((level, amplitude)) = level_and_amplitude(d, omega, y) {
            let same_side = y.iter().all(|v| v * level > 0.0);
            if same_side && level.abs() > 1.25 * amplitude {
                return Oscillation::ClearOfZero;
            }
        }
    }
    Oscillation::At(omega)
}

/// The least-squares `C` and `√(a² + b²)` of `y ≈ C + a cos ωt + b sin ωt`
/// at `t = 0, d, …, 4d`.
fn level_and_amplitude(d: f64, omega: f64, y: [f64; 5]) -> Option<(f64, f64)> {
    let mut normal = [[0.0; 3]; 3];
    let mut right = [0.0; 3];
    for (i, &v) in y.iter().enumerate() {
        let phase = omega * d * i as f64;
        let basis = [1.0, phase.cos(), phase.sin()];
        for r in 0..3 {
            right[r] += basis[r] * v;
            for c in 0..3 {
                normal[r][c] += basis[r] * basis[c];
            }
        }
    }
    // Cramer's rule on the 3 × 3 normal equations.
    let det = |m: [[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let whole = det(normal);
    if !(whole.abs() > 0.0) {
        return None;
    }
    let mut x = [0.0; 3];
    for (column, unknown) in x.iter_mut().enumerate() {
        let mut m = normal;
        for r in 0..3 {
            m[r][column] = right[r];
        }
        *unknown = det(m) / whole;
    }
    if !x.iter().all(|v| v.is_finite()) {
        return None;
    }
    Some((x[0], x[1].hypot(x[2])))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The pace after a step `[t - h, t]` of the functions `g`.
    fn paced(g: impl Fn(f64) -> f64, t: f64, h: f64) -> f64 {
        let mut pace = SwitchPace::default();
        let at: Vec<[f64; 1]> = (0..5).map(|i| [g(t - h + 0.25 * i as f64 * h)]).collect();
        pace.observe(h, [&at[0], &at[1], &at[2], &at[3], &at[4]]);
        pace.limit(t, f64::INFINITY) - t
    }

    #[test]
    fn the_pace_follows_an_oscillation_at_every_phase_and_lets_growth_run() {
        // sin(20 t): at most PHASE_PER_STEP of its phase a step, on its way
        // up, at its top or on its way down, and past its next zero when
        // that is nearer.
        for t in [0.01, 0.05, 0.0785, 0.1, 0.15, 1.234] {
            let reach = paced(|t| (20.0 * t).sin(), t, 0.01);
            let phase = PHASE_PER_STEP / 20.0;
            let next_zero =
                (std::f64::consts::PI * (20.0 * t / std::f64::consts::PI).ceil() - 20.0 * t) / 20.0;
            assert!(
                reach <= 1.01 * phase && reach >= (0.4 * phase).min(next_zero),
                "at {t}: {reach}"
            );
        }
        // A height that grows from zero (a rocket climbing), or a velocity
        // growing linearly: no limit (or one of rounding's size, a
        // curvature of 1e-15 reaching 1e6 further).
        assert!(paced(|t| t * t, 0.1, 0.05) > 1e6);
        assert!(paced(|t| 3.0 * t - 1.0, 1.0, 0.1) > 1e6);
        // Heading linearly to zero at t = 2: the next step reaches past it.
        let reach = paced(|t| 2.0 - t, 1.0, 0.1);
        assert!((reach - REACH_PAST_ZERO).abs() < 1e-12, "{reach}");
    }

    #[test]
    fn the_pace_follows_an_oscillation_about_a_level() {
        // sin(500 t) − 0.5 (a duty cycle of a third): curving away from
        // zero for part of each period, where g''/g says nothing; the fit
        // of a level and an amplitude paces it at every phase. Clear of
        // zero (a level of 2) it sets no pace.
        let phase = PHASE_PER_STEP / 500.0;
        for t in [0.0011, 0.002, 0.0031, 0.005, 0.0077, 1.2345] {
            let reach = paced(|t| (500.0 * t).sin() - 0.5, t, 0.0012);
            assert!(reach <= 1.01 * phase, "at {t}: {reach}");
            assert!(paced(|t| (500.0 * t).sin() - 2.0, t, 0.0012) > 1e6);
        }
    }

    #[test]
    fn finds_roots_to_rounding_on_smooth_and_flat_functions() {
        let root = locate(0.0, -1.0, 2.0, 3.0, |t: f64| Ok::<_, ()>(t * t - 1.0)).unwrap();
        assert!((root - 1.0).abs() < 1e-15, "{root}");
        // A root of multiplicity 3, where regula falsi alone stalls.
        let f = |t: f64| Ok::<_, ()>((t - 0.3).powi(3));
        let root = locate(0.0, f(0.0).unwrap(), 1.0, f(1.0).unwrap(), f).unwrap();
        assert!((root - 0.3).abs() < 1e-5, "{root}");
        assert!(root >= 0.3 - 1e-15);
        // cos changes sign at π/2.
        let root = locate(1.0, 1.0_f64.cos(), 2.0, 2.0_f64.cos(), |t| {
            Ok::<_, ()>(t.cos())
        })
        .unwrap();
        assert!((root - std::f64::consts::FRAC_PI_2).abs() <= 8.0 * f64::EPSILON * 2.0);
    }

    #[test]
    fn a_root_hit_exactly_stays_the_root() {
        // g = 1 − t from a positive side: the secant lands on t = 1 exactly,
        // where g is 0 (signum(0) = +1 once sent the bracket back to a).
        let root = locate(0.871, 0.129, 1.2, -0.2, |t: f64| Ok::<_, ()>(1.0 - t)).unwrap();
        assert!((root - 1.0).abs() <= 8.0 * f64::EPSILON, "{root}");
        assert!(root >= 1.0);
        // And from a negative side.
        let root = locate(0.5, -0.5, 1.5, 0.5, |t: f64| Ok::<_, ()>(t - 1.0)).unwrap();
        assert!((root - 1.0).abs() <= 8.0 * f64::EPSILON, "{root}");
    }
}
