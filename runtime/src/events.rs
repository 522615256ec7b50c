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
