//! Where a run starts: the time span and the initial state, with the
//! checks every entry point applies (the generated crate's command line
//! and the library API, which the Python module and the FMU use), so that
//! a start the command line refuses is refused everywhere.

use crate::failure::{Failure, FailureKind};
use crate::model::{DynModel, Initial};
use crate::run::impacts::touching_at_start;

/// The model's time span, refused unless finite and increasing.
pub fn time_span(model: &dyn DynModel) -> Result<(f64, f64), Failure> {
    let (t0, t1) = model.time_span();
    if !(t0.is_finite() && t1.is_finite() && t1 > t0) {
        return Err(Failure::new(t0, FailureKind::BadTimeSpan { t0, t1 }));
    }
    Ok((t0, t1))
}

/// The initial state at `t0`: `given[i]` replaces a value the model
/// states; one the constraints fix is checked against them. A value that
/// is not finite is refused, naming the velocity to give where a
/// constraint's pivot vanishes at the start (a pendulum in `x, y`
/// released level with its pivot: `y' = −x x'/y` is 0/0); so is a start
/// whose candidates all vanish.
pub fn initial_state(
    model: &dyn DynModel,
    t0: f64,
    given: &[Option<f64>],
) -> Result<Vec<f64>, Failure> {
    let stated: Vec<Option<f64>> = given
        .iter()
        .zip(model.initial_kinds())
        .map(|(g, kind)| if *kind == Initial::Given { *g } else { None })
        .collect();
    let x0 = model.initial_state(&stated)?;
    if let Some(i) = x0.iter().position(|v| !v.is_finite()) {
        crate::run::regime::check_first_candidates(model, t0, &x0)?;
        return Err(Failure::new(
            t0,
            FailureKind::NonFiniteInitialValue {
                component: model.state_names()[i].to_string(),
            },
        ));
    }
    for (i, (g, kind)) in given.iter().zip(model.initial_kinds()).enumerate() {
        if let (Some(stated), false) = (g, *kind == Initial::Given) {
            if (stated - x0[i]).abs() > 1e-9 * x0[i].abs().max(1.0) {
                return Err(Failure::new(
                    t0,
                    FailureKind::InconsistentInitialValue {
                        component: model.state_names()[i].to_string(),
                        stated: *stated,
                        required: x0[i],
                    },
                ));
            }
        }
    }
    crate::run::regime::check_initial_candidates(model, t0, &x0)?;
    no_impact_holds(model, t0, &x0)?;
    Ok(x0)
}

/// Refuses a start inside a `when`'s condition (not on its boundary within
/// rounding, which [`touching_at_start`] takes as not yet true): an impact
/// fires where the motion enters its condition, so a ball started below
/// its floor (`initial y = -0.1` with `when y < 0 then y' = -e * y'`) fell
/// through it for ever, exit 0, "within 10·rtol". A reset at t0 is not
/// what the model says either: the start is the user's to move. The
/// message names the state components the condition reads there.
fn no_impact_holds(model: &dyn DynModel, t0: f64, x0: &[f64]) -> Result<(), Failure> {
    if model.impacts().is_empty() {
        return Ok(());
    }
    let mut model = model.boxed_clone();
    let mode = crate::run::regime::best_mode(&*model, t0, x0).0;
    let mut branches = crate::run::regime::initial_branches(&*model, t0, x0);
    touching_at_start(&mut *model, mode, t0, x0, &mut branches);
    let Some(w) = (0..model.impacts().len()).find(|&w| model.impact_holds(w, &branches)) else {
        return Ok(());
    };
    // The switching functions whose side decides the condition here, and
    // the components (and time) that move them.
    let k = model.switches();
    let deciding: Vec<usize> = (0..k)
        .filter(|&j| {
            let mut flipped = branches.clone();
            flipped[j] = !flipped[j];
            !model.impact_holds(w, &flipped)
        })
        .collect();
    let (mut g, mut moved) = (vec![0.0; k], vec![0.0; k]);
    model.switching_functions(t0, x0, &mut g);
    let moves = |moved: &[f64]| deciding.iter().any(|&j| moved[j] != g[j]);
    let mut values: Vec<String> = Vec::new();
    let mut y = x0.to_vec();
    for (i, name) in model.state_names().iter().enumerate() {
        y[i] = x0[i] + 1e-6 * x0[i].abs().max(1.0);
        model.switching_functions(t0, &y, &mut moved);
        y[i] = x0[i];
        if moves(&moved) {
            values.push(format!("{name} = {}", x0[i]));
        }
    }
    model.switching_functions(t0 + 1e-6 * t0.abs().max(1.0), x0, &mut moved);
    if moves(&moved) {
        values.push(format!("t = {t0}"));
    }
    if values.is_empty() {
        values = model
            .state_names()
            .iter()
            .zip(x0)
            .map(|(name, v)| format!("{name} = {v}"))
            .collect();
    }
    Err(Failure::new(
        t0,
        FailureKind::ImpactHoldsAtStart {
            condition: model.impacts()[w].to_string(),
            values: values.join(", "),
        },
    ))
}
