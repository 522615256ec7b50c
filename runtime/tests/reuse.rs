//! A run made in the storage an earlier run left (`run_reusing`, what
//! `--repeat` and a program solving one model repeatedly use) is the run
//! a fresh `run` makes: the same samples to the bit, the same outcome, the
//! same failure. One spare goes through every case in turn — models of
//! other sizes, every integrator (RODAS4's and the field's solvers are
//! not reused, DOP853's is), events, modes, a failure — so storage left
//! by any of them must not show in the next.

mod models;

use lagc_runtime::choice::IntegratorChoice;
use lagc_runtime::driver::{run, run_reusing, Options, Spare};
use lagc_runtime::method::Method;
use lagc_runtime::model::{DynModel, Model};
use lagc_runtime::output::sample_times;
use lagc_runtime::tolerance::Tolerance;
use models::{
    DoublePendulum, KnifeEdge, Oscillator, SphericalPendulum, StiffDamped, ThrownBall,
    VanishingMass,
};

fn models() -> Vec<(&'static str, Box<dyn DynModel>)> {
    vec![
        (
            "oscillator",
            Box::new(Oscillator::new(&<Oscillator as Model>::parameters(&[
                None, None,
            ]))),
        ),
        ("thrown ball", Box::new(ThrownBall::new(&[]))),
        ("knife edge", Box::new(KnifeEdge::new(&[]))),
        (
            "double pendulum",
            Box::new(DoublePendulum::new(&<DoublePendulum as Model>::parameters(
                &[],
            ))),
        ),
        (
            "spherical pendulum",
            Box::new(SphericalPendulum::new(
                &<SphericalPendulum as Model>::parameters(&[]),
            )),
        ),
        ("stiff damped", Box::new(StiffDamped::new(&[]))),
        ("vanishing mass", Box::new(VanishingMass::new(&[]))),
    ]
}

/// The samples' bits and the outcome (or the failure) in words.
type Ran = (Vec<(u64, Vec<u64>)>, String);

fn record(model: &mut dyn DynModel, options: &Options, spare: Option<&mut Spare>) -> Ran {
    let (t0, t1) = model.time_span();
    let x0 = model.initial_state(&vec![None; model.dim()]).unwrap();
    let times = sample_times(t0, t1, 23);
    let mut samples = Vec::new();
    let keep = |_: &dyn DynModel, t: f64, x: &[f64]| {
        samples.push((t.to_bits(), x.iter().map(|v| v.to_bits()).collect()));
        Ok(())
    };
    let outcome = match spare {
        Some(spare) => run_reusing(model, options, t0, t1, &x0, &times, keep, spare),
        None => run(model, options, t0, t1, &x0, &times, keep),
    };
    (samples, format!("{outcome:?}"))
}

#[test]
fn a_run_in_an_earlier_runs_storage_is_a_fresh_run_to_the_bit() {
    let mut spare = Spare::default();
    let mut compared = 0;
    // Twice round: the second time every case starts from storage left by
    // another model.
    for round in 0..2 {
        for (name, mut model) in models() {
            for (method, integrator) in [
                (Method::Direct, Some(IntegratorChoice::Explicit)),
                (Method::Direct, None),
                (Method::Direct, Some(IntegratorChoice::Stiff)),
                (Method::Field, None),
            ] {
                for rtol in [1e-4, 1e-9] {
                    let options = Options {
                        method,
                        integrator,
                        tol: Tolerance {
                            rtol,
                            atol: rtol / 100.0,
                        },
                        ..Options::default()
                    };
                    let fresh = record(&mut *model, &options, None);
                    let reused = record(&mut *model, &options, Some(&mut spare));
                    let case =
                        format!("{name}, {method:?} {integrator:?}, rtol {rtol:e}, round {round}");
                    assert_eq!(fresh.1, reused.1, "{case}: outcome");
                    assert_eq!(fresh.0, reused.0, "{case}: samples");
                    // The check can fail: the run produced samples (the
                    // vanishing mass fails part way, after some).
                    assert!(!fresh.0.is_empty(), "{case}: no sample");
                    compared += 1;
                }
            }
        }
    }
    assert_eq!(compared, 2 * 7 * 4 * 2);
}
