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

#[cfg(test)]
mod tests {
    use super::*;

    /// The pace after a step `[t - h, t]` of the functions `g`.
    fn paced(g: impl Fn(f64) -> f64, t: f64, h: f64) -> f64 {
        let mut pace = SwitchPace::default();
        let at = |f: f64| [g(t - h + f * h)];
        pace.observe(h, &at(0.5), &at(0.75), &at(1.0));
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

/// How far the next step may reach so that no switch changes sign unseen
/// (SPEC: every switch is located). A step's dense output is looked at in
/// a few points only, so a switching function with a time scale of its own
/// — a force switched by a clock, `if sin(20 t) > 0 …`, over a motion that
/// DOP853 integrates exactly in long steps — would change sign and back
/// between them. After each step the pace estimates, from every
/// function's values at the last step's half, three quarters and end, how
/// soon it may reach zero:
/// - heading toward zero (`g g' < 0`): in `|g / g'|`; the next step may
///   reach [`REACH_PAST_ZERO`] times as far, so that the crossing falls
///   inside it;
/// - curving toward zero (`g g'' < 0`), as an oscillation does at every
///   phase: with `ω = √|g'' / g|` (exact for `g = A sin ωt`), the next
///   step covers at most [`PHASE_PER_STEP`] of its phase.
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

impl SwitchPace {
    /// Learns from a step of length `h` with no sign change: the functions'
    /// values at its half, three quarters and end.
    pub fn observe(&mut self, h: f64, half: &[f64], three_quarters: &[f64], end: &[f64]) {
        let d = 0.25 * h.abs();
        if !(d > 0.0) {
            return;
        }
        self.rate = 0.0;
        for ((&g0, &g1), &g2) in end.iter().zip(three_quarters).zip(half) {
            if g0 == 0.0 || !g0.is_finite() {
                continue;
            }
            // The slope at the step's end (one-sided, second order); the
            // curvature at three quarters (central), compared with the
            // value there.
            let slope = (3.0 * g0 - 4.0 * g1 + g2) / (2.0 * d);
            let curvature = (g0 - 2.0 * g1 + g2) / (d * d);
            let mut rate = 0.0_f64;
            if g0 * slope < 0.0 {
                rate = rate.max((slope / g0).abs() / REACH_PAST_ZERO);
            }
            if g1 * curvature < 0.0 {
                rate = rate.max((curvature / g1).abs().sqrt() / PHASE_PER_STEP);
            }
            if rate.is_finite() {
                self.rate = self.rate.max(rate);
            }
        }
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
