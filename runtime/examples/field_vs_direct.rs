//! Field against direct on the runtime's hand-written models: work
//! (right-side evaluations, linearisations) and wall time at a ladder of
//! tolerances, with the error against a tight reference.
//! `cargo run --release -p lagc-runtime --example field_vs_direct`

#[path = "../tests/models/mod.rs"]
mod models;

use lagc_runtime::driver::{run, Options};
use lagc_runtime::method::{IntegratorChoice, Method};
use lagc_runtime::model::Model;
use lagc_runtime::output::sample_times;
use lagc_runtime::tolerance::Tolerance;
use models::{DoublePendulum, MassLossPendulum, Oscillator, SphericalPendulum};
use std::time::Instant;

fn solve<M: Model + 'static>(method: Method, rtol: f64) -> (Vec<(f64, Vec<f64>)>, f64, String) {
    let params = M::parameters(&vec![None; M::PARAMS.len()]);
    let mut model = M::new(&params);
    let (t0, t1) = model.time_span();
    let x0 = model.initial_state(&vec![None; M::STATE.len()]).unwrap();
    let options = Options {
        method,
        integrator: Some(IntegratorChoice::Explicit),
        tol: Tolerance { rtol, atol: rtol },
        ..Options::default()
    };
    let times = sample_times(t0, t1, 11);
    let mut best = f64::INFINITY;
    let mut rows = Vec::new();
    let mut info = String::new();
    for _ in 0..20 {
        rows.clear();
        let start = Instant::now();
        let outcome = run(&mut model, &options, t0, t1, &x0, &times, |_, t, x| {
            rows.push((t, x.to_vec()));
            Ok(())
        })
        .unwrap();
        best = best.min(start.elapsed().as_secs_f64());
        let r = outcome.report;
        info = format!(
            "steps {:4}+{:<3} evals {:6} lin {:6} pred {:4}",
            r.stats.accepted_steps,
            r.stats.rejected_steps,
            r.stats.rhs_evaluations,
            r.linearizations,
            r.predictor.map_or(0, |p| p.accepted_steps)
        );
    }
    (rows, best, info)
}

fn error(a: &[(f64, Vec<f64>)], b: &[(f64, Vec<f64>)]) -> f64 {
    a.iter()
        .zip(b)
        .flat_map(|((_, x), (_, y))| {
            x.iter()
                .zip(y)
                .map(|(u, v)| (u - v).abs() / v.abs().max(1.0))
        })
        .fold(0.0, f64::max)
}

fn table<M: Model + 'static>() {
    let (reference, _, _) = solve::<M>(Method::Direct, 1e-14);
    println!("{}:", M::NAME);
    for rtol in [1e-6, 1e-8, 1e-10, 1e-12] {
        let (d, td, di) = solve::<M>(Method::Direct, rtol);
        let (f, tf, fi) = solve::<M>(Method::Field, rtol);
        println!(
            "  rtol {rtol:.0e}: direct {:.1e} in {:8.1} µs [{di}] | field {:.1e} in {:8.1} µs [{fi}] | ratio {:.1}",
            error(&d, &reference),
            td * 1e6,
            error(&f, &reference),
            tf * 1e6,
            tf / td
        );
    }
}

fn main() {
    table::<Oscillator>();
    table::<MassLossPendulum>();
    table::<SphericalPendulum>();
    table::<DoublePendulum>();
}
