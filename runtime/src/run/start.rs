//! Where a run starts: the time span and the initial state, with the
//! checks every entry point applies (the generated crate's command line
//! and the library API, which the Python module and the FMU use), so that
//! a start the command line refuses is refused everywhere.

use crate::failure::{Failure, FailureKind};
use crate::model::{DynModel, Initial};

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
    Ok(x0)
}
