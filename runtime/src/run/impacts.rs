//! Impacts (SPEC §2.3, `when COND then y' = EXPR;`): at an event where a
//! `when`'s condition becomes true (the crossing into it, never out of
//! it), its resets are applied to the located state, the switching
//! functions the resets moved get the branch of the side the motion goes
//! to, and the run restarts there.
//!
//! After a bounce the function that fired is still at zero (`y = 0` with
//! `y'` reversed): its branch is the side its rate points to, so the event
//! does not fire again at once. Where the resets do not turn it back (a
//! restitution of 0, or a bounce too small to leave the boundary) the
//! motion stays on the condition's boundary, a contact the reduced system
//! cannot follow: the run ends there, naming the `when`. Impacts of one
//! `when` whose intervals shrink geometrically (a ball with restitution
//! e < 1 bounces infinitely often before a finite time t∞) end the run
//! where the bounces left before t∞ are below the tolerance or rounding,
//! naming the `when` and t∞. Both endings are the model's own (exit 0),
//! like `stop when`.

use crate::failure::Failure;
use crate::model::{DynModel, Regime};
use crate::ode::tolerance::Tolerance;
use crate::run::options::Ending;

/// What the impacts did at an event.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AtEvent {
    /// No `when` fired.
    None,
    /// Resets were applied: the run restarts from the new state.
    Reset,
    /// The run ends here.
    Stop(Ending),
}

/// The impacts remembered along a run: each `when`'s last few times.
#[derive(Clone, Debug, Default)]
pub struct Impacts {
    times: Vec<Vec<f64>>,
    /// Per `when`: another `when` fired since its last impact (its last
    /// interval is then no bounce of its own).
    interleaved: Vec<bool>,
    /// `(k, r)`: switching function `k` left the boundary at the last
    /// impact and is within rounding `r` of it there; until the next
    /// impact its values within `r` count as on its branch's side.
    guards: Vec<(usize, f64)>,
}

/// How many of a `when`'s last impact times are kept: three intervals, two
/// ratios that must agree for the impacts to count as accumulating.
const KEPT: usize = 4;

/// Two successive ratios of impact intervals agree within this fraction
/// when the impacts accumulate geometrically.
const RATIO_AGREEMENT: f64 = 0.2;

/// Impacts accumulating within this many rounding units of the time
/// (`eps·max(|t|, 1)`) end the run whatever the tolerance: intervals of a
/// few hundred units are the last the event locator (to 4 units) resolves
/// with ratios good to a percent. At t = 4 this is 9e-12.
const RESOLVED_UNITS: f64 = 1e4;

/// An interval between impacts this many rounding units long is not
/// resolved at all: the run ends even without a geometric pattern.
const UNRESOLVED_UNITS: f64 = 64.0;

impl Impacts {
    pub fn new(model: &dyn DynModel) -> Impacts {
        Impacts {
            times: vec![Vec::new(); model.impacts().len()],
            interleaved: vec![false; model.impacts().len()],
            guards: Vec::new(),
        }
    }

    /// [`Impacts::new`] for a run that starts with the functions `guards`
    /// on a boundary ([`touching_at_start`]).
    pub fn starting_on_boundaries(model: &dyn DynModel, guards: Vec<(usize, f64)>) -> Impacts {
        Impacts {
            guards,
            ..Impacts::new(model)
        }
    }

    /// Function `k`'s value as the event search reads it: after a bounce
    /// the function starts on the boundary, its sign there rounding
    /// (below zero by 1e-15 while it rises at 1e-8 a second, it would
    /// fire the impact again at once); values within that rounding count
    /// as on the side of its branch (`positive`).
    pub fn as_seen(&self, k: usize, g: f64, positive: bool) -> f64 {
        match self.guards.iter().find(|&&(j, _)| j == k) {
            Some(&(_, r)) if g.abs() <= r => {
                if positive {
                    r.max(f64::MIN_POSITIVE)
                } else {
                    -r.max(f64::MIN_POSITIVE)
                }
            }
            _ => g,
        }
    }

    /// Takes out of `switched` (and puts back on the branch of `before`,
    /// with a guard) every function of a `when`'s condition that only
    /// grazes its boundary at the event: pulled back out of the condition
    /// along the motion, by an excursion into it within what rounding
    /// resolves. A ball thrown up to touch a ceiling at its top (`when
    /// y > H` with the top at H) crossed H by 4e-15 on the field's dense
    /// output, and the impact fired with the rate of that rounding, 3e-7:
    /// y' off by 60 rtol at rtol 1e-9, exit 0, "within 10·rtol". The
    /// motion never enters the condition, so no impact fires (SPEC: the
    /// crossing into it). A function driven into the condition (a ball
    /// settling on its floor under gravity) is never a graze.
    fn grazes(
        &mut self,
        model: &dyn DynModel,
        regime: &mut Regime,
        before: &[bool],
        switched: &mut Vec<usize>,
        t: f64,
        x: &[f64],
    ) -> Result<(), Failure> {
        let mut after = before.to_vec();
        for &j in switched.iter() {
            after[j] = !after[j];
        }
        let mut g = vec![0.0; model.switches()];
        model.switching_functions(t, x, &mut g);
        let mut kept = Vec::with_capacity(switched.len());
        for &j in switched.iter() {
            // Only a function whose side decides a `when` that becomes true.
            let mut without = after.clone();
            without[j] = before[j];
            let decides = (0..model.impacts().len()).any(|w| {
                !model.impact_holds(w, before)
                    && model.impact_holds(w, &after)
                    && !model.impact_holds(w, &without)
            });
            if !decides {
                kept.push(j);
                continue;
            }
            let inward = if after[j] { 1.0 } else { -1.0 };
            let rate_in = inward * rate(model, t, x, j)?;
            let pull_in = inward * acceleration(model, t, x, j)?;
            let noise = rounding(model, t, x, j);
            let reach = EXCURSION_UNITS * noise;
            let grazing = pull_in < 0.0
                && (rate_in <= 0.0 || rate_in * rate_in / (2.0 * pull_in.abs()) <= reach);
            if grazing {
                regime.branches[j] = before[j];
                self.guards.retain(|&(k, _)| k != j);
                self.guards.push((j, reach.max(2.0 * g[j].abs())));
            } else {
                kept.push(j);
            }
        }
        *switched = kept;
        Ok(())
    }

    /// At the event at `t` where the switches `switched` changed their
    /// branches from `before` to `regime.branches`: applies the resets of
    /// every `when` whose condition became true to `x`, and sets the
    /// branches of the functions they moved.
    ///
    /// Every reset reads the state before the impact, as one impact's
    /// several resets do (`when … then x1' = …, x2' = …`): two balls
    /// colliding written as two `when`s with one condition, each
    /// reading the state the previous one left, gave the second ball a
    /// velocity from the first's new one (momentum 2 → −2.06, exit 0).
    /// The components the constraints fix are recomputed from the state
    /// every reset left (`Model::impact_reset`).
    #[allow(clippy::too_many_arguments)]
    pub fn at_event(
        &mut self,
        model: &mut dyn DynModel,
        regime: &mut Regime,
        before: &[bool],
        switched: &mut Vec<usize>,
        t: f64,
        x: &mut [f64],
        tol: Tolerance,
    ) -> Result<AtEvent, Failure> {
        self.grazes(model, regime, before, switched, t, x)?;
        let switched: &[usize] = switched;
        let fired: Vec<usize> = (0..model.impacts().len())
            .filter(|&w| !model.impact_holds(w, before) && model.impact_holds(w, &regime.branches))
            .collect();
        if fired.is_empty() {
            return Ok(AtEvent::None);
        }
        let x_before = x.to_vec();
        let mut out = x.to_vec();
        for &w in &fired {
            model.impact_reset(w, t, &x_before, &mut out);
        }
        fixed_after_resets(model, regime, &fired, t, &mut out)?;
        if let Some(i) = out.iter().position(|v| !v.is_finite()) {
            return Err(Failure::non_finite(t, model.state_names()[i]));
        }
        x.copy_from_slice(&out);
        // The guards of functions this event did not switch that are still
        // within their rounding of the boundary are kept: in Newton's
        // cradle with touching balls, ball 2 struck ball 3 and ball 1 then
        // struck ball 2 again at once; without its guard the pair 2-3, just
        // separating, read its rounding (-1e-17) as a new crossing and
        // collided again (x3' 0.9025 -> 0.0925).
        let mut g = vec![0.0; model.switches()];
        model.switching_functions(t, x, &mut g);
        self.guards
            .retain(|&(j, r)| !switched.contains(&j) && g[j].abs() <= r);
        let after = branches_after(
            model,
            regime,
            before,
            switched,
            t,
            &x_before,
            x,
            &mut self.guards,
        )?;
        for (w, interleaved) in self.interleaved.iter_mut().enumerate() {
            if !fired.contains(&w) {
                *interleaved = true;
            }
        }
        for &w in &fired {
            let impact = model.impacts()[w];
            // Newton's cradle with touching balls: ball 1 strikes 2, 2
            // strikes 3, and 1 (left closing on 2 by e < 1) strikes 2 again
            // within rounding of the first. That last interval is short
            // because another impact came between, not because the pair
            // bounces ever faster: taken as unresolved bouncing it stopped
            // the run at t = 0.1 (exit 0, "the impacts accumulate").
            let interleaved = std::mem::take(&mut self.interleaved[w]);
            let times = &mut self.times[w];
            times.push(t);
            if times.len() > KEPT {
                times.remove(0);
            }
            let limit = accumulation(times);
            if after.stays && model.impact_holds(w, &regime.branches) {
                // Stopped on the boundary: where the impacts were
                // accumulating, the last bounce was too small to resolve.
                return Ok(AtEvent::Stop(Ending::Rest {
                    impact,
                    at: t,
                    accumulation: limit,
                }));
            }
            if times.len() < 2 {
                continue;
            }
            let units = f64::EPSILON * t.abs().max(1.0);
            let last = times[times.len() - 1] - times[times.len() - 2];
            let settled = match limit {
                _ if after.unresolved || (last <= UNRESOLVED_UNITS * units && !interleaved) => true,
                Some(limit) => {
                    limit - t <= RESOLVED_UNITS * units
                        || moves_within_tolerance(model, t, x, limit - t, tol)
                }
                None => false,
            };
            if settled {
                return Ok(AtEvent::Stop(Ending::Rest {
                    impact,
                    at: t,
                    accumulation: Some(limit.unwrap_or(t)),
                }));
            }
        }
        Ok(AtEvent::Reset)
    }
}

/// The `when`s whose condition became true at an event where the
/// switching functions `switched` changed sign from the branches
/// `before` (the model in the regime before): the impacts that fire
/// there, in declaration order.
pub fn fired(model: &dyn DynModel, before: &[bool], switched: &[usize]) -> Vec<usize> {
    let mut after = before.to_vec();
    for &s in switched {
        after[s] = !after[s];
    }
    (0..model.impacts().len())
        .filter(|&w| !model.impact_holds(w, before) && model.impact_holds(w, &after))
        .collect()
}

/// At the start `(t0, x0)` of a run: a `when` whose condition holds only
/// because a switching function sits on its boundary within rounding —
/// Newton's cradle written with touching balls, `when x3 - x2 < 2 * r`
/// with `x3 - x2 = 0.3 - 0.2` (2.8e-17 below `2 * r` = 0.1), or exactly
/// on it with the balls about to close (`initial_branches` takes the side
/// a moment later) — never became true, so it never fired: ball 2 passed
/// through ball 3 when ball 1 struck it (exit 0, "within 10·rtol"). Such a
/// function is put on the side where the condition does not hold, with a
/// guard for its rounding, so that the motion into the condition is a
/// crossing, located and fired as any impact (a ball at rest on its floor
/// then ends at once with the named stop on the boundary). Returns the
/// guards; `branches` holds the initial regime's branches and is changed.
pub fn touching_at_start(
    model: &mut dyn DynModel,
    mode: usize,
    t0: f64,
    x0: &[f64],
    branches: &mut [bool],
) -> Vec<(usize, f64)> {
    let mut guards: Vec<(usize, f64)> = Vec::new();
    if model.impacts().is_empty() {
        return guards;
    }
    let mut g = vec![0.0; model.switches()];
    model.set_regime(&Regime {
        mode,
        branches: branches.to_vec(),
    });
    model.switching_functions(t0, x0, &mut g);
    for w in 0..model.impacts().len() {
        if !model.impact_holds(w, branches) {
            continue;
        }
        for j in 0..g.len() {
            let noise = rounding(model, t0, x0, j);
            if g[j].abs() > noise || guards.iter().any(|&(k, _)| k == j) {
                continue;
            }
            branches[j] = !branches[j];
            if model.impact_holds(w, branches) {
                // Not this function's boundary: the condition holds
                // on both of its sides.
                branches[j] = !branches[j];
            } else {
                guards.push((j, noise.max(g[j].abs())));
                break;
            }
        }
    }
    model.set_regime(&Regime {
        mode,
        branches: branches.to_vec(),
    });
    guards
}

/// `state` with the resets of the impacts `fired` applied at `t`, each
/// reading `state` (as [`Impacts::at_event`] applies them), and in a
/// model of several modes the components `after.mode` (the mode the
/// impact chose) fixes recomputed: for the derivatives of the resets (the
/// sensitivities' jump, the carried error's saltation). Where that mode
/// cannot complete the state, not finite.
pub fn reset(
    model: &dyn DynModel,
    after: &Regime,
    fired: &[usize],
    t: f64,
    state: &[f64],
) -> Vec<f64> {
    let mut out = state.to_vec();
    for &w in fired {
        model.impact_reset(w, t, state, &mut out);
    }
    if !fired.is_empty() && !model.impact_targets().is_empty() {
        let mut in_mode = model.boxed_clone();
        in_mode.set_regime(after);
        if recompute_fixed(&*in_mode, after.mode, t, &mut out).is_err() {
            out.fill(f64::NAN);
        }
    }
    out
}

/// In a model of several modes, whose `impact_reset` writes the resets
/// only (`Model::IMPACT_TARGETS`): the mode the run goes on in after the
/// impacts `fired` (`regime::mode_after_resets`), set in `regime` and
/// `model`, and the components it fixes recomputed in `out` (the state
/// with the resets applied) from the new state. Why not in the generated
/// code, as a model of one mode does: which components are fixed depends
/// on the mode, and a target the current mode fixes must be freed by
/// another mode, or refused; recomputed in mode 0's formulas, a reset of
/// `y'` in the mode that fixes `x'` was undone (`y'` from the old `x'`).
fn fixed_after_resets(
    model: &mut dyn DynModel,
    regime: &mut Regime,
    fired: &[usize],
    t: f64,
    out: &mut [f64],
) -> Result<(), Failure> {
    let all = model.impact_targets();
    if all.is_empty() || fired.is_empty() {
        return Ok(());
    }
    let targets: Vec<usize> = fired
        .iter()
        .flat_map(|&w| all.get(w).copied().unwrap_or(&[]).iter().copied())
        .collect();
    let condition = model.impacts()[fired[0]];
    regime.mode =
        crate::run::regime::mode_after_resets(&*model, regime.mode, &targets, condition, t, out)?;
    model.set_regime(regime);
    recompute_fixed(&*model, regime.mode, t, out)
}

/// The components `mode` (the model's current mode) fixes, recomputed in
/// `out` from the rest of it.
fn recompute_fixed(
    model: &dyn DynModel,
    mode: usize,
    t: f64,
    out: &mut [f64],
) -> Result<(), Failure> {
    let Some(fixed) = model.fixed_components().get(mode) else {
        return Ok(());
    };
    let mut kept = out.to_vec();
    model.constrained(t, out, &mut kept)?;
    for &j in *fixed {
        out[j] = kept[j];
    }
    Ok(())
}

/// What the resets left of the functions that fired.
struct After {
    /// A function still at zero stays on the new side although the resets
    /// changed its rate: they stopped the motion on the boundary instead
    /// of turning it back.
    stays: bool,
    /// A function turned back leaves the boundary by less than its
    /// rounding before it is pulled back: the bounce cannot be resolved.
    unresolved: bool,
}

/// A bounce whose excursion from the boundary is below this many times
/// its switching function's rounding is not resolved.
const EXCURSION_UNITS: f64 = 16.0;

/// Puts every switching function the resets moved on the side the
/// motion goes to from the new state `x` (the model set to `regime` on
/// return), and guards each that leaves the boundary for its rounding.
/// A function that switched at this event and is still at zero (within
/// rounding) takes the side its rate points to, tried first on the side
/// it came from (a bounce leaves the condition); one the resets moved
/// elsewhere takes its sign.
#[allow(clippy::too_many_arguments)]
fn branches_after(
    model: &mut dyn DynModel,
    regime: &mut Regime,
    before: &[bool],
    switched: &[usize],
    t: f64,
    x_before: &[f64],
    x: &[f64],
    guards: &mut Vec<(usize, f64)>,
) -> Result<After, Failure> {
    let k = model.switches();
    let (mut g_before, mut g_after) = (vec![0.0; k], vec![0.0; k]);
    model.set_regime(regime);
    model.switching_functions(t, x_before, &mut g_before);
    model.switching_functions(t, x, &mut g_after);
    let mut after = After {
        stays: false,
        unresolved: false,
    };
    for j in 0..k {
        let noise = rounding(model, t, x, j);
        let at_zero =
            switched.contains(&j) && g_after[j].abs() <= noise.max(2.0 * g_before[j].abs());
        if at_zero {
            // The motion on the side the function came from: does the
            // new state leave the boundary to it?
            let came_from = before[j];
            let mut trial = regime.clone();
            trial.branches[j] = came_from;
            model.set_regime(&trial);
            let leaving = direction(model, t, x, j)?;
            let rate_after = rate(model, t, x, j)?;
            let rate_before = rate(model, t, x_before, j)?;
            let pull = acceleration(model, t, x, j)?;
            model.set_regime(regime);
            if leaving == Some(came_from) {
                regime.branches[j] = came_from;
                guards.push((j, noise.max(g_after[j].abs())));
                // Pulled back to the boundary: the excursion v² / 2|a|.
                let outward = if came_from { 1.0 } else { -1.0 };
                if pull * outward < 0.0 {
                    let excursion = rate_after * rate_after / (2.0 * pull.abs());
                    after.unresolved |= excursion <= EXCURSION_UNITS * noise;
                }
            } else {
                let unchanged = (rate_after - rate_before).abs()
                    <= 1e-9 * rate_after.abs().max(rate_before.abs());
                after.stays |= !unchanged;
            }
        } else if g_after[j] != g_before[j] {
            regime.branches[j] = if g_after[j] != 0.0 {
                g_after[j] > 0.0
            } else {
                direction(model, t, x, j)?.unwrap_or(regime.branches[j])
            };
        }
    }
    model.set_regime(regime);
    Ok(after)
}

/// How much rounding moves switching function `k` at `(t, x)`: its change
/// when `t` and each component of `x` move by a rounding unit, summed, with
/// a margin of 4 (a height above an inclined floor, `sin(a) x + cos(a) y`
/// with x ≈ 4.7, rounds to about 1e-15: a bounce lower than that is not
/// seen, and its sign there is noise).
fn rounding(model: &dyn DynModel, t: f64, x: &[f64], k: usize) -> f64 {
    let mut g0 = vec![0.0; model.switches()];
    let mut g = vec![0.0; model.switches()];
    model.switching_functions(t, x, &mut g0);
    let mut total = f64::EPSILON * g0[k].abs();
    model.switching_functions(t + f64::EPSILON * t.abs(), x, &mut g);
    total += (g[k] - g0[k]).abs();
    let mut y = x.to_vec();
    for i in 0..x.len() {
        y[i] = x[i] + f64::EPSILON * x[i].abs();
        model.switching_functions(t, &y, &mut g);
        total += (g[k] - g0[k]).abs();
        y[i] = x[i];
    }
    if total.is_finite() {
        4.0 * total
    } else {
        0.0
    }
}

/// The second derivative of switching function `k` along the motion at
/// `(t, x)`: the change of its rate a moment ahead and behind.
fn acceleration(model: &dyn DynModel, t: f64, x: &[f64], k: usize) -> Result<f64, Failure> {
    let n = x.len();
    let mut slope = vec![0.0; n];
    model.rhs(t, x, &mut slope)?;
    let h = 1e-4 * t.abs().max(1.0);
    let ahead: Vec<f64> = x.iter().zip(&slope).map(|(v, r)| v + h * r).collect();
    let behind: Vec<f64> = x.iter().zip(&slope).map(|(v, r)| v - h * r).collect();
    Ok((rate(model, t + h, &ahead, k)? - rate(model, t - h, &behind, k)?) / (2.0 * h))
}

/// The limit `t∞ = t_n + Δ_n r / (1 − r)` of impacts at `times` whose last
/// three intervals shrink by ratios that agree (`r` the last).
fn accumulation(times: &[f64]) -> Option<f64> {
    if times.len() < KEPT {
        return None;
    }
    let d: Vec<f64> = times.windows(2).map(|w| w[1] - w[0]).collect();
    let n = d.len();
    let (r1, r2) = (d[n - 2] / d[n - 3], d[n - 1] / d[n - 2]);
    let shrinking = d[n - 1] > 0.0 && r1 < 1.0 && r2 < 1.0;
    if !(shrinking && (r1 - r2).abs() <= RATIO_AGREEMENT * r2) {
        return None;
    }
    Some(times[n] + d[n - 1] * r2 / (1.0 - r2))
}

/// Whether the motion from `(t, x)` at its present rates moves no
/// component by more than the tolerance in `tau`: what is left of it
/// before the impacts accumulate is then below what the run resolves.
fn moves_within_tolerance(
    model: &dyn DynModel,
    t: f64,
    x: &[f64],
    tau: f64,
    tol: Tolerance,
) -> bool {
    let mut dx = vec![0.0; x.len()];
    if model.rhs(t, x, &mut dx).is_err() {
        return false;
    }
    x.iter()
        .zip(&dx)
        .all(|(v, r)| (r * tau).abs() <= tol.atol + tol.rtol * v.abs())
}

/// The rate of switching function `k` along the motion at `(t, x)`:
/// `∂g/∂t + ∇g·X` by a central difference along `X`, over a step long
/// enough that rounding in `g` (of the state's size) hardly shows: 1e-5
/// of the time reads a rate of 1e-10 for a function of states of size 1.
fn rate(model: &dyn DynModel, t: f64, x: &[f64], k: usize) -> Result<f64, Failure> {
    let n = x.len();
    let mut slope = vec![0.0; n];
    model.rhs(t, x, &mut slope)?;
    let h = 1e-5 * t.abs().max(1.0);
    let mut g = vec![0.0; model.switches()];
    let mut at = |s: f64| {
        let state: Vec<f64> = x.iter().zip(&slope).map(|(v, r)| v + s * r).collect();
        model.switching_functions(t + s, &state, &mut g);
        g[k]
    };
    Ok((at(h) - at(-h)) / (2.0 * h))
}

/// The side (`true`: positive) function `k` moves to from `(t, x)` along
/// the motion: its rate's sign, or where the rate vanishes, the sign of
/// its change a moment later along Heun's second-order step (a body
/// stopped on the boundary, accelerated into it); `None` when neither
/// moves it.
fn direction(model: &dyn DynModel, t: f64, x: &[f64], k: usize) -> Result<Option<bool>, Failure> {
    let r = rate(model, t, x, k)?;
    if r != 0.0 {
        return Ok(Some(r > 0.0));
    }
    let n = x.len();
    let (mut slope, mut slope_ahead) = (vec![0.0; n], vec![0.0; n]);
    model.rhs(t, x, &mut slope)?;
    let h = 1e-6 * t.abs().max(1.0);
    let euler: Vec<f64> = x.iter().zip(&slope).map(|(v, s)| v + h * s).collect();
    model.rhs(t + h, &euler, &mut slope_ahead)?;
    let ahead: Vec<f64> = x
        .iter()
        .zip(slope.iter().zip(&slope_ahead))
        .map(|(v, (s, s1))| v + h / 2.0 * (s + s1))
        .collect();
    let mut g = vec![0.0; model.switches()];
    let mut g_ahead = vec![0.0; model.switches()];
    model.switching_functions(t, x, &mut g);
    model.switching_functions(t + h, &ahead, &mut g_ahead);
    let change = g_ahead[k] - g[k];
    Ok((change != 0.0).then_some(change > 0.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn geometric_impact_times_predict_their_accumulation() {
        // A ball: impacts at T0 (1 + 2 e (1 - e^(n-1)) / (1 - e)), the limit
        // T0 (1 + 2 e / (1 - e)), from the last four.
        let (t0, e) = (0.45_f64, 0.8_f64);
        let impact = |n: i32| t0 * (1.0 + 2.0 * e * (1.0 - e.powi(n - 1)) / (1.0 - e));
        let times: Vec<f64> = (5..9).map(impact).collect();
        let limit = accumulation(&times).unwrap();
        assert!(
            (limit - t0 * (1.0 + 2.0 * e / (1.0 - e))).abs() < 1e-12,
            "{limit}"
        );
        // Evenly spaced (an elastic ball), growing, or too few: none.
        assert_eq!(accumulation(&[1.0, 2.0, 3.0, 4.0]), None);
        assert_eq!(accumulation(&[1.0, 1.1, 1.3, 1.7]), None);
        assert_eq!(accumulation(&[1.0, 1.5, 1.75]), None);
        // Shrinking, but not by one ratio: none.
        assert_eq!(accumulation(&[0.0, 1.0, 1.9, 1.91]), None);
    }
}
