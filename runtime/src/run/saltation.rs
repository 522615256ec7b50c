//! A small change of the state carried through an event: the saltation
//! of the event's time and the impact's reset (SPEC §2.3 `when`), for
//! the global error a run carries along its motion.
//!
//! Where the run crosses switching function `g` at `τ` with the state
//! off by `e` (the run's error, `x_run − x_exact`), the exact motion
//! crosses at `τ + dτ`, `dτ = −∇g·e / (∇g·f⁻ + ∂g/∂t)`, and the resets `R`
//! of the impacts that fired (the identity at a plain switch) leave
//! `e⁺ = R_x e + (R_x f⁻ − f⁺) dτ` (the sensitivities' jump,
//! `run::sensitivity`, for one direction). Why: the error carried through
//! a bounce unchanged missed what the bounce does to it. A ball thrown
//! with quadratic drag and bouncing 120 times (e = 0.8) ended 34 rtol
//! off at rtol 1e-8, its carried estimate 6.5 ("within"): each bounce
//! turns a height error into a time error and that into a velocity
//! error (`docs/BENCHMARKS.md` §10u).
//!
//! The partials are central differences along `e` and in `t` (the event
//! function and the resets are cheap algebraic maps): two resets, four
//! values of `g` and two right sides an event.

use crate::failure::Failure;
use crate::model::{DynModel, Regime};

/// `e`, the state's error just before the event at `t` where the
/// switching functions `switched` changed sign (the model in the regime
/// after it, `before` the one before), made the error just after it:
/// `x_before` is the located state, `x_after` the state the run goes on
/// from (the resets applied). A grazing crossing (no rate of `g` along
/// the motion) leaves `e` as it is: the time's shift is not defined.
pub fn through_event(
    model: &dyn DynModel,
    before: &Regime,
    switched: &[usize],
    t: f64,
    x_before: &[f64],
    x_after: &[f64],
    e: &mut [f64],
) -> Result<(), Failure> {
    let Some(&k) = switched.first() else {
        return Ok(());
    };
    let n = x_before.len();
    if !(relative_size(e, x_before) > 0.0) {
        return Ok(());
    }
    let mut old = model.boxed_clone();
    old.set_regime(before);
    let old = &*old;
    let mut f_minus = vec![0.0; n];
    old.rhs(t, x_before, &mut f_minus)?;
    let mut f_plus = vec![0.0; n];
    model.rhs(t, x_after, &mut f_plus)?;
    let mut values = vec![0.0; model.switches()];
    let mut g = |t: f64, x: &[f64]| {
        old.switching_functions(t, x, &mut values);
        values[k]
    };
    let g_e = directional(x_before, e, |x| vec![g(t, x)])[0];
    let g_f = directional(x_before, &f_minus, |x| vec![g(t, x)])[0];
    let dt = f64::EPSILON.sqrt() * t.abs().max(1.0);
    let g_t = (g(t + dt, x_before) - g(t - dt, x_before)) / (2.0 * dt);
    let rate = g_f + g_t;
    if !(rate.abs() > 0.0 && rate.is_finite() && g_e.is_finite()) {
        return Ok(());
    }
    let shift = -g_e / rate;
    // The impacts that fired, their resets applied in order, as
    // `Impacts::at_event` applies them (the model in the regime before).
    // `before.mode` is the mode the run goes on in: the one the impact
    // chose, whose fixed components the resets recompute.
    let fired = crate::run::impacts::fired(old, &before.branches, switched);
    let reset = |state: &[f64]| crate::run::impacts::reset(old, before, &fired, t, state);
    // R_x applied to a direction: the identity where nothing fired.
    let r_x = |d: &[f64]| -> Vec<f64> {
        if fired.is_empty() {
            d.to_vec()
        } else {
            directional(x_before, d, reset)
        }
    };
    let r_e = r_x(e);
    let r_f = r_x(&f_minus);
    let jumped: Vec<f64> = r_e
        .iter()
        .zip(&r_f)
        .zip(&f_plus)
        .map(|((re, rf), fp)| re + (rf - fp) * shift)
        .collect();
    if jumped.iter().all(|v| v.is_finite()) {
        e.copy_from_slice(&jumped);
    }
    Ok(())
}

/// `max_i |d_i| / max(|x_i|, 1)`: how large `d` is beside the state.
fn relative_size(d: &[f64], x: &[f64]) -> f64 {
    let size = d
        .iter()
        .zip(x)
        .fold(0.0_f64, |m, (d, x)| m.max(d.abs() / x.abs().max(1.0)));
    if size.is_finite() {
        size
    } else {
        0.0
    }
}

/// The derivative of `map` at `x` along `d`, by a central difference
/// over a step of about √eps of the state's size (an algebraic map's
/// difference is good to about √eps); zero along a zero direction.
fn directional(x: &[f64], d: &[f64], mut map: impl FnMut(&[f64]) -> Vec<f64>) -> Vec<f64> {
    let size = relative_size(d, x);
    if size == 0.0 {
        return vec![0.0; map(x).len()];
    }
    let s = f64::EPSILON.sqrt() / size;
    let moved =
        |sign: f64| -> Vec<f64> { x.iter().zip(d).map(|(x, d)| x + sign * s * d).collect() };
    let (plus, minus) = (map(&moved(1.0)), map(&moved(-1.0)));
    plus.iter()
        .zip(&minus)
        .map(|(p, m)| (p - m) / (2.0 * s))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::directional;

    #[test]
    fn a_directional_difference_of_a_linear_map_is_the_map() {
        let x = [1.0, -2.0, 3.0];
        let d = [1e-9, 2e-9, -4e-9];
        let map = |y: &[f64]| vec![2.0 * y[0] - y[2], -0.5 * y[1]];
        let got = directional(&x, &d, map);
        let want = [2.0 * d[0] - d[2], -0.5 * d[1]];
        for (g, w) in got.iter().zip(want) {
            assert!((g - w).abs() <= 1e-6 * w.abs(), "{g} against {w}");
        }
    }
}
