//! One field for many initial states: exact for an affine motion (against
//! direct integrations and the closed form), and first order in the spread
//! for a non-affine one.

mod models;

use lagc_runtime::driver::{run, run_ensemble, Options};
use lagc_runtime::method::Method;
use lagc_runtime::model::Model;
use lagc_runtime::output::sample_times;
use lagc_runtime::tolerance::Tolerance;
use models::{MassLossPendulum, Oscillator};

fn members(x0: &[f64], count: usize, spread: f64) -> Vec<Vec<f64>> {
    (0..count)
        .map(|k| {
            x0.iter()
                .enumerate()
                .map(|(i, &x)| {
                    let u = ((k as f64) * (2.0 + i as f64).sqrt()).fract() * 2.0 - 1.0;
                    if k == 0 {
                        x
                    } else {
                        x + spread * x.abs().max(1.0) * u
                    }
                })
                .collect()
        })
        .collect()
}

fn direct<M: Model + 'static>(x0: &[f64], times: &[f64]) -> Vec<Vec<f64>> {
    let mut model = M::new(&M::parameters(&vec![None; M::PARAMS.len()]));
    let (t0, t1) = model.time_span();
    let options = Options {
        method: Method::Direct,
        tol: Tolerance {
            rtol: 1e-12,
            atol: 1e-14,
        },
        ..Options::default()
    };
    let mut rows = Vec::new();
    run(&mut model, &options, t0, t1, x0, times, |_, _, x| {
        rows.push(x.to_vec());
        Ok(())
    })
    .unwrap();
    rows
}

fn largest_difference<M: Model + 'static>(spread: f64, count: usize) -> f64 {
    let mut model = M::new(&M::parameters(&vec![None; M::PARAMS.len()]));
    let (t0, t1) = model.time_span();
    let x0 = model.initial_state(&vec![None; M::STATE.len()]).unwrap();
    let all = members(&x0, count, spread);
    let times = sample_times(t0, t1, 11);
    let options = Options {
        tol: Tolerance {
            rtol: 1e-11,
            atol: 1e-13,
        },
        ..Options::default()
    };
    let mut field: Vec<Vec<Vec<f64>>> = Vec::new();
    let handed = lagc_runtime::ensemble::States::from_rows(&all);
    run_ensemble(&mut model, &options, t0, t1, handed, &times, |_, states| {
        field.push(states.rows().map(<[f64]>::to_vec).collect())
    })
    .unwrap();
    let mut largest = 0.0_f64;
    for (m, x) in all.iter().enumerate() {
        let reference = direct::<M>(x, &times);
        for (i, row) in reference.iter().enumerate() {
            for (a, b) in field[i][m].iter().zip(row) {
                largest = largest.max((a - b).abs() / b.abs().max(1.0));
            }
        }
    }
    largest
}

#[test]
fn an_affine_ensemble_is_exact_for_every_member() {
    let error = largest_difference::<Oscillator>(0.3, 20);
    eprintln!("oscillator ensemble: {error:.2e}");
    assert!(error < 1e-9, "{error}");
}

#[test]
fn a_non_affine_ensemble_is_first_order_in_the_spread() {
    let coarse = largest_difference::<MassLossPendulum>(1e-2, 8);
    let fine = largest_difference::<MassLossPendulum>(1e-3, 8);
    eprintln!("pendulum ensemble: spread 1e-2 → {coarse:.2e}, 1e-3 → {fine:.2e}");
    // First order: the linearisation's error is second order in the spread.
    assert!(fine < coarse / 30.0, "{coarse} → {fine}");
    assert!(coarse < 1e-2);
}
